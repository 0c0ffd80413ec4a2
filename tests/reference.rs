//! The path tracer, the reference everything else is measured against, against answers known
//! without it: the furnace, a point light over a plane, its own noise estimate, and the same
//! image for any thread count. Then the meshless solver against it.

mod common;

use common::{backends, camera, material, shipped, Builder};
use glam::{DVec3, Vec3};
use meshlight::reference::{path_trace, PathImage, PathOptions};
use meshlight::scene::PointLight;
use meshlight::{Backend, Scene};

/// [`trace`] at `spp` samples per pixel, the other options their defaults.
fn trace_spp(scene: &Scene, backend: Backend, spp: u32) -> PathImage {
    trace(
        scene,
        backend,
        PathOptions {
            spp,
            ..PathOptions::default()
        },
    )
}

fn trace(scene: &Scene, backend: Backend, options: PathOptions) -> PathImage {
    let vis = backend.build(scene).unwrap();
    path_trace(scene, vis.as_ref(), &options, &mut |_| {
        meshlight::Control::Continue
    })
    .unwrap()
}

/// A shipped scene with a smaller image.
fn small(name: &str, size: u32) -> Scene {
    let mut scene = Scene::load(shipped(name)).unwrap();
    let camera = meshlight::scene::Camera {
        width: size,
        height: size,
        ..*scene.camera()
    };
    scene.set_camera(camera).unwrap();
    scene
}

#[test]
fn furnace_is_ke_over_one_minus_kd_everywhere() {
    // Closed cube, Kd 0.5, Ke 0.1 on every face: L = 0.1 / (1 − 0.5) = 0.2 at every pixel.
    let scene = small("box", 32);
    for backend in backends() {
        let traced = trace(
            &scene,
            backend,
            PathOptions {
                spp: 512,
                ..PathOptions::default()
            },
        );
        let mean = traced.image.mean();
        let mae = traced
            .image
            .pixels
            .iter()
            .map(|p| (p.as_dvec3() - DVec3::splat(0.2)).abs().element_sum() / 3.0)
            .sum::<f64>()
            / traced.image.pixels.len() as f64
            / 0.2;
        assert!(
            traced.noise > 0.0 && traced.noise < 0.02,
            "noise {}",
            traced.noise
        );
        // The image's error is its noise, within a third of it, and the mean within 1%.
        assert!(
            (mae - traced.noise).abs() < 0.35 * traced.noise,
            "{backend}: MAE/mean {mae:.5} against the noise estimate {:.5}",
            traced.noise
        );
        assert!((mean - 0.2).abs() < 0.01 * 0.2, "{backend}: mean {mean}");
    }
}

/// A grey plane 40 m square lit by a point light of intensity 7 at `light`, seen from `eye`
/// towards `look_at` (24 × 24 pixels), and each pixel's analytic radiance averaged over the pixel (box filter)
/// on a 16 × 16 grid: Kd/π · I · cosθ / r² where the ray lands.
fn point_light_over_a_plane(light: Vec3, eye: Vec3, look_at: Vec3) -> (Scene, Vec<f64>) {
    let mut builder = Builder::default();
    let grey = builder.material(material("grey", 0.5, 0.0));
    builder.quad(
        [
            Vec3::new(-20., 0., -20.),
            Vec3::new(-20., 0., 20.),
            Vec3::new(20., 0., 20.),
            Vec3::new(20., 0., -20.),
        ],
        grey,
    );
    let intensity = 7.0;
    builder.point_lights.push(PointLight {
        position: light,
        intensity: Vec3::splat(intensity),
    });
    let scene = builder.scene(camera(eye, look_at, 24));
    let c = &scene.camera();
    let radiance = |x: f32, y: f32| -> f64 {
        let d = c.direction(x, y).as_dvec3();
        let o = c.position.as_dvec3();
        if d.y >= 0.0 {
            return 0.0;
        }
        let p = o + d * (-o.y / d.y);
        let to = light.as_dvec3() - p;
        if p.x.abs() > 20.0 || p.z.abs() > 20.0 {
            return 0.0;
        }
        0.5 / std::f64::consts::PI * f64::from(intensity) * (to.y / to.length())
            / to.length_squared()
    };
    let expected = (0..24 * 24)
        .map(|i| {
            let (px, py) = ((i % 24) as f32, (i / 24) as f32);
            (0..16 * 16)
                .map(|k| {
                    radiance(
                        px + ((k % 16) as f32 + 0.5) / 16.0,
                        py + ((k / 16) as f32 + 0.5) / 16.0,
                    )
                })
                .sum::<f64>()
                / 256.0
        })
        .collect();
    (scene, expected)
}

#[test]
fn a_point_light_over_a_plane_gives_kd_over_pi_times_i_cos_over_r_squared() {
    let (scene, expected) = point_light_over_a_plane(
        Vec3::new(0.3, 1.5, -0.2),
        Vec3::new(0.0, 3.0, 2.5),
        Vec3::ZERO,
    );
    for backend in backends() {
        let traced = trace_spp(&scene, backend, 256);
        for (i, (p, &expected)) in traced.image.pixels.iter().zip(&expected).enumerate() {
            let got = f64::from(p.x);
            assert!(
                (got - expected).abs() <= 0.01 * expected + 1e-9,
                "{backend}: pixel {i}: {got} vs {expected}"
            );
        }
    }
}

