/* Participating media in the loaders: JSON "media", "camera_medium" and shapes' "medium";
 * pbrt MakeNamedMedium, MediumInterface, the camera's medium, "interface" shapes between
 * media; located errors and warnings for what is wrong or unsupported. */
#include "unit/pbrt_test_util.h"

static const char *JSON_FOG =
    "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
    " \"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}},\n"
    " \"media\": {\"fog\": {\"sigma_a\": 0.1, \"sigma_s\": [0.2, 0.3, 0.4], \"scale\": 2, \"g\": 0.5,\n"
    "                    \"Le\": [1, 0, 0], \"Lescale\": 3},\n"
    "           \"mist\": {}},\n"
    " \"camera_medium\": \"mist\",\n"
    " \"shapes\": [\n"
    "  {\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1,\n"
    "   \"medium\": {\"inside\": \"fog\", \"outside\": \"mist\", \"boundary\": true}},\n"
    "  {\"type\": \"sphere\", \"center\": [3, 0, 0], \"radius\": 1, \"material\": \"white\"}]}\n";

static void test_json_media(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json_string(JSON_FOG, strlen(JSON_FOG), "fog.json", &s, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_media, 2);
    const HomogeneousMedium *h = &s->media[0].u.homog;
    assert_true(fabsf(h->sigma_a.c[0] - 0.2f) < 1e-6f && fabsf(h->sigma_s.c[2] - 0.8f) < 1e-6f);
    assert_true(fabsf(h->le.c[0] - 3.0f) < 1e-6f && s->media[0].g == 0.5f);
    assert_true(s->media[1].u.homog.sigma_s.c[1] == 1.0f); /* pbrt-v4's default, 1 */
    assert_int_equal(s->camera_medium, 1);
    assert_int_equal(s->sphere_info[0].medium, 1);
    assert_true(s->medium_ifaces[0].inside == 0 && s->medium_ifaces[0].outside == 1 && s->medium_ifaces[0].boundary);
    assert_int_equal(s->sphere_info[1].medium, 0);
    cst_scene_destroy(s);
}

static void json_error(const char *text, const char *want)
{
    CstScene *s = NULL;
    CstError err;
    assert_int_not_equal(cst_scene_load_json_string(text, strlen(text), "bad.json", &s, &err), CST_OK);
    if (!strstr(err.msg, want)) fail_msg("message \"%s\" lacks \"%s\"", err.msg, want);
    assert_null(s);
}

static void test_json_media_errors(void **state)
{
    (void)state;
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"fog\": {\"g\": 1.5}}, \"shapes\": []}",
               "bad.json:2:25: media.fog.g: 1.5; expected a number in (-1, 1)");
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"fog\": {\"type\": \"nanovdb\"}}, \"shapes\": []}",
               "bad.json:2:");
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"fog\": {}}, \"shapes\": [\n"
               "  {\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"medium\": {\"inside\": \"smoke\"}}]}",
               "bad.json:3:77: shapes[0].medium.inside: medium \"smoke\" is not defined; expected null or one of: fog");
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"fog\": {\"sigma_s\": -1}}, \"shapes\": []}",
               "bad.json:2:");
}

static const char *PBRT_FOG =
    "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.2 0.3]\n"
    "    \"rgb sigma_s\" [1 1 1] \"float scale\" 0.5 \"float g\" 0.3\n"
    "MakeNamedMedium \"vdb\" \"string type\" \"nanovdb\"\n"
    "MediumInterface \"\" \"fog\"\n"
    "LookAt 0 0 5 0 0 0 0 1 0\n"
    "Camera \"perspective\"\n"
    "WorldBegin\n"
    "Material \"diffuse\"\n"
    "Shape \"sphere\" \"float radius\" 3\n"
    "AttributeBegin\n"
    "  MediumInterface \"fog\" \"\"\n"
    "  Material \"interface\"\n"
    "  Shape \"sphere\" \"float radius\" 1\n"
    "AttributeEnd\n"
    "AttributeBegin\n"
    "  MediumInterface \"vdb\" \"\"\n"
    "  Material \"interface\"\n"
    "  Shape \"sphere\" \"float radius\" 2\n"
    "AttributeEnd\n";

static void test_pbrt_media(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    if (load_w(PBRT_FOG, &s, &err, &w) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_media, 1);
    assert_true(fabsf(s->media[0].u.homog.sigma_a.c[2] - 0.15f) < 1e-6f && s->media[0].g == 0.3f);
    assert_int_equal(s->camera_medium, 0);
    /* The sphere of radius 3 keeps the interface set before the camera (vacuum inside, fog
     * outside: a transition, as in pbrt-v4), the fog ball is a boundary; the "vdb" ball
     * (vacuum on both sides) is left out. */
    assert_int_equal(s->num_spheres, 2);
    assert_int_equal(s->sphere_info[0].medium, 1);
    assert_true(s->medium_ifaces[0].inside == -1 && s->medium_ifaces[0].outside == 0 && !s->medium_ifaces[0].boundary);
    assert_int_equal(s->sphere_info[1].medium, 2);
    assert_true(s->medium_ifaces[1].inside == 0 && s->medium_ifaces[1].outside == -1 && s->medium_ifaces[1].boundary);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:3:") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "\"nanovdb\" is not supported") >= 0);
    cst_scene_destroy(s);
}

static void test_pbrt_media_errors(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    const char *t = "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\nMediumInterface \"smoke\"\n";
    assert_int_equal(load_w(t, &s, &err, NULL), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "t.pbrt:4:17: MediumInterface: medium \"smoke\" is not defined"))
        fail_msg("%s", err.msg);
    t = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"float g\" 1\n";
    assert_int_not_equal(load_w(t, &s, &err, NULL), CST_OK);
    if (!strstr(err.msg, "t.pbrt:1:")) fail_msg("%s", err.msg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json_media),
        cmocka_unit_test(test_json_media_errors),
        cmocka_unit_test(test_pbrt_media),
        cmocka_unit_test(test_pbrt_media_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
