//! `meshlight report`: one self-contained HTML page a lighting designer can hand in — the
//! lights, every grid with its targets met or missed, the isolux plans, the rendered view and
//! how it was computed. Images are embedded (PNG as base64 `data:` URIs); no script, no
//! network; each section starts a printed page.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use meshlight::scene::luminance;
use meshlight::{Scene, Solution};

use super::lux::Measured;
use super::plan::round_label;

/// What the page shows besides the scene and its grids.
pub struct Extras<'a> {
    /// The rendered view as PNG bytes: tone-mapped radiance, then its luminance in false
    /// colour.
    pub views: Vec<Vec<u8>>,
    /// The solve's summary as the command line printed it.
    pub summary: &'a str,
    /// Seconds the solve, the grids and the view took.
    pub seconds: (f64, f64, f64),
    /// A year of weather, where the scene has `[annual]`.
    pub annual: Option<AnnualPage>,
}

/// A year of weather as the page shows it.
pub struct AnnualPage {
    /// The lines `meshlight annual` printed (the weather first).
    pub lines: Vec<String>,
    /// The year.
    pub year: meshlight::annual::Year,
    /// Per grid, its DA, UDI and exposure plans.
    pub plans: Vec<[std::path::PathBuf; 3]>,
}

/// Writes `DIR/index.html`; answers its path.
pub fn write(
    dir: &Path,
    scene: &Scene,
    solution: &Solution,
    grids: &[Measured],
    extras: &Extras,
) -> Result<std::path::PathBuf> {
    let html = page(scene, solution, grids, extras)?;
    let path = dir.join("index.html");
    std::fs::write(&path, html).with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(path)
}

fn page(scene: &Scene, solution: &Solution, grids: &[Measured], extras: &Extras) -> Result<String> {
    let mut h = String::new();
    header(&mut h, scene)?;
    lights_section(&mut h, scene)?;
    grids_section(&mut h, scene, grids)?;
    if grids.iter().any(|g| !g.daylight.is_empty()) {
        daylight_section(&mut h, grids)?;
    }
    if let Some(annual) = &extras.annual {
        annual_section(&mut h, annual)?;
    }
    plans_section(&mut h, grids)?;
    if !extras.views.is_empty() {
        views_section(&mut h, extras)?;
    }
    method_section(&mut h, solution, extras)?;
    writeln!(h, "</body>\n</html>")?;
    Ok(h)
}

/// The document's head and the page's title block.
fn header(h: &mut String, scene: &Scene) -> Result<()> {
    let units = scene.units();
    let flux = units.flux();
    let name = escape(&scene.path().display().to_string());
    writeln!(
        h,
        "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>Lighting report: {name}</title>\n<style>\n{STYLE}</style>\n</head>\n<body>"
    )?;
    writeln!(
        h,
        "<header><h1>Lighting report</h1><p>Scene <code>{name}</code>: {} triangles, {} \
         surfaces; {} units. Computed by meshlight {} (meshless radiosity with ray-cast \
         visibility).</p></header>",
        scene.triangles().len(),
        scene.surfaces().len(),
        if flux == "lm" {
            "photometric"
        } else {
            "radiometric"
        },
        env!("CARGO_PKG_VERSION"),
    )?;

    Ok(())
}

