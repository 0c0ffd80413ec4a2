//! Links between clusters, refined by an error bound as in hierarchical radiosity with
//! clustering (Hanrahan, Salzman and Aupperle 1991; Smits, Arvo and Greenberg 1994).
//!
//! Light goes both ways along a pair of nodes and visibility is symmetric, so pairs are refined
//! unordered: starting from two receiver groups' roots, a pair {A, B} is
//! - dropped when no member of one faces any member of the other (the planes, or the normal
//!   cones and the pair's angular size, say so), or when it is a planar node with itself;
//! - a pair of leaf links when both are single samples: the flat solver's form factors and one
//!   ray;
//! - a pair of cluster links (A → B and B → A) when both nodes are coherent (or the pair has
//!   so few member pairs that the probes see every one, so nothing can hide behind what stands
//!   among the members: a partial view then links member by member, below), well separated
//!   (d > 2(r_A + r_B), and beyond the near field of either node's largest sample), and the
//!   bound on the radiosity error either link can make at its receiver is below the tolerance:
//!   ρ_max(R) · P_S · (c_S⁺c_R⁺/(d − r)² − c_S⁻c_R⁻/(d + r)²) / π, with P_S the power the
//!   shooter stands for, r = r_A + r_B, and c± the largest and smallest cosines the geometry
//!   allows (the least taken as 0 where some members face away). Its visibility comes from
//!   probes: member pairs, every pair when there are few, else stratified; a ray for each
//!   pair that faces. All visible (and each node wholly in front of the other): linked. None:
//!   dropped. Unless some of the pairs were left unprobed and something hovers close in front
//!   of either node (a light fixture just under a ceiling: members in its gap and members
//!   beside it see the room differently, and all probes may land on one kind): then refined.
//!   Some: refined; where every pair was probed, each receiving member gets one link from the
//!   whole shooter with the share of it that member sees, if it sees every shooting member
//!   that faces it or the shooter stands for its members evenly (coherent, no fixture hovering
//!   over any of them), else a link from each largest part of the shooter all of whose members
//!   it sees and faces. Visibility never makes a link coarser. A partly visible link is
//!   averaged only where everything it could carry is negligible, and never with
//!   `exact_visibility`: refining every
//!   partial link down to samples follows each doorway's silhouette sample by sample, so its
//!   links grow faster than the samples (N^1.2 on the gallery against N^0.6);
//! - otherwise refined: the larger node (the one holding the other, if so) is split.
//!
//! Where some members face away (a facet whose plane cuts through a wall node), a fully
//! visible link is kept with its formula scaled by Σ (exact form factor) / Σ (formula) over
//! its probes, which counts the pairs facing away as nothing.
//!
//! Pairs are taken from a stack in waves; each wave's rays go to the backend in one batch. The
//! order is fixed, so the links do not depend on the thread count.

use glam::Vec3;

use super::tree::{angle, Ref, Tree, View, MULTI};
use crate::error::Result;
use crate::sampling::{Samples, SurfaceMap};
use crate::solver::form_factor::{segment, Shooter, NEAR};
use crate::visibility::{Segment, Visibility};

/// A link between two samples: receiver r gets F · ΔB_s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LeafLink {
    pub r: u32,
    pub s: u32,
    pub f: f32,
}

/// A link between clusters (or a cluster and a sample): `sweep`'s formula from s to r, times
/// `factor` (1, or the probes' correction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ClusterLink {
    pub r: Ref,
    pub s: Ref,
    pub factor: f32,
}

/// The links into one receiver group (or part of them).
#[derive(Clone, Debug, Default)]
pub(crate) struct Links {
    pub leaf: Vec<LeafLink>,
    pub cluster: Vec<ClusterLink>,
    /// Visibility queries made to find them.
    pub queries: u64,
}

impl Links {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.leaf.capacity() * std::mem::size_of::<LeafLink>()
            + self.cluster.capacity() * std::mem::size_of::<ClusterLink>()
    }
}

