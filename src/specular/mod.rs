//! Light that reaches a diffuse surface by way of specular ones (`docs/method.md` §22): the
//! paper's other future work. What a scene's mirrors, glossy surfaces and glass are
//! (`Specular`); light paths through mirror windows and glass to a light (`shadow`); the
//! mirror images of lights (`images`); and chains followed from a receiver through specular
//! bounces to the diffuse surfaces and lights they end at (`gather`).

pub(crate) mod gather;
pub(crate) mod highlight;
pub(crate) mod images;
pub(crate) mod lights;
pub(crate) mod shadow;

use glam::Vec3;

use crate::scene::{Kind, Scene};

/// The most specular bounces a chain, or a mirror image of a light, may take at most.
pub const MAX_SPECULAR_DEPTH: u32 = 16;

/// How a planar surface reflects a mirror image of a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Reflects {
    /// A mirror: Ks, the same at every angle, on its front (both sides if two-sided).
    Mirror(Vec3),
    /// A thin pane: R' = 2R/(1 + R) on either side.
    Pane(f32),
    /// A glass solid's face from outside: Fresnel R.
    Glass(f32),
}

impl Reflects {
    /// The reflectance at cos θ (RGB).
    pub(crate) fn at(self, cos: f64) -> glam::DVec3 {
        use crate::material::fresnel;
        match self {
            Reflects::Mirror(ks) => ks.as_dvec3(),
            Reflects::Pane(ior) => {
                glam::DVec3::splat(fresnel::pane_reflectance(cos, f64::from(ior)))
            }
            Reflects::Glass(ior) => glam::DVec3::splat(fresnel::reflectance(cos, f64::from(ior))),
        }
    }

    /// The reflectance at normal incidence, brightest channel: what a chain of images can carry
    /// at most, about (to leave out the images that carry next to nothing).
    pub(crate) fn typical(self) -> f64 {
        match self {
            Reflects::Mirror(ks) => f64::from(ks.max_element()),
            _ => self.at(1.0).max_element(),
        }
    }
}

/// A planar surface that makes mirror images of lights.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reflector {
    pub surface: u32,
    /// The plane: unit normal (the front) and offset.
    pub normal: Vec3,
    pub offset: f32,
    pub reflects: Reflects,
    /// Whether its back reflects too.
    pub both_sides: bool,
    /// Its triangles' bounding box, widened a little: a line that crosses the plane outside it
    /// cannot pass the window.
    pub bounds: (Vec3, Vec3),
}

/// A surface's bounding box, widened for the rounding of a crossing point and of the lifts.
pub(crate) fn window_bounds(scene: &Scene, surface: &crate::scene::Surface) -> (Vec3, Vec3) {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    let range = surface.triangles.start as usize..surface.triangles.end as usize;
    for t in &scene.triangles[range] {
        for v in t.vertices {
            (lo, hi) = (lo.min(v), hi.max(v));
        }
    }
    let pad = Vec3::splat(1e-3 * (hi - lo).length() + 1e-3);
    (lo - pad, hi + pad)
}

/// Bounds that turn nothing away.
#[cfg(test)]
pub(crate) const EVERYWHERE: (Vec3, Vec3) = (Vec3::splat(f32::MIN), Vec3::splat(f32::MAX));

impl Reflector {
    /// Whether the straight segment `from` → `to` can pass through this reflector's outline:
    /// false only when it crosses the plane outside the bounding box (or not at all). Exact
    /// as a filter: a segment it turns away would have missed the surface.
    pub(crate) fn may_pass(&self, from: Vec3, to: Vec3) -> bool {
        let (a, b) = (
            self.normal.dot(from) - self.offset,
            self.normal.dot(to) - self.offset,
        );
        if a * b > 0.0 {
            return false;
        }
        if a == b {
            return true;
        }
        let p = from + (to - from) * (a / (a - b));
        let (lo, hi) = self.bounds;
        p.cmpge(lo).all() && p.cmple(hi).all()
    }

    /// Whether any line from `from` to a point of `triangles` (a light's image behind this
    /// reflector) may pass its window: false only when every such line crosses the plane
    /// outside the bounding box. Seen from `from`, the triangles project onto the plane inside
    /// the box of their vertices' projections, so that box is compared, widened by a margin
    /// for the shadow rays' lifted ends.
    pub(crate) fn may_show(&self, from: Vec3, triangles: &[[Vec3; 3]]) -> bool {
        let a = self.normal.dot(from) - self.offset;
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for &v in triangles.iter().flatten() {
            let b = self.normal.dot(v) - self.offset;
            if a * b >= 0.0 || a == b {
                // A vertex on the near side: the projection is unbounded.
                return true;
            }
            let p = from + (v - from) * (a / (a - b));
            (lo, hi) = (lo.min(p), hi.max(p));
        }
        let margin = Vec3::splat(1e-3 * (1.0 + (hi - lo).length()));
        let (wlo, whi) = self.bounds;
        (lo - margin).cmple(whi).all() && (hi + margin).cmpge(wlo).all()
    }
}

