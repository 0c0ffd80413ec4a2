//! Light that reaches a diffuse surface by way of specular ones (`docs/method.md` §22): the
//! paper's other future work. What a scene's mirrors, glossy surfaces and glass are
//! (`Specular`); light paths through mirror windows and glass to a light (`shadow`); the
//! mirror images of lights (`images`); and chains followed from a receiver through specular
//! bounces to the diffuse surfaces and lights they end at (`gather`).

pub(crate) mod gather;
pub(crate) mod highlight;
pub(crate) mod images;
pub(crate) mod lights;
pub(crate) mod photons;
pub(crate) mod shadow;

use glam::Vec3;

use crate::scene::{Kind, Scene};

/// The most specular bounces a chain, or a mirror image of a light, may take at most.
pub const MAX_SPECULAR_DEPTH: u32 = 64;

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
    /// Its area: what a chain through it can carry grows with it.
    pub area: f32,
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

/// Neighbouring facets of one specular material whose normals differ by less than this
/// (radians) belong to one curved surface: a tessellated sphere's facets differ by a few
/// degrees, a box's faces by 90°.
const CURVED_ANGLE: f32 = 0.6;

/// A facet of a curved piece whose area is below this share of the piece's is curved: it makes
/// no mirror images (a large flat mirror with narrow bevels keeps its own).
const CURVED_SHARE: f64 = 0.25;

/// A piece of thick glass whose thickness (across its largest face) is at most this share of
/// its width is a slab (a window's pane modelled as a box, a table top): light passes it along
/// the straight line (`shadow`). Thicker pieces (a block, a ball) refract it: their light is
/// carried by photons (`photons`).
const SLAB: f32 = 0.1;

/// What a scene's specular surfaces are.
#[derive(Clone, Debug, Default)]
pub(crate) struct Specular {
    /// Per surface: whether its material is specular (mirror, glossy or glass).
    pub specular: Vec<bool>,
    /// Per surface: its glass, if any (index, filter, thin).
    pub glass: Vec<Option<(f32, Vec3, bool)>>,
    /// Per surface: whether shadow rays pass it straight (thin panes, and the faces of slabs);
    /// other glass blocks them.
    pub straight: Vec<bool>,
    /// Per surface: whether it is a facet of a curved surface (no mirror images, no highlight
    /// plane).
    pub curved: Vec<bool>,
    /// The planar reflectors, in surface order: mirrors, panes and glass faces that are not
    /// facets of a curved surface.
    pub reflectors: Vec<Reflector>,
    /// Per surface: its index in `reflectors`, if it is one.
    pub reflector_of: Vec<Option<u32>>,
    /// Whether any surface is glass (shadow rays then pass through it).
    pub any_glass: bool,
    /// Per triangle: its surface and front normal (what a hit needs).
    pub faces: Vec<(u32, Vec3)>,
}

