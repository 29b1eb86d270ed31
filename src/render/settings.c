/* Render settings: cst_render_settings_init (every field unset) and
 * cst_render_settings_resolve (unset fields from the scene file, then the defaults). */
#include <string.h>
#include <unistd.h>

#include "scene/scene.h"

void cst_render_settings_init(CstRenderSettings *s)
{
    memset(s, 0, sizeof *s); /* enums *_DEFAULT, seed_set = exposure_set = 0, no callback */
    s->width = s->height = s->spp = s->threads = CST_UNSET;
    s->max_depth = s->rr_depth = s->light_rr_depth = s->photons = CST_UNSET;
    s->time_limit = s->photon_radius = s->exposure = s->max_component = CST_UNSET;
    s->png_linear = s->aovs = s->regularize = s->subsurface_walk = CST_UNSET;
    s->white_balance = CST_UNSET;
    for (int k = 0; k < 4; k++) s->crop[k] = CST_UNSET;
    s->first_sample = CST_UNSET;
    s->mlt_large_step = s->mlt_sigma = CST_UNSET;
    s->mlt_bootstrap = s->mlt_chains = CST_UNSET;
    s->sample_block = CST_UNSET;
    s->noise_target = CST_UNSET;
}

/* Whether a field holds a value. Fields where 0 means nothing (sizes, counts, radii, the
 * enums' *_DEFAULT) also read 0 as unset, as zero-initialised structs always did. */
static int int_set(int v, int zero_unset) { return v != CST_UNSET && !(zero_unset && v == 0); }
static int dbl_set(double v, int zero_unset) { return v != CST_UNSET && !(zero_unset && v == 0.0); }

#define PICK_INT(field, zero_unset, dflt)                                                          \
    out->field = int_set((int)in->field, zero_unset) ? in->field                                  \
               : int_set((int)sc->field, zero_unset) ? sc->field : (dflt)
#define PICK_DBL(field, zero_unset, dflt)                                                          \
    out->field = dbl_set(in->field, zero_unset) ? in->field : dbl_set(sc->field, zero_unset) ? sc->field : (dflt)

void cst_render_settings_resolve(const CstScene *scene, const CstRenderSettings *in, CstRenderSettings *out)
{
    CstRenderSettings unset;
    cst_render_settings_init(&unset);
    if (!in) in = &unset;
    const CstRenderSettings *sc = &scene->settings;
    *out = *in;
    PICK_INT(width, 1, CST_DEFAULT_WIDTH);
    PICK_INT(height, 1, CST_DEFAULT_HEIGHT);
    PICK_INT(integrator, 1, CST_INTEGRATOR_PATH);
    PICK_INT(filter, 1, CST_FILTER_BOX);
    PICK_INT(max_depth, 0, 0);                /* 0 = unbounded */
    PICK_INT(rr_depth, 1, CST_DEFAULT_RR_DEPTH);
    PICK_INT(light_rr_depth, 1, out->rr_depth); /* after rr_depth: its default */
    PICK_DBL(time_limit, 0, 0.0);             /* 0 = none */
    if (out->noise_target == CST_UNSET) out->noise_target = 0.0; /* a render's, never the scene's */
    PICK_INT(photons, 1, 0);                  /* 0 stays: the photon integrator's default */
    PICK_DBL(photon_radius, 1, 0.0);          /* 0 stays: automatic */
    PICK_INT(sampler, 1, CST_SAMPLER_ZSOBOL);    /* pbrt-v4's default too */
    PICK_INT(color_mode, 1, CST_COLOR_RGB);
    PICK_DBL(max_component, 1, 0.0);          /* 0 = no clamp */
    PICK_INT(regularize, 0, 0);
    PICK_INT(subsurface_walk, 0, 0);
    PICK_DBL(mlt_large_step, 0, 0.3);         /* pbrt-v4's MLT defaults */
    PICK_DBL(mlt_sigma, 1, 0.01);
    PICK_INT(mlt_bootstrap, 1, 100000);
    PICK_INT(mlt_chains, 1, 1000);
    PICK_INT(png_linear, 0, 0);
    PICK_INT(aovs, 0, 0);
    PICK_DBL(white_balance, 1, 0.0);          /* 0 = none */
    /* A time limit alone means "as many samples as fit", a noise target "as many as it
     * needs" (up to CST_NOISE_SPP_CAP); otherwise the default count.
     * CST_SPP_UNLIMITED says so over a scene's spp (cst_render refuses it without a time
     * limit). */
    PICK_INT(spp, 1, out->time_limit > 0.0 || out->noise_target > 0.0 ? 0 : CST_DEFAULT_SPP);
    if (in->spp == CST_SPP_UNLIMITED) out->spp = 0;
    if (in->crop[0] == CST_UNSET) memcpy(out->crop, sc->crop, sizeof out->crop);
    if (out->crop[0] == CST_UNSET || !(out->crop[0] | out->crop[1] | out->crop[2] | out->crop[3])) {
        out->crop[0] = 0; out->crop[1] = out->width;
        out->crop[2] = 0; out->crop[3] = out->height;
    }
    if (out->first_sample == CST_UNSET) out->first_sample = 0; /* a render's, never the scene's */
    if (out->sample_block == CST_UNSET || out->sample_block == 0) out->sample_block = 1;
    if (!in->seed_set) { out->seed = sc->seed_set ? sc->seed : 0; out->seed_set = 1; }
    if (!in->exposure_set) { out->exposure = sc->exposure_set ? sc->exposure : 0.0; out->exposure_set = 1; }
    if (out->threads <= 0) { /* 0 and CST_UNSET: one per core */
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        out->threads = n > 0 ? (int)n : 1;
    }
}
#undef PICK_INT
#undef PICK_DBL
