//! Luminaires from IES files in a scene: the direct light on a floor equals I(C, γ)·cosθ/r²
//! worked out by hand from the file and `docs/scene-format.md`'s orientation rules (aimed down, and tilted
//! with an asymmetric distribution), on both backends; the scene's `units`, and every
//! malformed luminaire named by file and line.

mod common;

use common::backends;
use glam::{DVec3, Vec3};
use meshlight::scene::{Memory, Units};
use meshlight::solver::{Control, Options};
use meshlight::Scene;

/// A 20 × 20 m floor at y = 0 facing up, Kd 0.5, no other geometry (no inter-reflection).
const OBJ: &str =
    "mtllib f.mtl\nv -10 0 -10\nv -10 0 10\nv 10 0 10\nv 10 0 -10\nusemtl floor\nf 1 2 3 4\n";
const MTL: &str = "newmtl floor\nKd 0.5 0.5 0.5\n";

/// I(γ) = 1000 − 10 γ (degrees) on one C plane, tabulated every 30°: bilinear is exact.
const DOWNLIGHT: &str =
    "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 4 1 1 2 0 0 0\n1 1 10\n0 30 60 90\n0\n1000 700 400 100\n";

/// I(C) = 100 + C (degrees, 0–180, mirrored beyond), the same at every γ from 0 to 90.
const WASHER: &str = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 3 1 2 0 0 0\n1 1 10\n0 90\n0 90 180\n100 100\n190 190\n280 280\n";

fn scene(luminaire: &str) -> meshlight::Result<Scene> {
    let toml = format!(
        "obj = \"f.obj\"\nunits = \"photometric\"\n\n[camera]\nposition = [0, 5, -8]\nlook_at = [0, 0, 0]\nfov_y = 50\nwidth = 16\nheight = 12\n\n[[luminaire]]\n{luminaire}\n"
    );
    let files = Memory::default()
        .with("scene.toml", toml.as_str())
        .with("f.obj", OBJ)
        .with("f.mtl", MTL)
        .with("down.ies", DOWNLIGHT)
        .with("washer.ies", WASHER);
    Scene::load_from(&files, "scene.toml")
}

/// Checks every floor sample's direct irradiance against `expected(x)`, on both backends.
fn check(scene: &Scene, expected: impl Fn(Vec3) -> f64) {
    for backend in backends() {
        let vis = backend.build(scene).unwrap();
        let options = Options {
            epsilon: Some(1.0),
            rounds: 0,
            ..Options::default()
        };
        let s =
            meshlight::solve(scene, vis.as_ref(), &options, &mut |_| Control::Continue).unwrap();
        let mut worst = 0.0f64;
        for k in 0..s.samples().len() {
            let x = s.samples().position()[k];
            let want = expected(x);
            let got = s.direct()[k].irradiance;
            // White light: every channel the same.
            assert!(
                (got.x - got.y).abs() <= 1e-9 * got.y.abs().max(1.0),
                "{got}"
            );
            worst = worst.max((got.y - want).abs() / want.max(1e-3));
        }
        eprintln!("{backend}: worst relative error {worst:.2e}");
        assert!(worst < 1e-3, "{backend}: worst relative error {worst}");
    }
}

#[test]
fn a_downlight_lights_the_floor_by_i_of_gamma_cos_over_r_squared() {
    let scene = scene("ies = \"down.ies\"\nposition = [1, 2, 0.5]").unwrap();
    assert_eq!(scene.units(), Units::Photometric);
    let light = Vec3::new(1.0, 2.0, 0.5);
    check(&scene, |x| {
        let d = (x - light).as_dvec3();
        let r = d.length();
        let cos_gamma = -d.y / r; // γ from straight down
        let gamma = cos_gamma.acos().to_degrees();
        let intensity = if gamma <= 90.0 {
            1000.0 - 10.0 * gamma
        } else {
            0.0
        };
        intensity * cos_gamma / (r * r) // the floor faces up: cosθ = cosγ
    });
}

