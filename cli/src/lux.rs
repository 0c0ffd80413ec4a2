//! `meshlight lux`: solve, then measure illuminance at every grid's points; per grid a CSV
//! (`x,y,z,E,in_solid`), an isolux plan, and a summary line.

use std::io::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use meshlight::lux::{illuminance, LuxOptions};
use meshlight::scene::luminance;
use meshlight::{Scene, Solution, Visibility};

use super::plan::{round_label, Plan};

/// One grid's numbers: Emin, Eavg, Emax (luminance-weighted).
pub struct Summary {
    /// The smallest.
    pub min: f64,
    /// The mean.
    pub avg: f64,
    /// The largest.
    pub max: f64,
}

impl Summary {
    /// Over `values`; all zero when there are none (every point inside a solid).
    fn of(values: &[f64]) -> Summary {
        if values.is_empty() {
            return Summary {
                min: 0.0,
                avg: 0.0,
                max: 0.0,
            };
        }
        let min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let avg = values.iter().sum::<f64>() / values.len().max(1) as f64;
        Summary { min, avg, max }
    }

    /// Emin / Eavg.
    pub fn uniformity(&self) -> f64 {
        if self.avg > 0.0 {
            self.min / self.avg
        } else {
            0.0
        }
    }

    /// Emin / Emax.
    pub fn diversity(&self) -> f64 {
        if self.max > 0.0 {
            self.min / self.max
        } else {
            0.0
        }
    }
}

/// One grid measured: what `lux` prints and `report` tabulates.
pub struct Measured {
    /// The grid's name.
    pub name: String,
    /// Its points, and how many of them lie inside solids (left out).
    pub points: usize,
    pub left_out: usize,
    /// Emin, Eavg, Emax over the points left in.
    pub summary: Summary,
    /// Its targets, and whether they are met ("meets …" / "does NOT meet …").
    pub target_em: Option<f64>,
    pub target_u0: Option<f64>,
    pub verdict: Option<String>,
    /// Under an overcast or uniform sky: its daylight factor and its targets' verdicts (and a
    /// warning where no daylight reaches it).
    pub daylight: Vec<String>,
    /// Its daylight-factor plan, where the sky is overcast or uniform.
    pub df_png: Option<std::path::PathBuf>,
    /// The CSV and the plan written.
    pub csv: std::path::PathBuf,
    pub png: std::path::PathBuf,
}

/// Measures every grid, writing `DIR/<name>.csv` and `DIR/<name>.png` and printing a line per
/// grid.
pub fn run(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    options: &LuxOptions,
    dir: &Path,
) -> Result<()> {
    measure(scene, solution, vis, options, dir).map(|_| ())
}

