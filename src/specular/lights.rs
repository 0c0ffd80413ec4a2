//! Light sampling at glossy vertices: a point on each area light (uniform over its area) and
//! each point light, combined with the lobe's own samples by the power heuristic (multiple
//! importance sampling, Veach 1997): what a glossy surface reflects of the lights, in the image,
//! the solve's chains and the grids.

use glam::{DVec3, Vec3};

use crate::material::Lobe;
use crate::scene::{PointSource, Scene};

/// An area light to sample: an emitting surface, or a piece of many (`scene::adjacency`).
struct AreaLight {
    triangles: Vec<[Vec3; 3]>,
    /// Per triangle, its front normal.
    normals: Vec<Vec3>,
    cumulative: Vec<f64>,
    area: f64,
    ke: DVec3,
}

/// The scene's lights, for sampling from glossy vertices.
pub(crate) struct Lights {
    areas: Vec<AreaLight>,
    /// Per surface: its index in `areas`, if it emits.
    of_surface: Vec<Option<u32>>,
    points: Vec<PointSource>,
    lift: f32,
}

/// One light sample from a glossy vertex: the light point (lifted), and the radiance it sends
/// back along the incoming direction if nothing is in the way (MIS-weighted).
pub(crate) struct LightSample {
    pub to: Vec3,
    pub radiance: DVec3,
}

impl Lights {
    pub(crate) fn new(scene: &Scene) -> Lights {
        let mut of_surface = vec![None; scene.surfaces.len()];
        let mut areas = Vec::new();
        for group in scene.emitter_groups() {
            let triangles = scene.triangles_of(&group);
            let cumulative = crate::sampling::triangles::cumulative_area(&triangles);
            let total = cumulative.last().copied().unwrap_or(0.0);
            for &s in &group {
                of_surface[s as usize] = Some(areas.len() as u32);
            }
            areas.push(AreaLight {
                triangles: triangles.iter().map(|t| t.vertices).collect(),
                normals: triangles.iter().map(|t| t.normal).collect(),
                cumulative,
                area: total,
                ke: scene.material_of(group[0]).ke.as_dvec3(),
            });
        }
        Lights {
            areas,
            of_surface,
            points: scene.point_sources(),
            lift: crate::visibility::lift(scene),
        }
    }

    /// Samples of every light from a glossy vertex at `v` (lifted off its surface): `count` per
    /// area light, drawn with `uniforms` (two numbers in [0, 1) each, `count` pairs), weighted
    /// against `lobe_samples` samples of the lobe; one per point light. Only lights in front of
    /// the lobe's side and facing `v` come out.
    pub(crate) fn sample(
        &self,
        lobe: &Lobe,
        v: Vec3,
        count: u32,
        lobe_samples: u32,
        uniforms: &mut impl FnMut() -> (f64, f64),
        out: &mut Vec<LightSample>,
    ) {
        self.sample_with(lobe, v, (count, lobe_samples), uniforms, &|_, _| 0.0, out);
    }