impl Specular {
    /// The scene's specular surfaces.
    pub(crate) fn of(scene: &Scene) -> Specular {
        let n = scene.surfaces.len();
        let (curved, straight) = shapes(scene);
        let mut s = Specular {
            specular: vec![false; n],
            glass: vec![None; n],
            straight,
            curved,
            reflectors: Vec::new(),
            reflector_of: vec![None; n],
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
            if let Some(reflects) = reflects.filter(|_| !s.curved[i]) {
                let pane = matches!(reflects, Reflects::Pane(_));
                s.reflector_of[i] = Some(s.reflectors.len() as u32);
                s.reflectors.push(Reflector {
                    bounds: window_bounds(scene, surface),
                    surface: i as u32,
                    area: surface.area as f32,
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

/// How a scene's specular surfaces carry light (`docs/method.md` §22), as `meshlight info`
/// reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct SpecularSummary {
    /// Flat mirrors, panes and glass faces: they make mirror images of the lights.
    pub flat_reflectors: usize,
    /// Facets of curved mirrors and glass (a tessellated ball's): they make no images.
    pub curved_facets: usize,
    /// Faces of glass solids shadow rays do not pass straight (a block, a ball: not a slab or
    /// a pane).
    pub refracting_faces: usize,
    /// Glossy surfaces (rough mirrors): their light comes by the chains' light sampling.
    pub glossy_surfaces: usize,
    /// Chains of images listed (at most 64), and whether they are all the chains that carry
    /// light.
    pub chains: usize,
    /// Whether every chain that carries light is listed.
    pub chains_complete: bool,
    /// Whether photons carry light the images do not.
    pub photons: bool,
}

/// How `scene`'s specular surfaces carry light at specular depth `depth`.
pub fn summary(scene: &Scene, depth: u32) -> SpecularSummary {
    let spec = Specular::of(scene);
    let listing = images::chains(&spec, depth);
    let n = scene.surfaces.len();
    SpecularSummary {
        flat_reflectors: spec.reflectors.len(),
        curved_facets: (0..n).filter(|&s| spec.specular[s] && spec.curved[s]).count(),
        refracting_faces: (0..n)
            .filter(|&s| spec.glass[s].is_some() && !spec.straight[s])
            .count(),
        glossy_surfaces: (0..n)
            .filter(|&s| {
                spec.specular[s]
                    && matches!(scene.material_of(s as u32).kind, Kind::Specular { roughness, .. } if roughness > 0.0)
            })
            .count(),
        chains: listing.chains.len(),
        chains_complete: listing.complete,
        photons: depth > 0 && photons::needed(scene, &spec, &listing),
    }
}

/// Per surface: whether it is a facet of a curved specular surface, and whether shadow rays
/// pass it straight (see [`Specular::straight`]).
fn shapes(scene: &Scene) -> (Vec<bool>, Vec<bool>) {
    use crate::scene::adjacency::{pieces, shared_edges};
    let n = scene.surfaces.len();
    let material = |s: u32| scene.material_of(s);
    let edges = shared_edges(scene);
    // Curved: facets of one specular material joined along edges at shallow angles.
    let smooth = edges.iter().copied().filter(|&(a, b)| {
        let (sa, sb) = (&scene.surfaces[a as usize], &scene.surfaces[b as usize]);
        sa.material == sb.material
            && material(a).is_specular()
            && sa.normal.dot(sb.normal) > CURVED_ANGLE.cos()
    });
    let piece = pieces(n, smooth);
    let mut piece_area = vec![0.0f64; n];
    let mut members = vec![0u32; n];
    for (s, surface) in scene.surfaces.iter().enumerate() {
        piece_area[piece[s] as usize] += surface.area;
        members[piece[s] as usize] += 1;
    }
    let curved = (0..n)
        .map(|s| {
            let p = piece[s] as usize;
            members[p] > 1 && scene.surfaces[s].area < CURVED_SHARE * piece_area[p]
        })
        .collect();
    // Straight: panes, and the faces of thick glass pieces (joined at any angle) thin across
    // their largest face.
    let glass = |s: u32| match material(s).kind {
        Kind::Glass { thin, .. } => Some(thin),
        _ => None,
    };
    let solid = edges
        .iter()
        .copied()
        .filter(|&(a, b)| glass(a) == Some(false) && glass(b) == Some(false));
    let piece = pieces(n, solid);
    let mut largest: Vec<Option<u32>> = vec![None; n];
    for s in (0..n as u32).filter(|&s| glass(s) == Some(false)) {
        let p = &mut largest[piece[s as usize] as usize];
        if p.is_none_or(|l| scene.surfaces[l as usize].area < scene.surfaces[s as usize].area) {
            *p = Some(s);
        }
    }
    let mut extent: Vec<Option<(Vec3, Vec3)>> = vec![None; n];
    for s in (0..n as u32).filter(|&s| glass(s) == Some(false)) {
        let p = piece[s as usize] as usize;
        let Some(l) = largest[p] else { continue };
        // In the frame of the largest face: (across, along u, along v).
        let normal = scene.surfaces[l as usize].normal;
        let (u, v) = normal.any_orthonormal_pair();
        let range = &scene.surfaces[s as usize].triangles;
        for t in &scene.triangles[range.start as usize..range.end as usize] {
            for x in t.vertices {
                let q = Vec3::new(normal.dot(x), u.dot(x), v.dot(x));
                let e = extent[p].get_or_insert((q, q));
                *e = (e.0.min(q), e.1.max(q));
            }
        }
    }
    let straight = (0..n as u32)
        .map(|s| match glass(s) {
            Some(true) => true,
            Some(false) => extent[piece[s as usize] as usize].is_some_and(|(lo, hi)| {
                let size = hi - lo;
                size.x <= SLAB * size.y.min(size.z)
            }),
            None => false,
        })
        .collect();
    (curved, straight)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::fixtures::{glass, mirror, Parts};

    #[test]
    fn curved_facets_and_refracting_solids_are_told_from_flat_ones() {
        let mut p = Parts::default();
        let room = p.material(crate::scene::Material::diffuse(
            "room",
            Vec3::splat(0.5),
            Vec3::splat(1.0),
        ));
        let (chrome, solid, pane) = (p.material(mirror(0.9)), p.material(glass(false)), {
            p.material(glass(true))
        });
        p.cuboid(Vec3::ZERO, Vec3::splat(10.0), true, room);
        // A chrome ball (320 facets) and a chrome box; a glass cube, a glass slab 5 cm thick,
        // a box of panes; a glass ball.
        p.sphere(Vec3::new(2.0, 2.0, 2.0), 1.0, 2, chrome);
        p.cuboid(
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(6.0, 1.0, 6.0),
            false,
            chrome,
        );
        p.cuboid(
            Vec3::new(7.0, 0.0, 7.0),
            Vec3::new(8.0, 1.0, 8.0),
            false,
            solid,
        );
        p.cuboid(
            Vec3::new(1.0, 5.0, 7.0),
            Vec3::new(2.0, 5.05, 8.0),
            false,
            solid,
        );
        p.cuboid(
            Vec3::new(7.0, 5.0, 1.0),
            Vec3::new(8.0, 6.0, 2.0),
            false,
            pane,
        );
        p.sphere(Vec3::new(5.0, 7.0, 2.0), 1.0, 2, solid);
        let scene = p.scene(Vec3::new(5.0, 5.0, 9.5), Vec3::new(5.0, 5.0, 0.0));
        let spec = Specular::of(&scene);
        // Each object's surfaces, by where their first corner lies.
        let of = |lo: Vec3, hi: Vec3| -> Vec<usize> {
            (0..scene.surfaces.len())
                .filter(|&s| {
                    let t = &scene.triangles[scene.surfaces[s].triangles.start as usize];
                    t.vertices[0].cmpge(lo).all() && t.vertices[0].cmple(hi).all()
                })
                .collect()
        };
        let ball = of(Vec3::splat(0.9), Vec3::splat(3.1));
        let chrome_box = of(Vec3::new(5.0, 0.0, 5.0), Vec3::new(6.0, 1.0, 6.0));
        let cube = of(Vec3::new(7.0, 0.0, 7.0), Vec3::new(8.0, 1.0, 8.0));
        let slab = of(Vec3::new(1.0, 5.0, 7.0), Vec3::new(2.0, 5.05, 8.0));
        let panes = of(Vec3::new(7.0, 5.0, 1.0), Vec3::new(8.0, 6.0, 2.0));
        let glass_ball = of(Vec3::new(3.9, 5.9, 0.9), Vec3::new(6.1, 8.1, 3.1));
        assert_eq!(ball.len(), 320);
        assert_eq!(glass_ball.len(), 320);
        assert_eq!(
            [chrome_box.len(), cube.len(), slab.len(), panes.len()],
            [6; 4]
        );
        // Curved facets make no images; flat faces do.
        for &s in ball.iter().chain(&glass_ball) {
            assert!(
                spec.curved[s] && spec.reflector_of[s].is_none(),
                "surface {s}"
            );
        }
        for &s in chrome_box.iter().chain(&cube).chain(&slab).chain(&panes) {
            assert!(
                !spec.curved[s] && spec.reflector_of[s].is_some(),
                "surface {s}"
            );
        }
        // Shadow rays pass panes and the slab straight, not the cube or the ball.
        assert!(slab.iter().chain(&panes).all(|&s| spec.straight[s]));
        assert!(cube.iter().chain(&glass_ball).all(|&s| !spec.straight[s]));
        assert!(chrome_box.iter().chain(&ball).all(|&s| !spec.straight[s]));
    }

    #[test]
    fn a_segment_passes_a_window_only_where_it_crosses_the_plane_inside_it() {
        // A 1 × 1 window in the plane y = 0, facing up.
        let r = Reflector {
            surface: 0,
            area: 1.0,
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
