/* Unit tests for the pbrt-v4 loader (scene/pbrt/), geometry: shapes, PLY meshes, image
 * maps next to them, the directives caustic ignores, and ObjectBegin/ObjectInstance. */
#include "unit/pbrt_test_util.h"

/* ------------------------------------------------------------------ shapes */

static void test_shapes(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD(
        "AttributeBegin\nTranslate 1 2 3\nScale 2 2 2\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n"
        "AttributeBegin\nScale 1 1 3\nShape \"sphere\"\nAttributeEnd\n"
        "Shape \"sphere\" \"float zmax\" 0.5\n"
        "Shape \"disk\" \"float radius\" 2 \"float height\" 1\n"
        "Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"integer indices\" [0 1 2 3]\n"
        "Shape \"loopsubdiv\" \"integer levels\" 2 \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
        "Shape \"cylinder\"\n"
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  2 0 0  0 1 0] \"integer indices\" [0 1 2 0 1 3]\n"),
        &w);
    assert_int_equal(s->num_spheres, 1);
    assert_vec(s->spheres[0].center, 1, 2, 3, 0);
    assert_true(s->spheres[0].radius == 1.0f);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "non-uniform transform tessellated") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "partial sphere") < 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "cylinder") < 0);
    assert_true(find_warning(&w, CST_WARN_GEOMETRY, "1 of 2 triangles are degenerate") >= 0);
    /* analytic shapes: the partial sphere, the disk (area pi r^2 at z = 1), the bilinear
     * patch, the cylinder */
    assert_int_equal(s->num_shapes, 4);
    assert_int_equal(s->shapes[0].p.type, SHAPE_TAG_SPHERE);
    assert_true(s->shapes[0].p.z_max == 0.5f && s->shapes[0].p.z_min == -1.0f);
    assert_int_equal(s->shapes[1].p.type, SHAPE_TAG_DISK);
    assert_true(s->shapes[1].p.height == 1.0f && s->shapes[1].p.radius == 2.0f);
    assert_true(fabs((double)shape_area(&s->shapes[1]) - 4.0 * 3.14159265358979) < 1e-4);
    assert_int_equal(s->shapes[2].p.type, SHAPE_TAG_BILINEAR);
    ShapeSurface sf; /* facing +z, as pbrt's dp/du x dp/dv */
    shape_surface_at(&s->shapes[2], v2(0.5f, 0.5f), &sf);
    assert_true(sf.n.z > 0.999f);
    assert_int_equal(s->shapes[3].p.type, SHAPE_TAG_CYLINDER);
    assert_true(s->shapes[3].p.z_min == -1.0f && s->shapes[3].p.z_max == 1.0f && s->shapes[3].p.radius == 1.0f);
    int first_disk = 2 * 64 * 31; /* after the tessellated sphere: the disk and the patch have no triangles */
    /* the loopsubdiv triangle refined twice: 16 triangles (its limit surface: test_loop_subdiv) */
    assert_int_equal(s->num_triangles, first_disk + 16 + 1);
    cst_scene_destroy(s);
}

/* A full sphere whose material reads uv or dp/du (here a texture) is the analytic sphere,
 * for pbrt-v4's parametrization in the object frame: under Rotate 90 about x, (u, v) =
 * (0.25, 0.5) is object +y, world +z, with dp/du along -x (2 pi long); (0.25, 0.75) is
 * theta = pi/4 from object +z, world (0, -0.707, 0.707). Plain and emitting spheres stay
 * caustic's own. */
