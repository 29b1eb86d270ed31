/* The built-in Cornell box: the original Cornell University measured data (millimetres),
 * with the light quad lowered to y = 548.7 so it sits just below the ceiling.
 * scenes/cornell-box.json holds exactly the same numbers; a test renders both. */
#include "caustic/caustic.h"
#include "core/error.h"
#include "scene/scene.h"

/* Double literals converted once with (float), exactly as the JSON loader converts the
 * doubles jansson parses, so both scenes hold bit-identical floats. */
static const double CORNELL_QUADS[][4][3] = {
    /* light */
    {{343.0, 548.7, 227.0}, {343.0, 548.7, 332.0}, {213.0, 548.7, 332.0}, {213.0, 548.7, 227.0}},
    /* floor */
    {{552.8, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 559.2}, {549.6, 0.0, 559.2}},
    /* ceiling */
    {{556.0, 548.8, 0.0}, {556.0, 548.8, 559.2}, {0.0, 548.8, 559.2}, {0.0, 548.8, 0.0}},
    /* back wall */
    {{549.6, 0.0, 559.2}, {0.0, 0.0, 559.2}, {0.0, 548.8, 559.2}, {556.0, 548.8, 559.2}},
    /* right wall (green) */
    {{0.0, 0.0, 559.2}, {0.0, 0.0, 0.0}, {0.0, 548.8, 0.0}, {0.0, 548.8, 559.2}},
    /* left wall (red) */
    {{552.8, 0.0, 0.0}, {549.6, 0.0, 559.2}, {556.0, 548.8, 559.2}, {556.0, 548.8, 0.0}},
    /* short block */
    {{130.0, 165.0, 65.0}, {82.0, 165.0, 225.0}, {240.0, 165.0, 272.0}, {290.0, 165.0, 114.0}},
    {{290.0, 0.0, 114.0}, {290.0, 165.0, 114.0}, {240.0, 165.0, 272.0}, {240.0, 0.0, 272.0}},
    {{130.0, 0.0, 65.0}, {130.0, 165.0, 65.0}, {290.0, 165.0, 114.0}, {290.0, 0.0, 114.0}},
    {{82.0, 0.0, 225.0}, {82.0, 165.0, 225.0}, {130.0, 165.0, 65.0}, {130.0, 0.0, 65.0}},
    {{240.0, 0.0, 272.0}, {240.0, 165.0, 272.0}, {82.0, 165.0, 225.0}, {82.0, 0.0, 225.0}},
    /* tall block */
    {{423.0, 330.0, 247.0}, {265.0, 330.0, 296.0}, {314.0, 330.0, 456.0}, {472.0, 330.0, 406.0}},
    {{423.0, 0.0, 247.0}, {423.0, 330.0, 247.0}, {472.0, 330.0, 406.0}, {472.0, 0.0, 406.0}},
    {{472.0, 0.0, 406.0}, {472.0, 330.0, 406.0}, {314.0, 330.0, 456.0}, {314.0, 0.0, 456.0}},
    {{314.0, 0.0, 456.0}, {314.0, 330.0, 456.0}, {265.0, 330.0, 296.0}, {265.0, 0.0, 296.0}},
    {{265.0, 0.0, 296.0}, {265.0, 330.0, 296.0}, {423.0, 330.0, 247.0}, {423.0, 0.0, 247.0}},
};
enum { CORNELL_NUM_QUADS = sizeof CORNELL_QUADS / sizeof CORNELL_QUADS[0] };

static Color rgbd(double r, double g, double b) { return color_rgb((float)r, (float)g, (float)b); }
static Vec3 v3d(double x, double y, double z) { return v3((float)x, (float)y, (float)z); }

CstStatus cst_scene_create_cornell_box(CstScene **out, CstError *err)
{
    *out = NULL;
    Scene *s = scene_create();
    if (!s) return cst_fail(err, CST_ERR_OOM, "out of memory creating the Cornell box");
    CstStatus st;
    int light, white, red, green;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = rgbd(0.0, 0.0, 0.0), .ior = 1.0f};
    if ((st = scene_add_material(s, &m, &light, err))) goto fail;
    m.albedo = rgbd(0.725, 0.71, 0.68);
    if ((st = scene_add_material(s, &m, &white, err))) goto fail;
    m.albedo = rgbd(0.63, 0.065, 0.05);
    if ((st = scene_add_material(s, &m, &red, err))) goto fail;
    m.albedo = rgbd(0.14, 0.45, 0.091);
    if ((st = scene_add_material(s, &m, &green, err))) goto fail;

    for (int q = 0; q < CORNELL_NUM_QUADS; q++) {
        Vec3 v[4];
        for (int k = 0; k < 4; k++)
            v[k] = v3d(CORNELL_QUADS[q][k][0], CORNELL_QUADS[q][k][1], CORNELL_QUADS[q][k][2]);
        int mat = q == 0 ? light : (q == 4 ? green : (q == 5 ? red : white));
        Emission em = {rgbd(17.0, 12.0, 4.0), 0, 0};
        if ((st = scene_add_quad(s, v, mat, q == 0 ? &em : NULL, err))) goto fail;
    }
    CameraDesc cam = {v3d(278.0, 273.0, -800.0), v3d(278.0, 273.0, 0.0), v3d(0.0, 1.0, 0.0),
                      (float)39.3077, 0.0f, (float)800.0, 0.0f};
    scene_set_camera(s, &cam);
    if ((st = scene_set_output_path(s, "cornell-box.png", err))) goto fail;
    /* The same settings as scenes/cornell-box.json, so the two are interchangeable. */
    s->settings.width = 512;
    s->settings.height = 512;
    s->settings.spp = 64;
    s->settings.seed = 0;
    s->settings.seed_set = 1;
    s->settings.integrator = CST_INTEGRATOR_PATH;
    s->settings.filter = CST_FILTER_BOX;
    if ((st = scene_commit(s, err))) goto fail;
    *out = s;
    return CST_OK;
fail:
    scene_destroy(s);
    return st;
}
