//! How much sky a grid sees, and through what: the check that a daylight model lets light in
//! where it should (a model left closed, glass modelled facing inward, or a `north` or `up`
//! pointing elsewhere shows as a grid that sees none).

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::error::{Error, Result};
use crate::scene::{Grid, Kind, Scene};
use crate::visibility::{Ray, Visibility};

/// The sky a grid's points see, as shares of their hemisphere weighted by the cosine (so a
/// share is the daylight factor the sky would give if it were uniform and nothing reflected).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SkyView {
    /// Through openings: rays that leave the model above the horizon crossing nothing.
    pub open: f64,
    /// Through glass: rays that leave the model above the horizon crossing glass.
    pub glazed: f64,
    /// Rays that leave the model below the horizon (they see the ground).
    pub ground: f64,
}

/// Rays per grid point.
const RAYS: u32 = 256;
/// Glass faces a ray may pass before it is taken as blocked.
const MAX_CROSSINGS: usize = 16;

/// The sky `grid` sees in `scene` (which must have daylight), by `RAYS` cosine-weighted rays a
/// point, deterministic.
pub fn sky_view(scene: &Scene, vis: &dyn Visibility, grid: &Grid) -> Result<SkyView> {
    let Some(daylight) = scene.daylight() else {
        return Err(Error::Option {
            option: "sky",
            problem: "the scene has no [sky]: there is no sky to see".into(),
        });
    };
    let checked = crate::visibility::Checked::new(vis, scene);
    let up = daylight.up();
    let n = grid.normal();
    let (t, b) = n.any_orthonormal_pair();
    let far = 2.0 * scene.bounds().diagonal() + 1.0;
    let lift = crate::visibility::lift(scene);
    let points = grid.points();
    let mut view = SkyView::default();
    let mut rng = Pcg64Mcg::seed_from_u64(0x5C1E_u64);
    for &p in &points {
        // Rays on their way: (ray, crossed glass).
        let mut rays: Vec<(Ray, bool)> = (0..RAYS)
            .map(|i| {
                let u = (f64::from(i) + rng.random::<f64>()) / f64::from(RAYS);
                let phi = std::f64::consts::TAU * rng.random::<f64>();
                let r = u.sqrt();
                let dir = (t * (r * phi.cos()) as f32
                    + b * (r * phi.sin()) as f32
                    + n * (1.0 - u).max(0.0).sqrt() as f32)
                    .normalize();
                let ray = Ray {
                    origin: p + lift * n,
                    dir,
                    t_min: 0.0,
                    t_max: far,
                };
                (ray, false)
            })
            .collect();
        for _ in 0..MAX_CROSSINGS {
            if rays.is_empty() {
                break;
            }
            let plain: Vec<Ray> = rays.iter().map(|r| r.0).collect();
            let mut hits = vec![None; plain.len()];
            checked.intersect(&plain, &mut hits)?;
            let mut next = Vec::new();
            for ((ray, glazed), hit) in rays.into_iter().zip(hits) {
                match hit {
                    None => {
                        let share = 1.0 / f64::from(RAYS) / points.len() as f64;
                        if ray.dir.dot(up) <= 0.0 {
                            view.ground += share;
                        } else if glazed {
                            view.glazed += share;
                        } else {
                            view.open += share;
                        }
                    }
                    Some(h) => {
                        let tri = &scene.triangles()[h.triangle as usize];
                        let material = scene.material_of(tri.surface);
                        if matches!(material.kind, Kind::Glass { .. }) {
                            // On through the glass (straight: what matters is where it ends).
                            let at = ray.origin + ray.dir * h.t;
                            let side = if ray.dir.dot(tri.normal) > 0.0 {
                                tri.normal
                            } else {
                                -tri.normal
                            };
                            let ray = Ray {
                                origin: at + lift * side,
                                ..ray
                            };
                            next.push((ray, true));
                        }
                    }
                }
            }
            rays = next;
        }
    }
    Ok(view)
}

impl SkyView {
    /// Whether the grid sees any sky at all.
    pub fn sees_sky(&self) -> bool {
        self.open + self.glazed > 0.0
    }
}
