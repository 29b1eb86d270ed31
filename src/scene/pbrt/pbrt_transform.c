/* Transforms with their inverses, the current transformation matrix, the graphics-state
 * stack and named coordinate systems, and the directives that change them. */
#include "scene/pbrt/pbrt_transform.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


Xf pbrt_xf_identity(void)
{
    Xf x = {transform_identity(), transform_identity(), 1};
    return x;
}

Xf pbrt_xf_compose(const Xf *a, const Xf *b)
{
    Xf r;
    r.m = transform_compose(a->m, b->m);
    r.inv = transform_compose(b->inv, a->inv);
    r.inv_ok = a->inv_ok && b->inv_ok;
    return r;
}

/* From a matrix alone, inverting it. */
static Xf xf_from(Transform m)
{
    Xf r;
    r.m = m;
    r.inv_ok = transform_invert(&m, &r.inv);
    if (!r.inv_ok) r.inv = transform_identity();
    return r;
}

Xf pbrt_xf_swap(Xf x)
{
    Transform t = x.m;
    x.m = x.inv;
    x.inv = t;
    return x;
}

/* pbrt's LookAt: camera-from-world for a camera at eye looking at look, with camera x =
 * normalize(up x dir) (left-handed), y the orthogonalised up and z = dir. Built directly
 * with its inverse (world-from-camera, the frame's columns), in double. */
static int xf_look_at(const double e[3], const double l[3], const double u[3], Xf *out)
{
    double d[3] = {l[0] - e[0], l[1] - e[1], l[2] - e[2]};
    double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(dl > 0.0) || !(ul > 0.0) || !isfinite(dl) || !isfinite(ul)) return 0;
    double un[3] = {u[0] / ul, u[1] / ul, u[2] / ul};
    for (int k = 0; k < 3; k++) d[k] /= dl;
    double r[3] = {un[1] * d[2] - un[2] * d[1], un[2] * d[0] - un[0] * d[2], un[0] * d[1] - un[1] * d[0]};
    double rl = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(rl > 1e-6)) return 0;
    for (int k = 0; k < 3; k++) r[k] /= rl;
    double nu[3] = {d[1] * r[2] - d[2] * r[1], d[2] * r[0] - d[0] * r[2], d[0] * r[1] - d[1] * r[0]};
    Transform w = transform_identity(), c = transform_identity();
    for (int k = 0; k < 3; k++) {
        w.m[k][0] = (float)r[k];
        w.m[k][1] = (float)nu[k];
        w.m[k][2] = (float)d[k];
        w.m[k][3] = (float)e[k];
        c.m[0][k] = (float)r[k];
        c.m[1][k] = (float)nu[k];
        c.m[2][k] = (float)d[k];
    }
    c.m[0][3] = (float)-(r[0] * e[0] + r[1] * e[1] + r[2] * e[2]);
    c.m[1][3] = (float)-(nu[0] * e[0] + nu[1] * e[1] + nu[2] * e[2]);
    c.m[2][3] = (float)-(d[0] * e[0] + d[1] * e[1] + d[2] * e[2]);
    out->m = c;
    out->inv = w;
    out->inv_ok = 1;
    return 1;
}

static int xf_finite(const Xf *x)
{
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            if (!isfinite(x->m.m[r][c])) return 0;
    return 1;
}

/* pbrt-v4's ForActiveTransforms: t applied (after the CTM) to the start CTM, the end CTM, or
 * both, as ActiveTransform chose. */
static CstStatus apply_ctm(Loader *ld, Xf t, Loc loc, const char *d)
{
    if (!xf_finite(&t))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the transform is not finite in 32-bit floats", d);
    if (ld->gs.active_start) ld->gs.ctm = pbrt_xf_compose(&ld->gs.ctm, &t);
    if (ld->gs.active_end) ld->gs.ctm_end = pbrt_xf_compose(&ld->gs.ctm_end, &t);
    return CST_OK;
}

/* Transform and Identity: the active CTMs replaced by x. */
static void set_ctm(Loader *ld, Xf x)
{
    if (ld->gs.active_start) ld->gs.ctm = x;
    if (ld->gs.active_end) ld->gs.ctm_end = x;
}

int pbrt_ctm_moving(const Loader *ld)
{
    return memcmp(ld->gs.ctm.m.m, ld->gs.ctm_end.m.m, sizeof ld->gs.ctm.m.m) != 0;
}

void pbrt_warn_static(Loader *ld, Loc loc, const char *d, const char *why)
{
    if (pbrt_ctm_moving(ld))
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s moves (its transform differs between the start and end "
                     "times) but %s: rendered static at its start-time transform", d, why);
}

static int find_named_xf(Loader *ld, const char *name)
{
    for (int i = 0; i < ld->num_coords; i++)
        if (strcmp(ld->coords[i].name, name) == 0) return i;
    return -1;
}

