# The room of scripts/blender_room.py (cube 4 x 4 x 3 m, normals out, white 0.7 walls, red box,
# 100 W point light of radius 0, same camera, 256 x 192, Cycles settings for a fair reference),
# plus a textured wall: a separate plane 1 mm in front of the cube's +Y wall (Blender coords),
# facing into the room (-Y), whose Base Color is an Image Texture of stripes.png (64 x 64, 8
# vertical stripes alternating sRGB (230,230,230) and (60,60,200)); the plane's own UVs cover
# 0..1 exactly once (u along +X = left-to-right as the camera sees it, v up).
# Writes into OUTDIR: stripes.png, room.glb, room.obj + room.mtl, room-cycles.exr, plus
# wall-mask.png and room-cycles-preview.png (checks) and prints the figures for the report.
#   /tmp/bpy-venv/bin/python scripts/blender_textured.py -- OUTDIR [SAMPLES=512]
# Made scenes/blender-stripes/ (room.obj, room.mtl, stripes.png, room.glb; scene.toml by hand).
import bpy, math, os, struct, sys, time, zlib, json
import numpy as np
from mathutils import Vector

args = sys.argv[sys.argv.index("--") + 1:]
outdir = os.path.abspath(args[0])
samples = int(args[1]) if len(args) > 1 else 512
os.makedirs(outdir, exist_ok=True)
P = lambda name: os.path.join(outdir, name)


def write_png(path, rgb):  # rgb: uint8 array (h, w, 3), row 0 = top
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


