//! Writes meshlight's gallery scene as OBJ: a grid of rooms (2 × 2 by default: four 12 m × 7.9 m
//! rooms) under one 4.5 m ceiling, joined by doorways in solid partition walls 0.2 m thick, with
//! pedestals carrying faceted sculptures, framed paintings on the outer walls, benches, and two
//! point lights per room under the ceiling (in `scene.toml`). Floors and outer walls are tiled
//! (`tile`, default 0.1 m), as architectural exports often are, which gives ≥ 100k triangles per
//! four rooms, mixing huge ceiling triangles with small ones. The OBJ is generated rather than
//! committed (several MB). Larger grids (`rooms`) go to a folder of their own, with a
//! `scene.toml` written for them.
//!
//! Every solid (partition walls, pedestals, frames, benches, sculptures) faces outwards; the
//! rooms' floor, ceiling and outer walls face inwards. No faces hide inside solids: tiles under
//! partition walls and wall faces behind junctions are left out.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// Settings of the generated geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GalleryOptions {
    /// Side of the floor and outer-wall tiles, metres (a multiple of 0.1 divides 0.1 evenly:
    /// use 0.1, 0.05, ... or 0.2 for a lighter mesh).
    pub tile: f64,
    /// Subdivision level of the icosphere sculptures (0 = icosahedron).
    pub sphere_detail: u32,
    /// Rooms along x and along z (each 12 m × 8 m between partition centres).
    pub rooms: [usize; 2],
    /// A glazed skylight 4 m × 2 m in the middle of each room's ceiling (`gallery-skylit.obj`,
    /// lit by `daylight.toml`).
    pub skylights: bool,
}

impl Default for GalleryOptions {
    fn default() -> Self {
        GalleryOptions {
            tile: 0.1,
            sphere_detail: 2,
            rooms: [2, 2],
            skylights: false,
        }
    }
}

/// A room's size between partition centres, metres.
const ROOM_X: f64 = 12.0;
const ROOM_Z: f64 = 8.0;
const HEIGHT: f64 = 4.5;
/// Partition walls: along x at z = 8, 16, ..., along z at x = 12, 24, ...
const WALL: f64 = 0.2;
const DOOR_WIDTH: f64 = 1.6;
const DOOR_HEIGHT: f64 = 2.6;
/// A skylight's opening, along x and z, metres.
const SKYLIGHT: [f64; 2] = [4.0, 2.0];

/// The grid of rooms.
#[derive(Clone, Copy, Debug)]
struct Layout {
    nx: usize,
    nz: usize,
}

impl Layout {
    fn width(&self) -> f64 {
        ROOM_X * self.nx as f64
    }

    fn depth(&self) -> f64 {
        ROOM_Z * self.nz as f64
    }

    /// Room (i, j)'s floor between partition faces: (x0, x1, z0, z1).
    fn room(&self, i: usize, j: usize) -> (f64, f64, f64, f64) {
        let half = WALL / 2.0;
        let x0 = ROOM_X * i as f64 + if i > 0 { half } else { 0.0 };
        let x1 = ROOM_X * (i + 1) as f64 - if i + 1 < self.nx { half } else { 0.0 };
        let z0 = ROOM_Z * j as f64 + if j > 0 { half } else { 0.0 };
        let z1 = ROOM_Z * (j + 1) as f64 - if j + 1 < self.nz { half } else { 0.0 };
        (x0, x1, z0, z1)
    }

    /// The doorway (x range) of the wall along x at z = 8j, in room column i.
    fn door_x(&self, i: usize, j: usize) -> (f64, f64) {
        let a = ROOM_X * i as f64 + 5.0 + if (i + j + 1) % 2 == 1 { 0.4 } else { 0.0 };
        (a, a + DOOR_WIDTH)
    }

    /// The doorway (z range) of the wall along z at x = 12i, in room row j.
    fn door_z(&self, j: usize) -> (f64, f64) {
        let a = ROOM_Z * j as f64 + 3.2;
        (a, a + DOOR_WIDTH)
    }

