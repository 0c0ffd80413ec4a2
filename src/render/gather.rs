//! A final gather where another surface is near (`docs/method.md` §18, "Contacts and
//! creases"): where surfaces meet (a box on a floor, a wall under a ceiling) the inter-reflected
//! light falls off within centimetres, finer than the samples, each of which stands for its
//! region's average. At a camera hit with another surface within its samples' kernels, the
//! inter-reflected irradiance is therefore gathered there: rays over the hemisphere, each
//! reading the light its hit reflects from the samples there. Visibility at the hit itself is
//! then exact, which is what the crease is made of. The gather's hits along the crease (within
//! the reach) are as wrong as the first hit when interpolated: they are interpolated in full,
//! their direct light traced, and they gather in turn with a few rays; its far hits read their
//! nearest sample. The gather is blended with the interpolated value by how much of the
//! hemisphere the near surfaces fill, so it fades out smoothly away from them and costs
//! nothing on open surfaces.

use glam::{DVec3, Vec3};

use super::{Pending, Shader};
use crate::error::Result;
use crate::field::interpolate::Site;
use crate::sampling::side_of;
use crate::visibility::{Hit, Ray, Segment};

/// Short rays that find whether a pixel's hit has another surface near it.
const PROBES: u32 = 8;
/// The fewest probes a hit gets when a pixel's rays share them.
const MIN_SHARED_PROBES: u32 = 2;
/// The fewest gather rays a hit near another surface gets when a pixel's rays share them.
const MIN_SHARED_RAYS: u32 = 4;

/// The most gather rays per hit.
pub const MAX_GATHER_RAYS: u32 = 4096;

/// Seeds of the probes' and the gather's rotations.
const PROBE_SEED: u64 = 0x7072_6f62_6573_2121;
const GATHER_SEED: u64 = 0x6761_7468_6572_2121;
const NEAR_DIRECT_SEED: u64 = 0x6e65_6172_2121_2121;
/// Shadow rays per area light at a gather's near hits.
pub(super) const NEAR_LIGHT_SAMPLES: u32 = 4;

/// A hit's gathered inter-reflected light and how much of it replaces the interpolated one.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Gathered {
    /// Weight of the gathered light, 0 to 1: twice the share of the (cosine-weighted)
    /// hemisphere whose rays hit a surface within the reach, so 1 at a contact line and 0 where
    /// nothing is within the reach.
    pub alpha: f32,
    /// Inter-reflected irradiance gathered (without the direct light, traced apart).
    pub irradiance: DVec3,
}

/// A point to gather at.
struct Spot {
    point: Vec3,
    normal: Vec3,
    /// How far its interpolation reaches: surfaces nearer than this are near.
    reach: f32,
    seed: u64,
}

/// Levels of gathering: the hits of a gather near its point lie near the crease too, where
/// their interpolated light is as wrong as the point's, so they gather in turn, with
/// [`NEXT_RAYS`] rays each (their noise averages out over the many near hits of a gather, and
/// the cost stays proportional to the first level's rays); the next level's hits are
/// interpolated.
const LEVELS: u32 = 2;
const NEXT_RAYS: u32 = 4;

/// First-level gather rays cast at once: bounds a batch's memory (its rays, hits, sites and
/// the next level's) whatever the image's width and the rays per hit.
const RAYS_AT_ONCE: usize = 1 << 15;