static void test_sphere_uv(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD("Texture \"c\" \"spectrum\" \"checkerboard\"\n"
                               "AttributeBegin\nMaterial \"diffuse\" \"texture reflectance\" \"c\"\n"
                               "Rotate 90 1 0 0\nShape \"sphere\"\n"
                               "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\nTranslate 0 0 9\nShape \"sphere\"\n"
                               "AttributeEnd\nTranslate 0 0 -9\nShape \"sphere\"\n"),
                         &w);
    assert_int_equal(s->num_shapes, 1);
    assert_int_equal(s->num_spheres, 2);
    assert_int_equal(s->shapes[0].p.type, SHAPE_TAG_SPHERE);
    ShapeSurface sf;
    shape_surface_at(&s->shapes[0], v2(0.25f, 0.5f), &sf);
    assert_vec(sf.p, 0.0f, 0.0f, 1.0f, 1e-5f);
    assert_vec(sf.dpdu, -6.2831853f, 0.0f, 0.0f, 1e-4f);
    assert_true(fabsf(sf.uv.x - 0.25f) < 1e-6f && fabsf(sf.uv.y - 0.5f) < 1e-6f);
    shape_surface_at(&s->shapes[0], v2(0.25f, 0.75f), &sf);
    assert_vec(sf.p, 0.0f, -0.70710678f, 0.70710678f, 1e-5f);
    cst_scene_destroy(s);
}

/* An emitting disk, cylinder and partial sphere are analytic area lights (their "power"
 * normalised by the world area, pbrt-v4's DiffuseAreaLight::Create); under a non-uniform
 * scale an emitting disk falls back to its tessellation and an emitting cylinder is
 * skipped, with a warning that says why. */
static void test_quadric_emitters(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD("AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
                               "Shape \"disk\" \"float radius\" 2 \"float innerradius\" 1\nShape \"cylinder\"\n"
                               "AttributeEnd\n"
                               "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"float power\" 10\n"
                               "Translate 0 0 5 Scale 2 2 2\n"
                               "Shape \"sphere\" \"float zmin\" 0 \"float phimax\" 180\nAttributeEnd\n"
                               "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"),
                         &w);
    assert_int_equal(s->num_shapes, 3);
    assert_int_equal(s->num_triangles, 1);
    assert_int_equal(s->num_emitters, 3);
    const float pi = 3.14159265f;
    assert_float_equal(s->emitters[0].area, 3.0f * pi, 1e-5f); /* pi (2^2 - 1^2) */
    assert_float_equal(s->emitters[1].area, 4.0f * pi, 1e-5f); /* 2 pi r h, r 1, h 2 */
    /* half of the upper hemisphere of radius 2: pi r^2 = 4 pi; L = power / (pi A) */
    assert_float_equal(s->emitters[2].area, 4.0f * pi, 1e-5f);
    assert_float_equal(s->emitters[2].radiance.c[0], 10.0f / (pi * 4.0f * pi), 1e-5f);
    cst_scene_destroy(s);
    Warnings w2 = {0};
    s = expect_ok(WORLD("AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\nScale 1 2 1\n"
                        "Shape \"disk\"\nShape \"cylinder\"\nAttributeEnd\n"
                        "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"),
                  &w2);
    assert_int_equal(s->num_shapes, 0);
    assert_int_equal(s->num_triangles, 128 + 1);
    assert_true(find_warning(&w2, CST_WARN_UNSUPPORTED, "emitting under a non-uniform scale") >= 0);
    cst_scene_destroy(s);
}

/* loopsubdiv: the limit surface with limit normals (geometry/loop_subdiv.c; the values are
 * test_loop_subdiv's), normals facing the way pbrt-v4's do (the octahedron's inward, against
 * its outward winding, and the triangles turned to face them); N and uv ignored with a
 * warning; a non-manifold control mesh renders as itself with a located warning. */