/// As [`run`], answering what it measured.
pub fn measure(
    scene: &Scene,
    solution: &Solution,
    vis: &dyn Visibility,
    options: &LuxOptions,
    dir: &Path,
) -> Result<Vec<Measured>> {
    if scene.grids().is_empty() {
        anyhow::bail!(
            "{}: the scene has no [[grid]] to measure (docs/scene-format.md, \"Grids\")",
            scene.path().display()
        );
    }
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let unit = scene.units().irradiance();
    let mut measured = Vec::new();
    for grid in scene.grids() {
        let started = Instant::now();
        let points = grid.points();
        let what = format!("grid '{}', {} points", grid.name(), points.len());
        let e = crate::progress::with_progress(&what, |progress| {
            illuminance(scene, solution, vis, grid, options, progress)
        })?;
        let values: Vec<f64> = e
            .values
            .iter()
            .map(|v| f64::from(luminance(v.as_vec3())))
            .collect();
        let inside = meshlight::lux::enclosed(scene, vis, grid)?;
        let open: Vec<f64> = values
            .iter()
            .zip(&inside)
            .filter(|(_, &i)| !i)
            .map(|(v, _)| *v)
            .collect();
        let left_out = values.len() - open.len();
        let stem = grid.file_stem();
        let csv = dir.join(format!("{stem}.csv"));
        write_csv(&csv, &points, &values, &inside)?;
        let s = Summary::of(&open);
        let line = format!(
            "grid '{}': {} points{}, Emin {} {unit}, Eavg {} {unit}, Emax {} {unit}, U0 = Emin/Eavg {:.2}, Emin/Emax {:.2}; {:.2} s",
            grid.name(),
            values.len(),
            if left_out > 0 {
                format!(" ({left_out} inside solids left out)")
            } else {
                String::new()
            },
            round_label(s.min),
            round_label(s.avg),
            round_label(s.max),
            s.uniformity(),
            s.diversity(),
            started.elapsed().as_secs_f64()
        );
        let png = dir.join(format!("{stem}.png"));
        isolux_plan(&png, scene, grid, &values, &inside, &s)?;
        println!("{line}");
        let verdict = targets(grid.target_em(), grid.target_u0(), &s, unit);
        if let Some(verdict) = &verdict {
            println!("grid '{}': {verdict}", grid.name());
        }
        let daylight = daylight_factor(scene, grid, &open);
        for said in &daylight {
            println!("grid '{}': {said}", grid.name());
        }
        // The same plan in daylight factor, where it is defined.
        let df_png = match df_sky(scene) {
            Some(eh) => {
                let path = dir.join(format!("{stem}-df.png"));
                df_plan(&path, scene, grid, &values, &inside, eh, &daylight)?;
                Some(path)
            }
            None => None,
        };
        println!("wrote {} and {}", csv.display(), png.display());
        measured.push(Measured {
            name: grid.name().to_string(),
            points: values.len(),
            left_out,
            summary: s,
            target_em: grid.target_em(),
            target_u0: grid.target_u0(),
            verdict,
            daylight,
            df_png,
            csv,
            png,
        });
    }
    Ok(measured)
}

/// A grid's values as CSV: x,y,z,E,in_solid.
fn write_csv(csv: &Path, points: &[glam::Vec3], values: &[f64], inside: &[bool]) -> Result<()> {
    let mut out = std::io::BufWriter::new(
        std::fs::File::create(csv).with_context(|| format!("{}: cannot write", csv.display()))?,
    );
    writeln!(out, "x,y,z,E,in_solid")?;
    for ((p, v), &solid) in points.iter().zip(values).zip(inside) {
        writeln!(out, "{},{},{},{v},{}", p.x, p.y, p.z, u8::from(solid))?;
    }
    out.flush()?;
    Ok(())
}

/// A grid's isolux plan, its figures in the caption, the lights over it marked.
fn isolux_plan(
    png: &Path,
    scene: &Scene,
    grid: &meshlight::scene::Grid,
    values: &[f64],
    inside: &[bool],
    s: &Summary,
) -> Result<()> {
    let unit = scene.units().irradiance();
    let (nu, nv) = grid.counts_uv();
    let (u, v) = grid.edges();
    let caption = [
        format!("Emin {} {unit}", round_label(s.min)),
        format!("Eavg {} {unit}", round_label(s.avg)),
        format!("Emax {} {unit}", round_label(s.max)),
        format!("U0 {:.2}", s.uniformity()),
    ];
    super::plan::plan_png(
        png,
        &Plan {
            counts: (nu, nv),
            values,
            excluded: inside,
            spacing: (
                f64::from(u.length()) / f64::from(nu),
                f64::from(v.length()) / f64::from(nv),
            ),
            marks: &lights_over(scene, grid),
            outline: &cut(scene, grid),
            unit,
            title: &format!("{} ({unit})", grid.name()),
            caption: &caption,
        },
    )
}

/// The same plan in daylight factor (%, against the sky's `eh`), its figures from the
/// `daylight` lines in the caption.
fn df_plan(
    path: &Path,
    scene: &Scene,
    grid: &meshlight::scene::Grid,
    values: &[f64],
    inside: &[bool],
    eh: f64,
    daylight: &[String],
) -> Result<()> {
    let (nu, nv) = grid.counts_uv();
    let (u, v) = grid.edges();
    let df: Vec<f64> = values.iter().map(|v| 100.0 * v / eh).collect();
    // "daylight factor min a%, average b%, median c% (E_h …)": a line each.
    let caption: Vec<String> = daylight
        .iter()
        .filter_map(|l| l.strip_prefix("daylight factor "))
        .flat_map(|l| l.split(" (").next().unwrap_or("").split(", "))
        .map(|part| format!("DF {part}"))
        .collect();
    super::plan::plan_png(
        path,
        &Plan {
            counts: (nu, nv),
            values: &df,
            excluded: inside,
            spacing: (
                f64::from(u.length()) / f64::from(nu),
                f64::from(v.length()) / f64::from(nv),
            ),
            marks: &[],
            outline: &cut(scene, grid),
            unit: "%",
            title: &format!("{} (daylight factor, %)", grid.name()),
            caption: &caption,
        },
    )
}