impl Shader<'_> {
    /// For each hit that gets its direct light traced, with the reach it is interpolated over
    /// (its samples' kernel support): the light gathered there, or the default (α 0) where no
    /// surface is within the reach or the gather is off. `share` hits of a pixel share its
    /// probes and gather rays (a grid averages its hits' answers). Returns the visibility
    /// queries made.
    pub(super) fn gather(
        &self,
        hits: &[(&Pending, f32)],
        share: u32,
    ) -> Result<(Vec<Gathered>, u64)> {
        let mut out = vec![Gathered::default(); hits.len()];
        if self.gather_rays == 0 || share == 0 || hits.is_empty() {
            return Ok((out, 0));
        }
        let rays = (self.gather_rays / share).max(MIN_SHARED_RAYS);
        let per_hit = (PROBES / share).max(MIN_SHARED_PROBES);
        // Which hits have a surface within their reach (one sealed off from its samples has
        // none).
        let reached: Vec<usize> = (0..hits.len())
            .filter(|&i| hits[i].1 > 0.0 && hits[i].1.is_finite())
            .collect();
        let probes: Vec<Segment> = reached
            .iter()
            .flat_map(|&i| {
                let (p, reach) = hits[i];
                let from = p.point + self.lift * p.normal;
                directions(p.normal, per_hit, seed(PROBE_SEED, u64::from(p.id))).map(move |d| {
                    Segment {
                        a: from,
                        b: from + reach * d,
                    }
                })
            })
            .collect();
        let mut blocked = vec![false; probes.len()];
        self.vis.occluded(&probes, &mut blocked)?;
        let k = per_hit as usize;
        let near: Vec<usize> = (0..reached.len())
            .filter(|&r| blocked[r * k..(r + 1) * k].contains(&true))
            .map(|r| reached[r])
            .collect();
        let spots: Vec<Spot> = near
            .iter()
            .map(|&i| Spot {
                point: hits[i].0.point,
                normal: hits[i].0.normal,
                reach: hits[i].1,
                seed: seed(GATHER_SEED, u64::from(hits[i].0.id)),
            })
            .collect();
        let mut queries = probes.len() as u64;
        let at_once = (RAYS_AT_ONCE / rays as usize).max(1);
        for (near, spots) in near.chunks(at_once).zip(spots.chunks(at_once)) {
            let (gathered, q) = self.gather_at(spots, rays, LEVELS - 1)?;
            queries += q;
            for (&i, g) in near.iter().zip(gathered) {
                out[i] = g;
            }
        }
        Ok((out, queries))
    }

    /// Gathers `rays` rays at each spot; hits within a spot's reach gather in turn while
    /// `levels` remain.
    fn gather_at(&self, spots: &[Spot], rays: u32, levels: u32) -> Result<(Vec<Gathered>, u64)> {
        if spots.is_empty() {
            return Ok((Vec::new(), 0));
        }
        let cast = self.cast(spots, rays)?;
        let mut queries = cast.casts.len() as u64;
        let sites = self.sites(&cast)?;
        let (weights, mut parts, q) = self.read_sites(spots, &cast, &sites)?;
        queries += q;
        // Sites within their spot's reach gather in turn.
        let (next, next_of) = if levels > 0 {
            self.next_spots(spots, &cast, &sites, &weights)
        } else {
            (Vec::new(), vec![None; sites.sites.len()])
        };
        let (again, q) = self.gather_at(&next, NEXT_RAYS, levels.saturating_sub(1))?;
        queries += q;
        queries += self.trace_direct(&next, &next_of, &mut parts)?;
        let out = combine(spots, &cast, &sites, &parts, &next_of, &again);
        Ok((out, queries))
    }

    /// `rays` cosine-distributed rays from each spot, and what they hit.
    fn cast(&self, spots: &[Spot], rays: u32) -> Result<Cast> {
        let casts: Vec<Ray> = spots
            .iter()
            .flat_map(|spot| {
                let from = spot.point + self.lift * spot.normal;
                directions(spot.normal, rays, spot.seed).map(move |dir| Ray {
                    origin: from,
                    dir,
                    t_min: 0.0,
                    t_max: f32::INFINITY,
                })
            })
            .collect();
        let mut found = vec![None; casts.len()];
        self.vis.intersect(&casts, &mut found)?;
        Ok(Cast {
            casts,
            found,
            per_spot: rays as usize,
        })
    }

    /// The hits that reflect sampled light, as sites to read, with their reflectance (their
    /// texel, or their material's) and whether something hovers over each (so it reads samples
    /// covered as it is: the floor under a box is dark).
    fn sites(&self, cast: &Cast) -> Result<Sites> {
        let mut sites = Vec::new();
        let mut reflectance = Vec::new();
        let mut site_of = vec![None; cast.casts.len()];
        for (j, (ray, hit)) in cast.casts.iter().zip(&cast.found).enumerate() {
            let Some(Hit { t, triangle }) = *hit else {
                continue;
            };
            let tri = &self.scene.triangles[triangle as usize];
            let back = ray.dir.dot(tri.normal) > 0.0;
            let side = side_of(tri.surface, back);
            if !self.interpolator.has_samples(side) {
                continue;
            }
            let point = ray.origin + t * ray.dir;
            site_of[j] = Some(sites.len());
            sites.push(Site {
                point,
                side,
                normal: if back { -tri.normal } else { tri.normal },
                covered: false,
            });
            let rho = self
                .texel(triangle, point)
                .unwrap_or_else(|| self.scene.material_of(tri.surface).kd);
            reflectance.push(rho.as_dvec3());
        }
        let points: Vec<(Vec3, Vec3)> = sites.iter().map(|s| (s.point, s.normal)).collect();
        let covered = self.interpolator.covered(&points)?;
        for (site, covered) in sites.iter_mut().zip(covered) {
            site.covered = covered;
        }
        Ok(Sites {
            sites,
            reflectance,
            site_of,
        })
    }

    /// Each site's samples and weights, and its direct and inter-reflected light per unit
    /// reflectance read from them; the queries. Sites within their spot's reach lie along the
    /// crease, where the light changes fastest: they are interpolated in full (kernels, samples
    /// in sight, the local-linear fit). The far ones, most of them, read their nearest sample:
    /// each is a small share of a smooth answer, and their kernels' visibility queries cost
    /// more than the rest of the render (on the gallery, 2.9 s of render against 5.4 s).
    fn read_sites(
        &self,
        spots: &[Spot],
        cast: &Cast,
        sites: &Sites,
    ) -> Result<(Vec<Weights>, Vec<Light>, u64)> {
        let sites_list = &sites.sites;
        let mut near_site = vec![false; sites_list.len()];
        for (j, found) in cast.found.iter().enumerate() {
            if let (Some(s), Some(hit)) = (sites.site_of[j], found) {
                near_site[s] = hit.t < spots[j / cast.per_spot].reach;
            }
        }
        let close: Vec<Site> = (0..sites_list.len())
            .filter(|&s| near_site[s])
            .map(|s| sites_list[s])
            .collect();
        let mut interpolated = Vec::new();
        let queries =
            self.interpolator.weights(&close, &mut interpolated)? + sites_list.len() as u64;
        let mut interpolated = interpolated.into_iter();
        // The far sites read their nearest sample, or where their ray's patch spans several
        // samples the patch's mean.
        let nearest: Vec<Option<u32>> = sites_list
            .iter()
            .zip(&near_site)
            .map(|(site, &near)| {
                if near {
                    None
                } else {
                    self.interpolator.nearest(site)
                }
            })
            .collect();
        let patch = self.patch_means(sites, &nearest, &footprints(spots, cast, sites))?;
        let weights: Vec<Vec<(u32, f32)>> = near_site
            .iter()
            .zip(&nearest)
            .zip(&patch)
            .map(|((&near, nearest), patch)| match (near, patch) {
                (true, _) => interpolated.next().unwrap_or_default(),
                (false, Some(_)) => Vec::new(),
                (false, None) => nearest.map_or_else(Vec::new, |k| vec![(k, 1.0)]),
            })
            .collect();
        let parts = weights
            .iter()
            .zip(&patch)
            .map(|(chosen, patch)| {
                if let Some(light) = patch {
                    return (DVec3::ZERO, *light);
                }
                let (mut wsum, mut direct, mut reflected) = (0.0f64, DVec3::ZERO, DVec3::ZERO);
                for &(k, w) in chosen {
                    let w = f64::from(w);
                    wsum += w;
                    direct += w * self.outgoing[k as usize].0;
                    reflected += w * self.outgoing[k as usize].1;
                }
                if wsum > 0.0 {
                    (
                        (direct / wsum).max(DVec3::ZERO),
                        (reflected / wsum).max(DVec3::ZERO),
                    )
                } else {
                    (DVec3::ZERO, DVec3::ZERO)
                }
            })
            .collect();
        Ok((weights, parts, queries))
    }

    /// For each far site (with its nearest sample, covered as it is) whose ray's patch (of
    /// radius `radius`) is wider than [`PATCH_CELLS`] cells, the patch's mean light
    /// (`field::patches`), read in the region of that sample when the site sees it (on a side
    /// something stands on, one query each); none elsewhere.
    fn patch_means(
        &self,
        sites: &Sites,
        nearest: &[Option<u32>],
        radius: &[f32],
    ) -> Result<Vec<Option<DVec3>>> {
        let mut out = vec![None; sites.sites.len()];
        let Some(patches) = self.patches.as_ref() else {
            return Ok(out);
        };
        let field = self.interpolator.field();
        let obstruction = field.layout.obstruction();
        let mut wide = Vec::new();
        let mut tests = Vec::new();
        for (i, site) in sites.sites.iter().enumerate() {
            let Some(k) = nearest[i] else {
                continue;
            };
            if radius[i] <= PATCH_CELLS * patches.cell(k) {
                continue;
            }
            // The nearest sample may lie on another side of a curved piece.
            let s = &field.samples;
            let across = s
                .side
                .get(k as usize)
                .is_some_and(|&side| side != site.side);
            let tested = if across {
                obstruction.may_block_between(field.layout.maps(), s, site.side, site.point, k)
            } else {
                obstruction.is_obstructed(site.side)
            };
            if tested {
                tests.push(if across {
                    crate::sampling::Obstruction::lifted(
                        self.lift,
                        site.point,
                        site.normal,
                        s.position[k as usize],
                        s.normal[k as usize],
                    )
                } else {
                    obstruction.segment(site.normal, site.point, s, k)
                });
            }
            wide.push((i, k, tested));
        }
        let mut blocked = vec![false; tests.len()];
        self.vis.occluded(&tests, &mut blocked)?;
        let mut answer = blocked.into_iter();
        for (i, k, tested) in wide {
            if tested && answer.next().unwrap_or(true) {
                continue;
            }
            let site = &sites.sites[i];
            out[i] = patches.mean(field, k, site.point, SQUARE * radius[i]);
        }
        Ok(out)
    }

    /// The sites within their spot's reach, as the spots of the next level, and which spot
    /// each site became.
    fn next_spots(
        &self,
        spots: &[Spot],
        cast: &Cast,
        sites: &Sites,
        weights: &[Vec<(u32, f32)>],
    ) -> (Vec<Spot>, Vec<Option<usize>>) {
        let mut next = Vec::new();
        let mut next_of = vec![None; sites.sites.len()];
        for (j, found) in cast.found.iter().enumerate() {
            let (Some(s), Some(hit)) = (sites.site_of[j], found) else {
                continue;
            };
            let spot = &spots[j / cast.per_spot];
            if hit.t < spot.reach {
                next_of[s] = Some(next.len());
                next.push(Spot {
                    point: sites.sites[s].point,
                    normal: sites.sites[s].normal,
                    reach: self.reach(&weights[s]),
                    seed: seed(spot.seed, j as u64),
                });
            }
        }
        (next, next_of)
    }

    /// The next level's direct light, traced, not interpolated: beside a contact the other
    /// surface's direct light changes as fast as its inter-reflected light (the floor at a
    /// box's foot lies in the box's shadow), and reads too bright from its samples. Into
    /// `parts`; the queries.
    fn trace_direct(
        &self,
        next: &[Spot],
        next_of: &[Option<usize>],
        parts: &mut [Light],
    ) -> Result<u64> {
        let Some(light) = self.near_light.as_ref().filter(|_| !next.is_empty()) else {
            return Ok(0);
        };
        let points: Vec<(Vec3, Vec3)> = next.iter().map(|n| (n.point, n.normal)).collect();
        let ids: Vec<u32> = next.iter().map(|n| n.seed as u32).collect();
        let mut arrivals = vec![crate::light::Arrival::default(); next.len()];
        let queries = light.batch(self.vis, &points, &ids, NEAR_DIRECT_SEED, &mut arrivals)?;
        for (s, m) in next_of.iter().enumerate() {
            if let Some(m) = *m {
                parts[s].0 = arrivals[m].irradiance / std::f64::consts::PI;
            }
        }
        Ok(queries)
    }
}

