//! Next-event estimation through planar mirrors, and shadow rays through thin panes.
//!
//! A planar mirror shows a light at the light's mirror image: from a point x the light y is
//! reached along the straight line from x to y's image, bent at the mirror, with the unfolded
//! length |x − image| in the geometry term. Chains of up to `mirror_depth` mirrors image the
//! light once per mirror. A chain is only a proposal: probes (repeated closest-hit queries)
//! check that each leg's first hit is the mirror it aims at, on a side that reflects, passing
//! thin panes on the way (each multiplying by T'·Tf), and that the last leg reaches the light.

use glam::{DVec3, Vec3};

use crate::material::fresnel;
use crate::scene::{Kind, Scene};
use crate::visibility::{Ray, SEGMENT_T_MAX, SEGMENT_T_MIN};

/// The most mirrors a chain may hold (`PathOptions::mirror_depth`).
pub(crate) const MAX_MIRROR_DEPTH: u32 = 4;
/// Chains looked through at every vertex at most: the depth is lowered until they fit.
const MAX_CHAINS: usize = 1024;
/// Thin panes a leg (of a shadow ray, or of a path between two reflections) may cross; one more
/// blocks it.
pub(super) const MAX_CROSSINGS: u32 = 8;

/// How a mirror surface reflects.
#[derive(Clone, Copy, Debug)]
enum Reflects {
    /// A mirror: Ks at every angle.
    Ks(DVec3),
    /// A thin pane of this index: R'(θ) = 2R/(1 + R).
    Pane(f64),
}

/// A planar surface that reflects like a mirror.
#[derive(Clone, Copy, Debug)]
struct Mirror {
    surface: u32,
    /// The plane: unit normal (to the front) and offset.
    normal: DVec3,
    offset: f64,
    /// Whether the back reflects too (two-sided mirrors, panes).
    both_sides: bool,
    reflects: Reflects,
    /// Bounds of its triangles, widened by twice the lift.
    min: DVec3,
    max: DVec3,
}

impl Mirror {
    fn signed(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.offset
    }

    fn image(&self, p: DVec3) -> DVec3 {
        p - 2.0 * self.signed(p) * self.normal
    }

    fn weight(&self, cos: f64) -> DVec3 {
        match self.reflects {
            Reflects::Ks(ks) => ks,
            Reflects::Pane(ior) => DVec3::splat(fresnel::pane_reflectance(cos, ior)),
        }
    }

    fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// The scene's planar mirrors (mirror materials, r = 0, and thin panes) and the chains of them
/// next-event estimation looks through.
pub(super) struct Mirrors {
    list: Vec<Mirror>,
    /// Per surface: its index in `list`.
    of_surface: Vec<Option<u32>>,
    /// Chains, flattened: each `(start, len)` into `links`.
    chains: Vec<(u32, u32)>,
    links: Vec<u32>,
    /// Reflections a chain holds at most: `mirror_depth`, lowered until the chains fit.
    depth: u32,
    /// Whether any surface is a thin pane.
    panes: bool,
}

/// A light reached through a chain of mirrors.
pub(super) struct Unfolded {
    /// Unit direction leaving x.
    pub omega: DVec3,
    /// Unfolded length: x to the light's image.
    pub distance: f64,
    /// Product of the mirrors' reflectances.
    pub weight: DVec3,
    /// The last reflection point (where the light is seen from).
    pub last: DVec3,
    /// The legs a probe checks.
    pub legs: [Leg; MAX_MIRROR_DEPTH as usize + 1],
    pub count: usize,
}

impl Mirrors {
    pub(super) fn new(scene: &Scene, mirror_depth: u32, lift: f32) -> Mirrors {
        let mut list = Vec::new();
        let mut of_surface = vec![None; scene.surfaces.len()];
        let mut panes = false;
        for (s, surface) in scene.surfaces.iter().enumerate() {
            let m = &scene.materials[surface.material as usize];
            let (reflects, both_sides) = match m.kind {
                Kind::Specular { ks, .. } if m.is_mirror() => {
                    (Reflects::Ks(ks.as_dvec3()), surface.two_sided)
                }
                Kind::Glass {
                    ior, thin: true, ..
                } => {
                    panes = true;
                    (Reflects::Pane(f64::from(ior)), true)
                }
                _ => continue,
            };
            let triangles =
                &scene.triangles[surface.triangles.start as usize..surface.triangles.end as usize];
            let points = triangles.iter().flat_map(|t| t.vertices);
            let bounds = crate::scene::Bounds::around(points);
            let margin = DVec3::splat(2.0 * f64::from(lift));
            of_surface[s] = Some(list.len() as u32);
            list.push(Mirror {
                surface: s as u32,
                normal: surface.normal.as_dvec3().normalize(),
                offset: f64::from(surface.offset),
                both_sides,
                reflects,
                min: bounds.min.as_dvec3() - margin,
                max: bounds.max.as_dvec3() + margin,
            });
        }
        // Every sequence of mirrors without the same one twice in a row (a plane cannot reflect
        // onto itself), shortest first; as deep as fits.
        let m = list.len();
        let mut depth = 0;
        let (mut count, mut level) = (0usize, 1usize);
        while depth < mirror_depth && m > 0 {
            level = level.saturating_mul(if depth == 0 { m } else { m - 1 });
            if level == 0 || count.saturating_add(level) > MAX_CHAINS {
                break;
            }
            count += level;
            depth += 1;
        }
        let mut chains = Vec::with_capacity(count);
        let mut links = Vec::new();
        let mut frontier: Vec<Vec<u32>> = (0..m as u32).map(|i| vec![i]).collect();
        for length in 1..=depth {
            let mut next = Vec::new();
            for chain in &frontier {
                chains.push((links.len() as u32, chain.len() as u32));
                links.extend_from_slice(chain);
                if length == depth {
                    continue;
                }
                for i in 0..m as u32 {
                    if Some(&i) != chain.last() {
                        let mut longer = chain.clone();
                        longer.push(i);
                        next.push(longer);
                    }
                }
            }
            frontier = next;
        }
        Mirrors {
            list,
            of_surface,
            chains,
            links,
            depth,
            panes,
        }
    }

    /// Whether any surface is a thin pane (shadow rays then go through them).
    pub(super) fn panes(&self) -> bool {
        self.panes
    }

    /// Reflections a chain holds at most.
    pub(super) fn depth(&self) -> u32 {
        self.depth
    }

    /// Whether a surface is one of the mirrors next-event estimation looks through.
    pub(super) fn is_mirror(&self, surface: u32) -> bool {
        self.of_surface[surface as usize].is_some()
    }

    /// The chains, each a list of mirror indices.
    pub(super) fn chains(&self) -> impl Iterator<Item = &[u32]> + '_ {
        self.chains
            .iter()
            .map(|&(start, len)| &self.links[start as usize..(start + len) as usize])
    }

    /// The path from `x` (off the surface `own`) to the light point `y` by the mirrors of
    /// `chain`, if each reflects it on a side that reflects, within its bounds; `None` when the
    /// chain cannot join them.
    pub(super) fn unfold(&self, chain: &[u32], own: u32, x: DVec3, y: DVec3) -> Option<Unfolded> {
        let k = chain.len();
        if self.list[chain[0] as usize].surface == own {
            return None;
        }
        // images[i]: what the path aims at leaving reflection i (x for i = 0): y seen through
        // the mirrors chain[i..].
        let mut images = [DVec3::ZERO; MAX_MIRROR_DEPTH as usize];
        let mut image = y;
        for i in (0..k).rev() {
            image = self.list[chain[i] as usize].image(image);
            images[i] = image;
        }
        let mut legs = [Leg::Point(Vec3::ZERO); MAX_MIRROR_DEPTH as usize + 1];
        let mut weight = DVec3::ONE;
        let mut at = x;
        for i in 0..k {
            let m = &self.list[chain[i] as usize];
            let (s_at, s_aim) = (m.signed(at), m.signed(images[i]));
            let side = s_at > 0.0 || (m.both_sides && s_at < 0.0);
            if !side || s_at * s_aim >= 0.0 {
                return None;
            }
            let p = at + (images[i] - at) * (s_at / (s_at - s_aim));
            if !m.contains(p) {
                return None;
            }
            let cos = (images[i] - at).normalize().dot(m.normal).abs();
            weight *= m.weight(cos);
            legs[i] = Leg::Mirror {
                surface: m.surface,
                both_sides: m.both_sides,
                aim: images[i].as_vec3(),
            };
            at = p;
        }
        legs[k] = Leg::Point(y.as_vec3());
        let to = images[0] - x;
        let distance = to.length();
        (distance > 0.0).then(|| Unfolded {
            omega: to / distance,
            distance,
            weight,
            last: at,
            legs,
            count: k + 1,
        })
    }
}

