# Jensen's Cornell box as a Blender user makes it: the shipped Cornell-like room (4 x 3 x 4 m,
# red and green side walls, white elsewhere, closed) with a small square light 1 cm under the
# ceiling towards the back, a chrome ball (Blender's UV sphere, 64 segments x 48 rings, metallic 1, roughness 0)
# and a glass ball (an ico sphere of 5 subdivisions: 5,120 triangles). Exported as OBJ with
# the PBR extensions, as Blender writes them; OBJ has no glass, so scene.toml makes the glass
# ball's material glass. Made scenes/cornell-spheres/spheres.obj and .mtl:
#   python3 -m venv /tmp/bpy-venv && /tmp/bpy-venv/bin/pip install bpy==5.0.1
#   /tmp/bpy-venv/bin/python scripts/blender_spheres.py -- scenes/cornell-spheres/spheres.obj
import bpy, bmesh, sys
out = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene

def B(x, y, z):
    # OBJ (x, y, z) as the exporter writes it (forward -Z, up Y) from Blender (x, -z, y).
    return (x, -z, y)

def principled(name, rgb, metallic=0.0, roughness=1.0, emission=0.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (*rgb, 1.0)
    b.inputs["Roughness"].default_value = roughness
    b.inputs["Metallic"].default_value = metallic
    b.inputs["Specular IOR Level"].default_value = 0.0
    if emission > 0.0:
        b.inputs["Emission Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        b.inputs["Emission Strength"].default_value = emission
    return m

def quads(name, faces, material):
    # Faces given in OBJ coordinates, counter-clockwise seen from the front.
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    for f in faces:
        bm.faces.new([bm.verts.new(B(*v)) for v in f])
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    obj.data.materials.append(material)
    return obj

white = principled("white", (0.72, 0.72, 0.72))
red = principled("red", (0.63, 0.065, 0.05))
green = principled("green", (0.14, 0.45, 0.091))
light = principled("light", (0.0, 0.0, 0.0), emission=40.0)
chrome = principled("chrome", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.0)
glass = principled("glass", (1.0, 1.0, 1.0), roughness=0.0)

# The room, normals inwards.
quads("floor", [[(0, 0, 0), (0, 0, 4), (4, 0, 4), (4, 0, 0)]], white)
quads("ceiling", [[(0, 3, 0), (4, 3, 0), (4, 3, 4), (0, 3, 4)]], white)
quads("back", [[(0, 0, 4), (0, 3, 4), (4, 3, 4), (4, 0, 4)]], white)
quads("front", [[(0, 0, 0), (4, 0, 0), (4, 3, 0), (0, 3, 0)]], white)
quads("left", [[(0, 0, 0), (0, 3, 0), (0, 3, 4), (0, 0, 4)]], red)
quads("right", [[(4, 0, 0), (4, 0, 4), (4, 3, 4), (4, 3, 0)]], green)
# A 0.5 m square light 1 cm under the ceiling, towards the back, facing down: it throws the
# glass ball's caustic forward, where the camera sees it.
quads("light", [[(1.75, 2.99, 2.75), (2.25, 2.99, 2.75), (2.25, 2.99, 3.25), (1.75, 2.99, 3.25)]], light)

bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=48, radius=0.75, location=B(1.0, 0.75, 2.9))
bpy.context.object.data.materials.append(chrome)
bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=5, radius=0.75, location=B(2.8, 0.75, 1.9))
bpy.context.object.data.materials.append(glass)

bpy.ops.wm.obj_export(filepath=out, export_materials=True, export_triangulated_mesh=True,
                      export_pbr_extensions=True, export_normals=False, export_uv=False,
                      export_selected_objects=False)
