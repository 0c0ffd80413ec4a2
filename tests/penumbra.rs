//! Penumbrae against a closed form: a square light, a shelf whose straight edge casts a metre-
//! wide penumbra on the floor, every surface black so that the floor's irradiance is the direct
//! light alone. The visible part of the light from a floor point is a rectangle, whose
//! irradiance has a closed form (the form factor from a point to a parallel rectangle); the
//! rendered irradiance in the penumbra must follow it pixel by pixel: hits next to one whose 16
//! shadow rays disagree are traced again with 64, and the rims must carry no bias.

mod common;

use common::{backends, camera, material, Builder};
use glam::Vec3;
use meshlight::visibility::Ray;
use meshlight::{Backend, Control, Direct, Options, Quantity, RenderOptions, Scene};

/// The light: [LIGHT.0, LIGHT.1]² in x and z, at this height, facing down.
const LIGHT: (f32, f32) = (1.5, 2.5);
const LIGHT_Y: f32 = 2.99;
/// The shelf covers x < SHELF_X at this height.
const SHELF_X: f32 = 2.0;
const SHELF_Y: f32 = 1.5;

fn shelf_room(size: u32) -> Scene {
    let mut b = Builder::default();
    // Nearly black: surfaces need a reflectance to carry samples; what they reflect is 1e-3
    // of what arrives, below what the test resolves.
    let black = b.material(material("black", 0.001, 0.0));
    let light = b.material(material("light", 0.0, 8.0));
    b.room(Vec3::ZERO, Vec3::new(4.0, 3.0, 4.0), black, &[]);
    let (y, (a, c)) = (LIGHT_Y, LIGHT);
    b.quad(
        [
            Vec3::new(a, y, a),
            Vec3::new(c, y, a),
            Vec3::new(c, y, c),
            Vec3::new(a, y, c),
        ],
        light,
    );
    let s = SHELF_Y;
    b.quad(
        [
            Vec3::new(0.0, s, 0.0),
            Vec3::new(SHELF_X, s, 0.0),
            Vec3::new(SHELF_X, s, 4.0),
            Vec3::new(0.0, s, 4.0),
        ],
        black,
    );
    // Below the shelf, looking down at the floor under the light.
    b.scene(camera(
        Vec3::new(3.6, 1.3, 2.0),
        Vec3::new(2.0, 0.0, 2.0),
        size,
    ))
}

/// Form factor from a point to the rectangle [0, a] × [0, b] in a parallel plane at height h
/// whose corner is straight above the point, signed by the signs of a and b.
fn corner(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a.abs() / h, b.abs() / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    let f = (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI);
    f * a.signum() * b.signum()
}

/// Form factor from floor point p to the part of the light the shelf leaves in sight.
fn visible_factor(p: Vec3) -> f64 {
    let (x, z) = (f64::from(p.x), f64::from(p.z));
    let h = f64::from(LIGHT_Y);
    // A ray to light point (xl, ·) passes the shelf's plane at x + (xl − x) SHELF_Y / LIGHT_Y,
    // blocked below SHELF_X: the light is in sight beyond xl = x + (SHELF_X − x) LIGHT_Y / SHELF_Y.
    let cut = x + (f64::from(SHELF_X) - x) * h / f64::from(SHELF_Y);
    let x0 = cut.max(f64::from(LIGHT.0));
    let x1 = f64::from(LIGHT.1);
    if x0 >= x1 {
        return 0.0;
    }
    let (z0, z1) = (f64::from(LIGHT.0), f64::from(LIGHT.1));
    corner(x1 - x, z1 - z, h) - corner(x0 - x, z1 - z, h) - corner(x1 - x, z0 - z, h)
        + corner(x0 - x, z0 - z, h)
}

/// The full light's form factor from floor point p.
fn full_factor(p: Vec3) -> f64 {
    let (x, z, h) = (f64::from(p.x), f64::from(p.z), f64::from(LIGHT_Y));
    let (a, c) = (f64::from(LIGHT.0), f64::from(LIGHT.1));
    corner(c - x, c - z, h) - corner(a - x, c - z, h) - corner(c - x, a - z, h)
        + corner(a - x, a - z, h)
}

