//! The solve's specular transfer (`docs/method.md` §22): light leaving a diffuse sample that
//! reaches another by way of mirrors, glossy surfaces and glass. Each sample's chains
//! (`specular::gather`) end at points on surfaces with samples; interpolating the samples at
//! those points turns them into a sparse matrix G — the irradiance a receiver gets per unit
//! radiosity of each sample — which the shooting applies beside its links, to the unshot
//! radiosity it shoots. The chains' ends do not depend on the samples, so they are followed
//! once per sample; G is rebuilt every round, as adaptive samples change the interpolation.

use glam::{DVec3, Vec3};

use super::{Options, Solution};
use crate::error::Result;
use crate::field::interpolate::{Interpolator, Site};
use crate::scene::Scene;
use crate::specular::gather::{Chains, End};
use crate::specular::highlight::Highlights;
use crate::specular::lights::Lights;
use crate::specular::photons::{self, Landing};
use crate::specular::Specular;
use crate::visibility::Visibility;

/// The specular transfer of a solution.
#[derive(Clone, Debug, Default)]
pub(crate) struct Transfer {
    /// Where every sample's chains end (receiver: the sample).
    pub ends: Vec<End>,
    /// Per sample: irradiance from the lights by way of glossy bounces.
    pub direct: Vec<DVec3>,
    /// Per sample: the share of its hemisphere (cosine-weighted, as its chains found it) whose
    /// first hit is specular: there its light comes through G, not through links.
    pub specular_share: Vec<f32>,
    /// G by receiver (compressed rows): row i is `entries[starts[i]..starts[i + 1]]`, each
    /// (sample, irradiance at i per unit radiosity of the sample, RGB).
    starts: Vec<u32>,
    entries: Vec<(u32, [f32; 3])>,
    /// G by shooter (its transpose), for the flat solver.
    column_starts: Vec<u32>,
    columns: Vec<(u32, [f32; 3])>,
    /// Per shooter: the flux its unit radiosity delivers through G, Σᵢ Gᵢⱼ Sᵢ.
    pub column_flux: Vec<DVec3>,
    /// Where photons landed (`specular::photons`), traced once.
    pub landings: Vec<Landing>,
    /// Per sample: the irradiance the photons bring, their power over its area.
    pub caustic: Vec<DVec3>,
    /// Per sample: the direct light through chains of two reflectors or more (the image
    /// interpolates it: `light::Reach`).
    pub far: Vec<DVec3>,
}

fn rgb(w: [f32; 3]) -> DVec3 {
    Vec3::from(w).as_dvec3()
}

impl Transfer {
    /// Follows the chains of samples `first..` of `solution` (`options`' depth, rays a sample,
    /// seed and threads) and keeps their ends and direct light; returns the queries.
    pub(crate) fn follow(
        &mut self,
        scene: &Scene,
        solution: &Solution,
        vis: &dyn Visibility,
        (spec, lights): (&Specular, &Lights),
        options: &Options,
        first: usize,
    ) -> Result<u64> {
        let (depth, rays) = (options.specular_depth, options.specular_rays);
        let (seed, threads) = (options.seed, options.threads);
        let s = &solution.field.samples;
        let n = s.len();
        let interpolator = Interpolator::new(scene, &solution.field, vis);
        let has_samples = |side| interpolator.has_samples(side);
        let highlights = Highlights::of(scene, spec);
        let chains = Chains {
            scene,
            spec,
            lights,
            vis,
            lift: crate::visibility::lift(scene),
            depth,
            rays,
            has_samples: &has_samples,
            highlights: &highlights,
            unlisted: None,
        };
        let receivers: Vec<(Vec3, Vec3, u32)> = (first..n)
            .map(|k| (s.position[k], s.normal[k], k as u32))
            .collect();
        // In parallel chunks of receivers, each chunk's ends in receiver order.
        const CHUNK: usize = 256;
        let mut found = vec![Default::default(); receivers.len().div_ceil(CHUNK)];
        crate::parallel::for_chunks(&mut found, 1, threads, |c, out| {
            let part = &receivers[c * CHUNK..((c + 1) * CHUNK).min(receivers.len())];
            out[0] = chains.follow(part, seed)?;
            Ok(())
        })?;
        self.direct.resize(first, DVec3::ZERO);
        self.specular_share.resize(first, 0.0);
        let mut queries = 0;
        for (c, f) in found.into_iter().enumerate() {
            let base = (first + c * CHUNK) as u32;
            self.ends.extend(f.ends.into_iter().map(|mut e| {
                e.receiver += base;
                e
            }));
            self.direct.extend(f.direct);
            self.specular_share.extend(f.specular_share);
            queries += f.queries;
        }
        Ok(queries)
    }

