//! Which reflecting sides light can reach. A scene exported with every face two-sided (glTF's
//! `doubleSided`, Blender's default) hands the solver the outer faces of its rooms and the
//! insides of its closed objects as reflecting sides; no light ever gets there, yet they took
//! half the samples, and the automatic ε grew by √2 to spread its budget over them. Such sides
//! are left without samples: they render black, which is what they are.
//!
//! Only sides of two-sided surfaces are ever left out (a one-sided front is what the scene
//! says reflects), and only in scenes where light travels from lights to diffuse surfaces and
//! between diffuse surfaces alone (no daylight, no specular surface: light that goes out to
//! the sky or through a mirror is not followed here). A side is reached when a point light or
//! luminaire shines on one of its probe points unblocked, or one of the probes' rays meets an
//! emitter, a side kept for what it is (a one-sided front, an emitter's), or a side reached;
//! the reached set grows until nothing changes. Probe points cover each side by area (at least
//! [`MIN_PROBES`], about [`PROBES`] over the whole scene), each with [`RAYS`]
//! cosine-distributed rays: a side reached only through an opening narrower than the probes'
//! spacing is missed.

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::directions::cosine;
use super::triangles::{cumulative_area, in_triangle};
use super::{is_back, reflecting_sides, side_of, surface_of, Side};
use crate::error::Result;
use crate::scene::Scene;
use crate::visibility::{Ray, Segment, Visibility};

/// Probe points over all the candidate sides together, shared by area.
const PROBES: f64 = 16_384.0;
/// Probe points on each candidate side at least, however small.
const MIN_PROBES: usize = 16;
/// Probe points on each candidate side at most.
const MAX_PROBES: usize = 1024;
/// Rays per probe point.
const RAYS: usize = 8;
/// Rays cast in one batch (the sides' probes are gathered until they pass this).
const BATCH_RAYS: usize = 1 << 14;
/// Seed of the probes (fixed: the answer is the scene's, not the solve's).
const SEED: u64 = 0x6c69_745f_7369_6465;

/// The reflecting sides light can reach, in [`reflecting_sides`]' order: all of them when
/// the scene has daylight or specular surfaces, when none is two-sided, or when no light
/// reaches any (a dark scene is said so elsewhere, on all its sides).
pub fn lit_sides(scene: &Scene, vis: &dyn Visibility) -> Result<Vec<Side>> {
    lit_sides_heard(scene, vis, &mut |_| false)
}