/// The samples a site reads, with their weights.
type Weights = Vec<(u32, f32)>;

/// A site's direct and inter-reflected light per unit reflectance.
type Light = (DVec3, DVec3);

/// The rays a level of spots cast, and their hits.
struct Cast {
    casts: Vec<Ray>,
    found: Vec<Option<Hit>>,
    /// Rays per spot (spot i cast rays i × per_spot ..).
    per_spot: usize,
}

/// The hits that reflect sampled light.
struct Sites {
    sites: Vec<Site>,
    /// Each site's reflectance.
    reflectance: Vec<DVec3>,
    /// Per ray: its site, if its hit is one.
    site_of: Vec<Option<usize>>,
}

/// The radius of the patch of surface each site's ray stands for: `n` stratified
/// cosine-weighted rays each cover a projected solid angle of π/n, which at distance t and
/// incidence θ' from a spot whose normal makes θ with the ray is a patch of area
/// t² π / (n cos θ cos θ'), a disc of radius t / √(n cos θ cos θ'). (The cosines are bounded
/// below: a grazing ray's patch is long and thin, not wide.)
fn footprints(spots: &[Spot], cast: &Cast, sites: &Sites) -> Vec<f32> {
    let mut radius = vec![0.0f32; sites.sites.len()];
    let n = cast.per_spot as f32;
    for (j, found) in cast.found.iter().enumerate() {
        if let (Some(s), Some(hit)) = (sites.site_of[j], found) {
            let dir = cast.casts[j].dir;
            let at_spot = dir.dot(spots[j / cast.per_spot].normal).max(MIN_COSINE);
            let at_hit = (-dir.dot(sites.sites[s].normal)).max(MIN_COSINE);
            radius[s] = hit.t / (n * at_spot * at_hit).sqrt();
        }
    }
    radius
}

