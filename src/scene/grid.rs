//! Calculation surfaces (scene-format.md, "Grids"): rectangles of points floating in the
//! scene where illuminance is measured, on a small surface facing `normal`.

use glam::Vec3;

/// The most points one grid may have.
pub const MAX_GRID_POINTS: u64 = 10_000_000;

/// A grid of measuring points: the centres of an n_u × n_v grid of equal cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Its name, unique in the scene.
    pub name: String,
    /// One corner.
    pub origin: Vec3,
    /// The first edge (direction and length).
    pub u: Vec3,
    /// The second edge.
    pub v: Vec3,
    /// The direction the measuring surface faces (unit length).
    pub normal: Vec3,
    /// The cell size asked for.
    pub spacing: f32,
    /// Cells along `u`: ⌈|u| / spacing⌉.
    pub n_u: u32,
    /// Cells along `v`.
    pub n_v: u32,
}

impl Grid {
    /// The default spacing from EN 12464-1 (as the spec gives it): p = 0.2 · 5^log10(d), d the
    /// longer edge.
    pub fn default_spacing(u: Vec3, v: Vec3) -> f32 {
        let d = u.length().max(v.length());
        0.2 * 5f32.powf(d.log10())
    }

    /// The cell counts for `spacing`, or None past [`MAX_GRID_POINTS`]. A ratio a hair above a
    /// whole number from rounding (0.6 / 0.2 in 32 bits) counts as that number.
    pub fn counts(u: Vec3, v: Vec3, spacing: f32) -> Option<(u32, u32)> {
        let n = |e: Vec3| {
            let cells = f64::from(e.length()) / f64::from(spacing);
            (cells * (1.0 - 1e-6)).ceil().max(1.0)
        };
        let (nu, nv) = (n(u), n(v));
        (nu * nv <= MAX_GRID_POINTS as f64).then_some((nu as u32, nv as u32))
    }

    /// The points, row by row along `u` (index i_v · n_u + i_u).
    pub fn points(&self) -> Vec<Vec3> {
        let (nu, nv) = (self.n_u as usize, self.n_v as usize);
        let mut out = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                let s = (i as f32 + 0.5) / nu as f32;
                let t = (j as f32 + 0.5) / nv as f32;
                out.push(self.origin + s * self.u + t * self.v);
            }
        }
        out
    }

    /// The grid's name as a file name: every character but letters, digits, `-` and `_` as `_`.
    pub fn file_stem(&self) -> String {
        self.name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    }
}
