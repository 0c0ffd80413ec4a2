//! Rendering: the furnace image, the dark room behind a wall, the image files.

mod common;

use common::{backends, shipped, two_rooms};
use glam::Vec3;
use meshlight::solver::Options;
use meshlight::{Image, Scene};

fn solve_and_render(scene: &Scene, backend: meshlight::Backend, options: Options) -> Image {
    common::solve_and_render(scene, backend, options, true).1
}

#[test]
fn furnace_every_pixel_is_at_the_analytic_radiance() {
    let scene = Scene::load(shipped("box")).unwrap();
    for backend in backends() {
        let image = solve_and_render(
            &scene,
            backend,
            Options {
                tolerance: 1e-5,
                ..Options::default()
            },
        );
        assert_eq!(image.pixels.len(), 128 * 128);
        for (i, p) in image.pixels.iter().enumerate() {
            let worst = (*p - glam::Vec3::splat(0.2)).abs().max_element() / 0.2;
            assert!(worst < 0.01, "{backend}: pixel {i} = {p}");
        }
    }
}

#[test]
fn the_room_behind_the_wall_renders_black() {
    let scene = two_rooms();
    for backend in backends() {
        let image = solve_and_render(&scene, backend, Options::default());
        // The camera stands in the dark room: every pixel is exactly zero.
        for (i, p) in image.pixels.iter().enumerate() {
            assert_eq!(*p, glam::Vec3::ZERO, "{backend}: pixel {i}");
        }
    }
}

#[test]
fn exr_round_trip_and_png() {
    let scene = Scene::load(shipped("room")).unwrap();
    let image = solve_and_render(
        &scene,
        meshlight::Backend::default_backend(),
        Options::preview(),
    );
    assert!(image.mean() > 0.0);
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("room.exr");
    image.write_exr(&exr).unwrap();
    let back = Image::read_exr(&exr).unwrap();
    assert_eq!(back, image, "EXR keeps the linear values exactly");
    let png = dir.path().join("room.png");
    image.write_png(&png, image.auto_exposure()).unwrap();
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
}

#[test]
fn the_image_is_upright_and_not_mirrored() {
    // The camera looks along +z with up +y, so its right is −x: the red wall (x = 5.5) shows
    // on the left, the green one (x = 0) on the right, and the light under the ceiling in the
    // top half; pixel (0, 0) is the top-left.
    let scene = Scene::load(shipped("room")).unwrap();
    let image = solve_and_render(
        &scene,
        meshlight::Backend::default_backend(),
        Options::preview(),
    );
    let (w, h) = (image.width as usize, image.height as usize);
    let band = |x0: usize, x1: usize| -> glam::Vec3 {
        let mut sum = glam::Vec3::ZERO;
        for y in h * 2 / 5..h * 3 / 5 {
            for x in x0..x1 {
                sum += image.pixels[y * w + x];
            }
        }
        sum
    };
    let (left, right) = (band(0, w / 12), band(w - w / 12, w));
    assert!(left.x > 3.0 * left.y, "left band {left}: not the red wall");
    assert!(
        right.y > 2.0 * right.x,
        "right band {right}: not the green wall"
    );
    let brightest = (0..w * h)
        .max_by(|&a, &b| {
            image.pixels[a]
                .length()
                .total_cmp(&image.pixels[b].length())
        })
        .unwrap();
    assert!(
        brightest / w < h / 4,
        "the light shows at row {} of {h}",
        brightest / w
    );
}

/// Form factor from a point to a parallel rectangle [0, a] × [0, b] with a corner straight
/// above it at height h (the textbook closed form).
fn corner_rectangle(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
}

/// Form factor from (px, pz) on the floor to the parallel rectangle [x0, x1] × [z0, z1] at
/// height h: four corner rectangles, signed.
fn rectangle_above(px: f64, pz: f64, (x0, x1, z0, z1): (f64, f64, f64, f64), h: f64) -> f64 {
    let part = |x: f64, z: f64| {
        let (dx, dz) = (x - px, z - pz);
        dx.signum() * dz.signum() * corner_rectangle(dx.abs(), dz.abs(), h)
    };
    part(x1, z1) - part(x0, z1) - part(x1, z0) + part(x0, z0)
}