/// [`lit_sides`], telling `stop` the share of the sides probed before each batch of probes and
/// once all are, and hearing from it whether the host wants to stop: then the probing ends and
/// every reflecting side is kept, as in a scene whose light reaches them all. (Probes in a
/// mesh whose triangles all lie in each other's boxes, thousands of facets fanned round one
/// edge, can take minutes.)
pub(crate) fn lit_sides_heard(
    scene: &Scene,
    vis: &dyn Visibility,
    stop: &mut dyn FnMut(f64) -> bool,
) -> Result<Vec<Side>> {
    let all = reflecting_sides(scene);
    // Only the materials surfaces use: an MTL file may list a glass nothing is made of.
    let specular = scene
        .surfaces
        .iter()
        .any(|s| scene.materials[s.material as usize].is_specular());
    let candidate = |side: Side| scene.surfaces[surface_of(side) as usize].two_sided;
    if scene.daylight.is_some() || specular || !all.iter().any(|&s| candidate(s)) {
        return Ok(all);
    }
    let n_sides = 2 * scene.surfaces.len();
    // What each side is to a probe ray that meets it: a source (kept, or emitting), a
    // candidate (a source once reached), or nothing.
    let mut reached = vec![false; n_sides];
    let mut source = vec![false; n_sides];
    for (i, s) in scene.surfaces.iter().enumerate() {
        let m = &scene.materials[s.material as usize];
        if m.is_emitter() {
            source[side_of(i as u32, false) as usize] = true;
            source[side_of(i as u32, true) as usize] = true;
        }
    }
    for &side in &all {
        if !candidate(side) {
            source[side as usize] = true;
        }
    }
    let candidates: Vec<Side> = all.iter().copied().filter(|&s| candidate(s)).collect();
    let total: f64 = candidates
        .iter()
        .map(|&s| scene.surfaces[surface_of(s) as usize].area)
        .sum();
    let lift = crate::visibility::lift(scene);
    let lights: Vec<Vec3> = scene.lamp_positions().collect();
    // The candidates' probes, in batches of segments to the lights and of rays (a few
    // thousand sides at a time, so a scene of many small faces does not hold all at once).
    let mut seen_from: Vec<Vec<Side>> = vec![Vec::new(); candidates.len()];
    let mut first = 0;
    while first < candidates.len() {
        if stop(first as f64 / candidates.len() as f64) {
            return Ok(all);
        }
        let mut segments: Vec<(usize, Segment)> = Vec::new();
        let mut rays: Vec<(usize, Ray)> = Vec::new();
        let mut c = first;
        while c < candidates.len() && rays.len() < BATCH_RAYS {
            let side = candidates[c];
            let surface = &scene.surfaces[surface_of(side) as usize];
            let count =
                ((surface.area / total * PROBES).ceil() as usize).clamp(MIN_PROBES, MAX_PROBES);
            let (points, normal) = probe_points(scene, side, count, lift);
            let mut rng = Pcg64Mcg::seed_from_u64(SEED ^ u64::from(side).wrapping_mul(0x9e37_79b9));
            for &x in &points {
                for &l in &lights {
                    if normal.dot(l - x) > 0.0 {
                        segments.push((c, Segment { a: x, b: l }));
                    }
                }
                for _ in 0..RAYS {
                    let dir = cosine(normal, rng.random(), rng.random());
                    let ray = Ray {
                        origin: x,
                        dir,
                        t_min: 0.0,
                        t_max: f32::INFINITY,
                    };
                    rays.push((c, ray));
                }
            }
            c += 1;
        }
        first = c;
        let mut blocked = vec![true; segments.len()];
        let only: Vec<Segment> = segments.iter().map(|s| s.1).collect();
        vis.occluded(&only, &mut blocked)?;
        for ((c, _), blocked) in segments.iter().zip(&blocked) {
            if !blocked {
                reached[candidates[*c] as usize] = true;
            }
        }
        let mut hits = vec![None; rays.len()];
        let only: Vec<Ray> = rays.iter().map(|r| r.1).collect();
        vis.intersect(&only, &mut hits)?;
        for ((c, ray), hit) in rays.iter().zip(&hits) {
            let Some(t) = hit.and_then(|h| scene.triangles.get(h.triangle as usize)) else {
                continue;
            };
            let met = side_of(t.surface, ray.dir.dot(t.normal) > 0.0);
            if source[met as usize] {
                reached[candidates[*c] as usize] = true;
            }
            seen_from[*c].push(met);
        }
    }
    stop(1.0);
    for met in &mut seen_from {
        met.sort_unstable();
        met.dedup();
    }
    // Light spreads from reached sides to the candidates that see them.
    loop {
        let mut changed = false;
        for (c, &side) in candidates.iter().enumerate() {
            if !reached[side as usize] && seen_from[c].iter().any(|&s| reached[s as usize]) {
                reached[side as usize] = true;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    if !candidates.iter().any(|&s| reached[s as usize]) {
        return Ok(all);
    }
    Ok(all
        .into_iter()
        .filter(|&s| !candidate(s) || reached[s as usize])
        .collect())
}

/// `count` points spread by area over a side (lifted off it), and the side's normal.
pub(super) fn probe_points(
    scene: &Scene,
    side: Side,
    count: usize,
    lift: f32,
) -> (Vec<Vec3>, Vec3) {
    let surface = &scene.surfaces[surface_of(side) as usize];
    let normal = if is_back(side) {
        -surface.normal
    } else {
        surface.normal
    };
    let triangles: Vec<_> = scene.triangles
        [surface.triangles.start as usize..surface.triangles.end as usize]
        .iter()
        .collect();
    let cumulative = cumulative_area(&triangles);
    let total = cumulative.last().copied().unwrap_or(0.0);
    let mut rng = Pcg64Mcg::seed_from_u64(SEED ^ u64::from(side));
    let points = (0..count)
        .map(|k| {
            // Stratified along the running area, so every triangle of a large side gets its
            // share.
            let u = (k as f64 + rng.random::<f64>()) / count as f64 * total;
            let t = cumulative
                .partition_point(|&c| c <= u)
                .min(triangles.len() - 1);
            in_triangle(triangles[t].vertices, rng.random(), rng.random()) + lift * normal
        })
        .collect();
    (points, normal)
}
