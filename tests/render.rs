//! Rendering: the furnace image, the dark room behind a wall, the image files.

mod common;

use common::{backends, shipped, two_rooms};
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
