//! One sweep of shooting along the links: every sample's unshot radiosity goes out at once.
//!
//! A shooter node stands for its members through its moments M = Σ ΔB S n (one vector per
//! channel), placed at the centroid of its unshot power. A receiver point x with normal n then
//! gets n · E(x) from it, with the irradiance vector E(x) = −(M·v) v / (π |v|⁴), v = x − the
//! shooter's place: the far-field form factor of every member pair, to first order in the
//! shooter's extent (placing it where its power is, not where its area is, removes the
//! first-order error of uneven unshot power).
//!
//! That point form errs at second order in the shooter's extent, and not evenly: the kernel
//! is concave seen head-on and convex seen edge-on, so the receivers' row normalisation (one
//! scale per receiver) cannot take the error out, and at albedo 0.95 a Cornell-like room lost
//! 0.10–0.21% of its light against the flat solver on the same samples, depending on the
//! seed. Each node with members in more than one place therefore shoots from four points,
//! c + L sₖ with L Lᵀ the spread (covariance) of its unshot power about c and sₖ the corners
//! of a tetrahedron (±1, ±1, ±1 with an even number of minus signs), each with a quarter of
//! its moments: their mean is c and their spread the members', so the field is right to
//! second order (`docs/method.md` §15).
//!
//! What a receiver node gets is pushed down to its samples by area × cosine, and to first order
//! in its extent too: each link adds E at the node's centroid and its Jacobian J, and sample i
//! of the node gets nᵢ · (E + J (xᵢ − c)), summed over the links into the node and its
//! ancestors. The flux the node receives is the integral of that over its members, so it is
//! conserved to the same order; a constant push-down (each sample getting nᵢ · E) erred by 5%
//! of the inter-reflected light at the edges of two facing squares.

use glam::{DMat3, DVec3, Vec3};

use super::links::Links;
use super::tree::{Ref, Tree};
use crate::sampling::adaptive::luminance;
use crate::sampling::Samples;

/// Receiver nodes smaller than this fraction of their distance to the shooter take the field's
/// first-order expansion; larger ones, the field at every member (the kernel's second-order
/// term, 10 (r/d)², would reach 2.5% at the node's edge).
const LINEAR: f64 = 0.05;

/// A shooter node this sweep: its moments, the place its unshot power sits, and the offsets
/// of the four points it shoots from (all zero: it shoots from its centre alone).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shooter {
    pub moments: [DVec3; 3],
    pub centre: DVec3,
    pub spread: [Vec3; 4],
}

/// Corners of a tetrahedron whose mean is 0 and whose second moments are the identity.
const CORNERS: [DVec3; 4] = [
    DVec3::new(1.0, 1.0, 1.0),
    DVec3::new(1.0, -1.0, -1.0),
    DVec3::new(-1.0, 1.0, -1.0),
    DVec3::new(-1.0, -1.0, 1.0),
];

impl Shooter {
    /// The points it shoots from, each with its share of the moments.
    fn points(&self) -> ([DVec3; 4], usize, f64) {
        if self.spread == [Vec3::ZERO; 4] {
            ([self.centre; 4], 1, 1.0)
        } else {
            (self.spread.map(|o| self.centre + o.as_dvec3()), 4, 0.25)
        }
    }
}

/// The second moments x xᵀ of a point, as xx, xy, xz, yy, yz, zz.
fn outer(x: DVec3) -> [f64; 6] {
    [
        x.x * x.x,
        x.x * x.y,
        x.x * x.z,
        x.y * x.y,
        x.y * x.z,
        x.z * x.z,
    ]
}

/// The offsets L sₖ for the spread `q` (a symmetric 3×3 as xx, xy, xz, yy, yz, zz), with L its
/// Cholesky factor; pivots a spread does not have (flat or thin nodes) are left out, and a
/// spread that is not positive (mixed signs of unshot power) gives none.
fn spread_points(q: [f64; 6]) -> [Vec3; 4] {
    let [xx, xy, xz, yy, yz, zz] = q;
    let trace = xx + yy + zz;
    if !trace.is_finite() || trace <= 0.0 {
        return [Vec3::ZERO; 4];
    }
    let tiny = 1e-9 * trace;
    let pivot = |d: f64| if d > tiny { d.sqrt() } else { 0.0 };
    let div = |a: f64, l: f64| if l > 0.0 { a / l } else { 0.0 };
    let l11 = pivot(xx);
    let (l21, l31) = (div(xy, l11), div(xz, l11));
    let l22 = pivot(yy - l21 * l21);
    let l32 = div(yz - l31 * l21, l22);
    let l33 = pivot(zz - l31 * l31 - l32 * l32);
    let l = DMat3::from_cols(
        DVec3::new(l11, l21, l31),
        DVec3::new(0.0, l22, l32),
        DVec3::new(0.0, 0.0, l33),
    );
    CORNERS.map(|s| (l * s).as_vec3())
}