    /// Whether a point lies within a partition wall's footprint (doorways included).
    fn in_partition(&self, x: f64, z: f64) -> bool {
        let near =
            |v: f64, step: f64, n: usize| (1..n).any(|k| (v - step * k as f64).abs() < WALL / 2.0);
        near(x, ROOM_X, self.nx) || near(z, ROOM_Z, self.nz)
    }

    /// Whether floor point (x, z) lies under a partition wall (outside the doorways).
    fn under_wall(&self, x: f64, z: f64) -> bool {
        let column = ((x / ROOM_X).floor() as usize).min(self.nx - 1);
        let row = ((z / ROOM_Z).floor() as usize).min(self.nz - 1);
        let in_a = (1..self.nz).any(|j| {
            (z - ROOM_Z * j as f64).abs() < WALL / 2.0 && {
                let (a, b) = self.door_x(column, j);
                !(x > a && x < b)
            }
        });
        let in_b = (1..self.nx).any(|i| {
            (x - ROOM_X * i as f64).abs() < WALL / 2.0 && {
                let (a, b) = self.door_z(row);
                !(z > a && z < b)
            }
        });
        in_a || in_b
    }
}

/// What was written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stats {
    /// Vertices written.
    pub vertices: usize,
    /// Triangles, counting each quad as two (as the loader fan-triangulates them).
    pub triangles: usize,
}

/// A point or vector, in metres.
pub type P = [f64; 3];

/// An OBJ under construction: deduplicated vertices, faces grouped by material.
#[derive(Default)]
struct Obj {
    vertices: Vec<P>,
    index: HashMap<[i64; 3], usize>,
    faces: Vec<(String, Vec<usize>)>,
    triangles: usize,
}

impl Obj {
    fn vertex(&mut self, p: P) -> usize {
        let key = p.map(|x| (x * 1e6).round() as i64);
        let next = self.vertices.len() + 1;
        *self.index.entry(key).or_insert_with(|| {
            self.vertices.push(p);
            next
        })
    }

    /// A planar polygon, wound so that its front faces along `normal`.
    fn polygon(&mut self, material: &str, mut corners: Vec<P>, normal: P) {
        let (a, b, c) = (corners[0], corners[1], corners[2]);
        let e1 = sub(b, a);
        let e2 = sub(c, a);
        let cross = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        if dot(cross, normal) < 0.0 {
            corners.reverse();
        }
        self.triangles += corners.len() - 2;
        let ids = corners.into_iter().map(|p| self.vertex(p)).collect();
        self.faces.push((material.to_string(), ids));
    }

    /// An axis-aligned rectangle spanned by two axes from `origin`, facing `normal`.
    fn rect(&mut self, material: &str, origin: P, u: P, v: P, normal: P) {
        let corners = vec![
            origin,
            add(origin, u),
            add(add(origin, u), v),
            add(origin, v),
        ];
        self.polygon(material, corners, normal);
    }

    fn write(&self, header: &str) -> String {
        let mut s = String::with_capacity(self.vertices.len() * 30 + self.faces.len() * 24);
        s.push_str(header);
        s.push_str("mtllib gallery.mtl\n");
        for v in &self.vertices {
            let _ = writeln!(s, "v {} {} {}", num(v[0]), num(v[1]), num(v[2]));
        }
        let mut current = "";
        for (material, ids) in &self.faces {
            if material != current {
                let _ = writeln!(s, "usemtl {material}");
                current = material;
            }
            s.push('f');
            for id in ids {
                let _ = write!(s, " {id}");
            }
            s.push('\n');
        }
        s
    }
}

fn num(x: f64) -> String {
    let r = (x * 1e6).round() / 1e6;
    if r == 0.0 {
        "0".into()
    } else {
        format!("{r}")
    }
}

fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn scale(a: P, s: f64) -> P {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn normalize(a: P) -> P {
    scale(a, 1.0 / dot(a, a).sqrt())
}

/// One straight partition-wall segment: from `start` along unit axis `along` for `length`,
/// thickness across `across` (centred), with doorways at offsets along it. Emits the two long
/// faces (split around doors), and each door's jambs and soffit; no ends (they abut other walls).
fn partition(obj: &mut Obj, start: P, along: P, length: f64, across: P, doors: &[(f64, f64)]) {
    let up = [0.0, 1.0, 0.0];
    let half = scale(across, WALL / 2.0);
    for side in [1.0, -1.0] {
        let normal = scale(across, side);
        let face_origin = add(start, scale(half, side));
        let mut u = 0.0;
        for &(d0, d1) in doors.iter().chain(std::iter::once(&(length, length))) {
            if d0 > u {
                obj.rect(
                    "wall",
                    add(face_origin, scale(along, u)),
                    scale(along, d0 - u),
                    scale(up, HEIGHT),
                    normal,
                );
            }
            if d1 > d0 {
                let lintel = add(add(face_origin, scale(along, d0)), scale(up, DOOR_HEIGHT));
                obj.rect(
                    "wall",
                    lintel,
                    scale(along, d1 - d0),
                    scale(up, HEIGHT - DOOR_HEIGHT),
                    normal,
                );
            }
            u = d1;
        }
    }
    for &(d0, d1) in doors {
        let back = sub(start, half);
        let thick = scale(across, WALL);
        let jamb0 = add(back, scale(along, d0));
        obj.rect("wall", jamb0, thick, scale(up, DOOR_HEIGHT), along);
        let jamb1 = add(back, scale(along, d1));
        obj.rect(
            "wall",
            jamb1,
            thick,
            scale(up, DOOR_HEIGHT),
            scale(along, -1.0),
        );
        let soffit = add(add(back, scale(along, d0)), scale(up, DOOR_HEIGHT));
        obj.rect(
            "wall",
            soffit,
            thick,
            scale(along, d1 - d0),
            [0.0, -1.0, 0.0],
        );
    }
}

/// An axis-aligned box from `min` to `max`; `bottom` says whether to emit its underside.
fn block(obj: &mut Obj, material: &str, min: P, max: P, bottom: bool) {
    let d = sub(max, min);
    let (x, y, z) = ([d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]);
    obj.rect(material, [min[0], max[1], min[2]], x, z, [0.0, 1.0, 0.0]);
    if bottom {
        obj.rect(material, min, x, z, [0.0, -1.0, 0.0]);
    }
    obj.rect(material, min, x, y, [0.0, 0.0, -1.0]);
    obj.rect(material, [min[0], min[1], max[2]], x, y, [0.0, 0.0, 1.0]);
    obj.rect(material, min, z, y, [-1.0, 0.0, 0.0]);
    obj.rect(material, [max[0], min[1], min[2]], z, y, [1.0, 0.0, 0.0]);
}

/// A faceted icosphere (flat facets: each is one planar surface for the solver).
fn icosphere(obj: &mut Obj, material: &str, centre: P, radius: f64, detail: u32) {
    let (v, faces) = unit_icosphere(detail);
    for f in faces {
        let corners: Vec<P> = f
            .iter()
            .map(|&i| add(centre, scale(v[i], radius)))
            .collect();
        let c = scale(add(add(v[f[0]], v[f[1]]), v[f[2]]), 1.0 / 3.0);
        obj.polygon(material, corners, c);
    }
}

/// The unit icosphere of the sculptures: an icosahedron whose faces are cut in four `detail`
/// times; its vertices and its triangles (indices, counter-clockwise seen from outside).
pub fn unit_icosphere(detail: u32) -> (Vec<P>, Vec<[usize; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<P> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| normalize(p))
    .collect();
    let mut faces: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..detail {
        let mut midpoints: HashMap<(usize, usize), usize> = HashMap::new();
        let mut mid = |a: usize, b: usize, v: &mut Vec<P>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(normalize(scale(add(v[a], v[b]), 0.5)));
                v.len() - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    (v, faces)
}

/// A framed painting on a wall: canvas 2 cm off the wall, a frame of four bars around it.
/// `origin` is the canvas's lower-left corner on the wall plane, `right` and `normal` unit axes.
fn painting(obj: &mut Obj, canvas: &str, origin: P, right: P, normal: P, w: f64, h: f64) {
    let up = [0.0, 1.0, 0.0];
    let at = |u: f64, v: f64| add(add(origin, scale(right, u)), scale(up, v));
    obj.rect(
        canvas,
        add(at(0.0, 0.0), scale(normal, 0.02)),
        scale(right, w),
        scale(up, h),
        normal,
    );
    let (bar, depth) = (0.07, 0.05);
    let dn = scale(normal, depth);
    // Bottom and top bars span the full width; the side bars fit between them, so their ends
    // (which would touch the other bars face to face) are left out.
    let bars = [
        (-bar, -bar, w + 2.0 * bar, bar, true),
        (-bar, h, w + 2.0 * bar, bar, true),
        (-bar, 0.0, bar, h, false),
        (w, 0.0, bar, h, false),
    ];
    for (u, v, a, b, horizontal) in bars {
        let corner = at(u, v);
        let (ua, ub) = (scale(right, a), scale(up, b));
        obj.rect("frame", add(corner, dn), ua, ub, normal);
        if horizontal {
            obj.rect("frame", corner, ua, dn, scale(up, -1.0));
            obj.rect("frame", add(corner, ub), ua, dn, up);
        }
        obj.rect("frame", corner, ub, dn, scale(right, -1.0));
        obj.rect("frame", add(corner, ua), ub, dn, right);
    }
}

/// Builds the whole gallery.
fn build(options: GalleryOptions) -> Obj {
    let mut obj = Obj::default();
    let tile = options.tile;
    let layout = Layout {
        nx: options.rooms[0].max(1),
        nz: options.rooms[1].max(1),
    };
    let (width, depth) = (layout.width(), layout.depth());

    // Floor: tiles, none under the partition walls (doorways keep theirs).
    let (nx, nz) = (
        (width / tile).round() as usize,
        (depth / tile).round() as usize,
    );
    for i in 0..nx {
        for k in 0..nz {
            let (x, z) = (i as f64 * tile, k as f64 * tile);
            if !layout.under_wall(x + tile / 2.0, z + tile / 2.0) {
                obj.rect(
                    "floor",
                    [x, 0.0, z],
                    [tile, 0.0, 0.0],
                    [0.0, 0.0, tile],
                    [0.0, 1.0, 0.0],
                );
            }
        }
    }
    // Ceiling: one large quad per room (huge triangles beside the small ones); with skylights,
    // four around each room's opening, and a pane over it overlapping the opening.
    for i in 0..layout.nx {
        for j in 0..layout.nz {
            let (x0, x1, z0, z1) = layout.room(i, j);
            if !options.skylights {
                obj.rect(
                    "ceiling",
                    [x0, HEIGHT, z0],
                    [x1 - x0, 0.0, 0.0],
                    [0.0, 0.0, z1 - z0],
                    [0.0, -1.0, 0.0],
                );
                continue;
            }
            let (cx, cz) = (0.5 * (x0 + x1), 0.5 * (z0 + z1));
            let (hx0, hx1) = (cx - 0.5 * SKYLIGHT[0], cx + 0.5 * SKYLIGHT[0]);
            let (hz0, hz1) = (cz - 0.5 * SKYLIGHT[1], cz + 0.5 * SKYLIGHT[1]);
            for (a, b, c, d) in [
                (x0, x1, z0, hz0),
                (x0, x1, hz1, z1),
                (x0, hx0, hz0, hz1),
                (hx1, x1, hz0, hz1),
            ] {
                obj.rect(
                    "ceiling",
                    [a, HEIGHT, c],
                    [b - a, 0.0, 0.0],
                    [0.0, 0.0, d - c],
                    [0.0, -1.0, 0.0],
                );
            }
            // 0.3 m of overlap 5 cm up: no ray from inside the room rises that flat.
            obj.rect(
                "skylight",
                [hx0 - 0.3, HEIGHT + 0.05, hz0 - 0.3],
                [hx1 - hx0 + 0.6, 0.0, 0.0],
                [0.0, 0.0, hz1 - hz0 + 0.6],
                [0.0, -1.0, 0.0],
            );
        }
    }
    // Outer walls, tiled, facing in; no tiles behind the partition walls' ends.
    let ny = (HEIGHT / tile).round() as usize;
    let walls: [(P, P, f64, P); 4] = [
        ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], width, [0.0, 0.0, 1.0]),
        ([0.0, 0.0, depth], [1.0, 0.0, 0.0], width, [0.0, 0.0, -1.0]),
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], depth, [1.0, 0.0, 0.0]),
        ([width, 0.0, 0.0], [0.0, 0.0, 1.0], depth, [-1.0, 0.0, 0.0]),
    ];
    for (origin, along, length, normal) in walls {
        let n = (length / tile).round() as usize;
        for i in 0..n {
            let u = (i as f64 + 0.5) * tile;
            let mid = add(origin, scale(along, u));
            if layout.in_partition(mid[0], mid[2]) {
                continue;
            }
            for j in 0..ny {
                let o = add(
                    add(origin, scale(along, i as f64 * tile)),
                    [0.0, j as f64 * tile, 0.0],
                );
                obj.rect("wall", o, scale(along, tile), [0.0, tile, 0.0], normal);
            }
        }
    }
    // Partition walls, one segment per room they bound, each with its doorway: along x at
    // z = 8j, along z at x = 12i.
    for j in 1..layout.nz {
        for i in 0..layout.nx {
            let (x0, x1, _, _) = layout.room(i, j);
            let (a, b) = layout.door_x(i, j);
            partition(
                &mut obj,
                [x0, 0.0, ROOM_Z * j as f64],
                [1.0, 0.0, 0.0],
                x1 - x0,
                [0.0, 0.0, 1.0],
                &[(a - x0, b - x0)],
            );
        }
    }
    for i in 1..layout.nx {
        for j in 0..layout.nz {
            let (_, _, z0, z1) = layout.room(i, j);
            let (a, b) = layout.door_z(j);
            partition(
                &mut obj,
                [ROOM_X * i as f64, 0.0, z0],
                [0.0, 0.0, 1.0],
                z1 - z0,
                [1.0, 0.0, 0.0],
                &[(a - z0, b - z0)],
            );
        }
    }

    // Per room: two pedestals with sculptures, a bench, paintings on its outer walls.
    let canvases = ["canvas_red", "canvas_blue", "canvas_ochre", "canvas_teal"];
    for j in 0..layout.nz {
        for i in 0..layout.nx {
            let r = j * layout.nx + i;
            let (rx, x1, rz, z1) = layout.room(i, j);
            let (w, d) = (x1 - rx, z1 - rz);
            for (p, &(fx, fz)) in [(0.3, 0.35), (0.7, 0.65)].iter().enumerate() {
                let (cx, cz) = (rx + fx * w, rz + fz * d);
                block(
                    &mut obj,
                    "pedestal",
                    [cx - 0.3, 0.0, cz - 0.3],
                    [cx + 0.3, 1.0, cz + 0.3],
                    false,
                );
                let detail = if p == 0 {
                    options.sphere_detail
                } else {
                    options.sphere_detail.saturating_sub(1)
                };
                icosphere(&mut obj, "stone", [cx, 1.0 + 0.32, cz], 0.32, detail);
            }
            let (bx, bz) = (rx + 0.5 * w, rz + 0.5 * d);
            block(
                &mut obj,
                "bench",
                [bx - 0.8, 0.0, bz - 0.2],
                [bx + 0.8, 0.45, bz + 0.2],
                false,
            );
            // The room's outer walls, if it has any: z = 0 or the depth, x = 0 or the width.
            let z_wall = match j {
                0 => Some((0.0, [0.0, 0.0, 1.0])),
                _ if j + 1 == layout.nz => Some((depth, [0.0, 0.0, -1.0])),
                _ => None,
            };
            let x_wall = match i {
                0 => Some((0.0, [1.0, 0.0, 0.0])),
                _ if i + 1 == layout.nx => Some((width, [-1.0, 0.0, 0.0])),
                _ => None,
            };
            if let Some((z, normal)) = z_wall {
                for k in 0..3 {
                    let canvas = canvases[(r + k) % canvases.len()];
                    let x = rx + 1.8 + k as f64 * 3.4;
                    painting(
                        &mut obj,
                        canvas,
                        [x, 1.3, z],
                        [1.0, 0.0, 0.0],
                        normal,
                        1.6,
                        1.1,
                    );
                }
            }
            if let Some((x, normal)) = x_wall {
                for k in 0..2 {
                    let canvas = canvases[(r + k + 1) % canvases.len()];
                    let z = rz + 1.6 + k as f64 * 3.2;
                    painting(
                        &mut obj,
                        canvas,
                        [x, 1.3, z],
                        [0.0, 0.0, 1.0],
                        normal,
                        1.4,
                        1.0,
                    );
                }
            }
        }
    }
    obj
}

