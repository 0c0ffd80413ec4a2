//! Occlusion and closest-hit throughput of each backend on the shipped room and gallery, as
//! `meshlight bench-vis` measures them, under criterion: `cargo bench --bench visibility`.

use std::path::PathBuf;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use meshlight::{Backend, Scene};

#[path = "../cli/src/workload.rs"]
mod workload;
use workload::{camera_rays, facing_segments};

const SEGMENTS: usize = 100_000;
const RAYS: usize = 20_000;
const BATCH: usize = 1024;

fn scenes() -> Vec<(&'static str, Scene)> {
    let room = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/room/scene.toml");
    let gallery = meshlight_gallery::ensure().expect("generate the gallery");
    vec![
        ("room", Scene::load(room).expect("load room")),
        ("gallery", Scene::load(gallery).expect("load gallery")),
    ]
}

fn visibility(c: &mut Criterion) {
    for (name, scene) in scenes() {
        let segments = facing_segments(&scene, SEGMENTS, 1);
        let rays = camera_rays(&scene, RAYS, 2);
        let mut group = c.benchmark_group(format!("visibility/{name}"));
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(4));
        for backend in Backend::available() {
            let vis = backend.build(&scene).expect("build backend");
            let mut occluded = vec![false; segments.len()];
            group.throughput(Throughput::Elements(segments.len() as u64));
            group.bench_function(BenchmarkId::new("occluded", backend.name()), |b| {
                b.iter(|| {
                    for (s, o) in segments.chunks(BATCH).zip(occluded.chunks_mut(BATCH)) {
                        vis.occluded(s, o).expect("occluded");
                    }
                })
            });
            let mut hits = vec![None; rays.len()];
            group.throughput(Throughput::Elements(rays.len() as u64));
            group.bench_function(BenchmarkId::new("intersect", backend.name()), |b| {
                b.iter(|| {
                    for (r, o) in rays.chunks(BATCH).zip(hits.chunks_mut(BATCH)) {
                        vis.intersect(r, o).expect("intersect");
                    }
                })
            });
        }
        group.sample_size(10);
        for backend in Backend::available() {
            group.throughput(Throughput::Elements(scene.triangles().len() as u64));
            group.bench_function(BenchmarkId::new("build", backend.name()), |b| {
                b.iter(|| backend.build(&scene).expect("build backend"))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, visibility);
criterion_main!(benches);
