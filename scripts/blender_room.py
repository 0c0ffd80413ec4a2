# A room as a Blender user makes one: a cube scaled to 4 x 4 x 3 m (normals out, as Blender
# adds it), white walls, a red box, a 100 W point light (radius 0), a camera inside. Exported
# as .glb with cameras and lights; rendered with Cycles as the reference (the settings of
# ../shared/notes: no clamping, box filter, no denoiser, 256 spp). Made tests/data/blender-room.glb:
#   python3 -m venv /tmp/bpy-venv && /tmp/bpy-venv/bin/pip install bpy==5.0.1
#   /tmp/bpy-venv/bin/python scripts/blender_room.py -- /tmp/room   # room.glb, room-cycles.exr
import bpy, math, sys
out = sys.argv[sys.argv.index("--") + 1]
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
bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.8, 0.6, 0.4))
box = bpy.context.object
box.scale = (0.8, 0.8, 0.8)
box.data.materials.append(principled("red", (0.6, 0.1, 0.08)))
bpy.ops.object.light_add(type="POINT", location=(-0.5, -0.3, 2.4))
light = bpy.context.object
light.data.energy = 100.0
light.data.shadow_soft_size = 0.0
bpy.ops.object.camera_add(location=(-1.8, -1.8, 1.6))
cam = bpy.context.object
cam.rotation_euler = (math.radians(80), 0, math.radians(-45))
scene.camera = cam
scene.render.resolution_x = 256
scene.render.resolution_y = 192
scene.world = bpy.data.worlds.new("black")
scene.world.color = (0, 0, 0)
bpy.ops.export_scene.gltf(filepath=out + ".glb", export_cameras=True, export_lights=True)
# Cycles, as the notes say for a fair reference.
scene.render.engine = "CYCLES"
c = scene.cycles
c.device = "CPU"
c.samples = 256
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
scene.render.filepath = out + "-cycles.exr"
bpy.ops.render.render(write_still=True)