/// The point lights of a generated gallery: two per room under the ceiling.
fn lights(layout: Layout) -> Vec<P> {
    let mut out = Vec::new();
    for j in 0..layout.nz {
        for i in 0..layout.nx {
            let (x, z) = (ROOM_X * i as f64, ROOM_Z * j as f64);
            out.push([x + 3.0, 4.3, z + 2.0]);
            out.push([x + 8.9, 4.3, z + 5.9]);
        }
    }
    out
}

/// The `scene.toml` of a generated gallery of another size than the shipped one: the shipped
/// camera, two point lights per room, ε 0.3.
pub fn scene_toml(options: GalleryOptions) -> String {
    let layout = Layout {
        nx: options.rooms[0].max(1),
        nz: options.rooms[1].max(1),
    };
    let mut s = format!(
        "# A generated gallery of {} × {} rooms (meshlight-gallery --rooms {}x{}).\n\
         obj = \"gallery.obj\"\n\n[camera]\nposition = [2.0, 1.6, 1.2]\nlook_at = [12.0, 1.5, 4.0]\n\
         fov_y = 55.0\nwidth = 768\nheight = 512\n",
        layout.nx, layout.nz, layout.nx, layout.nz
    );
    for p in lights(layout) {
        let _ = write!(
            s,
            "\n[[point_light]]\nposition = [{}, {}, {}]\nintensity = [40.0, 38.0, 34.0]\n",
            num(p[0]),
            num(p[1]),
            num(p[2])
        );
    }
    s.push_str("\n[solver]\nepsilon = 0.3\n");
    s
}