/// The least cosine [`footprints`] takes.
const MIN_COSINE: f32 = 0.25;
/// A far site reads its patch's mean where the patch is wider than this many of the
/// tables' cells (about a sample each); its nearest sample where it is narrower.
const PATCH_CELLS: f32 = 2.0;
/// Half the side of the square of a disc's area, over its radius (√π / 2).
const SQUARE: f32 = 0.886_226_9;

/// Each spot's gathered light: its rays' sites' light (direct and inter-reflected, the latter
/// blended with what the sites gathered again), and how much of the answer comes from within
/// the spot's reach.
fn combine(
    spots: &[Spot],
    cast: &Cast,
    sites: &Sites,
    parts: &[Light],
    next_of: &[Option<usize>],
    again: &[Gathered],
) -> Vec<Gathered> {
    let n = cast.per_spot;
    spots
        .iter()
        .enumerate()
        .map(|(i, spot)| {
            let (mut radiance, mut close) = (DVec3::ZERO, 0usize);
            for j in i * n..(i + 1) * n {
                if let Some(s) = sites.site_of[j] {
                    let (direct, mut reflected) = parts[s];
                    if let Some(g) = next_of[s].map(|m| again[m]) {
                        let gathered = g.irradiance / std::f64::consts::PI;
                        reflected += f64::from(g.alpha) * (gathered - reflected);
                    }
                    radiance += sites.reflectance[s] * (direct + reflected);
                }
                if cast.found[j].is_some_and(|h| h.t < spot.reach) {
                    close += 1;
                }
            }
            // Cosine-weighted directions: the irradiance is π times the mean radiance.
            Gathered {
                alpha: (2.0 * close as f32 / n as f32).min(1.0),
                irradiance: radiance * std::f64::consts::PI / n as f64,
            }
        })
        .collect()
}