#[test]
fn a_tilted_asymmetric_luminaire_follows_its_aim_and_c0() {
    // Aimed 45° down towards +x; C 0 towards the floor's −x side ... made perpendicular to aim.
    let scene = scene(
        "ies = \"washer.ies\"\nposition = [0, 3, 0]\naim = [1, -1, 0]\nc0 = [1, 1, 0]\nmultiplier = 2\ncolor = [1, 1, 1]",
    )
    .unwrap();
    let (p, aim, c0) = (
        DVec3::new(0.0, 3.0, 0.0),
        DVec3::new(1.0, -1.0, 0.0).normalize(),
        DVec3::new(1.0, 1.0, 0.0).normalize(),
    );
    let c90 = (-aim).cross(c0); // docs/scene-format.md: C 90 points along (−aim) × c0
    check(&scene, |x| {
        let d = x.as_dvec3() - p;
        let r = d.length();
        let u = d / r;
        let gamma = u.dot(aim).acos().to_degrees();
        if gamma > 90.0 {
            return 0.0;
        }
        let mut c = u.dot(c90).atan2(u.dot(c0)).to_degrees().rem_euclid(360.0);
        if c > 180.0 {
            c = 360.0 - c; // the file covers 0–180: mirrored
        }
        let intensity = 2.0 * (100.0 + c); // × the multiplier
        intensity * (-u.y) / (r * r)
    });
}

#[test]
fn the_flux_counts_in_the_emitted_power() {
    // 2π ∫₀^{π/2} (1000 − 10 γ°) sin γ dγ, by hand: 2π (1000 − 10·(180/π)·1) = 2π (1000 − 572.96).
    let scene = scene("ies = \"down.ies\"\nposition = [0, 2, 0]\ncolor = [1, 0.5, 0.25]").unwrap();
    let flux = 2.0 * std::f64::consts::PI * (1000.0 - 10.0 * 180.0 / std::f64::consts::PI);
    let power = scene.emitted_power();
    // The colour is normalised to luminance 1: the luminance of the power is the file's flux.
    let y = 0.2126 * power.x + 0.7152 * power.y + 0.0722 * power.z;
    eprintln!(
        "flux {y:.2} lm vs {flux:.2} lm by hand: {:+.3}%",
        100.0 * (y / flux - 1.0)
    );
    assert!((y / flux - 1.0).abs() < 0.005, "{y} lm vs {flux} lm");
    assert!(power.x > power.y && power.y > power.z);
}

#[test]
fn malformed_luminaires_name_their_file_and_line() {
    let cases = [
        (
            "ies = \"down.ies\"\nposition = [0, 2, 0]\naim = [0, 0, 0]",
            "scene.toml:11:",
            "aim",
        ),
        (
            "ies = \"down.ies\"\nposition = [0, 2, 0]\nc0 = [0, -2, 0]",
            "scene.toml:11:",
            "parallel to its aim",
        ),
        (
            "ies = \"down.ies\"\nposition = [0, 2, 0]\nmultiplier = -1",
            "scene.toml:11:",
            "multiplier -1",
        ),
        (
            "ies = \"down.ies\"\nposition = [0, 2, 0]\ncolor = [0, 0, 0]",
            "scene.toml:11:",
            "color",
        ),
        (
            "ies = \"gone.ies\"\nposition = [0, 2, 0]",
            "gone.ies: cannot read",
            "",
        ),
        (
            "ies = \"down.ies\"\nposition = [0, 2]",
            "scene.toml:13:",
            "array of length 3",
        ),
    ];
    for (luminaire, at, problem) in cases {
        let e = scene(luminaire).unwrap_err().to_string();
        assert!(
            e.starts_with(at) && e.contains(problem),
            "expected {at} … {problem}: {e}"
        );
    }
    // A broken IES file: its own name and line.
    let bad = Memory::default()
        .with("scene.toml", "obj = \"f.obj\"\n[camera]\nposition = [0, 5, -8]\nlook_at = [0, 0, 0]\nfov_y = 50\nwidth = 16\nheight = 12\n[[luminaire]]\nies = \"b.ies\"\nposition = [0, 2, 0]\n")
        .with("f.obj", OBJ)
        .with("f.mtl", MTL)
        .with("b.ies", DOWNLIGHT.replace("700", "-700").as_str());
    let e = Scene::load_from(&bad, "scene.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("b.ies:7:") && e.contains("candela value -700 is negative"),
        "{e}"
    );
    let units = Memory::default()
        .with("scene.toml", "obj = \"f.obj\"\nunits = \"imperial\"\n[camera]\nposition = [0, 5, -8]\nlook_at = [0, 0, 0]\nfov_y = 50\nwidth = 16\nheight = 12\n")
        .with("f.obj", OBJ)
        .with("f.mtl", MTL);
    let e = Scene::load_from(&units, "scene.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("scene.toml:2:") && e.contains("imperial"),
        "{e}"
    );
}
