//! What makes a scene's image black or wrong without any error: no light at all, light that
//! leaves the scene or falls on the backs of one-sided faces, an area light facing away from
//! everything, a camera outside the scene or looking at backs. Each check casts a few thousand
//! rays, far fewer than a solve, and reports in words that name what to fix; the library never
//! prints, so a host (or the CLI) decides what to do with the findings.

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::error::Result;
// A surface narrower than NARROW ε holds about a row or two of samples ε apart along its length
// however narrow it is (dart throwing within it): its samples follow its length, not its area, so
// the density by area is read from the wider ones. The width is the one the solver joins facets by.
use crate::sampling::pieces::NARROW;
use crate::scene::Scene;
use crate::visibility::{Hit, Ray, Visibility};

/// Rays cast from each light.
const LIGHT_RAYS: usize = 1024;
/// Camera rays cast, a side.
const CAMERA_GRID: u32 = 32;
/// The share of light or view that must go astray before a warning.
const MOST: f64 = 0.5;
/// An area light whose rays meet a surface within this share of the scene's diagonal, for
/// half of them or more, faces something close by.
const CLOSE: f32 = 0.02;
/// An area light whose front meets the scene with fewer of its rays than this faces away.
const SEES_NOTHING: f64 = 0.05;

/// One thing found.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    /// Whether the scene cannot give a meaningful result at all (nothing emits light).
    pub fatal: bool,
    /// What was found and what to do, in one or two sentences.
    pub message: String,
}

/// Where a ray from a light or the camera first lands.
#[derive(Clone, Copy, PartialEq)]
enum Landing {
    /// Nothing: it leaves the scene.
    Away,
    /// The back of a one-sided face (which absorbs it unseen), with the surface.
    Back(u32),
    /// A side that reflects or emits.
    Front,
}

fn landing(scene: &Scene, ray: &Ray, hit: Option<Hit>) -> Landing {
    let Some(hit) = hit else {
        return Landing::Away;
    };
    let t = &scene.triangles()[hit.triangle as usize];
    let surface = &scene.surfaces()[t.surface as usize];
    let two_sided = surface.two_sided || scene.materials()[surface.material as usize].two_sided;
    if ray.dir.dot(t.normal) > 0.0 && !two_sided {
        Landing::Back(t.surface)
    } else {
        Landing::Front
    }
}

/// A material's name for messages: the surface's material, and the surface's index.
fn surface_name(scene: &Scene, surface: u32) -> String {
    let m = scene.surfaces()[surface as usize].material as usize;
    format!(
        "surface {surface} (material '{}')",
        scene.materials()[m].name
    )
}

