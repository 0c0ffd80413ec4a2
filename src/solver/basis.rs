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

/// Shoots a solution's samples again from new first light.
pub(crate) struct Basis<'a> {
    scene: &'a Scene,
    solution: &'a Solution,
    vis: &'a dyn Visibility,
    options: &'a Options,
    /// The hierarchy's triangles (none for the flat solver).
    grid: Option<TriangleGrid>,
    reflectance: Vec<DVec3>,
    dark_emitters: Vec<f64>,
}

impl<'a> Basis<'a> {
    /// Ready to shoot `solution` (solved for `scene` with `options`) again.
    pub(crate) fn new(
        scene: &'a Scene,
        solution: &'a Solution,
        vis: &'a dyn Visibility,
        options: &'a Options,
    ) -> Basis<'a> {
        let n = solution.samples.len();
        Basis {
            scene,
            solution,
            vis,
            options,
            grid: (!options.flat()).then(|| TriangleGrid::new(scene)),
            reflectance: (0..n)
                .map(|k| super::reflectance(scene, &solution.samples, k))
                .collect(),
            dark_emitters: solution.direct.iter().map(|a| a.dark_emitters).collect(),
        }
    }

    /// The reflected radiosity ρH of every sample when `first` is the light arriving at each
    /// straight from the sources (the emitters' own light left out), shot to the options'
    /// tolerance; and the shooting's stats. `stop` is asked now and then and may end it early.
    pub(crate) fn reflected(
        &self,
        first: &[DVec3],
        stop: &mut dyn FnMut() -> bool,
    ) -> Result<(Vec<DVec3>, ShootStats)> {
        let solution = self.solution;
        let samples = &solution.samples;
        let n = samples.len();
        debug_assert_eq!(first.len(), n);
        let rho = &self.reflectance;
        let radiosity: Vec<DVec3> = (0..n).map(|k| rho[k] * first[k]).collect();
        let mut irradiance = first.to_vec();
        let mut unshot = radiosity.clone();
        let mut ledger = EnergyLedger {
            emitted: (0..n).map(|k| first[k] * samples.area[k]).sum(),
            ..EnergyLedger::default()
        };
        let mut row_scale = solution.row_scale.clone();
        let mut state = State {
            samples,
            maps: &solution.maps,
            reflectance: rho,
            radiosity: &radiosity,
            irradiance: &mut irradiance,
            unshot: &mut unshot,
            ledger: &mut ledger,
            row_scale: &mut row_scale,
            closed: &solution.closed,
            dark_emitters: &self.dark_emitters,
            specular: solution.specular.as_ref(),
        };
        let options = self.options;
        let hierarchical = self.grid.is_some();
        let settings = Settings {
            ranks: &crate::distributed::Single,
            threads: options.threads.max(1),
            capacity: options.pipeline_capacity.max(1),
            tolerance: options.tolerance,
            max_shots: options.max_shots.unwrap_or(if hierarchical {
                u64::MAX
            } else {
                200 * n as u64
            }),
            lift: crate::visibility::lift(self.scene),
            memory_bytes: options.memory_budget.saturating_sub(solution.bytes()),
            budget: options.memory_budget,
            // The row scales the solve found stand: the same links, the same geometry.
            normalise: hierarchical,
            threshold: options.cluster_threshold,
            exact_visibility: options.exact_visibility,
            seed: options.seed,
        };
        let mut report = |_: Tick| {
            if stop() {
                Control::Stop
            } else {
                Control::Continue
            }
        };
        let stats = match &self.grid {
            Some(grid) => {
                let cx = Context {
                    scene: self.scene,
                    grid,
                    samples,
                    obstruction: &solution.obstruction,
                    lift: settings.lift,
                };
                cluster::shoot(&mut state, self.vis, &settings, &cx, &mut report)?
            }
            None => flat::shoot(&mut state, self.vis, &settings, &mut report)?,
        };
        Ok(((0..n).map(|k| rho[k] * irradiance[k]).collect(), stats))
    }
}
