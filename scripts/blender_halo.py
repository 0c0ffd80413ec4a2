# A Blender user's panel light under a ceiling, for the halo a two-sided mesh light left round
# it (issue: "a halo around a panel light just under a ceiling"). The cube room of
# scripts/blender_lamps.py (4 x 4 x 3 m, normals out, white 0.7), no box, lit only by Blender's
# default mesh light: a 0.6 x 0.6 m plane added as it comes (normal +Z, facing the ceiling),
# 1 cm under the ceiling, Principled base colour black, emission white, strength 10 (Blender's
# mesh lights emit from both faces). A camera in a corner looking up at it, 128 x 96.
# Writes OUTDIR/halo.glb (tests/data/blender-halo.glb) and OUTDIR/cycles.exr
# (tests/data/blender-halo-cycles.exr: Cycles with the notes' fair settings, SAMPLES spp).
#   /tmp/bpy-venv/bin/python blender_halo.py -- OUTDIR [SAMPLES=1024]
import bpy, math, os, sys, time

args = sys.argv[sys.argv.index("--") + 1:]
outdir = os.path.abspath(args[0])
samples = int(args[1]) if len(args) > 1 else 1024
os.makedirs(outdir, exist_ok=True)
P = lambda name: os.path.join(outdir, name)


bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene


def principled(name, rgb):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (*rgb, 1.0)
    b.inputs["Roughness"].default_value = 1.0
    b.inputs["Metallic"].default_value = 0.0
    b.inputs["Specular IOR Level"].default_value = 0.0
    return m



bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 1.5))
room = bpy.context.object
room.scale = (4, 4, 3)
room.data.materials.append(principled("white", (0.7, 0.7, 0.7)))
# Blender's default mesh light: a plane (normal +Z: facing the ceiling), 1 cm under it.
bpy.ops.mesh.primitive_plane_add(size=0.6, location=(0.0, 0.0, 2.99))
panel = bpy.context.object
pm = principled("emitter", (0.0, 0.0, 0.0))
pb = pm.node_tree.nodes["Principled BSDF"]
pb.inputs["Emission Color"].default_value = (1.0, 1.0, 1.0, 1.0)
pb.inputs["Emission Strength"].default_value = 10.0
panel.data.materials.append(pm)
bpy.ops.object.camera_add(location=(-1.6, -1.6, 1.4))
cam = bpy.context.object
cam.rotation_euler = (math.radians(110), 0, math.radians(-45))
scene.camera = cam
scene.render.resolution_x = 128
scene.render.resolution_y = 96
scene.world = bpy.data.worlds.new("black")
scene.world.color = (0, 0, 0)
bpy.context.view_layer.update()
# --- Cycles, as the notes say for a fair reference.
scene.render.engine = "CYCLES"
c = scene.cycles
c.device = "CPU"
c.use_adaptive_sampling = False
c.use_denoising = False
c.max_bounces = 128
c.diffuse_bounces = 128
c.glossy_bounces = 0
c.transmission_bounces = 0
c.transparent_max_bounces = 0
c.caustics_reflective = False
c.caustics_refractive = False
c.sample_clamp_direct = 0
c.sample_clamp_indirect = 0
c.light_sampling_threshold = 0
c.pixel_filter_type = "BOX"
c.filter_width = 1.0
scene.view_settings.view_transform = "Standard"
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.image_settings.color_mode = "RGB"  # no alpha: a smaller file



bpy.ops.export_scene.gltf(filepath=P("halo.glb"), export_format="GLB", export_cameras=True, export_lights=True)
c.samples = samples
scene.render.filepath = P("cycles.exr")
t0 = time.time()
bpy.ops.render.render(write_still=True)
print("cycles %d spp: %.1f s" % (samples, time.time() - t0))