static void test_loopsubdiv(void **state)
{
    (void)state;
    Warnings w = {0};
    const char *octa = "\"point3 P\" [1 0 0 -1 0 0 0 1 0 0 -1 0 0 0 1 0 0 -1] \"integer indices\" "
                       "[0 2 4 2 1 4 1 3 4 3 0 4 2 0 5 1 2 5 3 1 5 0 3 5]";
    char text[1024];
    snprintf(text, sizeof text, WORLD("Shape \"loopsubdiv\" \"integer levels\" 3 %s \"point2 uv\" [0 0 1 0 0 1 1 1 0 0 1 0]\n"), octa);
    Scene *s = expect_ok(text, &w);
    assert_int_equal(s->num_triangles, 8 * 64);
    assert_non_null(s->normals);
    /* the control vertices' limit points: +-1/2 on the axes, normal pointing to the centre */
    assert_vec(s->positions[0], 0.5f, 0.0f, 0.0f, 1e-6f);
    assert_vec(s->normals[0], -1.0f, 0.0f, 0.0f, 1e-5f);
    for (int t = 0; t < s->num_triangles; t++) /* every triangle faces its vertex normals */
        assert_true(v3_dot(s->tri_normals[t], s->normals[s->tri_indices[3 * t]]) > 0.0f);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"N\" and \"uv\" are ignored") >= 0);
    cst_scene_destroy(s);
    /* levels 0 (or negative, as pbrt-v4's loop that never runs): the control mesh pushed
     * to the limit */
    Warnings w0 = {0};
    snprintf(text, sizeof text, WORLD("Shape \"loopsubdiv\" \"integer levels\" -2 %s\n"), octa);
    s = expect_ok(text, &w0);
    assert_int_equal(s->num_triangles, 8);
    assert_vec(s->positions[2], 0.0f, 0.5f, 0.0f, 1e-6f);
    assert_int_equal(w0.n, 0);
    cst_scene_destroy(s);
    /* three faces on one edge */
    Warnings w2 = {0};
    const char *fin = WORLD("Shape \"loopsubdiv\" \"point3 P\" [0 0 0 1 0 0 0 1 0 0 -1 0 0 0 1] "
                            "\"integer indices\" [0 1 2 1 0 3 0 1 4]\n");
    s = expect_ok(fin, &w2);
    assert_int_equal(s->num_triangles, 3);
    int i = find_warning(&w2, CST_WARN_GEOMETRY, "Shape \"loopsubdiv\": edge (0, 1) is shared by 3 faces");
    if (i < 0) fail_msg("%d warnings, first: %s", w2.n, w2.msg[0]);
    if (strncmp(w2.msg[i], "t.pbrt:4:1: ", 12) != 0) fail_msg("%s", w2.msg[i]);
    assert_true(strstr(w2.msg[i], "rendered as its control mesh") != NULL);
    cst_scene_destroy(s);
}

/* Shape "alpha": a constant below 1, a float texture, a constant 0 (the shape left out),
 * 1 (opaque, no cut-out), and inside ObjectBegin (kept per triangle of the object). */