    /// Sends `options`' photons (where the scene needs them) and keeps their landings; the
    /// queries. Landings that could pass a quarter of the memory budget are refused before any
    /// is traced.
    pub(crate) fn trace_photons(
        &mut self,
        scene: &Scene,
        vis: &dyn Visibility,
        (spec, lights): (&Specular, &Lights),
        options: &Options,
        report: crate::parallel::Report,
    ) -> Result<u64> {
        let (count, depth, budget) = (
            options.photons,
            options.specular_depth,
            options.memory_budget,
        );
        let (seed, threads) = (options.seed, options.threads);
        let listing = crate::specular::images::chains(spec, depth);
        if !photons::needed(scene, spec, &listing) {
            return Ok(0);
        }
        let pass = photons::Photons::new(scene, (spec, &listing, lights), vis, count, depth);
        let most = pass.count() as f64 * std::mem::size_of::<Landing>() as f64;
        if most > budget as f64 / 4.0 {
            return Err(crate::budget::exceeded(
                budget,
                format!(
                    "{} photons could land in {}, more than a quarter of the budget: send fewer \
                     photons or raise the budget",
                    crate::budget::human_count(pass.count() as f64),
                    crate::budget::human_bytes(most)
                ),
            ));
        }
        let found = pass.trace(seed, threads, report)?;
        self.landings = found.landings;
        Ok(found.queries)
    }

    /// The irradiance the photons bring to each sample of `solution`: the power landing in each
    /// area cell is split among the samples as the cell's area is (eq. 5), and each sample's
    /// power is over its area. So a sample's irradiance is the photons' average over the very
    /// region its area stands for, and a uniform irradiance comes out uniform.
    pub(crate) fn deposit(&self, solution: &Solution) -> Vec<DVec3> {
        let s = &solution.field.samples;
        let mut cell_power = vec![DVec3::ZERO; s.cells.len()];
        let mut loose = vec![DVec3::ZERO; s.len()];
        // The landings side by side, each side's cells found by their grid keys.
        let mut order: Vec<usize> = (0..self.landings.len()).collect();
        order.sort_by_key(|&i| self.landings[i].side);
        let mut keys: Vec<(u64, u32)> = Vec::new();
        let mut side = u32::MAX;
        let mut grid = None;
        for i in order {
            let landing = &self.landings[i];
            let map =
                &solution.field.layout.maps()[crate::sampling::surface_of(landing.side) as usize];
            if landing.side != side {
                side = landing.side;
                let cell = 2.0 * s.cell_half.get(side as usize).copied().unwrap_or(0.0);
                grid = (cell > 0.0).then(|| {
                    let nx = ((map.max.x - map.min.x) / cell).floor() as u64 + 2;
                    (cell, nx)
                });
                keys.clear();
                if let Some((cell, nx)) = grid {
                    let key = |p: glam::Vec2| {
                        let q = ((p - map.min) / cell).floor().max(glam::Vec2::ZERO);
                        q.y as u64 * nx + q.x as u64
                    };
                    keys.extend(
                        s.cells_of(side)
                            .map(|c| (key(map.to_2d(s.cells[c].centroid)), c as u32)),
                    );
                    keys.sort_unstable();
                }
            }
            let power = Vec3::from(landing.power).as_dvec3();
            let uv = map.to_2d(landing.point);
            let found = grid.and_then(|(cell, nx)| {
                let q = ((uv - map.min) / cell).floor().max(glam::Vec2::ZERO);
                let key = q.y as u64 * nx + q.x as u64;
                let at = keys.partition_point(|&(k, _)| k < key);
                keys.get(at).filter(|&&(k, _)| k == key).map(|&(_, c)| c)
            });
            match found {
                Some(c) => cell_power[c as usize] += power,
                // Off every cell (at a rim, by rounding): to the nearest sample.
                None => {
                    if let Some(k) = solution.field.layout.index().nearest(s, landing.side, uv) {
                        loose[k as usize] += power;
                    }
                }
            }
        }
        let whole = f64::from(crate::sampling::CELL_UNITS);
        (0..s.len())
            .map(|k| {
                let power: DVec3 = s
                    .shares
                    .of(k)
                    .map(|(c, units)| cell_power[c as usize] * (f64::from(units) / whole))
                    .sum::<DVec3>()
                    + loose[k];
                if s.area[k] > 0.0 {
                    power / s.area[k]
                } else {
                    DVec3::ZERO
                }
            })
            .collect()
    }

