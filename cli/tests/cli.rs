//! The `meshlight` command, black-box: what it prints and how it fails.

use std::process::{Command, Output};

fn meshlight(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_meshlight"))
        .args(args)
        // The workspace root, where the shipped scenes are.
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("run meshlight")
}

/// `meshlight` with `args`, which must succeed (its stderr says why not).
fn succeed(args: &[&str]) -> Output {
    let out = meshlight(args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    out
}

/// A path from the workspace root, where the shipped scenes are.
fn root(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn info_summarises_the_room() {
    let out = succeed(&["info", "scenes/room/scene.toml"]);
    let stdout = text(&out.stdout);
    for expected in [
        "triangles     34",
        "surfaces      17",
        "total area    298.05",
        "area lights   1 surface(s), area 1.440000, power 45.2389 45.2389 45.2389 W",
        "point lights  0",
        "fov_y 62°, 512x512",
        "(diagonal 11.895",
    ] {
        assert!(
            stdout.contains(expected),
            "missing '{expected}' in:\n{stdout}"
        );
    }
}

#[test]
fn errors_name_the_file_and_exit_non_zero() {
    let out = meshlight(&["info", "scenes/nowhere/scene.toml"]);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("scenes/nowhere/scene.toml: cannot read"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    // The cause is said once, not once per level of the error chain.
    assert_eq!(stderr.matches("os error 2").count(), 1, "{stderr}");
}

#[test]
fn unknown_backend_is_refused() {
    let out = meshlight(&["bench-vis", "scenes/box/scene.toml", "--backend", "optix"]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("unknown backend 'optix'"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn bench_vis_prints_rates_for_every_backend_and_their_agreement() {
    let out = succeed(&[
        "bench-vis",
        "scenes/room/scene.toml",
        "--queries",
        "20000",
        "--rays",
        "2000",
        "--repeats",
        "1",
    ]);
    let stdout = text(&out.stdout);
    assert!(stdout.contains("20000 occlusion segments"), "{stdout}");
    assert!(stdout.contains("bvh thorough-wide"), "{stdout}");
    if cfg!(feature = "embree") {
        assert!(
            stdout.contains("embree 3") || stdout.contains("embree 4"),
            "{stdout}"
        );
        assert!(
            stdout.contains("trait / best raw path, 2 thread(s)"),
            "{stdout}"
        );
        assert!(
            stdout.contains("agreement embree vs bvh: 0 of 20000"),
            "{stdout}"
        );
    }
}

#[test]
fn gallery_generator_writes_a_loadable_reduced_gallery() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    meshlight_gallery::write_scene(
        dir.path(),
        meshlight_gallery::GalleryOptions {
            tile: 0.5,
            sphere_detail: 0,
            ..Default::default()
        },
    )
    .unwrap();
    let out = succeed(&["info", path.to_str().unwrap()]);
    assert!(
        text(&out.stdout).contains("point lights  8"),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn render_writes_exr_and_png_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box.exr");
    let run = meshlight(&[
        "render",
        "scenes/box/scene.toml",
        "-o",
        out.to_str().unwrap(),
        "--threads",
        "2",
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let stdout = text(&run.stdout);
    for expected in [
        "round",
        "samples",
        "converged",
        "render 128x128",
        "ε 0.1 (scene file)",
    ] {
        assert!(
            stdout.contains(expected),
            "missing '{expected}' in:\n{stdout}"
        );
    }
    let image = meshlight::Image::read_exr(&out).unwrap();
    assert!(
        (image.mean() - 0.2).abs() < 0.002,
        "furnace mean {}",
        image.mean()
    );
    assert!(out.with_extension("png").exists());
}

#[test]
fn samples_writes_a_ply_point_cloud() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.ply");
    let run = meshlight(&[
        "samples",
        "scenes/box/scene.toml",
        "-o",
        out.to_str().unwrap(),
        "--preset",
        "preview",
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let ply = std::fs::read_to_string(&out).unwrap();
    let count: usize = ply
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .and_then(|n| n.parse().ok())
        .expect("a vertex count");
    let body: Vec<&str> = ply
        .lines()
        .skip_while(|l| *l != "end_header")
        .skip(1)
        .collect();
    assert_eq!(body.len(), count);
    assert!(count > 100);
    assert_eq!(
        body[0].split_whitespace().count(),
        11,
        "x y z nx ny nz r g b radius area"
    );
}

#[test]
fn no_epsilon_means_an_automatic_one_that_is_announced() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(root("scenes/box/box.obj"), dir.path().join("box.obj")).unwrap();
    std::fs::copy(root("scenes/box/box.mtl"), dir.path().join("box.mtl")).unwrap();
    let toml = std::fs::read_to_string(root("scenes/box/scene.toml"))
        .unwrap()
        .replace("[solver]\nepsilon = 0.1\n", "");
    std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
    let out = dir.path().join("a.exr");
    let run = meshlight(&[
        "render",
        dir.path().join("scene.toml").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--rounds",
        "0",
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert!(
        text(&run.stderr).contains("no epsilon given: chose ε ="),
        "{}",
        text(&run.stderr)
    );
    assert!(
        text(&run.stdout).contains("(automatic)"),
        "{}",
        text(&run.stdout)
    );
}

#[test]
fn the_preview_says_where_its_epsilon_came_from_and_info_gives_the_same_length() {
    // The box's file asks for ε 0.1; the preview takes 0.14 of the free path `info` prints
    // (the box has no lamps to shorten it).
    let info = meshlight(&["info", root("scenes/box/scene.toml").to_str().unwrap()]);
    assert!(info.status.success(), "{}", text(&info.stderr));
    let info = text(&info.stdout);
    let free_path: f64 = info
        .lines()
        .find_map(|l| l.strip_prefix("free path"))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{info}"));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.exr");
    let run = meshlight(&[
        "render",
        root("scenes/box/scene.toml").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--preset",
        "preview",
        "--width",
        "16",
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert!(
        text(&run.stderr).contains("of the length over which the scene's light changes"),
        "{}",
        text(&run.stderr)
    );
    let stdout = text(&run.stdout);
    let epsilon: f64 = stdout
        .split("ε ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(stdout.contains("(the scene's light length)"), "{stdout}");
    assert!(
        (epsilon / (0.14 * free_path) - 1.0).abs() < 1e-4,
        "ε {epsilon} against 0.14 × {free_path}"
    );
}

fn write_pair(dir: &std::path::Path, b: &[[f32; 3]], a: &[[f32; 3]]) -> (String, String) {
    let image = |p: &[[f32; 3]]| meshlight::Image {
        width: p.len() as u32,
        height: 1,
        pixels: p.iter().map(|&c| glam::Vec3::from(c)).collect(),
    };
    let (pa, pb) = (dir.join("a.exr"), dir.join("b.exr"));
    image(a).write_exr(&pa).unwrap();
    image(b).write_exr(&pb).unwrap();
    (
        pa.to_str().unwrap().to_string(),
        pb.to_str().unwrap().to_string(),
    )
}

#[test]
fn compare_reports_bias_and_draws_the_signed_error() {
    let dir = tempfile::tempdir().unwrap();
    // Reference mean 2; the first pixel is 0.5 too bright on every channel: MAE = 1.5/6 / 2,
    // bias = (2.25 − 2) / 2, signed error of that pixel 0.5 / 2 = 0.25 of the mean.
    let (a, b) = write_pair(
        dir.path(),
        &[[1.0, 1.0, 1.0], [3.0, 3.0, 3.0]],
        &[[1.5, 1.5, 1.5], [3.0, 3.0, 3.0]],
    );
    let png = dir.path().join("diff.png");
    let run = meshlight(&["compare", &a, &b, "--diff", png.to_str().unwrap()]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let stdout = text(&run.stdout);
    assert!(stdout.contains("MAE/mean 0.12500"), "{stdout}");
    assert!(stdout.contains("bias +0.12500"), "{stdout}");
    // Two pixels in a row: none has a whole 3 × 3 neighbourhood.
    assert!(stdout.contains("sparkles 0 vs reference 0"), "{stdout}");
    // The 99th percentile of |error| is 0.25, rounded up to 0.5: the bright pixel sits
    // halfway up the red side (the light-red stop), the exact one is white.
    assert!(stdout.contains("saturate at ±50.000%"), "{stdout}");
    let picture = image::open(&png).unwrap().to_rgb8();
    assert_eq!(picture.dimensions(), (2 + 200, 320));
    assert_eq!(picture.get_pixel(0, 0).0, [244, 165, 130]);
    assert_eq!(picture.get_pixel(1, 0).0, [247, 247, 247]);
    // The legend has text: dark pixels right of the image, above the caption's end.
    let dark = (2..202)
        .flat_map(|x| (0..320).map(move |y| (x, y)))
        .filter(|&(x, y)| picture.get_pixel(x, y).0.iter().all(|&c| c < 80))
        .count();
    assert!(dark > 200, "{dark} dark legend pixels");

    let identical = meshlight(&["compare", &b, &b]);
    let stdout = text(&identical.stdout);
    assert!(stdout.contains("MAE/mean 0.00000"), "{stdout}");
    assert!(stdout.contains("bias +0.00000"), "{stdout}");
}

#[test]
fn compare_refuses_images_of_different_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = write_pair(dir.path(), &[[1.0; 3], [1.0; 3]], &[[1.0; 3]]);
    let run = meshlight(&["compare", &a, &b]);
    assert!(!run.status.success());
    let stderr = text(&run.stderr);
    assert!(
        stderr.contains(" is 1x1 but ") && stderr.contains(" is 2x1: compare images of one size"),
        "{stderr}"
    );
    assert!(!stderr.contains("invalid option"), "{stderr}");
}

#[test]
fn sweep_writes_a_row_per_setting_and_a_plot() {
    let dir = tempfile::tempdir().unwrap();
    // A 16×16 path-traced reference of the furnace box: every run renders at its size.
    let mut scene = meshlight::Scene::load(root("scenes/box/scene.toml")).unwrap();
    let camera = meshlight::scene::Camera {
        width: 16,
        height: 16,
        ..*scene.camera()
    };
    scene.set_camera(camera).unwrap();
    let vis = meshlight::Backend::Bvh.build(&scene).unwrap();
    let traced = meshlight::reference::path_trace(
        &scene,
        vis.as_ref(),
        &meshlight::reference::PathOptions {
            spp: 1024,
            ..Default::default()
        },
        &mut |_| meshlight::Control::Continue,
    )
    .unwrap();
    let reference = dir.path().join("ref.exr");
    traced.image.write_exr(&reference).unwrap();
    let prefix = dir.path().join("s");
    let run = meshlight(&[
        "sweep",
        "scenes/box/scene.toml",
        "--reference",
        reference.to_str().unwrap(),
        "--vary",
        "epsilon=0.3,0.2",
        "--vary",
        "rounds=0,1",
        "--max-spp",
        "8",
        "--backend",
        "bvh",
        "--out",
        prefix.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let csv = std::fs::read_to_string(prefix.with_extension("csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(
        lines[0].starts_with("method,epsilon,rounds,spp,samples,"),
        "{}",
        lines[0]
    );
    let meshless: Vec<Vec<&str>> = lines[1..]
        .iter()
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[0] == "meshless")
        .collect();
    let settings: Vec<(&str, &str)> = meshless.iter().map(|f| (f[1], f[2])).collect();
    assert_eq!(
        settings,
        [("0.3", "0"), ("0.3", "1"), ("0.2", "0"), ("0.2", "1")]
    );
    let columns = lines[0].split(',').count();
    for f in &meshless {
        assert_eq!(f.len(), columns);
        let samples: usize = f[4].parse().unwrap();
        assert!(samples > 10, "{f:?}");
        // The furnace is uniform: every run lands within the reference's noise (about 0.7%) of it.
        let mae: f64 = f[columns - 5].parse().unwrap();
        assert!(mae > 0.0 && mae < 0.02, "{f:?}");
    }
    // Finer spacing, more samples.
    let samples = |i: usize| meshless[i][4].parse::<usize>().unwrap();
    assert!(samples(2) > samples(0));
    let spp: Vec<&str> = lines[1..]
        .iter()
        .filter(|l| l.starts_with("pathtrace"))
        .map(|l| l.split(',').nth(3).unwrap())
        .collect();
    assert!(!spp.is_empty() && spp.len() <= 3, "{spp:?}");
    assert_eq!(spp[0], "2");
    let png = image::open(prefix.with_extension("png")).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (900, 600));
    let coloured = png
        .pixels()
        .filter(|p| p.0[0] > 150 && p.0[1] < 60 && p.0[2] < 80)
        .count();
    assert!(
        coloured > 100,
        "the path tracer's red curve: {coloured} pixels"
    );

    let bad = meshlight(&[
        "sweep",
        "scenes/box/scene.toml",
        "--reference",
        reference.to_str().unwrap(),
        "--vary",
        "zeta=fast",
    ]);
    assert!(!bad.status.success());
    assert!(
        text(&bad.stderr).contains("--vary zeta: 'fast' is not a valid value"),
        "{}",
        text(&bad.stderr)
    );
}

#[test]
fn lux_writes_a_csv_and_a_plan_per_grid_and_summarises_them() {
    // The furnace box with a 3 × 2 grid floating inside, facing up: E = π · 0.2 everywhere
    // (radiance 0.2 all round), so Emin ≈ Eavg ≈ Emax and U0 ≈ 1.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    for f in ["box.obj", "box.mtl"] {
        std::fs::copy(root(&format!("scenes/box/{f}")), dir.path().join(f)).unwrap();
    }
    let toml = std::fs::read_to_string(root("scenes/box/scene.toml")).unwrap()
        + "\n[[grid]]\nname = \"mid plane\"\norigin = [0.2, 0.5, 0.2]\nu = [0.6, 0, 0]\nv = [0, 0, 0.4]\nspacing = 0.2\ntarget_em = 0.5\ntarget_u0 = 0.9\n"
        + "\n[[grid]]\nname = \"asks too much\"\norigin = [0.2, 0.3, 0.2]\nu = [0.6, 0, 0]\nv = [0, 0, 0.4]\nspacing = 0.2\ntarget_em = 1.0\n";
    std::fs::write(&scene, toml).unwrap();
    let out_dir = dir.path().join("lux");
    let out = succeed(&[
        "lux",
        scene.to_str().unwrap(),
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    let stdout = text(&out.stdout);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("grid 'mid plane': 6 points"))
        .unwrap_or_else(|| panic!("{stdout}"));
    // Targets: π · 0.2 = 0.628 (within 2%) meets 0.5 by 23–28% and U0 0.9; 1.0 is 0.36–0.38
    // short, 36–39%.
    assert!(
        stdout.contains("grid 'mid plane': meets its targets: Ēm 0.5 W/m² (+2"),
        "{stdout}"
    );
    let short = stdout
        .lines()
        .find(|l| l.starts_with("grid 'asks too much': does NOT meet Ēm 1 W/m²: 0.3"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(short.contains("short (-3"), "{short}");
    let csv = std::fs::read_to_string(out_dir.join("mid_plane.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows[0], "x,y,z,E,in_solid");
    assert_eq!(rows.len(), 7);
    let e: Vec<f64> = rows[1..]
        .iter()
        .map(|r| r.split(',').nth(3).unwrap().parse().unwrap())
        .collect();
    let want = std::f64::consts::PI * 0.2;
    for v in &e {
        assert!((v / want - 1.0).abs() < 0.02, "{v} vs {want}");
    }
    let avg = e.iter().sum::<f64>() / 6.0;
    // Three significant figures, as designers read them (0.6 to 1: three decimals).
    assert!(
        line.contains(&format!("Eavg {avg:.3} W/m²")),
        "{line} (avg {avg:.4})"
    );
    assert!(
        std::fs::metadata(out_dir.join("mid_plane.png"))
            .unwrap()
            .len()
            > 1000
    );
}

#[test]
fn false_colour_renders_hold_the_illuminance_and_refuse_bad_ranges() {
    // The furnace: every surface receives E = π · 0.2 (radiance 0.2 from all round).
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("e.exr");
    succeed(&[
        "render",
        "scenes/box/scene.toml",
        "-o",
        exr.to_str().unwrap(),
        "--false-color",
        "illuminance",
    ]);
    let image = meshlight::Image::read_exr(&exr).unwrap();
    let want = std::f64::consts::PI * 0.2;
    assert!(
        (image.mean() / want - 1.0).abs() < 0.02,
        "{} vs {want}",
        image.mean()
    );
    assert!(std::fs::metadata(exr.with_extension("png")).unwrap().len() > 1000);
    for (args, problem) in [
        (
            vec!["--false-color", "luminance", "--range", "5:1"],
            "MIN must be below MAX",
        ),
        (
            vec!["--false-color", "luminance", "--range", "0:1", "--log"],
            "--log needs a range above 0",
        ),
        (
            vec!["--false-color", "luminance", "--method", "pathtrace"],
            "meshless only",
        ),
    ] {
        let mut all = vec![
            "render",
            "scenes/box/scene.toml",
            "-o",
            exr.to_str().unwrap(),
        ];
        all.extend(args);
        let out = meshlight(&all);
        assert!(!out.status.success());
        assert!(text(&out.stderr).contains(problem), "{}", text(&out.stderr));
    }
}

#[test]
fn a_scene_without_light_is_refused_and_a_light_facing_the_ceiling_is_named() {
    // The Cornell room as Blender's OBJ exporter leaves it when the light is a plain Emission
    // node (Ke 0), and again with its light panel turned to face the ceiling 1 cm above.
    let dir = tempfile::tempdir().unwrap();
    let cornell = root("scenes/cornell");
    for file in ["cornell.obj", "cornell.mtl"] {
        std::fs::copy(cornell.join(file), dir.path().join(file)).unwrap();
    }
    let scene = std::fs::read_to_string(cornell.join("scene.toml")).unwrap();
    let dark = dir.path().join("dark.toml");
    std::fs::write(
        &dark,
        format!("{scene}\n[material.light]\nke = [0.0, 0.0, 0.0]\n"),
    )
    .unwrap();
    let out = meshlight(&["render", dark.to_str().unwrap(), "-o", "/dev/null"]);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("dark.toml: nothing in the scene emits light") && stderr.contains("Ke 0"),
        "{stderr}"
    );
    // The light's face turned up: its vertex order reversed in the OBJ.
    let obj = std::fs::read_to_string(dir.path().join("cornell.obj")).unwrap();
    let mut flipped = String::new();
    let mut light = false;
    for line in obj.lines() {
        if line.starts_with("usemtl") {
            light = line.trim() == "usemtl light";
        }
        if light && line.starts_with("f ") {
            let mut v: Vec<&str> = line.split_whitespace().skip(1).collect();
            v.reverse();
            flipped.push_str(&format!("f {}\n", v.join(" ")));
        } else {
            flipped.push_str(line);
            flipped.push('\n');
        }
    }
    std::fs::write(dir.path().join("cornell.obj"), flipped).unwrap();
    let up = dir.path().join("up.toml");
    std::fs::write(&up, &scene).unwrap();
    let exr = dir.path().join("up.exr");
    let out = succeed(&[
        "render",
        up.to_str().unwrap(),
        "--preset",
        "preview",
        "-o",
        exr.to_str().unwrap(),
    ]);
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("warning: the area light") && stderr.contains("material 'light'"),
        "{stderr}"
    );
}

#[test]
fn a_gltf_renders_on_its_own_from_the_camera_named() {
    // Blender's export: geometry, materials, the point light and the camera "Camera" all from
    // the file (512 × 384 from its aspect ratio), no scene file.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("room.exr");
    let run = meshlight(&[
        "render",
        "tests/data/blender-room.glb",
        "--camera",
        "Camera",
        "--epsilon",
        "0.4",
        "--rounds",
        "0",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let stdout = text(&run.stdout);
    assert!(stdout.contains("render 512x384"), "{stdout}");
    assert!(out.exists());
    let run = meshlight(&["info", "tests/data/blender-room.glb", "--camera", "Kamera"]);
    assert!(!run.status.success());
    let stderr = text(&run.stderr);
    assert!(stderr.contains("no camera 'Kamera'"), "{stderr}");
}

#[test]
fn lux_plans_trace_iso_lines_on_a_point_lights_circles_and_hatch_solids() {
    // A 10 m square floor (nearly black, so the light is the point light's alone), a 1 m box
    // standing on it at x, z ∈ [1, 2], a point light of 1000 W/sr 2 m over the floor's centre,
    // and a grid 0.05 m over the floor, 0.25 m apart. E = I h / (r² + h²)^{3/2} with h = 1.95:
    // the 50, 100 and 150 W/m² iso-lines are circles of radius r = √((I h / E)^{2/3} − h²),
    // by hand. The plan is to scale, 48 pixels a metre (480 for the 10 m), its left edge at
    // pixel 52 and its top at 10 (docs/cli.md): on each circle, at 36 angles, a black line pixel
    // lies within half a spacing (6 px) of the radius at most of them (labels cover a few).
    // Points inside the box are hatched grey, never the colour of 0 lx.
    let (dir, scene) = floor_scene("");
    let out_dir = dir.path().join("lux");
    succeed(&[
        "lux",
        scene.to_str().unwrap(),
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    let png = image::open(out_dir.join("floor.png")).unwrap().to_rgb8();
    // Floor metres (x along u, z along v) to pixels: v runs up the picture.
    let pixel = |x: f64, z: f64| (52.0 + 48.0 * x, 10.0 + 480.0 - 48.0 * z);
    let black = |x: f64, y: f64| {
        let (x, y) = (x.round() as u32, y.round() as u32);
        png.get_pixel(x, y).0 == [0, 0, 0]
    };
    let (i, h) = (1000.0f64, 1.95f64);
    for level in [50.0, 100.0, 150.0] {
        let r = ((i * h / level).powf(2.0 / 3.0) - h * h).sqrt();
        let found = (0..36)
            .filter(|k| {
                let a = f64::from(*k) * std::f64::consts::TAU / 36.0;
                (-6..=6).any(|d| {
                    let rr = r + f64::from(d) / 48.0;
                    let (px, py) = pixel(5.0 + rr * a.cos(), 5.0 + rr * a.sin());
                    black(px, py)
                })
            })
            .count();
        assert!(
            found >= 30,
            "{level} W/m² (r {r:.3} m): a line at {found} of 36 angles"
        );
    }
    // The box's footprint: hatched (light or dark grey), not sequential(0) dark blue.
    for (x, z) in [(1.5, 1.5), (1.3, 1.7), (1.6, 1.2)] {
        let (px, py) = pixel(x, z);
        let c = png.get_pixel(px.round() as u32, py.round() as u32).0;
        assert!(
            c == [215, 215, 215] || c == [150, 150, 150],
            "{x}, {z}: {c:?}"
        );
    }
    // And a measured point beside it is coloured.
    let (px, py) = pixel(3.0, 3.0);
    let c = png.get_pixel(px as u32, py as u32).0;
    assert!(c[0] != c[1] || c[1] != c[2], "{c:?}");
}

/// A 10 m square floor (nearly black), a 1 m box on it at x, z ∈ [1, 2], a point light of
/// 1000 W/sr 2 m over the floor's centre, and a grid "floor" 0.05 m over it, 0.25 m apart;
/// `extra` is added to the scene file.
fn floor_scene(extra: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("floor.obj"),
        "mtllib floor.mtl\nusemtl dark\nv 0 0 0\nv 0 0 10\nv 10 0 10\nv 10 0 0\nf 1 2 3 4\n\
         v 1 0 1\nv 2 0 1\nv 2 0 2\nv 1 0 2\nv 1 1 1\nv 2 1 1\nv 2 1 2\nv 1 1 2\n\
         f 5 6 7 8\nf 9 12 11 10\nf 5 9 10 6\nf 6 10 11 7\nf 7 11 12 8\nf 8 12 9 5\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("floor.mtl"),
        "newmtl dark\nKd 0.01 0.01 0.01\n",
    )
    .unwrap();
    let scene = dir.path().join("scene.toml");
    let toml = "obj = \"floor.obj\"\n[camera]\nposition = [5, 8, 5]\nlook_at = [5, 0, 5.01]\n\
                fov_y = 60\nwidth = 16\nheight = 16\n[[point_light]]\nposition = [5, 2, 5]\n\
                intensity = [1000, 1000, 1000]\n[[grid]]\nname = \"floor\"\n\
                origin = [0, 0.05, 0]\nu = [10, 0, 0]\nv = [0, 0, 10]\nnormal = [0, 1, 0]\n\
                spacing = 0.25\n"
        .to_string()
        + extra;
    std::fs::write(&scene, toml).unwrap();
    (dir, scene)
}

#[test]
fn report_writes_one_self_contained_page_with_every_grid_and_its_targets() {
    // The floor scene with a second grid that asks for more than it gets: the page lists both
    // grids with Ēm as their CSVs give it (within 0.1%; the floor's points inside the box left
    // out), marks the second as failing with its shortfall, embeds every picture as a PNG that
    // decodes, and needs no script or network.
    let (dir, scene) = floor_scene(
        "[[grid]]\nname = \"near the box\"\norigin = [0.5, 0.05, 3]\nu = [2, 0, 0]\n\
         v = [0, 0, 1]\nnormal = [0, 1, 0]\nspacing = 0.25\ntarget_em = 1000\ntarget_u0 = 0.5\n",
    );
    let out_dir = dir.path().join("report");
    succeed(&[
        "report",
        scene.to_str().unwrap(),
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(out_dir.join("index.html")).unwrap();
    assert!(!html.contains("<script") && !html.contains("http://") && !html.contains("https://"));
    for (grid, csv) in [("floor", "floor.csv"), ("near the box", "near_the_box.csv")] {
        let csv = std::fs::read_to_string(out_dir.join(csv)).unwrap();
        let row = html
            .split("<tr data-em=\"")
            .skip(1)
            .find(|r| r.contains(&format!("<td>{grid}</td>")))
            .unwrap_or_else(|| panic!("no row for {grid}"));
        let em: f64 = row.split('"').next().unwrap().parse().unwrap();
        let outside: Vec<f64> = csv
            .lines()
            .skip(1)
            .filter_map(|r| {
                let f: Vec<f64> = r.split(',').map(|v| v.parse().unwrap()).collect();
                let inside = (1.0..=2.0).contains(&f[0]) && (1.0..=2.0).contains(&f[2]);
                (!inside).then_some(f[3])
            })
            .collect();
        let mean = outside.iter().sum::<f64>() / outside.len() as f64;
        assert!(
            (em / mean - 1.0).abs() < 1e-3,
            "{grid}: page {em}, CSV {mean}"
        );
        if grid == "near the box" {
            assert!(
                row.contains("class=\"fail\"") && row.contains("short"),
                "{row}"
            );
        }
    }
    let images: Vec<&str> = html.split("src=\"data:image/png;base64,").skip(1).collect();
    assert_eq!(
        images.len(),
        4,
        "two plans and the view in radiance and false colour"
    );
    for b64 in images {
        let bytes = decode_base64(b64.split('"').next().unwrap());
        assert!(image::load_from_memory(&bytes).is_ok());
    }
}

/// Base64 (RFC 4648) decoded, written out here rather than taken from the program.
fn decode_base64(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let mut out = Vec::new();
    let (mut bits, mut count) = (0u32, 0);
    for c in text.bytes().take_while(|&c| c != b'=') {
        bits = (bits << 6) | u32::from(value(c));
        count += 6;
        if count >= 8 {
            count -= 8;
            out.push((bits >> count) as u8);
        }
    }
    out
}

/// Chromium, if installed (CI installs Debian's `chromium`); without it a test that needs it
/// is skipped, unless `MESHLIGHT_REQUIRE_CHROMIUM` is set (as CI sets it): then it fails.
fn chromium() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser"].into_iter().find(|c| {
        Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    });
    if found.is_none() {
        assert!(
            std::env::var_os("MESHLIGHT_REQUIRE_CHROMIUM").is_none(),
            "MESHLIGHT_REQUIRE_CHROMIUM is set but no chromium is installed"
        );
        eprintln!("skipped: no chromium installed (apt-get install chromium)");
    }
    found
}

/// Runs headless Chromium on a page with `args`, within 60 s; its output.
fn headless(chromium: &str, page: &std::path::Path, args: &[&str]) -> Output {
    let output = Command::new("timeout")
        .args([
            "60",
            chromium,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
        ])
        .args(args)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("run chromium");
    assert!(output.status.success(), "{}", text(&output.stderr));
    output
}

#[test]
fn the_report_opens_in_headless_chromium_and_prints_a_page_per_section() {
    // A real browser on the designed gallery's report: the DOM it builds holds the grid table
    // with every grid, each with its Ēm within 0.1% of the mean of its CSV's points outside
    // solids; a screenshot shows the plans (the pedestals' hatch, grey 150, is drawn: the
    // images decoded); nothing goes to the console; printed to PDF, each of the five sections
    // starts a page.
    let Some(chromium) = chromium() else { return };
    meshlight_gallery::ensure().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("report");
    succeed(&[
        "report",
        "scenes/gallery/design.toml",
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    let page = out_dir.join("index.html");
    let dom = text(&headless(chromium, &page, &["--dump-dom"]).stdout);
    // The schedule: the design's eight downlights and three wall-washers, by file.
    assert!(dom.contains("<td>8 × downlight.ies") && dom.contains("<td>3 × wallwasher.ies"));
    let table = dom
        .split("<table id=\"grid-table\">")
        .nth(1)
        .and_then(|t| t.split("</table>").next())
        .unwrap_or_else(|| panic!("no grid table in the DOM:\n{dom}"));
    for (grid, csv) in [
        ("room 1 work plane", "room_1_work_plane.csv"),
        ("painting 1", "painting_1.csv"),
        ("painting 2", "painting_2.csv"),
    ] {
        let row = table
            .split("<tr data-em=\"")
            .skip(1)
            .find(|r| r.contains(&format!("<td>{grid}</td>")))
            .unwrap_or_else(|| panic!("no row for {grid}: {table}"));
        let em: f64 = row.split('"').next().unwrap().parse().unwrap();
        let csv = std::fs::read_to_string(out_dir.join(csv)).unwrap();
        let open: Vec<f64> = csv
            .lines()
            .skip(1)
            .filter(|r| r.ends_with(",0"))
            .map(|r| r.split(',').nth(3).unwrap().parse().unwrap())
            .collect();
        let mean = open.iter().sum::<f64>() / open.len() as f64;
        assert!(
            (em / mean - 1.0).abs() < 1e-3,
            "{grid}: DOM {em}, CSV {mean}"
        );
    }
    let shot = dir.path().join("shot.png");
    let run = headless(
        chromium,
        &page,
        &[
            "--enable-logging=stderr",
            "--v=0",
            "--window-size=1200,3000",
            &format!("--screenshot={}", shot.display()),
        ],
    );
    let log = text(&run.stderr);
    assert!(
        !log.contains("CONSOLE") && !log.contains("Uncaught"),
        "{log}"
    );
    let png = image::open(&shot).unwrap().to_rgb8();
    let hatch = png.pixels().filter(|p| p.0 == [150, 150, 150]).count();
    assert!(hatch > 50, "{hatch} pixels of the hatch in the screenshot");
    let pdf = dir.path().join("report.pdf");
    headless(
        chromium,
        &page,
        &[
            "--no-pdf-header-footer",
            &format!("--print-to-pdf={}", pdf.display()),
        ],
    );
    let bytes = std::fs::read(&pdf).unwrap();
    assert!(bytes.starts_with(b"%PDF"));
    let pages = bytes
        .windows(11)
        .filter(|w| w.starts_with(b"/Type /Page") && w[10] != b's')
        .count()
        + bytes
            .windows(10)
            .filter(|w| w.starts_with(b"/Type/Page") && w[9] != b's')
            .count();
    assert!(pages >= 5, "{pages} pages");
}

#[test]
fn a_preset_sets_the_render_too_and_given_options_override_it() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("b.exr");
    // The shadow rays the render traced, from its summary line.
    let shadow_rays = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "scenes/box/scene.toml",
            "-o",
            exr.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = text(&succeed(&args).stdout);
        let line = out
            .lines()
            .find(|l| l.starts_with("render "))
            .unwrap()
            .to_string();
        let rays: u64 = line
            .split(", ")
            .find_map(|part| part.strip_suffix(" shadow rays"))
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{line}"));
        (rays, out)
    };
    let (preview, _) = shadow_rays(&["--preset", "preview"]);
    let (default, _) = shadow_rays(&[]);
    let (overridden, _) = shadow_rays(&["--preset", "preview", "--direct-rays", "16"]);
    // 4 rays a hit instead of 16 (the penumbra's second look scales with them).
    assert!(
        4 * preview <= default + default / 10,
        "{preview} vs {default}"
    );
    assert!(overridden > 3 * preview, "{overridden} vs {preview}");
    // The final preset takes 0.04 of the scene's free path, not the file's ε (0.1 for the
    // box), and says so: the box is a closed unit cube, whose free path is 4V/S = 2/3.
    let (_, out) = shadow_rays(&["--preset", "final", "--supersample", "1"]);
    assert!(out.contains("(the scene's light length)"), "{out}");
    let epsilon: f64 = out
        .split("ε ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{out}"));
    assert!(
        (epsilon / (0.04 * 2.0 / 3.0) - 1.0).abs() < 0.01,
        "ε {epsilon}"
    );
}

#[test]
fn a_run_whose_stderr_is_a_log_prints_plain_progress_lines_unless_quiet() {
    // Here stderr is a pipe, as in a batch job's log: a progress bar would hide itself and a
    // long run say nothing until it ends. Plain lines instead (the first at the first report,
    // then every few seconds), for the solve and the render; none with --quiet.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.exr");
    let args = [
        "render",
        "scenes/box/scene.toml",
        "-o",
        out.to_str().unwrap(),
        "--rounds",
        "0",
    ];
    let run = succeed(&args);
    let log = text(&run.stderr);
    let lines: Vec<&str> = log
        .lines()
        .filter(|l| l.starts_with("meshlight: ") && l.contains(" s: "))
        .collect();
    assert!(
        lines.iter().any(|l| l.contains("round 0: "))
            && lines.iter().any(|l| l.contains("render: ")),
        "{log}"
    );
    // No line counts samples before there are any.
    assert!(!lines.iter().any(|l| l.contains(" 0 samples")), "{log}");
    let quiet = succeed(&[&args[..], &["--quiet"]].concat());
    assert!(
        !text(&quiet.stderr).lines().any(|l| l.contains(" s: round")),
        "{}",
        text(&quiet.stderr)
    );
}

#[test]
fn daylight_scenes_report_their_sky_and_a_closed_one_says_it_sees_none() {
    // The office: info names the sky and what the work plane sees; lux its daylight factor
    // and target.
    let out = succeed(&["info", "scenes/office/scene.toml"]);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("sky           CIE overcast, 10000 lx"),
        "{stdout}"
    );
    assert!(stdout.contains("grid 'work plane'    sees 5."), "{stdout}");
    let out = succeed(&["info", "scenes/office/sun.toml"]);
    let stdout = text(&out.stdout);
    assert!(stdout.contains("sun:          altitude 37.0"), "{stdout}");
    let dir = tempfile::tempdir().unwrap();
    let out = succeed(&[
        "lux",
        "scenes/office/scene.toml",
        "--quiet",
        "-o",
        dir.path().to_str().unwrap(),
    ]);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("grid 'work plane': daylight factor min"),
        "{stdout}"
    );
    assert!(stdout.contains("DF average"), "{stdout}");
    // The report shows the daylight factor and the target's verdict.
    let page = dir.path().join("report");
    succeed(&[
        "report",
        "scenes/office/scene.toml",
        "--quiet",
        "-o",
        page.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(page.join("index.html")).unwrap();
    assert!(
        html.contains("<h2>Daylight factor</h2>"),
        "no daylight section"
    );
    assert!(
        html.contains("class=\"pass\">work plane: DF average"),
        "no verdict"
    );
    assert!(
        html.contains("alt=\"daylight factor plan of work plane\""),
        "no DF plan"
    );
    assert!(page.join("work_plane-df.png").exists());
    // A closed cube under a sky: no opening, no glass.
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
               f 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 4 3 7 8\nf 1 4 8 5\nf 2 6 7 3\n";
    std::fs::write(dir.path().join("cube.obj"), obj).unwrap();
    let toml = "obj = \"cube.obj\"\ntwo_sided = true\n[camera]\nposition = [0.5, 0.5, 0.5]\n\
                look_at = [0.5, 0.5, 1.0]\nfov_y = 60.0\nwidth = 8\nheight = 8\n[sky]\n\
                model = \"uniform\"\n[[grid]]\nname = \"floor\"\norigin = [0.1, 0.2, 0.1]\n\
                u = [0.8, 0, 0]\nv = [0, 0, 0.8]\nnormal = [0, 1, 0]\nspacing = 0.4\n";
    let scene = dir.path().join("closed.toml");
    std::fs::write(&scene, toml).unwrap();
    let out = succeed(&["info", scene.to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert!(stdout.contains("grid 'floor'    sees no sky"), "{stdout}");
    let out = succeed(&[
        "lux",
        scene.to_str().unwrap(),
        "--quiet",
        "-o",
        dir.path().to_str().unwrap(),
    ]);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("grid 'floor': no daylight reaches it"),
        "{stdout}"
    );
    assert!(stdout.contains("daylight factor min 0.00%"), "{stdout}");
}

#[test]
fn annual_writes_each_points_year_and_the_grids_metrics() {
    let out = succeed(&["info", "scenes/office/annual.toml"]);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("occupied hours 8-18, sky in 145 patches"),
        "{stdout}"
    );
    let dir = tempfile::tempdir().unwrap();
    let out = succeed(&[
        "annual",
        "scenes/office/annual.toml",
        "--quiet",
        "--epsilon",
        "0.4",
        "--hourly",
        "-o",
        dir.path().to_str().unwrap(),
    ]);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("grid 'work plane': 80 points, 3650 occupied hours: sDA300/50%"),
        "{stdout}"
    );
    assert!(stdout.contains("GREENSBORO"), "{stdout}");
    let csv = std::fs::read_to_string(dir.path().join("work_plane.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("x,y,z,DA,UDI,sun_hours,exposure"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 80);
    // A point's yearly exposure is the sum of its hours in the hourly file.
    let hourly = std::fs::read_to_string(dir.path().join("work_plane-hourly.csv")).unwrap();
    let mut lines = hourly.lines();
    assert_eq!(lines.next(), Some("month,day,hour,x,y,z,E"));
    let first = &rows[0];
    let (mut sum, mut hours) = (0.0, 0);
    for l in lines {
        let v: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
        if v[3..6] == first[..3] {
            sum += v[6];
            hours += 1;
        }
    }
    assert!(hours > 4000, "{hours}");
    assert!(
        (sum / first[6] - 1.0).abs() < 1e-3,
        "{sum} against {}",
        first[6]
    );
    for r in &rows {
        assert!(
            (0.0..=100.0).contains(&r[3]) && (0.0..=100.0).contains(&r[4]),
            "{r:?}"
        );
    }
    // The report shows the year: its metrics table and plans.
    let page = dir.path().join("report");
    succeed(&[
        "report",
        "scenes/office/annual.toml",
        "--quiet",
        "--epsilon",
        "0.4",
        "-o",
        page.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(page.join("index.html")).unwrap();
    assert!(
        html.contains("<h2>A year of daylight</h2>"),
        "no annual section"
    );
    assert!(html.contains("id=\"annual-table\""));
    assert!(html.contains("work plane: daylight autonomy"));
    // Without a sky of its own the one-moment grids are under the overcast sky: a daylight
    // factor.
    assert!(html.contains("<h2>Daylight factor</h2>"));
    // A weather file cut short names itself and its last line; a scene without [annual]
    // says what it lacks.
    let broken = tempfile::tempdir().unwrap();
    let text_of = |p: &str| std::fs::read_to_string(root(p)).unwrap();
    let epw: String = text_of("scenes/office/greensboro.epw")
        .lines()
        .take(500)
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(broken.path().join("greensboro.epw"), epw).unwrap();
    let scene = text_of("scenes/office/annual.toml").replace(
        "obj = \"office.obj\"",
        &format!("obj = \"{}\"", root("scenes/office/office.obj").display()),
    );
    let toml = broken.path().join("annual.toml");
    std::fs::write(&toml, scene).unwrap();
    let out = meshlight(&[
        "annual",
        toml.to_str().unwrap(),
        "--quiet",
        "-o",
        broken.path().to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("greensboro.epw:500: 492 hourly rows"),
        "{stderr}"
    );
    // One moment of a year's scene without a sky: told where its daylight is.
    let out = meshlight(&["lux", "scenes/office/annual.toml", "--quiet"]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("its daylight is a year of weather ([annual])"),
        "{}",
        text(&out.stderr)
    );
    let out = meshlight(&["annual", "scenes/office/scene.toml", "--quiet"]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("has no [annual]"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn render_takes_the_image_size_from_the_command_line_keeping_the_aspect_ratio() {
    // blender-stripes' camera is 256 × 192 (4:3).
    let dir = tempfile::tempdir().unwrap();
    let scene = root("scenes/blender-stripes/scene.toml");
    for (flags, size) in [
        (&["--width", "64"][..], (64, 48)),
        (&["--height", "30"][..], (40, 30)),
        (&["--width", "50", "--height", "20"][..], (50, 20)),
    ] {
        let out = dir.path().join("x.exr");
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--preset",
            "preview",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(flags);
        succeed(&args);
        let png = image::open(out.with_extension("png")).unwrap();
        assert_eq!((png.width(), png.height()), size, "{flags:?}");
    }
    let run = meshlight(&["render", scene.to_str().unwrap(), "--width", "0"]);
    assert!(!run.status.success());
    assert!(
        text(&run.stderr).contains("--width"),
        "{}",
        text(&run.stderr)
    );
}

/// The number just before `key` in `line`.
fn number_before(line: &str, key: &str) -> u64 {
    let head = &line[..line
        .find(key)
        .unwrap_or_else(|| panic!("no '{key}' in {line}"))];
    let word = head.trim_end().rsplit([' ', '(']).next().unwrap();
    word.parse()
        .unwrap_or_else(|_| panic!("no count before '{key}' in {line}"))
}

#[test]
fn bench_render_times_each_thread_count_and_counts_the_rays_render_casts() {
    // Not the defaults' render flags: a bench that ignored them would count other rays.
    let size = [
        "--width",
        "64",
        "--height",
        "48",
        "--supersample",
        "2",
        "--direct-rays",
        "8",
    ];
    let mut args = vec![
        "bench-render",
        "scenes/room/scene.toml",
        "--repeats",
        "2",
        "--render-threads",
        "1,2",
        "--quiet",
    ];
    args.extend(size);
    let bench = text(&succeed(&args).stdout);
    // The same image through `render`: its summary counts the same rays.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("room.exr");
    let mut args = vec![
        "render",
        "scenes/room/scene.toml",
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend(size);
    let render = text(&succeed(&args).stdout);
    let rendered = render
        .lines()
        .find(|l| l.starts_with("render 64x48:"))
        .unwrap_or_else(|| panic!("{render}"));
    let each = bench
        .lines()
        .find(|l| l.starts_with("each render:"))
        .unwrap_or_else(|| panic!("{bench}"));
    for key in [
        "camera rays",
        "edge pixels supersampled",
        "shadow rays",
        "interpolation queries",
    ] {
        assert_eq!(
            number_before(each, key),
            number_before(rendered, key),
            "{key}:\n{bench}\n{rendered}"
        );
    }
    assert!(bench.contains("64 x 48 (3072 pixels)"), "{bench}");
    // A row per thread count: its median is of its two renders, its time per pixel the
    // median over the pixels.
    for threads in ["1", "2"] {
        let row = bench
            .lines()
            .find(|l| l.split_whitespace().next() == Some(threads))
            .unwrap_or_else(|| panic!("no row for {threads} thread(s):\n{bench}"));
        let cells: Vec<f64> = row.split_whitespace().map(|c| c.parse().unwrap()).collect();
        // Threads, median s, best s, ns a pixel, rays alone s, render / rays, then the 2
        // renders.
        assert_eq!(cells.len(), 8, "{row}");
        let (median, best, ns) = (cells[1], cells[2], cells[3]);
        assert!((median - 0.5 * (cells[6] + cells[7])).abs() < 1e-3, "{row}");
        assert!((best - cells[6].min(cells[7])).abs() < 1e-3, "{row}");
        // The median is printed to 0.1 ms: 16 ns a pixel here.
        assert!((ns - median * 1e9 / 3072.0).abs() <= 17.0, "{row}");
        assert!(cells[4] > 0.0 && cells[5] > 0.0, "{row}");
    }
    assert!(bench.contains("1 -> 2 threads: the render"), "{bench}");
    assert!(
        bench.contains("every render's image the same bit for bit: yes"),
        "{bench}"
    );
}
