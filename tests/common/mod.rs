//! Helpers shared by the integration tests: scenes built from parts, and running a test body
//! on every visibility backend.

#![allow(dead_code)]

pub mod counting;
pub mod mirror;

use std::path::PathBuf;

use glam::Vec3;
use meshlight::scene::{Camera, Material, Mesh, PointLight, SceneParts, SolverDefaults};
use meshlight::{Backend, Scene};

/// A specular material: Kd + Ks with roughness r (0: a mirror).
pub fn specular(name: &str, kd: f32, ks: f32, roughness: f32) -> Material {
    let mut m = Material::diffuse(name, Vec3::splat(kd), Vec3::ZERO);
    m.kind = meshlight::scene::Kind::Specular {
        ks: Vec3::splat(ks),
        roughness,
    };
    m
}

/// Smooth glass of index `ior`; `thin`: a one-face pane.
pub fn glass(name: &str, ior: f32, thin: bool) -> Material {
    let mut m = Material::diffuse(name, Vec3::ZERO, Vec3::ZERO);
    m.kind = meshlight::scene::Kind::Glass {
        ior,
        transmit: Vec3::ONE,
        thin,
    };
    m
}

/// A shipped scene's path.
pub fn shipped(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .join("scene.toml")
}

/// A shipped scene with its camera's image resized to `size` × `size` (references traced in
/// tests stay affordable).
pub fn shipped_at(name: &str, size: u32) -> Scene {
    let mut scene = Scene::load(shipped(name)).unwrap();
    let mut camera = *scene.camera();
    (camera.width, camera.height) = (size, size);
    scene.set_camera(camera).unwrap();
    scene
}

/// A diffuse material.
pub fn material(name: &str, kd: f32, ke: f32) -> Material {
    Material::diffuse(name, Vec3::splat(kd), Vec3::splat(ke))
}

/// Builds a mesh from quads.
#[derive(Default)]
pub struct Builder {
    pub mesh: Mesh,
    pub point_lights: Vec<PointLight>,
    /// Whether faces reflect on both sides (the scene file's `two_sided`).
    pub two_sided: bool,
}

impl Builder {
    /// Adds a material and returns its index.
    pub fn material(&mut self, m: Material) -> u32 {
        self.mesh.materials.push(m);
        self.mesh.materials.len() as u32 - 1
    }

    /// A quad a→b→c→d, counter-clockwise seen from its front.
    pub fn quad(&mut self, corners: [Vec3; 4], material: u32) {
        let base = self.mesh.positions.len() as u32;
        self.mesh.positions.extend(corners);
        self.mesh.triangles.push([base, base + 1, base + 2]);
        self.mesh.triangles.push([base, base + 2, base + 3]);
        self.mesh.triangle_materials.extend([material, material]);
    }

    /// An axis-aligned box seen from inside (faces pointing inwards), without the faces
    /// listed in `skip` ("-x", "+x", "-y", "+y", "-z", "+z").
    pub fn room(&mut self, lo: Vec3, hi: Vec3, material: u32, skip: &[&str]) {
        let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let (a, b) = (lo, hi);
        let faces = [
            (
                "-y",
                [
                    v(a.x, a.y, a.z),
                    v(a.x, a.y, b.z),
                    v(b.x, a.y, b.z),
                    v(b.x, a.y, a.z),
                ],
            ),
            (
                "+y",
                [
                    v(a.x, b.y, a.z),
                    v(b.x, b.y, a.z),
                    v(b.x, b.y, b.z),
                    v(a.x, b.y, b.z),
                ],
            ),
            (
                "-z",
                [
                    v(a.x, a.y, a.z),
                    v(b.x, a.y, a.z),
                    v(b.x, b.y, a.z),
                    v(a.x, b.y, a.z),
                ],
            ),
            (
                "+z",
                [
                    v(a.x, a.y, b.z),
                    v(a.x, b.y, b.z),
                    v(b.x, b.y, b.z),
                    v(b.x, a.y, b.z),
                ],
            ),
            (
                "-x",
                [
                    v(a.x, a.y, a.z),
                    v(a.x, b.y, a.z),
                    v(a.x, b.y, b.z),
                    v(a.x, a.y, b.z),
                ],
            ),
            (
                "+x",
                [
                    v(b.x, a.y, a.z),
                    v(b.x, a.y, b.z),
                    v(b.x, b.y, b.z),
                    v(b.x, b.y, a.z),
                ],
            ),
        ];
        for (name, corners) in faces {
            if !skip.contains(&name) {
                self.quad(corners, material);
            }
        }
    }

