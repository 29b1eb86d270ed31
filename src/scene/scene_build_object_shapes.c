/* cst_scene_add_object_shape: analytic shapes (spheres, cylinders, disks, tori, patches,
 * curves, SDFs) in instanced objects, so that moving instances carry them (motion blur). */
#include "core/error.h"
#include "scene/scene.h"
#include "scene/scene_build.h"
#include "scene/scene_build_check.h"

CstStatus cst_scene_add_object_shape(CstScene *scene, int object, const CstShapeDesc *d, int *out_id, CstError *err)
{
    static const char fn[] = "cst_scene_add_object_shape";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!d) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc is NULL", fn);
    const CstEmission *e = &d->emission;
    if (e->radiance[0] != 0.0f || e->radiance[1] != 0.0f || e->radiance[2] != 0.0f || e->texture || e->two_sided)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: the shape has an emission; instances do not emit "
                        "(expected a zero emission; add emitters with cst_scene_add_shape)", fn);
    const int objects = scene->instances ? scene->instances->num_protos : 0;
    if (object < -1 || object >= objects)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: object %d is not an object of this scene; expected -1 (a new "
                        "object)%s", fn, object, objects ? " or an id from cst_scene_add_object" : "");
    const bool made = object < 0;
    if (made && (st = scene_add_instance_proto(scene, NULL, NULL, 0, NULL, NULL, 0, &object, err)) != CST_OK)
        return st;
    /* cst_scene_add_shape's checks and conversions, its shape put into the object. */
    scene->shape_object = 1 + object;
    st = cst_scene_add_shape(scene, d, err);
    scene->shape_object = 0;
    if (st != CST_OK && made) instances_pop_proto(scene->instances);
    if (st == CST_OK && out_id) *out_id = object;
    return st;
}
