//! The checks for scenes that would give a black or wrong image without an error: each fires
//! on the broken scene it is about, and none fires on the shipped scenes.

mod common;

use common::mirror::{facing_down, facing_up, v};
use common::{backends, camera, hall_of_columns, material, Builder};
use meshlight::diagnose::{before_solve, image, samples, Finding};
use meshlight::solver::Options;
use meshlight::Scene;

fn findings(scene: &Scene) -> Vec<Finding> {
    let mut all = Vec::new();
    for backend in backends() {
        let vis = backend.build(scene).unwrap();
        let found = before_solve(scene, vis.as_ref()).unwrap();
        if let Some(first) = all.first() {
            assert_eq!(&found, first, "{backend} finds otherwise");
        }
        all.push(found);
    }
    all.swap_remove(0)
}

fn says(found: &[Finding], words: &str) -> bool {
    found.iter().any(|f| f.message.contains(words))
}

/// A closed 4 × 3 × 4 room of grey seen from inside, with what `light` adds.
fn room(light: impl FnOnce(&mut Builder, u32)) -> Builder {
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.6, 0.0));
    b.room(v(0.0, 0.0, 0.0), v(4.0, 3.0, 4.0), grey, &[]);
    let lamp = b.material(material("lamp", 0.0, 10.0));
    light(&mut b, lamp);
    b
}

fn inside() -> meshlight::scene::Camera {
    camera(v(2.0, 1.5, 0.2), v(2.0, 1.2, 4.0), 32)
}

#[test]
fn a_correct_room_raises_nothing() {
    // The control for every case below: the same room lit from a panel facing down.
    let scene = room(|b, lamp| facing_down(b, 2.99, [1.5, 2.5], [1.5, 2.5], lamp)).scene(inside());
    assert_eq!(findings(&scene), vec![]);
}

#[test]
fn a_scene_without_light_is_fatal_and_names_the_exporters_habit() {
    let scene = room(|_, _| {}).scene(inside());
    let found = findings(&scene);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].fatal);
    assert!(says(&found, "nothing in the scene emits light") && says(&found, "Blender"));
}

#[test]
fn a_room_whose_faces_point_out_loses_its_light_to_their_backs() {
    // Blender's cube: every face points out, so the light inside meets only backs.
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.6, 0.0));
    b.solid(v(0.0, 0.0, 0.0), v(4.0, 3.0, 4.0), grey);
    let lamp = b.material(material("lamp", 0.0, 10.0));
    facing_down(&mut b, 2.99, [1.5, 2.5], [1.5, 2.5], lamp);
    let found = findings(&b.scene(inside()));
    assert!(!found.iter().any(|f| f.fatal));
    assert!(says(&found, "most of the light goes astray"), "{found:?}");
    assert!(says(&found, "material 'grey'") && says(&found, "two_sided"));
    assert!(
        says(&found, "the backs of one-sided faces (black)"),
        "{found:?}"
    );
}

#[test]
fn a_panel_facing_the_ceiling_from_a_centimetre_away_is_trapped() {
    let scene = room(|b, lamp| facing_up(b, 2.99, [1.5, 2.5], [1.5, 2.5], lamp)).scene(inside());
    let found = findings(&scene);
    assert!(says(&found, "faces a surface 0.01"), "{found:?}");
    assert!(says(&found, "material 'lamp'"));
}

#[test]
fn a_two_sided_panel_under_the_ceiling_is_told_its_upper_face_is_trapped_not_to_turn_two_sided() {
    // Blender's mesh lights (glTF doubleSided): the face towards the ceiling is trapped, and
    // the advice is not the one for a one-sided panel (it is two-sided already).
    let mut b = room(|b, lamp| facing_down(b, 2.99, [1.5, 2.5], [1.5, 2.5], lamp));
    b.mesh.materials[1].two_sided = true;
    let found = findings(&b.scene(inside()));
    assert!(says(&found, "faces a surface 0.01"), "{found:?}");
    assert!(says(&found, "two_sided = false"), "{found:?}");
    assert!(!says(&found, "set two_sided = true"), "{found:?}");
    // One line of prose, without the source's indentation in it.
    assert!(found.iter().all(|f| !f.message.contains("  ")), "{found:?}");
}

#[test]
fn a_light_facing_the_open_sky_sees_nothing() {
    // A floor and, above it, a panel facing up: its front sees nothing at all.
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.6, 0.0));
    facing_up(&mut b, 0.0, [0.0, 4.0], [0.0, 4.0], grey);
    let lamp = b.material(material("lamp", 0.0, 10.0));
    facing_up(&mut b, 1.0, [1.5, 2.5], [1.5, 2.5], lamp);
    let found = findings(&b.scene(camera(v(2.0, 3.0, -2.0), v(2.0, 0.0, 2.0), 32)));
    assert!(says(&found, "faces away from the scene"), "{found:?}");
    assert!(says(&found, "most of the light goes astray"), "{found:?}");
}

