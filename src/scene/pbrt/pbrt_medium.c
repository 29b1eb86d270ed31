/* pbrt's participating media (pbrt_medium.h): pbrt-v4's homogeneous, uniformgrid and cloud
 * media with their parameters and defaults (HomogeneousMedium::Create: sigma_a = sigma_s
 * = 1, scale 1, g 0, Le 0, Lescale 1, "preset"; GridMedium::Create: p0 (0,0,0), p1
 * (1,1,1), nx = ny = nz = 1, density required; CloudMedium::Create: density 1, wispiness
 * 1, frequency 5), names resolved when MediumInterface names them, other medium types a
 * located warning (read as vacuum). */
#include "scene/pbrt/pbrt_medium.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "media/medium_presets.h"

#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_spectrum.h"
#include "scene/pbrt/pbrt_transform.h"

static CstStatus add_name(Loader *ld, const char *name, int id)
{
    if (!GROW(ld->med_names, ld->cap_meds, ld->num_meds + 1) || !GROW(ld->med_ids, ld->cap_med_ids, ld->num_meds + 1))
        return pbrt_oom(ld);
    if (!(ld->med_names[ld->num_meds] = pbrt_dup_str(name))) return pbrt_oom(ld);
    ld->med_ids[ld->num_meds++] = id;
    return CST_OK;
}

/* A "point3" parameter into out (unchanged when absent). */
static CstStatus get_point3(Loader *ld, Params *ps, const char *d, const char *name, float out[3])
{
    Param *p;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_POINT3), "point3", &p));
    if (!p) return CST_OK;
    char nm[72];
    if (p->num_nums != 3)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" has %d values; expected 3", d,
                            pbrt_clip(p->decl, nm), p->num_nums);
    for (int i = 0; i < 3; i++) {
        double v = p->nums[i];
        if (!(fabs(v) <= 1e30))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" value %d is %g; expected a finite "
                                "coordinate", d, pbrt_clip(p->decl, nm), i + 1, v);
        out[i] = (float)v;
    }
    return CST_OK;
}

/* A "float" array of exactly count values >= 0 (pbrt-v4's grid samples) into a new array
 * (*out; NULL when absent, *found then 0). */
static CstStatus get_grid(Loader *ld, Params *ps, const char *d, const char *name, size_t count, float **out,
                          int *found)
{
    *out = NULL;
    *found = 0;
    Param *p;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_FLOAT), "float", &p));
    if (!p) return CST_OK;
    *found = 1;
    char nm[72];
    if ((size_t)p->num_nums != count)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" has %d values; expected nx*ny*nz = %zu",
                            d, pbrt_clip(p->decl, nm), p->num_nums, count);
    for (size_t i = 0; i < count; i++)
        if (!(p->nums[i] >= 0.0 && p->nums[i] <= 1e30))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" value %zu is %g; expected finite "
                                "values >= 0", d, pbrt_clip(p->decl, nm), i + 1, p->nums[i]);
    float *a = malloc((count ? count : 1) * sizeof *a);
    if (!a) return pbrt_oom(ld);
    for (size_t i = 0; i < count; i++) a[i] = (float)p->nums[i];
    *out = a;
    return CST_OK;
}

/* pbrt-v4's GridMedium::Create and CloudMedium::Create parameters (the coefficients are
 * read by the caller), placed by the CTM. The grid arrays are new (caller frees). */
