/* Emitting analytic shapes render the same by every path-tracing strategy: a floor lit by
 * a disk (innerradius, phimax), a cylinder (phimax) and a partial sphere (zmin, zmax,
 * phimax, two-sided), each alone, rendered with MIS (path), NEE only (path-nee) and BSDF
 * sampling only (path-bsdf), which agree block by block within Z_LIMIT standard errors:
 * the area sampler, its pdf_w and the MIS density on hits are consistent. The three
 * together under the light BVH and under power selection agree the same way. Against
 * pbrt-v4: a floor lit by each, direct light, mean per channel within 1 %. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "math/transform.h"
#include "caustic/caustic.h"
#include "render/blocks.h"
#include "render/render_util.h"
#include "scene/scene.h"

enum { SH_DISK = 1, SH_CYLINDER = 2, SH_SPHERE = 4 };

static void add_shape(Scene *s, CstShapeType type, Transform xf, int material, float L, int two_sided,
                      float r, float z0, float z1, float ri, float phi_deg)
{
    CstError err;
    CstShapeDesc d;
    memset(&d, 0, sizeof d);
    d.type = type;
    d.radius = r;
    d.z_min = z0;
    d.z_max = z1;
    d.inner_radius = ri;
    d.phi_max_degrees = phi_deg;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) d.world_from_object[4 * i + j] = xf.m[i][j];
    d.material = material;
    d.emission.radiance[0] = 1.0f * L;
    d.emission.radiance[1] = 0.8f * L;
    d.emission.radiance[2] = 0.6f * L;
    d.emission.two_sided = two_sided;
    if (cst_scene_add_shape(s, &d, &err) != CST_OK) fail_msg("%s", err.msg);
}

/* A 6 x 6 floor at y = 0 and the emitting shapes in `which`, world y up. */
static Scene *shape_scene(int which, const char *light_sampler)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int white;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.6f, 0.6f, 0.6f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    Vec3 floor[4] = {{-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}};
    assert_int_equal(scene_add_quad(s, floor, white, NULL, &err), CST_OK);
    const float deg = CST_PI / 180.0f;
    if (which & SH_DISK) /* +z turned to -y (facing the floor), scaled by 1.2, 1.4 up */
        add_shape(s, CST_SHAPE_DISK,
                  transform_compose(transform_translate(v3(-0.8f, 1.4f, 0.3f)),
                                    transform_compose(transform_rotate(v3(1, 0, 0), 90.0f * deg),
                                                      transform_scale(v3s(1.2f)))),
                  white, 3.0f, 0, 0.8f, 0.0f, 0.0f, 0.3f, 270.0f);
    if (which & SH_CYLINDER) /* axis along +y, standing on the floor, open over 90 degrees */
        add_shape(s, CST_SHAPE_CYLINDER,
                  transform_compose(transform_translate(v3(0.9f, 0.0f, 0.2f)),
                                    transform_rotate(v3(1, 0, 0), -90.0f * deg)),
                  white, 2.0f, 0, 0.35f, 0.05f, 1.2f, 0.0f, 270.0f);
    if (which & SH_SPHERE) /* a band with a cut, two-sided, tilted */
        add_shape(s, CST_SHAPE_SPHERE,
                  transform_compose(transform_translate(v3(0.0f, 1.0f, 1.2f)),
                                    transform_rotate(v3_normalize(v3(1, 1, 0)), 50.0f * deg)),
                  white, 2.0f, 1, 0.6f, -0.25f, 0.45f, 0.0f, 300.0f);
    CameraDesc cam = {{0, 2.8f, -4.5f}, {0, 0.6f, 0.3f}, {0, 1, 0}, 50.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    if (light_sampler) assert_int_equal(cst_scene_set_light_sampler(s, light_sampler, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    assert_int_equal(s->num_shapes, (which & 1) + ((which >> 1) & 1) + ((which >> 2) & 1));
    assert_int_equal(s->emitter_sampler.count, s->num_shapes);
    return s;
}

static void run_strategies(int which, const char *name)
{
    Scene *s = shape_scene(which, NULL);
    RegionStat mis[R], nee[R], bsdf[R];
    render_blocks(s, CST_INTEGRATOR_PATH, 256, 501u, mis);
    render_blocks(s, CST_INTEGRATOR_PATH_NEE, 256, 502u, nee);
    render_blocks(s, CST_INTEGRATOR_PATH_BSDF, 1024, 503u, bsdf);
    char what[96];
    snprintf(what, sizeof what, "%s: path vs path-nee", name);
    compare_blocks(what, mis, nee);
    snprintf(what, sizeof what, "%s: path vs path-bsdf", name);
    compare_blocks(what, mis, bsdf);
    snprintf(what, sizeof what, "%s: path-nee vs path-bsdf", name);
    compare_blocks(what, nee, bsdf);
    scene_destroy(s);
}

static void test_disk(void **state) { (void)state; run_strategies(SH_DISK, "disk"); }
static void test_cylinder(void **state) { (void)state; run_strategies(SH_CYLINDER, "cylinder"); }
static void test_partial_sphere(void **state) { (void)state; run_strategies(SH_SPHERE, "partial sphere"); }

/* The light BVH's bounds of the shapes (a disk's one normal, the others' every
 * direction) change the noise, not the image. */
static void test_bvh_vs_power(void **state)
{
    (void)state;
    Scene *a = shape_scene(SH_DISK | SH_CYLINDER | SH_SPHERE, "bvh");
    Scene *b = shape_scene(SH_DISK | SH_CYLINDER | SH_SPHERE, "power");
    assert_non_null(a->emitter_sampler.bvh);
    RegionStat ra[R], rb[R];
    render_blocks(a, CST_INTEGRATOR_PATH, 256, 601u, ra);
    render_blocks(b, CST_INTEGRATOR_PATH, 256, 602u, rb);
    compare_blocks("three shapes: light BVH vs power", ra, rb);
    scene_destroy(a);
    scene_destroy(b);
}

/* ------------------------------------------------------------------ against pbrt-v4 */

#define PBRT_HEAD                                                                                  \
    "Film \"rgb\" \"integer xresolution\" [16] \"integer yresolution\" [16] \"string filename\" "  \
    "\"out.exr\"\nSampler \"independent\"\nIntegrator \"path\" \"integer maxdepth\" [1]\n"         \
    "LookAt 0 4 4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [50]\nWorldBegin\n"          \
    "Material \"diffuse\" \"rgb reflectance\" [0.7 0.35 0.15]\n"                                   \
    "Shape \"bilinearmesh\" \"point3 P\" [-3 0 -3  3 0 -3  -3 0 3  3 0 3]\nAttributeBegin\n"

/* The references: pbrt-v4 (/work/shared/tools/pbrt-v4, source commit 5f7a6068) rendering
 * PBRT_HEAD + the case + "AttributeEnd", `pbrt --nthreads 2 --seed 1 --spp N X.pbrt
 * --outfile X.exr`, mean over the 16 x 16 pixels of the linear sRGB EXR. The full disk and
 * the cylinder with pbrt-v4's "path" (N = 4096, 8192). The partial disk and the partial
 * sphere with pbrt-v4's "randomwalk" instead (N = 32768; the same scene otherwise): its
 * Disk::Sample draws points over the whole disk of `radius` (innerradius and phimax
 * ignored) at density 1 / Area(), and Sphere::Sample over the whole sphere, so its "path"
 * is biased for partial emitters (the partial disk 5.6 % dark, the partial sphere 11 %
 * bright in red), while randomwalk only meets emitters by its own directions. */
static const struct {
    const char *name, *shape;
    double ref[3];
} PBRT_CASES[] = {
    {"disk", "AreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nTranslate 0.2 1.5 0\nRotate 90 1 0 0\n"
             "Shape \"disk\" \"float radius\" 1\n",
     {0.172454, 0.086194, 0.036901}},
    {"cylinder", "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"float power\" 20\nTranslate 0.5 0 0\n"
                 "Rotate -90 1 0 0\nShape \"cylinder\" \"float radius\" 0.4 \"float zmin\" 0 \"float zmax\" 1 "
                 "\"float phimax\" 270\n",
     {0.082390, 0.064483, 0.054307}},
    {"partial disk", "AreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nTranslate 0.2 1.5 0\nRotate 90 1 0 0\n"
                     "Shape \"disk\" \"float radius\" 1 \"float innerradius\" 0.4 \"float phimax\" 270\n",
     {0.116771, 0.058301, 0.025008}},
    {"partial sphere", "AreaLightSource \"diffuse\" \"rgb L\" [2 2 2] \"bool twosided\" true\nTranslate 0 1 0\n"
                       "Rotate 40 1 1 0\nShape \"sphere\" \"float radius\" 0.7 \"float zmin\" -0.3 "
                       "\"float zmax\" 0.5 \"float phimax\" 300\n",
     {0.176231, 0.149999, 0.135088}},
};

/* Each channel's mean within 1 % of the reference's brightest channel plus 4 standard
 * errors of caustic's mean (spectral mode, as pbrt-v4). Measured at 2048 spp: within
 * 0.5 % on every channel of every case. */
static void test_against_pbrt(void **state)
{
    (void)state;
    for (size_t k = 0; k < sizeof PBRT_CASES / sizeof PBRT_CASES[0]; k++) {
        char text[2048];
        snprintf(text, sizeof text, "%s%sAttributeEnd\n", PBRT_HEAD, PBRT_CASES[k].shape);
        CstScene *s = NULL;
        CstError err;
        if (cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/shape_emitters.pbrt", NULL, &s, &err))
            fail_msg("%s: %s", PBRT_CASES[k].name, err.msg);
        assert_int_equal(((const Scene *)s)->num_shapes, 2); /* the floor patch and the emitter */
        CstRenderSettings rs;
        cst_render_settings_init(&rs);
        rs.spp = 2048;
        rs.seed = 11 + k;
        rs.seed_set = 1;
        rs.threads = 2;
        rs.color_mode = CST_COLOR_SPECTRAL;
        CstFilm *film = NULL;
        rs.sampler = CST_SAMPLER_INDEPENDENT; /* region_stat's per-pixel variances assume it */
        if (cst_render(s, &rs, &film, NULL, &err)) fail_msg("%s: %s", PBRT_CASES[k].name, err.msg);
        RegionStat r = region_stat(film, 0, 0, cst_film_width(film), cst_film_height(film));
        const double *ref = PBRT_CASES[k].ref;
        double top = fmax(ref[0], fmax(ref[1], ref[2]));
        print_message("  %-14s caustic (%.6f %.6f %.6f) +- (%.6f %.6f %.6f); pbrt-v4 (%.6f %.6f %.6f)\n",
                      PBRT_CASES[k].name, r.mean[0], r.mean[1], r.mean[2], r.se[0], r.se[1], r.se[2], ref[0],
                      ref[1], ref[2]);
        for (int c = 0; c < 3; c++)
            if (fabs(r.mean[c] - ref[c]) > 0.01 * top + 4.0 * r.se[c])
                fail_msg("%s: channel %d mean %.6f, pbrt-v4 %.6f (limit %.6f)", PBRT_CASES[k].name, c, r.mean[c],
                         ref[c], 0.01 * top + 4.0 * r.se[c]);
        cst_film_destroy(film);
        cst_scene_destroy(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_disk),
        cmocka_unit_test(test_cylinder),
        cmocka_unit_test(test_partial_sphere),
        cmocka_unit_test(test_bvh_vs_power),
        cmocka_unit_test(test_against_pbrt),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
