//! One sweep of shooting along the links: every sample's unshot radiosity goes out at once.
//!
//! A shooter node stands for its members through its moments M = Σ ΔB S n (one vector per
//! channel), placed at the centroid of its unshot power. A receiver point x with normal n then
//! gets n · E(x) from it, with the irradiance vector E(x) = −(M·v) v / (π |v|⁴), v = x − the
//! shooter's place: the far-field form factor of every member pair, to first order in the
//! shooter's extent (placing it where its power is, not where its area is, removes the
//! first-order error of uneven unshot power).
//!
//! What a receiver node gets is pushed down to its samples by area × cosine, and to first order
//! in its extent too: each link adds E at the node's centroid and its Jacobian J, and sample i
//! of the node gets nᵢ · (E + J (xᵢ − c)), summed over the links into the node and its
//! ancestors. The flux the node receives is the integral of that over its members, so it is
//! conserved to the same order; a constant push-down (each sample getting nᵢ · E) erred by 5%
//! of the inter-reflected light at the edges of two facing squares.

use glam::{DMat3, DVec3};

use super::links::Links;
use super::tree::{Ref, Tree};
use crate::sampling::adaptive::luminance;
use crate::sampling::Samples;

/// Receiver nodes smaller than this fraction of their distance to the shooter take the field's
/// first-order expansion; larger ones, the field at every member (the kernel's second-order
/// term, 10 (r/d)², would reach 2.5% at the node's edge).
const LINEAR: f64 = 0.05;

/// A shooter node this sweep: its moments and the place its unshot power sits.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shooter {
    pub moments: [DVec3; 3],
    pub centre: DVec3,
}

/// Sums of a node's members, bottom-up.
#[derive(Clone, Copy, Default)]
struct Sums {
    moments: [DVec3; 3],
    /// Σ w x, Σ w and Σ |w| with w the luminance of ΔB S.
    weighted: DVec3,
    weight: f64,
    magnitude: f64,
}

impl Sums {
    fn of_sample(samples: &Samples, unshot: &[DVec3], k: usize) -> Sums {
        let n = samples.normal[k].as_dvec3() * samples.area[k];
        let b = unshot[k];
        let w = luminance(b) * samples.area[k];
        Sums {
            moments: [n * b.x, n * b.y, n * b.z],
            weighted: samples.centroid[k].as_dvec3() * w,
            weight: w,
            magnitude: w.abs(),
        }
    }

    fn add(&mut self, o: &Sums) {
        for (m, x) in self.moments.iter_mut().zip(o.moments) {
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
        .map(|(s, node)| Shooter {
            moments: s.moments,
            centre: if s.magnitude > 0.0 && s.weight.abs() >= 0.5 * s.magnitude {
                s.weighted / s.weight
            } else {
                node.centroid.as_dvec3()
            },
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
            let visible = f64::from(link.factor);
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
                    let v = c - shooter.centre;
                    let field = &mut fields[link.r.index() - base];
                    let length2 = v.length_squared();
                    let s = visible / (std::f64::consts::PI * length2 * length2);
                    let outer_vv = DMat3::from_cols(v * v.x, v * v.y, v * v.z) * (4.0 / length2);
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
                _ => {
                    // Near: the field at every member.
                    for &k in members {
                        let k = k as usize;
                        let x = self.samples.centroid[k].as_dvec3();
                        let n = self.samples.normal[k].as_dvec3();
                        let v = x - shooter.centre;
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