/// Lights: luminaires (one row per file and tint), point lights, area lights, with their flux.
fn lights_section(h: &mut String, scene: &Scene) -> Result<()> {
    let flux = scene.units().flux();
    writeln!(h, "<section id=\"luminaires\"><h2>Luminaire schedule</h2>")?;
    writeln!(
        h,
        "<table id=\"luminaire-table\"><thead><tr><th>light</th><th>position</th><th>aim</th>\
         <th>flux ({flux})</th></tr></thead><tbody>"
    )?;
    let v3 = |v: glam::Vec3| {
        format!(
            "{}, {}, {}",
            round_label(v.x.into()),
            round_label(v.y.into()),
            round_label(v.z.into())
        )
    };
    // Luminaires of one file (and one tint) in one row: how many, where, and each one's flux.
    let mut kinds: Vec<(String, Vec<&meshlight::scene::Luminaire>)> = Vec::new();
    for l in scene.luminaires() {
        let key = format!("{}|{:?}", l.photometry.source, l.tint);
        match kinds.iter_mut().find(|(k, _)| *k == key) {
            Some((_, ls)) => ls.push(l),
            None => kinds.push((key, vec![l])),
        }
    }
    for (_, ls) in &kinds {
        let first = ls[0];
        let watts = first.photometry.input_watts.map_or(String::new(), |w| {
            format!(", {} W input each", round_label(w))
        });
        let at: Vec<String> = ls.iter().map(|l| format!("({})", v3(l.position))).collect();
        let aims: Vec<String> = ls.iter().map(|l| format!("({})", v3(l.aim))).collect();
        writeln!(
            h,
            "<tr><td>{} × {}{watts}</td><td>{}</td><td>{}</td><td>{} each</td></tr>",
            ls.len(),
            escape(&first.photometry.source),
            at.join("<br>"),
            aims.join("<br>"),
            round_label(luminance(first.flux().as_vec3()).into())
        )?;
    }
    for (i, l) in scene.point_lights().iter().enumerate() {
        let f = luminance(l.power().as_vec3());
        writeln!(
            h,
            "<tr><td>point light {}</td><td>{}</td><td>all round</td><td>{}</td></tr>",
            i + 1,
            v3(l.position),
            round_label(f.into())
        )?;
    }
    for (s, power) in scene.emitters() {
        let m = &scene.materials()[scene.surfaces()[s as usize].material as usize];
        writeln!(
            h,
            "<tr><td>area light '{}' (surface {s})</td><td>—</td><td>its normal</td><td>{}</td></tr>",
            escape(&m.name),
            round_label(luminance(power.as_vec3()).into())
        )?;
    }
    writeln!(h, "</tbody></table></section>")?;

    Ok(())
}

/// Every grid's figures against its targets.
fn grids_section(h: &mut String, scene: &Scene, grids: &[Measured]) -> Result<()> {
    let lux = scene.units().irradiance();
    writeln!(h, "<section id=\"grids\"><h2>Calculation grids</h2>")?;
    writeln!(
        h,
        "<table id=\"grid-table\"><thead><tr><th>grid</th><th>points</th><th>Emin ({lux})</th>\
         <th>Ēm ({lux})</th><th>Emax ({lux})</th><th>U0</th><th>Emin/Emax</th>\
         <th>target Ēm</th><th>target U0</th><th>result</th></tr></thead><tbody>"
    )?;
    for g in grids {
        let s = &g.summary;
        let (class, result) = match &g.verdict {
            None => ("", "no target".to_string()),
            Some(v) if v.starts_with("meets") => ("pass", v.clone()),
            Some(v) => ("fail", v.clone()),
        };
        let target = |t: Option<f64>| t.map_or("—".to_string(), round_label);
        writeln!(
            h,
            "<tr data-em=\"{}\"><td>{}</td><td>{}{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.2}</td>\
             <td>{:.2}</td><td>{}</td><td>{}</td><td class=\"{class}\">{}</td></tr>",
            s.avg,
            escape(&g.name),
            g.points,
            if g.left_out > 0 {
                format!(" ({} in solids)", g.left_out)
            } else {
                String::new()
            },
            round_label(s.min),
            round_label(s.avg),
            round_label(s.max),
            s.uniformity(),
            s.diversity(),
            target(g.target_em),
            target(g.target_u0),
            escape(&result)
        )?;
    }
    writeln!(h, "</tbody></table>")?;
    writeln!(
        h,
        "<p>Points inside solids are left out of Emin, Ēm and Emax and hatched on the plans. \
         Each grid's values are in <code>{}</code> beside this page.</p></section>",
        grids
            .iter()
            .map(|g| escape(&file_name(&g.csv)))
            .collect::<Vec<_>>()
            .join(", ")
    )?;

    Ok(())
}

