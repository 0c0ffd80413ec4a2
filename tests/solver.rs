//! The solver against answers known without it: the furnace, form factors of known shapes,
//! area conservation, energy balance, the inverse-square law, no light through walls,
//! determinism, and adaptive samples going where light changes.

mod common;

use common::{
    assert_dark_room_is_dark, backends, camera, material, shipped, solve, two_rooms, Builder,
};
use glam::{DVec3, Vec3};
use meshlight::scene::PointLight;
use meshlight::solver::{transfer, Control, Options, StopReason};
use meshlight::{Backend, Scene};

#[test]
fn furnace_every_sample_is_at_the_analytic_radiance() {
    // Closed cube, Kd 0.5, Ke 0.1 everywhere: L = Ke / (1 − Kd) = 0.2.
    let scene = Scene::load(shipped("box")).unwrap();
    for backend in backends() {
        let s = solve(
            &scene,
            backend,
            Options {
                tolerance: 1e-5,
                ..Options::default()
            },
        );
        assert_eq!(s.stop(), StopReason::Converged);
        let mut worst = 0.0f64;
        for b in s.radiosity() {
            let l = b / std::f64::consts::PI;
            worst = worst.max((l - DVec3::splat(0.2)).abs().max_element() / 0.2);
        }
        assert!(
            worst < 0.01,
            "{backend}: worst relative error {worst:.4} over {} samples",
            s.samples().len()
        );
    }
}

#[test]
fn every_preset_solves_the_furnace_within_its_tolerance() {
    // Each preset stops shooting with a share t of the emitted power unshot; in the furnace
    // that leaves the radiance short by about t of 0.2 (the unshot light would have been
    // amplified by 1/(1 − Kd) like the rest). Each must land within 2t + 0.5% of it.
    let scene = Scene::load(shipped("box")).unwrap();
    for preset in meshlight::Preset::ALL {
        let options = preset.options();
        let t = options.tolerance;
        for backend in backends() {
            let s = solve(&scene, backend, options.clone());
            assert_eq!(s.validate(), Ok(()), "{preset} on {backend}");
            assert_eq!(s.stop(), StopReason::Converged, "{preset} on {backend}");
            let worst = s
                .radiosity()
                .iter()
                .map(|b| {
                    ((b / std::f64::consts::PI) - DVec3::splat(0.2))
                        .abs()
                        .max_element()
                        / 0.2
                })
                .fold(0.0, f64::max);
            assert!(
                worst < 2.0 * t + 0.005,
                "{preset} on {backend}: worst relative error {worst:.5} (tolerance {t})"
            );
        }
    }
}

/// Flux arriving at the samples of `receiver` when every sample of `source` has radiosity 1,
/// through the meshless transfer (sample to sample), on every backend.
fn meshless_flux(scene: &Scene, source: u32, receiver: u32) -> Vec<f64> {
    backends()
        .into_iter()
        .map(|backend| {
            let vis = backend.build(scene).unwrap();
            let s = meshlight::solve(
                scene,
                vis.as_ref(),
                &Options {
                    rounds: 0,
                    ..Options::default()
                },
                &mut |_| Control::Continue,
            )
            .unwrap();
            let samples = &s.samples();
            let shooters: Vec<u32> = (0..samples.len() as u32)
                .filter(|&k| samples.surface(k as usize) == source)
                .collect();
            let h = transfer(scene, &s, vis.as_ref(), &shooters, DVec3::ONE).unwrap();
            (0..samples.len())
                .filter(|&k| samples.surface(k) == receiver && !samples.is_back(k))
                .map(|k| h[k].x * samples.area()[k])
                .sum()
        })
        .collect()
}

/// A unit square at height 1 facing down, and one at height 0 facing up: coaxial, parallel.
const UPPER_SQUARE: [Vec3; 4] = [
    Vec3::new(0., 0., 1.),
    Vec3::new(0., 1., 1.),
    Vec3::new(1., 1., 1.),
    Vec3::new(1., 0., 1.),
];
const LOWER_SQUARE: [Vec3; 4] = [
    Vec3::new(0., 0., 0.),
    Vec3::new(1., 0., 0.),
    Vec3::new(1., 1., 0.),
    Vec3::new(0., 1., 0.),
];

