/* The photon map: photons stored in a balanced kd-tree (Jensen, "Realistic Image Synthesis
 * Using Photon Mapping", 2001, ch. 6; Bentley 1975) with radius and k-nearest queries. */
#ifndef CST_INTEGRATORS_PHOTON_MAP_H
#define CST_INTEGRATORS_PHOTON_MAP_H

#include <stddef.h>
#include <stdint.h>

#include "caustic/caustic.h"
#include "math/color.h"
#include "math/vec3.h"

/* 60 bytes: three float triples, one Color (four lanes), a time and an instance, no padding, 4-byte aligned. Full floats rather than
 * Jensen's packed 20-byte record: the directions feed bsdf_eval() directly, and the tree
 * keeps its own copy of the positions (PhotonNode), so the record's size only costs
 * memory, not traversal bandwidth.
 *   pos   where the photon landed, world space.
 *   wi    unit; from pos towards where the photon came from (the reverse of its flight
 *         direction), the same convention as wi in bsdf_eval(wo, wi).
 *   power flux carried (already divided by the number of emitted paths), linear RGB.
 *   n     unit geometric normal at pos, flipped to the side the photon arrived from
 *         (dot(n, wi) >= 0); the zero vector when unknown. A gather point whose normal
 *         faces its viewer rejects photons with dot(n, n_gather) <= 0: those landed on
 *         the other side of a thin wall.
 *   time  the instant of the photon's path (motion blur: photon.c's time window in scenes
 *         with moving instances); 0 where nothing moves.
 *   inst  -1: pos, wi and n are in world space. Else the moving instance the photon landed
 *         on, and pos, wi and n are in that instance's rest frame (instances_rest_frame):
 *         only a query on the same instance, in its rest frame, finds it (photon.c).
 *         A volume photon (n = 0, photon.c's volume map; never on an instance) holds here
 *         the index of the medium it scattered in: an estimate gathers only its own
 *         medium's (the field reused so that a Photon stays within 60 bytes). */
typedef struct Photon {
    Vec3 pos;
    Vec3 wi;
    Color power;
    Vec3 n;
    float time;
    int32_t inst;
} Photon;

/* One tree node: the photon's position again, so the traversal streams 16-byte nodes
 * (four per cache line) and touches a 60-byte Photon only when it is within range.
 * meta = input index << 2 | split axis (0, 1, 2; PHOTON_MAP_NO_SPLIT for leaf photons). */
typedef struct PhotonNode {
    float p[3];
    uint32_t meta;
} PhotonNode;

enum {
    PHOTON_MAP_MAX_K = 1024,  /* largest k photon_map_knn() accepts: its heap lives on the stack */
    PHOTON_MAP_LEAF_SIZE = 16, /* ranges of at most this many photons are leaves (see photon_map.c) */
    PHOTON_MAP_NO_SPLIT = 3    /* PhotonNode.meta & 3 of a photon that is not a split */
};

/* The input index has 30 bits of PhotonNode.meta. */
#define PHOTON_MAP_MAX_COUNT ((size_t)1 << 30)

/* A balanced kd-tree stored implicitly in array order, with no child pointers. The range
 * [lo, hi) of nodes (the whole map is [0, count)) is a leaf when it holds at most
 * PHOTON_MAP_LEAF_SIZE photons, in no particular order. Otherwise its median
 * m = lo + (hi - lo) / 2 is a split on axis nodes[m].meta & 3: every photon of [lo, m) has
 * coordinate <= nodes[m]'s on that axis, every one of (m, hi) >= (equal values may fall on
 * either side), and the axis is the largest extent of the range's bounds. So each subtree
 * is a contiguous run of the array, and the depth is about log2(count / LEAF_SIZE).
 * nodes[i] and photons[i] are the same photon. A zeroed PhotonMap is a valid empty map.
 * Read-only after photon_map_build(): queries may run from any number of threads at once. */
typedef struct PhotonMap {
    PhotonNode *nodes;
    Photon *photons;
    size_t count;
} PhotonMap;

/* The squared distance every query uses, and the one a brute-force check must use to
 * agree to the bit: ((dx*dx + dy*dy) + dz*dz) in float, no fused multiply-add (ISO C
 * mode, -ffp-contract=off, is what the build uses). */
static inline float photon_dist2(Vec3 a, Vec3 b)
{
    float dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
    return dx * dx + dy * dy + dz * dz;
}

/* Called once per photon found, with its squared distance to the query point. */
typedef void (*PhotonVisitFn)(void *ctx, const Photon *ph, float dist2);

/* Copies count photons (the caller keeps its array) and builds the tree in O(n log n).
 * Positions must be finite (no NaN or infinity: the split comparisons assume a total
 * order); wi, power and n are copied untouched. count = 0 gives an empty map. Overwrites
 * *map without freeing it. Fails with CST_ERR_INVALID_ARG (photons NULL, count > 0),
 * CST_ERR_UNSUPPORTED (count > PHOTON_MAP_MAX_COUNT) or CST_ERR_OOM; *map is then zeroed.
 * The result depends only on the input array, never on timing or thread count. */
CstStatus photon_map_build(PhotonMap *map, const Photon *photons, size_t count, CstError *err);
/* Accepts NULL and a zeroed map; leaves the map zeroed. */
void photon_map_free(PhotonMap *map);
size_t photon_map_count(const PhotonMap *map);
/* The position in the array given to photon_map_build() of a photon a query returned. */
size_t photon_map_index(const PhotonMap *map, const Photon *ph);

/* Visits every photon with photon_dist2(x, pos) <= radius * radius (the boundary is
 * inclusive), in no particular order, and returns how many it visited. visit may be NULL
 * to only count. A negative or NaN radius visits nothing; INFINITY visits everything.
 * x must be finite. No allocation; iterative. */
size_t photon_map_radius(const PhotonMap *map, Vec3 x, float radius, PhotonVisitFn visit, void *ctx);

/* The k photons nearest to x among those with photon_dist2(x, pos) <= max_radius^2
 * (inclusive, as above; INFINITY for no limit), written to out[0..] and their squared
 * distances to dist2_out[0..] (may be NULL) in increasing order of distance; photons at
 * equal distance are ordered by their index in the build's input array, lower first, so
 * the result is the first k of all photons sorted by (dist2, input index). Returns how
 * many were written: min(k, photons within max_radius); 0 when k <= 0 or max_radius is
 * negative or NaN; -1, writing nothing, when k > PHOTON_MAP_MAX_K. No allocation (the
 * max-heap is on the stack, 16 KB). */
int photon_map_knn(const PhotonMap *map, Vec3 x, int k, float max_radius, const Photon **out,
                   float *dist2_out);

#endif
