/* The result of a closest-hit query, shared by every acceleration back end. */
#ifndef CST_GEOMETRY_HIT_H
#define CST_GEOMETRY_HIT_H

#include <stdint.h>

typedef struct Hit {
    float t;
    float u, v;    /* triangle barycentrics of v1 and v2; 0 for spheres */
    uint32_t prim; /* scene primitive id: triangles 0..T-1, then spheres */
} Hit;

#endif