/// The first line of a generated OBJ: identifies the generator version and options, so a stale
/// file is regenerated.
pub fn header(options: GalleryOptions) -> String {
    let rooms = if options.rooms == GalleryOptions::default().rooms {
        String::new()
    } else {
        format!(" rooms={}x{}", options.rooms[0], options.rooms[1])
    };
    format!(
        "# meshlight gallery v1 tile={} sphere_detail={}{rooms}{}\n",
        options.tile,
        options.sphere_detail,
        if options.skylights {
            " skylights=2"
        } else {
            ""
        }
    )
}

/// The OBJ's file name: `gallery.obj`, or `gallery-skylit.obj` with skylights.
pub fn obj_name(options: GalleryOptions) -> &'static str {
    if options.skylights {
        "gallery-skylit.obj"
    } else {
        "gallery.obj"
    }
}

/// Writes `gallery.obj` into `dir` (atomically: a temporary file renamed into place, so
/// concurrent writers never leave a torn file).
pub fn write_obj(dir: &Path, options: GalleryOptions) -> io::Result<Stats> {
    let obj = build(options);
    let text = obj.write(&header(options));
    let path = dir.join(obj_name(options));
    let tmp = dir.join(format!("{}.{}.tmp", obj_name(options), std::process::id()));
    std::fs::write(&tmp, text)?;
    std::fs::rename(&tmp, &path)?;
    Ok(Stats {
        vertices: obj.vertices.len(),
        triangles: obj.triangles,
    })
}

