//! Mirror images of lights (Rushmeier and Torrance 1990; Radiance's virtual sources): light that
//! reaches a point by way of planar mirrors, panes and glass faces comes from the light's image
//! across them, seen through each reflector's outline as through a window. The images are
//! chains of reflectors, nearest the receiver first; a chain whose reflectances at normal
//! incidence multiply to less than [`IMAGE_CUTOFF`] is left out.

use glam::{DMat3, DVec3, Vec3};

use super::{Reflector, Specular};

/// Chains of images carrying less than this share of a light (at normal incidence) are left
/// out: a pane's reflection of a pane's reflection (0.6%), say.
pub(crate) const IMAGE_CUTOFF: f64 = 0.01;

/// A chain of reflectors a light is seen through: indices into `Specular::reflectors`, the
/// one nearest the receiver first.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Chain {
    pub reflectors: Vec<u32>,
    /// Maps a direction along the unfolded straight line to the direction of the last
    /// segment, at the light.
    pub linear: DMat3,
}

/// A point reflected across a reflector's plane.
pub(crate) fn reflect_point(r: &Reflector, p: Vec3) -> Vec3 {
    p - 2.0 * (r.normal.dot(p) - r.offset) * r.normal
}

/// Chains of images listed at most. Each chain costs every receiver and every pixel a test of
/// its window, and shadow rays where the image shows: a room of mirrors has R(R − 1)^(d−1)
/// chains of d reflectors. The chains left out carry their light by photons (`photons`).
pub(crate) const MAX_CHAINS: usize = 64;

/// The chains of images to look through.
#[derive(Clone, Debug, Default)]
pub(crate) struct Listing {
    /// Shorter chains first, then by reflector.
    pub chains: Vec<Chain>,
    /// Whether every chain that can carry light was listed (none left out for
    /// [`MAX_CHAINS`]).
    pub complete: bool,
}

/// The chains of at most `depth` reflectors that carry at least [`IMAGE_CUTOFF`] and that a
/// straight line could pass (see [`can_follow`]), at most [`MAX_CHAINS`]: each length whole
/// while it fits, then its chains that carry the most (reflectance × smallest window).
pub(crate) fn chains(spec: &Specular, depth: u32) -> Listing {
    let mut listed: Vec<Vec<u32>> = Vec::new();
    let mut level: Vec<(Vec<u32>, f64)> = vec![(Vec::new(), 1.0)];
    let mut complete = true;
    for _ in 0..depth {
        // Every way to make a listed chain one reflector longer: (chain, carried, weight).
        let mut longer: Vec<(Vec<u32>, f64, f64)> = Vec::new();
        for (chain, carried) in &level {
            for (i, r) in spec.reflectors.iter().enumerate() {
                let next = carried * r.reflects.typical();
                if chain.last() == Some(&(i as u32))
                    || next < IMAGE_CUTOFF
                    || !can_follow(spec, chain, i as u32)
                {
                    continue;
                }
                let window = chain
                    .iter()
                    .map(|&k| spec.reflectors[k as usize].area)
                    .fold(r.area, f32::min);
                let mut c = chain.clone();
                c.push(i as u32);
                longer.push((c, next, next * f64::from(window)));
            }
        }
        let room = MAX_CHAINS - listed.len();
        if longer.len() > room {
            complete = false;
            longer.sort_by(|a, b| b.2.total_cmp(&a.2).then_with(|| a.0.cmp(&b.0)));
            longer.truncate(room);
        }
        if longer.is_empty() {
            break;
        }
        longer.sort_by(|a, b| a.0.cmp(&b.0));
        listed.extend(longer.iter().map(|(c, ..)| c.clone()));
        level = longer
            .into_iter()
            .map(|(c, carried, _)| (c, carried))
            .collect();
    }
    let chains = listed
        .into_iter()
        .map(|reflectors| {
            let linear = reflectors.iter().fold(DMat3::IDENTITY, |a, &k| {
                let n = spec.reflectors[k as usize].normal.as_dvec3();
                (DMat3::IDENTITY - 2.0 * outer(n, n)) * a
            });
            Chain { reflectors, linear }
        })
        .collect();
    Listing { chains, complete }
}

/// The listed chains as a tree of reflectors, to follow a path's reflections one at a time
/// and know at its end whether the images carry it.
#[derive(Clone, Debug, Default)]
pub(crate) struct ChainTree {
    /// (node, reflector) → the node one reflector further.
    next: std::collections::HashMap<(u32, u32), u32>,
    /// Per node: whether its reflectors, in order, are a listed chain.
    listed: Vec<bool>,
}

