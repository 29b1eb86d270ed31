/* Light selection: every light (area emitters, point, spot, directional) is picked with
 * probability proportional to its power, checked by a chi-square test of 10^6 picks against
 * powers computed here from their closed forms; the densities NEE reports agree with
 * those probabilities; sphere lights' cone sampling against its pdf (chi-square). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "render/render_util.h"
#include "scene/scene.h"
#include "unit/chi2.h"

#define PI_D 3.14159265358979323846

static Scene *scene_with_lights(double power[6])
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    /* Two quads (2 triangles each) and a sphere: power pi A L (x2 two-sided). */
    Vec3 q1[4] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
    Vec3 q2[4] = {{0, 2, 0}, {0, 2, 2}, {3, 2, 2}, {3, 2, 0}};
    Emission e1 = {{{1.0f, 1.0f, 1.0f}}, 0, 0}, e2 = {{{0.5f, 0.2f, 0.1f}}, 1, 0}, e3 = {{{4.0f, 4.0f, 4.0f}}, 0, 0};
    assert_int_equal(scene_add_quad(s, q1, mat, &e1, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, q2, mat, &e2, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(5, 5, 5), 0.25f, mat, &e3, &err), CST_OK);
    DeltaLight pt = {DELTA_POINT, {1, 1, 1}, {0, 0, 0}, {{2, 2, 2}}, 0, 0, {0}, {0}};
    DeltaLight sp = {DELTA_SPOT, {2, 1, 1}, {0, -1, 0}, {{8, 4, 2}}, 0.9f, 0.8f, {0}, {0}};
    DeltaLight dl = {DELTA_DIRECTIONAL, {0, 0, 0}, {0, -1, 0}, {{0.01f, 0.01f, 0.01f}}, 0, 0, {0}, {0}};
    assert_int_equal(scene_add_delta_light(s, &pt, &err), CST_OK);
    assert_int_equal(scene_add_delta_light(s, &sp, &err), CST_OK);
    assert_int_equal(scene_add_delta_light(s, &dl, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    /* Per light of the combined list: quad 1 (2 triangles), quad 2 (2), the sphere, then
     * the delta lights. Folded per source below. */
    const double y2 = 0.2126 * 0.5 + 0.7152 * 0.2 + 0.0722 * 0.1;
    power[0] = PI_D * 1.0 * 1.0;                 /* quad 1, area 1, one-sided, L = 1 */
    power[1] = PI_D * 6.0 * y2 * 2.0;            /* quad 2, area 6, two-sided */
    power[2] = PI_D * 4.0 * PI_D * 0.0625 * 4.0; /* sphere, area 4 pi r^2 */
    power[3] = 4.0 * PI_D * 2.0;
    double ysp = 0.2126 * 8 + 0.7152 * 4 + 0.0722 * 2;
    power[4] = 2.0 * PI_D * ysp * (1.0 - 0.5 * (0.9 + 0.8));
    double r = (double)s->emitter_sampler.radius;
    power[5] = PI_D * r * r * 0.01;
    return s;
}

/* The source (0..5) of combined-list light i. */
static int source_of(const Scene *s, int i)
{
    if (i >= s->emitter_sampler.count) return 3 + (i - s->emitter_sampler.count);
    uint32_t prim = s->emitters[i].prim;
    if ((int)prim >= s->num_triangles) return 2;
    return prim < 2 ? 0 : 1;
}

static void test_selection_by_power(void **state)
{
    (void)state;
    double power[6];
    Scene *s = scene_with_lights(power);
    assert_int_equal(s->emitter_sampler.lights, 5 + 3);
    double total = 0.0;
    for (int k = 0; k < 6; k++) total += power[k];
    enum { N = 1000000 };
    double obs[6] = {0};
    Pcg32 rng;
    pcg32_seed(&rng, 17u, 3u);
    EmitterGeometry g = scene_emitter_geometry(s);
    for (int n = 0; n < N; n++) {
        EmissionSample es;
        float u_sel = pcg32_float(&rng);
        Vec2 a = pcg32_v2(&rng), b = pcg32_v2(&rng);
        emitter_sample_emission(&s->emitter_sampler, &g, u_sel, a, b, &es);
        obs[source_of(s, es.emitter)] += 1.0;
    }
    double chi2 = 0.0;
    for (int k = 0; k < 6; k++) {
        double e = N * power[k] / total;
        chi2 += (obs[k] - e) * (obs[k] - e) / e;
        print_message("  source %d: %8.0f picks, expected %10.1f\n", k, obs[k], e);
    }
    double p = gamma_q(2.5, 0.5 * chi2); /* 5 degrees of freedom */
    print_message("  light selection: chi2 = %.2f, dof 5, p = %.4f\n", chi2, p);
    assert_true(p > 0.01);
    scene_destroy(s);
}

/* NEE's densities: a point on a triangle has pdf_a = pmf / area (converted to solid angle), a delta
 * light reports its pick probability, and each pmf is the light's share of the power. */
static void test_nee_densities(void **state)
{
    (void)state;
    double power[6];
    Scene *s = scene_with_lights(power);
    double total = 0.0;
    for (int k = 0; k < 6; k++) total += power[k];
    EmitterGeometry g = scene_emitter_geometry(s);
    Pcg32 rng;
    pcg32_seed(&rng, 5u, 9u);
    Vec3 x = v3(1.5f, -1.0f, 1.0f); /* below quad 1 (which faces down), inside the spot's cone */
    int seen[8] = {0};
    for (int n = 0; n < 20000; n++) {
        LightLi ls;
        float u_sel = pcg32_float(&rng);
        Vec2 u = pcg32_v2(&rng);
        if (!light_sample_li(&s->emitter_sampler, &g, x, u_sel, u, &ls)) continue;
        seen[ls.light] = 1;
        int src = source_of(s, ls.light);
        if (ls.delta) {
            double expect = power[src] / total;
            assert_true(fabs((double)ls.pmf - expect) <= 1e-5 * expect);
            continue;
        }
        const Emitter *e = &s->emitters[ls.light];
        /* Triangles of one quad split its power by area: pmf = power * (A_tri / A_quad). */
        double area_src = src == 0 ? 1.0 : src == 1 ? 6.0 : 4.0 * PI_D * 0.0625;
        double pmf = power[src] / total * (double)e->area / area_src;
        double d2 = (double)ls.dist * (double)ls.dist;
        double expect = pmf / (double)e->area * d2 / (double)ls.cos_light;
        /* direct_pdf (the bidirectional weights' density) is area sampling's always;
         * the sphere, seen from outside, is sampled by its cone: pdf_w = pmf / (2 pi
         * (1 - cos theta_max)) with sin^2 theta_max = r^2 / |c - x|^2. */
        assert_true(fabs((double)ls.direct_pdf - expect) <= 1e-4 * expect);
        if (src == 2) {
            double dx = 5.0 - 1.5, dy = 5.0 + 1.0, dz = 5.0 - 1.0;
            double s2 = 0.0625 / (dx * dx + dy * dy + dz * dz);
            expect = pmf / (2.0 * PI_D * (1.0 - sqrt(1.0 - s2)));
        }
        assert_true(fabs((double)ls.pdf_w - expect) <= 1e-4 * expect);
    }
    for (int i = 0; i < 8; i++) assert_true(seen[i]);
    scene_destroy(s);
}

/* A synthetic 64 x 32 environment: a sky gradient, a bright sun of a few pixels and a dark
 * band, so the distribution has structure at every scale. Returns a malloc'd buffer. */
static float *synthetic_env(int w, int h)
{
    float *rgb = malloc((size_t)w * (size_t)h * 3 * sizeof *rgb);
    assert_non_null(rgb);
    for (int r = 0; r < h; r++)
        for (int c = 0; c < w; c++) {
            float *p = &rgb[3 * ((size_t)r * (size_t)w + (size_t)c)];
            float sky = 0.2f + 0.8f * (float)(h - r) / (float)h;
            p[0] = 0.5f * sky; p[1] = 0.7f * sky; p[2] = sky;
            if (r >= 6 && r < 8 && c >= 40 && c < 43) { p[0] = 200.0f; p[1] = 180.0f; p[2] = 150.0f; }
            if (r >= 20 && r < 24) { p[0] = p[1] = p[2] = 0.0f; }
        }
    return rgb;
}

/* Environment sampling against its pdf: 10^6 directions into a (theta, phi) histogram
 * twice as fine as the image in each direction (so cell edges fall on pixel edges and
 * the density is smooth inside each cell), expected counts from envmap_pdf integrated
 * with d omega = sin theta dtheta dphi on 4 x 4 midpoints per cell; cells expecting fewer
 * than 5 pooled. Also every sample's reported pdf equals envmap_pdf of its direction. */
static void test_envmap_chi2(void **state)
{
    (void)state;
    EnvMap m;
    CstError err;
    assert_int_equal(envmap_init_image(&m, synthetic_env(64, 32), 64, 32, color_s(1.0f), &err), CST_OK);
    enum { NT = 64, NP = 128, N = 1000000, SUB = 4 };
    static double obs[NT * NP], expd[NT * NP];
    memset(obs, 0, sizeof obs);
    Pcg32 rng;
    pcg32_seed(&rng, 21u, 4u);
    for (int n = 0; n < N; n++) {
        Vec2 u = pcg32_v2(&rng);
        float pdf;
        Vec3 w = envmap_sample(&m, u, &pdf);
        if (!(pdf == envmap_pdf(&m, w))) fail_msg("sample %d: pdf %g, envmap_pdf %g", n, (double)pdf, (double)envmap_pdf(&m, w));
        double theta = acos(fmax(-1.0, fmin(1.0, (double)w.y))), phi = atan2((double)w.z, (double)w.x);
        if (phi < 0.0) phi += 2.0 * PI_D;
        int i = (int)(theta / PI_D * NT), j = (int)(phi / (2.0 * PI_D) * NP);
        i = i < 0 ? 0 : i >= NT ? NT - 1 : i;
        j = j < 0 ? 0 : j >= NP ? NP - 1 : j;
        obs[i * NP + j] += 1.0;
    }
    double total = 0.0;
    for (int i = 0; i < NT; i++)
        for (int j = 0; j < NP; j++) {
            double sum = 0.0;
            for (int a = 0; a < SUB; a++)
                for (int b = 0; b < SUB; b++) {
                    double th = PI_D * (i + (a + 0.5) / SUB) / NT, phi = 2.0 * PI_D * (j + (b + 0.5) / SUB) / NP;
                    Vec3 w = v3((float)(sin(th) * cos(phi)), (float)cos(th), (float)(sin(th) * sin(phi)));
                    sum += (double)envmap_pdf(&m, w) * sin(th);
                }
            expd[i * NP + j] = sum / (SUB * SUB) * (PI_D / NT) * (2.0 * PI_D / NP) * N;
            total += expd[i * NP + j];
        }
    print_message("  environment map: pdf integrates to %.5f\n", total / N);
    assert_true(fabs(total / N - 1.0) < 2e-3);
    double chi2, outside;
    int dof;
    double p = chi2_pvalue(obs, expd, NT * NP, &dof, &chi2, &outside);
    assert_true(outside == 0.0); /* no sample where the pdf is 0 */
    print_message("  environment map: chi2 = %.1f, dof %d, p = %.4f\n", chi2, dof, p);
    assert_true(p > 0.01);
    envmap_free(&m);
}

/* One sphere emitter (centre c, radius r, radiance 1): its only light, pmf 1. */
static Scene *scene_with_sphere(Vec3 c, float r)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    Emission e = {{{1.0f, 1.0f, 1.0f}}, 0, 0};
    assert_int_equal(scene_add_sphere(s, c, r, mat, &e, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

/* Sphere lights seen from outside are sampled by the cone they subtend (light.c,
 * sphere_sample_cone): the direction toward the returned point must be uniform in that
 * cone. 10^6 directions from x binned by t = (1 - cos theta) / (1 - cos theta_max) (theta
 * from the axis toward the centre, computed here in double) and phi, 32 x 32 equal-solid-
 * angle cells, against the uniform expectation pdf_w gives; every sample's pdf_w must be
 * 1 / (2 pi (1 - cos theta_max)) and equal light_area_pdf_w's; the point must lie on the
 * sphere with its normal toward x (so it is the nearer hit along wi). Three sizes: a near sphere (theta_max
 * 53 deg), a mid one (5.7 deg) and a far one (0.057 deg, where 1 - sqrt(1 - s) in float
 * would have lost most digits). */
static void cone_case(double dist, double radius, uint64_t seed)
{
    const Vec3 x = v3(0.3f, -0.2f, 0.1f);
    const Vec3 axis_f = v3_normalize(v3(1.0f, 2.0f, -0.5f));
    const Vec3 c = v3_madd(x, axis_f, (float)dist);
    Scene *s = scene_with_sphere(c, (float)radius);
    EmitterGeometry g = scene_emitter_geometry(s);
    /* The axis and theta_max in double, from the float centre actually stored. */
    double ax = (double)c.x - (double)x.x, ay = (double)c.y - (double)x.y, az = (double)c.z - (double)x.z;
    double d = sqrt(ax * ax + ay * ay + az * az);
    ax /= d; ay /= d; az /= d;
    double s2 = (double)radius * (double)radius / (d * d);
    double omc_max = s2 / (1.0 + sqrt(1.0 - s2));
    double pdf_expect = 1.0 / (2.0 * PI_D * omc_max);
    /* A frame around the axis for phi. */
    double bx, by, bz;
    if (fabs(ax) < 0.9) { bx = 0; by = az; bz = -ay; } else { bx = -az; by = 0; bz = ax; }
    double bl = sqrt(bx * bx + by * by + bz * bz);
    bx /= bl; by /= bl; bz /= bl;
    double tx = ay * bz - az * by, ty = az * bx - ax * bz, tz = ax * by - ay * bx;
    enum { NT = 32, NP = 32, N = 1000000 };
    static double obs[NT * NP], expd[NT * NP];
    memset(obs, 0, sizeof obs);
    Pcg32 rng;
    pcg32_seed(&rng, seed, 7u);
    double max_pdf_err = 0.0, max_radius_err = 0.0, max_facing = -1.0;
    for (int n = 0; n < N; n++) {
        LightLi ls;
        float u_sel = pcg32_float(&rng);
        Vec2 u = pcg32_v2(&rng);
        if (!light_sample_li(&s->emitter_sampler, &g, x, u_sel, u, &ls)) continue;
        max_pdf_err = fmax(max_pdf_err, fabs((double)ls.pdf_w / pdf_expect - 1.0));
        float pw = light_area_pdf_w(&s->emitter_sampler, &g, 0, x, ls.dist, ls.cos_light);
        if (!(pw == ls.pdf_w)) fail_msg("sample %d: pdf_w %g, light_area_pdf_w %g", n, (double)ls.pdf_w, (double)pw);
        double px = (double)ls.p.x - (double)c.x, py = (double)ls.p.y - (double)c.y, pz = (double)ls.p.z - (double)c.z;
        max_radius_err = fmax(max_radius_err, fabs(sqrt(px * px + py * py + pz * pz) / radius - 1.0));
        /* On the sphere and facing x: the nearer of the two intersections along wi. */
        double facing = (double)v3_dot(ls.n, ls.wi);
        if (!(facing <= 1e-6)) fail_msg("sample %d: the point faces away from x (n . wi = %g)", n, facing);
        max_facing = fmax(max_facing, facing);
        double wx = (double)ls.wi.x, wy = (double)ls.wi.y, wz = (double)ls.wi.z;
        double wl = sqrt(wx * wx + wy * wy + wz * wz);
        wx /= wl; wy /= wl; wz /= wl;
        /* 1 - cos theta without cancellation: |w - axis|^2 / 2. */
        double ex = wx - ax, ey = wy - ay, ez = wz - az;
        double omc = 0.5 * (ex * ex + ey * ey + ez * ez);
        double phi = atan2(wx * tx + wy * ty + wz * tz, wx * bx + wy * by + wz * bz);
        if (phi < 0.0) phi += 2.0 * PI_D;
        int i = (int)(omc / omc_max * NT), j = (int)(phi / (2.0 * PI_D) * NP);
        i = i < 0 ? 0 : i >= NT ? NT - 1 : i;
        j = j < 0 ? 0 : j >= NP ? NP - 1 : j;
        obs[i * NP + j] += 1.0;
    }
    for (int k = 0; k < NT * NP; k++) expd[k] = (double)N / (NT * NP);
    double chi2, outside;
    int dof;
    double p = chi2_pvalue(obs, expd, NT * NP, &dof, &chi2, &outside);
    print_message("  sphere cone, theta_max %.4g deg: chi2 = %.1f, dof %d, p = %.4f; max |pdf_w rel err| %.1e, "
                  "|p - c| / r - 1 %.1e, max n . wi %.1e\n",
                  asin(sqrt(s2)) * 180.0 / PI_D, chi2, dof, p, max_pdf_err, max_radius_err, max_facing);
    assert_true(p > 0.01);
    assert_true(max_pdf_err < 1e-4);
    assert_true(max_radius_err < 1e-4);
    scene_destroy(s);
}

static void test_sphere_cone_chi2(void **state)
{
    (void)state;
    cone_case(2.5, 2.0, 31u);
    cone_case(10.0, 1.0, 32u);
    cone_case(1000.0, 1.0, 33u);
}

/* Inside a sphere light there is no cone: a uniform point by area, pdf_w = dist^2 /
 * (A |cos|), and light_area_pdf_w agrees. */
static void test_sphere_inside(void **state)
{
    (void)state;
    const Vec3 c = v3(1.0f, 2.0f, 3.0f);
    Scene *s = scene_with_sphere(c, 2.0f);
    EmitterGeometry g = scene_emitter_geometry(s);
    Pcg32 rng;
    pcg32_seed(&rng, 41u, 2u);
    const Vec3 x = v3(1.5f, 2.5f, 2.0f);
    for (int n = 0; n < 1000; n++) {
        LightLi ls;
        float u_sel = pcg32_float(&rng);
        Vec2 u = pcg32_v2(&rng);
        if (!light_sample_li(&s->emitter_sampler, &g, x, u_sel, u, &ls)) continue; /* one-sided: dark inside */
        fail_msg("a one-sided sphere light lit its inside");
    }
    float pa = light_area_pdf_w(&s->emitter_sampler, &g, 0, x, 2.0f, 0.5f);
    double expect = 4.0 / (4.0 * PI_D * 4.0) / 0.5;
    assert_true(fabs((double)pa - expect) <= 1e-5 * expect);
    scene_destroy(s);
}

/* A goniometric light's light paths carry its flux: the mean of beta over emission
 * samples is 4 pi I mean(image) (with one light, pmf 1), within 4 standard errors; and
 * its selection weight (power) is that flux's luminance. The image: 16 x 16 factors
 * 0, 1, ..., 255 scaled by 1/64, uneven enough to catch a direction that ignores it. */
static void test_gonio_emission(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    enum { N = 16 };
    float *img = malloc(N * N * sizeof *img);
    assert_non_null(img);
    double sum = 0.0;
    for (int i = 0; i < N * N; i++) sum += (double)(img[i] = (float)i / 64.0f);
    DeltaLight l;
    memset(&l, 0, sizeof l);
    l.type = DELTA_GONIO;
    l.p = v3(0.5f, 1.0f, -0.5f);
    l.intensity = color_rgb(2.0f, 1.0f, 0.5f);
    l.gonio.factor = img;
    l.gonio.n = N;
    l.gonio.mean = (float)(sum / (N * N));
    const float rot[9] = {0, 0, 1, 1, 0, 0, 0, 1, 0};
    memcpy(l.gonio.light_from_world, rot, sizeof rot);
    assert_int_equal(scene_add_delta_light(s, &l, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    EmitterGeometry g = scene_emitter_geometry(s);
    Pcg32 rng;
    pcg32_seed(&rng, 71u, 5u);
    enum { M = 400000 };
    double m = 0.0, m2 = 0.0;
    for (int k = 0; k < M; k++) {
        EmissionSample es;
        float u_sel = pcg32_float(&rng);
        Vec2 a = pcg32_v2(&rng), b = pcg32_v2(&rng);
        emitter_sample_emission(&s->emitter_sampler, &g, u_sel, a, b, &es);
        double v = (double)es.beta.c[0];
        m += v;
        m2 += v * v;
    }
    m /= M;
    double se = sqrt((m2 / M - m * m) / M);
    double flux = 4.0 * PI_D * 2.0 * sum / (N * N);
    print_message("  goniometric emission: mean beta %.4f (se %.4f), 4 pi I mean %.4f\n", m, se, flux);
    assert_true(fabs(m - flux) <= 4.0 * se);
    double y = 0.2126 * 2.0 + 0.7152 * 1.0 + 0.0722 * 0.5;
    assert_true(fabs((double)light_power(&s->emitter_sampler.light[0], 1.0f) / (4.0 * PI_D * y * sum / (N * N)) - 1.0) < 1e-5);
    scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_selection_by_power),
        cmocka_unit_test(test_nee_densities),
        cmocka_unit_test(test_envmap_chi2),
        cmocka_unit_test(test_sphere_cone_chi2),
        cmocka_unit_test(test_sphere_inside),
        cmocka_unit_test(test_gonio_emission),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
