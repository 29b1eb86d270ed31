/* The built-in Cornell box: the original Cornell University measured data (millimetres),
 * with the light quad lowered to y = 548.7 so it sits just below the ceiling.
 * scenes/cornell-box.json holds exactly the same numbers; a test renders both. */
#include "caustic/caustic.h"

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

/* Double triples converted once with (float), as the JSON loader converts jansson's doubles. */
static void f3(float out[3], double x, double y, double z)
{
    out[0] = (float)x;
    out[1] = (float)y;
    out[2] = (float)z;
}

/* Built through the public API alone (cst_scene_*), as any caller would build it. */
CstStatus cst_scene_create_cornell_box(CstScene **out, CstError *err)
{
    *out = NULL;
    CstScene *s = NULL;
    CstStatus st = cst_scene_create(&s, err);
    if (st != CST_OK) return st;
    int light, white, red, green;
    CstMaterialDesc m;
    cst_material_desc_init(&m, CST_MATERIAL_DIFFUSE);
    f3(m.albedo, 0.0, 0.0, 0.0);
    if ((st = cst_scene_add_material(s, &m, &light, err))) goto fail;
    f3(m.albedo, 0.725, 0.71, 0.68);
    if ((st = cst_scene_add_material(s, &m, &white, err))) goto fail;
    f3(m.albedo, 0.63, 0.065, 0.05);
    if ((st = cst_scene_add_material(s, &m, &red, err))) goto fail;
    f3(m.albedo, 0.14, 0.45, 0.091);
    if ((st = cst_scene_add_material(s, &m, &green, err))) goto fail;

    /* Each quad as two triangles (v0,v1,v2), (v0,v2,v3) with uvs (0,0), (1,0), (1,1), (0,1):
     * the JSON loader's quads. */
    static const uint32_t quad_idx[6] = {0, 1, 2, 0, 2, 3};
    static const float quad_uv[8] = {0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 0.0f, 1.0f};
    for (int q = 0; q < CORNELL_NUM_QUADS; q++) {
        float v[4][3];
        for (int k = 0; k < 4; k++) f3(v[k], CORNELL_QUADS[q][k][0], CORNELL_QUADS[q][k][1], CORNELL_QUADS[q][k][2]);
        CstMeshDesc mesh = {0};
        mesh.positions = v;
        mesh.num_vertices = 4;
        mesh.uvs = quad_uv;
        mesh.indices = quad_idx;
        mesh.num_triangles = 2;
        mesh.material = q == 0 ? light : (q == 4 ? green : (q == 5 ? red : white));
        if (q == 0) f3(mesh.emission.radiance, 17.0, 12.0, 4.0);
        if ((st = cst_scene_add_mesh(s, &mesh, NULL, err))) goto fail;
    }
    CstCameraDesc cam = {0};
    cam.type = CST_CAMERA_PERSPECTIVE;
    f3(cam.position, 278.0, 273.0, -800.0);
    f3(cam.look_at, 278.0, 273.0, 0.0);
    f3(cam.up, 0.0, 1.0, 0.0);
    cam.fov = (float)39.3077;
    cam.focus_distance = (float)800.0;
    if ((st = cst_scene_set_camera(s, &cam, err))) goto fail;
    if ((st = cst_scene_set_output_path(s, "cornell-box.png", err))) goto fail;
    /* The same settings as scenes/cornell-box.json, so the two are interchangeable. */
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = 512;
    rs.height = 512;
    rs.spp = 64;
    rs.seed = 0;
    rs.seed_set = 1;
    rs.integrator = CST_INTEGRATOR_PATH;
    rs.filter = CST_FILTER_BOX;
    if ((st = cst_scene_set_render_settings(s, &rs, err))) goto fail;
    if ((st = cst_scene_commit(s, err))) goto fail;
    *out = s;
    return CST_OK;
fail:
    cst_scene_destroy(s);
    return st;
}