static void test_shape_alpha(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD(
        "Texture \"mask\" \"float\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 4 "
        "\"float tex1\" 0 \"float tex2\" 1\n"
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"integer indices\" [0 1 2] \"float alpha\" 0.5\n"
        "Shape \"trianglemesh\" \"point3 P\" [0 0 1  1 0 1  0 1 1] \"integer indices\" [0 1 2] \"texture alpha\" \"mask\"\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [7 7 7]\n"
        "Shape \"bilinearmesh\" \"point3 P\" [0 0 2 1 0 2 0 1 2 1 1 2] \"float alpha\" [ 0 ]\nAttributeEnd\n"
        "Shape \"sphere\" \"float alpha\" 1\n"
        "Shape \"sphere\" \"float alpha\" 0.25\n"), &w);
    assert_int_equal(s->num_triangles, 2); /* the alpha-0 light left out */
    assert_int_equal(s->num_emitters, 0);
    assert_int_equal(s->num_alphas, 3);
    assert_int_equal(s->tri_info[0].alpha, 1);
    assert_true(s->alphas[0].value == 0.5f && s->alphas[0].texture == 0);
    assert_int_equal(s->tri_info[1].alpha, 2);
    assert_true(s->alphas[1].texture > 0);
    assert_int_equal(s->num_spheres, 2);
    assert_int_equal(s->sphere_info[0].alpha, 0);
    assert_int_equal(s->sphere_info[1].alpha, 3);
    assert_true(s->alphas[2].value == 0.25f);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "alpha") < 0);
    cst_scene_destroy(s);
    /* inside ObjectBegin: the cut-out per triangle of the object, its uvs kept; a shape
     * without uvs beside one with them gets corners of its own with the default uvs */
    Warnings w2 = {0};
    s = expect_ok(WORLD("ObjectBegin \"leaf\"\n"
                        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"integer indices\" [0 1 2] "
                        "\"point2 uv\" [0.5 0.5  1 0.5  0.5 1] \"float alpha\" 0.5\n"
                        "Shape \"trianglemesh\" \"point3 P\" [0 0 1  1 0 1  0 1 1  1 1 1] "
                        "\"integer indices\" [0 1 2  2 1 3]\n"
                        "Shape \"trianglemesh\" \"point3 P\" [0 0 2  1 0 2  0 1 2] \"integer indices\" [0 1 2] "
                        "\"float alpha\" 0\nObjectEnd\nObjectInstance \"leaf\"\n"), &w2);
    assert_true(find_warning(&w2, CST_WARN_UNSUPPORTED, "alpha") < 0);
    assert_int_equal(s->num_alphas, 1);
    assert_true(s->alphas[0].value == 0.5f);
    assert_non_null(s->instances);
    const InstProto *pr = &s->instances->protos[0];
    assert_int_equal(pr->num_triangles, 3); /* the alpha-0 shape left out */
    assert_int_equal(pr->num_positions, 3 + 6);
    assert_non_null(pr->tri_alpha);
    assert_true(pr->tri_alpha[0] == 1 && pr->tri_alpha[1] == 0 && pr->tri_alpha[2] == 0);
    assert_non_null(pr->uvs);
    assert_true(pr->uvs[pr->tri_indices[1]].x == 1.0f && pr->uvs[pr->tri_indices[1]].y == 0.5f);
    for (int t = 1; t < 3; t++) /* triangle_uv's default at the stored corners */
        assert_true(pr->uvs[pr->tri_indices[3 * t]].x == 0.0f && pr->uvs[pr->tri_indices[3 * t]].y == 0.0f &&
                    pr->uvs[pr->tri_indices[3 * t + 1]].x == 1.0f && pr->uvs[pr->tri_indices[3 * t + 2]].y == 1.0f);
    cst_scene_destroy(s);
}

static void test_plymesh(void **state)
{
    (void)state;
    write_text(CST_BINARY_DIR "/pbrt_quad.ply",
               "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
               "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
               "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n");
    const char *text = WORLD("Translate 0 0 7\nShape \"plymesh\" \"string filename\" \"pbrt_quad.ply\"\n");
    CstScene *s = NULL;
    CstError err;
    CstStatus st = load_at(text, CST_BINARY_DIR "/t.pbrt", &s, &err, NULL);
    if (st != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_triangles, 2);
    assert_vec(tri_vertex(s, 1, 2), 0, 1, 7, 0);
    cst_scene_destroy(s);
    /* the same square as one quad and a pentagon, gzip-compressed (`gzip -9n`): the quad
     * split as pbrt-v4 splits it, (v0 v1 v2) (v0 v2 v3), with an approximation warning; the
     * pentagon skipped with a warning, as pbrt-v4 skips it */
    static const char quad[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
        "property float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\n"
        "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n5 0 1 2 3 0\n";
    FILE *gz = popen("gzip -9n > " CST_BINARY_DIR "/pbrt_quad.ply.gz", "w");
    assert_non_null(gz);
    fputs(quad, gz);
    assert_int_equal(pclose(gz), 0);
    text = WORLD("Translate 0 0 7\nShape \"plymesh\" \"string filename\" \"pbrt_quad.ply.gz\"\n");
    Warnings w = {0};
    st = load_at(text, CST_BINARY_DIR "/t.pbrt", &s, &err, &w);
    if (st != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_triangles, 2);
    assert_vec(tri_vertex(s, 0, 2), 1, 1, 7, 0);
    assert_vec(tri_vertex(s, 1, 1), 1, 1, 7, 0);
    assert_vec(tri_vertex(s, 1, 2), 0, 1, 7, 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "t.pbrt:5:17: Shape \"plymesh\": "
                             "\"pbrt_quad.ply.gz\": 1 quads each split into two triangles") >= 0);
    assert_true(find_warning(&w, CST_WARN_GEOMETRY, "1 faces of other than 3 or 4 vertices "
                             "skipped (the first has 5)") >= 0);
    cst_scene_destroy(s);
}

