//! Embree and obvhs answer the same queries the same way, on every shipped scene: at least a
//! million segments between facing surface points and 100k camera rays each.

#![cfg(feature = "embree")]

use std::path::PathBuf;

use meshlight::visibility::{intersect_all, occluded_all, Visibility};
use meshlight::visibility::{BvhPreset, BvhScene, EmbreeOptions, EmbreeScene, Hit, Ray, Segment};
use meshlight::Scene;

#[path = "../cli/src/workload.rs"]
mod workload;
use workload::{camera_rays, facing_segments};

const SEGMENTS: usize = 1_000_000;
const RAYS: usize = 100_000;

fn shipped(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .join("scene.toml")
}

fn check(scene: &Scene) {
    let segments = facing_segments(scene, SEGMENTS, 7);
    assert_eq!(segments.len(), SEGMENTS, "enough facing pairs");
    let rays = camera_rays(scene, RAYS, 8);
    let embree = EmbreeScene::new(scene, EmbreeOptions::default()).unwrap();
    let bvh = BvhScene::new(scene, BvhPreset::default());

    let occ_e = occluded_all(&embree, &segments, 2).unwrap();
    let occ_b = occluded_all(&bvh, &segments, 2).unwrap();
    let blocked = occ_e.iter().filter(|&&b| b).count();
    assert!(
        blocked > 0 || scene.triangles().len() < 20,
        "some segments are blocked: {blocked}"
    );
    let differ: Vec<usize> = (0..segments.len())
        .filter(|&i| occ_e[i] != occ_b[i])
        .collect();
    assert!(
        differ.len() as f64 <= 1e-5 * segments.len() as f64,
        "{}: {} of {} occlusion answers differ, e.g.:\n{}",
        scene.path().display(),
        differ.len(),
        segments.len(),
        list_segments(&differ, &segments, &occ_e)
    );

    let hit_e = intersect_all(&embree, &rays, 2).unwrap();
    let hit_b = intersect_all(&bvh, &rays, 2).unwrap();
    let mut bad = Vec::new();
    for i in 0..rays.len() {
        let agree = match (hit_e[i], hit_b[i]) {
            (Some(a), Some(b)) => (a.t - b.t).abs() <= 1e-4 * a.t.max(b.t),
            (None, None) => true,
            _ => false,
        };
        if !agree {
            bad.push(i);
        }
    }
    assert!(
        bad.len() as f64 <= 1e-5 * rays.len() as f64,
        "{}: {} of {} closest hits differ, e.g.:\n{}",
        scene.path().display(),
        bad.len(),
        rays.len(),
        list_rays(&bad, &rays, &hit_e, &hit_b)
    );
}

fn list_segments(which: &[usize], segments: &[Segment], embree: &[bool]) -> String {
    which
        .iter()
        .take(20)
        .map(|&i| format!("  #{i}: {:?} embree blocked={}", segments[i], embree[i]))
        .collect::<Vec<_>>()
        .join("\n")
}