/// E_h of the scene's sky where the daylight factor is defined (an overcast or uniform sky).
fn df_sky(scene: &Scene) -> Option<f64> {
    use meshlight::daylight::SkyModel;
    let d = scene.daylight()?;
    (matches!(d.sky().model(), SkyModel::CieOvercast | SkyModel::Uniform)
        && d.diffuse_horizontal() > 0.0)
        .then(|| d.diffuse_horizontal())
}

/// The daylight factor DF = E / E_h of a grid under an overcast or uniform sky (min, average,
/// median, %), its targets, and a warning where no daylight reaches it.
fn daylight_factor(scene: &Scene, grid: &meshlight::scene::Grid, values: &[f64]) -> Vec<String> {
    use meshlight::daylight::SkyModel;
    let Some(daylight) = scene.daylight() else {
        return Vec::new();
    };
    let mut said = Vec::new();
    let eh = daylight.diffuse_horizontal();
    if values.is_empty() || eh <= 0.0 {
        return said;
    }
    if values.iter().all(|&v| v <= 0.0) && scene.emitted_power().max_element() <= 0.0 {
        said.push(
            "no daylight reaches it: its points see no sky, through no opening and no glass (is \
             the model closed, its glass modelled facing inward, or [site] north or up pointing \
             elsewhere?)"
                .to_string(),
        );
    }
    if !matches!(
        daylight.sky().model(),
        SkyModel::CieOvercast | SkyModel::Uniform
    ) {
        return said;
    }
    let df: Vec<f64> = values.iter().map(|v| 100.0 * v / eh).collect();
    let mut sorted = df.clone();
    sorted.sort_unstable_by(f64::total_cmp);
    let m = sorted.len();
    let median = if m % 2 == 1 {
        sorted[m / 2]
    } else {
        0.5 * (sorted[m / 2 - 1] + sorted[m / 2])
    };
    let average = df.iter().sum::<f64>() / m as f64;
    said.push(format!(
        "daylight factor min {:.2}%, average {:.2}%, median {:.2}% (E_h {} lx){}",
        sorted[0],
        average,
        median,
        round_label(eh),
        if scene.emitted_power().max_element() > 0.0 {
            "; the scene's lamps are counted too"
        } else {
            ""
        }
    ));
    for (name, target, value) in [
        ("average", grid.target_df(), average),
        ("median", grid.target_df_median(), median),
    ] {
        if let Some(t) = target {
            let verdict = if value >= t { "met" } else { "NOT met" };
            said.push(format!(
                "DF {name} {value:.2}% against target {t}%: {verdict}"
            ));
        }
    }
    said
}

/// The point lights and luminaires over a grid, in its coordinates (point (i, j) at (i, j)):
/// their feet on its plane, those that fall on the plan.
fn lights_over(scene: &Scene, grid: &meshlight::scene::Grid) -> Vec<(f64, f64)> {
    let (nu, nv) = grid.counts_uv();
    let (u, v) = grid.edges();
    scene
        .point_sources()
        .iter()
        .filter_map(|light| {
            let d = light.position - grid.origin();
            let x = f64::from(d.dot(u) / u.length_squared()) * f64::from(nu) - 0.5;
            let y = f64::from(d.dot(v) / v.length_squared()) * f64::from(nv) - 0.5;
            let on = |c: f64, n: u32| c >= -0.5 && c <= f64::from(n) - 0.5;
            (on(x, nu) && on(y, nv)).then_some((x, y))
        })
        .collect()
}