/* Directives that only warn, and the v3 leftovers that are accepted silently. */
static void test_other_directives(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok("Option \"bool disablepixeljitter\" true\n"
                         "ColorSpace \"aces2065-1\"\n"
                         "TransformTimes 0 1\n"
                         "WorldBegin\n"
                         "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
                         "MediumInterface \"fog\" \"\"\n"
                         "MediumInterface \"fog\"\n"
                         "Attribute \"shape\" \"float radius\" 2\n"
                         "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"vector3 S\" [1 0 0 1 0 0 1 0 0] "
                         "\"vector2 dpdu\" [1 0]\n"
                         "WorldEnd\n", &w);
    assert_int_equal(s->num_triangles, 1);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:1:1: Option is not supported") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "t.pbrt:2:12: ColorSpace \"aces2065-1\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:3:1: TransformTimes") < 0); /* supported */
    /* Media are rendered since issue 27 (test_media_loaders): no warning; the triangle's
     * interface "fog" "fog" is no transition. */
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "MakeNamedMedium") < 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "MediumInterface") < 0);
    assert_int_equal(s->num_media, 1);
    assert_int_equal(s->tri_info[0].medium, 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:8:1: Attribute \"shape\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"vector3 S\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"vector2 dpdu\"") >= 0);
    cst_scene_destroy(s);
}

/* Analytic shapes take their own MediumInterface (pbrt_medium_apply), not the last one a
 * triangle shape set: a disk and a cylinder declared without one after a fog-filled glass
 * triangle are outside every medium. */
static void test_analytic_medium_interface(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok("WorldBegin\n"
                         "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
                         "AttributeBegin\n"
                         "MediumInterface \"fog\" \"\"\n"
                         "Material \"dielectric\"\n"
                         "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n"
                         "AttributeEnd\n"
                         "Shape \"disk\"\n"
                         "Shape \"cylinder\"\n"
                         "AttributeBegin\n"
                         "MediumInterface \"fog\" \"\"\n"
                         "Material \"dielectric\"\n"
                         "Shape \"cylinder\"\n"
                         "AttributeEnd\n", &w);
    assert_int_equal(s->num_triangles, 1);
    assert_int_equal(s->num_shapes, 3);
    assert_true(s->tri_info[0].medium > 0);
    assert_int_equal(s->shape_info[0].medium, 0); /* the disk */
    assert_int_equal(s->shape_info[1].medium, 0); /* the first cylinder */
    assert_int_equal(s->shape_info[2].medium, s->tri_info[0].medium); /* the fog-filled glass cylinder */
    cst_scene_destroy(s);
}

