//! A host program embedding meshlight: it builds a scene from its own triangles in memory,
//! plugs in its own ray caster (brute force over the triangles), solves with a progress
//! callback that stops after a set number of shots, and renders the estimate so far.
//!
//! `cargo run --release --example embed` prints what it did; `tests/embed.rs` runs it and
//! checks it against the shipped backends.

use glam::Vec3;
use meshlight::scene::{Camera, Material, Mesh, PointLight, SceneParts, SolverDefaults};
use meshlight::solver::{Control, Options};
use meshlight::visibility::{Hit, Ray, Segment, SEGMENT_T_MAX, SEGMENT_T_MIN};
use meshlight::{Image, RenderOptions, Scene, Solution, Visibility};

/// The host's ray caster: every ray against every triangle (Möller–Trumbore).
pub struct BruteForce {
    triangles: Vec<[Vec3; 3]>,
}

impl BruteForce {
    /// Built from the loaded scene's triangles, in their order (hits name them by index).
    pub fn new(scene: &Scene) -> Self {
        BruteForce {
            triangles: scene.triangles().iter().map(|t| t.vertices).collect(),
        }
    }

    /// Distance along `dir` to triangle `v`, if the line meets it.
    fn hit(v: &[Vec3; 3], origin: Vec3, dir: Vec3) -> Option<f32> {
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            return None;
        }
        let s = origin - v[0];
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let w = dir.dot(q) / det;
        if u < 0.0 || w < 0.0 || u + w > 1.0 {
            return None;
        }
        Some(e2.dot(q) / det)
    }
}

impl Visibility for BruteForce {
    fn name(&self) -> &'static str {
        "brute-force"
    }

    fn occluded(&self, segments: &[Segment], out: &mut [bool]) -> meshlight::Result<()> {
        for (s, o) in segments.iter().zip(out) {
            let dir = s.b - s.a;
            *o = self.triangles.iter().any(|v| {
                Self::hit(v, s.a, dir).is_some_and(|t| (SEGMENT_T_MIN..=SEGMENT_T_MAX).contains(&t))
            });
        }
        Ok(())
    }

    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> meshlight::Result<()> {
        for (r, o) in rays.iter().zip(out) {
            *o = None;
            for (k, v) in self.triangles.iter().enumerate() {
                if let Some(t) = Self::hit(v, r.origin, r.dir) {
                    if t >= r.t_min && t <= r.t_max && o.is_none_or(|h| t < h.t) {
                        *o = Some(Hit {
                            t,
                            triangle: k as u32,
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

/// A 4 × 3 × 4 m room (walls Kd 0.6, a red wall), a 1 m² light under the ceiling and a lamp,
/// built from the host's own triangles.
pub fn host_scene() -> meshlight::Result<Scene> {
    let mut mesh = Mesh::default();
    let material = |name: &str, kd: Vec3, ke: f32| Material::diffuse(name, kd, Vec3::splat(ke));
    mesh.materials = vec![
        material("wall", Vec3::splat(0.6), 0.0),
        material("red", Vec3::new(0.6, 0.1, 0.1), 0.0),
        material("light", Vec3::ZERO, 5.0),
    ];
    // A quad (counter-clockwise from its front) as two triangles.
    let mut quad = |c: [Vec3; 4], m: u32| {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(c);
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
        mesh.triangle_materials.extend([m, m]);
    };
    let (x, y, z) = (4.0, 3.0, 4.0);
    let p = Vec3::new;
    // Faces point into the room.
    quad([p(0., 0., 0.), p(0., 0., z), p(x, 0., z), p(x, 0., 0.)], 0); // floor
    quad([p(0., y, 0.), p(x, y, 0.), p(x, y, z), p(0., y, z)], 0); // ceiling
    quad([p(0., 0., z), p(0., y, z), p(x, y, z), p(x, 0., z)], 0); // back
    quad([p(0., 0., 0.), p(x, 0., 0.), p(x, y, 0.), p(0., y, 0.)], 0); // front
    quad([p(0., 0., 0.), p(0., y, 0.), p(0., y, z), p(0., 0., z)], 1); // left, red
    quad([p(x, 0., 0.), p(x, 0., z), p(x, y, z), p(x, y, 0.)], 0); // right
    let h = y - 0.01;
    quad(
        [
            p(1.5, h, 1.5),
            p(2.5, h, 1.5),
            p(2.5, h, 2.5),
            p(1.5, h, 2.5),
        ],
        2,
    ); // light, facing down
    let camera = Camera {
        position: p(2.0, 1.5, 0.1),
        look_at: p(2.0, 1.2, 4.0),
        up: Vec3::Y,
        fov_y: 70.0,
        width: 48,
        height: 36,
    };
    let lamp = PointLight {
        position: p(3.0, 1.0, 3.0),
        intensity: Vec3::splat(2.0),
    };
    let parts = SceneParts {
        mesh,
        point_lights: vec![lamp],
        camera,
        two_sided: false,
        solver: SolverDefaults {
            epsilon: Some(0.4),
            ..SolverDefaults::default()
        },
    };
    Scene::from_parts("host room", parts)
}

/// What the host did: the solution, how many shots it allowed, what it saw and the image.
pub struct Run {
    /// The stopped solve.
    pub solution: Solution,
    /// The largest shot count reported before the host said stop.
    pub shots_seen: u64,
    /// How many progress reports came.
    pub reports: usize,
    /// The rendered estimate.
    pub image: Image,
}

/// Solves `scene` with `vis`, stopping after `max_shots` shots, and renders the estimate.
pub fn run(scene: &Scene, vis: &dyn Visibility, max_shots: u64) -> meshlight::Result<Run> {
    let options = Options {
        rounds: 1,
        threads: 2,
        ..Options::default()
    };
    let (mut shots_seen, mut reports) = (0, 0);
    let solution = meshlight::solve(scene, vis, &options, &mut |progress| {
        reports += 1;
        shots_seen = shots_seen.max(progress.shots);
        if progress.shots >= max_shots {
            Control::Stop
        } else {
            Control::Continue
        }
    })?;
    let render = RenderOptions {
        threads: 2,
        ..RenderOptions::default()
    };
    let (image, _) = meshlight::render(scene, &solution, vis, &render, &mut |_| {
        meshlight::Control::Continue
    })?;
    Ok(Run {
        solution,
        shots_seen,
        reports,
        image,
    })
}

#[allow(dead_code)] // tests/embed.rs includes this file for `run`, not `main`.
fn main() -> meshlight::Result<()> {
    let scene = host_scene()?;
    let vis = BruteForce::new(&scene);
    let done = run(&scene, &vis, 10)?;
    println!(
        "host room: {} triangles, {} samples; stopped after {} shots ({:?}), {} progress reports; \
         image {}x{}, mean radiance {:.4}",
        scene.triangles().len(),
        done.solution.samples().len(),
        done.shots_seen,
        done.solution.stop(),
        done.reports,
        done.image.width,
        done.image.height,
        done.image.mean()
    );
    Ok(())
}