/// The daylight factor, where the sky is overcast or uniform: each grid's verdicts and plan.
fn daylight_section(h: &mut String, grids: &[Measured]) -> Result<()> {
    writeln!(h, "<section id=\"daylight\"><h2>Daylight factor</h2><ul>")?;
    for g in grids {
        for said in &g.daylight {
            let class = if said.contains("NOT met") || said.starts_with("no daylight") {
                " class=\"fail\""
            } else if said.contains(": met") {
                " class=\"pass\""
            } else {
                ""
            };
            writeln!(h, "<li{class}>{}: {}</li>", escape(&g.name), escape(said))?;
        }
    }
    writeln!(
        h,
        "</ul><p>DF = E / E<sub>h</sub>, E<sub>h</sub> the sky's illuminance on an \
             unobstructed horizontal plane.</p>"
    )?;
    for g in grids {
        let Some(path) = &g.df_png else { continue };
        let png =
            std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
        writeln!(
            h,
            "<figure><img alt=\"daylight factor plan of {n}\" \
                 src=\"data:image/png;base64,{}\"><figcaption>{n}: daylight factor, \
                 iso-lines at round values (%)</figcaption></figure>",
            base64(&png),
            n = escape(&g.name)
        )?;
    }
    writeln!(h, "</section>")?;
    Ok(())
}

/// Each grid's isolux plan.
fn plans_section(h: &mut String, grids: &[Measured]) -> Result<()> {
    writeln!(h, "<section id=\"plans\"><h2>Isolux plans</h2>")?;
    for g in grids {
        let png =
            std::fs::read(&g.png).with_context(|| format!("{}: cannot read", g.png.display()))?;
        writeln!(
            h,
            "<figure><img alt=\"isolux plan of {n}\" src=\"data:image/png;base64,{}\">\
             <figcaption>{n}: iso-lines at round values, to scale (axes in metres)</figcaption></figure>",
            base64(&png),
            n = escape(&g.name)
        )?;
    }
    writeln!(h, "</section>")?;

    Ok(())
}

/// The rendered view: tone-mapped, then its luminance in false colour.
fn views_section(h: &mut String, extras: &Extras) -> Result<()> {
    writeln!(h, "<section id=\"views\"><h2>Rendered view</h2>")?;
    let captions = [
        "The camera's view, radiance tone-mapped to sRGB.",
        "The same view's luminance in false colour.",
    ];
    for (view, caption) in extras.views.iter().zip(captions) {
        writeln!(
            h,
            "<figure><img alt=\"{caption}\" src=\"data:image/png;base64,{}\">\
                 <figcaption>{caption}</figcaption></figure>",
            base64(view)
        )?;
    }
    writeln!(h, "</section>")?;
    Ok(())
}

/// How it was computed: the samples, the times, the solve's summary, and where the accuracy is
/// measured.
fn method_section(h: &mut String, solution: &Solution, extras: &Extras) -> Result<()> {
    let (solve, measure, view) = extras.seconds;
    writeln!(
        h,
        "<section id=\"method\"><h2>How it was computed</h2><p>{} samples (ε {}); solve {} s, \
         grids {} s, view {} s.</p><pre>{}</pre><p>Accuracy: meshlight's illuminance on grids \
         agrees with Radiance within 0.3–0.8% per point on three rooms, and its images with \
         Mitsuba 3 and Blender's Cycles within their noise on the rooms checked; see \
         <code>docs/validation.md</code> in meshlight's repository for how each was \
         measured.</p></section>",
        solution.samples().len(),
        round_label(solution.epsilon().into()),
        round_label(solve),
        round_label(measure),
        round_label(view),
        escape(extras.summary.trim_end())
    )?;
    Ok(())
}