/// Two unit squares: `a` and `b`, both grey, no light.
fn two_squares(a: [Vec3; 4], b: [Vec3; 4]) -> Scene {
    let mut builder = Builder::default();
    let grey = builder.material(material("grey", 0.5, 0.0));
    builder.quad(a, grey);
    builder.quad(b, grey);
    builder.scene(camera(
        Vec3::new(3.0, 0.5, 0.5),
        Vec3::new(0.5, 0.5, 0.5),
        16,
    ))
}

#[test]
fn form_factor_of_parallel_coaxial_unit_squares() {
    // Unit squares at distance 1, facing each other: F = 0.199825 (the closed form for
    // coaxial rectangles). Measured +0.031%; the bound is 0.1%.
    let scene = two_squares(UPPER_SQUARE, LOWER_SQUARE);
    assert!((scene.surfaces()[0].normal - Vec3::NEG_Z).length() < 1e-6);
    for flux in meshless_flux(&scene, 0, 1) {
        assert!(
            (flux - 0.199825).abs() < 0.001 * 0.199825,
            "delivered {flux:.6}, expected 0.199825"
        );
    }
}

#[test]
fn form_factor_of_perpendicular_unit_squares_sharing_an_edge() {
    // Unit squares at a right angle along a common edge: F = 0.200044 (the closed form for
    // perpendicular rectangles). Measured +0.10%, three times the facing squares' error: the
    // point formula's second-order error in the middle range, which the row scales cannot
    // take out (docs/accuracy.md, what is left on cornell at Kd 0.95). The bound is 0.15%:
    // taking only the nearest cell exactly (+0.17%) or the near range to 1 √S (+0.20%)
    // fails it.
    let scene = two_squares(
        [
            Vec3::new(0., 0., 0.),
            Vec3::new(0., 1., 0.),
            Vec3::new(0., 1., 1.),
            Vec3::new(0., 0., 1.),
        ],
        LOWER_SQUARE,
    );
    for flux in meshless_flux(&scene, 0, 1) {
        assert!(
            (flux - 0.200044).abs() < 0.0015 * 0.200044,
            "delivered {flux:.6}, expected 0.200044"
        );
    }
}

#[test]
fn direct_light_from_an_area_light_delivers_its_form_factor() {
    // The upper square emits Ke = 1 (radiosity π) and reflects nothing; the lower one
    // receives π·F·A = π·0.1998.
    let mut builder = Builder::default();
    let light = builder.material(material("light", 0.0, 1.0));
    let grey = builder.material(material("grey", 0.5, 0.0));
    builder.quad(UPPER_SQUARE, light);
    builder.quad(LOWER_SQUARE, grey);
    let scene = builder.scene(camera(
        Vec3::new(3.0, 0.5, 0.5),
        Vec3::new(0.5, 0.5, 0.5),
        16,
    ));
    for backend in backends() {
        let s = solve(
            &scene,
            backend,
            Options {
                rounds: 0,
                ..Options::default()
            },
        );
        let flux: f64 = (0..s.samples().len())
            .map(|k| s.direct()[k].irradiance.x * s.samples().area()[k])
            .sum();
        let expected = std::f64::consts::PI * 0.1998;
        eprintln!(
            "{backend}: flux {flux:.5} vs {expected:.5}: {:+.3}%",
            100.0 * (flux / expected - 1.0)
        );
        assert!(
            (flux - expected).abs() < 0.02 * expected,
            "{backend}: {flux:.5} vs {expected:.5}"
        );
    }
}

