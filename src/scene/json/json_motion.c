/* Moving shapes of the JSON format: meshes and analytic shapes under "motion", each an
 * object placed by one moving instance (pbrt-v4's AnimatedPrimitive). */
#include "scene/json/json_motion.h"

#include "scene/json/json_geometry.h"

/* A transform as the 3 x 4 rows of cst_scene_add_instance. */
static void transform_rows(const Transform *t, float rows[12])
{
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 4; k++) rows[4 * r + k] = t->m[r][k];
}

/* "medium" or "emission" on a moving shape: refused (instances carry neither). */
static CstStatus check_moving(Loader *ld, const json_t *shape, const char *what)
{
    const char *bad = json_object_get(shape, "medium") ? "medium" : json_object_get(shape, "emission") ? "emission" : NULL;
    if (bad)
        return json_fail_here(ld, "a moving %s (\"motion\") cannot have \"%s\": it is placed as a moving instance, "
                                  "and instances carry no emission or medium", what, bad);
    return CST_OK;
}

/* The instance of object obj moving as "motion" says. */
static CstStatus add_motion_instance(Loader *ld, const json_t *motion, int obj)
{
    Transform t0, t1;
    LOADER_TRY(json_parse_motion(ld, motion, &t0, &t1));
    float r0[12], r1[12];
    transform_rows(&t0, r0);
    transform_rows(&t1, r1);
    CstStatus st = cst_scene_add_instance_motion(ld->scene, obj, r0, r1, ld->err);
    return st == CST_OK ? CST_OK : json_fail_builder(ld, st);
}

CstStatus json_add_moving_mesh(Loader *ld, const json_t *motion, const CstMeshDesc *mesh, const json_t *shape)
{
    LOADER_TRY(check_moving(ld, shape, "mesh"));
    int obj = -1;
    CstStatus st = cst_scene_add_object(ld->scene, mesh, &obj, NULL, ld->err);
    if (st != CST_OK) return json_fail_builder(ld, st);
    return add_motion_instance(ld, motion, obj);
}

CstStatus json_add_moving_shape(Loader *ld, const json_t *motion, const CstShapeDesc *sd, const json_t *shape)
{
    json_path_push_key(ld, "motion");
    LOADER_TRY(check_moving(ld, shape, "shape"));
    int obj = -1;
    CstStatus st = cst_scene_add_object_shape(ld->scene, -1, sd, &obj, ld->err);
    if (st != CST_OK) return json_fail_builder(ld, st);
    LOADER_TRY(add_motion_instance(ld, motion, obj));
    json_path_pop(ld);
    return CST_OK;
}

Transform json_sphere_uv_frame(void)
{
    const float rows[16] = {0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 0, 0, 1};
    return transform_from_rows(rows);
}
