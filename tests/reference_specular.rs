//! The path tracer with mirrors, glossy surfaces and thin panes, against answers known without
//! it: a mirror wall is the room doubled, a point light's image in a mirror, the furnace with
//! specular reflection, a point light through a pane; and light sampling through mirrors and
//! panes changes the noise, not the answer.

mod common;

use std::f64::consts::PI;

use common::mirror::{facing_down, facing_up, mirror_room, v, wall_x, wall_z, Light};
use common::{backends, glass, material, specular, Builder};
use glam::{DVec3, Vec3};
use meshlight::reference::{path_trace, PathImage, PathOptions};
use meshlight::scene::{Camera, PointLight};
use meshlight::{Backend, Scene};

fn trace(scene: &Scene, backend: Backend, options: PathOptions) -> PathImage {
    let vis = backend.build(scene).unwrap();
    path_trace(scene, vis.as_ref(), &options, &mut |_| {
        meshlight::Control::Continue
    })
    .unwrap()
}

fn spp(spp: u32) -> PathOptions {
    PathOptions {
        spp,
        ..PathOptions::default()
    }
}

#[test]
#[ignore = "full tier: a reference comparison at many samples (cargo test -- --include-ignored)"]
fn an_ideal_mirror_wall_shows_the_room_doubled() {
    // Everything the unmirrored half sees of light by the mirror, it sees of the doubled room
    // through the plane x = 2: the two path-traced images agree but for noise. The camera
    // does not see the mirror, so every difference passes through inter-reflection and light
    // sampling by the mirror's image.
    for light in [Light::Area, Light::Point] {
        let name = match light {
            Light::Area => "area light",
            Light::Point => "point light",
        };
        let (mirrored, doubled) = (mirror_room(light, true), mirror_room(light, false));
        for backend in backends() {
            let a = trace(&mirrored, backend, spp(1024));
            let b = trace(&doubled, backend, spp(1024));
            let e = meshlight::metrics::compare_blocks(&a.image, &b.image, 4).unwrap();
            // Over 4 × 4 blocks each image's noise falls by about 4.
            let noise = (a.noise + b.noise) / 2.0 / 4.0;
            println!(
                "{backend}, {name}: MAE/mean over 4×4 blocks {:.4}, bias {:+.4}, pixel noise {:.4} and {:.4}",
                e.mae_over_mean, e.bias, a.noise, b.noise
            );
            // Noise alone then gives about √2 × 0.4% over blocks, and the means differ by
            // about 0.1% (σ).
            assert!(
                noise < 0.0045,
                "{backend}, {name}: noise {noise} over blocks"
            );
            assert!(
                e.mae_over_mean < 0.01 && e.bias.abs() < 0.004,
                "{backend}, {name}: MAE/mean {:.4} over 4×4 blocks",
                e.mae_over_mean
            );
        }
    }
}

#[test]
#[ignore = "full tier: a reference comparison at many samples (cargo test -- --include-ignored)"]
fn two_mirror_walls_in_a_corner_show_the_room_four_times() {
    // Mirrors at x = 2 and z = 2: the light has three images (one in each mirror, one in
    // both), so light sampling needs chains of two mirrors. The reference is the room
    // repeated to [0, 4] × [0, 4] with four lights.
    let build = |mirror: bool| {
        let mut b = Builder::default();
        let grey = b.material(material("grey", 0.6, 0.0));
        let end = if mirror { 2.0 } else { 4.0 };
        facing_up(&mut b, 0.0, [0.0, end], [0.0, end], grey);
        facing_down(&mut b, 2.0, [0.0, end], [0.0, end], grey);
        let far = if mirror {
            b.material(specular("mirror", 0.0, 1.0, 0.0))
        } else {
            grey
        };
        wall_x(&mut b, 0.0, [0.0, end], false, grey);
        wall_z(&mut b, 0.0, [0.0, end], false, grey);
        wall_x(&mut b, end, [0.0, end], true, far);
        wall_z(&mut b, end, [0.0, end], true, far);
        let lights: &[(f32, f32)] = if mirror {
            &[(1.4, 1.3)]
        } else {
            &[(1.4, 1.3), (2.6, 1.3), (1.4, 2.7), (2.6, 2.7)]
        };
        for &(x, z) in lights {
            b.point_lights.push(PointLight {
                position: v(x, 1.6, z),
                intensity: Vec3::splat(2.0),
            });
        }
        b.scene(common::camera(v(1.9, 1.1, 1.9), v(0.0, 0.7, 0.0), 32))
    };
    let (mirrored, repeated) = (build(true), build(false));
    for backend in backends() {
        let a = trace(&mirrored, backend, spp(1024));
        let b = trace(&repeated, backend, spp(1024));
        let e = meshlight::metrics::compare_blocks(&a.image, &b.image, 4).unwrap();
        println!(
            "{backend}: MAE/mean over 4×4 blocks {:.4}, bias {:+.4}, pixel noise {:.4} and {:.4}",
            e.mae_over_mean, e.bias, a.noise, b.noise
        );
        assert!((a.noise + b.noise) / 2.0 / 4.0 < 0.0045);
        assert!(
            e.mae_over_mean < 0.01 && e.bias.abs() < 0.004,
            "{backend}: {:.4}, bias {:+.4}",
            e.mae_over_mean,
            e.bias
        );
    }
}