#[test]
fn areas_are_conserved_per_surface_also_after_adaptive_rounds() {
    let scene = Scene::load(shipped("room")).unwrap();
    let s = solve(
        &scene,
        Backend::default_backend(),
        Options {
            rounds: 2,
            ..Options::default()
        },
    );
    assert!(
        s.rounds().len() >= 2 && s.rounds()[1].added > 0,
        "adaptive rounds added samples"
    );
    let per_side = s
        .samples()
        .area_per_side(2 * scene.surfaces().len())
        .unwrap();
    for (side, &area) in per_side.iter().enumerate() {
        if area > 0.0 {
            let expected = scene.surfaces()[side / 2].area;
            assert!(
                (area - expected).abs() <= 1e-3 * expected,
                "side {side}: {area} vs {expected}"
            );
        }
    }
    assert!(s.samples().area().iter().all(|&a| a >= 0.0));
}

/// An open scene: a 4 m × 4 m floor and a 4 m × 2 m wall along one edge, a point light.
fn open_scene() -> Scene {
    let mut builder = Builder::default();
    let floor = builder.material(material("floor", 0.5, 0.0));
    let wall = builder.material(material("wall", 0.8, 0.0));
    builder.quad(
        [
            Vec3::new(0., 0., 0.),
            Vec3::new(0., 0., 4.),
            Vec3::new(4., 0., 4.),
            Vec3::new(4., 0., 0.),
        ],
        floor,
    );
    builder.quad(
        [
            Vec3::new(0., 0., 0.),
            Vec3::new(4., 0., 0.),
            Vec3::new(4., 2., 0.),
            Vec3::new(0., 2., 0.),
        ],
        wall,
    );
    builder.point_lights.push(PointLight {
        position: Vec3::new(1.5, 1.5, 1.0),
        intensity: Vec3::splat(10.0),
    });
    builder.scene(camera(
        Vec3::new(2.0, 1.5, 6.0),
        Vec3::new(2.0, 0.5, 0.0),
        16,
    ))
}

/// Power (red channel) the samples reflect out of the scene: each sample's shot radiosity ×
/// area × the share of `rays` cosine-distributed rays (a stratified grid) that hit nothing.
fn reflected_escape(s: &meshlight::Solution, vis: &dyn meshlight::Visibility, rays: usize) -> f64 {
    let n = (rays as f64).sqrt() as usize;
    let mut out = 0.0;
    for k in 0..s.samples().len() {
        let normal = s.samples().normal()[k];
        let a = if normal.x.abs() < 0.9 {
            Vec3::X
        } else {
            Vec3::Y
        };
        let t = (a - normal * normal.dot(a)).normalize();
        let b = normal.cross(t);
        let origin = s.samples().position()[k] + normal * 1e-4;
        let batch: Vec<meshlight::visibility::Ray> = (0..n * n)
            .map(|i| {
                // Malley: a uniform point of the disc lifted onto the hemisphere.
                let (u, v) = (
                    ((i % n) as f32 + 0.5) / n as f32,
                    ((i / n) as f32 + 0.5) / n as f32,
                );
                let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
                let dir = t * (r * phi.cos()) + b * (r * phi.sin()) + normal * (1.0 - u).sqrt();
                meshlight::visibility::Ray {
                    origin,
                    dir,
                    t_min: 0.0,
                    t_max: f32::INFINITY,
                }
            })
            .collect();
        let mut hits = vec![None; batch.len()];
        vis.intersect(&batch, &mut hits).unwrap();
        let missed = hits.iter().filter(|h| h.is_none()).count() as f64 / batch.len() as f64;
        let shot = s.radiosity()[k].x - s.unshot()[k].x;
        out += shot * s.samples().area()[k] * missed;
    }
    out
}

/// Solid angle of the rectangle [x0, x1] × [z0, z1] of the plane at distance h from a point
/// straight above the origin (sum over corners of atan(x z / (h √(h² + x² + z²)))).
fn rectangle_solid_angle(x0: f64, x1: f64, z0: f64, z1: f64, h: f64) -> f64 {
    let f = |x: f64, z: f64| (x * z / (h * (h * h + x * x + z * z).sqrt())).atan();
    f(x1, z1) - f(x0, z1) - f(x1, z0) + f(x0, z0)
}