/// The year: the weather, each grid's climate-based metrics and verdicts, and its plans.
fn annual_section(h: &mut String, annual: &AnnualPage) -> Result<()> {
    use meshlight::annual::metrics::cie157_class;
    writeln!(
        h,
        "<section id=\"annual\"><h2>A year of daylight</h2><p>{}</p>",
        escape(annual.lines.first().map_or("", String::as_str))
    )?;
    writeln!(
        h,
        "<table id=\"annual-table\"><thead><tr><th>grid</th><th>points</th>\
         <th>sDA300/50%</th><th>ASE1000,250h</th><th>EN 17037 (300 lx, half the grid, half \
         the daylight hours)</th><th>largest exposure (lx·h a year)</th><th>CIE 157</th>\
         </tr></thead><tbody>"
    )?;
    for g in &annual.year.grids {
        let s = &g.summary;
        let (class, verdict) = if s.en17037_met {
            (
                "pass",
                format!(
                    "met ({:.1}% of {} hours)",
                    s.en17037_hours, s.daylight_hours
                ),
            )
        } else {
            (
                "fail",
                format!(
                    "not met ({:.1}% of {} hours)",
                    s.en17037_hours, s.daylight_hours
                ),
            )
        };
        let cie = match cie157_class(s.max_exposure) {
            Some(c) => format!("within the limit for {c}-responsivity objects"),
            None => "beyond every limit: light-irresponsive objects only".to_string(),
        };
        writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{:.1}%</td><td>{:.1}%</td><td class=\"{class}\">{}</td>\
             <td>{}</td><td>{}</td></tr>",
            escape(&g.name),
            s.points,
            s.sda,
            s.ase,
            verdict,
            round_label(s.max_exposure),
            cie
        )?;
    }
    writeln!(
        h,
        "</tbody></table><p>DA: the share of occupied hours a point reaches its target (300 lx \
         unless the grid sets <code>target_em</code>); sDA: the share of points with DA ≥ 50% \
         (IES LM-83); ASE: the share of points with more than 250 occupied hours of direct sun \
         ≥ 1000 lx; UDI: the share of occupied hours within 100-3000 lx; exposure: lux-hours \
         over the whole year, against CIE 157's limits of 15,000 (high responsivity), 150,000 \
         (medium) and 600,000 lx·h (low).</p>"
    )?;
    let captions = [
        "daylight autonomy (% of occupied hours)",
        "useful daylight illuminance 100-3000 lx (% of occupied hours)",
        "yearly exposure (klx·h)",
    ];
    for (g, plans) in annual.year.grids.iter().zip(&annual.plans) {
        for (path, caption) in plans.iter().zip(captions) {
            let png =
                std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
            writeln!(
                h,
                "<figure><img alt=\"{caption} of {n}\" src=\"data:image/png;base64,{}\">\
                 <figcaption>{n}: {caption}</figcaption></figure>",
                base64(&png),
                n = escape(&g.name)
            )?;
        }
    }
    writeln!(h, "</section>")?;
    Ok(())
}

const STYLE: &str =
    "body { font-family: sans-serif; max-width: 62em; margin: 2em auto; color: #222; }
table { border-collapse: collapse; margin: 1em 0; }
th, td { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: right; }
th:first-child, td:first-child { text-align: left; }
td.fail { color: #a00; font-weight: bold; text-align: left; }
td.pass { color: #060; text-align: left; }
figure { margin: 1em 0; }
img { max-width: 100%; }
pre { font-size: 0.8em; white-space: pre-wrap; }
section { break-before: page; }
";

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// Text for HTML: `&`, `<`, `>` and `"` escaped.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Standard base64 with padding (RFC 4648).
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648() {
        // RFC 4648, section 10.
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
        assert_eq!(escape("a<b & \"c\">"), "a&lt;b &amp; &quot;c&quot;&gt;");
    }
}
