//! The pure-Rust backend: an `obvhs` BVH built by PLOC (Meister & Bittner 2018) with
//! parallel reinsertion (Meister & Bittner 2018), any-hit traversal with early exit for occlusion, closest hit for camera rays.
//!
//! The default builds with heavy reinsertion and traverses an 8-wide CWBVH: see [`BvhPreset`].

use std::time::Duration;

use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::RayHit;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle as ObvhsTriangle;
use obvhs::BvhBuildParams;

use super::{check_lengths, Hit, Ray, Segment, Visibility, SEGMENT_T_MAX, SEGMENT_T_MIN};
use crate::error::Result;
use crate::scene::Scene;

/// obvhs build settings, fastest build first. Measured on the gallery with
/// `meshlight bench-vis --bvh-preset all` (README): obvhs's own presets up to `very_slow`
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
    /// Triangles in the tree's primitive order, so leaves index them directly, with edges and
    /// normal precomputed for the intersection test.
    triangles: Vec<RtTriangle>,
    /// Scene triangle index of each entry of `triangles`.
    ids: Vec<u32>,
    preset: BvhPreset,
}

impl BvhScene {
    /// Builds the BVH.
    pub fn new(scene: &Scene, preset: BvhPreset) -> Self {
        let input: Vec<ObvhsTriangle> = scene
            .triangles
            .iter()
            .map(|t| ObvhsTriangle {
                v0: t.vertices[0].into(),
                v1: t.vertices[1].into(),
                v2: t.vertices[2].into(),
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
            .map(|&i| RtTriangle::from(&input[i as usize]))
            .collect();
        BvhScene {
            tree,
            triangles,
            ids,
            preset,
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
        let tris = &self.triangles;
        for (s, o) in segments.iter().zip(out.iter_mut()) {
            let ray =
                obvhs::ray::Ray::new(s.a.into(), (s.b - s.a).into(), SEGMENT_T_MIN, SEGMENT_T_MAX);
            let intersect = |r: &obvhs::ray::Ray, id: usize| tris[id].intersect(r);
            *o = !match &self.tree {
                Tree::Binary(bvh) => bvh.ray_traverse_miss(ray, intersect),
                Tree::Wide(bvh) => bvh.ray_traverse_miss(ray, intersect),
            };
        }
        Ok(())
    }

    fn intersect(&self, rays: &[Ray], out: &mut [Option<Hit>]) -> Result<()> {
        check_lengths("bvh", rays.len(), out.len())?;
        let tris = &self.triangles;
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            let ray = obvhs::ray::Ray::new(r.origin.into(), r.dir.into(), r.t_min, r.t_max);
            let mut hit = RayHit::none();
            let intersect = |r: &obvhs::ray::Ray, id: usize| tris[id].intersect(r);
            let found = match &self.tree {
                Tree::Binary(bvh) => bvh.ray_traverse(ray, &mut hit, intersect),
                Tree::Wide(bvh) => bvh.ray_traverse(ray, &mut hit, intersect),
            };
            *o = found.then(|| Hit {
                t: hit.t,
                triangle: self.ids[hit.primitive_id as usize],
            });
        }
        Ok(())
    }
}