#[test]
fn energy_balance_in_an_open_scene() {
    let scene = open_scene();
    for backend in backends() {
        let s = solve(
            &scene,
            backend,
            Options {
                rounds: 0,
                tolerance: 1e-6,
                ..Options::default()
            },
        );
        let emitted = s.ledger().emitted.x;
        let absorbed = s.absorbed(&scene).x;
        let escaped = s.ledger().escaped.x;
        let unshot = s.unshot_power().x;
        let balance = (absorbed + escaped + unshot - emitted).abs() / emitted;
        assert!(balance < 1e-3, "{backend}: emitted {emitted} vs absorbed {absorbed} + escaped {escaped} + unshot {unshot}");
        assert!(
            escaped > 0.5 * emitted,
            "most light leaves an open scene: {escaped} of {emitted}"
        );

        // Escape measured, not defined as the remainder: the direct light missing floor and
        // wall is I × (4π − their solid angles); of what each sample reflects, the share that
        // leaves is the share of cosine-distributed rays from it that hit nothing.
        let omega_floor = rectangle_solid_angle(-1.5, 2.5, -1.0, 3.0, 1.5);
        let omega_wall = rectangle_solid_angle(-1.5, 2.5, -1.5, 0.5, 1.0);
        let direct_out = 10.0 * (4.0 * std::f64::consts::PI - omega_floor - omega_wall);
        let vis = backend.build(&scene).unwrap();
        let reflected_out = reflected_escape(&s, vis.as_ref(), 256);
        let measured = direct_out + reflected_out;
        assert!(
            (escaped - measured).abs() < 1e-3 * emitted,
            "{backend}: the ledger's escape {escaped:.4} vs measured {measured:.4} (direct {direct_out:.4} + reflected {reflected_out:.4}) of {emitted:.4}"
        );

        // Independently: the direct flux on the floor is I × its solid angle from the light.
        let floor_flux: f64 = (0..s.samples().len())
            .filter(|&k| s.samples().surface(k) == 0)
            .map(|k| s.direct()[k].irradiance.x * s.samples().area()[k])
            .sum();
        let exact = 10.0 * rectangle_solid_angle(-1.5, 2.5, -1.0, 3.0, 1.5);
        assert!(
            (floor_flux - exact).abs() < 2e-3 * exact,
            "{backend}: floor flux {floor_flux} vs {exact}"
        );
    }
}

#[test]
fn point_light_over_a_large_plane_follows_the_inverse_square_law() {
    let mut builder = Builder::default();
    let grey = builder.material(material("grey", 0.4, 0.0));
    builder.quad(
        [
            Vec3::new(-10., 0., -10.),
            Vec3::new(-10., 0., 10.),
            Vec3::new(10., 0., 10.),
            Vec3::new(10., 0., -10.),
        ],
        grey,
    );
    let light = Vec3::new(1.0, 2.0, -0.5);
    builder.point_lights.push(PointLight {
        position: light,
        intensity: Vec3::new(5.0, 10.0, 20.0),
    });
    let scene = builder.scene(camera(Vec3::new(0.0, 5.0, 12.0), Vec3::ZERO, 16));
    for backend in backends() {
        let s = solve(
            &scene,
            backend,
            Options {
                rounds: 0,
                ..Options::default()
            },
        );
        assert!(s.samples().len() > 1000);
        // By hand: a light at height h = 2 over the plane y = 0 gives E = I·cosθ/r² with
        // cosθ = h/r, so E = I·h/r³ with r² = (x − 1)² + h² + (z + 0.5)².
        let intensity = DVec3::new(5.0, 10.0, 20.0);
        let mut worst = 0.0f64;
        for k in 0..s.samples().len() {
            let p = s.samples().position()[k];
            let r = f64::from(((p.x - 1.0).powi(2) + 4.0 + (p.z + 0.5).powi(2)).sqrt());
            let expected = intensity * 2.0 / (r * r * r);
            let got = s.direct()[k].irradiance;
            worst = worst.max((got - expected).abs().max_element() / expected.max_element());
            assert!(
                (got - expected).abs().max_element() <= 1e-4 * expected.max_element(),
                "sample {k}: {got} vs {expected}"
            );
        }
        eprintln!(
            "worst relative error {worst:.2e} over {} samples",
            s.samples().len()
        );
    }
}

