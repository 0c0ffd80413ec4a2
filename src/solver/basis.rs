//! One solve's samples lit again: the inter-reflection of any first light (an irradiance at
//! every sample) through the same areas, row scales, specular transfer and shooting the solve
//! used. Radiosity is linear in its sources, so a year of daylight is a sum of such bases, one
//! per sky patch and sun position (`annual`), each shot once.

use glam::DVec3;

use super::cluster::coherence::{Context, TriangleGrid};
use super::shooting::{Settings, State, Tick};
use super::{cluster, flat, EnergyLedger, Options, ShootStats, Solution};
use crate::error::Result;
use crate::progress::Control;
use crate::scene::Scene;
use crate::visibility::Visibility;

/// The loosest tolerance a basis is shot to: at 0.1 the office's year came 8.4% off a
/// one-moment solve at a point, at 0.01 within 3.4%.
const MAX_TOLERANCE: f64 = 1e-2;

/// Shoots a solution's samples again from new first light.
pub(crate) struct Basis<'a> {
    scene: &'a Scene,
    solution: &'a Solution,
    vis: &'a dyn Visibility,
    options: &'a Options,
    reflectance: Vec<DVec3>,
    dark_emitters: Vec<f64>,
    /// The hierarchy's tree and links, built once for every lighting (none for the flat
    /// solver), and the row scales they found.
    linked: Option<cluster::Linked>,
    row_scale: Vec<f32>,
}

impl<'a> Basis<'a> {
    /// Ready to shoot `solution` (solved for `scene` with `options`) again: with the
    /// hierarchy, its tree and links are built here once, their error bound weighing each
    /// shooter by the solution's own radiosity (every lighting then shoots along the same
    /// links: their visibility, the costly part, is found once). `None` if `stop` said so.
    pub(crate) fn new(
        scene: &'a Scene,
        solution: &'a Solution,
        vis: &'a dyn Visibility,
        options: &'a Options,
        stop: &mut dyn FnMut() -> bool,
    ) -> Result<Option<Basis<'a>>> {
        let n = solution.field.samples.len();
        let mut basis = Basis {
            scene,
            solution,
            vis,
            options,
            reflectance: (0..n)
                .map(|k| super::reflectance(scene, &solution.field.samples, k))
                .collect(),
            dark_emitters: solution
                .field
                .direct
                .iter()
                .map(|a| a.dark_emitters)
                .collect(),
            linked: None,
            row_scale: solution.row_scale.clone(),
        };
        if options.flat() {
            return Ok(Some(basis));
        }
        let grid = TriangleGrid::new(scene);
        let (mut irradiance, mut unshot) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        let mut ledger = EnergyLedger::default();
        let mut row_scale = solution.row_scale.clone();
        let mut state = State {
            samples: &solution.field.samples,
            maps: solution.field.layout.maps(),
            reflectance: &basis.reflectance,
            radiosity: &solution.field.radiosity,
            irradiance: &mut irradiance,
            unshot: &mut unshot,
            ledger: &mut ledger,
            row_scale: &mut row_scale,
            closed: &solution.closed,
            dark_emitters: &basis.dark_emitters,
            specular: solution.specular.as_ref(),
            regather: None,
        };
        let settings = basis.settings();
        let cx = Context {
            scene,
            grid: &grid,
            samples: &solution.field.samples,
            obstruction: solution.field.layout.obstruction(),
            pieces: solution.field.layout.pieces(),
            lift: settings.lift,
        };
        let mut report = |_: Tick| {
            if stop() {
                Control::Stop
            } else {
                Control::Continue
            }
        };
        let Some(linked) = cluster::link(&mut state, vis, &settings, &cx, &mut report)? else {
            return Ok(None);
        };
        basis.linked = Some(linked);
        basis.row_scale = row_scale;
        Ok(Some(basis))
    }

    fn settings(&self) -> Settings<'static> {
        let options = self.options;
        let n = self.solution.field.samples.len();
        let hierarchical = !options.flat();
        Settings {
            exec: crate::exec::Exec::local(options.threads, options.seed),
            capacity: options.pipeline_capacity.max(1),
            // Ten times looser than the solve's: each basis's first light is exact (at the
            // samples and, straight in, at the grid points), and what is left unshot is carried
            // to its end by the sweeps' tail; the office's year takes 0.65× the time at the
            // same error (docs/performance.md, "A year of daylight").
            tolerance: (10.0 * options.tolerance).min(MAX_TOLERANCE),
            max_shots: options.max_shots.unwrap_or(if hierarchical {
                u64::MAX
            } else {
                200 * n as u64
            }),
            lift: crate::visibility::lift(self.scene),
            memory_bytes: options.memory_budget.saturating_sub(self.solution.bytes()),
            budget: options.memory_budget,
            normalise: false,
            threshold: options.cluster_threshold,
            exact_visibility: options.exact_visibility,
        }
    }

    /// The reflected radiosity ρH of every sample when `first` is the light arriving at each
    /// straight from the sources (the emitters' own light left out), shot to ten times the
    /// options' tolerance (at most [`MAX_TOLERANCE`]); and the shooting's stats. `stop` is asked now and then and may end it early.
    pub(crate) fn reflected(
        &mut self,
        first: &[DVec3],
        stop: &mut dyn FnMut() -> bool,
    ) -> Result<(Vec<DVec3>, ShootStats)> {
        let solution = self.solution;
        let samples = &solution.field.samples;
        let n = samples.len();
        debug_assert_eq!(first.len(), n);
        let settings = self.settings();
        let rho = &self.reflectance;
        let radiosity: Vec<DVec3> = (0..n).map(|k| rho[k] * first[k]).collect();
        let mut irradiance = first.to_vec();
        let mut unshot = radiosity.clone();
        let mut ledger = EnergyLedger {
            emitted: (0..n).map(|k| first[k] * samples.area[k]).sum(),
            ..EnergyLedger::default()
        };
        let mut row_scale = self.row_scale.clone();
        let mut state = State {
            samples,
            maps: solution.field.layout.maps(),
            reflectance: rho,
            radiosity: &radiosity,
            irradiance: &mut irradiance,
            unshot: &mut unshot,
            ledger: &mut ledger,
            row_scale: &mut row_scale,
            closed: &solution.closed,
            dark_emitters: &self.dark_emitters,
            specular: solution.specular.as_ref(),
            regather: None,
        };
        let mut report = |_: Tick| {
            if stop() {
                Control::Stop
            } else {
                Control::Continue
            }
        };
        let stats = match &mut self.linked {
            Some(linked) => cluster::shoot_along(&mut state, linked, &settings, &mut report)?,
            None => flat::shoot(&mut state, self.vis, &settings, &mut report)?,
        };
        Ok(((0..n).map(|k| rho[k] * irradiance[k]).collect(), stats))
    }
}
