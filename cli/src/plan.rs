//! Isolux plans as lighting designers hand them in: the grid's illuminance interpolated
//! between its points, iso-lines at round values (multiples of a 1-2-5 step) traced through
//! that field by marching squares and labelled, points inside solids hatched (never coloured
//! as 0), luminaires marked, axes in metres and a scale bar.

use std::path::Path;

use anyhow::Result;
use plotters::prelude::*;

use super::plot::{nice_ceiling, plot_error, sequential, with_legend, Legend, Root};

/// A grid's values and what to draw over them.
pub struct Plan<'a> {
    /// Points along u and v.
    pub counts: (u32, u32),
    /// Row by row along u (v = 0 first).
    pub values: &'a [f64],
    /// Points inside solids, left out of the summary: drawn hatched.
    pub excluded: &'a [bool],
    /// Distance between points along u and along v, metres (or the scene's length unit).
    pub spacing: (f64, f64),
    /// Luminaires over the grid, in grid units (point (i, j) at (i, j)).
    pub marks: &'a [(f64, f64)],
    /// The scene cut by the grid's plane (walls, furniture), as segments in grid units.
    pub outline: &'a [[(f64, f64); 2]],
    /// The values' unit.
    pub unit: &'a str,
    /// Over the legend.
    pub title: &'a str,
    /// Under the legend.
    pub caption: &'a [String],
}

/// Pixels per grid spacing at least and at most.
const CELL: (f64, f64) = (4.0, 64.0);
/// Margins of the plan: left and bottom hold the axes.
const LEFT: u32 = 52;
const BOTTOM: u32 = 36;
const TOP: u32 = 10;
const RIGHT: u32 = 10;
/// The "no value" hatch: light and dark grey, lines 3 of every 8 pixels.
pub const HATCH: ([u8; 3], [u8; 3]) = ([215, 215, 215], [150, 150, 150]);

/// The smallest 1-2-5 step (1, 2 or 5 × 10ⁿ) nearest `x`.
pub fn nice_step(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let decade = 10f64.powf(x.log10().floor());
    let m = x / decade;
    decade
        * if m < 1.5 {
            1.0
        } else if m < 3.5 {
            2.0
        } else if m < 7.5 {
            5.0
        } else {
            10.0
        }
}

/// Iso-levels strictly between `low` and `high`: the multiples of a 1-2-5 step that gives
/// three to seven of them.
pub fn levels(low: f64, high: f64) -> Vec<f64> {
    if !(low.is_finite() && high.is_finite() && high > low) {
        return Vec::new();
    }
    let step = nice_step((high - low) / 5.0);
    // k × step as k × m / 10ⁿ for steps below 1, so 6 × 0.1 is 0.6, not 0.6000000000000001.
    let decades = (-step.log10().floor()).max(0.0) as i32;
    let scale = 10f64.powi(decades);
    let m = (step * scale).round();
    let first = (low / step).floor() as i64 + 1;
    (first..)
        .map(|k| k as f64 * m / scale)
        .take_while(|&v| v < high)
        .filter(|&v| v > low)
        .take(12)
        .collect()
}

/// A value with three significant figures at most and no trailing zeros: 153.68 → "154",
/// 0.04567 → "0.0457", 2000 → "2000".
pub fn round_label(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let text = format!("{v:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        // Above 999 the integer part has more than three figures: rounded to three.
        let scale = 10f64.powi(v.abs().log10().floor() as i32 - 2);
        format!("{}", ((v / scale).round() * scale) as i64)
    }
}