#[test]
fn no_light_leaks_through_a_shared_wall() {
    // The flat solver here; the hierarchy in tests/hierarchy.rs.
    let scene = two_rooms();
    for backend in backends() {
        let s = solve(
            &scene,
            backend,
            Options {
                rounds: 2,
                cluster_threshold: 0.0,
                ..Options::default()
            },
        );
        assert_dark_room_is_dark(&s, &format!("{backend}, flat"));
    }
}

#[test]
fn one_or_two_threads_give_bit_identical_radiosity() {
    let scene = Scene::load(shipped("room")).unwrap();
    let one = solve(
        &scene,
        Backend::default_backend(),
        Options {
            threads: 1,
            ..Options::default()
        },
    );
    let two = solve(
        &scene,
        Backend::default_backend(),
        Options {
            threads: 2,
            ..Options::default()
        },
    );
    assert_eq!(one.samples(), two.samples());
    assert!(
        one.radiosity() == two.radiosity(),
        "radiosity differs between 1 and 2 threads"
    );
}

// Without Embree there is nothing to compare: the test is left out rather than passed.
#[cfg(feature = "embree")]
#[test]
fn embree_and_obvhs_give_the_same_radiosity() {
    let scene = Scene::load(shipped("room")).unwrap();
    let options = Options {
        rounds: 0,
        ..Options::default()
    };
    let a = solve(&scene, Backend::Embree, options.clone());
    let b = solve(&scene, Backend::Bvh, options);
    assert_eq!(a.samples(), b.samples());
    let mean = a.radiosity().iter().map(|b| b.element_sum()).sum::<f64>()
        / (3 * a.radiosity().len()) as f64;
    for (k, (x, y)) in a.radiosity().iter().zip(b.radiosity()).enumerate() {
        let scale = x.abs().max(*y).max_element().max(mean);
        assert!(
            (*x - *y).abs().max_element() <= 1e-4 * scale,
            "sample {k}: {x} vs {y}"
        );
    }
}

#[test]
fn adaptive_rounds_put_samples_at_shadow_boundaries() {
    let scene = Scene::load(shipped("room")).unwrap();
    let s = solve(&scene, Backend::default_backend(), Options::default());
    let initial: Vec<usize> = (0..s.samples().len())
        .filter(|&k| s.samples().round()[k] == 0)
        .collect();
    // Penumbra: initial samples that see part of the light; the rest are fully lit or dark.
    let penumbra: Vec<usize> = initial
        .iter()
        .copied()
        .filter(|&k| s.direct()[k].visible > 0.02 && s.direct()[k].visible < 0.98)
        .collect();
    let other: Vec<usize> = initial
        .iter()
        .copied()
        .filter(|&k| !penumbra.contains(&k))
        .collect();
    // Samples now within ε of those initial samples, per initial sample.
    let eps2 = s.epsilon() * s.epsilon();
    let density = |group: &[usize]| -> f64 {
        let count: usize = group
            .iter()
            .map(|&g| {
                (0..s.samples().len())
                    .filter(|&k| {
                        (s.samples().surface(k), s.samples().is_back(k))
                            == (s.samples().surface(g), s.samples().is_back(g))
                            && s.samples().position()[k].distance_squared(s.samples().position()[g])
                                < eps2
                    })
                    .count()
            })
            .sum();
        count as f64 / group.len() as f64
    };
    let (near_shadow, elsewhere) = (density(&penumbra), density(&other));
    assert!(penumbra.len() > 20, "{} penumbra samples", penumbra.len());
    assert!(
        near_shadow > 2.0 * elsewhere,
        "samples per ε-disc: {near_shadow:.2} near shadow boundaries vs {elsewhere:.2} elsewhere"
    );
}

#[test]
fn a_dark_scene_is_all_zero_and_says_so() {
    let mut builder = Builder::default();
    let grey = builder.material(material("grey", 0.5, 0.0));
    builder.room(Vec3::ZERO, Vec3::ONE, grey, &[]);
    let scene = builder.scene(camera(Vec3::splat(0.5), Vec3::new(0.5, 0.5, 1.0), 8));
    let s = solve(&scene, Backend::default_backend(), Options::default());
    assert_eq!(s.stop(), StopReason::NoLight);
    assert!(s.radiosity().iter().all(|b| *b == DVec3::ZERO));
}