/// What a scene's specular surfaces are.
#[derive(Clone, Debug, Default)]
pub(crate) struct Specular {
    /// Per surface: whether its material is specular (mirror, glossy or glass).
    pub specular: Vec<bool>,
    /// Per surface: its glass, if any (index, filter, thin).
    pub glass: Vec<Option<(f32, Vec3, bool)>>,
    /// The planar reflectors, in surface order.
    pub reflectors: Vec<Reflector>,
    /// Whether any surface is glass (shadow rays then pass through it).
    pub any_glass: bool,
    /// Per triangle: its surface and front normal (what a hit needs).
    pub faces: Vec<(u32, Vec3)>,
}

impl Specular {
    /// The scene's specular surfaces.
    pub(crate) fn of(scene: &Scene) -> Specular {
        let n = scene.surfaces.len();
        let mut s = Specular {
            specular: vec![false; n],
            glass: vec![None; n],
            reflectors: Vec::new(),
            any_glass: false,
            faces: scene
                .triangles
                .iter()
                .map(|t| (t.surface, t.normal))
                .collect(),
        };
        for (i, surface) in scene.surfaces.iter().enumerate() {
            let m = &scene.materials[surface.material as usize];
            s.specular[i] = m.is_specular();
            let reflects = match m.kind {
                Kind::Specular { ks, roughness } if roughness == 0.0 && ks.max_element() > 0.0 => {
                    Some(Reflects::Mirror(ks))
                }
                Kind::Glass {
                    ior,
                    transmit,
                    thin,
                } => {
                    s.glass[i] = Some((ior, transmit, thin));
                    s.any_glass = true;
                    Some(if thin {
                        Reflects::Pane(ior)
                    } else {
                        Reflects::Glass(ior)
                    })
                }
                _ => None,
            };
            if let Some(reflects) = reflects {
                let pane = matches!(reflects, Reflects::Pane(_));
                s.reflectors.push(Reflector {
                    bounds: window_bounds(scene, surface),
                    surface: i as u32,
                    normal: surface.normal,
                    offset: surface.offset,
                    reflects,
                    both_sides: pane || (surface.two_sided && !m.is_emitter()) || m.two_sided,
                });
            }
        }
        s
    }

    /// Whether the scene has anything specular at all.
    pub(crate) fn any(&self) -> bool {
        self.specular.iter().any(|&s| s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_passes_a_window_only_where_it_crosses_the_plane_inside_it() {
        // A 1 × 1 window in the plane y = 0, facing up.
        let r = Reflector {
            surface: 0,
            normal: Vec3::Y,
            offset: 0.0,
            reflects: Reflects::Mirror(Vec3::ONE),
            both_sides: false,
            bounds: (Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0)),
        };
        let v = Vec3::new;
        // Straight down through its middle; slanted, crossing at (0.75, 0, 0.5).
        assert!(r.may_pass(v(0.5, 1.0, 0.5), v(0.5, -1.0, 0.5)));
        assert!(r.may_pass(v(0.5, 1.0, 0.5), v(1.0, -1.0, 0.5)));
        // Slanted more, crossing at (1.5, 0, 0.5): outside.
        assert!(!r.may_pass(v(0.5, 1.0, 0.5), v(2.5, -1.0, 0.5)));
        // Both ends above the plane: it never crosses.
        assert!(!r.may_pass(v(0.5, 1.0, 0.5), v(0.5, 0.5, 0.5)));
        // An image triangle 1 below the plane seen from 1 above: it projects halfway, so one
        // at x ∈ [2, 3] shows through [1, 1.5] (touching the window's edge) and one at
        // x ∈ [3, 4] through [1.5, 2] (outside); one reaching above the plane always may.
        let from = v(0.0, 1.0, 0.5);
        let near = [[v(2.0, -1.0, 0.5), v(3.0, -1.0, 0.5), v(2.5, -1.0, 0.6)]];
        let far = [[v(3.0, -1.0, 0.5), v(4.0, -1.0, 0.5), v(3.5, -1.0, 0.6)]];
        let through = [[v(3.0, -1.0, 0.5), v(4.0, 0.5, 0.5), v(3.5, -1.0, 0.6)]];
        assert!(r.may_show(from, &near));
        assert!(!r.may_show(from, &far));
        assert!(r.may_show(from, &through));
    }
}
