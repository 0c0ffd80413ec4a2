//! The pure-Rust backend: an `obvhs` BVH built by PLOC (Meister & Bittner 2018) with
//! parallel reinsertion (Meister & Bittner 2018), any-hit traversal with early exit for occlusion, closest hit for camera rays.
//!
//! The default builds with heavy reinsertion and traverses an 8-wide CWBVH: see [`BvhPreset`].
//!
//! Triangles are tested with the watertight algorithm of Woop, Benthin and Wald, "Watertight
//! Ray/Triangle Intersection" (JCGT 2013): no ray slips between two triangles sharing an edge
//! (obvhs's Möller–Trumbore test let camera rays escape a closed box at its edges).

use std::collections::HashMap;
use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::RayHit;
use obvhs::triangle::Triangle as ObvhsTriangle;
use obvhs::BvhBuildParams;

use super::{check_lengths, Hit, Ray, Segment, Visibility, SEGMENT_T_MAX, SEGMENT_T_MIN};
use crate::error::Result;
use crate::scene::Scene;

/// obvhs build settings, fastest build first. Measured on the gallery with
/// `meshlight bench-vis --bvh-preset all` (`docs/performance.md`, "Visibility backends"): obvhs's own presets up to `very_slow`
/// leave trees that visit hundreds of nodes per query on scenes of tiled planes; evaluating
/// every node for reinsertion four times over (`Thorough`) fixes that at about a second of
/// build per 150k triangles, and the 8-wide CWBVH then traverses fastest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BvhPreset {
    /// obvhs `fast_build`, BVH2.
    Fast,
    /// obvhs `medium_build`, BVH2.
    Medium,
    /// obvhs `very_slow_build`, BVH2.
    VerySlow,
    /// `very_slow_build` with reinsertion ratio 4, BVH2.
    Thorough,
    /// `very_slow_build` with reinsertion ratio 4, converted to an 8-wide compressed CWBVH.
    #[default]
    ThoroughWide,
}

impl BvhPreset {
    /// Every preset, for benchmarks.
    pub const ALL: [BvhPreset; 5] = [
        Self::Fast,
        Self::Medium,
        Self::VerySlow,
        Self::Thorough,
        Self::ThoroughWide,
    ];

    /// Short name for reports and `--bvh-preset`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fast => "fast",
            Self::Medium => "medium",
            Self::VerySlow => "very-slow",
            Self::Thorough => "thorough",
            Self::ThoroughWide => "thorough-wide",
        }
    }

    /// The preset of a name.
    pub fn from_name(name: &str) -> Option<BvhPreset> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    fn wide(self) -> bool {
        self == Self::ThoroughWide
    }

    fn params(self) -> BvhBuildParams {
        match self {
            Self::Fast => BvhBuildParams::fast_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::VerySlow => BvhBuildParams::very_slow_build(),
            Self::Thorough | Self::ThoroughWide => BvhBuildParams {
                reinsertion_batch_ratio: 4.0,
                ..BvhBuildParams::very_slow_build()
            },
        }
    }
}

enum Tree {
    Binary(Bvh2),
    Wide(CwBvh),
}

/// An obvhs BVH over a meshlight scene's triangles.
pub struct BvhScene {
    tree: Tree,
    /// Triangles in the tree's primitive order, so leaves index them directly.
    triangles: Vec<[Vec3A; 3]>,
    /// Scene triangle index of each entry of `triangles`.
    ids: Vec<u32>,
    preset: BvhPreset,
    /// How far before its origin a ray is cast from (the scene's diagonal; see
    /// [`BvhScene::intersect`]).
    backoff: f32,
}

impl BvhScene {
    /// Builds the BVH.
    pub fn new(scene: &Scene, preset: BvhPreset) -> Self {
        // Each distinct triangle once: copies of one triangle (same corners, same winding)
        // answer every query alike, and obvhs's builders take time quadratic in the copies
        // (10k copies 3.7 s, 40k 66 s). A hit is reported on the first copy. Windings are
        // kept apart so a face and its reverse (a two-sided wall made of both) stay two.
        let mut first: HashMap<[[u32; 3]; 3], u32> = HashMap::new();
        let mut unique: Vec<u32> = Vec::new();
        for (i, t) in scene.triangles.iter().enumerate() {
            // + 0.0 folds −0.0 into 0.0 so the bits compare as the values do.
            let mut key = t
                .vertices
                .map(|v| (v + Vec3::ZERO).to_array().map(f32::to_bits));
            let start = (0..3).min_by_key(|&k| key[k]).unwrap_or(0);
            key.rotate_left(start);
            first.entry(key).or_insert_with(|| {
                unique.push(i as u32);
                i as u32
            });
        }
        let input: Vec<ObvhsTriangle> = unique
            .iter()
            .map(|&i| {
                let t = &scene.triangles[i as usize];
                ObvhsTriangle {
                    v0: t.vertices[0].into(),
                    v1: t.vertices[1].into(),
                    v2: t.vertices[2].into(),
                }
            })
            .collect();
        let mut build_time = Duration::ZERO;
        let (tree, ids) = match preset.wide() {
            true => {
                let cw = build_cwbvh_from_tris(&input, preset.params(), &mut build_time);
                let ids = cw.primitive_indices.clone();
                (Tree::Wide(cw), ids)
            }
            false => {
                let bvh = build_bvh2_from_tris(&input, preset.params(), &mut build_time);
                let ids = bvh.primitive_indices.clone();
                (Tree::Binary(bvh), ids)
            }
        };
        let triangles = ids
            .iter()
            .map(|&i| {
                let t = &input[i as usize];
                [t.v0, t.v1, t.v2]
            })
            .collect();
        let ids = ids.iter().map(|&i| unique[i as usize]).collect();
        BvhScene {
            tree,
            triangles,
            ids,
            preset,
            backoff: scene.bounds.diagonal(),
        }
    }