/// Writes a whole scene into `dir`: `gallery.obj`, and unless `dir` is the shipped folder,
/// `gallery.mtl` and `scene.toml` beside it (the shipped ones, or for a gallery of another size
/// one written for it).
pub fn write_scene(dir: &Path, options: GalleryOptions) -> io::Result<Stats> {
    std::fs::create_dir_all(dir)?;
    // Compared as real paths: copying a file onto itself would empty it.
    let shipped = std::fs::canonicalize(shipped_dir())?;
    if std::fs::canonicalize(dir)? != shipped {
        std::fs::copy(shipped_dir().join("gallery.mtl"), dir.join("gallery.mtl"))?;
        if options.rooms == GalleryOptions::default().rooms {
            std::fs::copy(shipped_dir().join("scene.toml"), dir.join("scene.toml"))?;
            if options.skylights {
                std::fs::copy(
                    shipped_dir().join("daylight.toml"),
                    dir.join("daylight.toml"),
                )?;
            }
        } else {
            std::fs::write(dir.join("scene.toml"), scene_toml(options))?;
        }
    }
    write_obj(dir, options)
}

/// This crate's own folder: `scenes/gallery`, where `scene.toml` and `gallery.mtl` live.
pub fn shipped_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Makes sure the shipped gallery's OBJ exists with the default options, writing it if it is
/// missing or stale; returns the path of `scene.toml`.
pub fn ensure() -> io::Result<PathBuf> {
    ensure_with(GalleryOptions::default())?;
    Ok(shipped_dir().join("scene.toml"))
}