static CstStatus read_hetero(Loader *ld, NamedCall *call, bool cloud, CstMediumDesc *md, float **density,
                             float **le_grid)
{
    Params *ps = &call->ps;
    const char *d = call->d;
    md->type = cloud ? CST_MEDIUM_CLOUD : CST_MEDIUM_UNIFORMGRID;
    const Transform *m = &ld->gs.ctm.m;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) md->world_from_medium[4 * r + c] = m->m[r][c];
    TRY(get_point3(ld, ps, d, "p0", md->p0));
    TRY(get_point3(ld, ps, d, "p1", md->p1));
    for (int a = 0; a < 3; a++)
        if (!(md->p0[a] != md->p1[a]))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, call->loc, "%s: p0 and p1 are equal on an axis; expected a "
                                "box of positive size", d);
    if (cloud) {
        TRY(pbrt_get_float(ld, ps, d, "density", 1.0f, &md->cloud_density, NULL));
        TRY(pbrt_get_float(ld, ps, d, "wispiness", 1.0f, &md->wispiness, NULL));
        TRY(pbrt_get_float(ld, ps, d, "frequency", 5.0f, &md->frequency, NULL));
        return CST_OK;
    }
    TRY(pbrt_get_int(ld, ps, d, "nx", 1, &md->nx));
    TRY(pbrt_get_int(ld, ps, d, "ny", 1, &md->ny));
    TRY(pbrt_get_int(ld, ps, d, "nz", 1, &md->nz));
    if (md->nx < 1 || md->ny < 1 || md->nz < 1 || md->nx > 4096 || md->ny > 4096 || md->nz > 4096)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, call->loc, "%s: nx, ny, nz = %d, %d, %d; expected each in 1 .. "
                            "4096", d, md->nx, md->ny, md->nz);
    size_t count = (size_t)md->nx * (size_t)md->ny * (size_t)md->nz;
    int found;
    TRY(get_grid(ld, ps, d, "density", count, density, &found));
    if (!found)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, call->loc, "%s: no \"float density\"; expected nx*ny*nz = %zu "
                            "values", d, count);
    Param *lp = pbrt_find_param(ps, "Lescale");
    if (lp && lp->type == PT_FLOAT && lp->num_nums == 1 && count != 1) {
        /* One value: a constant scale (pbrt-v4 asks for a whole grid; accepted). */
        TRY(pbrt_get_float(ld, ps, d, "Lescale", 1.0f, &md->le_scale, NULL));
    } else {
        TRY(get_grid(ld, ps, d, "Lescale", count, le_grid, &found));
        md->le_scale_grid = *le_grid;
    }
    Param *tp = pbrt_find_param(ps, "temperature");
    if (tp) {
        pbrt_params_mark_all_used(ps);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, tp->loc, "%s: the \"temperature\" grid (blackbody emission) is not "
                     "supported; the medium does not emit", d);
        md->le[0] = md->le[1] = md->le[2] = 0.0f;
    }
    md->density = *density;
    return CST_OK;
}