#[test]
fn a_point_light_over_a_mirror_lights_a_target_by_its_image() {
    // A mirror (Ks 0.8) fills the plane y = 0; a point light of I = 3 W/sr at (0, 1, 0); a
    // small grey target (Kd 0.5) at height 0.5 faces down, so the light itself is behind it
    // and only its image (0, −1, 0) lights it: E = 0.8 I cosθ' / r'², cosθ' = 1.5 / r'. The
    // camera looks up at the target, which fills the view. The target also lights itself by
    // its own image (0.1 × 0.1 at distance 1: 0.8 · 0.5/π · 0.01 ≈ 0.13% more), and nothing
    // else does. (Shading points are lifted off their surface by 10⁻⁴ of the scene's
    // diagonal, 0.8 mm here: 0.06% more.)
    let mut b = Builder::default();
    let mirror = b.material(specular("mirror", 0.0, 0.8, 0.0));
    let grey = b.material(material("grey", 0.5, 0.0));
    facing_up(&mut b, 0.0, [-3.0, 3.0], [-3.0, 3.0], mirror);
    facing_down(&mut b, 0.5, [0.95, 1.05], [-0.05, 0.05], grey);
    let intensity = 3.0;
    b.point_lights.push(PointLight {
        position: v(0.0, 1.0, 0.0),
        intensity: Vec3::splat(intensity as f32),
    });
    let camera = Camera {
        position: v(1.0, 0.1, 0.0),
        look_at: v(1.0, 0.5, 0.0),
        up: Vec3::Z,
        fov_y: 8.0,
        width: 8,
        height: 8,
    };
    let scene = b.scene(camera);
    let c = scene.camera();
    let radiance = |x: f32, y: f32| -> f64 {
        let d = c.direction(x, y).as_dvec3();
        let o = c.position.as_dvec3();
        let p = o + d * ((0.5 - o.y) / d.y);
        assert!(
            (p.x - 1.0).abs() < 0.05 && p.z.abs() < 0.05,
            "{p} is off the target"
        );
        let to_image = DVec3::new(0.0, -1.0, 0.0) - p;
        let r = to_image.length();
        0.5 / PI * 0.8 * intensity * (1.5 / r) / (r * r)
    };
    for backend in backends() {
        let traced = trace(&scene, backend, spp(256));
        let mut worst: f64 = 0.0;
        for (i, p) in traced.image.pixels.iter().enumerate() {
            let (px, py) = ((i % 8) as f32, (i / 8) as f32);
            let expected: f64 = (0..16 * 16)
                .map(|k| {
                    radiance(
                        px + ((k % 16) as f32 + 0.5) / 16.0,
                        py + ((k / 16) as f32 + 0.5) / 16.0,
                    )
                })
                .sum::<f64>()
                / 256.0;
            let ratio = f64::from(p.x) / expected - 1.0;
            worst = if ratio.abs() > worst.abs() {
                ratio
            } else {
                worst
            };
            assert!(
                ratio.abs() <= 0.01,
                "{backend}: pixel {i}: {} vs {expected}",
                p.x
            );
        }
        // The target's centre (1, 0.5, 0) sees the image at r'² = 1 + 1.5², cos θ' = 1.5 / r'.
        let centre: f64 = [27, 28, 35, 36]
            .iter()
            .map(|&i| f64::from(traced.image.pixels[i].x))
            .sum::<f64>()
            / 4.0;
        println!(
            "{backend}: the four centre pixels {centre:.6}, by hand at the centre {:.6}, worst \
             pixel {worst:+.5}",
            0.5 / PI * 0.8 * intensity * 1.5 / 3.25f64.powf(1.5)
        );
    }
}