/// A floor 8 m square under a camera 1 m up looking straight down, lit by `light`.
fn floor_under(light: impl FnOnce(&mut common::Builder)) -> Scene {
    let mut b = common::Builder::default();
    let grey = b.material(common::material("grey", 0.5, 0.0));
    b.quad(
        [
            Vec3::new(-4.0, 0.0, -4.0),
            Vec3::new(-4.0, 0.0, 4.0),
            Vec3::new(4.0, 0.0, 4.0),
            Vec3::new(4.0, 0.0, -4.0),
        ],
        grey,
    );
    light(&mut b);
    let mut camera = common::camera(Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO, 24);
    camera.up = Vec3::Z;
    b.scene(camera)
}

/// Where pixel (x, y)'s centre ray meets the floor y = 0.
fn floor_hit(scene: &Scene, x: usize, y: usize) -> Vec3 {
    let c = &scene.camera();
    let d = c.direction(x as f32 + 0.5, y as f32 + 0.5);
    c.position + d * (-c.position.y / d.y)
}

/// Irradiance images of a floor whose direct light has a closed form: traced at every pixel
/// it matches to float precision; interpolated from the samples it does not.
fn assert_direct_light_is_exact(scene: &Scene, exact: impl Fn(Vec3) -> f64) {
    for backend in backends() {
        let vis = backend.build(scene).unwrap();
        let solution = common::solve(scene, backend, Options::default());
        let mut worst = [0.0f64; 2];
        for (slot, direct) in [
            meshlight::Direct::Traced { light_samples: 4 },
            meshlight::Direct::Interpolated,
        ]
        .into_iter()
        .enumerate()
        {
            let options = meshlight::RenderOptions {
                quantity: meshlight::Quantity::Irradiance,
                supersample: 1,
                direct,
                ..meshlight::RenderOptions::default()
            };
            let (image, _) =
                meshlight::render(scene, &solution, vis.as_ref(), &options, &mut |_| {
                    meshlight::Control::Continue
                })
                .unwrap();
            let w = image.width as usize;
            for (i, p) in image.pixels.iter().enumerate() {
                let e = exact(floor_hit(scene, i % w, i / w));
                worst[slot] = worst[slot].max((f64::from(p.x) / e - 1.0).abs());
            }
        }
        // The floor sees nothing but the light: all its irradiance is direct.
        assert!(worst[0] < 1e-4, "{backend}: traced, worst {}", worst[0]);
        assert!(
            worst[1] > 1e-3,
            "{backend}: interpolated, worst {}: the test cannot tell",
            worst[1]
        );
    }
}

#[test]
fn direct_light_traced_at_each_pixel_follows_the_inverse_square_law() {
    let scene = floor_under(|b| {
        b.point_lights.push(meshlight::scene::PointLight {
            position: Vec3::new(0.3, 1.0, -0.2),
            intensity: Vec3::splat(10.0),
        })
    });
    // E = I cosθ / r² = I h / r³.
    assert_direct_light_is_exact(&scene, |p| {
        let r = (Vec3::new(0.3, 1.0, -0.2) - p).length() as f64;
        10.0 / (r * r * r)
    });
}

#[test]
fn direct_light_traced_at_each_pixel_matches_the_rectangle_form_factor() {
    // A 1 × 0.6 m panel of radiance 5 at height 1.2 facing down: E = π L F.
    let scene = floor_under(|b| {
        let lamp = b.material(common::material("lamp", 0.0, 5.0));
        b.quad(
            [
                Vec3::new(-0.4, 1.2, -0.3),
                Vec3::new(0.6, 1.2, -0.3),
                Vec3::new(0.6, 1.2, 0.3),
                Vec3::new(-0.4, 1.2, 0.3),
            ],
            lamp,
        );
    });
    assert_direct_light_is_exact(&scene, |p| {
        let f = rectangle_above(f64::from(p.x), f64::from(p.z), (-0.4, 0.6, -0.3, 0.3), 1.2);
        std::f64::consts::PI * 5.0 * f
    });
}

