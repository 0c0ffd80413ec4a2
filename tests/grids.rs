//! Grids and the illuminance at their points: counts and positions by `docs/scene-format.md`'s rule, the
//! errors it lists, direct light by hand under a downlight, and the gather of inter-reflected
//! light in the furnace, where every direction brings the same radiance.

mod common;

use common::{backends, shipped};
use glam::{DVec3, Vec3};
use meshlight::lux::{illuminance, LuxOptions};
use meshlight::scene::{Grid, Memory};
use meshlight::solver::{Control, Options};
use meshlight::Scene;

const CAMERA: &str =
    "[camera]\nposition = [0, 5, -8]\nlook_at = [0, 0, 0]\nfov_y = 50\nwidth = 16\nheight = 12\n";
const OBJ: &str =
    "mtllib f.mtl\nv -10 0 -10\nv -10 0 10\nv 10 0 10\nv 10 0 -10\nusemtl floor\nf 1 2 3 4\n";
const MTL: &str = "newmtl floor\nKd 0.5 0.5 0.5\n";
const DOWNLIGHT: &str =
    "TILT=NONE\n1 -1 1 4 1 1 2 0 0 0\n1 1 10\n0 30 60 90\n0\n1000 700 400 100\n";

fn floor_scene(extra: &str) -> meshlight::Result<Scene> {
    let toml = format!("obj = \"f.obj\"\nunits = \"photometric\"\n{CAMERA}\n{extra}\n");
    let files = Memory::default()
        .with("scene.toml", toml.as_str())
        .with("f.obj", OBJ)
        .with("f.mtl", MTL)
        .with("down.ies", DOWNLIGHT);
    Scene::load_from(&files, "scene.toml")
}

#[test]
fn points_are_cell_centres_and_the_default_spacing_follows_en_12464() {
    let scene = floor_scene(
        "[[grid]]\nname = \"work plane\"\norigin = [0.5, 0.8, 0.5]\nu = [0, 0, 7]\nv = [4.5, 0, 0]",
    )
    .unwrap();
    let g = &scene.grids()[0];
    // p = 0.2 · 5^log10(7) = 0.2 · 3.8965 = 0.7793: ⌈7 / 0.7793⌉ = 9, ⌈4.5 / 0.7793⌉ = 6.
    assert!((g.spacing() - 0.7793).abs() < 1e-4, "{}", g.spacing());
    assert_eq!(g.counts_uv(), (9, 6));
    // Facing u × v = (0, 0, 7) × (4.5, 0, 0) = (0, 31.5, 0): up.
    assert_eq!(g.normal(), Vec3::Y);
    let p = g.points();
    assert_eq!(p.len(), 54);
    // The first cell's centre: origin + u/18 + v/12; the last: origin + 17u/18 + 11v/12.
    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
    assert!(
        close(p[0], Vec3::new(0.5 + 4.5 / 12.0, 0.8, 0.5 + 7.0 / 18.0)),
        "{}",
        p[0]
    );
    assert!(
        close(
            p[53],
            Vec3::new(0.5 + 4.5 * 11.0 / 12.0, 0.8, 0.5 + 7.0 * 17.0 / 18.0)
        ),
        "{}",
        p[53]
    );
    let named = Grid::new("a b/c", Vec3::ZERO, Vec3::X, Vec3::Z, None, None).unwrap();
    assert_eq!(named.file_stem(), "a_b_c");
}

#[test]
fn grid_errors_name_the_file_and_the_key() {
    let grid = |body: &str| format!("[[grid]]\nname = \"g\"\n{body}");
    let cases = [
        (
            grid("origin = [0, 1, 0]\nu = [0, 0, 0]\nv = [1, 0, 0]"),
            "u has zero length",
        ),
        (
            grid("origin = [0, 1, 0]\nu = [1, 0, 0]\nv = [2, 0, 0]"),
            "parallel to v",
        ),
        (
            grid("origin = [0, 1, 0]\nu = [1, 0, 0]\nv = [0, 0, 1]\nnormal = [0, 0, 0]"),
            "normal",
        ),
        (
            grid("origin = [0, 1, 0]\nu = [1, 0, 0]\nv = [0, 0, 1]\nspacing = 0"),
            "spacing 0",
        ),
        (
            grid("origin = [0, 1, 0]\nu = [1000, 0, 0]\nv = [0, 0, 1000]\nspacing = 0.1"),
            "more than 10000000 points",
        ),
        (
            format!(
                "{}\n{}",
                grid("origin = [0, 1, 0]\nu = [1, 0, 0]\nv = [0, 0, 1]"),
                grid("origin = [0, 2, 0]\nu = [1, 0, 0]\nv = [0, 0, 1]")
            ),
            "name used twice",
        ),
        (
            grid("origin = [0, 1, 0]\nu = [1, 0, 0]\nv = [0, 0, 1]\ntarget_em = -500"),
            "target_em -500 must be a positive illuminance",
        ),
        (
            grid("origin = [0, 1, 0]\nu = [1, 0, 0]\nv = [0, 0, 1]\ntarget_u0 = 1.5"),
            "target_u0 1.5 must be a uniformity in (0, 1]",
        ),
    ];
    for (body, problem) in cases {
        let e = floor_scene(&body).unwrap_err().to_string();
        assert!(
            e.starts_with("scene.toml:") && e.contains("grid 'g'") && e.contains(problem),
            "{problem}: {e}"
        );
    }
    // A normal in the rectangle's plane is allowed (vertical illuminance on a horizontal grid).
    assert!(floor_scene(&grid(
        "origin = [0, 1, 0]\nu = [1, 0, 0]\nv = [0, 0, 1]\nnormal = [1, 0, 0]"
    ))
    .is_ok());
}