impl ChainTree {
    /// No reflection yet: the straight way, which the direct light carries.
    pub(crate) const ROOT: u32 = 0;
    /// Reflections no listed chain begins with.
    pub(crate) const OFF: u32 = u32::MAX;

    /// The tree of `chains` read from the receiver (`from_light` false: as listed, nearest the
    /// receiver first) or from the light (reversed).
    pub(crate) fn new(chains: &[Chain], from_light: bool) -> ChainTree {
        let mut tree = ChainTree {
            next: std::collections::HashMap::new(),
            listed: vec![true],
        };
        for chain in chains {
            let mut node = Self::ROOT;
            let order: Vec<u32> = if from_light {
                chain.reflectors.iter().rev().copied().collect()
            } else {
                chain.reflectors.clone()
            };
            for r in order {
                let fresh = tree.listed.len() as u32;
                node = *tree.next.entry((node, r)).or_insert(fresh);
                if node == fresh {
                    tree.listed.push(false);
                }
            }
            tree.listed[node as usize] = true;
        }
        tree
    }

    /// The node after reflecting on reflector `r` at `node`.
    pub(crate) fn step(&self, node: u32, r: u32) -> u32 {
        self.next.get(&(node, r)).copied().unwrap_or(Self::OFF)
    }

    /// Whether the reflections that led to `node` are a listed chain (or none).
    pub(crate) fn listed(&self, node: u32) -> bool {
        self.listed.get(node as usize).copied().unwrap_or(false)
    }
}