/// Pairs taken from the stack per batch of rays.
const WAVE: usize = 256;
/// Probes per cluster link, unless its member pairs are fewer than [`EXHAUSTIVE`].
const PROBES: usize = 8;
/// Links with at most this many member pairs probe every pair.
const EXHAUSTIVE: usize = 16;
/// A partly visible link is refined unless everything it could carry, seen wholly visible, is
/// below this fraction of the tolerance: then it carries what its visible probes say; and a
/// pair with an incoherent node (something standing among its members, `coherence`) of more
/// than [`EXHAUSTIVE`] member pairs is linked only then. Whatever such a link misplaces, a
/// blurred penumbra or light put behind what stands among its members, is below this share
/// of the tolerance. On the atrium, whose small nodes mostly have a facet standing among
/// them, faint incoherent pairs linked took the links from 679 to 467 a sample.
const NEGLIGIBLE: f64 = 0.25;
/// Sheltered nodes of at most this many members are refined when their probes agree but did
/// not see every pair: a fixture's outline crossing such a node leaves a few members of each
/// kind, which eight probes can all miss. Larger ones keep their probes' verdict: refining
/// every sheltered node took 5.6 times the visibility queries at a million samples, while on
/// `cornell` a limit of 64 changed no figure and 16 moved seeds by up to 0.03% (at 2, seed 5's
/// error of the probes came back; docs/accuracy.md).
const HOVERED_MEMBERS: usize = 16;
/// The least cosine at either end of a link whose formula is scaled by its probes (see
/// `Linker::conditioned`).
const MIN_COS: f32 = 0.2;

/// What link building reads.
pub(crate) struct Linker<'a> {
    pub tree: &'a Tree,
    pub samples: &'a Samples,
    pub maps: &'a [SurfaceMap],
    pub vis: &'a dyn Visibility,
    pub lift: f32,
    /// The largest radiosity error a cluster link may make (threshold × reference radiosity).
    pub tolerance: f64,
    /// Whether a partly visible link whose whole transfer is negligible may carry its probes'
    /// visible fraction instead of being refined (see [`NEGLIGIBLE`]).
    pub faint_links: bool,
    pub seed: u64,
    /// Set when the host has asked to stop: a pair's search gives up (its links are dropped).
    pub halt: &'a std::sync::atomic::AtomicBool,
}

/// Directions of a pair still wanted: light into b (from a), into a (from b).
const INTO_B: u8 = 1;
const INTO_A: u8 = 2;
const BOTH: u8 = INTO_B | INTO_A;

/// A pair of nodes on the stack, with the directions still to link.
#[derive(Clone, Copy, Debug)]
struct Pair {
    a: Ref,
    b: Ref,
    dirs: u8,
}

/// A pair waiting for its rays: probes `first..first + probes` of the wave.
struct Pending {
    a: Ref,
    b: Ref,
    dirs: u8,
    first: usize,
    probes: usize,
    kind: Kind,
}

enum Kind {
    /// Two samples, with the form factors a → b and b → a (if they face).
    Leaf(Option<f32>, Option<f32>),
    Cluster {
        /// Every member pair is among the probes.
        exhaustive: bool,
        /// Whether each node lies wholly in front of the other.
        one_sided: bool,
        /// Whether everything the links could carry is below [`NEGLIGIBLE`] × the tolerance.
        negligible: bool,
    },
}

/// A member pair (i of a, k of b) a link looks at: its form factors each way (the shooting
/// member's area included), what the links' formula gives the same pair each way, and its
/// ray in the wave's batch (none where the two do not face each other: no light passes
/// whatever stands between them).
#[derive(Clone, Copy)]
struct Probe {
    i: u32,
    k: u32,
    exact: [f64; 2],
    formula: [f64; 2],
    ray: Option<u32>,
}

