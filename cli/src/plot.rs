//! Pictures with text: false-colour error images with a legend, and error-against-time plots.
//! Drawn with plotters into an RGB buffer and written as PNG by `image`. Text needs a TrueType
//! font, read at run time (Debian's `fonts-dejavu-core`, or the file `MESHLIGHT_FONT` names),
//! so no system font library is linked.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::{anyhow, Context, Result};
use plotters::coord::combinators::{IntoLogRange, LogCoord, WithKeyPoints};
use plotters::prelude::*;
use plotters::style::FontStyle;

/// Where the font is looked for when `MESHLIGHT_FONT` is unset.
const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

/// Registers the font once per process; every later call answers the first one's outcome.
fn font() -> Result<()> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let candidates: Vec<PathBuf> = match std::env::var_os("MESHLIGHT_FONT") {
                Some(p) => vec![PathBuf::from(p)],
                None => FONT_PATHS.iter().map(PathBuf::from).collect(),
            };
            let Some((path, bytes)) = candidates
                .iter()
                .find_map(|p| std::fs::read(p).ok().map(|b| (p, b)))
            else {
                return Err(format!(
                    "no font for the picture's text: looked for {} (install Debian's \
                     fonts-dejavu-core, or name a .ttf file in MESHLIGHT_FONT)",
                    candidates
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            };
            // plotters keeps fonts for the life of the process.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
                .map_err(|_| format!("{} is not a TrueType font", path.display()))
        })
        .clone()
        .map_err(|e| anyhow!(e))
}

pub(crate) fn plot_error<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing failed: {e:?}")
}

/// Writes an RGB buffer as PNG.
fn write_rgb(path: &Path, width: u32, height: u32, rgb: Vec<u8>) -> Result<()> {
    let buffer = image::RgbImage::from_raw(width, height, rgb)
        .ok_or_else(|| anyhow!("picture buffer of the wrong size"))?;
    buffer
        .save_with_format(path, image::ImageFormat::Png)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// A diverging colour map (ColorBrewer's RdBu, reversed): −1 blue, 0 white, +1 red; clamped.
pub fn diverging(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 5] = [
        [33.0, 102.0, 172.0],
        [146.0, 197.0, 222.0],
        [247.0, 247.0, 247.0],
        [244.0, 165.0, 130.0],
        [178.0, 24.0, 43.0],
    ];
    let t = if t.is_finite() {
        t.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let x = (t + 1.0) * 2.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f32;
    let mut out = [0u8; 3];
    for c in 0..3 {
        out[c] = (STOPS[i][c] + (STOPS[i + 1][c] - STOPS[i][c]) * f + 0.5) as u8;
    }
    out
}

/// The smallest 1-2-5 step not below `x` (a legend's range).
pub fn nice_ceiling(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 || x.is_infinite() {
        return 0.01;
    }
    let decade = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|&v| v >= x * (1.0 - 1e-9))
        .unwrap_or(10.0 * decade)
}

/// A signed fraction as a short percentage: 0.025 → "+2.5%", 0 → "0%".
pub fn percent_label(fraction: f64) -> String {
    if fraction == 0.0 {
        return "0%".to_string();
    }
    let text = format!("{:+.3}", 100.0 * fraction);
    format!("{}%", text.trim_end_matches('0').trim_end_matches('.'))
}

/// The drawing area of a picture.
pub(crate) type Root<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// What a false-colour picture's legend says.
pub(crate) struct Legend<'a> {
    pub title: String,
    /// The colour at a height on the bar: 1 at the top, 0 at the bottom.
    pub colour: &'a dyn Fn(f32) -> [u8; 3],
    /// The values at 1, ¾, ½, ¼ and 0 of the bar, top down.
    pub labels: [String; 5],
    /// Lines under the bar.
    pub caption: &'a [String],
}

/// Writes a picture of `width` × `height` that `paint` draws, with `legend` to its right.
pub(crate) fn with_legend(
    path: &Path,
    (width, height): (u32, u32),
    paint: impl FnOnce(&Root) -> Result<()>,
    legend: &Legend,
) -> Result<()> {
    font()?;
    let (w, h) = (width + 200, height.max(320));
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        paint(&root)?;
        let style = ("sans-serif", 14).into_font();
        let left = width as i32 + 14;
        root.draw(&Text::new(legend.title.clone(), (left, 8), style.clone()))
            .map_err(plot_error)?;
        let (top, bar) = (34i32, 180i32);
        for i in 0..bar {
            let [r, g, b] = (legend.colour)(1.0 - i as f32 / (bar - 1) as f32);
            root.draw(&Rectangle::new(
                [(left, top + i), (left + 22, top + i + 1)],
                RGBColor(r, g, b).filled(),
            ))
            .map_err(plot_error)?;
        }
        root.draw(&Rectangle::new(
            [(left, top), (left + 22, top + bar)],
            BLACK.stroke_width(1),
        ))
        .map_err(plot_error)?;
        for (k, label) in legend.labels.iter().enumerate() {
            let y = top + (bar - 1) * k as i32 / 4;
            root.draw(&PathElement::new(
                vec![(left + 22, y), (left + 27, y)],
                BLACK,
            ))
            .map_err(plot_error)?;
            root.draw(&Text::new(label.clone(), (left + 31, y - 7), style.clone()))
                .map_err(plot_error)?;
        }
        for (i, line) in legend.caption.iter().enumerate() {
            let y = top + bar + 16 + 18 * i as i32;
            root.draw(&Text::new(line.clone(), (left, y), style.clone()))
                .map_err(plot_error)?;
        }
        root.present().map_err(plot_error)?;
    }
    write_rgb(path, w, h, rgb)
}