/// The segments where the field crosses `level`, in grid units, by marching squares over the
/// cells whose four corners are all measured; a saddle is split by the cell's mean.
pub fn contours(
    values: &[f64],
    excluded: &[bool],
    (nu, nv): (u32, u32),
    level: f64,
) -> Vec<[(f64, f64); 2]> {
    let (nu, nv) = (nu as usize, nv as usize);
    let at = |i: usize, j: usize| values[j * nu + i];
    let open = |i: usize, j: usize| !excluded.get(j * nu + i).copied().unwrap_or(false);
    let mut out = Vec::new();
    for j in 0..nv.saturating_sub(1) {
        for i in 0..nu.saturating_sub(1) {
            if !(open(i, j) && open(i + 1, j) && open(i + 1, j + 1) && open(i, j + 1)) {
                continue;
            }
            // Corners counter-clockwise from (i, j); edge k runs from corner k to k + 1.
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let v = corners.map(|(a, b)| at(a, b));
            let crossing = |k: usize| {
                let (a, b) = (k, (k + 1) % 4);
                let (va, vb) = (v[a], v[b]);
                if (va >= level) == (vb >= level) {
                    return None;
                }
                let t = (level - va) / (vb - va);
                let (pa, pb) = (corners[a], corners[b]);
                Some((
                    pa.0 as f64 + t * (pb.0 as f64 - pa.0 as f64),
                    pa.1 as f64 + t * (pb.1 as f64 - pa.1 as f64),
                ))
            };
            let points: Vec<(usize, (f64, f64))> =
                (0..4).filter_map(|k| crossing(k).map(|p| (k, p))).collect();
            match points.len() {
                2 => out.push([points[0].1, points[1].1]),
                4 => {
                    // A saddle: corners 0 and 2 on one side. If the centre is on their side
                    // they join, and the lines cut off corners 1 and 3; else the reverse.
                    let centre = v.iter().sum::<f64>() / 4.0;
                    let joined = (centre >= level) == (v[0] >= level);
                    let p = |k: usize| points[k].1;
                    if joined {
                        out.push([p(0), p(1)]);
                        out.push([p(2), p(3)]);
                    } else {
                        out.push([p(3), p(0)]);
                        out.push([p(1), p(2)]);
                    }
                }
                _ => {}
            }
        }
    }
    out
}

/// The value at grid coordinates (x, y): bilinear between the four points around it, the
/// measured ones only (weights renormalised); `None` where the nearest point is excluded.
pub fn value_at(
    values: &[f64],
    excluded: &[bool],
    (nu, nv): (u32, u32),
    x: f64,
    y: f64,
) -> Option<f64> {
    let (nu, nv) = (nu as usize, nv as usize);
    let clamp = |c: f64, n: usize| c.clamp(0.0, (n - 1) as f64);
    let (x, y) = (clamp(x, nu), clamp(y, nv));
    let nearest = (y.round() as usize) * nu + x.round() as usize;
    if excluded.get(nearest).copied().unwrap_or(false) {
        return None;
    }
    let (i0, j0) = (
        (x.floor() as usize).min(nu - 1),
        (y.floor() as usize).min(nv - 1),
    );
    let (i1, j1) = ((i0 + 1).min(nu - 1), (j0 + 1).min(nv - 1));
    let (fx, fy) = (x - i0 as f64, y - j0 as f64);
    let mut sum = (0.0, 0.0);
    for (i, j, w) in [
        (i0, j0, (1.0 - fx) * (1.0 - fy)),
        (i1, j0, fx * (1.0 - fy)),
        (i0, j1, (1.0 - fx) * fy),
        (i1, j1, fx * fy),
    ] {
        let k = j * nu + i;
        if !excluded.get(k).copied().unwrap_or(false) {
            sum.0 += w * values[k];
            sum.1 += w;
        }
    }
    (sum.1 > 0.0).then(|| sum.0 / sum.1)
}

/// Where the plan lies in the picture: to scale, about 480 pixels along its longer side.
#[derive(Clone, Copy, Debug)]
pub struct Layout {
    /// Pixels per metre.
    pub scale: f64,
    /// Metres between points along u and v.
    pub spacing: (f64, f64),
    /// The plan's size in pixels.
    pub size: (u32, u32),
}

impl Layout {
    /// The layout of a grid of `counts` points `spacing` apart.
    pub fn new((nu, nv): (u32, u32), spacing: (f64, f64)) -> Layout {
        let (wu, wv) = (f64::from(nu) * spacing.0, f64::from(nv) * spacing.1);
        let finest = spacing.0.min(spacing.1);
        let scale = (480.0 / wu.max(wv)).clamp(CELL.0 / finest, CELL.1 / finest);
        Layout {
            scale,
            spacing,
            size: (
                (wu * scale).round().max(1.0) as u32,
                (wv * scale).round().max(1.0) as u32,
            ),
        }
    }