/// Sums of a node's members, bottom-up.
#[derive(Clone, Copy, Default)]
struct Sums {
    moments: [DVec3; 3],
    /// Σ w x, Σ w x xᵀ (xx, xy, xz, yy, yz, zz), Σ w and Σ |w| with w the luminance of ΔB S.
    weighted: DVec3,
    second: [f64; 6],
    weight: f64,
    magnitude: f64,
}

impl Sums {
    fn of_sample(samples: &Samples, unshot: &[DVec3], k: usize) -> Sums {
        let n = samples.normal[k].as_dvec3() * samples.area[k];
        let b = unshot[k];
        let w = luminance(b) * samples.area[k];
        let x = samples.centroid[k].as_dvec3();
        Sums {
            moments: [n * b.x, n * b.y, n * b.z],
            weighted: x * w,
            second: outer(x).map(|v| v * w),
            weight: w,
            magnitude: w.abs(),
        }
    }

    fn add(&mut self, o: &Sums) {
        for (m, x) in self.moments.iter_mut().zip(o.moments) {
            *m += x;
        }
        for (m, x) in self.second.iter_mut().zip(o.second) {
            *m += x;
        }
        self.weighted += o.weighted;
        self.weight += o.weight;
        self.magnitude += o.magnitude;
    }
}

/// Every internal node as a shooter this sweep. Where a node's unshot power has mixed signs
/// (warm starts leave some negative) and nearly cancels, it is placed at its area centroid.
pub(crate) fn shooters(tree: &Tree, samples: &Samples, unshot: &[DVec3]) -> Vec<Shooter> {
    let mut sums = vec![Sums::default(); tree.nodes.len()];
    // Pre-order: children come after their parent, so a reverse pass sees them first.
    for i in (0..tree.nodes.len()).rev() {
        let mut total = Sums::default();
        for c in tree.nodes[i].children {
            if c.is_leaf() {
                total.add(&Sums::of_sample(samples, unshot, c.index()));
            } else {
                total.add(&sums[c.index()]);
            }
        }
        sums[i] = total;
    }
    sums.iter()
        .zip(&tree.nodes)
        .map(|(s, node)| {
            if s.magnitude > 0.0 && s.weight.abs() >= 0.5 * s.magnitude {
                let c = s.weighted / s.weight;
                // The spread about c: Σ w x xᵀ / Σ w − c cᵀ.
                let cc = outer(c);
                let q = std::array::from_fn(|i| s.second[i] / s.weight - cc[i]);
                Shooter {
                    moments: s.moments,
                    centre: c,
                    spread: spread_points(q),
                }
            } else {
                Shooter {
                    moments: s.moments,
                    centre: node.centroid.as_dvec3(),
                    spread: [Vec3::ZERO; 4],
                }
            }
        })
        .collect()
}

/// What a sweep reads.
pub(crate) struct Sources<'a> {
    pub tree: &'a Tree,
    pub samples: &'a Samples,
    /// Unshot radiosity of every sample, before the sweep.
    pub unshot: &'a [DVec3],
    /// Every internal node as a shooter ([`shooters`]).
    pub shooters: &'a [Shooter],
}

/// A receiver node's irradiance field, per channel: E at the node's centroid, and its Jacobian.
#[derive(Clone, Copy)]
struct Field {
    at: [DVec3; 3],
    slope: [DMat3; 3],
}

impl Field {
    // Not `Default`: glam's default matrix is the identity.
    const ZERO: Field = Field {
        at: [DVec3::ZERO; 3],
        slope: [DMat3::ZERO; 3],
    };
}