    /// G from the ends, interpolating the samples of `solution` there; returns the queries.
    pub(crate) fn build(
        &mut self,
        scene: &Scene,
        solution: &Solution,
        vis: &dyn Visibility,
    ) -> Result<u64> {
        let s = &solution.field.samples;
        let n = s.len();
        let interpolator = Interpolator::new(scene, &solution.field, vis).plain();
        let points: Vec<(Vec3, Vec3)> = self.ends.iter().map(|e| (e.point, e.normal)).collect();
        let covered = interpolator.covered(&points)?;
        let sites: Vec<Site> = self
            .ends
            .iter()
            .zip(&covered)
            .map(|(e, &covered)| Site::at(e.point, e.side, e.normal, covered))
            .collect();
        let mut weights = Vec::new();
        let queries = interpolator.weights(&sites, &mut weights)? + covered.len() as u64;
        // Rows: the ends are in receiver order; each row's entries merged by sample.
        let mut row: Vec<(u32, DVec3)> = Vec::new();
        self.starts = vec![0; n + 1];
        self.entries.clear();
        let mut at = 0;
        for i in 0..n {
            row.clear();
            while at < self.ends.len() && self.ends[at].receiver as usize == i {
                let chosen = &weights[at];
                let total: f64 = chosen.iter().map(|&(_, w)| f64::from(w)).sum();
                if total > 0.0 {
                    for &(k, w) in chosen {
                        row.push((k, self.ends[at].weight * (f64::from(w) / total)));
                    }
                }
                at += 1;
            }
            row.sort_by_key(|&(k, _)| k);
            let mut merged: Option<(u32, DVec3)> = None;
            for &(k, w) in &row {
                match &mut merged {
                    Some((j, sum)) if *j == k => *sum += w,
                    _ => {
                        if let Some((j, sum)) = merged.take() {
                            self.entries.push((j, sum.as_vec3().to_array()));
                        }
                        merged = Some((k, w));
                    }
                }
            }
            if let Some((j, sum)) = merged {
                self.entries.push((j, sum.as_vec3().to_array()));
            }
            self.starts[i + 1] = self.entries.len() as u32;
        }
        // The transpose, by counting.
        self.column_starts = vec![0; n + 1];
        for &(k, _) in &self.entries {
            self.column_starts[k as usize + 1] += 1;
        }
        for k in 0..n {
            self.column_starts[k + 1] += self.column_starts[k];
        }
        let mut next = self.column_starts.clone();
        self.columns = vec![(0, [0.0; 3]); self.entries.len()];
        self.column_flux = vec![DVec3::ZERO; n];
        for i in 0..n {
            for &(k, w) in &self.entries[self.starts[i] as usize..self.starts[i + 1] as usize] {
                self.columns[next[k as usize] as usize] = (i as u32, w);
                next[k as usize] += 1;
                self.column_flux[k as usize] += rgb(w) * s.area[i];
            }
        }
        Ok(queries)
    }

    /// Irradiance at receiver i from the samples' radiosities `b`: (G b)ᵢ.
    pub(crate) fn row_times(&self, i: usize, b: &[DVec3]) -> DVec3 {
        let (a, z) = (self.starts[i] as usize, self.starts[i + 1] as usize);
        self.entries[a..z]
            .iter()
            .map(|&(k, w)| rgb(w) * b[k as usize])
            .sum()
    }

