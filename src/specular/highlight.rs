//! Highlight sampling: the light a glossy plane reflects from a light to a receiver, drawn where
//! the plane shows the light. For a light point l, the mirror image l* across the plane is
//! where a perfect mirror would show it; a glossy lobe spreads that spot by about its width. So
//! a direction from the receiver is drawn in a cone around the one towards l* (half-angle
//! three lobe widths) and meets the plane where the highlight is. Neither gathering over the
//! receiver's hemisphere nor sampling the light from wherever a gather ray met the plane finds
//! that spot often when the lobe is narrow; the three strategies are combined by multiple
//! importance sampling (`gather`).

use glam::{DVec3, Vec3};

use super::images::reflect_point;
use super::{Reflector, Reflects, Specular};
use crate::scene::{Kind, Scene};

/// A glossy plane highlights are drawn on.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Plane {
    pub surface: u32,
    /// The plane, as a reflector (for the images).
    pub reflector: Reflector,
    /// 1 − the cosine of the cone's half-angle.
    one_minus_cos: f64,
}

/// The scene's glossy planes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Highlights {
    pub planes: Vec<Plane>,
    /// Per surface: its plane, if glossy.
    of_surface: Vec<Option<u32>>,
}

impl Highlights {
    pub(crate) fn of(scene: &Scene, spec: &Specular) -> Highlights {
        let mut h = Highlights {
            planes: Vec::new(),
            of_surface: vec![None; scene.surfaces.len()],
        };
        for (i, surface) in scene.surfaces.iter().enumerate() {
            let m = &scene.materials[surface.material as usize];
            if let Kind::Specular { ks, roughness } = m.kind {
                if roughness > 0.0 && ks.max_element() > 0.0 && spec.specular[i] && !spec.curved[i]
                {
                    let alpha = f64::from(roughness * roughness).max(1e-4);
                    let half_angle = (3.0 * alpha).clamp(0.01, 1.0);
                    h.of_surface[i] = Some(h.planes.len() as u32);
                    h.planes.push(Plane {
                        surface: i as u32,
                        reflector: Reflector {
                            surface: i as u32,
                            area: surface.area as f32,
                            normal: surface.normal,
                            offset: surface.offset,
                            reflects: Reflects::Mirror(ks),
                            both_sides: surface.two_sided,
                            bounds: super::window_bounds(scene, surface),
                        },
                        one_minus_cos: 1.0 - half_angle.cos(),
                    });
                }
            }
        }
        h
    }

    /// The glossy plane a surface is, if it is one.
    pub(crate) fn plane_of(&self, surface: u32) -> Option<&Plane> {
        self.of_surface
            .get(surface as usize)
            .copied()
            .flatten()
            .map(|p| &self.planes[p as usize])
    }
}

impl Plane {
    /// Whether a point lies on its reflecting side.
    pub(crate) fn faces(&self, x: Vec3) -> bool {
        let r = &self.reflector;
        r.both_sides || r.normal.dot(x) - r.offset > 0.0
    }

    /// The direction from x towards light point l's image.
    fn axis(&self, x: Vec3, l: Vec3) -> Option<DVec3> {
        let image = reflect_point(&self.reflector, l);
        (image - x).as_dvec3().try_normalize()
    }

    /// A direction drawn in the cone around the one from x to l's image, with (u1, u2).
    pub(crate) fn draw(&self, x: Vec3, l: Vec3, u1: f64, u2: f64) -> Option<DVec3> {
        let axis = self.axis(x, l)?;
        let cos = 1.0 - u1 * self.one_minus_cos;
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * u2;
        let (t, b) = axis.any_orthonormal_pair();
        Some((t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * cos).normalize())
    }

    /// The density (per solid angle) of drawing direction ω from x for light point l.
    pub(crate) fn density(&self, x: Vec3, l: Vec3, omega: DVec3) -> f64 {
        match self.axis(x, l) {
            Some(axis) if axis.dot(omega) >= 1.0 - self.one_minus_cos => {
                1.0 / (std::f64::consts::TAU * self.one_minus_cos)
            }
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cone_density_integrates_to_one_and_its_draws_stay_inside() {
        let plane = Plane {
            surface: 0,
            reflector: Reflector {
                surface: 0,
                area: 1.0,
                normal: Vec3::Y,
                offset: 0.0,
                reflects: Reflects::Mirror(Vec3::ONE),
                both_sides: false,
                bounds: crate::specular::EVERYWHERE,
            },
            one_minus_cos: 1.0 - 0.3f64.cos(),
        };
        let (x, l) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(2.0, 1.0, 0.0));
        // The image of l is (2, −1, 0): the axis from x points down at 45°.
        let axis = DVec3::new(2.0, -2.0, 0.0).normalize();
        let n = 200;
        let mut inside = 0;
        for i in 0..n {
            for j in 0..n {
                let w = plane
                    .draw(
                        x,
                        l,
                        (i as f64 + 0.5) / n as f64,
                        (j as f64 + 0.5) / n as f64,
                    )
                    .unwrap();
                assert!(w.dot(axis) >= 0.3f64.cos() - 1e-9);
                inside += usize::from(plane.density(x, l, w) > 0.0);
            }
        }
        assert_eq!(inside, n * n);
        // ∫ density dω over the cap = density × 2π(1 − cos θ) = 1.
        let cap = std::f64::consts::TAU * (1.0 - 0.3f64.cos());
        assert!((plane.density(x, l, axis) * cap - 1.0).abs() < 1e-12);
    }
}
