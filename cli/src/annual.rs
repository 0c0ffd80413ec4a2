//! `meshlight annual`: a year of weather at a scene's grids, the per-point CSVs and the
//! climate-based metrics (docs/scene-format.md, "A year of weather").

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;
use meshlight::annual::{AnnualOptions, Year};
use meshlight::Scene;

/// Runs the year and writes `DIR/<grid>.csv` (and `DIR/<grid>-hourly.csv` with `hourly`);
/// prints each grid's metrics.
pub fn run(
    scene: &Scene,
    vis: &dyn meshlight::Visibility,
    options: &AnnualOptions,
    dir: &Path,
) -> anyhow::Result<()> {
    year(scene, vis, options, dir).map(|_| ())
}

/// [`run`], answering the year and the lines it printed.
pub fn year(
    scene: &Scene,
    vis: &dyn meshlight::Visibility,
    options: &AnnualOptions,
    dir: &Path,
) -> anyhow::Result<(Year, Vec<String>)> {
    let Some(settings) = scene.annual() else {
        anyhow::bail!(
            "{}: the scene has no [annual] table naming a weather file (docs/scene-format.md, \
             \"A year of weather\")",
            scene.path().display()
        );
    };
    let t = Instant::now();
    let weather = meshlight::daylight::epw::read(&settings.weather)?;
    let reading = t.elapsed().as_secs_f64();
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let t = Instant::now();
    let year = crate::progress::with_progress("a year of daylight", |progress| {
        meshlight::annual::annual(scene, &weather, vis, options, progress)
    })?;
    let seconds = t.elapsed().as_secs_f64();
    if year.stopped {
        eprintln!("meshlight: warning: stopped: the metrics count the hours done");
    }
    if year.left_out > 0 {
        eprintln!(
            "meshlight: warning: {} hours with the sun up have no diffuse light in {}: left out \
             of the metrics",
            year.left_out,
            settings.weather.display()
        );
    }
    let site = &weather.site;
    let mut lines = vec![format!(
        "weather {} ({}, {:.2}°, {:.2}°, UTC{:+}): {} hours with the sun up, occupied hours \
         {}-{}",
        settings.weather.display(),
        site.name,
        settings.site.latitude.unwrap_or(site.latitude),
        settings.site.longitude.unwrap_or(site.longitude),
        settings.site.timezone.unwrap_or(site.timezone),
        year.sun_hours.len(),
        settings.hours.0,
        settings.hours.1
    )];
    for (g, grid) in year.grids.iter().zip(scene.grids()) {
        write_grid(g, &grid.file_stem(), &year, dir, options.hourly)?;
        lines.push(summary(g));
    }
    let peak = crate::memory::peak_bytes()
        .map(|b| format!(", peak memory {}", crate::units::bytes(b as f64)))
        .unwrap_or_default();
    lines.push(format!(
        "year: {} samples, {} coefficients a point ({} sky patches + ground, {} sun positions), \
         coefficients {}; weather read in {reading:.2} s, the year in {seconds:.2} s{peak}",
        year.samples,
        year.bases,
        year.bases
            .saturating_sub(1 + meshlight::annual::SUN_POSITIONS),
        meshlight::annual::SUN_POSITIONS,
        crate::units::bytes(year.coefficient_bytes as f64),
    ));
    for line in &lines {
        println!("{line}");
    }
    Ok((year, lines))
}