#[test]
fn a_camera_under_the_floor_is_outside_and_its_image_is_black() {
    // The position typed in Blender's Z-up coordinates: (2, 0.2, 1.5) becomes y = −1.5.
    let build = || room(|b, lamp| facing_down(b, 2.99, [1.5, 2.5], [1.5, 2.5], lamp));
    let scene = build().scene(camera(v(2.0, -1.5, 0.2), v(2.0, -1.5, 4.0), 16));
    let found = findings(&scene);
    assert!(says(&found, "outside the scene"), "{found:?}");
    // It looks along under the floor, at nothing: the image is black and says so; the same
    // room seen from inside is not.
    for (scene, black) in [(scene, true), (build().scene(inside()), false)] {
        let (_, picture) = common::solve_and_render(
            &scene,
            meshlight::Backend::default_backend(),
            Options::preview(),
            true,
        );
        let finding = image(&scene, &picture);
        assert_eq!(finding.is_some(), black, "{finding:?}");
        if black {
            assert!(finding.unwrap().message.contains("the image is black"));
        }
    }
}

#[test]
fn no_shipped_scene_raises_anything() {
    for name in [
        "box",
        "room",
        "cornell",
        "mirror-room",
        "glossy-room",
        "glass-room",
        "washroom",
    ] {
        let scene = Scene::load(common::shipped(name)).unwrap();
        assert_eq!(findings(&scene), vec![], "{name}");
    }
}

#[test]
fn columns_of_narrow_facets_are_told_their_samples_follow_the_tessellation() {
    // Round columns of 96 facets 2 cm wide: each facet gets a row of samples about ε apart
    // up its 4 m, against some 300 that the columns' 30 m² get at the walls' density.
    // Square columns of the same size (sides 0.6 m wide, over 2 ε): none of that. The square
    // columns' solve is the second route to what the area alone asks for: its first samples,
    // scaled by the sampled area (168 m² of room and 30.2 m² of round columns against 38.4 m²
    // of square ones' sides). With the adaptive rounds on, the note counts the first round's
    // samples only.
    let backend = backends()[0];
    let solved = |facets, rounds| {
        let scene = hall_of_columns(facets);
        let options = Options {
            epsilon: Some(0.25),
            rounds,
            ..Options::default()
        };
        let solution = common::solve(&scene, backend, options);
        let finding = samples(&scene, &solution);
        let first = solution.rounds()[0].samples;
        (first, solution.samples().len(), finding)
    };
    let (round, all, told) = solved(96, Options::default().rounds);
    let (square, _, silent) = solved(0, 0);
    eprintln!("first samples: round columns {round} ({all} after the rounds), square ones {square}; {told:?}");
    assert!(silent.is_none(), "square columns: {silent:?}");
    let told = told.expect("round columns: no finding");
    assert!(told.message.contains("tessellation") && !told.fatal);
    assert!(all > round, "the adaptive rounds added nothing");
    assert!(
        told.message
            .contains(&format!("of the {round} first samples")),
        "{}",
        told.message
    );
    // The columns' facets are all of the one material the hall has.
    assert!(
        told.message.contains("materials 'grey' "),
        "{}",
        told.message
    );
    assert!(round > 2 * square, "{round} samples against {square}");
    let by_area: f64 = told
        .message
        .split("about ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("the count by area");
    let expected = square as f64 * (168.0 + 30.2) / (168.0 + 38.4);
    assert!(
        (by_area / expected - 1.0).abs() < 0.15,
        "by area {by_area}, the square columns' solve says {expected:.0}"
    );
}

#[test]
fn no_shipped_scene_is_told_its_samples_follow_the_tessellation() {
    let gallery = meshlight_gallery::ensure().expect("generate the gallery");
    let scenes = std::fs::read_dir(common::shipped("room").parent().unwrap().parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().path().join("scene.toml"))
        .filter(|p| p.exists());
    let mut names = Vec::new();
    for path in scenes {
        let name = path.parent().unwrap().file_name().unwrap().to_owned();
        let path = if name == "gallery" {
            gallery.clone()
        } else if name == "atrium" {
            // The one made of small curved facets: the note is for it (performance.md).
            continue;
        } else {
            path
        };
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let options = Options {
            rounds: 0,
            ..Options::default()
        };
        let solution = common::solve(&scene, backends()[0], options);
        assert_eq!(samples(&scene, &solution), None, "{}", path.display());
        names.push(name);
    }
    assert!(names.len() >= 12, "shipped scenes checked: {names:?}");
}
