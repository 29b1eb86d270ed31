/* The participating-media scenes several render tests share: homogeneous and random-grid
 * media, the emitting furnace enclosure around a ball of medium (or filled with it), the fog
 * box (box_scene.h's open box with a ball of fog and a diffuse sphere), and the furnace
 * checks of constant radiance (the path tracer's from its films, the others' from
 * independent renders). Include after cmocka.h. */
#ifndef CST_TESTS_MEDIA_SCENES_H
#define CST_TESTS_MEDIA_SCENES_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/rng.h"
#include "render/box_scene.h"
#include "render/regions.h"
#include "render/render_util.h"
#include "scene/scene.h"

/* A homogeneous medium (coefficients per unit length, emitted radiance le, HG g); its id. */
static inline int media_add_homogeneous(Scene *s, Color sigma_a, Color sigma_s, Color le, float g)
{
    CstError err;
    Medium m = {.type = MEDIUM_HOMOGENEOUS, .g = g};
    m.u.homog.sigma_a = sigma_a;
    m.u.homog.sigma_s = sigma_s;
    m.u.homog.le = le;
    int id;
    assert_int_equal(scene_add_medium(s, &m, &id, &err), CST_OK);
    return id;
}

/* A grid medium over the box [lo, hi] with n^3 density samples (m.u.het.density left to
 * the caller), with sigma_a, sigma_s and emitted radiance le at density 1. */
static inline Medium media_grid_desc(Vec3 lo, Vec3 hi, int n, Color sigma_a, Color sigma_s, Color le, float g)
{
    Medium m = {.type = MEDIUM_GRID, .g = g};
    HeteroMedium *hm = &m.u.het;
    hm->sigma_a = sigma_a;
    hm->sigma_s = sigma_s;
    hm->le = le;
    hm->le_scale_1 = 1.0f;
    hm->medium_from_world = transform_identity();
    hm->p0 = lo;
    hm->p1 = hi;
    hm->n[0] = hm->n[1] = hm->n[2] = n;
    return m;
}

/* A grid medium of random densities, uniform in [0, dmax) on 8^3 samples over the box
 * [lo, hi] (PCG stream 77, the same field in every test), with sigma_a, sigma_s and emitted
 * radiance le at density 1; its id. The scene copies the densities. */
static inline int media_add_random_grid(Scene *s, Vec3 lo, Vec3 hi, float dmax, Color sigma_a, Color sigma_s,
                                        Color le, float g)
{
    CstError err;
    const int n = 8;
    Medium m = media_grid_desc(lo, hi, n, sigma_a, sigma_s, le, g);
    float *density = malloc((size_t)(n * n * n) * sizeof(float));
    assert_non_null(density);
    Pcg32 r;
    pcg32_seed_sample(&r, 77, 0, 0);
    for (int i = 0; i < n * n * n; i++) density[i] = dmax * pcg32_float(&r);
    m.u.het.density = density;
    int med;
    assert_int_equal(scene_add_medium(s, &m, &med, &err), CST_OK);
    free(density);
    return med;
}

/* The furnace around medium med of s: a black two-sided emitting sphere (radius `radius`
 * at the origin, radiance L) and in it a boundary ball of med (radius `ball`), or, with
 * ball == 0, med filling the enclosure (its sphere the non-boundary interface) with the
 * camera in it. The camera at (0, 0.5, cam_z) looks at the centre (50 degrees). Radiance
 * is L everywhere when the medium conserves (scattering only) or emits L where it absorbs.
 * Commits s and returns it. */
static inline Scene *media_furnace(Scene *s, int med, float radius, float ball, float cam_z, Color L)
{
    CstError err;
    int black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.0f, 0.0f, 0.0f, 0.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    Emission em = {L, 1, 0};
    if (ball == 0.0f) {
        assert_int_equal(scene_set_medium_interface(s, med, -1, 0, &err), CST_OK);
        assert_int_equal(scene_set_camera_medium(s, med, &err), CST_OK);
    }
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), radius, black, &em, &err), CST_OK);
    if (ball != 0.0f) {
        assert_int_equal(scene_set_medium_interface(s, med, -1, 1, &err), CST_OK);
        assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), ball, black, NULL, &err), CST_OK);
    }
    CameraDesc cam = {{0, 0.5f, cam_z}, {0, 0, 0}, {0, 1, 0}, 50.0f, 0.0f, cam_z, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}