/// A pair whose every member pair was probed, with what its rays said.
struct Probed<'p> {
    pending: &'p Pending,
    probes: &'p [Probe],
    blocked: &'p [bool],
    /// Whether each node lies wholly in front of the other.
    one_sided: bool,
    /// Whether the formula is far from grazing (see `Linker::conditioned`).
    conditioned: bool,
    same_group: bool,
}

/// Links found: into the first group of the pair, and into the second.
pub(crate) type Found = (Links, Links);

impl Linker<'_> {
    /// Every link between the subtrees of `a` and `b` (two receiver groups, or one group with
    /// itself), in both directions.
    pub fn links_between(&self, a: Ref, b: Ref) -> Result<Found> {
        let mut found: Found = Default::default();
        let mut stack = vec![Pair { a, b, dirs: BOTH }];
        let mut pending: Vec<Pending> = Vec::new();
        let mut segments: Vec<Segment> = Vec::new();
        let mut probes: Vec<Probe> = Vec::new();
        let mut blocked: Vec<bool> = Vec::new();
        while !stack.is_empty() {
            if self.halt.load(std::sync::atomic::Ordering::Relaxed) {
                break;
            }
            pending.clear();
            segments.clear();
            probes.clear();
            let mut taken = 0;
            while taken < WAVE {
                let Some(pair) = stack.pop() else { break };
                taken += 1;
                self.classify(pair, &mut stack, &mut pending, &mut segments, &mut probes);
            }
            if segments.is_empty() {
                continue;
            }
            blocked.clear();
            blocked.resize(segments.len(), false);
            self.vis.occluded(&segments, &mut blocked)?;
            found.0.queries += segments.len() as u64;
            for p in &pending {
                let probes = &probes[p.first..p.first + p.probes];
                self.resolve(p, probes, &blocked, &mut found, &mut stack, a == b);
            }
        }
        for links in [&mut found.0, &mut found.1] {
            links.leaf.shrink_to_fit();
            links.cluster.shrink_to_fit();
        }
        Ok(found)
    }

    /// What a pair's rays say: links, nothing, or a split.
    fn resolve(
        &self,
        p: &Pending,
        probes: &[Probe],
        blocked: &[bool],
        found: &mut Found,
        stack: &mut Vec<Pair>,
        same_group: bool,
    ) {
        let seen = |q: &Probe| q.ray.is_some_and(|ray| !blocked[ray as usize]);
        // Links into b go to the second group, into a to the first (one group: both there).
        let push_leaf = |found: &mut Found, into_b: bool, link: LeafLink| {
            if into_b && !same_group {
                found.1.leaf.push(link)
            } else {
                found.0.leaf.push(link)
            }
        };
        let (exhaustive, one_sided, negligible) = match p.kind {
            Kind::Leaf(ab, ba) => {
                if seen(&probes[0]) {
                    let (i, k) = (p.a.index() as u32, p.b.index() as u32);
                    if let Some(f) = ab {
                        push_leaf(found, true, LeafLink { r: k, s: i, f });
                    }
                    if let Some(f) = ba {
                        push_leaf(found, false, LeafLink { r: i, s: k, f });
                    }
                }
                return;
            }
            Kind::Cluster {
                exhaustive,
                one_sided,
                negligible,
            } => (exhaustive, one_sided, negligible),
        };
        let rays = probes.iter().filter(|q| q.ray.is_some()).count();
        let visible = probes.iter().filter(|q| seen(q)).count();
        let all = rays > 0 && visible == rays;
        let conditioned = self.conditioned(p.a, p.b);
        // The formula, scaled by Σ visible exact / Σ formula over the probes (pairs facing
        // away count 0); near grazing, where the formula is ill-conditioned, by the visible
        // share of the exact form factors.
        let factor = |d: usize| {
            let exact: f64 = probes.iter().filter(|q| seen(q)).map(|q| q.exact[d]).sum();
            let whole: f64 = if conditioned {
                probes.iter().map(|q| q.formula[d]).sum()
            } else {
                probes.iter().map(|q| q.exact[d]).sum()
            };
            if whole > 0.0 {
                (exact / whole) as f32
            } else {
                0.0
            }
        };
        // A few probes cannot vouch for a node something hovers close in front of: its members
        // in the gap and those beside it see differently, and all probes may land on one kind.
        let sure = exhaustive || !(self.hovered(p.a) || self.hovered(p.b));
        if (exhaustive && rays == 0) || (rays > 0 && visible == 0 && sure) {
            // Nothing faces, or every facing pair is blocked.
        } else if all && one_sided && sure {
            self.cluster_links(p, p.dirs, [1.0, 1.0], found, same_group);
        } else if all && conditioned && sure {
            // Wholly visible, but some members face away.
            self.cluster_links(p, p.dirs, [factor(0), factor(1)], found, same_group);
        } else if exhaustive {
            // Every member pair is known: see `member_links`.
            let probed = Probed {
                pending: p,
                probes,
                blocked,
                one_sided,
                conditioned,
                same_group,
            };
            for dir in [INTO_B, INTO_A] {
                if p.dirs & dir != 0 {
                    self.member_links(&probed, dir, found);
                }
            }
        } else if negligible && rays > 0 {
            self.faint_links(p, [factor(0), factor(1)], found, stack, same_group);
        } else {
            self.split(pair_of(p), stack);
        }
    }

    /// A faint, partly visible pair: a receiver takes the share of the shooter its probes see
    /// (`factors`, each way), unless it is a cluster something hovers close in front of (a gap
    /// its members may hide in, which would trap the light) or one holding a sample in or
    /// beside such a gap (the fixture shades it from much of the room, and the share would
    /// light it as its neighbours): that one is refined.
    fn faint_links(
        &self,
        p: &Pending,
        factors: [f32; 2],
        found: &mut Found,
        stack: &mut Vec<Pair>,
        same_group: bool,
    ) {
        let mut to_leaf = 0;
        let mut refine = 0;
        for (dir, receiver) in [(INTO_B, p.b), (INTO_A, p.a)] {
            if p.dirs & dir != 0 {
                let node = (!receiver.is_leaf()).then(|| &self.tree.nodes[receiver.index()]);
                if node.is_none_or(|n| !(n.sheltered || n.holds_hovered)) {
                    to_leaf |= dir;
                } else {
                    refine |= dir;
                }
            }
        }
        self.cluster_links(p, to_leaf, factors, found, same_group);
        if refine != 0 {
            self.split(
                Pair {
                    dirs: refine,
                    ..pair_of(p)
                },
                stack,
            );
        }
    }

    /// Whether something hovers close in front of `node` and its probes cannot vouch for it: a
    /// sample (see `LeafData::hovered`), or a sheltered node on one side of at most
    /// [`HOVERED_MEMBERS`] members (nodes over several sides, a curved piece's too, are left
    /// out: their probes span the sides).
    fn hovered(&self, node: Ref) -> bool {
        if node.is_leaf() {
            self.tree.leaf[node.index()].hovered
        } else {
            let n = &self.tree.nodes[node.index()];
            n.sheltered && n.side != MULTI && n.count as usize <= HOVERED_MEMBERS
        }
    }

    /// Whether a shooter node stands for its members evenly enough for a receiver to take the
    /// share of it that it sees: coherent (no occluder among its members, whose unshot light
    /// may differ across it) and holding no sample something hovers close in front of (those
    /// in a fixture's gap get less light than their neighbours). A single sample: its leaf
    /// links are as many.
    fn even(&self, node: Ref) -> bool {
        !node.is_leaf() && {
            let n = &self.tree.nodes[node.index()];
            n.coherent && !n.holds_hovered
        }
    }

    /// The links in direction `dir` of a pair whose every member pair was probed and some
    /// seen. Into each receiving member: from the whole shooter, where it stands for its members
    /// evenly (`even`) or the member sees every one that faces it, one link with the share it
    /// sees (its visible exact form factors over the formula's, or over all its exact ones
    /// where the formula is not well conditioned); else, and where the formula cannot be
    /// scaled (members facing away and near grazing), from the parts of the shooter it wholly
    /// sees (`cover`).
    fn member_links(&self, probed: &Probed, dir: u8, found: &mut Found) {
        let p = probed.pending;
        let into_b = dir == INTO_B;
        let (shooter, d) = if into_b { (p.a, 0) } else { (p.b, 1) };
        let seen = |q: &Probe| q.ray.is_some_and(|ray| !probed.blocked[ray as usize]);
        let receiver = |q: &Probe| if into_b { q.k } else { q.i };
        let into = if into_b && !probed.same_group {
            &mut found.1
        } else {
            &mut found.0
        };
        let even = self.even(shooter);
        let mut members: Vec<u32> = probed.probes.iter().map(receiver).collect();
        members.sort_unstable();
        members.dedup();
        for m in members {
            let run = || probed.probes.iter().filter(move |q| receiver(q) == m);
            // Whether every member of the shooter faces this one (each probe has a ray).
            let facing = run().all(|q| q.ray.is_some());
            let (mut visible, mut whole, mut all) = (0.0f64, 0.0f64, true);
            for q in run() {
                if seen(q) {
                    visible += q.exact[d];
                } else if q.ray.is_some() {
                    all = false;
                }
                whole += if probed.conditioned && !facing {
                    q.formula[d]
                } else {
                    q.exact[d]
                };
            }
            if visible <= 0.0 {
                continue;
            }
            // Where every member of the shooter faces this one, the formula holds as for a
            // one-sided pair, and the share is of the exact form factors.
            let usable = !shooter.is_leaf() && (probed.one_sided || probed.conditioned || facing);
            if usable && (even || all) && whole > 0.0 {
                into.cluster.push(ClusterLink {
                    r: Ref::sample(m),
                    s: shooter,
                    factor: (visible / whole) as f32,
                });
            } else {
                let clear: Vec<u32> = run()
                    .filter(|q| seen(q))
                    .map(|q| if into_b { q.i } else { q.k })
                    .collect();
                self.cover(shooter, &clear, m, into);
            }
        }
    }

    /// Links into sample `m` from the largest parts of `node` whose every member is in
    /// `clear` (seen from m and facing it): one cluster link each, carrying the formula as it
    /// is, as for a pair wholly in front of each other and seen; a leaf link from a member
    /// alone.
    fn cover(&self, node: Ref, clear: &[u32], m: u32, into: &mut Links) {
        if node.is_leaf() {
            let s = node.index() as u32;
            if clear.contains(&s) {
                let from = Shooter::of(self.samples, self.maps, s as usize);
                if let Some(f) = from.factor_to(self.samples, m as usize) {
                    into.leaf.push(LeafLink { r: m, s, f });
                }
            }
            return;
        }
        let n = &self.tree.nodes[node.index()];
        let members = &self.tree.order[n.first as usize..(n.first + n.count) as usize];
        let inside = members.iter().filter(|k| clear.contains(k)).count();
        if inside == members.len() {
            into.cluster.push(ClusterLink {
                r: Ref::sample(m),
                s: node,
                factor: 1.0,
            });
        } else if inside > 0 {
            for c in n.children {
                self.cover(c, clear, m, into);
            }
        }
    }

    /// The links of `dirs` (into b, into a) with their factors.
    fn cluster_links(
        &self,
        p: &Pending,
        dirs: u8,
        factor: [f32; 2],
        found: &mut Found,
        same_group: bool,
    ) {
        if dirs & INTO_B != 0 && factor[0] > 0.0 {
            let link = ClusterLink {
                r: p.b,
                s: p.a,
                factor: factor[0],
            };
            if same_group {
                found.0.cluster.push(link);
            } else {
                found.1.cluster.push(link);
            }
        }
        if dirs & INTO_A != 0 && factor[1] > 0.0 {
            found.0.cluster.push(ClusterLink {
                r: p.a,
                s: p.b,
                factor: factor[1],
            });
        }
    }

    /// Decides what to do with the pair {a, b}: see the module doc.
    fn classify(
        &self,
        pair: Pair,
        stack: &mut Vec<Pair>,
        pending: &mut Vec<Pending>,
        segments: &mut Vec<Segment>,
        probes: &mut Vec<Probe>,
    ) {
        let tree = self.tree;
        let Pair { a, b, dirs } = pair;
        let with = |a: Ref, b: Ref| Pair { a, b, dirs };
        if a == b {
            if a.is_leaf() || tree.nodes[a.index()].side != MULTI {
                // A sample, or samples of one plane: nothing passes between them.
                return;
            }
            let [x, y] = tree.nodes[a.index()].children;
            stack.extend([with(y, y), with(x, y), with(x, x)]);
            return;
        }
        let (av, bv) = (tree.view(self.samples, a), tree.view(self.samples, b));
        if !a.is_leaf() && holds(&av, &bv) {
            push_children(tree, a, |c| stack.push(with(c, b)));
            return;
        }
        if !b.is_leaf() && holds(&bv, &av) {
            push_children(tree, b, |c| stack.push(with(a, c)));
            return;
        }
        if a.is_leaf() && b.is_leaf() {
            self.leaf_pair(pair, pending, segments, probes);
            return;
        }
        let d = bv.centroid - av.centroid;
        let dist = d.length();
        let reach = av.radius + bv.radius;
        let (Some(cos_a), Some(cos_b)) = (
            cosines(&av, &bv, d, dist, reach, self.lift),
            cosines(&bv, &av, -d, dist, reach, self.lift),
        ) else {
            // No member of one faces any member of the other.
            return;
        };
        // A pair with an incoherent node (something stands among its members) is probed pair by
        // pair when it has few member pairs: those rays are the ones its leaf links would cast,
        // and where every pair sees, nothing hides behind what stands among them. A larger one
        // only where it is faint (below): light it puts behind what stands among its members
        // is then bounded by what a faint link may blur.
        let coherent = av.coherent && bv.coherent;
        let few = (av.count as usize) * (bv.count as usize) <= EXHAUSTIVE;
        let admissible =
            dist > 2.0 * reach && dist - reach >= NEAR * av.max_area.max(bv.max_area).sqrt();
        if admissible {
            // Where some members may face away, only the bound from above holds (their pairs
            // exchange nothing; the link would give them light): the whole transfer must then
            // be below the tolerance.
            let one_sided = cos_a.2 && cos_b.2;
            let (near, far) = (f64::from(dist - reach), f64::from(dist + reach));
            let upper = f64::from(cos_a.1 * cos_b.1) / (near * near);
            let lower = if one_sided {
                f64::from(cos_a.0 * cos_b.0) / (far * far)
            } else {
                0.0
            };
            let into_b = if dirs & INTO_B != 0 {
                f64::from(bv.rho) * av.power
            } else {
                0.0
            };
            let into_a = if dirs & INTO_A != 0 {
                f64::from(av.rho) * bv.power
            } else {
                0.0
            };
            let weight = into_b.max(into_a) / std::f64::consts::PI;
            // Everything the pair could carry, seen wholly visible, is negligible: whatever
            // stands among an incoherent node's members can then misplace no more than that.
            let faint = self.faint_links && weight * upper < NEGLIGIBLE * self.tolerance;
            if weight * (upper - lower) < self.tolerance && (coherent || few || faint) {
                let first = probes.len();
                let exhaustive = self.probe(&av, &bv, d, segments, probes, (a, b));
                pending.push(Pending {
                    a,
                    b,
                    dirs,
                    first,
                    probes: probes.len() - first,
                    kind: Kind::Cluster {
                        exhaustive,
                        one_sided,
                        negligible: faint,
                    },
                });
                return;
            }
        }
        self.split(pair, stack);
    }

    /// Two samples: the form factor each way the pair carries light, and its probe ray.
    fn leaf_pair(
        &self,
        pair: Pair,
        pending: &mut Vec<Pending>,
        segments: &mut Vec<Segment>,
        probes: &mut Vec<Probe>,
    ) {
        let Pair { a, b, dirs } = pair;
        let (i, k) = (a.index(), b.index());
        let ab = (dirs & INTO_B != 0)
            .then(|| Shooter::of(self.samples, self.maps, i).factor_to(self.samples, k))
            .flatten();
        let ba = (dirs & INTO_A != 0)
            .then(|| Shooter::of(self.samples, self.maps, k).factor_to(self.samples, i))
            .flatten();
        if ab.is_some() || ba.is_some() {
            pending.push(Pending {
                a,
                b,
                dirs,
                first: probes.len(),
                probes: 1,
                kind: Kind::Leaf(ab, ba),
            });
            probes.push(Probe {
                i: i as u32,
                k: k as u32,
                exact: [0.0; 2],
                formula: [0.0; 2],
                ray: Some(segments.len() as u32),
            });
            segments.push(segment(self.samples, self.lift, i, k));
        }
    }

    /// Whether the links' formula is far from grazing at both ends (the centroids' direction
    /// makes a cosine of at least [`MIN_COS`] with either node's axis), so that scaling it by
    /// its probes is well conditioned.
    fn conditioned(&self, a: Ref, b: Ref) -> bool {
        let (av, bv) = (
            self.tree.view(self.samples, a),
            self.tree.view(self.samples, b),
        );
        let omega = (bv.centroid - av.centroid).normalize_or_zero();
        av.axis.dot(omega) >= MIN_COS && -bv.axis.dot(omega) >= MIN_COS
    }

    /// Refines a pair by splitting the larger node (a sample cannot be split); a pair wanted
    /// in one direction only splits its receiver, so that refinement ends at single receivers.
    fn split(&self, pair: Pair, stack: &mut Vec<Pair>) {
        let tree = self.tree;
        let Pair { a, b, dirs } = pair;
        let split_a = match dirs {
            INTO_A if !a.is_leaf() => true,
            INTO_B if !b.is_leaf() => false,
            _ if a.is_leaf() => false,
            _ if b.is_leaf() => true,
            _ => tree.nodes[a.index()].radius >= tree.nodes[b.index()].radius,
        };
        if split_a {
            push_children(tree, a, |c| stack.push(Pair { a: c, b, dirs }));
        } else {
            push_children(tree, b, |c| stack.push(Pair { a, b: c, dirs }));
        }
    }

    /// Queues the probes (and the rays of those that face) that decide a pair's visibility;
    /// returns whether they cover every member pair. `d` runs from a's centroid to b's.
    fn probe(
        &self,
        av: &View,
        bv: &View,
        d: Vec3,
        segments: &mut Vec<Segment>,
        probes: &mut Vec<Probe>,
        (a, b): (Ref, Ref),
    ) -> bool {
        let order = &self.tree.order;
        let member = |v: &View, x: usize| order[v.first as usize + x] as usize;
        let (na, nb) = (av.count as usize, bv.count as usize);
        let samples = self.samples;
        let omega = d.normalize().as_dvec3();
        let length2 = f64::from(d.length_squared());
        let pi = std::f64::consts::PI;
        let mut push = |i: usize, k: usize| {
            let (ni, nk) = (samples.normal[i].as_dvec3(), samples.normal[k].as_dvec3());
            let v = (samples.centroid[k] - samples.centroid[i]).as_dvec3();
            let l2 = v.length_squared();
            let kernel = if l2 > 0.0 {
                ni.dot(v).max(0.0) * (-nk.dot(v)).max(0.0) / (pi * l2 * l2)
            } else {
                0.0
            };
            let formula = ni.dot(omega).max(0.0) * (-nk.dot(omega)).max(0.0) / (pi * length2);
            let ray = (kernel > 0.0).then(|| {
                segments.push(segment(samples, self.lift, i, k));
                segments.len() as u32 - 1
            });
            let (si, sk) = (samples.area[i], samples.area[k]);
            probes.push(Probe {
                i: i as u32,
                k: k as u32,
                exact: [kernel * si, kernel * sk],
                formula: [formula * si, formula * sk],
                ray,
            });
        };
        if na * nb <= EXHAUSTIVE {
            for x in 0..na {
                for y in 0..nb {
                    push(member(av, x), member(bv, y));
                }
            }
            return true;
        }
        // Stratified: the members' ranges (spatially coherent in tree order) cut in PROBES
        // strata each, b's strata visited in a shuffled order.
        let pair = mix(u64::from(a.raw()) << 32 | u64::from(b.raw()));
        for x in 0..PROBES {
            let h = mix(self.seed ^ pair ^ x as u64);
            let to_unit = |bits: u64| bits as f64 / (1u64 << 24) as f64;
            let (u, w) = (to_unit(h >> 40), to_unit(h & 0xff_ffff));
            let y = (x * 5 + 3) % PROBES;
            let i = (((x as f64 + u) / PROBES as f64) * na as f64) as usize;
            let k = (((y as f64 + w) / PROBES as f64) * nb as f64) as usize;
            push(member(av, i.min(na - 1)), member(bv, k.min(nb - 1)));
        }
        false
    }
}