/* imagemap as an image texture; binary PLY through assimp. */
static void test_imagemap_and_binary_ply(void **state)
{
    (void)state;
    const float px[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    CstError err;
    assert_int_equal(image_write(CST_BINARY_DIR "/pbrt_tex.pfm", px, 2, 2, &err), CST_OK);
    FILE *f = fopen(CST_BINARY_DIR "/pbrt_bin.ply", "wb");
    assert_non_null(f);
    fputs("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n", f);
    const float v[9] = {0, 0, 0, 2, 0, 0, 0, 3, 0};
    fwrite(v, sizeof v, 1, f);
    const unsigned char n3 = 3;
    const int32_t idx[3] = {0, 1, 2};
    fwrite(&n3, 1, 1, f);
    fwrite(idx, sizeof idx, 1, f);
    fclose(f);
    const char *text = WORLD("Texture \"img\" \"spectrum\" \"imagemap\" \"string filename\" \"pbrt_tex.pfm\"\n"
                             "Material \"diffuse\" \"texture reflectance\" \"img\"\n"
                             "Shape \"plymesh\" \"string filename\" \"pbrt_bin.ply\"\n");
    CstScene *s = NULL;
    Warnings w = {0};
    if (load_at(text, CST_BINARY_DIR "/t.pbrt", &s, &err, &w) != CST_OK)
        fail_msg("%s", err.msg);
    Color a = s->materials[s->tri_info[0].material].albedo;
    assert_true(fabsf(a.c[0] - 0.5f) < 1e-6f && fabsf(a.c[1] - 0.5f) < 1e-6f && fabsf(a.c[2] - 0.5f) < 1e-6f);
    assert_int_equal(s->textures[s->materials[s->tri_info[0].material].albedo_texture - 1].type, TEXTURE_IMAGE);
    assert_int_equal(w.n, 0);
    assert_int_equal(s->num_triangles, 1);
    assert_vec(tri_vertex(s, 0, 2), 0, 3, 0, 0);
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ instances */

static void test_instances(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD("ObjectBegin \"pair\"\n Translate 0 0 1\n" TRI
                               " AreaLightSource \"diffuse\"\n Shape \"sphere\" \"float radius\" 0.25\nObjectEnd\n"
                               "AttributeBegin\n Translate 10 0 0\n ObjectInstance \"pair\"\nAttributeEnd\n"
                               "AttributeBegin\n Translate 20 0 0\n ObjectInstance \"pair\"\nAttributeEnd\n"),
                         &w);
    assert_int_equal(s->num_triangles, 0); /* the triangle is instanced, not copied */
    assert_non_null(s->instances);
    assert_int_equal(s->instances->num_protos, 1);
    assert_int_equal(s->instances->num_insts, 2);
    assert_int_equal(s->instances->protos[0].num_triangles, 1);
    assert_vec(s->instances->protos[0].positions[1], 1, 0, 1, 0); /* the definition's CTM */
    assert_vec(transform_point(&s->instances->insts[1].world_from_obj, v3(1, 0, 1)), 21, 0, 1, 0);
    assert_int_equal(s->num_spheres, 2); /* spheres are copied */
    assert_vec(s->spheres[0].center, 10, 0, 1, 0);
    assert_int_equal(s->num_emitters, 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "spheres in instanced objects") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "area lights inside ObjectBegin") >= 0);
    /* a ray down onto the second instance's triangle */
    SurfaceHit sh;
    Ray r = ray_make(v3(20.25f, 0.25f, 5.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    assert_true(scene_intersect(s, &r, &sh));
    assert_true(fabsf(sh.t - 4.0f) < 1e-5f);
    assert_vec(sh.p, 20.25f, 0.25f, 1.0f, 1e-5f);
    assert_vec(sh.ng, 0, 0, 1, 1e-6f);
    assert_true(scene_occluded(s, &r));
    r.d = v3(0.0f, 0.0f, 1.0f);
    assert_false(scene_intersect(s, &r, &sh));
    CstSceneInfo info;
    cst_scene_info(s, &info);
    assert_int_equal(info.instances, 2);
    assert_int_equal(info.instanced_objects, 1);
    assert_true(info.instanced_triangles == 1);
    cst_scene_destroy(s);
}

/* The same objects instanced and written out as copies: every camera ray finds the same
 * surface (t to 1e-4 relative, same material, same normal), with rotations, non-uniform
 * scales and a mirror among the instance transforms. */
static void test_instances_match_copies(void **state)
{
    (void)state;
#define OBJ_SHAPES "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] \"integer indices\" [0 1 2 0 2 3]\n" \
                   "  \"normal N\" [0.3 0 1  0 0.4 1  -0.2 0.1 1  0 0 1]\n" \
                   "Material \"diffuse\" \"rgb reflectance\" [.1 .2 .3]\n" \
                   "Shape \"trianglemesh\" \"point3 P\" [0 0 0  0 1 1  1 0 1] \"integer indices\" [0 1 2]\n"
    static const char *const xfs[] = {"Translate -2 0 0", "Translate 2 0 1\nRotate 30 0 1 0",
                                      "Translate 0 2 0\nScale 0.5 1 2", "Translate 0 -2 0\nScale -1 1 1",
                                      "Translate 0 0 3\nRotate 200 1 1 0"};
    char inst[4096], copy[4096];
    int ni = snprintf(inst, sizeof inst, "LookAt 0 0 -8  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 60\n"
                      "WorldBegin\nObjectBegin \"o\"\n" OBJ_SHAPES "ObjectEnd\n");
    int nc = snprintf(copy, sizeof copy, "LookAt 0 0 -8  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 60\nWorldBegin\n");
    for (int i = 0; i < 5; i++) {
        ni += snprintf(inst + ni, sizeof inst - (size_t)ni, "AttributeBegin\n%s\nObjectInstance \"o\"\nAttributeEnd\n", xfs[i]);
        nc += snprintf(copy + nc, sizeof copy - (size_t)nc, "AttributeBegin\n%s\n" OBJ_SHAPES "AttributeEnd\n", xfs[i]);
    }
#undef OBJ_SHAPES
    Scene *a = expect_ok(inst, NULL), *b = expect_ok(copy, NULL);
    assert_int_equal(a->num_triangles, 0);
    assert_int_equal(b->num_triangles, 15);
    int hits = 0, smooth_hits = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            Vec3 d = v3_normalize(v3(((float)x + 0.5f) / 32.0f - 1.0f, ((float)y + 0.5f) / 32.0f - 1.0f, 1.6f));
            Ray r = ray_make(v3(0.0f, 0.0f, -8.0f), d, 0.0f, INFINITY);
            SurfaceHit ha, hb;
            bool ia = scene_intersect(a, &r, &ha), ib = scene_intersect(b, &r, &hb);
            if (ia != ib) fail_msg("ray %d,%d: instanced %d, copies %d", x, y, ia, ib);
            if (!ia) continue;
            hits++;
            if (fabsf(ha.t - hb.t) > 1e-4f * hb.t) fail_msg("ray %d,%d: t %g vs %g", x, y, (double)ha.t, (double)hb.t);
            assert_true(a->materials[ha.material].albedo.c[0] == b->materials[hb.material].albedo.c[0]);
            if (v3_dot(ha.ng, hb.ng) < 0.9999f)
                fail_msg("ray %d,%d: normal (%g %g %g) vs (%g %g %g)", x, y, (double)ha.ng.x, (double)ha.ng.y,
                         (double)ha.ng.z, (double)hb.ng.x, (double)hb.ng.y, (double)hb.ng.z);
            /* Shading normals (the square's N) carried the same way, except under the
             * non-uniform scale (copy 2, triangles 6..8 of b): copies renormalise each
             * transformed vertex normal before interpolating, instances interpolate in
             * object space and then transform (as pbrt-v4 does both), which differ there. */
            if (hb.prim / 3 != 2 && v3_dot(ha.ns, hb.ns) < 0.9999f)
                fail_msg("ray %d,%d: shading normal (%g %g %g) vs (%g %g %g)", x, y, (double)ha.ns.x, (double)ha.ns.y,
                         (double)ha.ns.z, (double)hb.ns.x, (double)hb.ns.y, (double)hb.ns.z);
            if (a->materials[ha.material].albedo.c[0] != 0.1f) smooth_hits += v3_dot(ha.ns, ha.ng) < 0.999f;
            assert_true(scene_occluded(a, &r) && scene_occluded(b, &r));
        }
    assert_true(hits > 300 && smooth_hits > 100);
    cst_scene_destroy(a);
    cst_scene_destroy(b);
}