/// One leg of a probe.
#[derive(Clone, Copy, Debug)]
pub(super) enum Leg {
    /// Towards `aim` (a light's image behind the mirror): the first hit other than a thin pane
    /// must be `surface`, on a side that reflects.
    Mirror {
        surface: u32,
        both_sides: bool,
        aim: Vec3,
    },
    /// To a light point: nothing but thin panes in between.
    Point(Vec3),
}

/// A connection to a light checked by closest-hit queries: its legs in turn, thin panes
/// multiplying the contribution by their transmittance.
pub(super) struct Probe {
    pub path: usize,
    pub contribution: DVec3,
    legs: [Leg; MAX_MIRROR_DEPTH as usize + 1],
    count: u8,
    leg: u8,
    pub ray: Ray,
    crossings: u32,
}

/// What a probe's hit means.
pub(super) enum Step {
    /// Go on with the probe's (new) ray.
    Continue,
    /// The light is reached: add the contribution.
    Clear,
    /// Something blocks it.
    Blocked,
}

impl Probe {
    /// A probe from `from` along `legs`.
    pub(super) fn new(path: usize, contribution: DVec3, from: Vec3, legs: &[Leg]) -> Probe {
        let mut all = [Leg::Point(Vec3::ZERO); MAX_MIRROR_DEPTH as usize + 1];
        all[..legs.len()].copy_from_slice(legs);
        Probe {
            path,
            contribution,
            legs: all,
            count: legs.len() as u8,
            leg: 0,
            ray: leg_ray(from, legs[0]),
            crossings: 0,
        }
    }

    /// Takes the current ray's closest hit.
    pub(super) fn step(
        &mut self,
        scene: &Scene,
        hit: Option<crate::visibility::Hit>,
        lift: f32,
    ) -> Step {
        let leg = self.legs[self.leg as usize];
        let Some(hit) = hit else {
            return match leg {
                Leg::Point(_) => Step::Clear,
                Leg::Mirror { .. } => Step::Blocked,
            };
        };
        let triangle = &scene.triangles[hit.triangle as usize];
        let d = self.ray.dir;
        if let Leg::Mirror {
            surface,
            both_sides,
            ..
        } = leg
        {
            if triangle.surface == surface {
                let front = d.dot(triangle.normal) < 0.0;
                if !(front || both_sides) {
                    return Step::Blocked;
                }
                let n = if front {
                    triangle.normal
                } else {
                    -triangle.normal
                };
                let from = self.ray.origin + d * hit.t + lift * n;
                self.leg += 1;
                debug_assert!(self.leg < self.count);
                self.ray = leg_ray(from, self.legs[self.leg as usize]);
                self.crossings = 0;
                return Step::Continue;
            }
        }
        let material = scene.material_of(triangle.surface);
        match material.kind {
            Kind::Glass {
                ior,
                transmit,
                thin: true,
            } => {
                self.crossings += 1;
                if self.crossings > MAX_CROSSINGS {
                    return Step::Blocked;
                }
                let cos = f64::from(d.normalize().dot(triangle.normal)).abs();
                let t = 1.0 - fresnel::pane_reflectance(cos, f64::from(ior));
                self.contribution *= transmit.as_dvec3() * t;
                if self.contribution.max_element() <= 0.0 {
                    return Step::Blocked;
                }
                self.ray.t_min = hit.t + lift / d.length();
                Step::Continue
            }
            _ => Step::Blocked,
        }
    }
}

/// The ray of a leg from `from`.
fn leg_ray(from: Vec3, leg: Leg) -> Ray {
    match leg {
        Leg::Mirror { aim, .. } => Ray {
            origin: from,
            dir: aim - from,
            t_min: 0.0,
            t_max: 1.0,
        },
        Leg::Point(b) => Ray {
            origin: from,
            dir: b - from,
            t_min: SEGMENT_T_MIN,
            t_max: SEGMENT_T_MAX,
        },
    }
}
