//! Writes meshlight's atrium scene as OBJ: a courtyard 24 m × 12 m between two storeys of
//! arcades, as in the atria global-illumination papers have used for twenty years (Dabrovic's
//! Sponza), generated: round columns with bases and flared capitals, semicircular arches cut
//! through the arcade walls, barrel vaults over the ground-floor galleries with a rib over
//! every column, a cornice, and cloths hanging from the upper arcade, folded. Most of its
//! surfaces are small facets of curved things (a column's 48 facets, an arch's 32 soffit
//! strips), which is what artist-made geometry is like. The courtyard is open to the sky; five
//! point lights (in `scene.toml`). The OBJ is generated rather than committed.
//!
//! Solids (columns, piers, cloths seen from the courtyard) face outwards; the floor, walls,
//! vaults and ceilings face the spaces they bound.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// The default [`write_obj`] detail.
pub const DEFAULT_DETAIL: u32 = 2;

type P = [f64; 3];

/// Courtyard and galleries: x along the arcades, z across, y up.
const LENGTH: f64 = 24.0;
const WIDTH: f64 = 12.0;
/// The galleries' depth to the arcade wall's inner face, and the arcade wall's thickness.
const GALLERY: f64 = 2.75;
const WALL: f64 = 0.5;
/// Column spacing along x (the first at BAY / 2).
const BAY: f64 = 3.0;
const COLUMNS: usize = 8;

/// A storey's arcade: floor level, column radius, capital radius, column height (to the
/// capitals' top, where the arches spring), wall top.
struct Storey {
    floor: f64,
    radius: f64,
    capital: f64,
    height: f64,
    top: f64,
}

const STOREYS: [Storey; 2] = [
    Storey {
        floor: 0.0,
        radius: 0.3,
        capital: 0.42,
        height: 4.0,
        top: 6.0,
    },
    Storey {
        floor: 6.0,
        radius: 0.22,
        capital: 0.32,
        height: 3.0,
        top: 11.0,
    },
];

fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: P, b: P) -> P {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The mesh being written: vertices shared by position, faces by material.
#[derive(Default)]
struct Obj {
    vertices: Vec<P>,
    index: HashMap<[u64; 3], usize>,
    faces: Vec<(String, [usize; 3])>,
}

impl Obj {
    fn vertex(&mut self, p: P) -> usize {
        // Rounded to a micrometre, so that neighbouring facets computed apart share corners.
        let key = p.map(|c| ((c * 1e6).round() as i64) as u64);
        if let Some(&i) = self.index.get(&key) {
            return i;
        }
        self.vertices.push(p);
        self.index.insert(key, self.vertices.len() - 1);
        self.vertices.len() - 1
    }

    /// A triangle facing `towards` (its corners reordered if need be); degenerate ones are
    /// left out.
    fn triangle(&mut self, material: &str, t: [P; 3], towards: P) {
        let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        if dot(n, n) < 1e-18 {
            return;
        }
        let t = if dot(n, towards) < 0.0 {
            [t[0], t[2], t[1]]
        } else {
            t
        };
        let v = t.map(|p| self.vertex(p));
        self.faces.push((material.to_string(), v));
    }

    /// A quad (corners in order around it) facing `towards`.
    fn quad(&mut self, material: &str, q: [P; 4], towards: P) {
        self.triangle(material, [q[0], q[1], q[2]], towards);
        self.triangle(material, [q[0], q[2], q[3]], towards);
    }

    fn write(&self, header: &str) -> String {
        let mut s = String::with_capacity(64 * self.faces.len());
        let _ = writeln!(s, "{header}\nmtllib atrium.mtl");
        for v in &self.vertices {
            let _ = writeln!(s, "v {} {} {}", num(v[0]), num(v[1]), num(v[2]));
        }
        let mut faces: Vec<&(String, [usize; 3])> = self.faces.iter().collect();
        faces.sort_by(|a, b| a.0.cmp(&b.0));
        let mut current = "";
        for (m, f) in faces {
            if m != current {
                let _ = writeln!(s, "usemtl {m}");
                current = m;
            }
            let _ = writeln!(s, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1);
        }
        s
    }
}

fn num(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// A round column at (x, z) from `y0` to `y1`: base, shaft and flared capital, `n` facets
/// around, facing out.
fn column(obj: &mut Obj, x: f64, z: f64, s: &Storey, n: usize) {
    let at = |r: f64, a: f64, y: f64| [x + r * a.cos(), y, z + r * a.sin()];
    let base = (s.capital, s.floor + 0.3);
    let capital_bottom = s.floor + s.height - 0.45;
    let top = s.floor + s.height;
    for i in 0..n {
        let (a0, a1) = (
            std::f64::consts::TAU * i as f64 / n as f64,
            std::f64::consts::TAU * (i + 1) as f64 / n as f64,
        );
        let mid = 0.5 * (a0 + a1);
        let out = [mid.cos(), 0.0, mid.sin()];
        // Base: a drum, and the ring on top of it around the shaft.
        obj.quad(
            "stone",
            [
                at(base.0, a0, s.floor),
                at(base.0, a1, s.floor),
                at(base.0, a1, base.1),
                at(base.0, a0, base.1),
            ],
            out,
        );
        obj.quad(
            "stone",
            [
                at(s.radius, a0, base.1),
                at(base.0, a0, base.1),
                at(base.0, a1, base.1),
                at(s.radius, a1, base.1),
            ],
            [0.0, 1.0, 0.0],
        );
        // Shaft.
        obj.quad(
            "column",
            [
                at(s.radius, a0, base.1),
                at(s.radius, a1, base.1),
                at(s.radius, a1, capital_bottom),
                at(s.radius, a0, capital_bottom),
            ],
            out,
        );
        // The capital's top, where it stands out of the pier it carries.
        obj.triangle(
            "stone",
            [[x, top, z], at(s.capital, a0, top), at(s.capital, a1, top)],
            [0.0, 1.0, 0.0],
        );
        // Capital: flaring out to the arches' springing, facing out and down.
        obj.quad(
            "column",
            [
                at(s.radius, a0, capital_bottom),
                at(s.radius, a1, capital_bottom),
                at(s.capital, a1, top),
                at(s.capital, a0, top),
            ],
            add(out, [0.0, -0.3, 0.0]),
        );
    }
}

/// One side's arcade wall of a storey, at z from `z_in` (the gallery's side) to `z_out` (the
/// courtyard's): piers over the columns, and between them semicircular arches of `n` segments
/// springing from the capitals.
fn arcade(obj: &mut Obj, s: &Storey, (z_in, z_out): (f64, f64), n: usize) {
    let spring = s.floor + s.height;
    let (into_gallery, into_court) = ([0.0, 0.0, z_in - z_out], [0.0, 0.0, z_out - z_in]);
    let xs: Vec<f64> = (0..COLUMNS).map(|i| BAY / 2.0 + BAY * i as f64).collect();
    // The wall beyond the outer columns, to the end walls, and the piers over the columns.
    let mut solid = vec![(0.0, xs[0] - s.capital)];
    solid.extend(xs.iter().map(|&x| (x - s.capital, x + s.capital)));
    solid.push((xs[COLUMNS - 1] + s.capital, LENGTH));
    for &(x0, x1) in &solid {
        let y0 = if x0 == 0.0 || x1 == LENGTH {
            s.floor
        } else {
            spring
        };
        for (z, towards) in [(z_in, into_gallery), (z_out, into_court)] {
            obj.quad(
                "stone",
                [[x0, y0, z], [x1, y0, z], [x1, s.top, z], [x0, s.top, z]],
                towards,
            );
        }
    }
    // The wall's ends beyond the outer columns face the arcade's openings.
    for (x, towards) in [
        (xs[0] - s.capital, [1.0, 0.0, 0.0]),
        (xs[COLUMNS - 1] + s.capital, [-1.0, 0.0, 0.0]),
    ] {
        obj.quad(
            "stone",
            [
                [x, s.floor, z_in],
                [x, s.floor, z_out],
                [x, spring, z_out],
                [x, spring, z_in],
            ],
            towards,
        );
    }
    for pair in xs.windows(2) {
        let (a, b) = (pair[0] + s.capital, pair[1] - s.capital);
        let (centre, r) = (0.5 * (a + b), 0.5 * (b - a));
        let arch = |i: usize, z: f64| {
            let t = std::f64::consts::PI * (1.0 - i as f64 / n as f64);
            [centre + r * t.cos(), spring + r * t.sin(), z]
        };
        let top = |i: usize, z: f64| [a + (b - a) * i as f64 / n as f64, s.top, z];
        for i in 0..n {
            // The wall above the arch, both faces; the soffit, facing the arch's axis.
            for (z, towards) in [(z_in, into_gallery), (z_out, into_court)] {
                obj.quad(
                    "stone",
                    [arch(i, z), arch(i + 1, z), top(i + 1, z), top(i, z)],
                    towards,
                );
            }
            let mid = std::f64::consts::PI * (1.0 - (i as f64 + 0.5) / n as f64);
            obj.quad(
                "stone",
                [
                    arch(i, z_in),
                    arch(i + 1, z_in),
                    arch(i + 1, z_out),
                    arch(i, z_out),
                ],
                [-mid.cos(), -mid.sin(), 0.0],
            );
        }
    }
}

/// A barrel vault along x over z from `z0` to `z1`, springing at `y`, of `n` strips facing
/// down into the gallery, with a rib of `n` strips over every column.
fn vault(obj: &mut Obj, (z0, z1): (f64, f64), y: f64, n: usize) {
    let (centre, r) = (0.5 * (z0 + z1), 0.5 * (z1 - z0).abs());
    let at = |i: usize, x: f64, radius: f64| {
        let t = std::f64::consts::PI * i as f64 / n as f64;
        [x, y + radius * t.sin(), centre + radius * t.cos()]
    };
    for i in 0..n {
        let mid = std::f64::consts::PI * (i as f64 + 0.5) / n as f64;
        let inward = [0.0, -mid.sin(), -mid.cos()];
        obj.quad(
            "vault",
            [
                at(i, 0.0, r),
                at(i + 1, 0.0, r),
                at(i + 1, LENGTH, r),
                at(i, LENGTH, r),
            ],
            inward,
        );
        // Ribs: bands 0.3 m wide hanging 0.12 m under the vault over every column.
        for c in 0..COLUMNS {
            let x = BAY / 2.0 + BAY * c as f64;
            let (xa, xb, rr) = (x - 0.15, x + 0.15, r - 0.12);
            obj.quad(
                "stone",
                [
                    at(i, xa, rr),
                    at(i + 1, xa, rr),
                    at(i + 1, xb, rr),
                    at(i, xb, rr),
                ],
                inward,
            );
            for (xs, towards) in [(xa, [-1.0, 0.0, 0.0]), (xb, [1.0, 0.0, 0.0])] {
                obj.quad(
                    "stone",
                    [
                        at(i, xs, rr),
                        at(i + 1, xs, rr),
                        at(i + 1, xs, r),
                        at(i, xs, r),
                    ],
                    towards,
                );
            }
        }
    }
}

/// A cornice along the courtyard face of an arcade wall, under height `y`: a quarter-round
/// moulding (an ovolo) of `n` strips standing out by 0.3 m, facing the courtyard and the sky,
/// and its flat underside.
fn cornice(obj: &mut Obj, z: f64, out: f64, y: f64, n: usize) {
    let at = |i: usize, x: f64| {
        let t = std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
        [x, y - 0.3 + 0.3 * t.sin(), z + out * 0.3 * t.cos()]
    };
    for i in 0..n {
        let t = std::f64::consts::FRAC_PI_2 * (i as f64 + 0.5) / n as f64;
        obj.quad(
            "stone",
            [at(i, 0.0), at(i + 1, 0.0), at(i + 1, LENGTH), at(i, LENGTH)],
            [0.0, t.sin(), out * t.cos()],
        );
    }
    obj.quad(
        "stone",
        [
            [0.0, y - 0.3, z],
            [LENGTH, y - 0.3, z],
            [LENGTH, y - 0.3, z + out * 0.3],
            [0.0, y - 0.3, z + out * 0.3],
        ],
        [0.0, -1.0, 0.0],
    );
}

/// A cloth hanging from (x, y) in front of an arcade at z, 1.2 m wide and 3.3 m long, folded
/// in three waves: a grid of 4n × 2n quads facing the courtyard (`out`).
fn cloth(obj: &mut Obj, material: &str, (x, y, z): (f64, f64, f64), out: f64, n: usize) {
    let (cols, rows) = (4 * n, 2 * n);
    let at = |i: usize, j: usize| {
        let u = i as f64 / cols as f64;
        let v = j as f64 / rows as f64;
        let fold = 0.08 * (std::f64::consts::TAU * 3.0 * u).sin() * (0.4 + 0.6 * v);
        [x - 0.6 + 1.2 * u, y - 3.3 * v, z + out * (0.1 + fold)]
    };
    for i in 0..cols {
        for j in 0..rows {
            obj.quad(
                material,
                [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)],
                [0.0, 0.0, out],
            );
        }
    }
}

fn build(detail: u32) -> Obj {
    let d = detail.max(1) as usize;
    let mut obj = Obj::default();
    // The courtyard's floor and its end walls (open above), the galleries' back walls.
    let top = STOREYS[1].top;
    obj.quad(
        "floor",
        [
            [0.0, 0.0, 0.0],
            [LENGTH, 0.0, 0.0],
            [LENGTH, 0.0, WIDTH],
            [0.0, 0.0, WIDTH],
        ],
        [0.0, 1.0, 0.0],
    );
    for (x, towards) in [(0.0, [1.0, 0.0, 0.0]), (LENGTH, [-1.0, 0.0, 0.0])] {
        obj.quad(
            "stone",
            [
                [x, 0.0, 0.0],
                [x, 0.0, WIDTH],
                [x, top, WIDTH],
                [x, top, 0.0],
            ],
            towards,
        );
    }
    // The galleries' back walls, but where the vault's back hides them (4.5 to 6 m).
    let vault_spring = STOREYS[0].floor + STOREYS[0].height + 0.5;
    for (z, towards) in [(0.0, [0.0, 0.0, 1.0]), (WIDTH, [0.0, 0.0, -1.0])] {
        for (y0, y1) in [(0.0, vault_spring), (STOREYS[1].floor, top)] {
            obj.quad(
                "stone",
                [[0.0, y0, z], [LENGTH, y0, z], [LENGTH, y1, z], [0.0, y1, z]],
                towards,
            );
        }
    }
    // Both sides: z from the back wall towards the courtyard (sign +1 at z = 0, −1 at 12).
    for (back, out) in [(0.0, 1.0), (WIDTH, -1.0)] {
        let z = |d: f64| back + out * d;
        let (z_in, z_out) = (z(GALLERY), z(GALLERY + WALL));
        for (k, s) in STOREYS.iter().enumerate() {
            for c in 0..COLUMNS {
                column(
                    &mut obj,
                    BAY / 2.0 + BAY * c as f64,
                    z(GALLERY + WALL / 2.0),
                    s,
                    24 * d,
                );
            }
            arcade(&mut obj, s, (z_in, z_out), 16 * d);
            if k == 0 {
                // The ground gallery's vault, springing 0.5 m over the arches, and the upper
                // gallery's floor over it.
                vault(&mut obj, (back, z_in), vault_spring, 12 * d);
                obj.quad(
                    "floor",
                    [
                        [0.0, s.top, back],
                        [LENGTH, s.top, back],
                        [LENGTH, s.top, z_out],
                        [0.0, s.top, z_out],
                    ],
                    [0.0, 1.0, 0.0],
                );
            } else {
                // The upper gallery's flat ceiling.
                obj.quad(
                    "stone",
                    [
                        [0.0, s.top, back],
                        [LENGTH, s.top, back],
                        [LENGTH, s.top, z_in],
                        [0.0, s.top, z_in],
                    ],
                    [0.0, -1.0, 0.0],
                );
            }
            cornice(&mut obj, z_out, out, s.top, 3 * d);
        }
        // Cloths from the upper arcade, red and green in turn.
        for (i, x) in [4.5, 10.5, 13.5, 19.5].into_iter().enumerate() {
            let material = if i % 2 == 0 {
                "cloth_red"
            } else {
                "cloth_green"
            };
            cloth(&mut obj, material, (x, 10.6, z_out), out, 3 * d);
        }
    }
    obj
}

/// The first line of the OBJ: says what made it, so a stale file is known.
pub fn header(detail: u32) -> String {
    format!("# meshlight atrium, detail {detail} (cargo run --release -p meshlight-atrium)")
}

/// What was written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stats {
    /// Distinct vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
}