# The texture: 64 x 64, 8 vertical stripes of 8 px; stripe 0 (u in [0, 1/8)) is A.
A, B = (230, 230, 230), (60, 60, 200)
tex = np.zeros((64, 64, 3), np.uint8)
for x in range(64):
    tex[:, x] = A if (x // 8) % 2 == 0 else B
write_png(P("stripes.png"), tex)
srgb2lin = lambda c: c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
print("stripe A linear", [round(srgb2lin(c / 255), 5) for c in A])
print("stripe B linear", [round(srgb2lin(c / 255), 5) for c in B])

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

# The textured wall: a 1 x 1 plane (normal +Z, UVs 0..1) scaled to 4 x 3 and turned +90 deg
# about X, so its normal is -Y (into the room), local +X stays +X (u), local +Y becomes +Z (v).
bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0, 2.0 - 0.001, 1.5), rotation=(math.radians(90), 0, 0))
wall = bpy.context.object
wall.name = "striped_wall"
wall.scale = (4, 3, 1)
mat = principled("stripes", (1, 1, 1))
img = bpy.data.images.load(P("stripes.png"))
img.colorspace_settings.name = "sRGB"
texnode = mat.node_tree.nodes.new("ShaderNodeTexImage")
texnode.image = img  # interpolation Linear, extension Repeat (the defaults)
mat.node_tree.links.new(texnode.outputs["Color"], mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
wall.data.materials.append(mat)
bpy.context.view_layer.update()
n = wall.matrix_world.to_3x3() @ wall.data.polygons[0].normal
print("wall normal (Blender)", tuple(round(c, 6) for c in n))
for loop in wall.data.loops:
    v = wall.matrix_world @ wall.data.vertices[loop.vertex_index].co
    print("  wall vertex (Blender)", tuple(round(c, 4) for c in v), "uv", tuple(wall.data.uv_layers.active.data[loop.index].uv))

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
bpy.context.view_layer.update()

# --- exports
bpy.ops.export_scene.gltf(filepath=P("room.glb"), export_format="GLB", export_cameras=True, export_lights=True)
bpy.ops.wm.obj_export(filepath=P("room.obj"), export_materials=True, path_mode="RELATIVE",
                      forward_axis="NEGATIVE_Z", up_axis="Y")

# --- camera and light in the OBJ's Y-up frame: OBJ (x, y, z) = Blender (x, z, -y)
toobj = lambda v: (v[0], v[2], -v[1])
W, H = scene.render.resolution_x, scene.render.resolution_y
R = cam.matrix_world.to_3x3()
fwd = R @ Vector((0, 0, -1))
up = R @ Vector((0, 1, 0))
# the look-at point: where the view axis meets the room's far vertical edge x = y = 2
t = (2.0 - cam.location.x) / fwd.x
look = cam.location + fwd * t
d = cam.data
print("camera lens %.3f mm, sensor %.1f x %.1f mm, fit %s" % (d.lens, d.sensor_width, d.sensor_height, d.sensor_fit))
vfov = 2 * math.degrees(math.atan(0.5 * d.sensor_width * H / W / d.lens))
hfov = 2 * math.degrees(math.atan(0.5 * d.sensor_width / d.lens))
print("camera pos (Blender)", tuple(round(c, 5) for c in cam.location), "forward", tuple(round(c, 5) for c in fwd), "up", tuple(round(c, 5) for c in up))
print("camera pos (OBJ)", tuple(round(c, 5) for c in toobj(cam.location)))
print("camera forward (OBJ)", tuple(round(c, 5) for c in toobj(fwd)), "up (OBJ)", tuple(round(c, 5) for c in toobj(up)))
print("camera look-at (OBJ)", tuple(round(c, 5) for c in toobj(look)), "at distance %.5f" % t)
print("vertical fov %.4f deg, horizontal %.4f deg" % (vfov, hfov))
print("light pos (Blender)", tuple(light.location), "(OBJ)", toobj(light.location),
      "power %.1f W, radius %.1f, intensity %.6f W/sr" % (light.data.energy, light.data.shadow_soft_size, light.data.energy / (4 * math.pi)))

# --- the striped wall's pixels: a ray per pixel centre (Blender's ray_cast on the evaluated scene)
dg = bpy.context.evaluated_depsgraph_get()
fr = [Vector(c) for c in d.view_frame(scene=scene)]  # top-right, bottom-right, bottom-left, top-left
right_x, left_x, top_y, bot_y, zc = fr[0].x, fr[2].x, fr[0].y, fr[2].y, fr[0].z
hit_wall = np.zeros((H, W), bool)   # row 0 = bottom (as Blender's image pixels)
stripe = np.full((H, W), -1, int)
for j in range(H):
    y = bot_y + (j + 0.5) / H * (top_y - bot_y)
    for i in range(W):
        x = left_x + (i + 0.5) / W * (right_x - left_x)
        dirw = (R @ Vector((x, y, zc))).normalized()
        ok, loc, nrm, idx, obj, _ = scene.ray_cast(dg, cam.location, dirw)
        if ok and obj.name == wall.name:
            hit_wall[j, i] = True
            stripe[j, i] = min(7, int((loc.x + 2.0) / 4.0 * 8))
# "pure" stripe pixels: the pixel and its 4 neighbours all on the wall in the same stripe
pure = hit_wall.copy()
for dj, di in ((1, 0), (-1, 0), (0, 1), (0, -1)):
    sh = np.roll(np.roll(stripe, dj, 0), di, 1)
    pure &= sh == stripe
pure[0, :] = pure[-1, :] = pure[:, 0] = pure[:, -1] = False
pureA = pure & (stripe % 2 == 0)
pureB = pure & (stripe % 2 == 1)
ys, xs = np.nonzero(hit_wall[::-1])
print("wall pixels %d of %d; bbox (row 0 = top) x %d..%d, y %d..%d; pure A %d, pure B %d"
      % (hit_wall.sum(), W * H, xs.min(), xs.max(), ys.min(), ys.max(), pureA.sum(), pureB.sum()))
m = np.zeros((H, W, 3), np.uint8)
m[hit_wall] = (128, 128, 128); m[pureA] = (255, 255, 255); m[pureB] = (60, 60, 255)
write_png(P("wall-mask.png"), m[::-1].copy())
np.save(P("wall-mask.npy"), np.stack([hit_wall, pureA, pureB])[:, ::-1])  # row 0 = top

# --- Cycles, as the notes say for a fair reference.
scene.render.engine = "CYCLES"
c = scene.cycles
c.device = "CPU"
c.samples = samples
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
scene.render.filepath = P("room-cycles.exr")
t0 = time.time()
bpy.ops.render.render(write_still=True)
print("cycles %d spp: %.1f s" % (samples, time.time() - t0))

# --- figures from the written EXR (read as compare_with_cycles.py does; row 0 = bottom)
im = bpy.data.images.load(P("room-cycles.exr"))
a = np.array(im.pixels[:], dtype=np.float64).reshape(im.size[1], im.size[0], 4)[:, :, :3]
fmt = lambda v: "(%.5f, %.5f, %.5f) mean %.5f" % (*v, v.mean())
print("EXR %dx%d" % tuple(im.size))
print("mean RGB whole image   ", fmt(a.reshape(-1, 3).mean(0)))
print("mean RGB striped wall  ", fmt(a[hit_wall].mean(0)))
print("mean RGB pure A stripes", fmt(a[pureA].mean(0)))
print("mean RGB pure B stripes", fmt(a[pureB].mean(0)))
print("mean RGB rest of image ", fmt(a[~hit_wall].mean(0)))
prev = np.clip((np.clip(a, 0, None) / max(a.mean() * 2.5, 1e-9)) ** (1 / 2.2), 0, 1)
write_png(P("room-cycles-preview.png"), (prev[::-1] * 255 + 0.5).astype(np.uint8))

# --- what the glb says about the camera and light
with open(P("room.glb"), "rb") as f:
    blob = f.read()
jl = struct.unpack("<I", blob[12:16])[0]
g = json.loads(blob[20:20 + jl])
print("glb bytes", len(blob), "images", [(i.get("name"), i.get("mimeType")) for i in g.get("images", [])])
print("glb cameras", g.get("cameras"))
print("glb lights", g.get("extensions", {}).get("KHR_lights_punctual"))
print("glb materials", json.dumps(g.get("materials")))
print("glb samplers", g.get("samplers"), "textures", g.get("textures"))
for nd in g["nodes"]:
    print("glb node", nd)