    /// Shooter j's column: (receiver, irradiance per unit radiosity of j).
    pub(crate) fn column(&self, j: usize) -> impl Iterator<Item = (usize, DVec3)> + '_ {
        let (a, z) = (
            self.column_starts[j] as usize,
            self.column_starts[j + 1] as usize,
        );
        self.columns[a..z]
            .iter()
            .map(|&(i, w)| (i as usize, rgb(w)))
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        use crate::sampling::vec_bytes;
        vec_bytes(&self.ends)
            + vec_bytes(&self.direct)
            + vec_bytes(&self.specular_share)
            + vec_bytes(&self.starts)
            + vec_bytes(&self.entries)
            + vec_bytes(&self.column_starts)
            + vec_bytes(&self.columns)
            + vec_bytes(&self.column_flux)
            + vec_bytes(&self.landings)
            + vec_bytes(&self.caustic)
            + vec_bytes(&self.far)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::{solve, Control, Options};
    use crate::visibility::Backend;

    #[test]
    fn photons_landing_evenly_give_every_sample_the_same_irradiance() {
        // Landings spread evenly over the room's floor, 4 × 4 at the centres of a sub-grid of
        // every area cell, of equal power: each full cell receives the same power per area, so
        // a sample whose region is made of full cells gets exactly the floor's power over the
        // landings' area, whatever its radius, and the floor's samples together get it all.
        let scene = crate::scene::Scene::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room/scene.toml"),
        )
        .unwrap();
        let vis = Backend::Bvh.build(&scene).unwrap();
        let options = Options {
            epsilon: Some(0.4),
            rounds: 1,
            ..Options::default()
        };
        let s = solve(&scene, vis.as_ref(), &options, &mut |_| Control::Continue).unwrap();
        let samples = &s.field.samples;
        assert!(samples.round.contains(&1), "adaptive samples too");
        // The floor: the largest side facing up.
        let side = (0..2 * scene.surfaces.len() as u32)
            .filter(|&side| {
                !samples.cells_of(side).is_empty() && {
                    let surface = &scene.surfaces[crate::sampling::surface_of(side) as usize];
                    surface.normal.y > 0.99 && !crate::sampling::is_back(side)
                }
            })
            .max_by(|&a, &b| {
                let area = |side| scene.surfaces[crate::sampling::surface_of(side) as usize].area;
                area(a).total_cmp(&area(b))
            })
            .unwrap();
        let map = &s.field.layout.maps()[crate::sampling::surface_of(side) as usize];
        let cell = 2.0 * samples.cell_half[side as usize];
        let (nx, ny) = (
            ((map.max.x - map.min.x) / cell).ceil() as usize * 4,
            ((map.max.y - map.min.y) / cell).ceil() as usize * 4,
        );
        let mut landings = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let uv = map.min + (glam::Vec2::new(i as f32, j as f32) + 0.5) * (cell / 4.0);
                if map.contains(uv) {
                    landings.push(Landing {
                        point: map.to_3d(uv),
                        side,
                        power: [1.0; 3],
                    });
                }
            }
        }
        let power = landings.len() as f64;
        let per_area = power / (landings.len() as f64 * f64::from(cell / 4.0).powi(2));
        let transfer = Transfer {
            landings,
            ..Transfer::default()
        };
        let e = transfer.deposit(&s);
        let on_floor: Vec<usize> = (0..samples.len())
            .filter(|&k| samples.side[k] == side)
            .collect();
        let total: f64 = on_floor.iter().map(|&k| e[k].x * samples.area[k]).sum();
        assert!((total / power - 1.0).abs() < 1e-9, "{total} of {power}");
        assert!(on_floor.iter().all(|&k| e[k].x > 0.0));
        let full = f64::from(cell * cell);
        let mut checked = 0;
        for &k in &on_floor {
            if samples
                .shares_of(k)
                .all(|(c, _)| (f64::from(samples.cells[c as usize].area) / full - 1.0).abs() < 1e-4)
            {
                checked += 1;
                assert!(
                    (e[k].x / per_area - 1.0).abs() < 1e-3,
                    "sample {k} (radius {}): {} against {per_area}",
                    samples.radius[k],
                    e[k].x
                );
            }
        }
        assert!(
            checked > on_floor.len() / 2,
            "{checked} of {}",
            on_floor.len()
        );
        assert!(e
            .iter()
            .enumerate()
            .all(|(k, e)| samples.side[k] == side || *e == DVec3::ZERO));
    }
}