/// Draws one pixel per value of a row-major `width`-wide image, coloured by `colour`.
fn paint_pixels(
    root: &Root,
    width: u32,
    values: &[f64],
    colour: impl Fn(f64) -> [u8; 3],
) -> Result<()> {
    for (i, &v) in values.iter().enumerate() {
        let [r, g, b] = colour(v);
        let (x, y) = ((i as u32 % width) as i32, (i as u32 / width) as i32);
        root.draw_pixel((x, y), &RGBColor(r, g, b))
            .map_err(plot_error)?;
    }
    Ok(())
}

/// Writes a false-colour picture of signed per-pixel `values` (row-major, `width` × `height`)
/// with a colour bar from −`range` to +`range` labelled in percent, a title over the bar and
/// `caption` lines under it.
pub fn false_colour_png(
    path: &Path,
    width: u32,
    height: u32,
    values: &[f32],
    range: f64,
    title: &str,
    caption: &[String],
) -> Result<()> {
    let values: Vec<f64> = values.iter().map(|&v| f64::from(v)).collect();
    let paint = |root: &Root| paint_pixels(root, width, &values, |v| diverging((v / range) as f32));
    let legend = Legend {
        title: title.to_string(),
        colour: &|f| diverging(2.0 * f - 1.0),
        labels: [0, 1, 2, 3, 4].map(|k| percent_label(range * (1.0 - 0.5 * f64::from(k)))),
        caption,
    };
    with_legend(path, (width, height), paint, &legend)
}

/// A sequential colour map for t in [0, 1] (dark blue, blue, green, yellow, red), as lighting
/// tools colour illuminance.
pub fn sequential(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 5] = [
        [0.05, 0.05, 0.35],
        [0.10, 0.35, 0.85],
        [0.20, 0.75, 0.35],
        [0.98, 0.85, 0.15],
        [0.85, 0.10, 0.08],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    } * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|c| ((a[c] + (b[c] - a[c]) * f) * 255.0 + 0.5) as u8)
}

/// Labels of a legend from `high` (top) to `low`, linear or logarithmic, in `unit`.
fn value_labels(low: f64, high: f64, log: bool, unit: &str) -> [String; 5] {
    [0, 1, 2, 3, 4].map(|k| {
        let t = 1.0 - f64::from(k) / 4.0;
        let value = if log {
            low * (high / low).powf(t)
        } else {
            low + (high - low) * t
        };
        format!("{value:.4} {unit}")
    })
}

/// Writes a false-colour picture of per-pixel `values` (row-major, `width` × `height`) on the
/// sequential map from `low` to `high` (logarithmic if `log`; then `low` must be > 0), with a
/// colour bar labelled in `unit` and a title.
pub fn sequential_png(
    path: &Path,
    (width, height): (u32, u32),
    values: &[f64],
    (low, high, log): (f64, f64, bool),
    unit: &str,
    title: &str,
) -> Result<()> {
    let level = |v: f64| -> f32 {
        let t = if log {
            (v.max(low) / low).ln() / (high / low).ln()
        } else {
            (v - low) / (high - low)
        };
        t as f32
    };
    let paint = |root: &Root| paint_pixels(root, width, values, |v| sequential(level(v)));
    let legend = Legend {
        title: title.to_string(),
        colour: &sequential,
        labels: value_labels(low, high, log, unit),
        caption: &[],
    };
    with_legend(path, (width, height), paint, &legend)
}

/// Writes `image`'s signed error against `reference` as a false-colour picture; answers the
/// range its colours saturate at (`range`, or the 99th percentile of |error| rounded up).
pub fn write_error_picture(
    image: &meshlight::Image,
    reference: &meshlight::Image,
    error: &meshlight::metrics::ImageError,
    range: Option<f64>,
    path: &Path,
) -> Result<f64> {
    let values = meshlight::metrics::signed_error_map(image, reference)?;
    let range = match range {
        Some(r) if r > 0.0 && r.is_finite() => r,
        Some(r) => return Err(anyhow!("--diff-range must be a positive fraction, not {r}")),
        None => {
            let mut magnitudes: Vec<f32> = values.iter().map(|v| v.abs()).collect();
            magnitudes.sort_unstable_by(f32::total_cmp);
            let p99 = magnitudes
                .get(magnitudes.len() * 99 / 100)
                .copied()
                .unwrap_or(0.0);
            nice_ceiling(f64::from(p99))
        }
    };
    let caption = vec![
        format!("MAE/mean {:.2}%", 100.0 * error.mae_over_mean),
        format!("bias {}", percent_label(error.bias)),
        format!("p99 {:.2}%", 100.0 * error.p99_over_mean),
    ];
    false_colour_png(
        path,
        image.width,
        image.height,
        &values,
        range,
        "error / mean",
        &caption,
    )?;
    Ok(range)
}