/// A hit's own seed: the same rays whatever the thread or rank that shades it.
fn seed(base: u64, id: u64) -> u64 {
    let mut z = base ^ id.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// `count` cosine-weighted directions about `normal`, stratified (a Hammersley set, shifted
/// by the seed as a whole): a gather of a few dozen rays then sees a smooth field with far
/// less noise than independent directions would.
fn directions(normal: Vec3, count: u32, seed: u64) -> impl Iterator<Item = Vec3> {
    let (a, b) = normal.any_orthonormal_pair();
    let shift = (
        (seed >> 40) as f32 / (1u64 << 24) as f32,
        ((seed >> 16) & 0xff_ffff) as f32 / (1u64 << 24) as f32,
    );
    (0..count).map(move |i| {
        let u1 = ((i as f32 + 0.5) / count as f32 + shift.0).fract();
        let u2 = (radical_inverse(i) + shift.1).fract();
        let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
        (a * (r * phi.cos()) + b * (r * phi.sin()) + normal * (1.0 - u1).max(0.0).sqrt())
            .normalize()
    })
}

/// The base-2 radical inverse of i, in [0, 1).
fn radical_inverse(i: u32) -> f32 {
    (i.reverse_bits() as f64 / 4_294_967_296.0) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_are_cosine_weighted() {
        // Over a cosine-weighted hemisphere the mean of cos θ is 2/3 and of cos² θ 1/2; the
        // mean of each tangent component is 0.
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let (a, _) = n.any_orthonormal_pair();
        let count = 1024;
        let (mut c1, mut c2, mut t) = (0.0f64, 0.0f64, 0.0f64);
        for d in directions(n, count, seed(7, 3)) {
            assert!((d.length() - 1.0).abs() < 1e-5);
            let c = f64::from(d.dot(n));
            assert!(c >= 0.0);
            c1 += c;
            c2 += c * c;
            t += f64::from(d.dot(a));
        }
        let m = f64::from(count);
        assert!((c1 / m - 2.0 / 3.0).abs() < 2e-3, "{}", c1 / m);
        assert!((c2 / m - 0.5).abs() < 2e-3, "{}", c2 / m);
        assert!((t / m).abs() < 5e-3, "{}", t / m);
    }

    #[test]
    fn a_wall_at_its_foot_fills_half_the_hemisphere() {
        // From a point on a wall at height h above a floor, the floor is within reach R along
        // the cosine-weighted directions whose disk coordinate toward the floor exceeds h/R:
        // a segment of the unit disk, (acos c - c sqrt(1 - c^2)) / π with c = h/R.
        let n = Vec3::X;
        for c in [0.0f64, 0.25, 0.5, 0.75] {
            let expected = (c.acos() - c * (1.0 - c * c).sqrt()) / std::f64::consts::PI;
            let count = 4096;
            let close = directions(n, count, seed(1, 2))
                .filter(|d| f64::from(-d.y) > c)
                .count();
            let share = close as f64 / f64::from(count);
            assert!(
                (share - expected).abs() < 0.01,
                "c {c}: {share} vs {expected}"
            );
        }
    }
}