/// A unit direction, uniform over the sphere.
fn sphere_direction(rng: &mut Pcg64Mcg) -> Vec3 {
    let (u1, u2): (f32, f32) = (rng.random(), rng.random());
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u2;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The checks that need no solve: a scene with no light (fatal), lights whose power mostly
/// leaves the scene or falls on backs, an area light whose front sees nothing, a camera
/// outside the scene or looking mostly at backs or into the void. Deterministic.
pub fn before_solve(scene: &Scene, vis: &dyn Visibility) -> Result<Vec<Finding>> {
    let checked = crate::visibility::Checked::new(vis, scene);
    let vis: &dyn Visibility = &checked;
    let mut found = Vec::new();
    let daylight = scene
        .daylight()
        .is_some_and(|d| d.diffuse_horizontal() > 0.0 || d.ground_luminance() > 0.0);
    if scene.emitted_power().max_element() <= 0.0 && !daylight {
        let message = if scene.annual().is_some() {
            // A year's scene has daylight, but not for one moment.
            "nothing lights the scene at one moment: its daylight is a year of weather \
             ([annual]), which `meshlight annual` (or `meshlight report`) computes; for one \
             moment give a [sky] (model = \"cie-overcast\", say), or lamps"
        } else {
            "nothing in the scene emits light: no material has a non-zero Ke, and there is no \
             point light or luminaire. (Blender's OBJ exporter writes Ke 0 for a plain Emission \
             node: set the light's material Ke in the MTL, or a [material.NAME] ke in the scene \
             file, or add a [[point_light]].)"
        };
        found.push(Finding {
            fatal: true,
            message: message.into(),
        });
        return Ok(found);
    }
    found.extend(lights(scene, vis)?);
    found.extend(camera(scene, vis)?);
    Ok(found)
}

/// Where each light's rays land: the power-weighted shares away and on backs, per-surface
/// back shares, and the area lights that see nothing.
fn lights(scene: &Scene, vis: &dyn Visibility) -> Result<Vec<Finding>> {
    let lift = crate::visibility::lift(scene);
    let mut rng = Pcg64Mcg::seed_from_u64(0x5EED_D1A6);
    let mut found = Vec::new();
    let mut astray = Astray {
        backs: vec![0.0; scene.surfaces().len()],
        ..Astray::default()
    };
    for (s, power) in scene.emitters() {
        let rays = crate::light::leaving::rays(scene, s, LIGHT_RAYS, lift, &mut rng);
        if rays.is_empty() {
            continue;
        }
        let mut hits = vec![None; rays.len()];
        vis.intersect(&rays, &mut hits)?;
        let power = power.max_element();
        let each = power / rays.len().max(1) as f64;
        let mut met = 0usize;
        for (ray, &hit) in rays.iter().zip(&hits) {
            let landing = landing(scene, ray, hit);
            met += usize::from(!matches!(landing, Landing::Away));
            astray.add(landing, each);
        }
        astray.total += power;
        found.extend(trapped(scene, s, &hits, met));
    }
    for source in scene.point_sources() {
        point_source(scene, vis, &source, &mut rng, &mut astray)?;
    }
    found.extend(astray.finding(scene));
    Ok(found)
}

/// The power-weighted shares of the lights' rays that leave the scene and that fall on backs
/// of one-sided faces (per surface too), of the power `total` cast.
#[derive(Default)]
struct Astray {
    away: f64,
    back: f64,
    total: f64,
    backs: Vec<f64>,
}

impl Astray {
    fn add(&mut self, landing: Landing, each: f64) {
        match landing {
            Landing::Away => self.away += each,
            Landing::Back(s) => {
                self.back += each;
                self.backs[s as usize] += each;
            }
            Landing::Front => {}
        }
    }

    /// Where most of the light goes astray: by how much, and the backs that take most.
    fn finding(&self, scene: &Scene) -> Option<Finding> {
        let total = self.total;
        if !(total > 0.0 && (self.away + self.back) / total > MOST) {
            return None;
        }
        let mut worst: Vec<(usize, f64)> = self
            .backs
            .iter()
            .copied()
            .enumerate()
            .filter(|&(_, b)| b > 0.0)
            .collect();
        worst.sort_by(|a, b| b.1.total_cmp(&a.1));
        let named: Vec<String> = worst
            .iter()
            .take(4)
            .map(|&(s, b)| {
                format!(
                    "{} ({:.0}%)",
                    surface_name(scene, s as u32),
                    100.0 * b / total
                )
            })
            .collect();
        let mut message = format!(
            "most of the light goes astray: {:.0}% of the emitted power leaves the scene and \
             {:.0}% falls on the backs of one-sided faces, which absorb it unseen.",
            100.0 * self.away / total,
            100.0 * self.back / total
        );
        if !named.is_empty() {
            message.push_str(&format!(
                " Facing away from the lights: {}. Flip their normals, or set two_sided = true \
                 in the scene file.",
                named.join(", ")
            ));
        } else {
            message.push_str(" Is the scene open, or are the lights outside it?");
        }
        Some(Finding {
            fatal: false,
            message,
        })
    }
}

/// An area light (surface `s`) whose front sees nothing (`met` of its rays met a surface), or
/// faces a surface close by over most of its front: its light is then lost or trapped.
fn trapped(scene: &Scene, s: u32, hits: &[Option<Hit>], met: usize) -> Option<Finding> {
    let rays = hits.len();
    if (met as f64) < SEES_NOTHING * rays as f64 {
        return Some(Finding {
            fatal: false,
            message: format!(
                "the area light {} faces away from the scene: its front sees nothing ({met} of \
                 {rays} rays from it met a surface). Flip its normals, or set two_sided = true \
                 on its material.",
                surface_name(scene, s),
            ),
        });
    }
    let mut distances: Vec<f32> = hits.iter().flatten().map(|h| h.t).collect();
    distances.sort_by(f32::total_cmp);
    let median = distances[distances.len() / 2];
    let material = &scene.materials()[scene.surfaces()[s as usize].material as usize];
    let advice = if material.two_sided {
        "its material is two_sided, so this is one of its two faces: the light that face \
         emits stays in the gap, as it would in Cycles. Make the material one-sided (two_sided \
         = false) if the panel is meant to light the room only"
    } else {
        "a light panel facing the ceiling? Blender's lights emit from both sides. Flip its \
         normals, or set two_sided = true on its material"
    };
    (median < CLOSE * scene.bounds().diagonal()).then(|| Finding {
        fatal: false,
        message: format!(
            "the area light {} faces a surface {median:.3} away over most of its front: its \
             light is trapped there ({advice}).",
            surface_name(scene, s)
        ),
    })
}

/// A point light's or luminaire's rays, over the sphere, each weighed by the intensity towards
/// it, into `astray`.
fn point_source(
    scene: &Scene,
    vis: &dyn Visibility,
    source: &crate::scene::PointSource,
    rng: &mut Pcg64Mcg,
    astray: &mut Astray,
) -> Result<()> {
    let dirs: Vec<Vec3> = (0..LIGHT_RAYS).map(|_| sphere_direction(rng)).collect();
    let weights: Vec<f64> = dirs
        .iter()
        .map(|&d| f64::from(source.towards(d).max_element()))
        .collect();
    let sum: f64 = weights.iter().sum();
    if sum <= 0.0 {
        return Ok(());
    }
    let power = sum / LIGHT_RAYS as f64 * 4.0 * std::f64::consts::PI;
    let rays: Vec<Ray> = dirs
        .iter()
        .map(|&dir| Ray {
            origin: source.position,
            dir,
            t_min: 0.0,
            t_max: f32::INFINITY,
        })
        .collect();
    let mut hits = vec![None; rays.len()];
    vis.intersect(&rays, &mut hits)?;
    for ((ray, hit), w) in rays.iter().zip(hits).zip(&weights) {
        astray.add(landing(scene, ray, hit), power * w / sum);
    }
    astray.total += power;
    Ok(())
}

/// Whether the camera is outside the scene's bounds, or sees mostly backs or nothing.
fn camera(scene: &Scene, vis: &dyn Visibility) -> Result<Vec<Finding>> {
    let mut found = Vec::new();
    let c = scene.camera();
    let b = scene.bounds();
    let pad = 1e-3 * b.diagonal();
    if (c.position.cmplt(b.min - Vec3::splat(pad)) | c.position.cmpgt(b.max + Vec3::splat(pad)))
        .any()
    {
        found.push(Finding {
            fatal: false,
            message: format!(
                "the camera at {} is outside the scene, whose bounds are {} to {}: is its \
                 position in the scene's coordinates (+Y up; Blender's are Z-up)?",
                c.position, b.min, b.max
            ),
        });
    }
    let n = CAMERA_GRID;
    let rays: Vec<Ray> = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            let x = (i as f32 + 0.5) / n as f32 * c.width as f32;
            let y = (j as f32 + 0.5) / n as f32 * c.height as f32;
            Ray {
                origin: c.position,
                dir: c.direction(x, y),
                t_min: 0.0,
                t_max: f32::INFINITY,
            }
        })
        .collect();
    let mut hits = vec![None; rays.len()];
    vis.intersect(&rays, &mut hits)?;
    let (mut away, mut back) = (0usize, 0usize);
    for (ray, hit) in rays.iter().zip(hits) {
        match landing(scene, ray, hit) {
            Landing::Away => away += 1,
            Landing::Back(_) => back += 1,
            Landing::Front => {}
        }
    }
    let all = rays.len() as f64;
    if (away + back) as f64 / all > MOST {
        found.push(Finding {
            fatal: false,
            message: format!(
                "the camera sees little of the scene: {:.0}% of its view is empty and {:.0}% \
                 the backs of one-sided faces (black). Check its position and look_at, and the \
                 faces' orientation (two_sided = true).",
                100.0 * away as f64 / all,
                100.0 * back as f64 / all
            ),
        });
    }
    Ok(found)
}