/// Bounds on the cosine between the normal of a member of `v` and the direction to a member
/// of `other`, whose centroid lies at `to` (length `dist`; `reach` the sum of the radii): the
/// least (≥ 0: pairs facing away exchange nothing), the greatest, and whether `v` is one-sided
/// toward `other` (no sample point of `other` lies behind a member of `v`). `None` when no
/// member of `other` can lie in front of any member of `v`. A planar node (one side, or a
/// sample) bounds the cosine by the other node's height above its plane; a node over several
/// sides by its normal cone and the pair's angular size.
fn cosines(
    v: &View,
    other: &View,
    to: Vec3,
    dist: f32,
    reach: f32,
    lift: f32,
) -> Option<(f32, f32, bool)> {
    if v.side != MULTI {
        // The lowest and highest sample points of `other` above the plane, from its bounds:
        // nothing passes to a node that lies wholly behind the plane or in it.
        let centre = v.axis.dot(0.5 * (other.lo + other.hi) - v.centroid);
        let extent = v.axis.abs().dot(0.5 * (other.hi - other.lo));
        if centre + extent <= lift {
            return None;
        }
        let one_sided = centre - extent >= -lift;
        let h = v.axis.dot(to);
        if dist <= reach {
            return Some((0.0, 1.0, one_sided));
        }
        let least = ((h - other.radius) / (dist + reach)).max(0.0);
        let most = ((h + other.radius) / (dist - reach)).min(1.0);
        return Some((least, most, one_sided));
    }
    if dist <= reach || v.spread >= std::f32::consts::PI {
        return Some((0.0, 1.0, false));
    }
    let beta = (reach / dist).asin();
    let a = angle(v.axis, to / dist);
    if a - v.spread - beta >= std::f32::consts::FRAC_PI_2 {
        return None;
    }
    let widest = a + v.spread + beta;
    let least = widest.min(std::f32::consts::FRAC_PI_2).cos();
    let most = (a - v.spread - beta).max(0.0).cos();
    Some((least, most, widest < std::f32::consts::FRAC_PI_2))
}

/// Whether node `a` holds `b` (their member ranges nest).
fn holds(a: &View, b: &View) -> bool {
    a.first <= b.first && b.first + b.count <= a.first + a.count
}

fn push_children(tree: &Tree, node: Ref, mut push: impl FnMut(Ref)) {
    let [a, b] = tree.nodes[node.index()].children;
    push(b);
    push(a);
}

fn pair_of(p: &Pending) -> Pair {
    Pair {
        a: p.a,
        b: p.b,
        dirs: p.dirs,
    }
}

/// SplitMix64's finaliser: a well-mixed hash of a 64-bit value.
fn mix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}