/* The path tracer's furnace check (test_media, test_grid_media): the first `variants` of MIS,
 * phase/BSDF sampling only and NEE only render s (32 x 32, spp, seeds seed + i), every 8 x 8
 * block's mean within Z_LIMIT standard errors of L (plus float rounding of zero-variance
 * estimates); prints the whole image's. Destroys s. */
static inline void media_path_furnace(Scene *s, Color L, int spp, uint64_t seed, int variants, CstColorMode mode,
                                      const char *what)
{
    static const CstIntegrator VARIANTS[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_BSDF, CST_INTEGRATOR_PATH_NEE};
    const double expect[3] = {(double)L.c[0], (double)L.c[1], (double)L.c[2]};
    for (int v = 0; v < variants; v++) {
        char name[128];
        snprintf(name, sizeof name, "%s, %s", what, cst_integrator_name(VARIANTS[v]));
        CstRenderSettings st = {.width = 32, .height = 32, .color_mode = mode};
        CstFilm *f = render_film(s, &st, VARIANTS[v], spp, seed + (uint64_t)v);
        Regions r = regions(cst_film_width(f), cst_film_width(f) / 4);
        film_regions(f, &r);
        for (int i = 0; i < r.count; i++)
            for (int c = 0; c < 3; c++) {
                const double dev = fabs(r.stat[i].mean[c] - expect[c]);
                if (!(dev <= Z_LIMIT * r.stat[i].se[c] + 1e-5 * expect[c]))
                    fail_msg("%s: block %d channel %d: %.6f, expected %.6f (z = %.2f)", name, i - 1, c,
                             r.stat[i].mean[c], expect[c], (r.stat[i].mean[c] - expect[c]) / r.stat[i].se[c]);
            }
        print_message("%s: whole image %.5f %.5f %.5f (se %.1e), expected %.5f %.5f %.5f\n", name,
                      r.stat[0].mean[0], r.stat[0].mean[1], r.stat[0].mean[2], r.stat[0].se[0], expect[0], expect[1],
                      expect[2]);
        cst_film_destroy(f);
    }
    scene_destroy(s);
}

/* What fills the fog box's ball: homogeneous fog (sigma_a 0.2, sigma_s 1.5 1 0.5, g 0.5),
 * emitting or not, or a random grid over the ball's box (densities in [0, 3), mean 1.5, so
 * that sigma_s means the homogeneous fog's in green), emitting or not. The emission is
 * Le = 1.2 0.6 0.2: sigma_a Le = 0.24 0.12 0.04 per unit length in the homogeneous fog,
 * about 0.5 0.3 0.1 at the grid's mean density. */
typedef enum FogKind { FOG_HOMOGENEOUS, FOG_HOMOGENEOUS_EMISSIVE, FOG_GRID, FOG_GRID_EMISSIVE } FogKind;

/* The kind's medium, added to s; its id. */
static inline int fog_box_medium(Scene *s, FogKind kind)
{
    const bool emits = kind == FOG_GRID_EMISSIVE || kind == FOG_HOMOGENEOUS_EMISSIVE;
    const Color le = emits ? color_rgb(1.2f, 0.6f, 0.2f) : color_s(0.0f);
    if (kind == FOG_HOMOGENEOUS || kind == FOG_HOMOGENEOUS_EMISSIVE)
        return media_add_homogeneous(s, color_s(0.2f), color_rgb(1.5f, 1.0f, 0.5f), le, 0.5f);
    const Vec3 lo = {-0.8f, -0.9f, -0.6f}, hi = {0.4f, 0.3f, 0.6f};
    return media_add_random_grid(s, lo, hi, 3.0f, color_rgb(0.3f, 0.35f, 0.4f), color_rgb(1.0f, 0.7f, 0.35f), le,
                                 0.5f);
}

/* The fog box's ball of medium med (a boundary sphere of the black material lightm, radius
 * 0.6) and a diffuse sphere of material wall half inside it, added to s after the open box. */