CstStatus pbrt_set_named_xf(Loader *ld, const char *name, Xf xf, Xf xf_end)
{
    int i = find_named_xf(ld, name);
    if (i < 0) {
        if (!GROW(ld->coords, ld->cap_coords, ld->num_coords + 1)) return pbrt_oom(ld);
        char *n = pbrt_dup_str(name);
        if (!n) return pbrt_oom(ld);
        i = ld->num_coords++;
        ld->coords[i].name = n;
    }
    ld->coords[i].xf = xf;
    ld->coords[i].xf_end = xf_end;
    return CST_OK;
}

CstStatus pbrt_push_state(Loader *ld, Loc loc, int transform_only)
{
    if (!GROW(ld->stack, ld->cap_stack, ld->num_stack + 1)) return pbrt_oom(ld);
    ld->gs.transform_only = transform_only;
    ld->gs.loc = loc;
    ld->stack[ld->num_stack++] = ld->gs;
    return CST_OK;
}

CstStatus pbrt_pop_state(Loader *ld, Loc loc, int transform_only, const char *d)
{
    if (ld->num_stack == 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s without a matching %s; expected %s only "
                            "after %s", d, transform_only ? "TransformBegin" : "AttributeBegin", d,
                            transform_only ? "TransformBegin" : "AttributeBegin");
    GState *top = &ld->stack[ld->num_stack - 1];
    if (top->transform_only != transform_only)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s closes the %s at line %d; expected %s",
                            d, top->transform_only ? "TransformBegin" : "AttributeBegin", top->loc.line,
                            top->transform_only ? "TransformEnd" : "AttributeEnd");
    if (transform_only) {
        ld->gs.ctm = top->ctm;
        ld->gs.ctm_end = top->ctm_end;
    } else {
        ld->gs = *top;
    }
    ld->num_stack--;
    return CST_OK;
}

CstStatus pbrt_translate_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[3];
    TRY(pbrt_expect_numbers(ld, lx, dname, 3, v));
    Xf x = {transform_translate(v3((float)v[0], (float)v[1], (float)v[2])),
            transform_translate(v3(-(float)v[0], -(float)v[1], -(float)v[2])), 1};
    return apply_ctm(ld, x, loc, dname);
}

CstStatus pbrt_scale_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[3];
    TRY(pbrt_expect_numbers(ld, lx, dname, 3, v));
    Vec3 sc = v3((float)v[0], (float)v[1], (float)v[2]);
    Xf x = {transform_scale(sc), transform_identity(), 0};
    if (sc.x != 0.0f && sc.y != 0.0f && sc.z != 0.0f) {
        x.inv = transform_scale(v3(1.0f / sc.x, 1.0f / sc.y, 1.0f / sc.z));
        x.inv_ok = 1;
    }
    return apply_ctm(ld, x, loc, dname);
}

CstStatus pbrt_rotate_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[4];
    TRY(pbrt_expect_numbers(ld, lx, dname, 4, v));
    Vec3 axis = v3((float)v[1], (float)v[2], (float)v[3]);
    if (!(v3_max_abs(axis) > 0.0f) || !v3_is_finite(axis))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "Rotate: axis (%g, %g, %g); expected a "
                            "nonzero finite axis", v[1], v[2], v[3]);
    Xf x = {transform_rotate_degrees(axis, v[0]), transform_rotate_degrees(axis, -v[0]), 1};
    return apply_ctm(ld, x, loc, dname);
}

CstStatus pbrt_look_at_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[9];
    TRY(pbrt_expect_numbers(ld, lx, dname, 9, v));
    Xf x;
    if (!xf_look_at(v, v + 3, v + 6, &x))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "LookAt: eye equals look, or up is zero or "
                       "parallel to the view direction; expected eye != look and up not along "
                            "look - eye");
    return apply_ctm(ld, x, loc, dname);
}

/* Transform replaces the CTM, ConcatTransform multiplies it. */
CstStatus pbrt_transform_directive(Loader *ld, Lexer *lx, Loc loc, const char *d)
{
    double v[16];
    TRY(pbrt_expect_number_array(ld, lx, d, 16, v));
    /* The file lists the matrix column by column (pbrt transposes it on reading). */
    float rows[16];
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) rows[4 * r + c] = (float)v[4 * c + r];
    Transform m = transform_from_rows(rows);
    for (int k = 0; k < 16; k++)
        if (!isfinite(rows[k]))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: element %d is not finite in 32-bit "
                                "floats; expected finite numbers", d, 4 * (k % 4) + k / 4 + 1);
    if (!transform_is_affine(&m)) {
        /* pbrt-v4 keeps the whole 4x4 matrix: points are divided by w (triangle meshes get
         * exactly that, pbrt_shape.c), directions and normals use the upper 3x3 alone (as
         * we do everywhere). What caustic cannot follow: points of lights and cameras, and
         * spheres (tessellated), use the affine part; the inverse is the affine part's. */
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: a projective matrix (bottom row %g %g %g %g, "
                     "elements 4, 8, 12, 16): kept as pbrt-v4 keeps it; triangle meshes are "
                     "divided by w as in pbrt-v4, directions use the 3x3 part as in pbrt-v4, "
                     "light and camera positions and spheres use the affine part", d,
                     v[3], v[7], v[11], v[15]);
    }
    Xf x = xf_from(m);
    if (d[0] == 'T') {
        set_ctm(ld, x);
        return CST_OK;
    }
    return apply_ctm(ld, x, loc, d);
}