    /// A round column of `facets` flat facets facing out, radius `r`, from the floor to `h`,
    /// its axis at (cx, cz).
    pub fn round_column(&mut self, cx: f32, cz: f32, r: f32, h: f32, facets: u32, material: u32) {
        let at = |i: u32, y: f32| {
            let a = std::f32::consts::TAU * i as f32 / facets as f32;
            Vec3::new(cx + r * a.cos(), y, cz + r * a.sin())
        };
        for i in 0..facets {
            self.quad(
                [at(i, 0.0), at(i, h), at(i + 1, h), at(i + 1, 0.0)],
                material,
            );
        }
    }

    /// An axis-aligned box seen from outside (faces pointing out): a solid.
    pub fn solid(&mut self, lo: Vec3, hi: Vec3, material: u32) {
        let first = self.mesh.triangles.len();
        self.room(lo, hi, material, &[]);
        for t in &mut self.mesh.triangles[first..] {
            t.swap(1, 2);
        }
    }

    /// A faceted ball, as the gallery's sculptures are (their icosphere): an icosahedron whose
    /// faces are cut in four `detail` times, facing out.
    pub fn ball(&mut self, centre: Vec3, radius: f32, detail: u32, material: u32) {
        let (vertices, faces) = meshlight_gallery::unit_icosphere(detail);
        let base = self.mesh.positions.len() as u32;
        self.mesh.positions.extend(
            vertices
                .iter()
                .map(|&p| centre + radius * Vec3::from(p.map(|x| x as f32))),
        );
        for f in faces {
            self.mesh.triangles.push(f.map(|i| base + i as u32));
            self.mesh.triangle_materials.push(material);
        }
    }

    /// The scene, with a camera.
    pub fn scene(self, camera: Camera) -> Scene {
        let parts = SceneParts {
            mesh: self.mesh,
            point_lights: self.point_lights,
            camera,
            two_sided: self.two_sided,
            solver: SolverDefaults::default(),
        };
        Scene::from_parts("test scene", parts).unwrap_or_else(|e| panic!("{e}"))
    }
}

/// A small camera.
pub fn camera(position: Vec3, look_at: Vec3, size: u32) -> Camera {
    Camera {
        position,
        look_at,
        up: Vec3::Y,
        fov_y: 60.0,
        width: size,
        height: size,
    }
}

/// Solves a scene on a backend (the options' backend is replaced).
pub fn solve(scene: &Scene, backend: Backend, options: meshlight::Options) -> meshlight::Solution {
    solve_and_render(scene, backend, options, false).0
}

