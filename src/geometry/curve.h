/* pbrt-v4's curve shape: one segment of a cubic Bezier curve (flat, cylinder or ribbon),
 * its ray test by recursive subdivision in ray space, its surface, bounds and blossoming. */
#ifndef CST_GEOMETRY_CURVE_H
#define CST_GEOMETRY_CURVE_H

#include <stdbool.h>
#include <stdint.h>

#include "geometry/ray.h"
#include "math/bbox.h"

typedef enum CurveType {
    CURVE_FLAT = 0,  /* a ribbon always facing the ray */
    CURVE_CYLINDER,  /* the flat ribbon, its normal rotated across the width to mimic a tube */
    CURVE_RIBBON     /* a ribbon oriented by normals given at the curve's two ends */
} CurveType;

/* One segment [u0, u1] of a whole curve (pbrt-v4 splits every curve into 2^splitdepth of
 * them, each a primitive of its own): 104 bytes, world space, float. The control points
 * are the segment's own (the whole curve's blossomed to [u0, u1]), so a test starts at
 * the segment; widths and normals are the whole curve's, interpolated in its u. */
typedef struct Curve {
    /* the test's fields first, in the order it reads them (shape.h's layout note) */
    Vec3 cp[4];           /* the segment's cubic Bezier control points, world space */
    float reach;          /* a radius about the chord cp[0]-cp[3] holding every hit
                           * (curve_init): the test's cheap first rejection */
    float u0, u1;         /* the segment's range of the whole curve's parameter u */
    float w0, w1;         /* the whole curve's widths (world units) at u = 0 and u = 1 */
    uint8_t type;         /* CurveType */
    uint8_t depth;        /* the subdivision depth of the test (curve_init) */
    bool flip;            /* pbrt-v4's ReverseOrientation XOR a mirroring transform */
    Vec3 n0, n1;          /* ribbon: unit normals at u = 0 and u = 1 */
    float normal_angle;   /* ribbon: the angle between n0 and n1 (radians) */
    float inv_sin_angle;  /* ribbon: 1 / sin(normal_angle), for the slerp */
} Curve;

/* A flat or cylinder segment's compact record for the accels' hot path (issue 28): what
 * curve_intersect reads before the widths, in one 64-byte line (a Curve inside an
 * AnalyticShape spans six), so 1M segments take 64 MB, not 384. The whole curve's widths,
 * shared by its segments, are a CurveWidths entry of their own that the test reads only
 * once the ray passes the chord's reach. Ribbons (their normals) have no compact record. */
typedef struct CurveSeg {
    Vec3 cp[4];     /* Curve.cp, bit for bit */
    float reach;    /* Curve.reach */
    float u0, u1;   /* Curve.u0, u1 */
    uint32_t info;  /* depth << 28 | type << 26 | the CurveWidths entry's index */
} CurveSeg;
_Static_assert(sizeof(CurveSeg) == 64, "CurveSeg: one cache line");
typedef struct CurveWidths { float w0, w1; } CurveWidths; /* Curve.w0, w1 */
#define CURVE_SEG_INDEX_MAX 0x03ffffffu

/* The compact record of c with its widths at widths[index] (which the caller fills with
 * c->w0, c->w1). False for ribbons and an index above CURVE_SEG_INDEX_MAX: such a
 * segment keeps curve_intersect on its Curve. */
bool curve_seg_init(CurveSeg *s, const Curve *c, uint32_t index);

/* curve_intersect on the compact record: the same arithmetic on the same values, so the
 * same answer (t, u, v) to the bit. widths: the array curve_seg_init's index is into. */
bool curve_seg_intersect(const CurveSeg *s, const CurveWidths *widths, const Ray *r, float *t, float *u, float *v);

/* The segment [u0, u1] of the whole cubic Bezier whole_cp (world space), widths w0, w1 at
 * the whole curve's ends, ribbon normals n (two, world space, any length; NULL unless
 * type is CURVE_RIBBON). False for non-finite input, negative widths, both widths 0, a
 * ribbon without normals or with a zero normal, or 0 <= u0 < u1 <= 1 violated. */
bool curve_init(Curve *c, const Vec3 whole_cp[4], float u0, float u1, float w0, float w1, CurveType type,
                const Vec3 *n, bool flip);

/* World bounds of every hit curve_intersect can report: the control points' box (the
 * convex hull property) widened by half the largest width over [u0, u1] and a relative
 * 2^-18 for the rounding of the float test. */
BBox curve_bounds(const Curve *c);

/* Tighter bounds for the accels: the segment cut into k pieces of equal u (k a power of
 * two, 1 to CURVE_MAX_PIECES, more the longer the segment is than wide), each piece's box
 * as curve_bounds makes it (its own control points, blossomed from cp in double, and
 * half its largest width). Every hit curve_intersect reports lies in the piece holding
 * its u: the point is the segment's curve at that u, moved less than half the width
 * there. Returns k; boxes[0..k) the pieces' boxes. */
enum { CURVE_MAX_PIECES = 8 };
int curve_piece_bounds(const Curve *c, BBox boxes[CURVE_MAX_PIECES]);

/* Nearest hit in (r->t_min, r->t_max): *t (world t, r->d need not be unit), u the whole
 * curve's parameter, v in [0, 1] across the width (pbrt-v4's, so the hair BSDF's offset is
 * h = -1 + 2 v). The test is pbrt-v4's Curve::RecursiveIntersect in float: the segment in
 * a frame whose z axis is the ray, halved curve_init's depth times (pruning halves whose
 * width-expanded box misses the ray), the last pieces as lines. A ray that starts within
 * one local width of the piece's chord is taken to leave that fibre and does not hit
 * that piece again (the role of pbrt-v4's 2-widths spawn offset). */
bool curve_intersect(const Curve *c, const Ray *r, float *t, float *u, float *v);

/* The surface at a hit (u, v) of ray r at t, as pbrt-v4's Curve::Intersect builds it:
 * p = o + t d, dp/du the whole curve's tangent, dp/dv across the width (flat: in the
 * plane facing the ray; cylinder: rotated about dp/du by -(v - 1/2) pi; ribbon: from the
 * interpolated normal), n = normalize(dp/du x dp/dv) (flipped by c->flip), also the
 * shading normal. */
void curve_surface(const Curve *c, const Ray *r, float t, float u, float v, Vec3 *p, Vec3 *n, Vec3 *dpdu,
                   Vec3 *dpdv);

/* dp/du at the whole curve's u and a dp/dv of the width's length perpendicular to it
 * (without a ray: for texture footprints and the hair BSDF's fibre direction). */
void curve_derivatives(const Curve *c, float u, Vec3 *dpdu, Vec3 *dpdv);

/* The width at the whole curve's parameter u. */
static inline float curve_width(const Curve *c, float u) { return (1.0f - u) * c->w0 + u * c->w1; }

/* The point and the derivative of the segment's cubic Bezier at its own parameter w. */
Vec3 curve_eval(const Vec3 cp[4], float w, Vec3 *deriv);

/* Quadratic and cubic B-splines and quadratic Beziers as cubic Bezier segments (pbrt-v4's
 * curve "basis" and "degree"): segment seg of the control polygon cp (degree 2 or 3). */
void curve_bezier_segment(const Vec3 *cp, int degree, bool bspline, int seg, Vec3 out[4]);

#endif