CstStatus pbrt_identity_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx, (void)loc, (void)dname;
    set_ctm(ld, pbrt_xf_identity());
    return CST_OK;
}

/* CoordinateSystem names the CTM, CoordSysTransform makes a named one current. */
CstStatus pbrt_coordinate_system_directive(Loader *ld, Lexer *lx, Loc loc, const char *d)
{
    (void)loc;
    char *s = NULL, nm[72];
    CstStatus st = CST_OK;
    int set = strcmp(d, "CoordinateSystem") == 0;
    Loc nl;
    TRY(pbrt_expect_string(ld, lx, d, "a coordinate system name", &s, &nl));
    if (set) {
        st = pbrt_set_named_xf(ld, s, ld->gs.ctm, ld->gs.ctm_end);
    } else {
        int i = find_named_xf(ld, s);
        if (i < 0) st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, nl, "CoordSysTransform: \"%s\" is not defined; "
                                     "expected a name given to CoordinateSystem (or \"camera\" after Camera)",
                                     pbrt_clip(s, nm));
        else {
            ld->gs.ctm = ld->coords[i].xf; /* both, whatever is active (pbrt-v4) */
            ld->gs.ctm_end = ld->coords[i].xf_end;
        }
    }
    free(s);
    return st;
}

CstStatus pbrt_active_transform_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)loc, (void)dname;
    PbrtToken w;
    TRY(pbrt_lex_next(ld, lx, &w));
    if (w.kind == PBRT_TOK_WORD && pbrt_tok_is(&w, "StartTime")) { ld->gs.active_start = 1; ld->gs.active_end = 0; }
    else if (w.kind == PBRT_TOK_WORD && pbrt_tok_is(&w, "EndTime")) { ld->gs.active_start = 0; ld->gs.active_end = 1; }
    else if (w.kind == PBRT_TOK_WORD && pbrt_tok_is(&w, "All")) { ld->gs.active_start = ld->gs.active_end = 1; }
    else {
        char got[96];
        pbrt_token_describe(&w, got, sizeof got);
        return pbrt_fail_at(ld, CST_ERR_PARSE, pbrt_tok_loc(lx, &w), "ActiveTransform: got %s; expected "
                            "StartTime, EndTime or All", got);
    }
    return CST_OK;
}

/* The times of the start and end CTMs (pbrt-v4: an option, before WorldBegin). Every
 * motion and the shutter are mapped to caustic's times, where start is 0 and end is 1. */
CstStatus pbrt_transform_times_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[2];
    TRY(pbrt_expect_numbers(ld, lx, dname, 2, v));
    if (ld->in_world)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "TransformTimes after WorldBegin; expected it before "
                            "WorldBegin (an option, as in pbrt-v4)");
    if (!(v[0] < v[1]) || !isfinite(v[1] - v[0]))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "TransformTimes %g %g; expected finite times with "
                            "start < end", v[0], v[1]);
    ld->transform_times[0] = v[0];
    ld->transform_times[1] = v[1];
    return CST_OK;
}

CstStatus pbrt_reverse_orientation_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx, (void)loc, (void)dname;
    ld->gs.reverse = !ld->gs.reverse;
    return CST_OK;
}

/* AttributeBegin/End push and pop the whole graphics state, TransformBegin/End (pbrt-v3)
 * only the CTM. */
CstStatus pbrt_begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx;
    return pbrt_push_state(ld, loc, dname[0] == 'T');
}

CstStatus pbrt_end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx;
    return pbrt_pop_state(ld, loc, dname[0] == 'T', dname);
}

CstStatus pbrt_world_begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx, (void)dname;
    if (ld->in_world)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "WorldBegin a second time; expected one world block");
    ld->in_world = 1;
    /* pbrt-v4 resets both CTMs and makes both active again. */
    ld->gs.ctm = ld->gs.ctm_end = pbrt_xf_identity();
    ld->gs.active_start = ld->gs.active_end = 1;
    return pbrt_set_named_xf(ld, "world", ld->gs.ctm, ld->gs.ctm_end);
}

/* pbrt-v3: the end of the file follows */
CstStatus pbrt_world_end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)ld, (void)lx, (void)loc, (void)dname;
    return CST_OK;
}
