/* The majorant grid's DDA (majorant.h): cell stepping as in Amanatides & Woo 1987, the
 * next crossing per axis kept in t so that every step is one comparison and one add. */
#include "media/majorant.h"

#include <math.h>

static inline float axis(Vec3 v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

void majorant_dda_init(MajorantDda *it, const MajorantGrid *g, Vec3 o, Vec3 d, float t0, float t1)
{
    it->g = g;
    it->t = t0;
    it->t_end = t1;
    /* The cell of the entry point; clamped, as rounding may put it a hair outside. */
    Vec3 p = v3_add(o, v3_scale(d, t0));
    for (int a = 0; a < 3; a++) {
        int n = g->res[a];
        float pa = axis(p, a), da = axis(d, a);
        int c = (int)floorf(pa * (float)n);
        c = c < 0 ? 0 : c >= n ? n - 1 : c;
        it->cell[a] = c;
        if (da > 0.0f) {
            it->step[a] = 1;
            it->limit[a] = n;
            it->dt[a] = 1.0f / (da * (float)n);
            it->next_t[a] = t0 + ((float)(c + 1) / (float)n - pa) / da;
        } else if (da < 0.0f) {
            it->step[a] = -1;
            it->limit[a] = -1;
            it->dt[a] = -1.0f / (da * (float)n);
            it->next_t[a] = t0 + ((float)c / (float)n - pa) / da;
        } else { /* parallel to the slabs of this axis: never crosses one */
            it->step[a] = 0;
            it->limit[a] = -2;
            it->dt[a] = INFINITY;
            it->next_t[a] = INFINITY;
        }
    }
}

bool majorant_dda_next(MajorantDda *it, MajorantSeg *seg)
{
    if (!(it->t < it->t_end)) return false;
    const MajorantGrid *g = it->g;
    int a = it->next_t[0] < it->next_t[1] ? 0 : 1;
    if (it->next_t[2] < it->next_t[a]) a = 2;
    float t1 = fminf(it->next_t[a], it->t_end);
    /* A crossing rounded to before the entry: an empty step, kept at zero length. */
    if (t1 < it->t) t1 = it->t;
    seg->t0 = it->t;
    seg->t1 = t1;
    seg->cell[0] = it->cell[0];
    seg->cell[1] = it->cell[1];
    seg->cell[2] = it->cell[2];
    seg->maj = g->max[(it->cell[2] * g->res[1] + it->cell[1]) * g->res[0] + it->cell[0]];
    it->t = t1;
    it->cell[a] += it->step[a];
    /* Leaving the grid ends the walk, whatever rounding says about t_end. */
    if (it->cell[a] == it->limit[a]) it->t = it->t_end;
    it->next_t[a] += it->dt[a];
    return true;
}

bool majorant_clip(Vec3 o, Vec3 d, Vec3 lo, Vec3 hi, float t0, float t1, float *out0, float *out1)
{
    for (int a = 0; a < 3; a++) {
        float oa = axis(o, a), da = axis(d, a), l = axis(lo, a), h = axis(hi, a);
        if (da == 0.0f) {
            if (oa < l || oa > h) return false;
            continue;
        }
        float inv = 1.0f / da;
        float tn = (l - oa) * inv, tf = (h - oa) * inv;
        if (tn > tf) {
            float tmp = tn;
            tn = tf;
            tf = tmp;
        }
        t0 = tn > t0 ? tn : t0;
        t1 = tf < t1 ? tf : t1;
        if (!(t0 < t1)) return false;
    }
    *out0 = t0;
    *out1 = t1;
    return true;
}
