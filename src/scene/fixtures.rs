//! Scenes built from parts for the library's unit tests: boxes and tessellated spheres.

use glam::Vec3;

use super::{Camera, Kind, Material, Mesh, Scene, SceneParts, SolverDefaults};

/// A mesh under construction.
#[derive(Default)]
pub(crate) struct Parts {
    pub mesh: Mesh,
}

impl Parts {
    /// Adds a material; its index.
    pub fn material(&mut self, m: Material) -> u32 {
        self.mesh.materials.push(m);
        self.mesh.materials.len() as u32 - 1
    }

    fn triangle(&mut self, [a, b, c]: [Vec3; 3], material: u32) {
        let first = self.mesh.positions.len() as u32;
        self.mesh.positions.extend([a, b, c]);
        self.mesh.triangles.push([first, first + 1, first + 2]);
        self.mesh.triangle_materials.push(material);
    }

    /// An axis-aligned box between `lo` and `hi`, faces pointing in (a room) or out (a solid).
    pub fn cuboid(&mut self, lo: Vec3, hi: Vec3, inwards: bool, material: u32) {
        let c = |i: usize| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        };
        // Each face counter-clockwise seen from outside.
        let faces = [
            [0, 4, 6, 2],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 2, 3, 1],
            [4, 5, 7, 6],
        ];
        for f in faces {
            let [a, b, d, e] = f.map(c);
            let (t1, t2) = ([a, b, d], [a, d, e]);
            if inwards {
                self.triangle([t1[0], t1[2], t1[1]], material);
                self.triangle([t2[0], t2[2], t2[1]], material);
            } else {
                self.triangle(t1, material);
                self.triangle(t2, material);
            }
        }
    }

    /// An ico sphere of 20 · 4^`level` triangles, faces pointing out, its corners shared
    /// between neighbouring triangles (as an exporter writes one).
    pub fn sphere(&mut self, centre: Vec3, radius: f32, level: u32, material: u32) {
        let t = (1.0 + 5f32.sqrt()) / 2.0;
        let mut v: Vec<Vec3> = [
            (-1.0, t, 0.0),
            (1.0, t, 0.0),
            (-1.0, -t, 0.0),
            (1.0, -t, 0.0),
            (0.0, -1.0, t),
            (0.0, 1.0, t),
            (0.0, -1.0, -t),
            (0.0, 1.0, -t),
            (t, 0.0, -1.0),
            (t, 0.0, 1.0),
            (-t, 0.0, -1.0),
            (-t, 0.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
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
        for _ in 0..level {
            let mut middle = std::collections::HashMap::new();
            let mut mid = |a: usize, b: usize, v: &mut Vec<Vec3>| {
                *middle.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    v.push(((v[a] + v[b]) / 2.0).normalize());
                    v.len() - 1
                })
            };
            faces = faces
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
                    [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
                })
                .collect();
        }
        let first = self.mesh.positions.len() as u32;
        self.mesh
            .positions
            .extend(v.iter().map(|&p| centre + radius * p));
        for f in faces {
            self.mesh.triangles.push(f.map(|i| first + i as u32));
            self.mesh.triangle_materials.push(material);
        }
    }

    /// A round column of `facets` flat facets (radius `radius`, `height` high, standing on
    /// `base`), faces pointing out, its corners shared between neighbouring facets.
    pub fn column(&mut self, base: Vec3, radius: f32, height: f32, facets: u32, material: u32) {
        let at = |i: u32, y: f32| {
            let a = std::f32::consts::TAU * (i % facets) as f32 / facets as f32;
            base + Vec3::new(radius * a.cos(), y, radius * a.sin())
        };
        for i in 0..facets {
            let (a, b, c, d) = (at(i, 0.0), at(i, height), at(i + 1, height), at(i + 1, 0.0));
            self.triangle([a, b, c], material);
            self.triangle([a, c, d], material);
        }
    }

    /// The scene, with a camera at `eye` looking at `at`.
    pub fn scene(self, eye: Vec3, at: Vec3) -> Scene {
        let parts = SceneParts {
            mesh: self.mesh,
            point_lights: Vec::new(),
            camera: Camera {
                position: eye,
                look_at: at,
                up: Vec3::Y,
                fov_y: 60.0,
                width: 16,
                height: 16,
            },
            two_sided: false,
            solver: SolverDefaults::default(),
        };
        Scene::from_parts("fixture", parts).unwrap_or_else(|e| panic!("{e}"))
    }
}

/// A mirror of reflectance `ks`.
pub(crate) fn mirror(ks: f32) -> Material {
    let mut m = Material::diffuse("mirror", Vec3::ZERO, Vec3::ZERO);
    m.kind = Kind::Specular {
        ks: Vec3::splat(ks),
        roughness: 0.0,
    };
    m
}

/// Smooth glass of index 1.5 (`thin`: a pane).
pub(crate) fn glass(thin: bool) -> Material {
    let mut m = Material::diffuse("glass", Vec3::ZERO, Vec3::ZERO);
    m.kind = Kind::Glass {
        ior: 1.5,
        transmit: Vec3::ONE,
        thin,
    };
    m
}