#[test]
fn a_stopped_solve_returns_its_current_estimate() {
    let scene = Scene::load(shipped("room")).unwrap();
    let vis = Backend::default_backend().build(&scene).unwrap();
    // The flat solver counts single shots; the hierarchy, sweeps of every sample at once.
    for (threshold, limit) in [(0.0, 64), (Options::default().cluster_threshold, 3)] {
        let mut reports = 0;
        let options = Options {
            cluster_threshold: threshold,
            ..Options::default()
        };
        let s = meshlight::solve(&scene, vis.as_ref(), &options, &mut |p| {
            reports += 1;
            if p.shots >= limit {
                Control::Stop
            } else {
                Control::Continue
            }
        })
        .unwrap();
        assert_eq!(s.stop(), StopReason::Stopped);
        assert_eq!(s.rounds().len(), 1);
        assert_eq!(s.rounds()[0].shooting.shots, limit, "threshold {threshold}");
        assert!(s.radiosity().iter().any(|b| b.x > 0.0));
        assert!(reports > 3);
    }
}

#[test]
fn too_small_an_epsilon_is_refused_before_allocating() {
    let scene = Scene::load(shipped("room")).unwrap();
    let vis = Backend::default_backend().build(&scene).unwrap();
    let options = Options {
        epsilon: Some(1e-4),
        ..Options::default()
    };
    let e = meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| Control::Continue)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("would place about") && e.contains("max_samples"),
        "{e}"
    );
}

/// Mean green radiosity of the ceiling's samples outside the light panel of `room` whose
/// distance to the panel's outline lies in `lo..hi` (metres).
fn ceiling_ring(s: &meshlight::Solution, lo: f32, hi: f32) -> f64 {
    let (mut sum, mut count) = (0.0, 0);
    for k in 0..s.samples().len() {
        let (p, n) = (s.samples().position()[k], s.samples().normal()[k]);
        if (p.y - 5.5).abs() > 1e-3 || n.y > -0.5 {
            continue;
        }
        // The panel: x 2.15..3.35, z 5.65..6.85, 1 cm under the ceiling.
        let dx = ((p.x - 2.75).abs() - 0.6).max(0.0);
        let dz = ((p.z - 6.25).abs() - 0.6).max(0.0);
        let d = dx.hypot(dz);
        if d >= lo && d < hi {
            sum += s.radiosity()[k].y;
            count += 1;
        }
    }
    assert!(
        count >= 10,
        "only {count} ceiling samples {lo}..{hi} m from the panel"
    );
    sum / f64::from(count)
}

#[test]
fn the_ceiling_beside_a_light_panel_is_not_darkened_by_the_dark_under_it() {
    // By hand: from a ceiling point d ≥ 5 cm beside the panel hanging 1 cm below, the panel
    // hides only directions less than atan(1/5) = 11.3° above the ceiling's plane on the side
    // facing it: at most ½·sin²(11.3°) = 1.9% of the cosine-weighted hemisphere. And these
    // points are nearer the bright floor under the light than the ring further out. So their
    // mean radiosity is at least 0.98 × the ring's at 25–60 cm. Interpolating new samples'
    // indirect light from old samples under the panel made the band 6–13% darker.
    let scene = Scene::load(shipped("room")).unwrap();
    for backend in backends() {
        for threshold in [0.05, 0.0] {
            let s = solve(
                &scene,
                backend,
                Options {
                    cluster_threshold: threshold,
                    ..Options::default()
                },
            );
            let (near, far) = (ceiling_ring(&s, 0.05, 0.25), ceiling_ring(&s, 0.25, 0.6));
            assert!(
                near >= 0.98 * far,
                "{backend:?}, threshold {threshold}: beside the panel {near:.4}, further out {far:.4}"
            );
        }
    }
}