fn measure(scene: &Scene, backend: meshlight::Backend, options: &Options) -> Vec<DVec3> {
    let vis = backend.build(scene).unwrap();
    let s = meshlight::solve(scene, vis.as_ref(), options, &mut |_| Control::Continue).unwrap();
    illuminance(
        scene,
        &s,
        vis.as_ref(),
        &scene.grids()[0],
        &LuxOptions::default(),
        &mut |_| meshlight::Control::Continue,
    )
    .unwrap()
    .values
}

#[test]
fn under_a_downlight_a_grid_measures_i_of_gamma_cos_over_r_squared() {
    // The grid 1 m over the floor faces up: it sees only the luminaire (the floor is behind).
    let scene = floor_scene(
        "[[luminaire]]\nies = \"down.ies\"\nposition = [0, 3, 0]\n\n[[grid]]\nname = \"g\"\norigin = [-3, 1, -3]\nu = [6, 0, 0]\nv = [0, 0, 6]\nnormal = [0, 1, 0]\nspacing = 1",
    )
    .unwrap();
    let points = scene.grids()[0].points();
    for backend in backends() {
        let e = measure(
            &scene,
            backend,
            &Options {
                epsilon: Some(1.0),
                rounds: 0,
                ..Options::default()
            },
        );
        let mut worst = 0.0f64;
        for (x, got) in points.iter().zip(&e) {
            let d = (*x - Vec3::new(0.0, 3.0, 0.0)).as_dvec3();
            let r = d.length();
            let cos = -d.y / r;
            let want = (1000.0 - 10.0 * cos.acos().to_degrees()) * cos / (r * r);
            worst = worst.max((got.y / want - 1.0).abs());
            assert!(
                (got.y / want - 1.0).abs() < 1e-3,
                "{backend} at {x}: {} lx vs {want}",
                got.y
            );
        }
        eprintln!("{backend}: worst relative error {worst:.2e}");
    }
}

#[test]
fn in_the_furnace_a_floating_grid_measures_pi_times_the_radiance_all_round() {
    // Every face emits Ke 0.1 and reflects Kd 0.5: radiance 0.2 in every direction, so a
    // point anywhere inside, facing any way, receives E = π · 0.2 — half of it straight from
    // the emitting faces, half reflected (the gather).
    let text = std::fs::read_to_string(shipped("box")).unwrap();
    let text = format!("{text}\n[[grid]]\nname = \"g\"\norigin = [0.3, 0.5, 0.3]\nu = [0.4, 0, 0]\nv = [0, 0, 0.4]\nnormal = [0, 1, 0.3]\nspacing = 0.2\n");
    let dir = shipped("box").parent().unwrap().to_path_buf();
    let files = Memory::default()
        .with(dir.join("scene.toml"), text.as_str())
        .with(
            dir.join("box.obj"),
            std::fs::read(dir.join("box.obj")).unwrap(),
        )
        .with(
            dir.join("box.mtl"),
            std::fs::read(dir.join("box.mtl")).unwrap(),
        );
    let scene = Scene::load_from(&files, dir.join("scene.toml")).unwrap();
    let want = std::f64::consts::PI * 0.2;
    for backend in backends() {
        let e = measure(
            &scene,
            backend,
            &Options {
                tolerance: 1e-5,
                ..Options::default()
            },
        );
        let errors: Vec<f64> = e.iter().map(|got| got.y / want - 1.0).collect();
        let (lo, hi) = errors
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        eprintln!(
            "{backend}: errors {:+.2}% to {:+.2}%",
            100.0 * lo,
            100.0 * hi
        );
        assert!(lo > -0.02 && hi < 0.02, "{backend}: {lo} to {hi}");
    }
}

#[test]
fn points_inside_a_solid_are_found_and_left_out() {
    // A 1 m cube standing on a floor (faces outwards: its box built with y swapped), a grid
    // through it at 0.5 m: the 2 × 2 of its 8 × 8 points with |x|, |z| < 0.5 are inside.
    let mut b = common::Builder::default();
    let grey = b.material(common::material("grey", 0.5, 0.0));
    b.quad(
        [
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(-5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, -5.0),
        ],
        grey,
    );
    b.room(
        Vec3::new(-0.5, 1.0, -0.5),
        Vec3::new(0.5, 0.0, 0.5),
        grey,
        &["+y"],
    );
    let mut scene = b.scene(common::camera(Vec3::new(0.0, 3.0, -6.0), Vec3::ZERO, 8));
    let through = Grid::new(
        "through the cube",
        Vec3::new(-2.0, 0.5, -2.0),
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 4.0),
        Some(Vec3::Y),
        Some(0.5),
    )
    .unwrap();
    scene.add_grid(through).unwrap();
    let grid = &scene.grids()[0];
    for backend in backends() {
        let vis = backend.build(&scene).unwrap();
        let inside = meshlight::lux::enclosed(&scene, vis.as_ref(), grid).unwrap();
        for (p, &i) in grid.points().iter().zip(&inside) {
            assert_eq!(i, p.x.abs() < 0.5 && p.z.abs() < 0.5, "{backend} at {p}");
        }
        assert_eq!(inside.iter().filter(|&&i| i).count(), 4);
    }
}