fn list_rays(which: &[usize], rays: &[Ray], a: &[Option<Hit>], b: &[Option<Hit>]) -> String {
    which
        .iter()
        .take(20)
        .map(|&i| format!("  #{i}: {:?} embree {:?} bvh {:?}", rays[i], a[i], b[i]))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn backends_agree_on_box() {
    check(&Scene::load(shipped("box")).unwrap());
}

#[test]
fn backends_agree_on_room() {
    check(&Scene::load(shipped("room")).unwrap());
}

#[test]
fn backends_agree_on_gallery() {
    let path = meshlight_gallery::ensure().expect("generate the gallery");
    check(&Scene::load(path).unwrap());
}

#[test]
fn both_backends_see_the_known_answer_through_the_room() {
    // Straight ahead above the boxes: the back wall at z = 9; low through the short box: blocked.
    let scene = Scene::load(shipped("room")).unwrap();
    let ray = Ray {
        origin: glam::Vec3::new(0.3, 5.0, 0.1),
        dir: glam::Vec3::Z,
        t_min: 0.0,
        t_max: f32::INFINITY,
    };
    let floor_to_ceiling = Segment {
        a: glam::Vec3::new(0.3, 0.01, 0.3),
        b: glam::Vec3::new(0.3, 5.49, 0.3),
    };
    let through_box = Segment {
        a: glam::Vec3::new(1.85, 0.5, 0.01),
        b: glam::Vec3::new(1.85, 0.5, 5.49),
    };
    for vis in [
        Box::new(EmbreeScene::new(&scene, EmbreeOptions::default()).unwrap())
            as Box<dyn meshlight::Visibility>,
        Box::new(BvhScene::new(&scene, BvhPreset::default())),
    ] {
        let mut hit = [None];
        vis.intersect(&[ray], &mut hit).unwrap();
        let hit = hit[0].unwrap_or_else(|| panic!("{} missed the back wall", vis.name()));
        assert!((hit.t - 8.9).abs() < 1e-5, "{}: t = {}", vis.name(), hit.t);
        assert_eq!(
            scene.triangles()[hit.triangle as usize].normal,
            glam::Vec3::NEG_Z
        );
        let mut blocked = [true, false];
        vis.occluded(&[floor_to_ceiling, through_box], &mut blocked)
            .unwrap();
        assert_eq!(blocked, [false, true], "{}", vis.name());
    }
}

#[test]
fn rays_embree_cannot_take_are_refused_not_an_abort() {
    // Embree asserts (and the process dies) on NaN or huge coordinates and NaN or negative
    // distances, obvhs on non-finite ones; the library checks every batch first and refuses
    // the first bad ray by its index, on both backends.
    let scene = Scene::load(shipped("box")).unwrap();
    let embree = EmbreeScene::new(&scene, EmbreeOptions::default()).unwrap();
    let bvh = BvhScene::new(&scene, BvhPreset::default());
    let good = Ray {
        origin: glam::Vec3::splat(0.5),
        dir: glam::Vec3::X,
        t_min: 0.0,
        t_max: f32::INFINITY,
    };
    let nan = f32::NAN;
    let bad = [
        Ray {
            origin: glam::Vec3::new(nan, 0.5, 0.5),
            ..good
        },
        Ray {
            dir: glam::Vec3::new(f32::INFINITY, 0.0, 0.0),
            ..good
        },
        Ray { t_min: nan, ..good },
        Ray {
            t_min: -1.0,
            ..good
        },
        Ray { t_max: nan, ..good },
        Ray {
            origin: glam::Vec3::splat(1e30),
            ..good
        },
    ];
    for ray in bad {
        let mut out = [None, None];
        let e = embree
            .intersect(&[good, ray], &mut out)
            .expect_err("a bad ray refused");
        assert!(e.to_string().contains("ray 1 of 2"), "{e}");
        let e = bvh.intersect(&[good, ray], &mut out).expect_err("refused");
        assert!(e.to_string().contains("ray 1 of 2"), "{e}");
    }
    // The good ray alone is answered: the box's wall at x = 1, half a unit away.
    let mut out = [None];
    embree.intersect(&[good], &mut out).unwrap();
    assert!((out[0].unwrap().t - 0.5).abs() < 1e-4);
    for b in [glam::Vec3::new(nan, 0.0, 0.0), glam::Vec3::splat(1e30)] {
        let s = Segment {
            a: glam::Vec3::splat(0.5),
            b,
        };
        let mut out = [false];
        let e = embree.occluded(&[s], &mut out).expect_err("refused");
        assert!(e.to_string().contains("segment 0 of 1"), "{e}");
        let e = bvh.occluded(&[s], &mut out).expect_err("refused");
        assert!(e.to_string().contains("segment 0 of 1"), "{e}");
    }
}
