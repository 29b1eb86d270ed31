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


/* Grid and cloud media, presets: JSON. */
static const char *JSON_GRID =
    "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
    " \"media\": {\"smoke\": {\"type\": \"uniformgrid\", \"nx\": 2, \"density\": [0.5, 1], \"p0\": [1, -1, -1],\n"
    "                     \"p1\": [-1, 1, 1], \"sigma_s\": 2, \"Le\": [1, 1, 1], \"Lescale\": [1, 2]},\n"
    "           \"milk\": {\"preset\": \"Wholemilk\", \"scale\": 0.5},\n"
    "           \"puff\": {\"type\": \"cloud\", \"density\": 2, \"p1\": [2, 2, 2]}},\n"
    " \"shapes\": [\n"
    "  {\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"medium\": {\"inside\": \"smoke\", \"boundary\": true}}]}\n";

static void test_json_grid_media(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json_string(JSON_GRID, strlen(JSON_GRID), "g.json", &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    assert_int_equal(s->num_media, 3);
    const Medium *g = &s->media[0];
    assert_int_equal(g->type, MEDIUM_GRID);
    assert_true(g->u.het.n[0] == 2 && g->u.het.n[1] == 1 && g->u.het.density[1] == 1.0f);
    assert_true(g->u.het.p0.x == -1.0f && g->u.het.p1.x == 1.0f); /* the box's corners, sorted */
    assert_true(g->u.het.le_scale && g->u.het.le_scale[1] == 2.0f && g->u.het.sigma_s.c[0] == 2.0f);
    assert_true(g->u.het.maj.max && g->u.het.maj.max[0] == 0.5f && g->u.het.maj.max[15] == 1.0f);
    const HomogeneousMedium *m = &s->media[1].u.homog;
    assert_true(fabsf(m->sigma_s.c[0] - 0.5f * 2.55f) < 1e-6f && fabsf(m->sigma_a.c[2] - 0.5f * 0.014f) < 1e-7f);
    assert_int_equal(s->media[2].type, MEDIUM_CLOUD);
    assert_true(s->media[2].u.het.cloud_density == 2.0f && s->media[2].u.het.frequency == 5.0f);
    cst_scene_destroy(s);
}

static void test_json_grid_errors(void **state)
{
    (void)state;
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"s\": {\"type\": \"uniformgrid\", \"nx\": 2, \"density\": [1, 2, 3]}}, \"shapes\": []}",
               "bad.json:2:61: media.s.density: 3 values; expected nx*ny*nz = 2");
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"s\": {\"type\": \"uniformgrid\", \"nx\": 2, \"density\": [1, -1]}}, \"shapes\": []}",
               "media.s.density[1]: -1; expected a number >= 0");
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"s\": {\"type\": \"uniformgrid\", \"nx\": 2}}, \"shapes\": []}",
               "density");
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"s\": {\"type\": \"uniformgrid\", \"nx\": 0, \"density\": []}}, \"shapes\": []}",
               "media.s.nx");
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"s\": {\"preset\": \"Milk\"}}, \"shapes\": []}",
               "media.s.preset: no scattering preset is called \"Milk\"");
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"s\": {\"type\": \"cloud\", \"nx\": 2}}, \"shapes\": []}",
               "bad.json:2:");
    /* Only a grid's Lescale may be an array. */
    json_error("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
               " \"media\": {\"s\": {\"Lescale\": [1, 2]}}, \"shapes\": []}",
               "media.s.Lescale");
}

/* Grid and cloud media, presets: pbrt. */
static void test_pbrt_grid_media(void **state)
{
    (void)state;
    const char *t =
        "Translate 0 0 -2\n"
        "MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"integer nx\" 2 \"float density\" [0.5 1]\n"
        "    \"point3 p0\" [-1 -1 -1] \"float Lescale\" [3 4] \"rgb Le\" [1 0 0]\n"
        "Identity\n"
        "MakeNamedMedium \"k\" \"string type\" \"homogeneous\" \"string preset\" \"Ketchup\"\n"
        "MakeNamedMedium \"x\" \"string type\" \"homogeneous\" \"string preset\" \"Tomato\"\n"
        "MakeNamedMedium \"c\" \"string type\" \"cloud\" \"float wispiness\" 0\n"
        "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n"
        "AttributeBegin\n  MediumInterface \"g\" \"\"\n  Material \"interface\"\n  Shape \"sphere\"\nAttributeEnd\n";
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    if (load_w(t, &s, &err, &w) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_media, 4);
    const HeteroMedium *g = &s->media[0].u.het;
    assert_int_equal(s->media[0].type, MEDIUM_GRID);
    assert_true(g->p0.x == -1.0f && g->p1.x == 1.0f && g->le_scale && g->le_scale[1] == 4.0f);
    /* medium_from_world undoes the CTM's translation. */
    Vec3 pm = transform_point(&g->medium_from_world, v3(0, 0, -2));
    assert_true(fabsf(pm.z) < 1e-6f);
    assert_true(fabsf(s->media[1].u.homog.sigma_a.c[1] - 0.97f) < 1e-6f);
    assert_true(s->media[2].u.homog.sigma_s.c[0] == 1.0f); /* unknown preset: the defaults */
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "no scattering preset is called \"Tomato\"") >= 0);
    assert_int_equal(s->media[3].type, MEDIUM_CLOUD);
    assert_true(s->media[3].u.het.wispiness == 0.0f);
    cst_scene_destroy(s);
}

static void test_pbrt_grid_errors(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    const char *t = "MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"integer nx\" 2 \"float density\" [1 2 3]\n";
    assert_int_equal(load_w(t, &s, &err, NULL), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "t.pbrt:1:") || !strstr(err.msg, "has 3 values; expected nx*ny*nz = 2")) fail_msg("%s", err.msg);
    t = "MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"integer nx\" 2 \"float density\" [1 -2]\n";
    assert_int_equal(load_w(t, &s, &err, NULL), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "t.pbrt:1:") || !strstr(err.msg, "value 2 is -2")) fail_msg("%s", err.msg);
    t = "MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"integer nx\" 2 \"float density\" [1 nan]\n";
    assert_int_not_equal(load_w(t, &s, &err, NULL), CST_OK);
    if (!strstr(err.msg, "t.pbrt:1:")) fail_msg("%s", err.msg);
    t = "MakeNamedMedium \"g\" \"string type\" \"uniformgrid\"\n";
    assert_int_equal(load_w(t, &s, &err, NULL), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "no \"float density\"")) fail_msg("%s", err.msg);
    t = "MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"float density\" [1] \"point3 p1\" [0 1 1]\n";
    assert_int_equal(load_w(t, &s, &err, NULL), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "p0 and p1 are equal")) fail_msg("%s", err.msg);
    t = "MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"integer nx\" -3 \"float density\" [1]\n";
    assert_int_equal(load_w(t, &s, &err, NULL), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "expected each in 1 .. 4096")) fail_msg("%s", err.msg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json_media),
        cmocka_unit_test(test_json_media_errors),
        cmocka_unit_test(test_pbrt_media),
        cmocka_unit_test(test_pbrt_media_errors),
        cmocka_unit_test(test_json_grid_media),
        cmocka_unit_test(test_json_grid_errors),
        cmocka_unit_test(test_pbrt_grid_media),
        cmocka_unit_test(test_pbrt_grid_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
