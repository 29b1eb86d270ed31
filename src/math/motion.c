/* Motion transforms (math/motion.h): polar decomposition of the ends, interpolation at a
 * ray's time, and the box swept over the shutter interval. */
#include "math/motion.h"

#include <math.h>
#include <string.h>

static double det3(const double m[9])
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
           m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/* inverse transpose of m; false when singular. */
static bool inv_transpose3(const double m[9], double out[9])
{
    double d = det3(m);
    if (!(fabs(d) > 0.0) || !isfinite(d)) return false;
    double inv = 1.0 / d;
    /* the cofactor matrix divided by det is the inverse transpose */
    out[0] = (m[4] * m[8] - m[5] * m[7]) * inv;
    out[1] = -(m[3] * m[8] - m[5] * m[6]) * inv;
    out[2] = (m[3] * m[7] - m[4] * m[6]) * inv;
    out[3] = -(m[1] * m[8] - m[2] * m[7]) * inv;
    out[4] = (m[0] * m[8] - m[2] * m[6]) * inv;
    out[5] = -(m[0] * m[7] - m[1] * m[6]) * inv;
    out[6] = (m[1] * m[5] - m[2] * m[4]) * inv;
    out[7] = -(m[0] * m[5] - m[2] * m[3]) * inv;
    out[8] = (m[0] * m[4] - m[1] * m[3]) * inv;
    return true;
}

/* Unit quaternion of the rotation matrix r (row-major, det +1): Shoemake, "Animating
 * Rotation with Quaternion Curves", SIGGRAPH 1985, the branch on the largest diagonal
 * term for accuracy. */
static void quat_from_matrix(const double r[9], double q[4])
{
    double tr = r[0] + r[4] + r[8];
    if (tr > 0.0) {
        double s = sqrt(tr + 1.0) * 2.0;
        q[3] = 0.25 * s;
        q[0] = (r[7] - r[5]) / s;
        q[1] = (r[2] - r[6]) / s;
        q[2] = (r[3] - r[1]) / s;
    } else if (r[0] > r[4] && r[0] > r[8]) {
        double s = sqrt(1.0 + r[0] - r[4] - r[8]) * 2.0;
        q[3] = (r[7] - r[5]) / s;
        q[0] = 0.25 * s;
        q[1] = (r[1] + r[3]) / s;
        q[2] = (r[2] + r[6]) / s;
    } else if (r[4] > r[8]) {
        double s = sqrt(1.0 + r[4] - r[0] - r[8]) * 2.0;
        q[3] = (r[2] - r[6]) / s;
        q[0] = (r[1] + r[3]) / s;
        q[1] = 0.25 * s;
        q[2] = (r[5] + r[7]) / s;
    } else {
        double s = sqrt(1.0 + r[8] - r[0] - r[4]) * 2.0;
        q[3] = (r[3] - r[1]) / s;
        q[0] = (r[2] + r[6]) / s;
        q[1] = (r[5] + r[7]) / s;
        q[2] = 0.25 * s;
    }
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int i = 0; i < 4; i++) q[i] /= n;
}

static void matrix_from_quat(const double q[4], double r[9])
{
    double x = q[0], y = q[1], z = q[2], w = q[3];
    r[0] = 1.0 - 2.0 * (y * y + z * z); r[1] = 2.0 * (x * y - z * w);       r[2] = 2.0 * (x * z + y * w);
    r[3] = 2.0 * (x * y + z * w);       r[4] = 1.0 - 2.0 * (x * x + z * z); r[5] = 2.0 * (y * z - x * w);
    r[6] = 2.0 * (x * z - y * w);       r[7] = 2.0 * (y * z + x * w);       r[8] = 1.0 - 2.0 * (x * x + y * y);
}

/* M = R S by the iteration R <- (R + R^-T) / 2 (Higham 1986; Shoemake & Duff 1992, sec. 3),
 * which converges quadratically to the orthogonal factor; S = R^T M. */
