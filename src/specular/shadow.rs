//! Light paths from a receiver to a point of a light, straight or through mirror images: what
//! share of the light arrives along each. A path follows the straight line to the light's image;
//! it must pass each reflector of its chain inside the reflector's outline (a window), on a
//! reflecting side, then go on to the next image, and finally reach the light. Glass it crosses
//! on the way passes light with its Fresnel transmittance (straight through, each face taken at
//! the angle the line meets it from the air: exact for thin panes, and for a slab's parallel
//! faces up to the sideways shift of the ray, whose internal bounces are summed:
//! T_in T_out / (1 − R_in R_out)); anything else blocks it. What a solid's refraction focuses
//! or spreads (caustics) is not modelled this way; the chains follow true refraction.

use glam::{DVec3, Vec3};

use super::images::reflect_point;
use super::Specular;
use crate::error::Result;
use crate::material::fresnel;
use crate::visibility::{Ray, Visibility, SEGMENT_T_MAX};

/// Glass faces one path may cross at most (a vitrine's panes, a lens's faces).
const MAX_CROSSINGS: usize = 32;

/// A light path to test.
#[derive(Clone, Debug)]
pub(crate) struct LightPath<'a> {
    /// The receiver, lifted off its surface.
    pub from: Vec3,
    /// The light point as seen from the receiver: its image through `chain`, lifted off the
    /// light.
    pub to: Vec3,
    /// The reflectors passed, nearest the receiver first (indices into `Specular::reflectors`).
    pub chain: &'a [u32],
}

/// One path on its way.
struct Walk {
    origin: Vec3,
    target: Vec3,
    /// Reflectors passed so far.
    stage: usize,
    share: DVec3,
    /// The reflectance of the glass face entered last (for a slab's internal bounces).
    entered: Option<f64>,
    crossings: usize,
    done: bool,
}

/// The share of light (RGB) that arrives along each path: the product of the reflectances of
/// its windows and the transmittances of the glass it crosses, 0 where it is blocked or misses
/// a window. Returns the visibility queries made.
pub(crate) fn arriving(
    spec: &Specular,
    vis: &dyn Visibility,
    lift: f32,
    paths: &[LightPath],
    out: &mut [DVec3],
) -> Result<u64> {
    let mut walks: Vec<Walk> = paths
        .iter()
        .map(|p| Walk {
            origin: p.from,
            target: p.to,
            stage: 0,
            share: DVec3::ONE,
            entered: None,
            crossings: 0,
            done: false,
        })
        .collect();
    let mut queries = 0u64;
    // A path whose line to the image crosses the first window's plane outside the window
    // arrives with nothing; most do, in a room of small panes, and cost no ray.
    let mut active: Vec<usize> = Vec::with_capacity(paths.len());
    for (i, p) in paths.iter().enumerate() {
        match p.chain.first() {
            Some(&k) if !spec.reflectors[k as usize].may_pass(p.from, p.to) => {
                walks[i].share = DVec3::ZERO;
                walks[i].done = true;
            }
            _ => active.push(i),
        }
    }
    let mut rays = Vec::new();
    let mut hits = Vec::new();
    while !active.is_empty() {
        rays.clear();
        rays.extend(active.iter().map(|&i| {
            let w = &walks[i];
            Ray {
                origin: w.origin,
                dir: w.target - w.origin,
                t_min: 0.0,
                t_max: SEGMENT_T_MAX,
            }
        }));
        hits.clear();
        hits.resize(rays.len(), None);
        vis.intersect(&rays, &mut hits)?;
        queries += rays.len() as u64;
        let mut still = Vec::with_capacity(active.len());
        for (&i, (ray, hit)) in active.iter().zip(rays.iter().zip(&hits)) {
            let w = &mut walks[i];
            let chain = paths[i].chain;
            let window = chain.get(w.stage).map(|&k| &spec.reflectors[k as usize]);
            let Some(hit) = hit else {
                // Reached the target: the light if every window is passed.
                if window.is_some() {
                    w.share = DVec3::ZERO;
                }
                w.done = true;
                continue;
            };
            let (surface, normal) = spec.faces[hit.triangle as usize];
            let dir = ray.dir.normalize();
            let cos = f64::from(dir.dot(normal));
            let point = ray.origin + hit.t * ray.dir;
            let goes_on = match window {
                Some(r) if r.surface == surface && (cos < 0.0 || r.both_sides) => {
                    w.share *= r.reflects.at(cos.abs());
                    let side = if cos < 0.0 { normal } else { -normal };
                    w.origin = point + lift * side;
                    w.target = reflect_point(r, w.target);
                    w.stage += 1;
                    w.entered = None;
                    true
                }
                _ => cross(spec, surface, w, point, dir, cos, lift),
            };
            if !goes_on {
                w.share = DVec3::ZERO;
                w.done = true;
                continue;
            }
            if w.share.max_element() > 0.0 {
                still.push(i);
            } else {
                w.done = true;
            }
        }
        active = still;
    }
    for (o, w) in out.iter_mut().zip(&walks) {
        *o = w.share;
    }
    Ok(queries)
}

/// A walk meets `surface` at `point` (along `dir`, at cosine `cos` with its normal) other
/// than at its next window: glass it may cross straight (its share dimmed by the faces'
/// transmission, a solid's inner bounces summed); anything else stops the light (false).
fn cross(
    spec: &Specular,
    surface: u32,
    w: &mut Walk,
    point: Vec3,
    dir: Vec3,
    cos: f64,
    lift: f32,
) -> bool {
    let Some((ior, filter, thin)) = spec.glass[surface as usize] else {
        return false;
    };
    if !(spec.straight[surface as usize] && w.crossings < MAX_CROSSINGS) {
        return false;
    }
    let ior = f64::from(ior);
    let filter = filter.as_dvec3();
    let passed = if thin {
        1.0 - fresnel::pane_reflectance(cos.abs(), ior)
    } else if cos < 0.0 {
        let r = fresnel::reflectance(-cos, ior);
        w.entered = Some(r);
        1.0 - r
    } else {
        // Leaving, at the angle the straight line has in air on this side: refracted, light
        // leaves at the angle it entered at, so the Fresnel factor is taken from outside (no
        // total internal reflection that a bent ray would not have).
        let r = fresnel::reflectance(cos, ior);
        let bounces = w.entered.take().map_or(1.0, |r_in| 1.0 / (1.0 - r_in * r));
        (1.0 - r) * bounces
    };
    w.share *= filter * passed;
    w.origin = point + lift * dir;
    w.crossings += 1;
    true
}
