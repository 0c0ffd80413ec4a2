//! The cluster tree: a binary tree over the samples (a BVH) whose nodes stand for groups of
//! samples in the links. The tree is split first by surface side, so every side's samples form
//! one subtree (one-sided, planar clusters), and a curved piece's samples one (split by place,
//! each side's group below); the sides and pieces are then grouped by position and normal
//! above those subtrees. Each node keeps what the links' error bound needs: centroid, bounding
//! radius, total area, area-weighted normal and normal cone, largest reflectance, the shooting
//! power its members stand for, and its members as a range of the tree order.
//!
//! Nodes are stored in pre-order, so a node's subtree is a contiguous range of nodes and its
//! members a contiguous range of `order`. Built deterministically (ties broken by index).

use glam::{DVec3, Vec3};

use super::coherence::{hovered_sample, sheltered, splitter, Context, Footprint, Owner};
use crate::sampling::{surface_of, Samples, Side};

/// A reference to a tree node or to a single sample (a leaf).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) struct Ref(u32);

const LEAF_BIT: u32 = 1 << 31;

impl Ref {
    /// Internal node `i`.
    pub fn node(i: u32) -> Ref {
        Ref(i)
    }

    /// Sample `k` as a leaf.
    pub fn sample(k: u32) -> Ref {
        Ref(k | LEAF_BIT)
    }

    /// Whether this is a single sample.
    pub fn is_leaf(self) -> bool {
        self.0 & LEAF_BIT != 0
    }

    /// The node or sample index.
    pub fn index(self) -> usize {
        (self.0 & !LEAF_BIT) as usize
    }

    /// The raw value (for hashing).
    pub fn raw(self) -> u32 {
        self.0
    }

    /// The reference whose [`raw`](Ref::raw) value this is.
    pub fn from_raw(raw: u32) -> Ref {
        Ref(raw)
    }
}

/// Side id of nodes whose samples lie on several sides.
pub(crate) const MULTI: Side = Side::MAX;

/// An internal node.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Node {
    pub children: [Ref; 2],
    /// Members: `order[first..first + count]`.
    pub first: u32,
    pub count: u32,
    /// This node's subtree is `nodes[self..end]`.
    pub end: u32,
    /// Area-weighted centroid of the members' regions.
    pub centroid: Vec3,
    /// Radius of a sphere about `centroid` holding every member's centroid and sample point.
    pub radius: f32,
    /// Total area.
    pub area: f64,
    /// Σ S n over the members.
    pub normal_sum: DVec3,
    /// Unit axis of the normal cone (the direction of Σ S n where it is not zero).
    pub axis: Vec3,
    /// Half-angle of the normal cone, radians (≥ π: no cone).
    pub spread: f32,
    /// Largest reflectance channel of any member.
    pub rho: f32,
    /// Σ p S over the members, p the radiosity each shooter is weighed by in the error bound.
    pub power: f64,
    /// Largest member area.
    pub max_area: f32,
    /// Bounds of the members' sample points and centroids.
    pub lo: Vec3,
    pub hi: Vec3,
    /// The side all members lie on, or [`MULTI`].
    pub side: Side,
    /// Whether the node may stand for its members in a link (see `coherence`).
    pub coherent: bool,
    /// Whether something hovers close in front of it (see `coherence::sheltered`).
    pub sheltered: bool,
    /// Whether it holds a sample something hovers close in front of (see [`LeafData::hovered`]).
    pub holds_hovered: bool,
}

/// Per-sample data the tree and the links use.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LeafData {
    /// Radius about the sample's centroid holding its sample point.
    pub radius: f32,
    /// Largest reflectance channel.
    pub rho: f32,
    /// p S (see [`Node::power`]).
    pub power: f64,
    /// Whether something hovers close in front of the sample, within its radius D (see
    /// `coherence::hovered_sample`; looked for only on sides whose top node is sheltered).
    pub hovered: bool,
}

