# Writes the OBJ/MTL of three shipped specular scenes (plain Python, no dependencies):
#   scenes/mirror-cab   a room whose four walls and ceiling are mirrors (Ks 0.9), a white floor,
#                       a red box, a 1 m^2 light 1 cm under the ceiling (an elevator cab);
#                       one-mirror.toml keeps only the back wall a mirror
#   scenes/veach        Veach's multiple-importance test: four glossy plates (GGX alpha 0.005,
#                       0.02, 0.05, 0.1) under four sphere lights of radii 0.03 to 0.9 m
#                       (ico spheres of 320 triangles) of equal power, in a closed grey room;
#                       diffuse-plates.toml makes the plates matte
#   scenes/glass-block  the Cornell-like room with its short box a block of glass (index 1.5)
#   python3 scripts/make_specular_scenes.py
import math, os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes")


class Obj:
    def __init__(self, comment):
        self.lines = [f"# {comment}"]
        self.v = 0
        self.material = None

    def use(self, m):
        if m != self.material:
            self.lines.append(f"usemtl {m}")
            self.material = m

    def face(self, pts, m):
        # Counter-clockwise seen from the front.
        self.use(m)
        first = self.v + 1
        for p in pts:
            self.lines.append("v %.6g %.6g %.6g" % p)
        self.v += len(pts)
        self.lines.append("f " + " ".join(str(first + i) for i in range(len(pts))))

    def room(self, lo, hi, mats):
        # Faces pointing inwards; mats: floor, ceiling, back (+z), front (-z), left (-x), right (+x).
        (a, b) = (lo, hi)
        self.face([(a[0], a[1], a[2]), (a[0], a[1], b[2]), (b[0], a[1], b[2]), (b[0], a[1], a[2])], mats[0])
        self.face([(a[0], b[1], a[2]), (b[0], b[1], a[2]), (b[0], b[1], b[2]), (a[0], b[1], b[2])], mats[1])
        self.face([(a[0], a[1], b[2]), (a[0], b[1], b[2]), (b[0], b[1], b[2]), (b[0], a[1], b[2])], mats[2])
        self.face([(a[0], a[1], a[2]), (b[0], a[1], a[2]), (b[0], b[1], a[2]), (a[0], b[1], a[2])], mats[3])
        self.face([(a[0], a[1], a[2]), (a[0], b[1], a[2]), (a[0], b[1], b[2]), (a[0], a[1], b[2])], mats[4])
        self.face([(b[0], a[1], a[2]), (b[0], a[1], b[2]), (b[0], b[1], b[2]), (b[0], b[1], a[2])], mats[5])

    def solid(self, lo, hi, m, bottom=False):
        # An axis-aligned box, faces pointing out; a bottom face only when asked (a box standing
        # on the floor needs none).
        (a, b) = (lo, hi)
        self.face([(a[0], b[1], a[2]), (a[0], b[1], b[2]), (b[0], b[1], b[2]), (b[0], b[1], a[2])], m)
        if bottom:
            self.face([(a[0], a[1], a[2]), (b[0], a[1], a[2]), (b[0], a[1], b[2]), (a[0], a[1], b[2])], m)
        self.face([(a[0], a[1], b[2]), (b[0], a[1], b[2]), (b[0], b[1], b[2]), (a[0], b[1], b[2])], m)
        self.face([(a[0], a[1], a[2]), (a[0], b[1], a[2]), (b[0], b[1], a[2]), (b[0], a[1], a[2])], m)
        self.face([(a[0], a[1], a[2]), (a[0], a[1], b[2]), (a[0], b[1], b[2]), (a[0], b[1], a[2])], m)
        self.face([(b[0], a[1], a[2]), (b[0], b[1], a[2]), (b[0], b[1], b[2]), (b[0], a[1], b[2])], m)

    def write(self, path, mtl):
        with open(path, "w") as f:
            f.write(self.lines[0] + "\n" + f"mtllib {mtl}\n" + "\n".join(self.lines[1:]) + "\n")