/// Solves a scene on a backend and renders its camera view.
pub fn solve_and_render(
    scene: &Scene,
    backend: Backend,
    options: meshlight::Options,
    render: bool,
) -> (meshlight::Solution, meshlight::Image) {
    let vis = backend.build(scene).unwrap();
    let solution = meshlight::solve(scene, vis.as_ref(), &options, &mut |_| {
        meshlight::solver::Control::Continue
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let image = if render {
        meshlight::render(
            scene,
            &solution,
            vis.as_ref(),
            &meshlight::RenderOptions::default(),
            &mut |_| meshlight::Control::Continue,
        )
        .unwrap()
        .0
    } else {
        meshlight::Image {
            width: 0,
            height: 0,
            pixels: Vec::new(),
        }
    };
    (solution, image)
}

/// Every backend in this build.
pub fn backends() -> Vec<Backend> {
    Backend::available()
}

/// Two rooms side by side, sharing one solid wall 0.2 thick and one continuous floor; a point
/// light in room A only; the camera in room B.
pub fn two_rooms() -> Scene {
    let mut builder = Builder::default();
    let white = builder.material(material("white", 0.8, 0.0));
    // Room A: x ∈ [0, 2]; room B: x ∈ [2.2, 4.2]; both y ∈ [0, 2], z ∈ [0, 2].
    builder.room(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 2.0, 2.0),
        white,
        &["-y"],
    );
    builder.room(
        Vec3::new(2.2, 0.0, 0.0),
        Vec3::new(4.2, 2.0, 2.0),
        white,
        &["-y"],
    );
    // One floor under both rooms and the wall between them.
    builder.quad(
        [
            Vec3::new(0., 0., 0.),
            Vec3::new(0., 0., 2.),
            Vec3::new(4.2, 0., 2.),
            Vec3::new(4.2, 0., 0.),
        ],
        white,
    );
    builder.point_lights.push(meshlight::scene::PointLight {
        position: Vec3::new(1.0, 1.5, 1.0),
        intensity: Vec3::splat(5.0),
    });
    builder.scene(camera(
        Vec3::new(4.0, 1.2, 1.0),
        Vec3::new(2.2, 0.6, 1.0),
        32,
    ))
}

/// Checks a solve of [`two_rooms`]: every sample of the dark room (x > 2.2) exactly 0, and
/// enough samples on both sides for that to mean something.
pub fn assert_dark_room_is_dark(s: &meshlight::Solution, label: &str) {
    let (mut dark, mut lit) = (0, 0);
    for k in 0..s.samples().len() {
        let x = s.samples().position()[k].x;
        if x > 2.2 {
            assert_eq!(
                s.radiosity()[k],
                glam::DVec3::ZERO,
                "{label}: sample {k} at {} in the dark room",
                s.samples().position()[k]
            );
            dark += 1;
        } else if x < 2.0 && s.radiosity()[k].x > 0.0 {
            lit += 1;
        }
    }
    assert!(
        dark > 100 && lit > 100,
        "{label}: {dark} dark, {lit} lit samples"
    );
}

/// A 6 × 4 × 6 m room with four columns 0.6 m across from floor to ceiling: round ones of
/// `facets` facets facing out, or square ones (`facets` 0), and a lamp under the ceiling.
pub fn hall_of_columns(facets: u32) -> Scene {
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.6, 0.0));
    b.room(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(6.0, 4.0, 6.0),
        grey,
        &[],
    );
    let (r, h) = (0.3f32, 4.0f32);
    for (cx, cz) in [(2.0, 2.0), (4.0, 2.0), (2.0, 4.0), (4.0, 4.0)] {
        if facets == 0 {
            b.solid(
                Vec3::new(cx - r, 0.0, cz - r),
                Vec3::new(cx + r, h, cz + r),
                grey,
            );
            continue;
        }
        b.round_column(cx, cz, r, h, facets, grey);
    }
    b.point_lights.push(meshlight::scene::PointLight {
        position: Vec3::new(3.0, 3.6, 3.0),
        intensity: glam::Vec3::splat(20.0),
    });
    let scene = b.scene(camera(
        Vec3::new(0.5, 1.6, 0.5),
        Vec3::new(3.0, 1.5, 3.0),
        32,
    ));
    // Every column facet faces out, away from its axis.
    let mut checked = 0;
    for s in scene.surfaces().iter().filter(|s| s.normal.y.abs() < 0.5) {
        let t = &scene.triangles()[s.triangles.start as usize];
        let c = (t.vertices[0] + t.vertices[1] + t.vertices[2]) / 3.0;
        let axis = Vec3::new((c.x / 2.0).round() * 2.0, c.y, (c.z / 2.0).round() * 2.0);
        if (0.2..0.5).contains(&(c - axis).length()) {
            assert!(s.normal.dot(c - axis) > 0.0, "a facet faces its axis");
            checked += 1;
        }
    }
    assert_eq!(checked, 4 * facets.max(4), "column sides checked");
    scene
}