/// Writes `atrium.obj` into `dir` (atomically: a temporary file renamed into place).
pub fn write_obj(dir: &Path, detail: u32) -> io::Result<Stats> {
    let obj = build(detail);
    let path = dir.join("atrium.obj");
    let tmp = dir.join(format!("atrium.obj.{}.tmp", std::process::id()));
    std::fs::write(&tmp, obj.write(&header(detail)))?;
    std::fs::rename(&tmp, &path)?;
    Ok(Stats {
        vertices: obj.vertices.len(),
        triangles: obj.faces.len(),
    })
}

/// This crate's own folder: `scenes/atrium`, where `scene.toml` and `atrium.mtl` live.
pub fn shipped_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Makes sure the atrium's OBJ exists at the default detail, writing it if it is missing or
/// stale; returns the path of `scene.toml`.
pub fn ensure() -> io::Result<PathBuf> {
    let dir = shipped_dir();
    let obj = dir.join("atrium.obj");
    let expected = header(DEFAULT_DETAIL);
    let current = std::fs::read(&obj).ok().and_then(|bytes| {
        let end = bytes.iter().position(|&b| b == b'\n')?;
        String::from_utf8(bytes[..end].to_vec()).ok()
    });
    if current.as_deref() != Some(expected.as_str()) {
        write_obj(&dir, DEFAULT_DETAIL)?;
    }
    Ok(dir.join("scene.toml"))
}
