/* pbrt's participating media (pbrt_medium.h): pbrt-v4's homogeneous medium with its
 * parameters and defaults (HomogeneousMedium::Create: sigma_a = sigma_s = 1, scale 1,
 * g 0, Le 0, Lescale 1), names resolved when MediumInterface names them, other medium
 * types and presets a located warning (read as vacuum). */
#include "scene/pbrt/pbrt_medium.h"

#include <stdlib.h>
#include <string.h>

#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_spectrum.h"

static CstStatus add_name(Loader *ld, const char *name, int id)
{
    if (!GROW(ld->med_names, ld->cap_meds, ld->num_meds + 1) || !GROW(ld->med_ids, ld->cap_med_ids, ld->num_meds + 1))
        return pbrt_oom(ld);
    if (!(ld->med_names[ld->num_meds] = pbrt_dup_str(name))) return pbrt_oom(ld);
    ld->med_ids[ld->num_meds++] = id;
    return CST_OK;
}

CstStatus pbrt_make_named_medium_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *d = call->d, *name = call->type, *type = NULL;
    Loc tloc = call->loc;
    TRY(pbrt_get_string(ld, ps, d, "type", &type, &tloc));
    if (!type)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, call->loc, "%s: no \"string type\"; expected the medium's "
                            "type (\"homogeneous\")", d);
    char buf[72];
    const char *preset = NULL;
    if (strcmp(type, "homogeneous") == 0) TRY(pbrt_get_string(ld, ps, d, "preset", &preset, NULL));
    if (strcmp(type, "homogeneous") != 0 || preset) {
        pbrt_params_mark_all_used(ps);
        if (preset)
            pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, tloc, "%s: the measured preset \"%s\" is not supported; the "
                         "medium is vacuum", d, pbrt_clip(preset, buf));
        else
            pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, tloc, "%s: medium type \"%s\" is not supported (only "
                         "\"homogeneous\"); the medium is vacuum", d, pbrt_clip(type, buf));
        return add_name(ld, name, -1);
    }
    CstMediumDesc md;
    cst_medium_desc_init(&md);
    Color sa = color_s(1.0f), ss = color_s(1.0f), le = color_s(0.0f);
    TRY(pbrt_get_spectrum(ld, ps, d, "sigma_a", SPEC_UNBOUNDED, 0, &sa, NULL));
    TRY(pbrt_get_spectrum(ld, ps, d, "sigma_s", SPEC_UNBOUNDED, 0, &ss, NULL));
    TRY(pbrt_get_spectrum(ld, ps, d, "Le", SPEC_ILLUMINANT, 0, &le, NULL));
    TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &md.scale, NULL));
    TRY(pbrt_get_float(ld, ps, d, "Lescale", 1.0f, &md.le_scale, NULL));
    TRY(pbrt_get_float(ld, ps, d, "g", 0.0f, &md.g, NULL));
    pbrt_color_floats(sa, md.sigma_a);
    pbrt_color_floats(ss, md.sigma_s);
    pbrt_color_floats(le, md.le);
    pbrt_params_warn_unused(ld, ps, d);
    int id;
    CstStatus st = cst_scene_add_medium(ld->scene, &md, &id, ld->err);
    if (st) return pbrt_fail_wrap(ld, st, call->loc, d);
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