    /// [`Lights::sample`] with a third strategy in the multiple importance sampling: `third(l,
    /// light_density)` is its density for the path through light point `l`, in the measure of
    /// the light samples (their solid-angle density at `v` for area lights, `None` for a point
    /// light, whose samples then weigh against the third strategy alone).
    pub(crate) fn sample_with(
        &self,
        lobe: &Lobe,
        v: Vec3,
        (count, lobe_samples): (u32, u32),
        uniforms: &mut impl FnMut() -> (f64, f64),
        third: &dyn Fn(Vec3, Option<f64>) -> f64,
        out: &mut Vec<LightSample>,
    ) {
        for light in &self.areas {
            for _ in 0..count {
                let (u1, u2) = uniforms();
                let (y, normal) = light.point(u1, u2);
                let d = (y - v).as_dvec3();
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    continue;
                }
                let dir = d / dist2.sqrt();
                let cos_y = -dir.dot(normal.as_dvec3());
                if cos_y <= 0.0 || dir.dot(lobe.normal()) <= 0.0 {
                    continue;
                }
                let f = lobe.eval(dir);
                if f.max_element() <= 0.0 {
                    continue;
                }
                let pdf_light = dist2 / (cos_y * light.area);
                let weight = power3(
                    f64::from(count) * pdf_light,
                    f64::from(lobe_samples) * lobe.pdf(dir),
                    third(y, Some(pdf_light)),
                );
                out.push(LightSample {
                    to: y + self.lift * normal,
                    radiance: light.ke * f / (f64::from(count) * pdf_light) * weight,
                });
            }
        }
        for source in &self.points {
            let d = (source.position - v).as_dvec3();
            let dist2 = d.length_squared();
            if dist2 <= 0.0 {
                continue;
            }
            let dir = d / dist2.sqrt();
            if dir.dot(lobe.normal()) <= 0.0 {
                continue;
            }
            let intensity = source.towards((-dir).as_vec3()).as_dvec3();
            // Against the third strategy alone, in its own measure (`third` gives it relative
            // to this sample's density, 1).
            let weight = power(1.0, third(source.position, None));
            out.push(LightSample {
                to: source.position,
                radiance: intensity * lobe.eval(dir) / dist2 * weight,
            });
        }
    }

    /// The power-heuristic weight of a lobe sample (density `pdf_lobe`, one of `lobe_samples`)
    /// that hit the emitting surface `surface` at `dist2` with cos θ = `cos_y` there, against
    /// `count` light samples of it.
    pub(crate) fn lobe_weight(
        &self,
        surface: u32,
        pdf_lobe: f64,
        dist2: f64,
        cos_y: f64,
        count: u32,
        lobe_samples: u32,
    ) -> f64 {
        self.lobe_weight_with(
            surface,
            pdf_lobe,
            (dist2, cos_y),
            (count, lobe_samples),
            0.0,
        )
    }

    /// [`Lights::lobe_weight`] against a third strategy too, whose density is
    /// `third_per_light` × the light samples' (see [`Lights::sample_with`]).
    pub(crate) fn lobe_weight_with(
        &self,
        surface: u32,
        pdf_lobe: f64,
        (dist2, cos_y): (f64, f64),
        (count, lobe_samples): (u32, u32),
        third_per_light: f64,
    ) -> f64 {
        let Some(Some(i)) = self.of_surface.get(surface as usize) else {
            return 1.0;
        };
        let pdf_light = dist2 / (cos_y.max(1e-12) * self.areas[*i as usize].area);
        power3(
            f64::from(lobe_samples) * pdf_lobe,
            f64::from(count) * pdf_light,
            third_per_light * pdf_light,
        )
    }

    /// The area lights: (index, area, Ke).
    pub(crate) fn area_lights(&self) -> impl Iterator<Item = (usize, f64, DVec3)> + '_ {
        self.areas
            .iter()
            .enumerate()
            .map(|(i, a)| (i, a.area, a.ke))
    }

    /// The box around area light `i`, as its centre and half its diagonal.
    pub(crate) fn bounds_of(&self, i: usize) -> (Vec3, f32) {
        let (lo, hi) = self.areas[i].triangles.iter().flatten().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        (0.5 * (lo + hi), 0.5 * (hi - lo).length())
    }

    /// A point on area light `i`, at (u1, u2), and the light's front normal there.
    pub(crate) fn point_on(&self, i: usize, u1: f64, u2: f64) -> (Vec3, Vec3) {
        self.areas[i].point(u1, u2)
    }

    /// The point lights and luminaires.
    pub(crate) fn point_sources(&self) -> &[PointSource] {
        &self.points
    }

    /// How far light points are lifted off their emitters.
    pub(crate) fn lift(&self) -> f32 {
        self.lift
    }
}

impl AreaLight {
    /// The point at (u1, u2), and the normal there: u1 along the cumulative area picks the
    /// triangle, the rest places the point uniformly inside.
    fn point(&self, u1: f64, u2: f64) -> (Vec3, Vec3) {
        let u = u1 * self.area;
        let t = self
            .cumulative
            .partition_point(|&c| c <= u)
            .min(self.triangles.len() - 1);
        let start = if t == 0 { 0.0 } else { self.cumulative[t - 1] };
        let within = ((u - start) / (self.cumulative[t] - start)).clamp(0.0, 1.0);
        (
            crate::sampling::triangles::in_triangle(self.triangles[t], within, u2),
            self.normals[t],
        )
    }
}

/// The power heuristic's weight for the strategy of (count × density) `a` against `b` and `c`.
pub(crate) fn power3(a: f64, b: f64, c: f64) -> f64 {
    let (a2, b2, c2) = (a * a, b * b, c * c);
    if a2 + b2 + c2 > 0.0 {
        a2 / (a2 + b2 + c2)
    } else {
        0.0
    }
}

/// The power heuristic's weight for the strategy of (count × density) `a` against `b`.
pub(crate) fn power(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}