/// [`ensure`] for the gallery with skylights; returns the path of `daylight.toml`.
pub fn ensure_skylit() -> io::Result<PathBuf> {
    ensure_with(GalleryOptions {
        skylights: true,
        ..GalleryOptions::default()
    })?;
    Ok(shipped_dir().join("daylight.toml"))
}

fn ensure_with(options: GalleryOptions) -> io::Result<()> {
    let dir = shipped_dir();
    let obj = dir.join(obj_name(options));
    let expected = header(options);
    let current = std::fs::read(&obj).ok().and_then(|bytes| {
        let end = bytes.iter().position(|&b| b == b'\n')? + 1;
        String::from_utf8(bytes[..end].to_vec()).ok()
    });
    if current.as_deref() != Some(expected.as_str()) {
        write_obj(&dir, options)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_gallery_has_at_least_100k_triangles() {
        let obj = build(GalleryOptions::default());
        assert!(obj.triangles >= 100_000, "{} triangles", obj.triangles);
    }

    #[test]
    fn icosphere_facets_face_outwards() {
        let mut obj = Obj::default();
        icosphere(&mut obj, "stone", [1.0, 2.0, 3.0], 0.5, 1);
        assert_eq!(obj.triangles, 80);
        for (_, ids) in &obj.faces {
            let [a, b, c] = [ids[0], ids[1], ids[2]].map(|i| obj.vertices[i - 1]);
            let n = {
                let (e1, e2) = (sub(b, a), sub(c, a));
                [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ]
            };
            assert!(dot(n, sub(a, [1.0, 2.0, 3.0])) > 0.0);
        }
    }
}