static bool decompose(const Transform *t, double tr[3], double q[4], double stretch[9])
{
    if (!transform_is_affine(t)) return false;
    double m[9], r[9];
    for (int i = 0; i < 3; i++) {
        tr[i] = (double)t->m[i][3];
        for (int j = 0; j < 3; j++) m[3 * i + j] = (double)t->m[i][j];
    }
    double d = det3(m);
    if (!(fabs(d) > 0.0) || !isfinite(d)) return false;
    memcpy(r, m, sizeof r);
    for (int it = 0; it < 100; it++) {
        double rit[9], diff = 0.0;
        if (!inv_transpose3(r, rit)) return false;
        for (int k = 0; k < 9; k++) {
            double nk = 0.5 * (r[k] + rit[k]);
            diff = fmax(diff, fabs(nk - r[k]));
            r[k] = nk;
        }
        if (diff < 1e-12) break;
    }
    /* A mirroring M has an orthogonal factor with det -1, no rotation: the reflection goes
     * to the stretch instead (M = (-R)(-S)). */
    if (d < 0.0)
        for (int k = 0; k < 9; k++) r[k] = -r[k];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            stretch[3 * i + j] = r[i] * m[j] + r[3 + i] * m[3 + j] + r[6 + i] * m[6 + j]; /* R^T M */
    quat_from_matrix(r, q);
    return true;
}

bool motion_init(MotionTransform *mt, const Transform *start, const Transform *end)
{
    memset(mt, 0, sizeof *mt);
    mt->start = *start;
    mt->end = *end;
    if (!decompose(start, mt->tr[0], mt->q[0], mt->stretch[0]) || !decompose(end, mt->tr[1], mt->q[1], mt->stretch[1]))
        return false;
    double dot = 0.0;
    for (int i = 0; i < 4; i++) dot += mt->q[0][i] * mt->q[1][i];
    if (dot < 0.0) /* q and -q are the same rotation: slerp the shorter way */
        for (int i = 0; i < 4; i++) mt->q[1][i] = -mt->q[1][i];
    mt->moving = memcmp(start->m, end->m, sizeof start->m) != 0;
    return true;
}

/* Spherical linear interpolation of unit quaternions (Shoemake 1985), a normalised lerp
 * where they are nearly parallel. */
static void slerp(const double a[4], const double b[4], double t, double out[4])
{
    double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    double wa, wb;
    if (dot > 0.9995) {
        wa = 1.0 - t;
        wb = t;
    } else {
        double theta = acos(fmin(1.0, fmax(-1.0, dot))), s = sin(theta);
        wa = sin((1.0 - t) * theta) / s;
        wb = sin(t * theta) / s;
    }
    double n = 0.0;
    for (int i = 0; i < 4; i++) {
        out[i] = wa * a[i] + wb * b[i];
        n += out[i] * out[i];
    }
    n = sqrt(n);
    for (int i = 0; i < 4; i++) out[i] /= n;
}

Transform motion_at(const MotionTransform *mt, float time)
{
    if (!mt->moving || time <= 0.0f) return mt->start;
    if (time >= 1.0f) return mt->end;
    double t = (double)time, q[4], r[9], s[9];
    slerp(mt->q[0], mt->q[1], t, q);
    matrix_from_quat(q, r);
    for (int k = 0; k < 9; k++) s[k] = (1.0 - t) * mt->stretch[0][k] + t * mt->stretch[1][k];
    Transform out;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++)
            out.m[i][j] = (float)(r[3 * i] * s[j] + r[3 * i + 1] * s[3 + j] + r[3 * i + 2] * s[6 + j]);
        out.m[i][3] = (float)((1.0 - t) * mt->tr[0][i] + t * mt->tr[1][i]);
        out.m[3][i] = 0.0f;
    }
    out.m[3][3] = 1.0f;
    return out;
}

BBox motion_bounds(const MotionTransform *mt, BBox b)
{
    BBox out = bbox_empty();
    Vec3 prev[8];
    float step = 0.0f;
    for (int k = 0; k <= MOTION_BOUND_STEPS; k++) {
        Transform t = motion_at(mt, (float)k / (float)MOTION_BOUND_STEPS);
        for (int c = 0; c < 8; c++) {
            Vec3 corner = v3(c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y, c & 4 ? b.max.z : b.min.z);
            Vec3 p = transform_point(&t, corner);
            if (k > 0) step = fmaxf(step, v3_length(v3_sub(p, prev[c])));
            prev[c] = p;
            out = bbox_add(out, p);
        }
        if (!mt->moving) break;
    }
    out.min = v3_sub(out.min, v3s(step));
    out.max = v3_add(out.max, v3s(step));
    return out;
}
