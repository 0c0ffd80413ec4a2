//! Prints the figures `docs/validation.md`'s "At the extremes" quotes (scale and light invariance,
//! brighter walls, one sample per surface, albedo 0.99): `cargo run --release --example extremes`.

use meshlight::solver::{Control, Options};
use meshlight::{Backend, Image, RenderOptions, Scene, Solution};

fn run(scene: &Scene, options: &Options) -> meshlight::Result<(Solution, Image)> {
    let vis = Backend::default_backend().build(scene)?;
    let solution = meshlight::solve(scene, vis.as_ref(), options, &mut |_| Control::Continue)?;
    let image = meshlight::render(
        scene,
        &solution,
        vis.as_ref(),
        &RenderOptions::default(),
        &mut |_| meshlight::Control::Continue,
    )?
    .0;
    Ok((solution, image))
}

/// Σ|a − b·f| / Σ|b·f| over pixels and channels.
fn relative(a: &Image, b: &Image, f: f64) -> f64 {
    let (mut diff, mut sum) = (0.0, 0.0);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        diff += (p.as_dvec3() - q.as_dvec3() * f).abs().element_sum();
        sum += (q.as_dvec3() * f).abs().element_sum();
    }
    diff / sum
}

fn main() -> meshlight::Result<()> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let room = Scene::load(dir.join("room/scene.toml"))?;
    let one_round = Options {
        rounds: 1,
        ..Options::default()
    };
    let (_, reference) = run(&room, &one_round)?;
    for s in [1e-3f32, 1e3] {
        let (_, image) = run(&room.scaled(s)?, &one_round)?;
        println!(
            "scene scaled by {s}: MAE/mean {:.2e}",
            relative(&image, &reference, 1.0)
        );
    }
    let (_, default) = run(&room, &Options::default())?;
    for f in [1e-6f32, 1e6] {
        let (_, image) = run(&room.with_lights_scaled(f)?, &Options::default())?;
        println!(
            "lights × {f}: relative difference {:.2e}",
            relative(&image, &default, f64::from(f))
        );
    }
    let white = room
        .materials()
        .iter()
        .position(|m| m.name == "white")
        .expect("room has white");
    for kd in [0.725f32, 0.85, 0.95] {
        let mut scene = room.clone();
        {
            let mut m = scene.materials()[white].clone();
            m.kd = glam::Vec3::splat(kd);
            scene.set_material(white, m).unwrap();
        }
        let (s, image) = run(
            &scene,
            &Options {
                rounds: 0,
                ..Options::default()
            },
        )?;
        println!(
            "white walls Kd {kd}: mean radiance {:.5}, {:?}",
            image.mean(),
            s.stop()
        );
    }
    let coarse = Options {
        epsilon: Some(100.0),
        rounds: 0,
        ..Options::default()
    };
    let (s, image) = run(&room, &coarse)?;
    println!(
        "ε = 100: {} samples, mean radiance {:.2} of the default solve's",
        s.samples().len(),
        image.mean() / default.mean()
    );
    let mut bright = Scene::load(dir.join("box/scene.toml"))?;
    let mut white = bright.materials()[0].clone();
    white.kd = glam::Vec3::splat(0.99);
    bright.set_material(0, white)?;
    let expected = 0.1 / (1.0 - 0.99);
    let t = std::time::Instant::now();
    let tight = Options {
        tolerance: 1e-4,
        max_shots: Some(2_000_000),
        ..Options::default()
    };
    let (s, image) = run(&bright, &tight)?;
    let worst = s
        .radiosity()
        .iter()
        .map(|b| (b.x / std::f64::consts::PI / expected - 1.0).abs())
        .fold(0.0, f64::max);
    let worst_pixel = image
        .pixels
        .iter()
        .map(|p| (f64::from(p.x) / expected - 1.0).abs())
        .fold(0.0, f64::max);
    let shots: u64 = s.rounds().iter().map(|r| r.shooting.shots).sum();
    println!(
        "albedo 0.99 box: worst sample {worst:.1e}, worst pixel {worst_pixel:.1e} off Ke/(1-ρ); {shots} shots, {:?}, {:.2} s",
        s.stop(),
        t.elapsed().as_secs_f64()
    );
    // The flat solver shoots one sample at a time, the hierarchy every sample at once: their
    // shot limits count different things.
    for (solver, threshold, shots) in [
        ("hierarchy", Options::default().cluster_threshold, 50),
        ("flat solver", 0.0, 5000),
    ] {
        let (s, _) = run(
            &bright,
            &Options {
                max_shots: Some(shots),
                rounds: 0,
                cluster_threshold: threshold,
                ..Options::default()
            },
        )?;
        println!(
            "albedo 0.99 box, {solver}, {shots} shots: {:?}, unshot fraction {:.3}, L {:.2} (converged: 10)",
            s.stop(),
            s.rounds()[0].shooting.unshot_fraction,
            s.radiosity()[0].x / std::f64::consts::PI
        );
    }
    Ok(())
}
