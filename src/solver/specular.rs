//! The solve's specular transfer (`docs/method.md` §22): light leaving a diffuse sample that
//! reaches another by way of mirrors, glossy surfaces and glass. Each sample's chains
//! (`specular::gather`) end at points on surfaces with samples; interpolating the samples at
//! those points turns them into a sparse matrix G — the irradiance a receiver gets per unit
//! radiosity of each sample — which the shooting applies beside its links, to the unshot
//! radiosity it shoots. The chains' ends do not depend on the samples, so they are followed
//! once per sample; G is rebuilt every round, as adaptive samples change the interpolation.

use glam::{DVec3, Vec3};

use super::Solution;
use crate::error::Result;
use crate::render::interpolate::{Interpolator, Site};
use crate::scene::Scene;
use crate::specular::gather::{Chains, End};
use crate::specular::highlight::Highlights;
use crate::specular::lights::Lights;
use crate::specular::Specular;
use crate::visibility::Visibility;

/// The specular transfer of a solution.
#[derive(Clone, Debug, Default)]
pub(crate) struct Transfer {
    /// Where every sample's chains end (receiver: the sample).
    pub ends: Vec<End>,
    /// Per sample: irradiance from the lights by way of glossy bounces.
    pub direct: Vec<DVec3>,
    /// G by receiver (compressed rows): row i is `entries[starts[i]..starts[i + 1]]`, each
    /// (sample, irradiance at i per unit radiosity of the sample, RGB).
    starts: Vec<u32>,
    entries: Vec<(u32, [f32; 3])>,
    /// G by shooter (its transpose), for the flat solver.
    column_starts: Vec<u32>,
    columns: Vec<(u32, [f32; 3])>,
    /// Per shooter: the flux its unit radiosity delivers through G, Σᵢ Gᵢⱼ Sᵢ.
    pub column_flux: Vec<DVec3>,
}

fn rgb(w: [f32; 3]) -> DVec3 {
    Vec3::from(w).as_dvec3()
}

impl Transfer {
    /// Follows the chains of samples `first..` of `solution` and keeps their ends and direct
    /// light; returns the queries.
    pub(crate) fn follow(
        &mut self,
        scene: &Scene,
        solution: &Solution,
        vis: &dyn Visibility,
        (spec, lights): (&Specular, &Lights),
        (depth, rays, seed, threads): (u32, u32, u64, usize),
        first: usize,
    ) -> Result<u64> {
        let s = &solution.samples;
        let n = s.len();
        let interpolator = Interpolator::new(scene, solution, vis);
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
        let mut queries = 0;
        for (c, f) in found.into_iter().enumerate() {
            let base = (first + c * CHUNK) as u32;
            self.ends.extend(f.ends.into_iter().map(|mut e| {
                e.receiver += base;
                e
            }));
            self.direct.extend(f.direct);
            queries += f.queries;
        }
        Ok(queries)
    }

    /// G from the ends, interpolating the samples of `solution` there; returns the queries.
    pub(crate) fn build(
        &mut self,
        scene: &Scene,
        solution: &Solution,
        vis: &dyn Visibility,
    ) -> Result<u64> {
        let s = &solution.samples;
        let n = s.len();
        let interpolator = Interpolator::new(scene, solution, vis).plain();
        let points: Vec<(Vec3, Vec3)> = self.ends.iter().map(|e| (e.point, e.normal)).collect();
        let covered = interpolator.covered(&points)?;
        let sites: Vec<Site> = self
            .ends
            .iter()
            .zip(&covered)
            .map(|(e, &covered)| e.site(covered))
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
            + vec_bytes(&self.starts)
            + vec_bytes(&self.entries)
            + vec_bytes(&self.column_starts)
            + vec_bytes(&self.columns)
            + vec_bytes(&self.column_flux)
    }
}