/// A 4 × 3 × 4 m room (faces inwards) lit only by an uplight: a point light 0.3 m deep in an
/// open-topped shade 0.4 m square, whose cone (33.7° from the vertical) reaches the ceiling
/// within 1.6 m of its centre and nothing else: the walls and floor get only what the
/// ceiling (and the shade) send them. Material 0 is the room's, 1 the shade's.
fn uplit_room(two_sided: bool) -> Scene {
    let mut b = Builder {
        two_sided,
        ..Builder::default()
    };
    let room = b.material(material("room", 0.7, 0.0));
    let shade = b.material(material("shade", 0.5, 0.0));
    b.room(Vec3::ZERO, Vec3::new(4.0, 3.0, 4.0), room, &[]);
    b.room(
        Vec3::new(1.8, 0.6, 1.8),
        Vec3::new(2.2, 1.2, 2.2),
        shade,
        &["+y"],
    );
    b.point_lights.push(PointLight {
        position: Vec3::new(2.0, 0.9, 2.0),
        intensity: Vec3::splat(10.0),
    });
    b.scene(camera(
        Vec3::new(0.5, 1.5, 0.5),
        Vec3::new(3.0, 1.0, 3.0),
        32,
    ))
}

#[test]
fn light_reaches_the_sides_it_bounces_onto_and_not_the_room_s_outsides() {
    // Two-sided, the room's outer faces reflect too, but nothing reaches them; the walls and
    // floor inside are reached only by what the ceiling reflects, the shade's outside by
    // what the room reflects. Expected, by the geometry: the room's fronts, the shade's both
    // sides, nothing else.
    let scene = uplit_room(true);
    let expected: Vec<u32> = meshlight::solver::reflecting_sides(&scene)
        .into_iter()
        .filter(|&side| {
            let surface = &scene.surfaces()[(side / 2) as usize];
            surface.material == 1 || side % 2 == 0
        })
        .collect();
    assert_eq!(expected.len(), 6 + 2 * 5);
    for backend in backends() {
        let vis = backend.build(&scene).unwrap();
        let lit = meshlight::solver::lit_sides(&scene, vis.as_ref()).unwrap();
        assert_eq!(lit, expected, "{backend}");
    }
}

#[test]
fn a_two_sided_closed_room_is_solved_as_its_one_sided_self() {
    // A closed room (faces inwards) and a floating box (faces outwards), a lamp between: with
    // every face two-sided, the room's outsides and the box's insides are left without
    // samples, so the automatic ε, the samples and the image are the one-sided scene's (they
    // took half the samples and made ε √2 times coarser).
    let scene = |two_sided: bool| {
        let mut b = Builder {
            two_sided,
            ..Builder::default()
        };
        let white = b.material(material("white", 0.7, 0.0));
        // A glass listed but used by nothing (an MTL file's spare) changes nothing.
        b.material(common::glass("spare", 1.5, false));
        b.room(Vec3::ZERO, Vec3::new(4.0, 3.0, 4.0), white, &[]);
        b.solid(Vec3::new(2.5, 0.5, 2.5), Vec3::new(3.1, 1.1, 3.1), white);
        b.point_lights.push(PointLight {
            position: Vec3::new(1.5, 2.4, 1.5),
            intensity: Vec3::splat(10.0),
        });
        b.scene(camera(
            Vec3::new(0.5, 1.5, 0.5),
            Vec3::new(3.0, 1.0, 3.0),
            32,
        ))
    };
    let (one, two) = (scene(false), scene(true));
    for backend in backends() {
        let (a, image_a) = common::solve_and_render(&one, backend, Options::default(), true);
        let (b, image_b) = common::solve_and_render(&two, backend, Options::default(), true);
        assert_eq!(a.epsilon(), b.epsilon(), "{backend}: ε");
        assert_eq!(a.samples().len(), b.samples().len(), "{backend}: samples");
        let (ma, mb) = (image_a.mean(), image_b.mean());
        assert!(
            (ma / mb - 1.0).abs() < 1e-3,
            "{backend}: image means {ma} one-sided, {mb} two-sided"
        );
    }
}
