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

/// Every chain of at most `depth` reflectors (no reflector twice in a row) that carries at
/// least [`IMAGE_CUTOFF`].
pub(crate) fn chains(spec: &Specular, depth: u32) -> Vec<Chain> {
    let mut out = Vec::new();
    let mut stack: Vec<(Vec<u32>, f64)> = vec![(Vec::new(), 1.0)];
    while let Some((chain, carried)) = stack.pop() {
        if chain.len() as u32 >= depth {
            continue;
        }
        for (i, r) in spec.reflectors.iter().enumerate() {
            if chain.last() == Some(&(i as u32)) {
                continue;
            }
            let next = carried * r.reflects.typical();
            if next < IMAGE_CUTOFF {
                continue;
            }
            let mut longer = chain.clone();
            longer.push(i as u32);
            let linear = longer.iter().fold(DMat3::IDENTITY, |a, &k| {
                let n = spec.reflectors[k as usize].normal.as_dvec3();
                (DMat3::IDENTITY - 2.0 * outer(n, n)) * a
            });
            out.push(Chain {
                reflectors: longer.clone(),
                linear,
            });
            stack.push((longer, next));
        }
    }
    // A fixed order, whatever the stack did: shorter chains first, then by reflector.
    out.sort_by(|a, b| {
        (a.reflectors.len(), &a.reflectors).cmp(&(b.reflectors.len(), &b.reflectors))
    });
    out
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

    fn mirror(normal: Vec3, offset: f32, ks: f32) -> Reflector {
        Reflector {
            surface: 0,
            normal,
            offset,
            reflects: Reflects::Mirror(Vec3::splat(ks)),
            both_sides: false,
            bounds: crate::specular::EVERYWHERE,
        }
    }

    #[test]
    fn two_facing_mirrors_make_images_of_images_until_they_carry_too_little() {
        let spec = Specular {
            reflectors: vec![mirror(Vec3::X, 0.0, 0.5), mirror(Vec3::NEG_X, -4.0, 0.5)],
            ..Specular::default()
        };
        // 0.5, 0.25, 0.125, …: 1% is passed after six reflections, two chains per length.
        let all = chains(&spec, 16);
        assert_eq!(all.len(), 12);
        assert_eq!(chains(&spec, 2).len(), 4);
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
