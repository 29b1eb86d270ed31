/* The rough plastic's coat albedo table (material_prepare, issue 25 item 11): the SSE/AVX
 * quadrature must give exactly, bit for bit, the table of the scalar loop it replaced (kept
 * here as the reference), so that images do not change. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "materials/fresnel.h"
#include "materials/material.h"
#include "materials/microfacet.h"

/* The quadrature as it was before issue 25 (material.c at c603ace), unchanged. */
static float reference_quadrature(float mu, float alpha, float eta, int n)
{
    Vec3 wo = v3(safe_sqrtf(1.0f - mu * mu), 0.0f, mu);
    double sum = 0.0;
    float g1 = ggx_g1(wo, alpha, alpha);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            Vec2 u = v2(((float)i + 0.5f) / (float)n, ((float)j + 0.5f) / (float)n);
            Vec3 m = ggx_sample_visible(wo, alpha, alpha, u);
            Vec3 wi = reflect_about(wo, m);
            if (wi.z <= 0.0f) continue;
            sum += (double)(fresnel_dielectric(v3_dot(wo, m), eta) * ggx_g2(wo, wi, alpha, alpha) / g1);
        }
    return (float)(sum / ((double)n * (double)n));
}

static void test_table_bit_identical(void **state)
{
    (void)state;
    /* Roughness from just above the smooth cut (alpha = 1e-3) to 1, IORs from 1 (no
     * interface) to the extreme 1e6 and beyond the float range of eta^2. */
    static const float rough[] = {0.0317f, 0.05f, 0.1f, 0.2f, 0.3333f, 0.4f, 0.5f, 0.7f, 0.9f, 1.0f};
    static const float ior[] = {1.0f, 1.0001f, 1.05f, 1.33f, 1.5f, 2.0f, 2.4f, 4.0f, 1e6f, 1e20f};
    int compared = 0;
    for (size_t a = 0; a < sizeof rough / sizeof rough[0]; a++)
        for (size_t b = 0; b < sizeof ior / sizeof ior[0]; b++) {
            Material m = {.type = MATERIAL_PLASTIC, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = ior[b], .roughness = rough[a]};
            material_prepare(&m);
            float alpha = material_alpha(m.roughness);
            for (int j = 0; j < MATERIAL_COAT_TABLE; j++) {
                float x = (float)j / (float)(MATERIAL_COAT_TABLE - 1);
                float want = reference_quadrature(maxf(x * x, 1e-4f), alpha, m.ior, 64);
                if (memcmp(&want, &m.coat_e[j], sizeof want) != 0)
                    fail_msg("roughness %g, ior %g, node %d: table %.9g, scalar quadrature %.9g", (double)rough[a],
                             (double)ior[b], j, (double)m.coat_e[j], (double)want);
                compared++;
            }
        }
    print_message("%d coat table entries bit-identical to the scalar quadrature\n", compared);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table_bit_identical),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