static inline void fog_box_add_ball(Scene *s, int med, int wall, int lightm)
{
    CstError err;
    assert_int_equal(scene_set_medium_interface(s, med, -1, 1, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(-0.2f, -0.3f, 0.0f), 0.6f, lightm, NULL, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, -1, -1, 0, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0.45f, -0.6f, 0.2f), 0.35f, wall, NULL, &err), CST_OK);
}

/* The fog box's camera (from +z, 40 degrees, the whole box in view); commits s. */
static inline void fog_box_commit(Scene *s)
{
    CstError err;
    CameraDesc cam = {{0, 0, 3.8f}, {0, 0, 0}, {0, 1, 0}, 40.0f, 0.0f, 3.8f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
}

/* The open box without its camera: the walls and the light (box_scene.h), the kind's ball
 * of fog and the diffuse sphere; *wall and *lightm as open_box_add's. */
static inline Scene *fog_box_uncommitted(FogKind kind, int *wall, int *lightm)
{
    Scene *s = scene_create();
    assert_non_null(s);
    open_box_add(s, wall, lightm);
    const int med = fog_box_medium(s, kind);
    fog_box_add_ball(s, med, *wall, *lightm);
    return s;
}

/* The fog box: an open box of diffuse walls lit by a small quad light, a ball of
 * forward-scattering, slightly absorbing fog (the kind's) and a diffuse sphere half inside
 * it; committed. */
static inline Scene *fog_box(FogKind kind)
{
    int wall, lightm;
    Scene *s = fog_box_uncommitted(kind, &wall, &lightm);
    fog_box_commit(s);
    return s;
}

/* A furnace's check: `renders` independent 16 x 16 renders of integ (settings st, seeds from
 * seed), every 8 x 8 block's and the whole image's mean within Z_LIMIT standard errors of L
 * plus rel_tol L (the float rounding of zero-variance estimates, or 0); prints the whole
 * image's. */
static inline void media_furnace_check(const Scene *s, CstRenderSettings st, CstIntegrator integ, int renders,
                                       uint64_t seed, Color L, double rel_tol, const char *what)
{
    st.width = st.height = 16;
    Regions r = regions(16, 8);
    split_regions(s, &st, integ, renders, seed, &r);
    for (int i = 0; i < r.count; i++)
        for (int c = 0; c < 3; c++) {
            const double dev = fabs(r.stat[i].mean[c] - (double)L.c[c]);
            if (!(dev <= Z_LIMIT * r.stat[i].se[c] + rel_tol * (double)L.c[c]))
                fail_msg("%s, %s: block %d channel %d: %.6f, expected %.6f (z = %.2f)", what,
                         cst_integrator_name(integ), i - 1, c, r.stat[i].mean[c], (double)L.c[c],
                         (r.stat[i].mean[c] - (double)L.c[c]) / r.stat[i].se[c]);
        }
    print_message("%s, %s: whole image %.5f %.5f %.5f (se %.1e), expected %.5f %.5f %.5f\n", what,
                  cst_integrator_name(integ), r.stat[0].mean[0], r.stat[0].mean[1], r.stat[0].mean[2],
                  r.stat[0].se[0], (double)L.c[0], (double)L.c[1], (double)L.c[2]);
}

/* Issue 27's edge furnace (test_photon_media, test_sppm_media): a scattering-only ball of
 * radius 1 and optical radius 2 (sigma_s 2, an interface sphere) in vacuum inside the
 * emitting sphere of radius 4, the camera outside the ball: L everywhere, and most camera
 * vertices in the medium lie near its boundary, where a volume estimate's ball of radius
 * `radius` reaches into the vacuum. integ (photon or sppm) renders it `renders` times with
 * spp samples (iterations) of `photons` photons, media_furnace_check's 4-sigma test. */
static inline void media_edge_furnace_check(CstIntegrator integ, int spp, float radius, int photons, int renders,
                                            CstColorMode mode)
{
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = scene_create();
    const int med = media_add_homogeneous(s, color_s(0.0f), color_s(2.0f), color_s(0.0f), 0.0f);
    s = media_furnace(s, med, 4.0f, 1.0f, 3.5f, L);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.spp = spp;
    st.photon_radius = radius;
    st.photons = photons;
    st.color_mode = mode;
    media_furnace_check(s, st, integ, renders, 300, L, 0.0, "edge of a scattering ball");
    scene_destroy(s);
}


#endif
