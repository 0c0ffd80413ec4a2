//! `mpirun -np N meshlight …` (the `mpi` feature): the same images and grids as one process,
//! the links shared out, rank 0 alone writing, and a failing rank ending the job at once.
//! Needs Open MPI's `mpirun` (Debian: openmpi-bin); .ci/run runs these.

#![cfg(feature = "mpi")]

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use meshlight::Image;

const BIN: &str = env!("CARGO_BIN_EXE_meshlight");
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `meshlight args` in one process, which must succeed.
fn alone(args: &[&str]) -> Output {
    let out = Command::new(BIN)
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("run meshlight");
    assert!(out.status.success(), "{}", text(&out.stderr));
    out
}

/// `mpirun -np n meshlight args` (as root in CI containers, and more ranks than cores).
fn mpirun(n: usize, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut command = Command::new("mpirun");
    // Containers often forbid the cross-memory attach Open MPI's shared memory uses for large
    // messages (it then fails with "Read -1"): copy through shared memory instead.
    command.env("OMPI_MCA_btl_vader_single_copy_mechanism", "none");
    command.args([
        "--allow-run-as-root",
        "--oversubscribe",
        "-np",
        &n.to_string(),
    ]);
    for (key, value) in env {
        command.env(key, value).args(["-x", key]);
    }
    command
        .arg(BIN)
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("run mpirun (Open MPI's openmpi-bin)")
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

fn pixels(path: &Path) -> Vec<f32> {
    let image = Image::read_exr(path).unwrap();
    image.pixels.iter().flat_map(|p| p.to_array()).collect()
}

/// "links held per rank at most X of Y" from the summary: X / Y.
fn held_share(stdout: &str) -> f64 {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("ranks: "))
        .unwrap_or_else(|| panic!("no ranks line in\n{stdout}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let at = words.iter().position(|&w| w == "most").unwrap();
    let held: f64 = words[at + 1].parse().unwrap();
    let all: f64 = words[at + 3].parse().unwrap();
    held / all
}

/// Renders `scene` alone and on 2 and 3 ranks, on both backends: the same image, bit for bit.
fn same_image(scene: &str, extra: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    for backend in ["embree", "bvh"] {
        let one = dir.path().join(format!("one-{backend}.exr"));
        let base = |out: &Path| -> Vec<String> {
            // A small image: the solve is what ranks share; the render splits rows the same
            // way at any size.
            let mut args: Vec<String> = [
                "render",
                scene,
                "--threads",
                "1",
                "--backend",
                backend,
                "--width",
                "128",
            ]
            .iter()
            .map(|s| s.to_string())
            .collect();
            args.extend(extra.iter().map(|s| s.to_string()));
            args.extend(["-o".into(), out.display().to_string()]);
            args
        };
        let args = base(&one);
        alone(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let reference = pixels(&one);
        for n in [2, 3] {
            let out_path = dir.path().join(format!("{n}-{backend}.exr"));
            let args = base(&out_path);
            let out = mpirun(n, &args.iter().map(String::as_str).collect::<Vec<_>>(), &[]);
            assert!(out.status.success(), "{}", text(&out.stderr));
            let stdout = text(&out.stdout);
            assert!(
                pixels(&out_path) == reference,
                "{scene}, {backend}, {n} ranks: the image differs from one process's"
            );
            // Only rank 0 prints: one summary.
            assert_eq!(stdout.matches("mean radiance").count(), 1, "{stdout}");
            let share = held_share(&stdout);
            let limit = if n == 2 { 0.6 } else { 0.45 };
            assert!(
                share <= limit,
                "{scene}, {backend}, {n} ranks: a rank holds {share:.2} of the links"
            );
        }
    }
}

#[test]
fn the_room_on_two_and_three_ranks_renders_one_process_image() {
    same_image("scenes/room/scene.toml", &[]);
}

#[test]
fn a_reduced_gallery_on_two_and_three_ranks_renders_one_process_image() {
    same_image(
        "scenes/gallery/scene.toml",
        &["--epsilon", "0.45", "--rounds", "1"],
    );
}

#[test]
fn lux_grids_on_two_ranks_are_one_process_grids() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    // The gallery lit by IES luminaires, with a work plane and two grids on paintings.
    let scene = "scenes/gallery/design.toml";
    let args = |out: &Path| -> Vec<String> {
        [
            "lux",
            scene,
            "--threads",
            "1",
            "--epsilon",
            "0.45",
            "--rounds",
            "1",
            "-o",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain([out.display().to_string()])
        .collect()
    };
    alone(&strs(&args(&a)));
    let out = mpirun(2, &strs(&args(&b)), &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let mut compared = 0;
    for entry in std::fs::read_dir(&a).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "csv") {
            let other = b.join(path.file_name().unwrap());
            assert_eq!(
                std::fs::read_to_string(&path).unwrap(),
                std::fs::read_to_string(&other).unwrap(),
                "{}",
                path.display()
            );
            compared += 1;
        }
    }
    assert!(compared > 0, "no grid was written");
}

#[test]
fn a_rank_that_fails_mid_solve_ends_the_job_with_its_error() {
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("never.exr");
    let started = Instant::now();
    let out = mpirun(
        3,
        &[
            "render",
            "scenes/gallery/scene.toml",
            "--threads",
            "1",
            "-o",
            out_path.to_str().unwrap(),
        ],
        &[("MESHLIGHT_FAIL_RANK", "1")],
    );
    let took = started.elapsed();
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "the job succeeded:\n{stderr}");
    assert!(stderr.contains("rank 1 failed on purpose"), "{stderr}");
    // The other ranks wait for rank 1 in the sweep's exchange: without the abort they would
    // wait for ever. A whole solve of this gallery takes about 6 s on 3 ranks here.
    assert!(took < Duration::from_secs(30), "took {took:?}");
    assert!(!out_path.exists(), "an image was written");
}

#[test]
fn commands_that_run_alone_refuse_several_ranks() {
    let out = mpirun(2, &["info", "scenes/room/scene.toml"], &[]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("only render, lux and samples run on several ranks"),
        "{}",
        text(&out.stderr)
    );
}