/// A closed box [0, 2]³ of one material emitting Ke 0.1 on every face, seen from its centre.
fn furnace(kd: f32, ks: f32, roughness: f32) -> Scene {
    let mut b = Builder::default();
    let mut m = specular("box", kd, ks, roughness);
    m.ke = Vec3::splat(0.1);
    let m = b.material(m);
    b.room(Vec3::ZERO, Vec3::splat(2.0), m, &[]);
    b.scene(common::camera(v(1.0, 1.0, 1.0), v(0.0, 1.0, 1.0), 24))
}

#[test]
fn the_furnace_with_mirrors_is_ke_over_one_minus_kd_minus_ks() {
    // Kd 0.3 + Ks 0.2 (an ideal mirror) with Ke 0.1 on every face: whatever arrives is 0.2·L
    // mirrored and 0.3·L diffused, so L = 0.1 / (1 − 0.5) = 0.2 at every pixel. Every face
    // is a mirror and an emitter: light sampling looks through chains of two of them, and
    // bounces between them must not count an emitter twice.
    let scene = furnace(0.3, 0.2, 0.0);
    for backend in backends() {
        let traced = trace(&scene, backend, spp(256));
        let mean = traced.image.mean();
        println!("{backend}: mean {mean:.5} (0.2), noise {:.4}", traced.noise);
        assert!(traced.noise < 0.02, "noise {}", traced.noise);
        assert!((mean - 0.2).abs() < 0.01 * 0.2, "{backend}: mean {mean}");
    }
}

/// GGX written out for the test (α = r², Smith's separable masking, F = 1), independent of the
/// crate: the albedo a(θo) = ∫ f_s cos θi dωi of a lobe, by quadrature over half vectors h
/// (dωi = 4 (ωo·h) dωh), θh spaced by the lobe's own distribution (tan θh = α √(u / (1 − u))).
fn ggx_albedo(alpha: f64, theta_o: f64) -> f64 {
    let a2 = alpha * alpha;
    let d = |cos_h: f64| {
        let t = cos_h * cos_h * (a2 - 1.0) + 1.0;
        a2 / (PI * t * t)
    };
    let g1 = |cos: f64| {
        if cos <= 0.0 {
            return 0.0;
        }
        let tan2 = (1.0 - cos * cos) / (cos * cos);
        2.0 / (1.0 + (1.0 + a2 * tan2).sqrt())
    };
    let wo = DVec3::new(theta_o.sin(), 0.0, theta_o.cos());
    let (nu, nphi) = (400, 400);
    let mut sum = 0.0;
    for i in 0..nu {
        let u = (i as f64 + 0.5) / nu as f64;
        let s = (u / (1.0 - u)).sqrt();
        let theta_h = (alpha * s).atan();
        // dθh/du = α (ds/du) / (1 + α² s²), ds/du = 1 / (2 √u (1 − u)^1.5).
        let dtheta = alpha / (2.0 * u.sqrt() * (1.0 - u).powf(1.5)) / (1.0 + a2 * s * s);
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) / nphi as f64 * 2.0 * PI;
            let h = DVec3::new(
                theta_h.sin() * phi.cos(),
                theta_h.sin() * phi.sin(),
                theta_h.cos(),
            );
            let oh = wo.dot(h);
            if oh <= 0.0 {
                continue;
            }
            let wi = 2.0 * oh * h - wo;
            if wi.z <= 0.0 {
                continue;
            }
            let f = d(h.z) * g1(wo.z) * g1(wi.z) / (4.0 * wo.z * wi.z);
            sum += f * wi.z * 4.0 * oh * theta_h.sin() * dtheta;
        }
    }
    sum / nu as f64 * (2.0 * PI / nphi as f64)
}