/// The check on a finished image: black, or nearly, though the scene emits light.
pub fn image(scene: &Scene, image: &crate::Image) -> Option<Finding> {
    let mean = image.mean();
    let emitted = scene.emitted_power().max_element();
    // A lit scene's image is black to a millionth of its lights' radiance scale only when nothing
    // lit is in view.
    let scale = emitted / scene.total_area().max(f64::MIN_POSITIVE) / std::f64::consts::PI;
    (emitted > 0.0 && mean <= 1e-6 * scale.max(f64::MIN_POSITIVE)).then(|| Finding {
        fatal: false,
        message: format!(
            "the image is black (mean radiance {mean:.3e}): the camera sees nothing the light \
             reaches. Likely causes: the camera is outside the room or looks at the backs of \
             its faces, or the light faces away from the scene."
        ),
    })
}

/// The share of the first samples beyond what the area asks for, above which [`samples`] says so.
const MOSTLY_TESSELLATION: f64 = 0.5;
/// The fewest first samples on wide surfaces from which their density is read.
const DENSITY_SAMPLES: usize = 100;

/// The check on a finished solve: whether most of the first (Poisson-disk) samples are there
/// because surfaces are cut into facets narrower than 2 ε rather than because of their area.
/// Each planar surface is sampled on its own, at least once and once every ε along its length,
/// so a column of 48 facets 4 cm wide gets a row of samples on each facet: the samples, and the
/// links and time with them, follow the mesh's tessellation, and ε moves them only along the
/// facets' length. The area's share is read from the density on the scene's wide surfaces.
pub fn samples(scene: &Scene, solution: &crate::Solution) -> Option<Finding> {
    // A solution of another scene has nothing to say about this one (and its sides would not
    // index this scene's surfaces).
    solution.check_fits(scene).ok()?;
    let s = solution.samples();
    let eps = f64::from(solution.epsilon());
    if eps.is_nan() || eps <= 0.0 {
        return None;
    }
    let surfaces = scene.surfaces();
    let narrow = crate::sampling::pieces::narrow_surfaces(scene, NARROW * eps);
    let pieces = solution.field().layout.pieces();
    let joined = pieces.joined();
    // The first round's samples only: the adaptive rounds add where light changes, which is
    // work the scene asks for.
    let mut first = vec![0usize; 2 * surfaces.len()];
    for (k, &side) in s.side.iter().enumerate() {
        if let (Some(0), Some(n)) = (s.round.get(k), first.get_mut(side as usize)) {
            *n += 1;
        }
    }
    let (mut wide_samples, mut wide_area, mut sampled_area) = (0usize, 0.0f64, 0.0f64);
    let (mut on_narrow, mut narrow_sides, mut total) = (0usize, 0usize, 0usize);
    // Samples on narrow sides, by material: what to simplify first.
    let mut by_material = vec![0usize; scene.materials().len()];
    // A curved piece's samples carry all its sides' area, those without samples of their own
    // too.
    let piece_sampled: Vec<bool> = (0..pieces.len() as u32)
        .map(|p| {
            pieces
                .sides(p)
                .iter()
                .any(|&side| first.get(side as usize).is_some_and(|&n| n > 0))
        })
        .collect();
    for (side, &n) in first.iter().enumerate() {
        let surface = crate::sampling::surface_of(side as u32) as usize;
        let area = surfaces[surface].area;
        if n == 0 {
            let in_sampled_piece = pieces
                .of(side as u32)
                .is_some_and(|p| piece_sampled.get(p as usize) == Some(&true));
            if in_sampled_piece {
                sampled_area += area;
            }
            continue;
        }
        total += n;
        sampled_area += area;
        if narrow[surface] {
            on_narrow += n;
            narrow_sides += 1;
            by_material[surfaces[surface].material as usize] += n;
        } else {
            wide_samples += n;
            wide_area += area;
        }
    }
    if wide_samples < DENSITY_SAMPLES || wide_area <= 0.0 || total == 0 {
        return None;
    }
    let by_area = wide_samples as f64 / wide_area * sampled_area;
    let excess = 1.0 - by_area / total as f64;
    if excess.is_nan() || excess <= MOSTLY_TESSELLATION {
        return None;
    }
    let mut most: Vec<(usize, usize)> = by_material
        .iter()
        .copied()
        .enumerate()
        .filter(|&(_, n)| n > 0)
        .collect();
    most.sort_by_key(|&(m, n)| (std::cmp::Reverse(n), m));
    let materials = most
        .iter()
        .take(3)
        .map(|&(m, n)| format!("'{}' {n}", scene.materials()[m].name))
        .collect::<Vec<_>>()
        .join(", ");
    Some(Finding {
        fatal: false,
        message: format!(
            "{:.0}% of the {total} first samples are there because surfaces are cut into \
             facets narrower than {NARROW} ε = {:.3} ({on_narrow} samples on {narrow_sides} such \
             sides, most in materials {materials}: the facets of columns, arches, mouldings, \
             spheres): each {} is sampled on its own, once every ε along its length, so the \
             samples, links and time follow the mesh's tessellation; by their area alone, at \
             the density of the wider surfaces, about {:.0} would do. {}ε moves these samples \
             only along the facets.",
            100.0 * excess,
            NARROW * eps,
            if joined {
                "facet or piece of facets (joined where they bend by little)"
            } else {
                "facet"
            },
            by_area,
            if joined {
                "Fewer facets on the curved surfaces cost less. "
            } else {
                "Joining the facets into the curved pieces they make (the solver option \
                 join_facets) samples them by their area; fewer facets cost less too. "
            }
        ),
    })
}