/// One named series of an error-against-time plot.
pub struct Series {
    /// The legend's name.
    pub name: String,
    /// (seconds, error) points, in percent of the reference's mean.
    pub points: Vec<(f64, f64)>,
    /// Join the points with a line (in the order given).
    pub line: bool,
    /// Colour.
    pub colour: RGBColor,
}

/// The ticks of a logarithmic axis over [lo, hi]: 1, 2 and 5 of each decade labelled, the other
/// integers of each decade as light lines.
fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut bold, mut light) = (Vec::new(), Vec::new());
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return (bold, light);
    }
    for k in lo.log10().floor() as i32..=hi.log10().ceil() as i32 {
        let decade = 10f64.powi(k);
        for m in 1..10 {
            let v = f64::from(m) * decade;
            if v >= lo && v <= hi {
                if matches!(m, 1 | 2 | 5) {
                    bold.push(v);
                } else {
                    light.push(v);
                }
            }
        }
    }
    (bold, light)
}

/// A logarithmic axis over [lo, hi] with 1-2-5 ticks.
fn log_axis(lo: f64, hi: f64) -> WithKeyPoints<LogCoord<f64>> {
    let (bold, light) = log_ticks(lo, hi);
    (lo..hi)
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light)
}

/// A tick label without trailing zeros: 0.5, 2, 10, 0.02.
fn short_number(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// Writes a log-log plot of error (percent) against seconds.
pub fn error_time_png(path: &Path, title: &str, series: &[Series]) -> Result<()> {
    font()?;
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|&(t, e)| t > 0.0 && e > 0.0 && t.is_finite() && e.is_finite())
        .collect();
    if all.is_empty() {
        return Err(anyhow!(
            "nothing to plot: no run has a positive time and error"
        ));
    }
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, 0f64, f64::MAX, 0f64);
    for &(t, e) in &all {
        (t0, t1, e0, e1) = (t0.min(t), t1.max(t), e0.min(e), e1.max(e));
    }
    let (t0, t1) = (t0 / 1.5, t1 * 1.5);
    let (e0, e1) = (e0 / 1.5, e1 * 1.5);
    let (w, h) = (900u32, 600u32);
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(log_axis(t0, t1), log_axis(e0, e1))
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("seconds (log)")
            .y_desc("MAE / mean, % (log)")
            .light_line_style(RGBColor(238, 238, 238))
            .label_style(("sans-serif", 14))
            .x_label_formatter(&|v| short_number(*v))
            .y_label_formatter(&|v| short_number(*v))
            .draw()
            .map_err(plot_error)?;
        for s in series {
            let colour = s.colour;
            let points: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|&(t, e)| t > 0.0 && e > 0.0 && t.is_finite() && e.is_finite())
                .collect();
            if s.line {
                chart
                    .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                    .map_err(plot_error)?;
            }
            chart
                .draw_series(
                    points
                        .iter()
                        .map(|&p| Circle::new(p, if s.line { 4 } else { 3 }, colour.filled())),
                )
                .map_err(plot_error)?
                .label(s.name.clone())
                .legend(move |(x, y)| Circle::new((x + 8, y), 4, colour.filled()));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    write_rgb(path, w, h, rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diverging_map_ends_and_middle() {
        assert_eq!(diverging(0.0), [247, 247, 247]);
        assert_eq!(diverging(-1.0), [33, 102, 172]);
        assert_eq!(diverging(1.0), [178, 24, 43]);
        assert_eq!(diverging(7.0), diverging(1.0));
        assert_eq!(diverging(f32::NAN), diverging(0.0));
        // Halfway between the white and the light red stop.
        assert_eq!(diverging(0.25), [246, 206, 189]);
    }

    #[test]
    fn log_axes_tick_each_decade_once() {
        let (bold, light) = log_ticks(0.35, 20.0);
        assert_eq!(bold, [0.5, 1.0, 2.0, 5.0, 10.0, 20.0]);
        assert_eq!(light.len(), 5 + 6);
        assert_eq!(short_number(10.0), "10");
        assert_eq!(short_number(0.5), "0.5");
        assert_eq!(short_number(0.02), "0.02");
    }

    #[test]
    fn percent_labels() {
        assert_eq!(percent_label(0.025), "+2.5%");
        assert_eq!(percent_label(-0.05), "-5%");
        assert_eq!(percent_label(0.0), "0%");
        assert_eq!(percent_label(0.001), "+0.1%");
    }

    #[test]
    fn nice_ceilings() {
        assert_eq!(nice_ceiling(0.013), 0.02);
        assert_eq!(nice_ceiling(0.02), 0.02);
        assert!((nice_ceiling(0.031) - 0.05).abs() < 1e-15);
        assert!((nice_ceiling(0.051) - 0.1).abs() < 1e-15);
        assert_eq!(nice_ceiling(0.0), 0.01);
    }
}
