//! The loader's answers on the shipped scenes, against values worked out by hand from the
//! scene descriptions (not read back from the loader).

use std::f64::consts::PI;
use std::path::PathBuf;

fn scene(name: &str) -> meshlight::Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .join("scene.toml");
    meshlight::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-5 * b.abs().max(1.0)
}

#[test]
fn box_is_a_closed_unit_cube_of_six_emitting_faces() {
    let s = scene("box");
    assert_eq!(s.triangles().len(), 12);
    assert_eq!(s.surfaces().len(), 6);
    assert!(close(s.total_area(), 6.0), "{}", s.total_area());
    // Every face: Ke 0.1 over 1 m², power π·Ke·A.
    let emitters: Vec<_> = s.emitters().collect();
    assert_eq!(emitters.len(), 6);
    for (_, p) in &emitters {
        assert!(close(p.x, PI * 0.1), "{p}");
    }
    assert!(close(s.emitted_power().y, 6.0 * PI * 0.1));
    // Faces point inwards: every normal points towards the centre.
    for surface in s.surfaces() {
        let t = &s.triangles()[surface.triangles.start as usize];
        let to_centre = glam::Vec3::splat(0.5) - t.vertices[0];
        assert!(surface.normal.dot(to_centre) > 0.0);
        assert!(close(surface.area, 1.0));
    }
    assert!(s.warnings().is_empty(), "{:?}", s.warnings());
}

#[test]
fn room_has_walls_light_and_two_boxes() {
    let s = scene("room");
    // 6 walls + 1 light + 2 boxes × 5 faces (no bottoms), each face a quad of 2 triangles.
    assert_eq!(s.surfaces().len(), 6 + 1 + 10);
    assert_eq!(s.triangles().len(), 2 * 17);
    // 5.5 m wide and high, 9 m deep.
    let walls = 4.0 * 5.5 * 9.0 + 2.0 * 5.5 * 5.5;
    let light = 1.2 * 1.2;
    let short_box = 5.0 * 1.65 * 1.65;
    let tall_box = 4.0 * 1.65 * 3.3 + 1.65 * 1.65;
    let total = walls + light + short_box + tall_box;
    assert!(
        close(s.total_area(), total),
        "{} vs {total}",
        s.total_area()
    );
    let emitters: Vec<_> = s.emitters().collect();
    assert_eq!(emitters.len(), 1);
    let (surface, power) = emitters[0];
    assert!(close(power.x, PI * 10.0 * light), "{power}");
    // The light faces down and sits 1 cm under the 5.5 m ceiling.
    let light_surface = &s.surfaces()[surface as usize];
    assert!((light_surface.normal - glam::Vec3::NEG_Y).length() < 1e-6);
    assert!(close(f64::from(-light_surface.offset), 5.49));
    assert_eq!(s.point_lights().len(), 0);
    assert_eq!((s.camera().width, s.camera().height), (512, 512));
    assert_eq!(s.solver_defaults().epsilon, Some(0.25));
    let red = s.materials().iter().find(|m| m.name == "red").unwrap();
    assert_eq!(red.kd, glam::Vec3::new(0.63, 0.065, 0.05));
}

#[test]
fn gallery_is_gallery_scale() {
    let path = meshlight_gallery::ensure().expect("generate the gallery");
    let s = meshlight::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        s.triangles().len() >= 100_000,
        "{} triangles",
        s.triangles().len()
    );
    assert_eq!(s.point_lights().len(), 8);
    for light in s.point_lights() {
        assert!(
            light.position.y > 4.0 && light.position.y < 4.5,
            "under the ceiling: {light:?}"
        );
    }
    assert_eq!(s.emitters().count(), 0);
    // 24 m × 16 m × 4.5 m building.
    assert_eq!(s.bounds().max, glam::Vec3::new(24.0, 4.5, 16.0));
    assert!(s.warnings().is_empty(), "{:?}", s.warnings());
}

#[test]
fn the_atrium_is_made_of_small_curved_facets() {
    // Artist-made geometry in kind: most of its planar surfaces are facets of columns, arches,
    // vaults and cloths, and none of its triangles is degenerate or hidden in a solid's face.
    let path = meshlight_atrium::ensure().expect("generate the atrium");
    let s = meshlight::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        s.triangles().len() > 20_000,
        "{} triangles",
        s.triangles().len()
    );
    let small = s.surfaces().iter().filter(|f| f.area < 0.5).count();
    assert!(
        small > 10_000 && small * 10 > 9 * s.surfaces().len(),
        "{small} of {} surfaces under 0.5 m²",
        s.surfaces().len()
    );
    assert_eq!(s.point_lights().len(), 5);
    assert_eq!(s.bounds().max, glam::Vec3::new(24.0, 11.0, 12.0));
    assert!(s.warnings().is_empty(), "{:?}", s.warnings());
}

#[test]
fn the_designed_gallery_has_its_luminaires_and_grids() {
    let path = meshlight_gallery::ensure().expect("generate the gallery");
    let design = path.with_file_name("design.toml");
    let s = meshlight::Scene::load(&design).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.units(), meshlight::scene::Units::Photometric);
    assert_eq!((s.luminaires().len(), s.grids().len()), (11, 3));
    // The downlight was written as I₀ cos³γ for 1,800 lm: Φ = 2π I₀ / 4 (by hand).
    let flux = s.luminaires()[0].flux().y;
    assert!((flux / 1800.0 - 1.0).abs() < 0.005, "{flux} lm");
    // Grid counts by `docs/scene-format.md`'s rule: 7.8 × 11.7 m at 0.2 · 5^log10(11.7) = 1.1 m → 7 × 11.
    assert_eq!(s.grids()[0].counts_uv(), (7, 11));
    assert_eq!(s.grids()[1].counts_uv(), (16, 11));
    assert!(s.warnings().is_empty(), "{:?}", s.warnings());
}
