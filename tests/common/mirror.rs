//! Parts for rooms with planar mirrors: quads facing each axis, and a room whose far wall is
//! an ideal mirror next to the same room doubled across the mirror's plane.

use glam::Vec3;
use meshlight::scene::PointLight;
use meshlight::Scene;

use super::{material, specular, Builder};

/// Shorthand for a point.
pub fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// A quad facing down (−y) at height y over [x0, x1] × [z0, z1].
pub fn facing_down(builder: &mut Builder, y: f32, x: [f32; 2], z: [f32; 2], m: u32) {
    builder.quad(
        [
            v(x[0], y, z[0]),
            v(x[1], y, z[0]),
            v(x[1], y, z[1]),
            v(x[0], y, z[1]),
        ],
        m,
    );
}

/// A quad facing up (+y) at height y over [x0, x1] × [z0, z1].
pub fn facing_up(builder: &mut Builder, y: f32, x: [f32; 2], z: [f32; 2], m: u32) {
    builder.quad(
        [
            v(x[0], y, z[0]),
            v(x[0], y, z[1]),
            v(x[1], y, z[1]),
            v(x[1], y, z[0]),
        ],
        m,
    );
}

/// A wall at x = `x` facing −x (`towards_minus`) or +x, over z ∈ [z0, z1], y ∈ [0, 2].
pub fn wall_x(builder: &mut Builder, x: f32, z: [f32; 2], towards_minus: bool, m: u32) {
    let mut corners = [
        v(x, 0., z[0]),
        v(x, 0., z[1]),
        v(x, 2., z[1]),
        v(x, 2., z[0]),
    ];
    if !towards_minus {
        corners.reverse();
    }
    builder.quad(corners, m);
}

/// A wall at z = `z` facing −z (`towards_minus`) or +z, over x ∈ [x0, x1], y ∈ [0, 2].
pub fn wall_z(builder: &mut Builder, z: f32, x: [f32; 2], towards_minus: bool, m: u32) {
    let mut corners = [
        v(x[0], 0., z),
        v(x[0], 2., z),
        v(x[1], 2., z),
        v(x[1], 0., z),
    ];
    if !towards_minus {
        corners.reverse();
    }
    builder.quad(corners, m);
}

/// What lights the mirror-room scenes.
#[derive(Clone, Copy)]
pub enum Light {
    /// An emitting square (Ke 4) hanging just under the ceiling, facing down.
    Area,
    /// A point light of 2 W/sr.
    Point,
}

/// Room [0, 2]³ of grey walls, seen from near x = 2 looking towards −x (so the wall at x = 2
/// is out of view), lit by `light` near x = 1.5. With `mirror` the wall at x = 2 is an ideal
/// mirror; without, the room goes on to x = 4 with every light mirrored across x = 2: what
/// the mirror shows.
pub fn mirror_room(light: Light, mirror: bool) -> Scene {
    let mut b = Builder::default();
    let grey = b.material(material("grey", 0.6, 0.0));
    let lamp = b.material(material("lamp", 0.0, 4.0));
    let end = if mirror { 2.0 } else { 4.0 };
    facing_up(&mut b, 0.0, [0.0, end], [0.0, 2.0], grey);
    facing_down(&mut b, 2.0, [0.0, end], [0.0, 2.0], grey);
    wall_z(&mut b, 0.0, [0.0, end], false, grey);
    wall_z(&mut b, 2.0, [0.0, end], true, grey);
    wall_x(&mut b, 0.0, [0.0, 2.0], false, grey);
    if mirror {
        let m = b.material(specular("mirror", 0.0, 1.0, 0.0));
        wall_x(&mut b, 2.0, [0.0, 2.0], true, m);
    } else {
        wall_x(&mut b, 4.0, [0.0, 2.0], true, grey);
    }
    // The light and, without the mirror, its image across x = 2.
    let xs: &[[f32; 2]] = if mirror {
        &[[1.2, 1.7]]
    } else {
        &[[1.2, 1.7], [2.3, 2.8]]
    };
    for &x in xs {
        match light {
            Light::Area => facing_down(&mut b, 1.98, x, [0.7, 1.3], lamp),
            Light::Point => b.point_lights.push(PointLight {
                position: v(0.5 * (x[0] + x[1]), 1.5, 1.0),
                intensity: Vec3::splat(2.0),
            }),
        }
    }
    b.scene(super::camera(v(1.9, 1.1, 1.0), v(0.0, 0.8, 1.0), 32))
}