#[test]
fn the_furnace_with_a_glossy_lobe_follows_the_lobes_mean_albedo() {
    // Kd 0.3 + Ks 0.2 with roughness 0.3 (α = 0.09): single-scattering GGX reflects a(θo) < 1
    // of what arrives, so L(θo) = 0.1 + (0.3 + 0.2 a(θo)) L̄ with L̄ the radiance arriving. If
    // what arrives at a point were uniform it would be L̄ = 0.1 / (1 − 0.3 − 0.2 ā), ā the
    // cosine-weighted mean of a over θo (light leaving the box's faces, aggregated, leaves
    // cosine-weighted). Why that is good to 1% here: a(θo) lies in [0.987, 0.990] for θo
    // below 40° — every direction this camera sees, so the pixels are L̄ (1 + 0.2 (a − ā))
    // ≈ L̄ (1 + 0.25%) — and only grazing light (a down to 0.87 at 85°) differs much from ā,
    // so what arrives differs from uniform by a fraction of 0.2 |a − ā| ~ 0.5% at most,
    // halved again (×(0.3 + 0.2) per bounce) in what is reflected.
    let alpha = 0.3f64 * 0.3;
    let n = 90;
    let mean_albedo: f64 = (0..n)
        .map(|i| {
            let theta = (i as f64 + 0.5) / n as f64 * PI / 2.0;
            ggx_albedo(alpha, theta) * 2.0 * theta.cos() * theta.sin() * (PI / 2.0 / n as f64)
        })
        .sum();
    let at_0 = ggx_albedo(alpha, 0.0);
    let at_40 = ggx_albedo(alpha, 40f64.to_radians());
    assert!(
        (0.97..0.99).contains(&mean_albedo),
        "ā = {mean_albedo}: single scattering loses a little"
    );
    assert!((at_0 - at_40).abs() < 0.005, "a(0°) {at_0}, a(40°) {at_40}");
    let expected = 0.1 / (1.0 - 0.3 - 0.2 * mean_albedo);
    let scene = furnace(0.3, 0.2, 0.3);
    for backend in backends() {
        let traced = trace(&scene, backend, spp(256));
        let mean = traced.image.mean();
        println!(
            "{backend}: mean {mean:.5}, expected {expected:.5} (ā = {mean_albedo:.4}, a(0°) = \
             {at_0:.4}, a(40°) = {at_40:.4}), noise {:.4}",
            traced.noise
        );
        assert!(traced.noise < 0.02, "noise {}", traced.noise);
        assert!(
            (mean - expected).abs() < 0.01 * expected,
            "{backend}: mean {mean} vs {expected}"
        );
    }
}

/// Fresnel reflectance of an unpolarised ray from air into index `n` at cos θi (written out
/// for the tests).
fn fresnel(cos_i: f64, n: f64) -> f64 {
    let sin_t2 = (1.0 - cos_i * cos_i) / (n * n);
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    let rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// A pane's transmittance: 1 − 2R/(1 + R).
fn pane_transmittance(cos_i: f64, n: f64) -> f64 {
    let r = fresnel(cos_i, n);
    1.0 - 2.0 * r / (1.0 + r)
}

#[test]
fn a_point_light_through_a_thin_pane_is_dimmed_by_t_at_normal_incidence() {
    // A grey floor (Kd 0.5) at y = 0, a pane (Ni 1.5, 0.4 × 0.4) at y = 1, a point light of
    // 4 W/sr at y = 2 above both: straight below, L = Kd/π · T'(0) · I / r², T'(0) =
    // 1 − 2R/(1 + R), R = 0.04, r = 2. The camera, between pane and floor, looks straight down
    // at a spot 2 cm wide. What the pane reflects of the floor back onto it adds at most
    // Kd/π · R' · (solid angle of the pane, 0.16 sr) ≈ 0.2%; the lift of shading points off
    // the floor (10⁻⁴ of the scene's diagonal, 0.6 mm) 0.06%.
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.5, 0.0));
    let pane = b.material(glass("pane", 1.5, true));
    facing_up(&mut b, 0.0, [-2.0, 2.0], [-2.0, 2.0], grey);
    facing_up(&mut b, 1.0, [-0.2, 0.2], [-0.2, 0.2], pane);
    b.point_lights.push(PointLight {
        position: v(0.0, 2.0, 0.0),
        intensity: Vec3::splat(4.0),
    });
    let camera = Camera {
        position: v(0.0, 0.5, 0.0),
        look_at: Vec3::ZERO,
        up: Vec3::Z,
        fov_y: 2.0,
        width: 8,
        height: 8,
    };
    let scene = b.scene(camera);
    let r = 0.04;
    let t0 = 1.0 - 2.0 * r / (1.0 + r);
    let expected = 0.5 / PI * t0 * 4.0 / 4.0;
    assert!((pane_transmittance(1.0, 1.5) - t0).abs() < 1e-12);
    for backend in backends() {
        let traced = trace(&scene, backend, spp(64));
        let mean = traced.image.mean();
        println!(
            "{backend}: {mean:.6} vs Kd/π T'(0) I/r² = {expected:.6} (T'(0) = {t0:.6}), ratio {:.5}",
            mean / expected
        );
        assert!(
            (mean / expected - 1.0).abs() < 0.01,
            "{backend}: {mean} vs {expected}"
        );
    }
}