#[test]
fn a_point_light_just_over_a_plane_is_measured_from_the_plane_not_from_the_lifted_point() {
    // 0.15 m over a plane 40 m across: the shadow rays leave 5.7 mm above the plane (10⁻⁴ of
    // the scene's diagonal), and measured from there the pool under the light read 2 × 5.7 /
    // 150 = 7.6% too bright at its centre (+5.3% over the 3 × 3 pixels below).
    let (scene, expected) = point_light_over_a_plane(
        Vec3::new(0.3, 0.15, -0.2),
        Vec3::new(0.3, 1.0, 0.6),
        Vec3::new(0.3, 0.0, -0.2),
    );
    // The pool: the 3 × 3 pixels about the brightest (a pixel is about 6 cm on the plane;
    // further out the lifted point reads the light too dim, and over the whole plane the
    // lift changes nothing).
    let peak = (0..expected.len())
        .max_by(|&a, &b| expected[a].total_cmp(&expected[b]))
        .unwrap();
    let pool: Vec<usize> = (0..expected.len())
        .filter(|&i| (i % 24).abs_diff(peak % 24) <= 1 && (i / 24).abs_diff(peak / 24) <= 1)
        .collect();
    let sum = |values: &dyn Fn(usize) -> f64| pool.iter().map(|&i| values(i)).sum::<f64>();
    let exact = sum(&|i| expected[i]);
    for backend in backends() {
        let traced = trace_spp(&scene, backend, 256);
        let got = sum(&|i| f64::from(traced.image.pixels[i].x));
        assert!(
            (got / exact - 1.0).abs() < 0.01,
            "{backend}: the pool's sum {got} against {exact} ({:+.2}%)",
            100.0 * (got / exact - 1.0)
        );
    }
}

#[test]
fn two_seeds_agree_within_three_times_their_noise_and_threads_do_not_matter() {
    let scene = small("room", 48);
    let run = |seed, threads| {
        trace(
            &scene,
            Backend::default_backend(),
            PathOptions {
                spp: 64,
                seed,
                threads,
                ..PathOptions::default()
            },
        )
    };
    let (a, b) = (run(1, 2), run(2, 2));
    let e = meshlight::metrics::compare(&a.image, &b.image).unwrap();
    // Two independent images differ by √2 times each one's error: their noise estimates say
    // how much.
    let expected = std::f64::consts::SQRT_2 * 0.5 * (a.noise + b.noise);
    assert!(
        e.mae_over_mean < 3.0 * expected && e.mae_over_mean > expected / 3.0,
        "MAE/mean between seeds {:.4}, noise estimates {:.4} and {:.4}",
        e.mae_over_mean,
        a.noise,
        b.noise
    );
    let one = run(1, 1);
    assert!(one.image == a.image, "1 and 2 threads differ");
    assert_eq!(one.halves, a.halves);
}

#[test]
#[ignore = "full tier: a reference comparison at many samples (cargo test -- --include-ignored)"]
fn meshless_room_is_within_two_percent_of_the_path_tracer_without_bias() {
    // A reduced room: 128 × 128 pixels (smaller, the edges of the light dominate the error),
    // the path tracer at 1024 samples per pixel (noise under 1%), the meshless solver at its
    // defaults on every backend.
    let scene = small("room", 128);
    let reference = trace(
        &scene,
        Backend::default_backend(),
        PathOptions {
            spp: 1024,
            ..PathOptions::default()
        },
    );
    assert!(reference.noise < 0.01, "noise {}", reference.noise);
    for backend in backends() {
        let (_, image) =
            common::solve_and_render(&scene, backend, meshlight::Options::default(), true);
        let e = meshlight::metrics::compare(&image, &reference.image).unwrap();
        let bias = image.mean() / reference.image.mean() - 1.0;
        assert!(
            e.mae_over_mean <= 0.02 && bias.abs() <= 0.005,
            "{backend}: MAE/mean {:.4}, bias {:+.4} (path tracer noise {:.4})",
            e.mae_over_mean,
            bias,
            reference.noise
        );
    }
}

/// A shipped scene at `size` × `size` with its white material at Kd 0.95: light is reflected
/// about twenty times, so a small shortfall in what the lights deliver shows.
fn white_at_0_95(name: &str, size: u32) -> Scene {
    let mut scene = small(name, size);
    let white = scene
        .materials()
        .iter()
        .position(|m| m.name == "white")
        .unwrap();
    let mut m = scene.materials()[white].clone();
    m.kd = Vec3::splat(0.95);
    scene.set_material(white, m).unwrap();
    scene
}

#[test]
#[ignore = "full tier: a reference comparison at many samples (cargo test -- --include-ignored)"]
fn at_albedo_0_95_the_meshless_mean_is_within_0_15_percent_of_the_path_tracer() {
    // The solver at its defaults (hierarchy, adaptive rounds, seed 1) against the path tracer
    // at 4,096 samples per pixel (two seeds' means differed by 0.02% on both scenes). With the
    // direct light measured at the sample points and not balanced against the lights' power,
    // `cornell` was −0.20% (−0.195% at 128² against 8,192 spp); balanced, −0.06%. `room`
    // +0.10% before and after.
    for name in ["cornell", "room"] {
        let scene = white_at_0_95(name, 64);
        let reference = trace(
            &scene,
            Backend::default_backend(),
            PathOptions {
                spp: 4096,
                ..PathOptions::default()
            },
        );
        for backend in backends() {
            let (_, image) =
                common::solve_and_render(&scene, backend, meshlight::Options::default(), true);
            let bias = image.mean() / reference.image.mean() - 1.0;
            eprintln!("{name}, {backend}: bias {:+.4}%", 100.0 * bias);
            assert!(
                bias.abs() <= 0.0015,
                "{name}, {backend}: bias {:+.4}% (path tracer noise per pixel {:.4})",
                100.0 * bias,
                reference.noise
            );
        }
    }
}
