/* The open box several render tests build their scenes in: five diffuse walls of
 * [-1, 1]^3 (open towards the camera at +z) and a small quad light under the ceiling. */
#ifndef CST_TESTS_BOX_SCENE_H
#define CST_TESTS_BOX_SCENE_H

#include "scene/scene.h"

/* Adds the box to s: *wall is the walls' diffuse material (albedo 0.7 0.6 0.5), *lightm the
 * light's black one; the light quad emits 8 8 6. */
static inline void open_box_add(Scene *s, int *wall, int *lightm)
{
    CstError err;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.7f, 0.6f, 0.5f, 0.6f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, wall, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, lightm, &err), CST_OK);
    const Vec3 walls[5][4] = {
        {{-1, -1, -1}, {1, -1, -1}, {1, -1, 1}, {-1, -1, 1}}, /* floor */
        {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}},     /* ceiling */
        {{-1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {1, -1, -1}}, /* back */
        {{-1, -1, -1}, {-1, -1, 1}, {-1, 1, 1}, {-1, 1, -1}}, /* left */
        {{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}},     /* right */
    };
    for (int i = 0; i < 5; i++) assert_int_equal(scene_add_quad(s, walls[i], *wall, NULL, &err), CST_OK);
    const Vec3 light[4] = {{-0.3f, 0.99f, -0.3f}, {0.3f, 0.99f, -0.3f}, {0.3f, 0.99f, 0.3f}, {-0.3f, 0.99f, 0.3f}};
    Emission em = {color_rgb(8.0f, 8.0f, 6.0f), 0, 0};
    assert_int_equal(scene_add_quad(s, light, *lightm, &em, &err), CST_OK);
}

#endif