#[test]
fn the_pool_under_a_lamp_just_over_a_floor_is_measured_to_each_pixel_s_mean() {
    // A point light 0.1 m over the floor, the camera 1 m up: the pool's peak is two pixels
    // wide, and a pixel's centre reads up to 20% off the pixel's mean (the image is its
    // mean). No edge between surfaces is in sight: the pool's pixels are supersampled for
    // their contrast alone, and an 8 × 8 grid on a smooth pool errs by a part in a hundred.
    let light = Vec3::new(0.03, 0.1, -0.02);
    let scene = floor_under(|b| {
        b.point_lights.push(meshlight::scene::PointLight {
            position: light,
            intensity: Vec3::splat(1.0),
        })
    });
    let c = scene.camera();
    let irradiance = |x: f32, y: f32| {
        let d = c.direction(x, y);
        let p = c.position + d * (-c.position.y / d.y);
        let r = f64::from((light - p).length());
        0.1 / (r * r * r)
    };
    // Each pixel's mean over a 32 × 32 midpoint grid, and its centre's value.
    let w = c.width as usize;
    let (mean, centre): (Vec<f64>, Vec<f64>) = (0..w * c.height as usize)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let grid = (0..32 * 32)
                .map(|k| {
                    irradiance(
                        x + ((k % 32) as f32 + 0.5) / 32.0,
                        y + ((k / 32) as f32 + 0.5) / 32.0,
                    )
                })
                .sum::<f64>()
                / 1024.0;
            (grid, irradiance(x + 0.5, y + 0.5))
        })
        .unzip();
    let peak = mean.iter().copied().fold(0.0, f64::max);
    let worst = |values: &[f64]| {
        values
            .iter()
            .zip(&mean)
            .map(|(v, m)| (v - m).abs() / peak)
            .fold(0.0, f64::max)
    };
    assert!(
        worst(&centre) > 0.05,
        "the centres err by {} of the peak: the test cannot tell",
        worst(&centre)
    );
    for backend in backends() {
        let vis = backend.build(&scene).unwrap();
        let solution = common::solve(&scene, backend, Options::default());
        let options = meshlight::RenderOptions {
            quantity: meshlight::Quantity::Irradiance,
            ..meshlight::RenderOptions::default()
        };
        let (image, _) = meshlight::render(&scene, &solution, vis.as_ref(), &options, &mut |_| {
            meshlight::Control::Continue
        })
        .unwrap();
        let seen: Vec<f64> = image.pixels.iter().map(|p| f64::from(p.x)).collect();
        assert!(
            worst(&seen) < 0.01,
            "{backend}: worst pixel off its mean by {} of the peak",
            worst(&seen)
        );
    }
}

#[test]
fn the_rim_of_a_bright_light_is_covered_to_its_area() {
    // A square of radiance 50 facing the camera before an unlit wall, an eighth of the image
    // wide: each pixel shows 50 × the share of it the square covers (the square's edges run
    // along the pixels'). An n × n jittered grid errs by at most one row of strata on such an
    // edge, 1/n of the pixel; the contrast (64× the image's mean) calls for 16 × 16 rays.
    let mut b = common::Builder::default();
    let dark = b.material(common::material("dark", 0.2, 0.0));
    let lamp = b.material(common::material("lamp", 0.0, 50.0));
    b.quad(
        [
            Vec3::new(-9.0, -9.0, 5.0),
            Vec3::new(-9.0, 9.0, 5.0),
            Vec3::new(9.0, 9.0, 5.0),
            Vec3::new(9.0, -9.0, 5.0),
        ],
        dark,
    );
    let camera = common::camera(Vec3::ZERO, Vec3::Z, 64);
    // Half-width of the view at distance 4 is 4 tan 30°; the square spans an eighth of it
    // each side of the centre, off the pixel grid by a third of a pixel.
    let half_view = 4.0 * (30.0f32).to_radians().tan();
    let (lo, hi) = (
        -half_view / 8.0 + half_view / 96.0,
        half_view / 8.0 + half_view / 96.0,
    );
    b.quad(
        [
            Vec3::new(lo, lo, 4.0),
            Vec3::new(lo, hi, 4.0),
            Vec3::new(hi, hi, 4.0),
            Vec3::new(hi, lo, 4.0),
        ],
        lamp,
    );
    let scene = b.scene(camera);
    // The square in pixels: x grows to the camera's right (−x in the scene), y downwards.
    let to_px = |v: f32| 32.0 + v / half_view * 32.0;
    let (x0, x1) = (to_px(-hi), to_px(-lo));
    let (y0, y1) = (to_px(-hi), to_px(-lo));
    let overlap = |a: f32, b: f32, p: f32| (b.min(p + 1.0) - a.max(p)).max(0.0);
    for backend in backends() {
        let image = solve_and_render(&scene, backend, Options::default());
        let mut worst = 0.0f32;
        for y in 0..64 {
            for x in 0..64 {
                let cover = overlap(x0, x1, x as f32) * overlap(y0, y1, y as f32);
                let seen = image.pixels[y * 64 + x].x / 50.0;
                worst = worst.max((seen - cover).abs());
            }
        }
        assert!(
            worst <= 1.0 / 16.0 + 1e-3,
            "{backend}: worst coverage error {worst}"
        );
    }
}
