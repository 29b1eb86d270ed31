/* Light selection: every light (area emitters, point, spot, directional) is picked with
 * probability proportional to its power, checked by a chi-square test of 10^6 picks against
 * powers computed here from their closed forms; and the densities NEE reports agree with
 * those probabilities. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "render/render_util.h"
#include "scene/scene.h"

#define PI_D 3.14159265358979323846

/* Regularised upper incomplete gamma Q(a, x) for the chi-square survival function, by the
 * series of P for x < a + 1, else the continued fraction (Numerical Recipes sec. 6.2). */
static double gamma_q(double a, double x)
{
    if (x <= 0.0) return 1.0;
    if (x < a + 1.0) {
        double sum = 1.0 / a, term = sum;
        for (int n = 1; n < 1000; n++) {
            term *= x / (a + n);
            sum += term;
            if (fabs(term) < fabs(sum) * 1e-15) break;
        }
        return 1.0 - sum * exp(-x + a * log(x) - lgamma(a));
    }
    double b = x + 1.0 - a, c = 1e300, d = 1.0 / b, h = d;
    for (int i = 1; i < 1000; i++) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (fabs(c) < 1e-300) c = 1e-300;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-15) break;
    }
    return exp(-x + a * log(x) - lgamma(a)) * h;
}

static Scene *scene_with_lights(double power[6])
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {0.5f, 0.5f, 0.5f}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    /* Two quads (2 triangles each) and a sphere: power pi A L (x2 two-sided). */
    Vec3 q1[4] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
    Vec3 q2[4] = {{0, 2, 0}, {0, 2, 2}, {3, 2, 2}, {3, 2, 0}};
    Emission e1 = {{1.0f, 1.0f, 1.0f}, 0}, e2 = {{0.5f, 0.2f, 0.1f}, 1}, e3 = {{4.0f, 4.0f, 4.0f}, 0};
    assert_int_equal(scene_add_quad(s, q1, mat, &e1, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, q2, mat, &e2, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(5, 5, 5), 0.25f, mat, &e3, &err), CST_OK);
    DeltaLight pt = {DELTA_POINT, {1, 1, 1}, {0, 0, 0}, {2, 2, 2}, 0, 0};
    DeltaLight sp = {DELTA_SPOT, {2, 1, 1}, {0, -1, 0}, {8, 4, 2}, 0.9f, 0.8f};
    DeltaLight dl = {DELTA_DIRECTIONAL, {0, 0, 0}, {0, -1, 0}, {0.01f, 0.01f, 0.01f}, 0, 0};
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
    EmitterGeometry g = {s->positions, s->tri_indices, s->num_triangles, s->spheres};
    for (int n = 0; n < N; n++) {
        EmissionSample es;
        float u_sel = pcg32_float(&rng);
        Vec2 a = v2(pcg32_float(&rng), pcg32_float(&rng)), b = v2(pcg32_float(&rng), pcg32_float(&rng));
        emitter_sample_emission(&s->emitter_sampler, s->emitters, &g, u_sel, a, b, &es);
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

/* NEE's densities: an area point has pdf_a = pmf / area (converted to solid angle), a delta
 * light reports its pick probability, and each pmf is the light's share of the power. */
static void test_nee_densities(void **state)
{
    (void)state;
    double power[6];
    Scene *s = scene_with_lights(power);
    double total = 0.0;
    for (int k = 0; k < 6; k++) total += power[k];
    EmitterGeometry g = {s->positions, s->tri_indices, s->num_triangles, s->spheres};
    Pcg32 rng;
    pcg32_seed(&rng, 5u, 9u);
    Vec3 x = v3(1.5f, -1.0f, 1.0f); /* below quad 1 (which faces down), inside the spot's cone */
    int seen[8] = {0};
    for (int n = 0; n < 20000; n++) {
        LightLi ls;
        float u_sel = pcg32_float(&rng);
        Vec2 u = v2(pcg32_float(&rng), pcg32_float(&rng));
        if (!light_sample_li(&s->emitter_sampler, s->emitters, &g, x, u_sel, u, &ls)) continue;
        seen[ls.light] = 1;
        int src = source_of(s, ls.light);
        if (ls.delta) {
            double expect = power[src] / total;
            assert_true(fabs((double)ls.pdf - expect) <= 1e-5 * expect);
            continue;
        }
        const Emitter *e = &s->emitters[ls.light];
        /* Triangles of one quad split its power by area: pmf = power * (A_tri / A_quad). */
        double area_src = src == 0 ? 1.0 : src == 1 ? 6.0 : 4.0 * PI_D * 0.0625;
        double pmf = power[src] / total * (double)e->area / area_src;
        double d2 = (double)ls.dist * (double)ls.dist;
        double expect = pmf / (double)e->area * d2 / (double)ls.cos_light;
        assert_true(fabs((double)ls.pdf - expect) <= 1e-4 * expect);
    }
    for (int i = 0; i < 8; i++) assert_true(seen[i]);
    scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_selection_by_power),
        cmocka_unit_test(test_nee_densities),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