/// The tree.
#[derive(Clone, Debug, Default)]
pub(crate) struct Tree {
    /// Internal nodes in pre-order; the root is node 0 when there is more than one sample.
    pub nodes: Vec<Node>,
    /// Samples in tree order.
    pub order: Vec<u32>,
    /// Per sample: its place in `order`.
    pub place: Vec<u32>,
    /// Per sample: radius, reflectance, power.
    pub leaf: Vec<LeafData>,
}

/// What the links need to know of a node or a leaf.
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    pub centroid: Vec3,
    pub radius: f32,
    pub axis: Vec3,
    pub spread: f32,
    pub rho: f32,
    pub power: f64,
    pub max_area: f32,
    pub coherent: bool,
    pub first: u32,
    pub count: u32,
    pub side: Side,
    /// Bounds of the members' sample points.
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Tree {
    /// Builds the tree over all samples. `rho` is each sample's largest reflectance channel and
    /// `weight` the radiosity its shooting is weighed by; `cx` says which groups are coherent.
    pub fn build(samples: &Samples, rho: &[f32], weight: &[f64], cx: &Context) -> Tree {
        let n = samples.len();
        let leaf: Vec<LeafData> = (0..n)
            .map(|k| LeafData {
                radius: region_radius(samples, k),
                rho: rho[k],
                power: weight[k] * samples.area[k],
                hovered: false,
            })
            .collect();
        let mut tree = Tree {
            nodes: Vec::with_capacity(n.saturating_sub(1)),
            order: Vec::with_capacity(n),
            place: vec![0; n],
            leaf,
        };
        if n == 0 {
            return tree;
        }
        // The sides, each with its samples in ascending order; a curved piece's sides as one,
        // so that its samples are grouped by place, not facet by facet (a column's facets are
        // strips as tall as the column: grouped whole, every node above them was as tall, and
        // overlapped the floor's and the arches' nodes down to a few samples).
        let group = |k: u32| {
            let side = samples.side[k as usize];
            cx.pieces.of(side).map_or((false, side), |p| (true, p))
        };
        let mut by_group: Vec<((bool, u32), Vec<u32>)> = Vec::new();
        {
            let mut ids: Vec<u32> = (0..n as u32).collect();
            ids.sort_by_key(|&k| (group(k), k));
            for k in ids {
                let g = group(k);
                match by_group.last_mut() {
                    Some((s, list)) if *s == g => list.push(k),
                    _ => by_group.push((g, vec![k])),
                }
            }
        }
        let mut items: Vec<Item> = by_group
            .into_iter()
            .map(|((piece, _), members)| Item::new(samples, piece, members))
            .collect();
        tree.top(samples, cx, &mut items);
        for (place, &k) in tree.order.iter().enumerate() {
            tree.place[k as usize] = place as u32;
        }
        if !tree.nodes.is_empty() {
            tree.mark_sheltered(cx, 0, true, true, true);
            tree.mark_holds_hovered();
        }
        tree
    }

    /// Marks node `i`'s subtree: a node is sheltered when its parent is and something hovers
    /// within a quarter of its radius in front of it. On a side or piece whose top node is
    /// sheltered (and under nodes over several of them) each sample is asked too, within its
    /// own radius (`coherence::hovered_sample`). `top`: whether the parent spans several sides
    /// or pieces; `hover`: whether the parent's samples are asked.
    fn mark_sheltered(&mut self, cx: &Context, i: usize, parent: bool, top: bool, hover: bool) {
        let node = &self.nodes[i];
        let members = &self.order[node.first as usize..(node.first + node.count) as usize];
        let owner = if node.side != MULTI {
            Owner::Side(node.side)
        } else {
            let piece = cx.pieces.of(cx.samples.side[members[0] as usize]);
            match piece {
                Some(p)
                    if members
                        .iter()
                        .all(|&k| cx.pieces.of(cx.samples.side[k as usize]) == Some(p)) =>
                {
                    Owner::Piece(p)
                }
                _ => Owner::Several,
            }
        };
        let here = parent
            && (owner == Owner::Several || {
                // Along the first edge of the first member's surface (its map's first axis).
                let surface =
                    &cx.scene.surfaces[surface_of(cx.samples.side[members[0] as usize]) as usize];
                let [a, b, _] = cx.scene.triangles[surface.triangles.start as usize].vertices;
                let at = Footprint::of(cx.samples, node.axis, b - a, members);
                sheltered(cx, owner, &at, 0.25 * node.radius)
            });
        self.nodes[i].sheltered = here;
        let several = owner == Owner::Several;
        let hover = several || if top { here } else { hover };
        for c in self.nodes[i].children {
            if !c.is_leaf() {
                self.mark_sheltered(cx, c.index(), here, several, hover);
            } else if hover {
                let k = c.index();
                self.leaf[k].hovered = hovered_sample(cx, k, cx.samples.radius[k]);
            }
        }
    }

    /// Marks the nodes that hold a hovered sample, children before parents (the nodes are in
    /// pre-order).
    fn mark_holds_hovered(&mut self) {
        for i in (0..self.nodes.len()).rev() {
            let holds = self.nodes[i].children.iter().any(|&c| {
                if c.is_leaf() {
                    self.leaf[c.index()].hovered
                } else {
                    self.nodes[c.index()].holds_hovered
                }
            });
            self.nodes[i].holds_hovered = holds;
        }
    }

    /// The root (a leaf when there is one sample), if there are samples.
    pub fn root(&self) -> Option<Ref> {
        match (self.nodes.is_empty(), self.order.first()) {
            (false, _) => Some(Ref::node(0)),
            (true, Some(&k)) => Some(Ref::sample(k)),
            (true, None) => None,
        }
    }

    /// What the links need of `r`.
    pub fn view(&self, samples: &Samples, r: Ref) -> View {
        if r.is_leaf() {
            let k = r.index();
            let l = &self.leaf[k];
            View {
                centroid: samples.centroid[k],
                radius: l.radius,
                axis: samples.normal[k],
                spread: 0.0,
                rho: l.rho,
                power: l.power,
                max_area: samples.area[k] as f32,
                coherent: true,
                first: self.place[k],
                count: 1,
                side: samples.side[k],
                lo: samples.position[k].min(samples.centroid[k]),
                hi: samples.position[k].max(samples.centroid[k]),
            }
        } else {
            let n = &self.nodes[r.index()];
            View {
                centroid: n.centroid,
                radius: n.radius,
                axis: n.axis,
                spread: n.spread,
                rho: n.rho,
                power: n.power,
                max_area: n.max_area,
                coherent: n.coherent,
                first: n.first,
                count: n.count,
                side: n.side,
                lo: n.lo,
                hi: n.hi,
            }
        }
    }

    /// The subtrees of at most `size` samples (or single nodes above them), left to right:
    /// the receiver groups the links and sweeps are cut into.
    pub fn cut(&self, size: usize) -> Vec<Ref> {
        let mut out = Vec::new();
        let Some(root) = self.root() else {
            return out;
        };
        let mut stack = vec![root];
        while let Some(r) = stack.pop() {
            if r.is_leaf() || self.nodes[r.index()].count as usize <= size {
                out.push(r);
            } else {
                let [a, b] = self.nodes[r.index()].children;
                stack.push(b);
                stack.push(a);
            }
        }
        out
    }

    /// Groups of sides and pieces, split by position and normal until one is left, then its
    /// subtree. Returns the new subtree's root.
    fn top(&mut self, samples: &Samples, cx: &Context, items: &mut [Item]) -> (Ref, u32) {
        if items.len() == 1 {
            let members = std::mem::take(&mut items[0].members);
            let start = self.order.len();
            self.order.extend_from_slice(&members);
            let end = self.order.len();
            return self.subtree(samples, cx, (start, end), items[0].piece, false);
        }
        let index = self.placeholder();
        // Positions and normals scaled by the group's size, so that sides facing different
        // ways are separated first.
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let (mut nlo, mut nhi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for item in items.iter() {
            lo = lo.min(item.lo);
            hi = hi.max(item.hi);
            nlo = nlo.min(item.normal);
            nhi = nhi.max(item.normal);
        }
        let size = (hi - lo).max_element().max(1e-30);
        let spatial = hi - lo;
        let angular = (nhi - nlo) * size;
        let (axis, by_normal) = if angular.max_element() > spatial.max_element() {
            (angular.max_position(), true)
        } else {
            (spatial.max_position(), false)
        };
        let key = |item: &Item| {
            if by_normal {
                item.normal[axis]
            } else {
                item.centre[axis]
            }
        };
        items.sort_by(|a, b| key(a).total_cmp(&key(b)).then(a.side.cmp(&b.side)));
        // Split where half the samples lie on each side (at least one item each).
        let total: usize = items.iter().map(|i| i.members.len()).sum();
        let mut count = 0;
        let mut m = 1;
        for (i, item) in items.iter().enumerate() {
            count += item.members.len();
            if 2 * count >= total {
                m = (i + 1).clamp(1, items.len() - 1);
                break;
            }
        }
        let (left, right) = items.split_at_mut(m);
        let a = self.top(samples, cx, left);
        let b = self.top(samples, cx, right);
        self.fill(samples, index, [a, b]);
        let coherent = [a.0, b.0]
            .iter()
            .all(|&c| c.is_leaf() || self.nodes[c.index()].coherent)
            && {
                let node = &self.nodes[index as usize];
                let members = &self.order[node.first as usize..(node.first + node.count) as usize];
                splitter(cx, None, members, node.lo, node.hi).is_none()
            };
        self.nodes[index as usize].coherent = coherent;
        (Ref::node(index), a.1)
    }

    /// The subtree over `order[start..end]`, the samples of one side or of one curved piece
    /// (`piece`: on several of its sides; a group of them on one side goes on as that side's): a
    /// group with something standing among its members is split along that occluder's plane; a
    /// coherent group (whose subsets are all coherent: `coherent`) at the median of its longer
    /// extent.
    fn subtree(
        &mut self,
        samples: &Samples,
        cx: &Context,
        (start, end): (usize, usize),
        piece: bool,
        coherent: bool,
    ) -> (Ref, u32) {
        if end - start == 1 {
            return (Ref::sample(self.order[start]), start as u32);
        }
        let index = self.placeholder();
        let members = &mut self.order[start..end];
        let side = samples.side[members[0] as usize];
        let piece = piece && members.iter().any(|&k| samples.side[k as usize] != side);
        let (lo, hi) = members.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &k| {
                let p = samples.position[k as usize];
                (lo.min(p), hi.max(p))
            },
        );
        let occluder = if coherent {
            None
        } else {
            splitter(cx, (!piece).then_some(side), members, lo, hi)
        };
        let mid = match occluder {
            Some(plane) => {
                // Behind the plane first, each part in sample order.
                members.sort_by_key(|&k| (plane.in_front(samples.position[k as usize]), k));
                members
                    .iter()
                    .take_while(|&&k| !plane.in_front(samples.position[k as usize]))
                    .count()
            }
            None => {
                let axis = (hi - lo).max_position();
                let mid = members.len() / 2;
                members.select_nth_unstable_by(mid, |&a, &b| {
                    samples.position[a as usize][axis]
                        .total_cmp(&samples.position[b as usize][axis])
                        .then(a.cmp(&b))
                });
                mid
            }
        };
        let coherent = occluder.is_none();
        let a = self.subtree(samples, cx, (start, start + mid), piece, coherent);
        let b = self.subtree(samples, cx, (start + mid, end), piece, coherent);
        self.fill(samples, index, [a, b]);
        self.nodes[index as usize].coherent = coherent;
        (Ref::node(index), start as u32)
    }

    fn placeholder(&mut self) -> u32 {
        let index = self.nodes.len() as u32;
        self.nodes.push(Node {
            children: [Ref(0); 2],
            first: 0,
            count: 0,
            end: 0,
            centroid: Vec3::ZERO,
            radius: 0.0,
            area: 0.0,
            normal_sum: DVec3::ZERO,
            axis: Vec3::Z,
            spread: 0.0,
            rho: 0.0,
            power: 0.0,
            max_area: 0.0,
            lo: Vec3::ZERO,
            hi: Vec3::ZERO,
            side: MULTI,
            coherent: false,
            sheltered: true,
            holds_hovered: false,
        });
        index
    }

    /// Fills node `index` from its two children (each with the place of its first member).
    fn fill(&mut self, samples: &Samples, index: u32, children: [(Ref, u32); 2]) {
        let parts = children.map(|(c, first)| self.part(samples, c, first));
        let children = children.map(|(c, _)| c);
        let area = parts[0].area + parts[1].area;
        let centroid = if area > 0.0 {
            ((parts[0].centroid.as_dvec3() * parts[0].area
                + parts[1].centroid.as_dvec3() * parts[1].area)
                / area)
                .as_vec3()
        } else {
            0.5 * (parts[0].centroid + parts[1].centroid)
        };
        let normal_sum = parts[0].normal_sum + parts[1].normal_sum;
        let axis = normal_sum
            .as_vec3()
            .try_normalize()
            .unwrap_or(parts[0].view.axis);
        let spread = parts
            .iter()
            .map(|p| angle(axis, p.view.axis) + p.view.spread)
            .fold(0.0f32, f32::max)
            .min(std::f32::consts::PI);
        let radius = parts
            .iter()
            .map(|p| centroid.distance(p.centroid) + p.view.radius)
            .fold(0.0f32, f32::max);
        let (a, b) = (&parts[0].view, &parts[1].view);
        self.nodes[index as usize] = Node {
            children,
            first: a.first.min(b.first),
            count: a.count + b.count,
            end: self.nodes.len() as u32,
            centroid,
            radius,
            area,
            normal_sum,
            axis,
            spread,
            rho: a.rho.max(b.rho),
            power: a.power + b.power,
            max_area: a.max_area.max(b.max_area),
            lo: parts[0].lo.min(parts[1].lo),
            hi: parts[0].hi.max(parts[1].hi),
            side: if a.side == b.side { a.side } else { MULTI },
            coherent: false,
            sheltered: true,
            holds_hovered: false,
        };
    }

    /// A child as its parent sees it; `first` is the place of its first member.
    fn part(&self, samples: &Samples, r: Ref, first: u32) -> Part {
        let mut view = self.view(samples, r);
        view.first = first;
        if r.is_leaf() {
            let k = r.index();
            Part {
                lo: view.lo,
                hi: view.hi,
                view,
                centroid: samples.centroid[k],
                area: samples.area[k],
                normal_sum: samples.normal[k].as_dvec3() * samples.area[k],
            }
        } else {
            let n = &self.nodes[r.index()];
            Part {
                view,
                centroid: n.centroid,
                area: n.area,
                normal_sum: n.normal_sum,
                lo: n.lo,
                hi: n.hi,
            }
        }
    }

    /// Checks the tree's invariants: members partition the samples; every node's totals are
    /// its children's; ranges nest; radii hold the children; cones hold the children's.
    /// Returns the first violation found.
    pub fn validate(&self, samples: &Samples) -> Result<(), String> {
        let n = samples.len();
        let mut seen = vec![false; n];
        for &k in &self.order {
            if std::mem::replace(&mut seen[k as usize], true) {
                return Err(format!("sample {k} appears twice in the order"));
            }
        }
        if self.order.len() != n || seen.iter().any(|s| !s) {
            return Err("the order does not hold every sample once".into());
        }
        if n > 1 && self.nodes.len() != n - 1 {
            return Err(format!("{} nodes for {n} samples", self.nodes.len()));
        }
        for (i, node) in self.nodes.iter().enumerate() {
            let parts = node.children.map(|c| self.view(samples, c));
            let (area, power, count): (f64, f64, u32) = node
                .children
                .iter()
                .zip(&parts)
                .map(|(&c, v)| {
                    let a = if c.is_leaf() {
                        samples.area[c.index()]
                    } else {
                        self.nodes[c.index()].area
                    };
                    (a, v.power, v.count)
                })
                .fold((0.0, 0.0, 0), |s, x| (s.0 + x.0, s.1 + x.1, s.2 + x.2));
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1e-30);
            if !close(area, node.area) || !close(power, node.power) || count != node.count {
                return Err(format!(
                    "node {i}: totals (area {}, power {}, count {}) are not its children's ({area}, {power}, {count})",
                    node.area, node.power, node.count
                ));
            }
            if parts[0].first != node.first || parts[1].first != parts[0].first + parts[0].count {
                return Err(format!(
                    "node {i}: children's member ranges do not tile its own"
                ));
            }
            for (c, v) in node.children.iter().zip(&parts) {
                if !c.is_leaf() {
                    let ci = c.index();
                    if ci <= i || ci >= node.end as usize || self.nodes[ci].end > node.end {
                        return Err(format!("node {i}: child {ci} is not inside its subtree"));
                    }
                }
                let reach = node.centroid.distance(v.centroid) + v.radius;
                if reach > node.radius * (1.0 + 1e-5) + 1e-6 {
                    return Err(format!(
                        "node {i}: radius {} does not hold a child ({reach})",
                        node.radius
                    ));
                }
                if node.spread < std::f32::consts::PI
                    && angle(node.axis, v.axis) + v.spread > node.spread + 1e-4
                {
                    return Err(format!("node {i}: normal cone does not hold a child's"));
                }
            }
            for &k in &self.order[node.first as usize..(node.first + node.count) as usize] {
                let k = k as usize;
                let p = samples.position[k];
                if p.cmplt(node.lo - 1e-5).any() || p.cmpgt(node.hi + 1e-5).any() {
                    return Err(format!("node {i}: member {k} lies outside its bounds"));
                }
                if node.side != MULTI && samples.side[k] != node.side {
                    return Err(format!("node {i}: member {k} is not on the node's side"));
                }
            }
        }
        Ok(())
    }
}