CstStatus pbrt_make_named_medium_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *d = call->d, *name = call->type, *type = NULL;
    Loc tloc = call->loc;
    pbrt_warn_static(ld, call->loc, d, "media do not move (as in pbrt-v4)");
    TRY(pbrt_get_string(ld, ps, d, "type", &type, &tloc));
    if (!type)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, call->loc, "%s: no \"string type\"; expected the medium's "
                            "type (\"homogeneous\", \"uniformgrid\", \"cloud\")", d);
    char buf[72];
    const bool homog = strcmp(type, "homogeneous") == 0, grid = strcmp(type, "uniformgrid") == 0,
               cloud = strcmp(type, "cloud") == 0;
    if (!homog && !grid && !cloud) {
        pbrt_params_mark_all_used(ps);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, tloc, "%s: medium type \"%s\" is not supported (only "
                     "\"homogeneous\", \"uniformgrid\", \"cloud\"); the medium is vacuum", d, pbrt_clip(type, buf));
        return add_name(ld, name, -1);
    }
    CstMediumDesc md;
    cst_medium_desc_init(&md);
    Color sa = color_s(1.0f), ss = color_s(1.0f), le = color_s(0.0f);
    const char *preset = NULL;
    Loc ploc = call->loc;
    /* Only pbrt-v4's homogeneous medium reads "preset"; an unknown one is a warning there
     * (sigma_a and sigma_s are then read as if there were none). */
    if (homog) TRY(pbrt_get_string(ld, ps, d, "preset", &preset, &ploc));
    if (preset && !medium_preset(preset, &sa, &ss)) {
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, ploc, "%s: no scattering preset is called \"%s\" (pbrt-v4's names: "
                     "\"Skimmilk\", \"Wholemilk\", \"Ketchup\", ...); sigma_a and sigma_s are used", d,
                     pbrt_clip(preset, buf));
        preset = NULL;
    }
    /* A preset's coefficients replace sigma_a and sigma_s, which pbrt-v4 then does not
     * read (so they are reported unused). */
    if (!preset) {
        TRY(pbrt_get_spectrum(ld, ps, d, "sigma_a", SPEC_UNBOUNDED, 0, &sa, NULL));
        TRY(pbrt_get_spectrum(ld, ps, d, "sigma_s", SPEC_UNBOUNDED, 0, &ss, NULL));
    }
    if (!cloud) TRY(pbrt_get_spectrum(ld, ps, d, "Le", SPEC_ILLUMINANT, 0, &le, NULL));
    TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &md.scale, NULL));
    if (homog) TRY(pbrt_get_float(ld, ps, d, "Lescale", 1.0f, &md.le_scale, NULL));
    TRY(pbrt_get_float(ld, ps, d, "g", 0.0f, &md.g, NULL));
    pbrt_color_floats(sa, md.sigma_a);
    pbrt_color_floats(ss, md.sigma_s);
    pbrt_color_floats(le, md.le);
    float *density = NULL, *le_grid = NULL;
    CstStatus st = homog ? CST_OK : read_hetero(ld, call, cloud, &md, &density, &le_grid);
    int id = -1;
    if (st == CST_OK) {
        pbrt_params_warn_unused(ld, ps, d);
        st = cst_scene_add_medium(ld->scene, &md, &id, ld->err);
        if (st) st = pbrt_fail_wrap(ld, st, call->loc, d);
    }
    free(density);
    free(le_grid);
    if (st) return st;
    return add_name(ld, name, id);
}

/* 1 + the scene medium named name, 0 for "" (vacuum) or a medium caustic reads as
 * vacuum; an unknown name is a located error. */
static CstStatus resolve(Loader *ld, const char *name, Loc loc, const char *dname, int *out)
{
    *out = 0;
    if (!name[0]) return CST_OK;
    for (int i = ld->num_meds - 1; i >= 0; i--)
        if (strcmp(ld->med_names[i], name) == 0) {
            *out = ld->med_ids[i] + 1;
            return CST_OK;
        }
    char buf[72];
    return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: medium \"%s\" is not defined; expected a name given "
                        "to MakeNamedMedium before, or \"\" for vacuum", dname, pbrt_clip(name, buf));
}

CstStatus pbrt_medium_interface_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    char *in = NULL, *out = NULL;
    Loc lin, lout;
    TRY(pbrt_expect_string(ld, lx, dname, "the inside medium's name", &in, &lin));
    PbrtToken n2;
    CstStatus st = pbrt_lex_peek(ld, lx, &n2);
    if (!st && n2.kind == PBRT_TOK_STRING) st = pbrt_expect_string(ld, lx, dname, "the outside medium's name", &out, &lout);
    (void)loc;
    /* One name: both sides (pbrt-v4). */
    int mi = 0, mo = 0;
    if (!st) st = resolve(ld, in, lin, dname, &mi);
    if (!st) st = out ? resolve(ld, out, lout, dname, &mo) : (mo = mi, CST_OK);
    free(in);
    free(out);
    if (st) return st;
    ld->gs.med_in = mi;
    ld->gs.med_out = mo;
    return CST_OK;
}

CstStatus pbrt_medium_apply(Loader *ld, int boundary, Loc loc, const char *d)
{
    if (ld->num_meds == 0) return CST_OK;
    CstStatus st = cst_scene_set_medium_interface(ld->scene, ld->gs.med_in - 1, ld->gs.med_out - 1,
                                                  boundary && pbrt_medium_transition(ld), ld->err);
    return st ? pbrt_fail_wrap(ld, st, loc, d) : CST_OK;
}
