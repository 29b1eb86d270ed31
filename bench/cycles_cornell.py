# Blender (Cycles) script: builds a caustic JSON scene made of quads with diffuse
# materials and one-sided quad emitters (scenes/cornell-box.json) and renders it with the
# settings caustic uses, for the time-to-quality benchmark of issue 29 (bench/cycles.sh).
#   blender -b --factory-startup -P bench/cycles_cornell.py -- SCENE.json OUT.exr SIZE SPP SEED THREADS
# Matched to caustic: box pixel filter of width 1, no denoising, no adaptive sampling, no
# clamping, no light threshold, no glossy filter, bounces effectively unbounded (Russian
# roulette only), emitters one-sided (black from behind), linear float EXR output with the
# "Standard" view transform. caustic's y-up frame maps to Blender's z-up one by the rotation
# (x, y, z) -> (x, -z, y), so the image is not mirrored.
import json
import math
import sys

import bpy
from mathutils import Vector

argv = sys.argv[sys.argv.index("--") + 1:]
scene_path, out_path = argv[0], argv[1]
size, spp, seed, threads = (int(a) for a in argv[2:6])
with open(scene_path) as f:
    desc = json.load(f)


def to_blender(p):
    return Vector((p[0], -p[2], p[1]))


bpy.ops.wm.read_factory_settings(use_empty=True)
sc = bpy.context.scene
sc.render.engine = "CYCLES"
cy = sc.cycles
cy.device = "CPU"
cy.samples = spp
cy.seed = seed
cy.use_adaptive_sampling = False
cy.use_denoising = False
cy.pixel_filter_type = "BOX"
cy.filter_width = 1.0
cy.sample_clamp_direct = 0.0
cy.sample_clamp_indirect = 0.0
cy.light_sampling_threshold = 0.0
cy.blur_glossy = 0.0
cy.caustics_reflective = True
cy.caustics_refractive = True
cy.max_bounces = 1024
cy.diffuse_bounces = 1024
cy.glossy_bounces = 1024
cy.transmission_bounces = 1024
cy.transparent_max_bounces = 1024
cy.volume_bounces = 0
cy.min_light_bounces = 0
cy.min_transparent_bounces = 0
cy.use_animated_seed = False
sc.render.threads_mode = "FIXED"
sc.render.threads = threads
sc.render.resolution_x = sc.render.resolution_y = size
sc.render.resolution_percentage = 100
sc.render.film_transparent = False
sc.view_settings.view_transform = "Standard"
sc.view_settings.look = "None"
sc.view_settings.exposure = 0.0
sc.view_settings.gamma = 1.0
sc.render.image_settings.file_format = "OPEN_EXR"
sc.render.image_settings.color_depth = "32"
sc.render.image_settings.exr_codec = "ZIP"
world = bpy.data.worlds.new("black")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
sc.world = world


def diffuse_material(name, albedo):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (*albedo, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0  # Lambertian
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return m


def emitter_material(name, radiance):
    # Radiance L from the front face only: emission (strength 1, colour L) mixed with
    # black by Geometry.Backfacing.
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*radiance, 1.0)
    em.inputs["Strength"].default_value = 1.0
    black = nt.nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
    nt.links.new(em.outputs["Emission"], mix.inputs[1])
    nt.links.new(black.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return m


materials = {name: diffuse_material(name, m["albedo"]) for name, m in desc["materials"].items()}
for i, shape in enumerate(desc["shapes"]):
    if shape["type"] != "quad":
        sys.exit("cycles_cornell.py: only quads are supported, got %s" % shape["type"])
    verts = [to_blender(v) for v in shape["vertices"]]
    mesh = bpy.data.meshes.new("quad%d" % i)
    mesh.from_pydata(verts, [], [(0, 1, 2, 3)])
    obj = bpy.data.objects.new("quad%d" % i, mesh)
    em = shape.get("emission")
    if em:
        if em.get("two_sided", False):
            sys.exit("cycles_cornell.py: two-sided emitters are not supported")
        mesh.materials.append(emitter_material("emit%d" % i, em["radiance"]))
    else:
        mesh.materials.append(materials[shape["material"]])
    sc.collection.objects.link(obj)

cam_desc = desc["camera"]
cam = bpy.data.cameras.new("camera")
cam.type = "PERSP"
cam.sensor_fit = "VERTICAL"
cam.angle = math.radians(cam_desc["fov"])
cam.clip_start = 0.1
cam.clip_end = 1e5
cam_obj = bpy.data.objects.new("camera", cam)
pos, target = to_blender(cam_desc["position"]), to_blender(cam_desc["look_at"])
cam_obj.location = pos
cam_obj.rotation_euler = (target - pos).to_track_quat("-Z", "Y").to_euler()
sc.collection.objects.link(cam_obj)
sc.camera = cam_obj

sc.render.filepath = out_path
bpy.ops.render.render(write_still=True)