    /// The preset it was built with.
    pub fn preset(&self) -> BvhPreset {
        self.preset
    }
}

impl Visibility for BvhScene {
    fn name(&self) -> &'static str {
        "bvh"
    }

    fn occluded(&self, segments: &[Segment], out: &mut [bool]) -> Result<()> {
        check_lengths("bvh", segments.len(), out.len())?;
        super::check_segments(segments)?;
        let tris = &self.triangles;
        for (s, o) in segments.iter().zip(out.iter_mut()) {
            // Cast from a point one length before `a`: obvhs's traversal misses some hits a few
            // 1e-5 of the length from a ray's origin (a face 1.5 mm before a lifted point on a
            // painting's canvas in the gallery), which Embree finds.
            let d = s.b - s.a;
            let ray = obvhs::ray::Ray::new(
                (s.a - d).into(),
                d.into(),
                1.0 + SEGMENT_T_MIN,
                1.0 + SEGMENT_T_MAX,
            );
            let test = Watertight::new(&ray);
            let intersect = |r: &obvhs::ray::Ray, id: usize| test.intersect(&tris[id], r);
            *o = !match &self.tree {
                Tree::Binary(bvh) => bvh.ray_traverse_miss(ray, intersect),
                Tree::Wide(bvh) => bvh.ray_traverse_miss(ray, intersect),
            };
        }
        Ok(())
    }

    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> Result<()> {
        check_lengths("bvh", rays.len(), out.len())?;
        super::check_rays(rays)?;
        let tris = &self.triangles;
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            // Cast from a scene's diagonal before the origin, as segments are: a final gather's
            // rays leave a lifted point beside a crease, whose first hit lies a lift away, and
            // obvhs missed some of those in a scene a millimetre across (Embree did not).
            let back = self.backoff / r.dir.length();
            let back = if back.is_finite() { back } else { 0.0 };
            let ray = obvhs::ray::Ray::new(
                (r.origin - back * r.dir).into(),
                r.dir.into(),
                r.t_min + back,
                r.t_max + back,
            );
            let mut hit = RayHit::none();
            let test = Watertight::new(&ray);
            let intersect = |r: &obvhs::ray::Ray, id: usize| test.intersect(&tris[id], r);
            let found = match &self.tree {
                Tree::Binary(bvh) => bvh.ray_traverse(ray, &mut hit, intersect),
                Tree::Wide(bvh) => bvh.ray_traverse(ray, &mut hit, intersect),
            };
            *o = found.then(|| Hit {
                t: (hit.t - back).max(r.t_min),
                triangle: self.ids[hit.primitive_id as usize],
            });
        }
        Ok(())
    }
}

/// Per-ray constants of the watertight test: the ray's dominant axis becomes z, and a shear
/// maps its direction onto +z, so the edge tests are 2D and exact in sign.
struct Watertight {
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
    origin: Vec3A,
}

impl Watertight {
    fn new(ray: &obvhs::ray::Ray) -> Self {
        let d = ray.direction;
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Watertight {
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
            origin: ray.origin,
        }
    }

    /// Distance to the triangle within [tmin, tmax], or infinity.
    fn intersect(&self, t: &[Vec3A; 3], ray: &obvhs::ray::Ray) -> f32 {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = t[0] - self.origin;
        let b = t[1] - self.origin;
        let c = t[2] - self.origin;
        let (ax, ay) = (a[kx] - self.sx * a[kz], a[ky] - self.sy * a[kz]);
        let (bx, by) = (b[kx] - self.sx * b[kz], b[ky] - self.sy * b[kz]);
        let (cx, cy) = (c[kx] - self.sx * c[kz], c[ky] - self.sy * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // Exactly on an edge in f32: decide in f64, so neighbours agree.
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (
                f64::from(ax),
                f64::from(ay),
                f64::from(bx),
                f64::from(by),
                f64::from(cx),
                f64::from(cy),
            );
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return f32::INFINITY;
        }
        let det = u + v + w;
        if det == 0.0 {
            return f32::INFINITY;
        }
        let (az, bz, cz) = (self.sz * a[kz], self.sz * b[kz], self.sz * c[kz]);
        let t_scaled = u * az + v * bz + w * cz;
        let t = t_scaled / det;
        if t >= ray.tmin && t <= ray.tmax && t.is_finite() {
            t
        } else {
            f32::INFINITY
        }
    }
}