/// The shelf room rendered (irradiance, each pixel its centre ray, 16 shadow rays per hit):
/// each pixel that sees the floor with the floor point it sees and its value, and the
/// irradiance per unit form factor read from the fully lit floor (one exact answer: every
/// shadow ray arrives, so the estimator returns Lambert's formula).
fn floor_seen(scene: &Scene, backend: Backend) -> (Vec<(Vec3, f64)>, f64) {
    let vis = backend.build(scene).unwrap();
    let solution = meshlight::solve(scene, vis.as_ref(), &Options::default(), &mut |_| {
        Control::Continue
    })
    .unwrap();
    let options = RenderOptions {
        quantity: Quantity::Irradiance,
        direct: Direct::Traced { light_samples: 16 },
        // Each pixel its centre ray: the floor point it sees is the one compared.
        supersample: 1,
        ..Default::default()
    };
    let (image, _) = meshlight::render(scene, &solution, vis.as_ref(), &options, &mut |_| {
        Control::Continue
    })
    .unwrap();
    let rays: Vec<Ray> = scene.camera().pixel_centres().collect();
    let mut hits = vec![None; rays.len()];
    vis.intersect(&rays, &mut hits).unwrap();
    let floor: Vec<(Vec3, f64)> = (0..rays.len())
        .filter_map(|p| {
            let point = rays[p].origin + hits[p].as_ref()?.t * rays[p].dir;
            (point.y < 1e-3).then_some((point, f64::from(image.pixels[p].x)))
        })
        .collect();
    let scale = floor
        .iter()
        .filter(|&&(q, _)| (visible_factor(q) - full_factor(q)).abs() < 1e-12)
        .map(|&(q, value)| value / full_factor(q))
        .fold(f64::NAN, f64::max);
    assert!(scale > 0.0, "{backend}: no fully lit floor in view");
    (floor, scale)
}

#[test]
fn the_penumbra_follows_the_closed_form_pixel_by_pixel() {
    let scene = shelf_room(64);
    for backend in backends() {
        let (floor, scale) = floor_seen(&scene, backend);
        let (mut squares, mut count, mut signed) = (0.0f64, 0usize, 0.0f64);
        for &(q, value) in &floor {
            let share = visible_factor(q) / full_factor(q);
            if (0.05..0.95).contains(&share) {
                let exact = scale * visible_factor(q);
                let e = (value - exact) / exact;
                squares += e * e;
                signed += e;
                count += 1;
            }
        }
        let rms = (squares / count as f64).sqrt();
        eprintln!(
            "{backend}: {count} penumbra pixels, RMS error {:.3}% mean {:.3}%",
            100.0 * rms,
            100.0 * signed / count as f64
        );
        assert!(count > 300, "{backend}: only {count} penumbra pixels");
        // Measured: 16 rays everywhere 10.9% (the test fails), 64 rays everywhere 3.9%,
        // 1,024 rays 0.30% with a mean of 0.001% (the closed form is right).
        assert!(rms < 0.06, "{backend}: RMS error {:.3}%", 100.0 * rms);
        assert!(signed.abs() / (count as f64) < 0.01, "{backend}: biased");
    }
}

/// Near a penumbra's rims a hit's 16 shadow rays may all miss the sliver of light (or of
/// blocker) there: the second look must not be chosen by the hit's own rays, or the rims come
/// out too bright outside and too dark inside.
#[test]
fn the_penumbras_rims_are_not_too_bright_or_too_dark() {
    let scene = shelf_room(160);
    for backend in backends() {
        let (floor, scale) = floor_seen(&scene, backend);
        for (lo, hi) in [(0.9, 0.999), (0.001, 0.1)] {
            let (mut signed, mut count) = (0.0f64, 0usize);
            for &(q, value) in &floor {
                let share = visible_factor(q) / full_factor(q);
                if (lo..hi).contains(&share) {
                    let full = scale * full_factor(q);
                    signed += (value - scale * visible_factor(q)) / full;
                    count += 1;
                }
            }
            let mean = signed / count as f64;
            eprintln!(
                "{backend}: {count} pixels seeing {lo}-{hi} of the light, mean error {:+.3}% of \
                 the full light's",
                100.0 * mean
            );
            assert!(count > 400, "{backend}: only {count} pixels in {lo}-{hi}");
            // Measured: +1.13% and -0.59% when a hit was looked at again by its own rays'
            // disagreement (those whose rays all missed the blocker kept the full light); by
            // its neighbours', -0.06% and +0.02%.
            assert!(
                mean.abs() < 0.003,
                "{backend}, {lo}-{hi}: mean error {:+.3}%",
                100.0 * mean
            );
        }
    }
}