def icosphere(level):
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
             (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        cache, out = {}, []

        def mid(i, j):
            key = (min(i, j), max(i, j))
            if key not in cache:
                m = [(a + b) / 2 for a, b in zip(verts[i], verts[j])]
                n = math.sqrt(sum(x * x for x in m))
                verts.append(tuple(x / n for x in m))
                cache[key] = len(verts) - 1
            return cache[key]

        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            out += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = out
    return verts, faces


def mirror_cab():
    o = Obj("An elevator cab: four mirror walls and a mirror ceiling (Ks 0.9), a white floor, a red box, a 1 m^2 light (scripts/make_specular_scenes.py).")
    o.room((0, 0, 0), (3, 2.6, 3), ["floor", "mirror", "back", "mirror", "mirror", "mirror"])
    o.face([(1.0, 2.59, 1.0), (2.0, 2.59, 1.0), (2.0, 2.59, 2.0), (1.0, 2.59, 2.0)], "light")
    o.solid((1.7, 0, 1.6), (2.4, 0.7, 2.3), "box")
    d = os.path.join(ROOT, "mirror-cab")
    o.write(os.path.join(d, "cab.obj"), "cab.mtl")
    with open(os.path.join(d, "cab.mtl"), "w") as f:
        f.write("""newmtl floor
Kd 0.72 0.72 0.72
newmtl box
Kd 0.63 0.065 0.05
newmtl light
Kd 0 0 0
Ke 10 10 10

# The back wall, and the other walls and the ceiling: silvered mirrors.
newmtl back
illum 3
Kd 0 0 0
Ks 0.9 0.9 0.9
newmtl mirror
illum 3
Kd 0 0 0
Ks 0.9 0.9 0.9
""")


def veach():
    o = Obj("Veach's multiple-importance test: four glossy plates under four sphere lights of equal power (scripts/make_specular_scenes.py).")
    o.room((-6, 0, -6), (6, 8, 8), ["grey"] * 6)
    camera = (0.0, 2.0, 7.5)
    lights = [(-3.75, 0.03), (-1.25, 0.1), (1.25, 0.3), (3.75, 0.9)]
    light_y, light_z = 6.0, -4.0
    for k, (x, r) in enumerate(lights):
        verts, faces = icosphere(2)
        for a, b, c in faces:
            p = [tuple(x0 + r * v for x0, v in zip((x, light_y, light_z), verts[i])) for i in (a, b, c)]
            o.face(p, f"light{k}")
    # Plates from near and low to far and high, each turned to show the lights to the camera.
    plates = [(1.0, 0.3), (0.0, 0.9), (-1.0, 1.6), (-2.0, 2.4)]
    for k, (z, y) in enumerate(plates):
        p = (0.0, y, z)
        to_cam = [c - q for c, q in zip(camera, p)]
        to_light = [l - q for l, q in zip((0.0, light_y, light_z), p)]
        n = lambda v: [x / math.sqrt(sum(y * y for y in v)) for x in v]
        h = n([a + b for a, b in zip(n(to_cam), n(to_light))])
        # The plate's depth direction: in the y-z plane, perpendicular to h.
        u = n([0.0, -h[2], h[1]])
        w, d = 4.5, 0.35
        corners = [(-w, -d), (w, -d), (w, d), (-w, d)]
        pts = [(sx, p[1] + sd * u[1], p[2] + sd * u[2]) for sx, sd in corners]
        # Counter-clockwise seen from h's side.
        e1 = [b - a for a, b in zip(pts[0], pts[1])]
        e2 = [b - a for a, b in zip(pts[0], pts[2])]
        cr = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        if sum(a * b for a, b in zip(cr, h)) < 0:
            pts.reverse()
        o.face(pts, f"plate{k}")
    d = os.path.join(ROOT, "veach")
    o.write(os.path.join(d, "veach.obj"), "veach.mtl")
    mtl = ["newmtl grey", "Kd 0.4 0.4 0.4"]
    for k, (_, r) in enumerate(lights):
        ke = 0.5 * (0.9 / r) ** 2
        mtl += [f"newmtl light{k}", "Kd 0 0 0", "Ke %.6g %.6g %.6g" % (ke, ke, ke)]
    mtl.append("")
    mtl.append("# GGX plates: alpha = Pr^2 = 0.005, 0.02, 0.05, 0.1.")
    for k, alpha in enumerate([0.005, 0.02, 0.05, 0.1]):
        mtl += [f"newmtl plate{k}", "illum 3", "Kd 0.05 0.05 0.05", "Ks 0.8 0.8 0.8", "Pr %.6g" % math.sqrt(alpha)]
    with open(os.path.join(d, "veach.mtl"), "w") as f:
        f.write("\n".join(mtl) + "\n")


def glass_block():
    o = Obj("The Cornell-like room with its short box a block of glass (scripts/make_specular_scenes.py).")
    o.room((0, 0, 0), (4, 3, 4), ["white", "white", "white", "white", "red", "green"])
    o.face([(1.5, 2.99, 1.5), (2.5, 2.99, 1.5), (2.5, 2.99, 2.5), (1.5, 2.99, 2.5)], "light")
    o.solid((0.8, 0, 2.2), (1.8, 1.8, 3.2), "white")
    # A closed solid, 5 mm above the floor: a face on the floor's plane would make hits there
    # a toss-up between the two.
    o.solid((2.3, 0.005, 0.9), (3.2, 0.905, 1.8), "glass", bottom=True)
    d = os.path.join(ROOT, "glass-block")
    o.write(os.path.join(d, "room.obj"), "room.mtl")
    with open(os.path.join(d, "room.mtl"), "w") as f:
        f.write("""newmtl white
Kd 0.72 0.72 0.72
newmtl red
Kd 0.63 0.065 0.05
newmtl green
Kd 0.14 0.45 0.091
newmtl light
Kd 0 0 0
Ke 10 10 10

# The short box: a solid block of glass, faces pointing out, its bottom 5 mm above the floor.
newmtl glass
illum 7
Ni 1.5
""")


mirror_cab()
veach()
glass_block()
