//! The scene's mean free path: how far light leaving a reflecting surface travels, on average,
//! before it meets the next surface. It is the length over which a room's light changes — for
//! a closed room, Cauchy's mean chord 4V/S (four times its volume over its area) — so a
//! spacing chosen as a fraction of it gives a scene the same samples at any scale and whatever
//! spacing its file asks for, and more samples where the scene is cut into more rooms or
//! filled with more things (the presets' ε, [`crate::Options::free_path_epsilon`]).
//!
//! Measured by rays: points spread by area over the sides light reaches, each casting
//! cosine-distributed rays (the directions light leaves a diffuse surface in); rays that leave
//! the scene do not count.
//!
//! A lamp close to a surface makes a pool of light about as wide as its distance from it, far
//! smaller than a room; the length the presets take ([`light_length`]) is the free path
//! shortened by such a lamp, never below a quarter of it (the adaptive rounds resolve what is
//! finer).

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::directions::cosine;
use super::lit::probe_points;
use super::{surface_of, Side};
use crate::error::Result;
use crate::scene::Scene;
use crate::visibility::{Ray, Visibility};

/// Probe points over the whole scene, shared among the sides by area.
const POINTS: f64 = 8192.0;
/// Rays per probe point.
const RAYS: usize = 4;
/// Below this share of rays meeting a surface the scene is too open to have a free path (a
/// floor under a lamp, a façade under the sky).
const MIN_HIT_SHARE: f64 = 0.05;
/// Seed of the probes (fixed: the answer is the scene's, not the solve's).
const SEED: u64 = 0x6672_6565_7061_7468;

/// The mean distance from a point on `sides` (by area) along a cosine-distributed direction to
/// the next surface, or `None` where fewer than one ray in twenty meets one.
pub fn mean_free_path(scene: &Scene, vis: &dyn Visibility, sides: &[Side]) -> Result<Option<f64>> {
    let total: f64 = sides
        .iter()
        .map(|&s| scene.surfaces[surface_of(s) as usize].area)
        .sum();
    if total.is_nan() || total <= 0.0 {
        return Ok(None);
    }
    let lift = crate::visibility::lift(scene);
    let mut rng = Pcg64Mcg::seed_from_u64(SEED);
    let mut rays = Vec::new();
    for &side in sides {
        // A side's share of the points, rounded at random so small facets count by their area
        // in expectation (a column of many facets is not over-counted).
        let share = scene.surfaces[surface_of(side) as usize].area / total * POINTS;
        let count = share.floor() as usize + usize::from(rng.random::<f64>() < share.fract());
        if count == 0 {
            continue;
        }
        let (points, normal) = probe_points(scene, side, count, lift);
        for x in points {
            for _ in 0..RAYS {
                rays.push(Ray {
                    origin: x,
                    dir: cosine(normal, rng.random(), rng.random()),
                    t_min: 0.0,
                    t_max: f32::INFINITY,
                });
            }
        }
    }
    let mut hits = vec![None; rays.len()];
    vis.intersect(&rays, &mut hits)?;
    let (sum, met) = hits
        .iter()
        .flatten()
        .fold((0.0, 0usize), |(sum, n), h| (sum + f64::from(h.t), n + 1));
    if rays.is_empty() || (met as f64) < MIN_HIT_SHARE * rays.len() as f64 {
        return Ok(None);
    }
    Ok(Some(sum / met as f64))
}

/// Rays cast from each lamp to find the nearest surface it lights.
const LAMP_RAYS: usize = 256;

/// How many of a lamp's clearances the length it allows spans: the gallery's lamps, 0.2 m
/// under a ceiling in rooms of 4.4 m free path, need samples twice as fine as the free path
/// alone gives without adaptive rounds (`docs/performance.md`, "Presets").
pub const LAMP_LENGTHS: f64 = 9.0;

/// The distance from the point lights and luminaires to the nearest surface any of them sees
/// (over 256 directions each), or `None` without them or where every ray leaves.
pub fn lamp_clearance(scene: &Scene, vis: &dyn Visibility) -> Result<Option<f64>> {
    let lamps: Vec<_> = scene.lamp_positions().collect();
    // Spread evenly over the sphere (a Fibonacci lattice): the same directions every time.
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let rays: Vec<Ray> = lamps
        .iter()
        .flat_map(|&origin| {
            (0..LAMP_RAYS).map(move |k| {
                let z = 1.0 - (2 * k + 1) as f32 / LAMP_RAYS as f32;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = golden * k as f32;
                Ray {
                    origin,
                    dir: glam::Vec3::new(r * phi.cos(), r * phi.sin(), z),
                    t_min: 0.0,
                    t_max: f32::INFINITY,
                }
            })
        })
        .collect();
    let mut hits = vec![None; rays.len()];
    vis.intersect(&rays, &mut hits)?;
    Ok(hits
        .iter()
        .flatten()
        .map(|h| f64::from(h.t))
        .min_by(f64::total_cmp))
}

/// The scene's lengths that set the presets' spacing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightLength {
    /// [`mean_free_path`] over the sides light reaches.
    pub free_path: f64,
    /// [`lamp_clearance`], where the scene has lamps.
    pub lamp_clearance: Option<f64>,
    /// The length ε is a fraction of: the free path, or 9 × the lamps'
    /// clearance where that is shorter, but not below a quarter of the free path.
    pub length: f64,
}

impl LightLength {
    /// The length ε is taken from with `rounds` adaptive rounds: a lamp's pool is resolved by
    /// the rounds where there are any; without them ε itself must follow it.
    pub fn for_rounds(&self, rounds: u32) -> f64 {
        if rounds == 0 {
            self.length
        } else {
            self.free_path
        }
    }
}

