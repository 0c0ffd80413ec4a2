//! The whole solve, flat against hierarchical, on the shipped room and on a reduced gallery
//! (big tiles, icosahedra, ε 0.6, no adaptive rounds): `cargo bench --bench solver`. The ratio
//! of the two on one machine in one run is the figure to read.

use std::path::PathBuf;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use meshlight::solver::{Control, Options};
use meshlight::{Backend, Scene};

fn scenes() -> Vec<(&'static str, Scene, Options)> {
    let room = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/room/scene.toml");
    let dir = std::env::temp_dir().join(format!("meshlight-bench-gallery-{}", std::process::id()));
    meshlight_gallery::write_scene(
        &dir,
        meshlight_gallery::GalleryOptions {
            tile: 0.5,
            sphere_detail: 0,
            ..Default::default()
        },
    )
    .expect("write the reduced gallery");
    let gallery = Scene::load(dir.join("scene.toml")).expect("load the reduced gallery");
    let _ = std::fs::remove_dir_all(&dir);
    vec![
        (
            "room",
            Scene::load(room).expect("load room"),
            Options::default(),
        ),
        (
            "reduced-gallery",
            gallery,
            Options {
                epsilon: Some(0.6),
                rounds: 0,
                ..Options::default()
            },
        ),
    ]
}

fn solver(c: &mut Criterion) {
    let backend = Backend::default_backend();
    for (name, scene, options) in scenes() {
        let vis = backend.build(&scene).expect("build backend");
        let mut group = c.benchmark_group(format!("solve/{name}"));
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(10));
        for (label, threshold) in [("flat", 0.0), ("hierarchy", options.cluster_threshold)] {
            let options = Options {
                cluster_threshold: threshold,
                ..options.clone()
            };
            group.bench_function(BenchmarkId::new(label, backend.name()), |b| {
                b.iter(|| {
                    meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| Control::Continue)
                        .expect("solve")
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, solver);
criterion_main!(benches);