impl Sources<'_> {
    /// Shooter `s` as moments and place.
    fn shooter(&self, s: Ref) -> Shooter {
        if s.is_leaf() {
            let k = s.index();
            let n = self.samples.normal[k].as_dvec3() * self.samples.area[k];
            let b = self.unshot[k];
            Shooter {
                moments: [n * b.x, n * b.y, n * b.z],
                centre: self.samples.centroid[k].as_dvec3(),
                spread: [Vec3::ZERO; 4],
            }
        } else {
            self.shooters[s.index()]
        }
    }

    /// The irradiance the links deliver to every member of `group`, in tree order from the
    /// group's first member (cleared first).
    pub fn gather(&self, group: Ref, links: &[Links], out: &mut Vec<DVec3>) {
        let tree = self.tree;
        let (first, count, base, end) = if group.is_leaf() {
            (tree.place[group.index()] as usize, 1, 0, 0)
        } else {
            let node = &tree.nodes[group.index()];
            (
                node.first as usize,
                node.count as usize,
                group.index(),
                node.end as usize,
            )
        };
        out.clear();
        out.resize(count, DVec3::ZERO);
        let place = |k: usize| tree.place[k] as usize - first;
        // Fields of the group's internal nodes, with E taken at the origin: E + J (x − c) is
        // stored as (E − J c) + J x, so ancestors' fields simply add up on the way down.
        let mut fields = vec![Field::ZERO; end - base];
        for link in links.iter().flat_map(|l| &l.cluster) {
            let shooter = self.shooter(link.s);
            let (points, count, share) = shooter.points();
            let points = &points[..count];
            let visible = f64::from(link.factor) * share;
            let single = [link.r.index() as u32];
            let (members, node) = if link.r.is_leaf() {
                (&single[..], None)
            } else {
                let node = &tree.nodes[link.r.index()];
                let members = &tree.order[node.first as usize..(node.first + node.count) as usize];
                (members, Some(node))
            };
            match node {
                Some(node)
                    if f64::from(node.radius)
                        < LINEAR * node.centroid.as_dvec3().distance(shooter.centre) =>
                {
                    // Far enough for the field to be nearly linear across the node.
                    let c = node.centroid.as_dvec3();
                    let field = &mut fields[link.r.index() - base];
                    for &from in points {
                        let v = c - from;
                        let length2 = v.length_squared();
                        let s = visible / (std::f64::consts::PI * length2 * length2);
                        let outer_vv =
                            DMat3::from_cols(v * v.x, v * v.y, v * v.z) * (4.0 / length2);
                        for ch in 0..3 {
                            let m = shooter.moments[ch];
                            let mv = m.dot(v);
                            let at = v * (-s * mv);
                            // J = s [−v mᵀ − (m·v) I + 4 (m·v) v vᵀ / |v|²]
                            let slope = (DMat3::from_cols(v * -m.x, v * -m.y, v * -m.z)
                                - DMat3::from_diagonal(DVec3::splat(mv))
                                + outer_vv * mv)
                                * s;
                            field.at[ch] += at - slope * c;
                            field.slope[ch] += slope;
                        }
                    }
                }
                _ => {
                    // Near: the field at every member.
                    for &k in members {
                        let k = k as usize;
                        let x = self.samples.centroid[k].as_dvec3();
                        let n = self.samples.normal[k].as_dvec3();
                        for &from in points {
                            let v = x - from;
                            // A member facing away from the shooter's place gets nothing.
                            let scale = visible * (-n.dot(v)).max(0.0)
                                / (std::f64::consts::PI * v.length_squared().powi(2));
                            out[place(k)] += scale
                                * DVec3::new(
                                    shooter.moments[0].dot(v),
                                    shooter.moments[1].dot(v),
                                    shooter.moments[2].dot(v),
                                );
                        }
                    }
                }
            }
        }
        for link in links.iter().flat_map(|l| &l.leaf) {
            out[place(link.r as usize)] += self.unshot[link.s as usize] * f64::from(link.f);
        }
        if group.is_leaf() {
            return;
        }
        // Push down: every member gets n · (Σ over its ancestors of (E − J c) + J x).
        let mut stack: Vec<(usize, Field)> = vec![(base, fields[0])];
        while let Some((i, acc)) = stack.pop() {
            for child in tree.nodes[i].children {
                if child.is_leaf() {
                    let k = child.index();
                    let n = self.samples.normal[k].as_dvec3();
                    let x = self.samples.centroid[k].as_dvec3();
                    let e = |ch: usize| n.dot(acc.at[ch] + acc.slope[ch] * x);
                    out[place(k)] += DVec3::new(e(0), e(1), e(2));
                } else {
                    let own = &fields[child.index() - base];
                    let mut sum = acc;
                    for ch in 0..3 {
                        sum.at[ch] += own.at[ch];
                        sum.slope[ch] += own.slope[ch];
                    }
                    stack.push((child.index(), sum));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exact(m: DVec3, c_s: DVec3, x: DVec3) -> DVec3 {
        let v = x - c_s;
        v * (-m.dot(v) / (std::f64::consts::PI * v.length_squared().powi(2)))
    }

    /// A planar node's members (unit normal +z, weights), in a disc of radius 1 about the
    /// origin, unevenly bright.
    fn members() -> Vec<(DVec3, f64)> {
        (0..64)
            .map(|i| {
                let (r, a) = (((i as f64) + 0.5) / 64.0, i as f64 * 2.399963);
                let x = DVec3::new(r.sqrt() * a.cos(), r.sqrt() * a.sin(), 0.0);
                (x, 1.0 + 0.8 * x.x)
            })
            .collect()
    }

    /// The field of a node at `x` from its four points (or its centre alone), against the sum
    /// of its members' own fields: the relative error.
    fn node_error(x: DVec3, four: bool) -> f64 {
        let members = members();
        let weight: f64 = members.iter().map(|m| m.1).sum();
        let c: DVec3 = members.iter().map(|m| m.0 * m.1).sum::<DVec3>() / weight;
        let mut q = [0.0; 6];
        for (p, w) in &members {
            for (q, t) in q.iter_mut().zip(outer(*p - c)) {
                *q += w * t / weight;
            }
        }
        let truth: DVec3 = members
            .iter()
            .map(|(p, w)| exact(DVec3::Z * *w, *p, x))
            .sum();
        let shooter = Shooter {
            moments: [DVec3::Z * weight; 3],
            centre: c,
            spread: if four {
                spread_points(q)
            } else {
                [Vec3::ZERO; 4]
            },
        };
        let (points, count, share) = shooter.points();
        let approx: DVec3 = points[..count]
            .iter()
            .map(|&p| exact(DVec3::Z * weight * share, p, x))
            .sum();
        (approx - truth).length() / truth.length()
    }

    #[test]
    fn four_points_shoot_right_to_second_order() {
        // Receivers at distance d from a node of radius 1, head-on, oblique and nearly edge-on:
        // the centre alone errs as (1/d)², the four points as (1/d)³ or better.
        for dir in [
            DVec3::Z,
            DVec3::new(1.0, 0.0, 1.0).normalize(),
            DVec3::new(0.3, 1.0, 0.15).normalize(),
        ] {
            let (e3, e6) = (node_error(dir * 3.0, false), node_error(dir * 6.0, false));
            let (f3, f6) = (node_error(dir * 3.0, true), node_error(dir * 6.0, true));
            assert!(e3 > 1e-3, "{dir}: the centre alone errs by {e3}: no test");
            assert!(f3 < 0.3 * e3, "{dir}: four points {f3} vs the centre {e3}");
            // Halving the node's angular size: at least 2³ less error with four points.
            assert!(f6 < f3 / 7.0, "{dir}: {f3} at d = 3, {f6} at d = 6");
            assert!(
                (e3 / e6 - 4.0).abs() < 1.0,
                "{dir}: centre {e3} at 3, {e6} at 6"
            );
        }
    }

    #[test]
    fn spread_points_have_the_spread() {
        let q = [0.5, 0.1, -0.05, 0.3, 0.02, 0.2];
        let points = spread_points(q);
        let mean: DVec3 = points.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / 4.0;
        assert!(mean.length() < 1e-6);
        let mut got = [0.0; 6];
        for p in points.map(|p| p.as_dvec3()) {
            for (g, t) in got.iter_mut().zip(outer(p)) {
                *g += t / 4.0;
            }
        }
        for (g, w) in got.iter().zip(q) {
            assert!((g - w).abs() < 1e-6, "{got:?} vs {q:?}");
        }
        // A flat spread (no z) keeps the points in the plane; none at all gives none.
        let flat = spread_points([0.5, 0.1, 0.0, 0.3, 0.0, 0.0]);
        assert!(flat.iter().all(|p| p.z.abs() < 1e-7), "{flat:?}");
        assert_eq!(spread_points([0.0; 6]), [Vec3::ZERO; 4]);
        assert_eq!(spread_points([f64::NAN; 6]), [Vec3::ZERO; 4]);
    }

    #[test]
    fn the_jacobian_predicts_the_field_nearby() {
        let (m, c_s, c) = (
            DVec3::new(0.1, 0.2, 1.0),
            DVec3::new(0.3, -0.2, 0.1),
            DVec3::new(0.5, 0.4, 2.0),
        );
        let v = c - c_s;
        let length2 = v.length_squared();
        let s = 1.0 / (std::f64::consts::PI * length2 * length2);
        let mv = m.dot(v);
        let outer_vv = DMat3::from_cols(v * v.x, v * v.y, v * v.z) * (4.0 / length2);
        let slope = (DMat3::from_cols(v * -m.x, v * -m.y, v * -m.z)
            - DMat3::from_diagonal(DVec3::splat(mv))
            + outer_vv * mv)
            * s;
        let h = 1e-4;
        for d in [DVec3::X, DVec3::Y, DVec3::Z] {
            let numeric = (exact(m, c_s, c + d * h) - exact(m, c_s, c - d * h)) / (2.0 * h);
            let analytic = slope * d;
            assert!(
                (numeric - analytic).length() < 1e-6 * numeric.length().max(1.0),
                "{numeric} vs {analytic}"
            );
        }
    }
}