/// Each grid's plans of DA, UDI and yearly exposure: `DIR/<grid>-da.png`, `-udi.png` and
/// `-exposure.png`.
pub fn plans(
    scene: &Scene,
    year: &Year,
    dir: &Path,
) -> anyhow::Result<Vec<[std::path::PathBuf; 3]>> {
    let mut out = Vec::new();
    for (g, grid) in year.grids.iter().zip(scene.grids()) {
        let stem = grid.file_stem();
        let (nu, nv) = grid.counts_uv();
        let (u, v) = grid.edges();
        let excluded: Vec<bool> = g.metrics.iter().map(Option::is_none).collect();
        let pick = |f: &dyn Fn(&meshlight::annual::PointYear) -> f64| -> Vec<f64> {
            g.metrics
                .iter()
                .map(|m| m.as_ref().map_or(0.0, f))
                .collect()
        };
        let s = &g.summary;
        let maps = [
            (
                "da",
                pick(&|m| m.da),
                "%",
                "DA (% of occupied hours)".to_string(),
                vec![format!("sDA300/50% {:.1}%", s.sda)],
            ),
            (
                "udi",
                pick(&|m| m.udi),
                "%",
                "UDI 100-3000 lx (%)".to_string(),
                vec![format!("ASE1000,250h {:.1}%", s.ase)],
            ),
            (
                "exposure",
                pick(&|m| m.exposure / 1000.0),
                "klx·h",
                "exposure (klx·h a year)".to_string(),
                vec![format!("largest {:.0} klx·h", s.max_exposure / 1000.0)],
            ),
        ];
        let mut paths = Vec::new();
        for (suffix, values, unit, title, caption) in &maps {
            let path = dir.join(format!("{stem}-{suffix}.png"));
            crate::plan::plan_png(
                &path,
                &crate::plan::Plan {
                    counts: (nu, nv),
                    values,
                    excluded: &excluded,
                    spacing: (
                        f64::from(u.length()) / f64::from(nu),
                        f64::from(v.length()) / f64::from(nv),
                    ),
                    marks: &[],
                    outline: &crate::lux::cut(scene, grid),
                    unit,
                    title,
                    caption,
                },
            )?;
            paths.push(path);
        }
        out.push([paths[0].clone(), paths[1].clone(), paths[2].clone()]);
    }
    Ok(out)
}

/// A grid's line: sDA, ASE, EN 17037 and the largest exposure.
pub fn summary(g: &meshlight::annual::GridYear) -> String {
    let s = &g.summary;
    format!(
        "grid '{}': {} points, {} occupied hours: sDA300/50% {:.1}%, ASE1000,250h {:.1}%, \
         EN 17037 300 lx over half the grid in {:.1}% of {} daylight hours: {}; largest \
         exposure {:.0} lx·h",
        g.name,
        s.points,
        s.occupied_hours,
        s.sda,
        s.ase,
        s.en17037_hours,
        s.daylight_hours,
        if s.en17037_met { "met" } else { "not met" },
        s.max_exposure
    ) + &match meshlight::annual::metrics::cie157_class(s.max_exposure) {
        Some(class) => format!(" (within CIE 157's yearly limit for {class}-responsivity objects)"),
        None => " (beyond CIE 157's yearly limits: for light-irresponsive objects only)".into(),
    }
}

/// `DIR/<name>.csv` (and the hourly CSV).
fn write_grid(
    g: &meshlight::annual::GridYear,
    file: &str,
    year: &Year,
    dir: &Path,
    hourly: bool,
) -> anyhow::Result<()> {
    let path = dir.join(format!("{file}.csv"));
    let mut text = String::from("x,y,z,DA,UDI,sun_hours,exposure\n");
    for (p, m) in g.points.iter().zip(&g.metrics) {
        match m {
            Some(m) => writeln!(
                text,
                "{},{},{},{:.2},{:.2},{},{:.0}",
                p.x, p.y, p.z, m.da, m.udi, m.sun_hours, m.exposure
            )?,
            // Inside a solid: no light, no metric.
            None => writeln!(text, "{},{},{},,,,", p.x, p.y, p.z)?,
        }
    }
    std::fs::write(&path, text).with_context(|| format!("{}: cannot write", path.display()))?;
    if hourly {
        let path = dir.join(format!("{file}-hourly.csv"));
        let f = std::fs::File::create(&path)
            .with_context(|| format!("{}: cannot write", path.display()))?;
        let mut w = std::io::BufWriter::new(f);
        writeln!(w, "month,day,hour,x,y,z,E")?;
        let n = g.points.len();
        for (h, stamp) in year.sun_hours.iter().enumerate() {
            for (i, p) in g.points.iter().enumerate() {
                let e = g.hourly[h * n + i];
                writeln!(
                    w,
                    "{},{},{},{},{},{},{:.1}",
                    stamp.month, stamp.day, stamp.hour, p.x, p.y, p.z, e
                )?;
            }
        }
        w.flush()
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(())
}