#[test]
fn an_area_light_through_a_thin_pane_matches_quadrature() {
    // An emitting square (Ke 3, 0.6 × 0.6, facing down) at y = 2 over a large pane (Ni 1.5) at
    // y = 1 over a grey floor (Kd 0.5): below the light's centre, L = Kd/π ∫ Ke T'(θ) cos θ
    // cos θ' / r² dA over the square, T' by Fresnel at the angle it crosses the pane. Light
    // sampling through the pane and paths through it (weighed against each other) both
    // find the light. Between pane and floor light bounces back: a grey floor's radiance times
    // R' ≈ 0.08, times Kd = 0.5, up to 4% of L more; so the floor is only a 0.1 × 0.1 grey
    // square the camera sees (its image in the pane: 0.0025 sr, 0.003% more).
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.5, 0.0));
    let pane = b.material(glass("pane", 1.5, true));
    let lamp = b.material(material("lamp", 0.0, 3.0));
    facing_up(&mut b, 0.0, [-0.05, 0.05], [-0.05, 0.05], grey);
    facing_up(&mut b, 1.0, [-1.5, 1.5], [-1.5, 1.5], pane);
    facing_down(&mut b, 2.0, [-0.3, 0.3], [-0.3, 0.3], lamp);
    let camera = Camera {
        position: v(0.0, 0.5, 0.0),
        look_at: Vec3::ZERO,
        up: Vec3::Z,
        fov_y: 2.0,
        width: 8,
        height: 8,
    };
    let scene = b.scene(camera);
    // The integral by the midpoint rule over the square.
    let n = 200;
    let mut e = 0.0;
    for i in 0..n {
        for j in 0..n {
            let x = -0.3 + 0.6 * (i as f64 + 0.5) / n as f64;
            let z = -0.3 + 0.6 * (j as f64 + 0.5) / n as f64;
            let r2 = x * x + z * z + 4.0;
            let cos = 2.0 / r2.sqrt();
            e += 3.0 * pane_transmittance(cos, 1.5) * cos * cos / r2;
        }
    }
    let expected = 0.5 / PI * e * (0.6 * 0.6) / (n * n) as f64;
    for backend in backends() {
        let traced = trace(&scene, backend, spp(256));
        let mean = traced.image.mean();
        println!(
            "{backend}: {mean:.6} vs quadrature {expected:.6}, ratio {:.5}, noise {:.4}",
            mean / expected,
            traced.noise
        );
        assert!(
            (mean / expected - 1.0).abs() < 0.01,
            "{backend}: {mean} vs {expected}"
        );
    }
}

