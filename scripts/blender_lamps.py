# The room of scripts/blender_room.py (cube 4 x 4 x 3 m, normals out, white 0.7 walls, red box,
# same camera, 256 x 192, same fair Cycles settings) WITHOUT the point light, lit instead by
#  (a) a 0.6 x 0.6 m emissive plane hanging vertically at (-0.8, 0.5, 1.6), normal along +X
#      (Blender mesh emission is two-sided: it lights both halves of the room); Principled BSDF
#      base colour black, Specular IOR Level 0, Emission Color white, Emission Strength 10;
#  (b) a 200 W spot light, spot_size 60 deg, spot_blend 0.3, radius 0, at (1.2, -1.0, 2.8),
#      rotation (0, 0, 0) = pointing straight down (-Z).
# Writes into OUTDIR: room.glb + room-cycles.exr (both lamps, SAMPLES spp),
# spot-only.glb + spot-only.exr (panel hidden from render, SAMPLES2 spp),
# panel-only.glb + panel-only.exr (spot hidden from render, SAMPLES2 spp), *-preview.png,
# and prints the glTF JSON (lights, emissive material, nodes), render times and EXR means.
#   /tmp/bpy-venv/bin/python blender_lamps.py -- OUTDIR [SAMPLES=512] [SAMPLES2=256]
import bpy, math, os, struct, sys, time, zlib, json
import numpy as np

args = sys.argv[sys.argv.index("--") + 1:]
outdir = os.path.abspath(args[0])
samples = int(args[1]) if len(args) > 1 else 512
samples2 = int(args[2]) if len(args) > 2 else 256
os.makedirs(outdir, exist_ok=True)
P = lambda name: os.path.join(outdir, name)


def write_png(path, rgb):  # rgb: uint8 array (h, w, 3), row 0 = top
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


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

# (a) the panel: a 0.6 x 0.6 plane (normal +Z) turned +90 deg about Y, so its normal is +X.
bpy.ops.mesh.primitive_plane_add(size=0.6, location=(-0.8, 0.5, 1.6), rotation=(0, math.radians(90), 0))
panel = bpy.context.object
panel.name = "panel"
pm = principled("emitter", (0.0, 0.0, 0.0))
pb = pm.node_tree.nodes["Principled BSDF"]
pb.inputs["Emission Color"].default_value = (1.0, 1.0, 1.0, 1.0)
pb.inputs["Emission Strength"].default_value = 10.0
panel.data.materials.append(pm)

# (b) the spot light.
bpy.ops.object.light_add(type="SPOT", location=(1.2, -1.0, 2.8), rotation=(0, 0, 0))
spot = bpy.context.object
spot.name = "spot"
spot.data.energy = 200.0
spot.data.spot_size = math.radians(60)
spot.data.spot_blend = 0.3
spot.data.shadow_soft_size = 0.0

bpy.ops.object.camera_add(location=(-1.8, -1.8, 1.6))
cam = bpy.context.object
cam.rotation_euler = (math.radians(80), 0, math.radians(-45))
scene.camera = cam
scene.render.resolution_x = 256
scene.render.resolution_y = 192
scene.world = bpy.data.worlds.new("black")
scene.world.color = (0, 0, 0)
bpy.context.view_layer.update()

n = panel.matrix_world.to_3x3() @ panel.data.polygons[0].normal
print("panel normal (Blender)", tuple(round(c, 6) for c in n), "area %.4f m^2" % panel.data.polygons[0].area)
for v in panel.data.vertices:
    print("  panel vertex (Blender)", tuple(round(c, 4) for c in panel.matrix_world @ v.co))
d = (spot.matrix_world.to_3x3() @ __import__("mathutils").Vector((0, 0, -1))).normalized()
print("spot direction (Blender)", tuple(round(c, 6) for c in d))

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


def glb_json(path):
    with open(path, "rb") as f:
        blob = f.read()
    jl = struct.unpack("<I", blob[12:16])[0]
    return len(blob), json.loads(blob[20:20 + jl])


def run(tag, glb, exr, spp, panel_on, spot_on):
    panel.hide_render = not panel_on
    spot.hide_render = not spot_on
    bpy.context.view_layer.update()
    # use_renderable: objects hidden from render are left out of the glb too.
    bpy.ops.export_scene.gltf(filepath=P(glb), export_format="GLB", export_cameras=True,
                              export_lights=True, use_renderable=True)
    size, g = glb_json(P(glb))
    print("=== %s: %s (%d bytes)" % (tag, glb, size))
    print("glb extensionsUsed", g.get("extensionsUsed"))
    print("glb lights", json.dumps(g.get("extensions", {}).get("KHR_lights_punctual")))
    print("glb materials", json.dumps(g.get("materials")))
    print("glb cameras", json.dumps(g.get("cameras")))
    for nd in g["nodes"]:
        print("glb node", json.dumps(nd))
    c.samples = spp
    scene.render.filepath = P(exr)
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    dt = time.time() - t0
    print("cycles %s %d spp: %.1f s" % (tag, spp, dt))
    im = bpy.data.images.load(P(exr))
    a = np.array(im.pixels[:], dtype=np.float64).reshape(im.size[1], im.size[0], 4)[:, :, :3]
    m = a.reshape(-1, 3).mean(0)
    print("EXR %s %dx%d mean RGB (%.5f, %.5f, %.5f) mean %.5f, max %.4f"
          % (exr, im.size[0], im.size[1], *m, m.mean(), a.max()))
    prev = np.clip((np.clip(a, 0, None) / max(a.mean() * 2.5, 1e-9)) ** (1 / 2.2), 0, 1)
    write_png(P(exr.replace(".exr", "-preview.png")), (prev[::-1] * 255 + 0.5).astype(np.uint8))
    bpy.data.images.remove(im)
    return a, dt


full, t_full = run("both", "room.glb", "room-cycles.exr", samples, True, True)
spot_a, t_spot = run("spot-only", "spot-only.glb", "spot-only.exr", samples2, False, True)
panel_a, t_panel = run("panel-only", "panel-only.glb", "panel-only.exr", samples2, True, False)
s = (spot_a + panel_a).reshape(-1, 3).mean(0)
print("spot-only + panel-only mean RGB (%.5f, %.5f, %.5f) mean %.5f (vs both %.5f)"
      % (*s, s.mean(), full.mean()))
# pixels seeing the panel itself (radiance should be ~10 = the Emission Strength)
hot = full.min(axis=2) > 5
print("pixels with all channels > 5 (the panel seen directly): %d, their mean %.4f" % (hot.sum(), full[hot].mean() if hot.any() else 0))
print("times: both %d spp %.1f s, spot-only %d spp %.1f s, panel-only %d spp %.1f s"
      % (samples, t_full, samples2, t_spot, samples2, t_panel))