/// The scene's triangles cut by a grid's plane, as segments in its coordinates (point (i, j)
/// at (i, j)): what a plan draws of walls and furniture.
pub fn cut(scene: &Scene, grid: &meshlight::scene::Grid) -> Vec<[(f64, f64); 2]> {
    let (nu, nv) = grid.counts_uv();
    let (u, v) = grid.edges();
    let n = u.cross(v).normalize_or_zero();
    let origin = grid.origin();
    let to_grid = |p: glam::Vec3| {
        let d = p - origin;
        (
            f64::from(d.dot(u) / u.length_squared()) * f64::from(nu) - 0.5,
            f64::from(d.dot(v) / v.length_squared()) * f64::from(nv) - 0.5,
        )
    };
    let mut out = Vec::new();
    for t in scene.triangles() {
        let h = t.vertices.map(|p| n.dot(p - origin));
        let mut ends = Vec::with_capacity(2);
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            if (h[a] < 0.0) != (h[b] < 0.0) {
                let s = h[a] / (h[a] - h[b]);
                ends.push(to_grid(t.vertices[a] + s * (t.vertices[b] - t.vertices[a])));
            }
        }
        if let [a, b] = ends[..] {
            out.push([a, b]);
        }
    }
    out
}

/// Whether a grid meets its targets, and by how much: "meets Ēm 500 lx (+12.3%) and U0 0.6
/// (0.71)" or "does NOT meet Ēm 500 lx: 46.1 lx short (-9.2%)". None without targets.
fn targets(em: Option<f64>, u0: Option<f64>, s: &Summary, unit: &str) -> Option<String> {
    let mut met = Vec::new();
    let mut failed = Vec::new();
    if let Some(em) = em {
        let margin = 100.0 * (s.avg / em - 1.0);
        if s.avg >= em {
            met.push(format!("Ēm {em} {unit} ({margin:+.1}%)"));
        } else {
            failed.push(format!(
                "Ēm {em} {unit}: {} {unit} short ({margin:+.1}%)",
                round_label(em - s.avg)
            ));
        }
    }
    if let Some(u0) = u0 {
        let have = s.uniformity();
        if have >= u0 {
            met.push(format!("U0 {u0} ({have:.2})"));
        } else {
            failed.push(format!("U0 {u0}: only {have:.2}"));
        }
    }
    match (met.is_empty(), failed.is_empty()) {
        (true, true) => None,
        (_, true) => Some(format!("meets its targets: {}", met.join(" and "))),
        (true, false) => Some(format!("does NOT meet {}", failed.join("; nor "))),
        (false, false) => Some(format!(
            "does NOT meet {}; meets {}",
            failed.join("; nor "),
            met.join(" and ")
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::{targets, Summary};

    #[test]
    fn targets_met_and_missed_with_their_margins() {
        let s = Summary::of(&[300.0, 500.0, 700.0]);
        // Ēm 500, U0 0.6: the average just meets 500, the uniformity 300/500 just meets 0.6.
        assert_eq!(
            targets(Some(500.0), Some(0.6), &s, "lx").unwrap(),
            "meets its targets: Ēm 500 lx (+0.0%) and U0 0.6 (0.60)"
        );
        // 550 lx asked: 50 short, −9.1%; U0 0.7 asked: only 0.60.
        assert_eq!(
            targets(Some(550.0), Some(0.7), &s, "lx").unwrap(),
            "does NOT meet Ēm 550 lx: 50 lx short (-9.1%); nor U0 0.7: only 0.60"
        );
        assert_eq!(
            targets(Some(400.0), Some(0.7), &s, "lx").unwrap(),
            "does NOT meet U0 0.7: only 0.60; meets Ēm 400 lx (+25.0%)"
        );
        assert_eq!(targets(None, None, &s, "lx"), None);
    }

    #[test]
    fn summaries_by_hand_and_of_nothing() {
        let s = Summary::of(&[1.0, 2.0, 3.0]);
        assert_eq!((s.min, s.avg, s.max), (1.0, 2.0, 3.0));
        assert_eq!((s.uniformity(), s.diversity()), (0.5, 1.0 / 3.0));
        // Every point inside a solid: zeros, not infinities.
        let none = Summary::of(&[]);
        assert_eq!(
            (none.min, none.avg, none.max, none.uniformity()),
            (0.0, 0.0, 0.0, 0.0)
        );
    }
}