#[test]
fn light_sampling_through_mirrors_changes_the_noise_not_the_answer() {
    // One room with everything specular the path tracer knows: a mirror wall with Kd, a
    // glossy floor, a thin pane across the room, a small area light. Light sampling through
    // chains of mirrors (mirror_depth 2) or none (0: paths alone find the light by the mirror
    // and the pane's reflection) must give the same image but for noise.
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.6, 0.0));
    let glossy = b.material(specular("glossy", 0.3, 0.5, 0.2));
    let mirror = b.material(specular("mirror", 0.2, 0.7, 0.0));
    let pane = b.material(glass("pane", 1.5, true));
    let lamp = b.material(material("lamp", 0.0, 2.0));
    facing_up(&mut b, 0.0, [0.0, 2.0], [0.0, 2.0], glossy);
    facing_down(&mut b, 2.0, [0.0, 2.0], [0.0, 2.0], grey);
    wall_z(&mut b, 0.0, [0.0, 2.0], false, grey);
    wall_z(&mut b, 2.0, [0.0, 2.0], true, grey);
    wall_x(&mut b, 0.0, [0.0, 2.0], false, grey);
    wall_x(&mut b, 2.0, [0.0, 2.0], true, mirror);
    // The pane across the room at z = 1.4, up to y = 1.5.
    b.quad(
        [
            v(0., 0., 1.4),
            v(2., 0., 1.4),
            v(2., 1.5, 1.4),
            v(0., 1.5, 1.4),
        ],
        pane,
    );
    facing_down(&mut b, 1.98, [1.0, 1.8], [1.5, 1.9], lamp);
    let scene = b.scene(common::camera(v(0.3, 1.2, 0.2), v(2.0, 0.5, 1.6), 32));
    for backend in backends() {
        let run = |depth| {
            trace(
                &scene,
                backend,
                PathOptions {
                    spp: 512,
                    mirror_depth: depth,
                    ..PathOptions::default()
                },
            )
        };
        let (with, without) = (run(2), run(0));
        let e = meshlight::metrics::compare_blocks(&with.image, &without.image, 4).unwrap();
        let bias = with.image.mean() / without.image.mean() - 1.0;
        // What noise alone gives: each image's expected MAE/mean is its noise estimate; over
        // 4 × 4 blocks a quarter of it; the two independent, in quadrature. The means of 1,024
        // pixels: σ ≈ 1.25 × MAE / 32 per image.
        let blocks = with.noise.hypot(without.noise) / 4.0;
        let mean = 1.25 * with.noise.hypot(without.noise) / 32.0;
        println!(
            "{backend}: MAE/mean over 4×4 blocks {:.4} (noise alone: {blocks:.4}), bias \
             {bias:+.4} (σ {mean:.4}), pixel noise {:.4} (depth 2) and {:.4} (depth 0)",
            e.mae_over_mean, with.noise, without.noise
        );
        assert!(
            with.noise < without.noise,
            "light sampling through mirrors should help"
        );
        assert!(
            e.mae_over_mean < 1.3 * blocks && bias.abs() < 4.0 * mean,
            "{backend}: MAE/mean {:.4}, bias {bias:+.4}",
            e.mae_over_mean
        );
    }
}

#[test]
fn lossless_glass_panes_and_mirrors_leave_a_uniform_furnace_uniform() {
    // A closed box whose walls emit Ke 0.5 and reflect Kd 0.5: L = 0.5 / (1 − 0.5) = 1
    // everywhere. Inside, nothing that absorbs: a glass cube (Ni 1.5: R + T = 1, radiance
    // ×1/η² in and ×η² out), a thin pane (R' + T' = 1), a two-sided ideal mirror (Ks 1). In a
    // uniform field each passes or returns radiance 1, so every pixel — walls, and walls seen
    // through glass, pane and mirror — is 1. Light sampling at the walls is blocked by the
    // cube, dimmed by the pane and looks through mirror and pane; paths through them find
    // the walls' emission the rest of the way: only counting every path once gives 1.
    let mut b = Builder::default();
    let wall = b.material(material("wall", 0.5, 0.5));
    let cube = b.material(glass("glass", 1.5, false));
    let pane = b.material(glass("pane", 1.5, true));
    let mut mirror = specular("mirror", 0.0, 1.0, 0.0);
    mirror.two_sided = true;
    let mirror = b.material(mirror);
    b.room(Vec3::ZERO, Vec3::splat(3.0), wall, &[]);
    // The cube, faces out.
    let first = b.mesh.triangles.len();
    b.room(v(0.4, 0.4, 1.6), v(1.3, 1.3, 2.5), cube, &[]);
    for t in &mut b.mesh.triangles[first..] {
        t.swap(1, 2);
    }
    // The pane across the right half, the mirror upright at the back right.
    b.quad(
        [
            v(1.6, 0.2, 1.4),
            v(2.8, 0.2, 1.4),
            v(2.8, 2.4, 1.4),
            v(1.6, 2.4, 1.4),
        ],
        pane,
    );
    b.quad(
        [
            v(1.7, 0.3, 2.7),
            v(1.7, 2.2, 2.7),
            v(2.6, 2.2, 2.2),
            v(2.6, 0.3, 2.2),
        ],
        mirror,
    );
    let scene = b.scene(common::camera(v(1.5, 1.4, 0.1), v(1.5, 1.0, 2.0), 24));
    for backend in backends() {
        let traced = trace(&scene, backend, spp(512));
        let mean = traced.image.mean();
        println!("{backend}: mean {mean:.5} (1), noise {:.4}", traced.noise);
        // The mean of 576 pixels: σ ≈ 1.25 × noise / 24 ≈ 0.15%.
        assert!(traced.noise < 0.03, "noise {}", traced.noise);
        assert!((mean - 1.0).abs() < 0.01, "{backend}: mean {mean}");
    }
}