/* Issue #6: 10^4 instances of a 70k-triangle mesh cost about one copy of the mesh plus the
 * instance table, not 10^4 copies (7 * 10^8 triangles, tens of GB). */
static void test_instances_memory(void **state)
{
    (void)state;
    enum { N = 188, INSTANCES = 10000 }; /* (N-1)^2 * 2 = 69938 triangles */
    size_t cap = 8u << 20, n = 0;
    char *t = malloc(cap);
    assert_non_null(t);
    n += (size_t)snprintf(t + n, cap - n, "LookAt 50 50 -150  50 50 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\n"
                          "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n"
                          "Translate 50 50 -60 Shape \"sphere\" \"float radius\" 20\nAttributeEnd\n"
                          "ObjectBegin \"bumps\"\nShape \"trianglemesh\" \"point3 P\" [");
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++)
            n += (size_t)snprintf(t + n, cap - n, "%.4f %.4f %.4f ", i / (double)(N - 1), j / (double)(N - 1),
                                  0.05 * sin(i * 0.3) * cos(j * 0.2));
    n += (size_t)snprintf(t + n, cap - n, "] \"integer indices\" [");
    for (int j = 0; j + 1 < N; j++)
        for (int i = 0; i + 1 < N; i++) {
            int v = j * N + i;
            n += (size_t)snprintf(t + n, cap - n, "%d %d %d %d %d %d ", v, v + 1, v + N + 1, v, v + N + 1, v + N);
        }
    n += (size_t)snprintf(t + n, cap - n, "]\nObjectEnd\n");
    for (int k = 0; k < INSTANCES; k++)
        n += (size_t)snprintf(t + n, cap - n, "AttributeBegin Translate %d %d 0 Rotate %d 0 0 1 ObjectInstance \"bumps\" AttributeEnd\n",
                              (k % 100) * 1, (k / 100) * 1, (k * 37) % 360);
    assert_true(n < cap - 1);
    Scene *s = expect_ok(t, NULL);
    free(t);
    CstSceneInfo info;
    cst_scene_info(s, &info);
    assert_int_equal(info.instances, INSTANCES);
    assert_true(info.instanced_triangles == (size_t)2 * (N - 1) * (N - 1));
    const InstProto *p = &s->instances->protos[0];
    size_t one_copy = (size_t)p->num_positions * sizeof(Vec3) +
                      (size_t)p->num_triangles * (3 * sizeof(int32_t) + sizeof(int32_t) + sizeof(Vec3)) +
                      accel_memory_bytes(&p->accel);
    size_t table = info.instance_bytes - one_copy;
    print_message("10^4 instances of a %zu-triangle mesh: %zu bytes in all = one copy %zu "
                  "(geometry + BVH) + instance table and top-level tree %zu (%.0f bytes per "
                  "instance); as copies: about %.1f GB\n",
                  info.instanced_triangles, info.instance_bytes, one_copy, table,
                  (double)table / INSTANCES, (double)one_copy * INSTANCES / 1e9);
    assert_true(table < (size_t)INSTANCES * 400);
    assert_true(info.instance_bytes < one_copy + (size_t)INSTANCES * 400);
    /* and it renders: the mesh field is lit, not black */
    CstRenderSettings st;
    cst_render_settings_init(&st); /* the scene's max_depth (pbrt: 5) */
    st.width = st.height = 24;
    st.spp = 4;
    st.threads = 2;
    CstFilm *f = NULL;
    CstError err;
    if (cst_render(s, &st, &f, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    int lit = 0;
    for (int y = 0; y < 24; y++)
        for (int x = 0; x < 24; x++) {
            double c[3];
            cst_film_pixel(f, x, y, c);
            lit += c[0] + c[1] + c[2] > 0.0;
        }
    /* the field covers about half the image at this distance */
    if (!(lit > 24 * 24 / 4)) fail_msg("%d of %d pixels lit", lit, 24 * 24);
    cst_film_destroy(f);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shapes),
        cmocka_unit_test(test_quadric_emitters),
        cmocka_unit_test(test_sphere_uv),
        cmocka_unit_test(test_loopsubdiv),
        cmocka_unit_test(test_shape_alpha),
        cmocka_unit_test(test_plymesh),
        cmocka_unit_test(test_other_directives),
        cmocka_unit_test(test_imagemap_and_binary_ply),
        cmocka_unit_test(test_instances),
        cmocka_unit_test(test_instances_match_copies),
        cmocka_unit_test(test_instances_memory),
        cmocka_unit_test(test_analytic_medium_interface),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
