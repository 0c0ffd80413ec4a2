# Writes the OBJs of the shipped daylight scene (plain Python, no dependencies):
#   scenes/office   a side-lit office, 5 m wide, 6 m deep, 3 m high, one window 3 x 1.5 m
#                   (sill 0.9 m) in its south wall (+z; the scene's north is -z): office.obj
#                   glazes it with a thin pane, office-open.obj leaves it an opening. Every face
#                   lies on one grid of corners, so the mesh is closed but for the window.
#   python3 scripts/make_daylight_scenes.py
import os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "office")
XS, YS, ZS = [0.0, 1.0, 4.0, 5.0], [0.0, 0.9, 2.4, 3.0], [0.0, 6.0]
HOLE = ((1.0, 4.0), (0.9, 2.4))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def write(name, pane):
    lines = ["# " + name + ": written by scripts/make_daylight_scenes.py", "mtllib office.mtl"]
    count = [0]

    def quad(pts, inward, material):
        n = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]))
        if sum(a * b for a, b in zip(n, inward)) < 0:
            pts = pts[::-1]
        lines.append("usemtl " + material)
        for p in pts:
            lines.append("v %g %g %g" % p)
        first = count[0] + 1
        count[0] += 4
        lines.append("f %d %d %d %d" % (first, first + 1, first + 2, first + 3))

    def plane(axis, value, inward, material, hole=None):
        # Cells of the grid on the plane `axis = value`.
        others = [a for a in range(3) if a != axis]
        grids = {0: XS, 1: YS, 2: ZS}
        us, vs = grids[others[0]], grids[others[1]]
        for i in range(len(us) - 1):
            for j in range(len(vs) - 1):
                if hole and (us[i], us[i + 1]) == hole[0] and (vs[j], vs[j + 1]) == hole[1]:
                    continue
                pts = []
                for (u, v) in [(us[i], vs[j]), (us[i + 1], vs[j]), (us[i + 1], vs[j + 1]), (us[i], vs[j + 1])]:
                    p = [0.0, 0.0, 0.0]
                    p[axis], p[others[0]], p[others[1]] = value, u, v
                    pts.append(tuple(p))
                quad(pts, inward, material)

    plane(1, 0.0, (0, 1, 0), "floor")
    plane(1, 3.0, (0, -1, 0), "ceiling")
    plane(0, 0.0, (1, 0, 0), "wall")
    plane(0, 5.0, (-1, 0, 0), "wall")
    plane(2, 0.0, (0, 0, 1), "wall")
    plane(2, 6.0, (0, 0, -1), "wall", HOLE)
    if pane:
        # The pane 5 cm outside the wall's face, facing out.
        (x0, x1), (y0, y1) = HOLE
        quad([(x0, y0, 6.05), (x1, y0, 6.05), (x1, y1, 6.05), (x0, y1, 6.05)], (0, 0, 1), "pane")
    with open(os.path.join(ROOT, name), "w") as f:
        f.write("\n".join(lines) + "\n")


os.makedirs(ROOT, exist_ok=True)
with open(os.path.join(ROOT, "office.mtl"), "w") as f:
    f.write("# The office's materials: matte floor, walls and ceiling; a clear pane.\n")
    for name, kd in [("floor", 0.3), ("wall", 0.6), ("ceiling", 0.8)]:
        f.write("newmtl %s\nKd %g %g %g\n\n" % (name, kd, kd, kd))
    f.write("newmtl pane\nKd 0 0 0\nKs 0 0 0\nNi 1.52\nTf 1 1 1\nillum 7\n")
write("office.obj", True)
write("office-open.obj", False)