/// The length over which the scene's light changes (see [`LightLength`]), or `None` for a scene
/// too open to have a free path.
pub fn light_length(
    scene: &Scene,
    vis: &dyn Visibility,
    sides: &[Side],
) -> Result<Option<LightLength>> {
    let Some(free_path) = mean_free_path(scene, vis, sides)? else {
        return Ok(None);
    };
    let lamp_clearance = lamp_clearance(scene, vis)?;
    let length = match lamp_clearance {
        Some(h) => free_path.min((LAMP_LENGTHS * h).max(free_path / 4.0)),
        None => free_path,
    };
    Ok(Some(LightLength {
        free_path,
        lamp_clearance,
        length,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::reflecting_sides;
    use crate::scene::fixtures::Parts;
    use crate::scene::Material;
    use crate::visibility::Backend;
    use glam::Vec3;

    fn free_path(parts: Parts) -> f64 {
        let scene = parts.scene(Vec3::new(1.0, 1.0, 0.5), Vec3::new(1.0, 1.0, 2.0));
        let vis = Backend::Bvh.build(&scene).unwrap();
        mean_free_path(&scene, vis.as_ref(), &reflecting_sides(&scene))
            .unwrap()
            .unwrap()
    }

    #[test]
    fn a_closed_room_s_free_path_is_four_times_its_volume_over_its_area() {
        // Cauchy: the mean chord of a closed cavity under cosine-distributed (isotropic-flux)
        // rays is 4V/S, whatever its shape; with a solid in it, V is the air and S counts the
        // solid's faces too.
        let mut empty = Parts::default();
        let white = empty.material(Material::diffuse("white", Vec3::splat(0.5), Vec3::ZERO));
        empty.cuboid(Vec3::ZERO, Vec3::new(4.0, 3.0, 2.0), true, white);
        let expected = 4.0 * 24.0 / (2.0 * (12.0 + 8.0 + 6.0));
        let measured = free_path(empty);
        assert!(
            (measured / expected - 1.0).abs() < 0.02,
            "{measured} vs {expected}"
        );

        let mut furnished = Parts::default();
        let white = furnished.material(Material::diffuse("white", Vec3::splat(0.5), Vec3::ZERO));
        furnished.cuboid(Vec3::ZERO, Vec3::new(4.0, 3.0, 2.0), true, white);
        furnished.cuboid(
            Vec3::new(1.0, 1.0, 0.5),
            Vec3::new(3.0, 2.0, 1.5),
            false,
            white,
        );
        // A 2 x 1 x 1 solid floating in the room.
        let volume = 24.0 - 2.0;
        let area = 52.0 + 2.0 * (2.0 + 2.0 + 1.0);
        let expected = 4.0 * volume / area;
        let measured = free_path(furnished);
        assert!(
            (measured / expected - 1.0).abs() < 0.02,
            "{measured} vs {expected}"
        );
    }

    #[test]
    fn a_lamp_near_the_ceiling_shortens_the_length_to_its_pool_but_not_below_a_quarter() {
        let lit = |height: f32| {
            let mut room = Parts::default();
            let white = room.material(Material::diffuse("white", Vec3::splat(0.5), Vec3::ZERO));
            room.cuboid(Vec3::ZERO, Vec3::new(4.0, 3.0, 2.0), true, white);
            let mut scene = room.scene(Vec3::new(1.0, 1.0, 0.5), Vec3::new(1.0, 1.0, 2.0));
            scene.point_lights.push(crate::scene::PointLight {
                position: Vec3::new(2.0, height, 1.0),
                intensity: Vec3::ONE,
            });
            let vis = Backend::Bvh.build(&scene).unwrap();
            light_length(&scene, vis.as_ref(), &reflecting_sides(&scene))
                .unwrap()
                .unwrap()
        };
        let free_path = 4.0 * 24.0 / 52.0;
        // In the middle (0.9 m from the ceiling, 1 m from the end walls): 9 × 0.9 is far
        // longer than the free path, which stands.
        let middle = lit(2.1);
        assert!(
            (middle.lamp_clearance.unwrap() / 0.9 - 1.0).abs() < 0.01,
            "{middle:?}"
        );
        assert_eq!(middle.length, middle.free_path);
        // 0.1 m under the ceiling: 0.9 m, shorter than the free path.
        let near = lit(2.9);
        assert!(
            (near.lamp_clearance.unwrap() / 0.1 - 1.0).abs() < 0.01,
            "{near:?}"
        );
        assert!((near.length / 0.9 - 1.0).abs() < 0.01, "{near:?}");
        // 1 cm under it: a quarter of the free path, not 0.09 m.
        let touching = lit(2.99);
        assert!(
            (touching.length / (free_path / 4.0) - 1.0).abs() < 0.02,
            "{touching:?}"
        );
    }

    #[test]
    fn an_open_scene_has_none() {
        let mut floor = Parts::default();
        let white = floor.material(Material::diffuse("white", Vec3::splat(0.5), Vec3::ZERO));
        // A thin slab: its top and bottom see only the sky.
        floor.cuboid(Vec3::ZERO, Vec3::new(100.0, 0.01, 100.0), false, white);
        let scene = floor.scene(Vec3::new(1.0, 1.0, 0.5), Vec3::new(1.0, 0.0, 2.0));
        let vis = Backend::Bvh.build(&scene).unwrap();
        assert_eq!(
            mean_free_path(&scene, vis.as_ref(), &reflecting_sides(&scene)).unwrap(),
            None
        );
    }
}
