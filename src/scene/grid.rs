//! Calculation surfaces (`docs/scene-format.md`, "Grids"): rectangles of points floating in the
//! scene where illuminance is measured, on a small surface facing `normal`.

use glam::Vec3;

/// The most points one grid may have.
pub const MAX_GRID_POINTS: u64 = 10_000_000;

/// A grid of measuring points: the centres of an n_u × n_v grid of equal cells. Made by
/// [`Grid::new`], which checks it; read through its accessors.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub(crate) name: String,
    pub(crate) origin: Vec3,
    pub(crate) u: Vec3,
    pub(crate) v: Vec3,
    pub(crate) normal: Vec3,
    pub(crate) spacing: f32,
    pub(crate) n_u: u32,
    pub(crate) n_v: u32,
    /// What the task area must reach: the average Ēm (the scene's irradiance unit) and the
    /// uniformity U0 = Emin / Ēm.
    pub(crate) target_em: Option<f64>,
    pub(crate) target_u0: Option<f64>,
    pub(crate) target_df: Option<f64>,
    pub(crate) target_df_median: Option<f64>,
}

impl Grid {
    /// A grid named `name` over the rectangle `origin` + s·u + t·v (s, t in [0, 1]), measuring
    /// on a surface facing `normal` (default u × v), with cells of `spacing` (default
    /// [`Grid::default_spacing`]). What is wrong, in words naming the key: a non-finite or
    /// out-of-range corner or edge, an edge of zero length, parallel edges, a normal that is
    /// no direction, a spacing that is not a positive length or makes more than
    /// [`MAX_GRID_POINTS`] points.
    pub fn new(
        name: impl Into<String>,
        origin: Vec3,
        u: Vec3,
        v: Vec3,
        normal: Option<Vec3>,
        spacing: Option<f32>,
    ) -> Result<Grid, String> {
        for (key, value) in [("origin", origin), ("u", u), ("v", v)] {
            if let Some(problem) = super::validate::position(value) {
                return Err(format!("{key}: {problem}"));
            }
        }
        for (key, edge) in [("u", u), ("v", v)] {
            if edge.length_squared() <= 0.0 {
                return Err(format!("{key} has zero length"));
            }
        }
        let cross = u.cross(v);
        if cross.length() <= 1e-6 * u.length() * v.length() {
            return Err(format!("u {u} is parallel to v {v}"));
        }
        let normal = normal.unwrap_or(cross);
        if !normal.is_finite() || normal.length_squared() <= 0.0 {
            return Err(format!("normal {normal} is not a direction"));
        }
        let spacing = spacing.unwrap_or_else(|| Grid::default_spacing(u, v));
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(format!("spacing {spacing} must be a positive length"));
        }
        let Some((n_u, n_v)) = Grid::counts(u, v, spacing) else {
            return Err(format!(
                "spacing {spacing} would make more than {MAX_GRID_POINTS} points"
            ));
        };
        Ok(Grid {
            name: name.into(),
            origin,
            u,
            v,
            normal: normal.normalize(),
            spacing,
            n_u,
            n_v,
            target_em: None,
            target_u0: None,
            target_df: None,
            target_df_median: None,
        })
    }

    /// The grid with targets (`docs/scene-format.md`, "Grid targets"): the average Ēm it must
    /// reach, a positive illuminance, and the uniformity U0 = Emin / Ēm, in (0, 1].
    pub fn with_targets(mut self, em: Option<f64>, u0: Option<f64>) -> Result<Grid, String> {
        if let Some(em) = em {
            if !(em.is_finite() && em > 0.0) {
                return Err(format!("target_em {em} must be a positive illuminance"));
            }
        }
        if let Some(u0) = u0 {
            if !(u0 > 0.0 && u0 <= 1.0) {
                return Err(format!(
                    "target_u0 {u0} must be a uniformity in (0, 1]: Emin / Em"
                ));
            }
        }
        self.target_em = em;
        self.target_u0 = u0;
        Ok(self)
    }

    /// The average illuminance Ēm the grid must reach, if it has a target.
    pub fn target_em(&self) -> Option<f64> {
        self.target_em
    }

    /// The uniformity Emin / Ēm the grid must reach, if it has a target.
    pub fn target_u0(&self) -> Option<f64> {
        self.target_u0
    }

    /// The grid with daylight-factor targets (%): the average and the median it must reach.
    pub fn with_df_targets(
        mut self,
        average: Option<f64>,
        median: Option<f64>,
    ) -> Result<Grid, String> {
        for (name, value) in [("target_df", average), ("target_df_median", median)] {
            if let Some(v) = value {
                if !(v.is_finite() && v > 0.0 && v <= 100.0) {
                    return Err(format!(
                        "{name} {v} must be a daylight factor in (0, 100] %"
                    ));
                }
            }
        }
        self.target_df = average;
        self.target_df_median = median;
        Ok(self)
    }

    /// The average daylight factor (%) the grid must reach, if it has a target.
    pub fn target_df(&self) -> Option<f64> {
        self.target_df
    }

    /// The median daylight factor (%) the grid must reach, if it has a target.
    pub fn target_df_median(&self) -> Option<f64> {
        self.target_df_median
    }

    /// Its name, unique in the scene.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// One corner.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// The two edges (direction and length).
    pub fn edges(&self) -> (Vec3, Vec3) {
        (self.u, self.v)
    }

    /// The direction the measuring surface faces (unit length).
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// The cell size.
    pub fn spacing(&self) -> f32 {
        self.spacing
    }

    /// Cells (points) along each edge: ⌈|u| / spacing⌉ and ⌈|v| / spacing⌉.
    pub fn counts_uv(&self) -> (u32, u32) {
        (self.n_u, self.n_v)
    }

    /// The default spacing from EN 12464-1 (`docs/scene-format.md`, "Grids"): p = 0.2 · 5^log10(d), d the
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
