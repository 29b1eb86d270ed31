/* 4x4 affine transforms (conventions in transform.h): constructors, composition,
 * determinant, inverse and normal matrix, all computed in double. */
#include "math/transform.h"

#include <float.h>
#include <string.h>

Transform transform_identity(void)
{
    Transform t;
    memset(&t, 0, sizeof t);
    for (int i = 0; i < 4; i++) t.m[i][i] = 1.0f;
    return t;
}

Transform transform_translate(Vec3 d)
{
    Transform t = transform_identity();
    t.m[0][3] = d.x;
    t.m[1][3] = d.y;
    t.m[2][3] = d.z;
    return t;
}

Transform transform_scale(Vec3 s)
{
    Transform t = transform_identity();
    t.m[0][0] = s.x;
    t.m[1][1] = s.y;
    t.m[2][2] = s.z;
    return t;
}

/* Rodrigues' formula: R = cos(a) I + sin(a) [k]x + (1 - cos(a)) k k^T, k the unit axis. */
static Transform rotate_cs(Vec3 axis, double c, double s)
{
    double kx = (double)axis.x, ky = (double)axis.y, kz = (double)axis.z;
    double len = sqrt(kx * kx + ky * ky + kz * kz);
    Transform t = transform_identity();
    if (!(len > 0.0) || !isfinite(len)) return t;
    kx /= len;
    ky /= len;
    kz /= len;
    double ic = 1.0 - c;
    double r[3][3] = {
        {c + kx * kx * ic, kx * ky * ic - kz * s, kx * kz * ic + ky * s},
        {ky * kx * ic + kz * s, c + ky * ky * ic, ky * kz * ic - kx * s},
        {kz * kx * ic - ky * s, kz * ky * ic + kx * s, c + kz * kz * ic},
    };
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) t.m[i][j] = (float)r[i][j];
    return t;
}

Transform transform_rotate(Vec3 axis, float angle_rad)
{
    return rotate_cs(axis, cos((double)angle_rad), sin((double)angle_rad));
}

Transform transform_rotate_degrees(Vec3 axis, double degrees)
{
    double a = fmod(degrees, 360.0);
    if (a < 0.0) a += 360.0;
    /* Quarter turns exactly: cos(pi/2) is 6e-17, not 0, in double. */
    if (a == 0.0) return rotate_cs(axis, 1.0, 0.0);
    if (a == 90.0) return rotate_cs(axis, 0.0, 1.0);
    if (a == 180.0) return rotate_cs(axis, -1.0, 0.0);
    if (a == 270.0) return rotate_cs(axis, 0.0, -1.0);
    double rad = a * (3.14159265358979323846 / 180.0);
    return rotate_cs(axis, cos(rad), sin(rad));
}

Transform transform_from_rows(const float rows[16])
{
    Transform t;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) t.m[i][j] = rows[4 * i + j];
    return t;
}

Transform transform_compose(Transform a, Transform b)
{
    Transform r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double sum = 0.0;
            for (int k = 0; k < 4; k++) sum += (double)a.m[i][k] * (double)b.m[k][j];
            r.m[i][j] = (float)sum;
        }
    return r;
}

bool transform_is_identity(const Transform *t)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (t->m[i][j] != (i == j ? 1.0f : 0.0f)) return false;
    return true;
}

bool transform_is_affine(const Transform *t)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!isfinite(t->m[i][j])) return false;
    return t->m[3][0] == 0.0f && t->m[3][1] == 0.0f && t->m[3][2] == 0.0f && t->m[3][3] == 1.0f;
}

/* Cofactor c[i][j] of the linear part: (-1)^(i+j) times the minor without row i, column j.
 * The cyclic index form gives the sign for free. */
static double cofactor(const Transform *t, int i, int j)
{
    int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
    const float(*m)[4] = t->m;
    return (double)m[i1][j1] * (double)m[i2][j2] - (double)m[i1][j2] * (double)m[i2][j1];
}

double transform_det(const Transform *t)
{
    double d = 0.0;
    for (int j = 0; j < 3; j++) d += (double)t->m[0][j] * cofactor(t, 0, j);
    return d;
}

/* inverse(A) = adj(A) / det(A) = cof(A)^T / det(A); inverse transpose = cof(A) / det(A). */
static bool inverse_linear(const Transform *t, double inv[3][3])
{
    double det = transform_det(t);
    if (!(det != 0.0) || !isfinite(det)) return false;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            inv[i][j] = cofactor(t, j, i) / det;
            if (!isfinite(inv[i][j]) || fabs(inv[i][j]) > (double)FLT_MAX) return false;
        }
    return true;
}

bool transform_invert(const Transform *t, Transform *out)
{
    double inv[3][3];
    if (!inverse_linear(t, inv)) return false;
    Transform r = transform_identity();
    for (int i = 0; i < 3; i++) {
        double tr = 0.0;
        for (int j = 0; j < 3; j++) {
            r.m[i][j] = (float)inv[i][j];
            tr -= inv[i][j] * (double)t->m[j][3]; /* -A^-1 b */
        }
        if (!(fabs(tr) <= (double)FLT_MAX)) return false;
        r.m[i][3] = (float)tr;
    }
    *out = r;
    return true;
}

bool transform_normal_matrix(const Transform *t, Transform *out)
{
    double inv[3][3];
    if (!inverse_linear(t, inv)) return false;
    Transform r = transform_identity();
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) r.m[i][j] = (float)inv[j][i];
    *out = r;
    return true;
}