/// Whether reflector `next` can follow `chain` on a straight line unfolded across the chain's
/// mirrors: each reflector must stand (partly) on the reflecting side of the one before it and
/// that one on its own, and, unfolded, `next`'s window must lie (partly) behind the plane of
/// every window before it (a line crosses each plane once). In a box of mirrors, say, left
/// wall → front wall → left wall is impossible: unfolded, the second left wall lies in the
/// plane of the first.
fn can_follow(spec: &Specular, chain: &[u32], next: u32) -> bool {
    let Some(&last) = chain.last() else {
        return true;
    };
    let r = |k: u32| &spec.reflectors[k as usize];
    let (a, b) = (r(last), r(next));
    let corners = |r: &Reflector| {
        let (lo, hi) = r.bounds;
        (0..8).map(move |i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
    };
    let tolerance = |r: &Reflector| 1e-5 * (r.bounds.1 - r.bounds.0).length();
    let in_front = |of: &Reflector, what: &Reflector| {
        of.both_sides || corners(what).any(|p| of.normal.dot(p) - of.offset > tolerance(what))
    };
    if !in_front(a, b) || !in_front(b, a) {
        return false;
    }
    // Unfolded: next's corners reflected back across chain[j + 1..] lie behind plane j.
    let mut points: Vec<Vec3> = corners(b).collect();
    for &k in chain.iter().rev() {
        let plane = r(k);
        for p in &mut points {
            *p = reflect_point(plane, *p);
        }
        if !plane.both_sides
            && !points
                .iter()
                .any(|&p| plane.normal.dot(p) - plane.offset < -tolerance(b))
        {
            return false;
        }
    }
    true
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

impl Chain {
    /// Where a light point appears from the receiver's side: reflected across the last
    /// reflector first.
    pub(crate) fn image_of(&self, spec: &Specular, p: Vec3) -> Vec3 {
        self.reflectors
            .iter()
            .rev()
            .fold(p, |p, &k| reflect_point(&spec.reflectors[k as usize], p))
    }

    /// Whether a receiver at x can see anything of the first reflector's reflecting side.
    pub(crate) fn faces(&self, spec: &Specular, x: Vec3) -> bool {
        let r = &spec.reflectors[self.reflectors[0] as usize];
        r.both_sides || r.normal.dot(x) - r.offset > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::super::Reflects;
    use super::*;

    /// A 4 × 4 mirror in the plane normal · x = offset, centred on the normal's line through
    /// the origin (an axis: the others span ±2).
    fn mirror(normal: Vec3, offset: f32, ks: f32) -> Reflector {
        let centre = normal * offset;
        let span = Vec3::splat(2.0) * (Vec3::ONE - normal.abs());
        Reflector {
            surface: 0,
            area: 16.0,
            normal,
            offset,
            reflects: Reflects::Mirror(Vec3::splat(ks)),
            both_sides: false,
            bounds: (centre - span, centre + span),
        }
    }

    /// The mirrors of a 4 × 4 × 4 box around the origin, facing in: −x, +x, −z, +z walls.
    fn box_walls(ks: f32) -> Vec<Reflector> {
        vec![
            mirror(Vec3::X, -2.0, ks),
            mirror(Vec3::NEG_X, -2.0, ks),
            mirror(Vec3::Z, -2.0, ks),
            mirror(Vec3::NEG_Z, -2.0, ks),
        ]
    }

    #[test]
    fn chains_a_straight_line_cannot_take_are_left_out() {
        // Four mirror walls around a room: a straight line meets the walls of each axis in
        // turn (left, right, left, …), so left, front, left is impossible. Of the 4 · 3 · 3
        // chains of three walls with none twice in a row, counted by hand: one axis only, 2
        // per axis (L R L, R L R; F B F, B F B): 4; both axes: 6 orders of the axes (x x z,
        // x z x, z x x, z z x, z x z, x z z), each with 2 ways for the axis used twice to
        // alternate and 2 walls for the other: 24. 28 in all.
        let spec = Specular {
            reflectors: box_walls(0.9),
            ..Specular::default()
        };
        let listing = chains(&spec, 3);
        let three: Vec<&Vec<u32>> = listing
            .chains
            .iter()
            .map(|c| &c.reflectors)
            .filter(|c| c.len() == 3)
            .collect();
        let axis = |k: u32| k / 2;
        // Each axis's walls alternate along the chain.
        for c in &three {
            for a in 0..2 {
                let along: Vec<u32> = c.iter().copied().filter(|&k| axis(k) == a).collect();
                assert!(along.windows(2).all(|w| w[0] != w[1]), "{c:?}");
            }
        }
        assert_eq!(three.len(), 28, "{three:?}");
        assert_eq!(listing.chains.len(), 4 + 4 * 3 + 28);
        assert!(listing.complete);
    }

    #[test]
    fn the_tree_of_chains_knows_a_listed_chain_read_either_way() {
        let spec = Specular {
            reflectors: box_walls(0.9),
            ..Specular::default()
        };
        let listing = chains(&spec, 2);
        for from_light in [false, true] {
            let tree = ChainTree::new(&listing.chains, from_light);
            let walk = |path: &[u32]| {
                path.iter()
                    .fold(ChainTree::ROOT, |node, &r| tree.step(node, r))
            };
            assert!(tree.listed(ChainTree::ROOT));
            for c in &listing.chains {
                let mut path = c.reflectors.clone();
                if from_light {
                    path.reverse();
                }
                assert!(tree.listed(walk(&path)), "{path:?}");
            }
            // Longer than listed, or a wall twice in a row: not carried.
            assert!(!tree.listed(walk(&[0, 1, 0])));
            assert!(!tree.listed(walk(&[2, 2])));
        }
    }

    #[test]
    fn a_listing_past_its_bound_keeps_the_short_chains_and_says_it_is_incomplete() {
        let spec = Specular {
            reflectors: box_walls(0.9),
            ..Specular::default()
        };
        let listing = chains(&spec, 16);
        assert_eq!(listing.chains.len(), MAX_CHAINS);
        assert!(!listing.complete);
        // Whole lengths first: every chain of one and two reflectors is listed.
        let short = listing
            .chains
            .iter()
            .filter(|c| c.reflectors.len() <= 2)
            .count();
        assert_eq!(short, 4 + 4 * 3);
    }

    #[test]
    fn two_facing_mirrors_make_images_of_images_until_they_carry_too_little() {
        let spec = Specular {
            reflectors: vec![mirror(Vec3::X, 0.0, 0.5), mirror(Vec3::NEG_X, -4.0, 0.5)],
            ..Specular::default()
        };
        // 0.5, 0.25, 0.125, …: 1% is passed after six reflections, two chains per length.
        let all = chains(&spec, 16).chains;
        assert_eq!(all.len(), 12);
        assert_eq!(chains(&spec, 2).chains.len(), 4);
        let c = &all[2];
        assert_eq!(c.reflectors, vec![0, 1]);
        // A light at x = 3 seen through the mirror at x = 0 after the one at x = 4: its image
        // at 5 across x = 4, then −5 across x = 0.
        let image = c.image_of(&spec, Vec3::new(3.0, 1.0, 0.0));
        assert!(
            (image - Vec3::new(-5.0, 1.0, 0.0)).length() < 1e-6,
            "{image}"
        );
        // The unfolded direction (−1, 0, 0) leaves the second mirror along −x again.
        let d = c.linear * DVec3::NEG_X;
        assert!((d - DVec3::NEG_X).length() < 1e-12, "{d}");
    }
}
