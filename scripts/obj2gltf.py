#!/usr/bin/env python3
"""Writes a scene's OBJ (with its MTL and its scene file's camera) as a glTF 2.0 file with the
buffer embedded, using nothing but Python's standard library: the fixtures that check
meshlight's glTF reader against its OBJ reader share no code with either.

    scripts/obj2gltf.py scenes/cornell/scene.toml scenes/cornell/cornell.gltf
    scripts/obj2gltf.py scenes/cornell/scene.toml OUT.gltf --moved   # under a transformed node
"""
import base64, json, math, struct, sys, tomllib
from pathlib import Path


def read_mtl(path):
    materials, name = {}, None
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "newmtl":
            name = parts[1]
            materials[name] = {"Kd": [0.0] * 3, "Ke": [0.0] * 3}
        elif parts[0] in ("Kd", "Ke"):
            materials[name][parts[0]] = [float(x) for x in parts[1:4]]
    return materials


def read_obj(path):
    positions, faces, material, libs = [], [], None, []
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            positions.append([float(x) for x in parts[1:4]])
        elif parts[0] == "usemtl":
            material = parts[1]
        elif parts[0] == "mtllib":
            libs.append(path.parent / parts[1])
        elif parts[0] == "f":
            idx = [int(p.split("/")[0]) for p in parts[1:]]
            idx = [i - 1 if i > 0 else len(positions) + i for i in idx]
            for k in range(1, len(idx) - 1):  # a fan, as OBJ readers do
                faces.append((material, [idx[0], idx[k], idx[k + 1]]))
    materials = {}
    for lib in libs:
        materials.update(read_mtl(lib))
    return positions, faces, materials


def look_rotation(position, look_at, up):
    """The quaternion (x, y, z, w) turning a glTF camera (looking down -Z, +Y up) to look from
    `position` at `look_at`."""
    sub = lambda a, b: [a[i] - b[i] for i in range(3)]
    cross = lambda a, b: [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    norm = lambda a: [x / math.sqrt(sum(y * y for y in a)) for x in a]
    f = norm(sub(look_at, position))
    r = norm(cross(f, up))
    u = cross(r, f)
    # Columns: local X → r, Y → u, Z → -f.
    m = [[r[0], u[0], -f[0]], [r[1], u[1], -f[1]], [r[2], u[2], -f[2]]]
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0:
        s = 0.5 / math.sqrt(trace + 1.0)
        return [(m[2][1] - m[1][2]) * s, (m[0][2] - m[2][0]) * s, (m[1][0] - m[0][1]) * s, 0.25 / s]
    i = max(range(3), key=lambda k: m[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + m[i][i] - m[j][j] - m[k][k])
    q = [0.0] * 4
    q[i] = 0.25 * s
    q[j] = (m[j][i] + m[i][j]) / s
    q[k] = (m[k][i] + m[i][k]) / s
    q[3] = (m[k][j] - m[j][k]) / s
    return q


def main():
    scene_path, out = Path(sys.argv[1]), Path(sys.argv[2])
    moved = "--moved" in sys.argv
    scene = tomllib.loads(scene_path.read_text())
    positions, faces, materials = read_obj(scene_path.parent / scene["obj"])
    names = sorted({m for m, _ in faces}, key=lambda m: list(materials).index(m))
    blob = bytearray(struct.pack(f"<{3 * len(positions)}f", *[c for p in positions for c in p]))
    accessors = [{
        "bufferView": 0, "componentType": 5126, "count": len(positions), "type": "VEC3",
        "min": [min(p[i] for p in positions) for i in range(3)],
        "max": [max(p[i] for p in positions) for i in range(3)],
    }]
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": len(blob)}]
    primitives = []
    for i, name in enumerate(names):
        idx = [v for m, f in faces if m == name for v in f]
        offset = len(blob)
        blob += struct.pack(f"<{len(idx)}I", *idx)
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": 4 * len(idx)})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125,
                          "count": len(idx), "type": "SCALAR"})
        primitives.append({"attributes": {"POSITION": 0}, "indices": len(accessors) - 1,
                           "material": i})
    gltf_materials = []
    for name in names:
        m = materials[name]
        entry = {"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": m["Kd"] + [1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}
        if any(m["Ke"]):
            peak = max(m["Ke"])
            entry["emissiveFactor"] = [c / peak for c in m["Ke"]]
            if peak != 1.0:
                entry["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": peak}}
        gltf_materials.append(entry)
    c = scene["camera"]
    camera_node = {"name": "camera", "camera": 0, "translation": c["position"],
                   "rotation": look_rotation(c["position"], c["look_at"], c.get("up", [0, 1, 0]))}
    nodes = [{"name": "room", "mesh": 0}, camera_node]
    roots = [0, 1]
    if moved:
        # Both under one node: moved, turned a quarter about y and doubled; the image must not change.
        s = math.sqrt(0.5)
        nodes.append({"name": "site", "children": [0, 1], "translation": [10.0, -3.0, 5.0],
                      "rotation": [0.0, s, 0.0, s], "scale": [2.0, 2.0, 2.0]})
        roots = [2]
    doc = {
        "asset": {"version": "2.0", "generator": "meshlight scripts/obj2gltf.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"name": "room", "primitives": primitives}],
        "materials": gltf_materials,
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": math.radians(c["fov_y"]), "aspectRatio": c["width"] / c["height"],
            "znear": 0.01}}],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    out.write_text(json.dumps(doc, indent=1) + "\n")


main()