    /// The picture position of grid coordinates (point (i, j) at (i, j); v upwards).
    pub fn pixel_of(self, (x, y): (f64, f64)) -> (f64, f64) {
        (
            f64::from(LEFT) + (x + 0.5) * self.spacing.0 * self.scale,
            f64::from(TOP + self.size.1) - (y + 0.5) * self.spacing.1 * self.scale,
        )
    }

    /// The grid coordinates of a pixel's centre (plan pixel (px, py), from its top-left).
    fn grid_of(self, px: u32, py: u32) -> (f64, f64) {
        (
            (f64::from(px) + 0.5) / (self.spacing.0 * self.scale) - 0.5,
            (f64::from(self.size.1 - py) - 0.5) / (self.spacing.1 * self.scale) - 0.5,
        )
    }
}

/// Writes the plan as PNG: the field, its iso-lines and labels, hatched excluded points,
/// luminaire marks, axes and a scale bar, with a legend of round values to the right.
pub fn plan_png(path: &Path, plan: &Plan) -> Result<()> {
    let layout = Layout::new(plan.counts, plan.spacing);
    let (pw, ph) = layout.size;
    let open: Vec<f64> = plan
        .values
        .iter()
        .zip(plan.excluded)
        .filter(|(_, &x)| !x)
        .map(|(&v, _)| v)
        .collect();
    let low = open.iter().copied().fold(f64::INFINITY, f64::min);
    let high = open.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let top = nice_ceiling(high.max(0.0));
    let paint = |root: &Root| -> Result<()> {
        for py in 0..ph {
            for px in 0..pw {
                let (x, y) = layout.grid_of(px, py);
                let [r, g, b] = match value_at(plan.values, plan.excluded, plan.counts, x, y) {
                    Some(v) => sequential((v / top) as f32),
                    None if (px + py) % 8 < 3 => HATCH.1,
                    None => HATCH.0,
                };
                root.draw_pixel(((LEFT + px) as i32, (TOP + py) as i32), &RGBColor(r, g, b))
                    .map_err(plot_error)?;
            }
        }
        let pixel = |p: (f64, f64)| {
            let (x, y) = layout.pixel_of(p);
            (x.round() as i32, y.round() as i32)
        };
        let style = ("sans-serif", 12).into_font();
        for level in levels(low, high) {
            let segments = contours(plan.values, plan.excluded, plan.counts, level);
            for [a, b] in &segments {
                root.draw(&PathElement::new(
                    vec![pixel(*a), pixel(*b)],
                    BLACK.stroke_width(2),
                ))
                .map_err(plot_error)?;
            }
            // One label per level, on the segment nearest the plan's middle of its run.
            if let Some([a, b]) = segments.get(segments.len() / 2) {
                let (x, y) = pixel(((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0));
                let text = round_label(level);
                let w = 7 * text.len() as i32 + 4;
                root.draw(&Rectangle::new(
                    [(x - w / 2, y - 8), (x + w / 2, y + 7)],
                    WHITE.filled(),
                ))
                .map_err(plot_error)?;
                root.draw(&Text::new(text, (x - w / 2 + 2, y - 7), style.clone()))
                    .map_err(plot_error)?;
            }
        }
        // The scene's cut, clipped to the plan: drawn over the field, under the marks.
        let (lo, hi) = (
            (-0.5, -0.5),
            (
                f64::from(plan.counts.0) - 0.5,
                f64::from(plan.counts.1) - 0.5,
            ),
        );
        for segment in plan.outline {
            if let Some([a, b]) = clip(*segment, lo, hi) {
                root.draw(&PathElement::new(
                    vec![pixel(a), pixel(b)],
                    RGBColor(70, 70, 70).stroke_width(2),
                ))
                .map_err(plot_error)?;
            }
        }
        for &m in plan.marks {
            let (x, y) = pixel(m);
            root.draw(&Circle::new((x, y), 5, WHITE.filled()))
                .map_err(plot_error)?;
            root.draw(&Circle::new((x, y), 5, BLACK.stroke_width(1)))
                .map_err(plot_error)?;
            root.draw(&PathElement::new(
                vec![(x - 3, y - 3), (x + 3, y + 3)],
                BLACK,
            ))
            .map_err(plot_error)?;
            root.draw(&PathElement::new(
                vec![(x - 3, y + 3), (x + 3, y - 3)],
                BLACK,
            ))
            .map_err(plot_error)?;
        }
        axes(root, &layout)?;
        // Under the legend's caption (`plot::with_legend` puts its lines 18 pixels apart from
        // 230 down, 14 pixels right of the picture).
        let x = (LEFT + pw + RIGHT) as i32 + 14;
        let y = 230 + 18 * plan.caption.len() as i32 + 4;
        scale_bar(root, &layout, (x, y))?;
        Ok(())
    };
    let legend = Legend {
        title: plan.title.to_string(),
        colour: &sequential,
        labels: [0, 1, 2, 3, 4].map(|k| {
            format!(
                "{} {}",
                round_label(top * (1.0 - f64::from(k) / 4.0)),
                plan.unit
            )
        }),
        caption: plan.caption,
    };
    with_legend(path, (LEFT + pw + RIGHT, TOP + ph + BOTTOM), paint, &legend)
}

/// The part of segment `s` inside the box `lo`–`hi` (Liang–Barsky), if any.
fn clip(s: [(f64, f64); 2], lo: (f64, f64), hi: (f64, f64)) -> Option<[(f64, f64); 2]> {
    let [a, b] = s;
    let d = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.0, a.0 - lo.0),
        (d.0, hi.0 - a.0),
        (-d.1, a.1 - lo.1),
        (d.1, hi.1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then(|| {
        let at = |t: f64| (a.0 + t * d.0, a.1 + t * d.1);
        [at(t0), at(t1)]
    })
}

/// A scale bar of a round length in metres, about 80 pixels long, at `(x, y)`.
fn scale_bar(root: &Root, layout: &Layout, (x, y): (i32, i32)) -> Result<()> {
    let length = nice_step(80.0 / layout.scale);
    let pixels = (length * layout.scale).round() as i32;
    for (a, b) in [
        ((x, y), (x + pixels, y)),
        ((x, y - 4), (x, y + 4)),
        ((x + pixels, y - 4), (x + pixels, y + 4)),
    ] {
        root.draw(&PathElement::new(vec![a, b], BLACK.stroke_width(2)))
            .map_err(plot_error)?;
    }
    let style = ("sans-serif", 14).into_font();
    root.draw(&Text::new(
        format!("{} m", round_label(length)),
        (x + pixels + 6, y - 7),
        style,
    ))
    .map_err(plot_error)?;
    Ok(())
}

/// A frame, and ticks labelled in metres along the bottom (u) and left (v) edges.
fn axes(root: &Root, layout: &Layout) -> Result<()> {
    let (pw, ph) = (layout.size.0 as i32, layout.size.1 as i32);
    let (left, top) = (LEFT as i32, TOP as i32);
    root.draw(&Rectangle::new(
        [(left, top), (left + pw, top + ph)],
        BLACK.stroke_width(1),
    ))
    .map_err(plot_error)?;
    let style = ("sans-serif", 12).into_font();
    let (wu, wv) = (f64::from(pw) / layout.scale, f64::from(ph) / layout.scale);
    let step = nice_step(wu.max(wv) / 5.0);
    let at = |k: u32| (f64::from(k) * step * layout.scale).round() as i32;
    for k in (0..).take_while(|&k| f64::from(k) * step <= wu + 1e-9) {
        let x = left + at(k);
        root.draw(&PathElement::new(
            vec![(x, top + ph), (x, top + ph + 5)],
            BLACK,
        ))
        .map_err(plot_error)?;
        let label = round_label(f64::from(k) * step);
        root.draw(&Text::new(label, (x - 6, top + ph + 8), style.clone()))
            .map_err(plot_error)?;
    }
    root.draw(&Text::new(
        "u (m)",
        (left + pw - 34, top + ph + 22),
        style.clone(),
    ))
    .map_err(plot_error)?;
    for k in (0..).take_while(|&k| f64::from(k) * step <= wv + 1e-9) {
        let y = top + ph - at(k);
        root.draw(&PathElement::new(vec![(left - 5, y), (left, y)], BLACK))
            .map_err(plot_error)?;
        let label = round_label(f64::from(k) * step);
        root.draw(&Text::new(label, (left - 40, y - 6), style.clone()))
            .map_err(plot_error)?;
    }
    root.draw(&Text::new("v (m)", (4, top), style))
        .map_err(plot_error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_are_multiples_of_a_1_2_5_step() {
        assert_eq!(
            levels(12.0, 153.7),
            vec![20.0, 40.0, 60.0, 80.0, 100.0, 120.0, 140.0]
        );
        assert_eq!(levels(0.31, 0.78), vec![0.4, 0.5, 0.6, 0.7]);
        assert!(levels(5.0, 5.0).is_empty());
        assert_eq!(nice_step(0.07), 0.05);
        assert_eq!(nice_step(300.0), 200.0);
    }

    #[test]
    fn segments_are_clipped_to_the_plan() {
        let (lo, hi) = ((0.0, 0.0), (1.0, 1.0));
        assert_eq!(
            clip([(-1.0, 0.5), (2.0, 0.5)], lo, hi),
            Some([(0.0, 0.5), (1.0, 0.5)])
        );
        assert_eq!(clip([(2.0, 2.0), (3.0, 3.0)], lo, hi), None);
        assert_eq!(
            clip([(0.2, 0.2), (0.4, 0.6)], lo, hi),
            Some([(0.2, 0.2), (0.4, 0.6)])
        );
    }

    #[test]
    fn labels_have_three_significant_figures() {
        assert_eq!(round_label(153.6829), "154");
        assert_eq!(round_label(25.7142), "25.7");
        assert_eq!(round_label(0.045671), "0.0457");
        assert_eq!(round_label(2000.0), "2000");
        assert_eq!(round_label(12345.0), "12300");
        assert_eq!(round_label(0.5), "0.5");
    }

    #[test]
    fn iso_lines_of_a_point_light_lie_on_its_circles() {
        // E = I h / (r² + h²)^{3/2} over a 41 × 41 grid of spacing 0.1 m, the light 1 m above
        // the centre point (20, 20), I = 1000: E at r is level L where
        // r = √((I h / L)^{2/3} − h²), by hand. Every vertex of every segment lies within half
        // a spacing of that circle.
        let (n, h, i) = (41u32, 1.0f64, 1000.0f64);
        let spacing = 0.1;
        let mut values = Vec::new();
        for j in 0..n {
            for k in 0..n {
                let (x, y) = (
                    (f64::from(k) - 20.0) * spacing,
                    (f64::from(j) - 20.0) * spacing,
                );
                values.push(i * h / (x * x + y * y + h * h).powf(1.5));
            }
        }
        let excluded = vec![false; values.len()];
        for level in [200.0, 500.0, 800.0] {
            let r = ((i * h / level).powf(2.0 / 3.0) - h * h).sqrt();
            let segments = contours(&values, &excluded, (n, n), level);
            assert!(segments.len() > 20, "{level}: {} segments", segments.len());
            for p in segments.iter().flatten() {
                let d = ((p.0 - 20.0).hypot(p.1 - 20.0)) * spacing;
                assert!(
                    (d - r).abs() < 0.5 * spacing,
                    "{level}: {p:?} at {d}, not {r}"
                );
            }
        }
    }

    #[test]
    fn excluded_points_have_no_value_and_break_the_lines() {
        // 3 × 3 points rising along u; the middle one excluded.
        let values = [0.0, 1.0, 2.0, 0.0, 1.0, 2.0, 0.0, 1.0, 2.0];
        let mut excluded = [false; 9];
        excluded[4] = true;
        assert_eq!(value_at(&values, &excluded, (3, 3), 1.0, 1.0), None);
        // Between measured points the value is theirs, the excluded one left out.
        let v = value_at(&values, &excluded, (3, 3), 0.5, 0.0).unwrap();
        assert!((v - 0.5).abs() < 1e-12);
        // Every cell touches the middle point: no iso-line is drawn through it.
        assert!(contours(&values, &excluded, (3, 3), 0.5).is_empty());
        assert_eq!(contours(&values, &[false; 9], (3, 3), 0.5).len(), 2);
    }
}
