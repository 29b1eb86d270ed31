/* embed: builds a small scene in code through libcaustic's public API (a diffuse floor,
 * a glass sphere, a glowing sphere, a point light, a camera), renders it and writes an
 * EXR. Build against an installed caustic:
 *   cc embed.c $(pkg-config --cflags --libs caustic) -o embed && ./embed out.exr
 * Exits 1 on any error. */
#include <stdio.h>
#include <stdlib.h>

#include <caustic/caustic.h>

/* The application's own vertex layout: the mesh is read through strides, not copied. */
typedef struct Vertex {
    float pos[3];
    float uv[2];
} Vertex;

#define TRY(call)                                                               \
    do {                                                                        \
        if ((call) != CST_OK) {                                                 \
            fprintf(stderr, "embed: %s: %s\n", #call, err.msg);                 \
            goto fail;                                                          \
        }                                                                       \
    } while (0)

int main(int argc, char **argv)
{
    const char *out = argc > 1 ? argv[1] : "embed.exr";
    static const Vertex floor[4] = {{{-4, 0, -4}, {0, 0}}, {{4, 0, -4}, {4, 0}},
                                    {{4, 0, 4}, {4, 4}},   {{-4, 0, 4}, {0, 4}}};
    static const uint32_t tris[2][3] = {{0, 2, 1}, {0, 3, 2}};
    CstError err = {0};
    CstScene *scene = NULL;
    CstFilm *film = NULL;
    int status = 1;

    TRY(cst_scene_create(&scene, &err));
    CstTextureDesc light = {.type = CST_TEXTURE_CONSTANT, .value = {0.8f, 0.8f, 0.8f}};
    CstTextureDesc dark = {.type = CST_TEXTURE_CONSTANT, .value = {0.2f, 0.25f, 0.3f}};
    CstTextureDesc check = {.type = CST_TEXTURE_CHECKERBOARD, .scale = 1.0f};
    TRY(cst_scene_add_texture(scene, &light, &check.even, &err));
    TRY(cst_scene_add_texture(scene, &dark, &check.odd, &err));
    int checker = 0, diffuse = 0, glass = 0, lamp = 0;
    TRY(cst_scene_add_texture(scene, &check, &checker, &err));

    CstMaterialDesc m;
    cst_material_desc_init(&m, CST_MATERIAL_DIFFUSE);
    m.albedo_texture = checker;
    TRY(cst_scene_add_material(scene, &m, &diffuse, &err));
    cst_material_desc_init(&m, CST_MATERIAL_GLASS);
    TRY(cst_scene_add_material(scene, &m, &glass, &err));
    cst_material_desc_init(&m, CST_MATERIAL_DIFFUSE);
    TRY(cst_scene_add_material(scene, &m, &lamp, &err));

    CstMeshDesc mesh = {.positions = floor[0].pos, .position_stride = sizeof(Vertex),
                        .uvs = floor[0].uv, .uv_stride = sizeof(Vertex), .num_vertices = 4,
                        .indices = tris, .num_triangles = 2, .material = diffuse};
    TRY(cst_scene_add_mesh(scene, &mesh, NULL, &err));
    TRY(cst_scene_add_sphere(scene, (const float[3]){0, 1, 0}, 1.0f, glass, NULL, &err));
    CstEmission glow = {.radiance = {8, 6, 4}};
    TRY(cst_scene_add_sphere(scene, (const float[3]){2, 2.5f, -1.5f}, 0.4f, lamp, &glow, &err));
    CstLightDesc point = {.type = CST_LIGHT_POINT, .position = {-2, 4, 2}, .intensity = {10, 10, 10}};
    TRY(cst_scene_add_light(scene, &point, &err));
    TRY(cst_scene_set_environment_constant(scene, (const float[3]){0.05f, 0.05f, 0.08f}, &err));
    CstCameraDesc cam = {.type = CST_CAMERA_PERSPECTIVE, .position = {0, 2, 6},
                         .look_at = {0, 0.8f, 0}, .fov = 40};
    TRY(cst_scene_set_camera(scene, &cam, &err));
    TRY(cst_scene_commit(scene, &err));

    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = 160, rs.height = 120, rs.spp = 8;
    CstRenderStats stats;
    TRY(cst_render(scene, &rs, &film, &stats, &err));
    TRY(cst_film_write(film, out, &err));
    printf("embed: %dx%d, %d spp in %.2f s -> %s\n", stats.width, stats.height, stats.spp,
           stats.seconds, out);
    status = 0;
fail:
    cst_film_destroy(film);
    cst_scene_destroy(scene);
    return status;
}