/// A side, or a curved piece, as the top of the tree sees it.
struct Item {
    /// The side of the first member.
    side: Side,
    /// Whether the members are a curved piece's.
    piece: bool,
    members: Vec<u32>,
    centre: Vec3,
    normal: Vec3,
    lo: Vec3,
    hi: Vec3,
}

impl Item {
    fn new(samples: &Samples, piece: bool, members: Vec<u32>) -> Item {
        let side = samples.side[members[0] as usize];
        let (lo, hi) = members.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &k| {
                let p = samples.position[k as usize];
                (lo.min(p), hi.max(p))
            },
        );
        let normal = samples.normal[members[0] as usize];
        Item {
            side,
            piece,
            members,
            centre: 0.5 * (lo + hi),
            normal,
            lo,
            hi,
        }
    }
}

struct Part {
    view: View,
    centroid: Vec3,
    area: f64,
    normal_sum: DVec3,
    lo: Vec3,
    hi: Vec3,
}

/// Angle between two unit vectors, radians.
pub(crate) fn angle(a: Vec3, b: Vec3) -> f32 {
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// Radius about sample k's centroid holding its sample point. The links bound the form-factor
/// kernel between region centroids (where the flat solver evaluates it in the far field) and
/// cast rays from sample points; the near field, where a region's extent matters, is left to
/// leaf links.
fn region_radius(samples: &Samples, k: usize) -> f32 {
    samples.centroid[k].distance(samples.position[k])
}
