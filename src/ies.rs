//! IES LM-63 photometric files (1986, 1991, 1995, 2002; 2019 reads the same way): the
//! luminous intensity of a luminaire in every direction, Type C photometry, with the file's
//! symmetries, bilinear interpolation between its angles and the flux integrated from it.
//!
//! The layout: keyword lines (`IESNA:LM-63-2002`, `[TEST] …`), a `TILT=` line (`NONE`, or
//! `INCLUDE` followed by the tilt table, which is read and not applied), then numbers
//! separated by blanks, commas or line ends: lamps, lumens per lamp (−1: absolute
//! photometry), candela multiplier, vertical angles, horizontal angles, photometric type,
//! units, width, length, height; ballast factor, ballast-lamp factor (1995: "future use"),
//! input watts; the vertical angles; the horizontal angles; the candela values, one run of
//! vertical values per horizontal angle. Every problem names the file and line.

use std::path::Path;

use crate::error::{Error, Result};

/// A Type C distribution: γ from the nadir (the luminaire's aim), C around it.
#[derive(Clone, Debug, PartialEq)]
pub struct Photometry {
    /// Vertical angles γ, degrees, increasing (0–90, 0–180 or 90–180).
    pub vertical: Vec<f64>,
    /// Horizontal angles C, degrees, increasing: one (symmetric about the axis), 0–90
    /// (quadrant symmetry), 0–180 (symmetric about the 0–180 plane), 90–270 (about the
    /// 90–270 plane) or 0–360 (none).
    pub horizontal: Vec<f64>,
    /// Candela, `candela[h * vertical.len() + v]`, the file's multiplier and ballast factors
    /// applied.
    pub candela: Vec<f64>,
    /// Whether the file says absolute photometry (lumens per lamp = −1).
    pub absolute: bool,
    /// Where it came from: the IES file's name, or what made it (a glTF spot).
    pub source: String,
    /// The input watts the file gives (none when it says 0).
    pub input_watts: Option<f64>,
    /// [`Photometry::flux`], integrated once.
    flux: std::sync::OnceLock<f64>,
}

/// Numbers after the keyword lines, each with its line.
struct Numbers<'a> {
    path: &'a Path,
    words: Vec<(&'a str, usize)>,
    next: usize,
    last_line: usize,
}

impl<'a> Numbers<'a> {
    /// The tilt data after `TILT=tilt` (on `tilt_line`): none, or included and skipped (it
    /// matters only for a lamp tilted away from its test position); a tilt file is refused.
    fn tilt(&mut self, tilt: &str, tilt_line: usize) -> Result<()> {
        match tilt {
            "NONE" => Ok(()),
            "INCLUDE" => {
                self.number("the tilt geometry")?;
                let pairs = self.count("the number of tilt angles", 10_000)?;
                self.angles("tilt angles", pairs)?;
                for _ in 0..pairs {
                    self.number("a tilt factor")?;
                }
                Ok(())
            }
            other => Err(Error::scene(
                self.path,
                Some(tilt_line),
                format!("TILT={other}: only NONE and INCLUDE are read (a tilt file is not)"),
            )),
        }
    }

    /// Type C angles: vertical within 0–180°, horizontal one of the symmetries the format
    /// knows.
    fn check_angles(&self, vertical: &[f64], horizontal: &[f64]) -> Result<()> {
        let (nv, nh) = (vertical.len(), horizontal.len());
        let fail = |problem: String| {
            Err(Error::scene(
                self.path,
                Some(self.words[self.next - 1].1),
                problem,
            ))
        };
        let (v0, v1) = (vertical[0], vertical[nv - 1]);
        if !(v0 >= 0.0 && v1 <= 180.0) {
            return fail(format!("vertical angles {v0}–{v1} leave 0–180°"));
        }
        let (h0, h1) = (horizontal[0], horizontal[nh - 1]);
        let symmetric = nh == 1
            || (h0 == 0.0 && [90.0, 180.0, 360.0].contains(&h1))
            || (h0 == 90.0 && h1 == 270.0);
        if !symmetric {
            return fail(format!(
                "horizontal angles {h0}–{h1}: type C files run 0, 0–90, 0–180, 90–270 or 0–360"
            ));
        }
        Ok(())
    }

    /// The `nv` × `nh` candela values, each × `scale`, and nothing after them. Counts that
    /// promise more values than the file holds are refused before allocating.
    fn candela(&mut self, nv: usize, nh: usize, scale: f64) -> Result<Vec<f64>> {
        let fail = |line: usize, problem: String| Err(Error::scene(self.path, Some(line), problem));
        if nv * nh > self.words.len() - self.next {
            return fail(
                self.last_line,
                format!(
                    "the file ends before its {} candela values ({nv} × {nh}); it holds {}",
                    nv * nh,
                    self.words.len() - self.next
                ),
            );
        }
        let mut candela = Vec::with_capacity(nv * nh);
        for _ in 0..nv * nh {
            let (c, line) = self.number("a candela value")?;
            if c < 0.0 {
                return fail(line, format!("candela value {c} is negative"));
            }
            candela.push(c * scale);
        }
        if let Some(&(extra, line)) = self.words.get(self.next) {
            return fail(
                line,
                format!(
                    "'{extra}' after the {} candela values its counts announce",
                    nv * nh
                ),
            );
        }
        Ok(candela)
    }

    fn new(path: &'a Path, lines: impl Iterator<Item = (usize, &'a str)>) -> Self {
        let mut words = Vec::new();
        let mut last_line = 1;
        for (line, text) in lines {
            last_line = line;
            for w in text.split(|c: char| c.is_whitespace() || c == ',') {
                if !w.is_empty() {
                    words.push((w, line));
                }
            }
        }
        Numbers {
            path,
            words,
            next: 0,
            last_line,
        }
    }

    /// The next number, named `what` in errors.
    fn number(&mut self, what: &str) -> Result<(f64, usize)> {
        let Some(&(word, line)) = self.words.get(self.next) else {
            return Err(Error::scene(
                self.path,
                Some(self.last_line),
                format!("the file ends where {what} should be (fewer values than its counts say)"),
            ));
        };
        self.next += 1;
        match word.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok((v, line)),
            _ => Err(Error::scene(
                self.path,
                Some(line),
                format!("{what}: '{word}' is not a number"),
            )),
        }
    }

    /// The next number as a count in 1..=`max`.
    fn count(&mut self, what: &str, max: usize) -> Result<usize> {
        let (v, line) = self.number(what)?;
        if v.fract() != 0.0 || v < 1.0 || v > max as f64 {
            return Err(Error::scene(
                self.path,
                Some(line),
                format!("{what} must be a whole number from 1 to {max}, found {v}"),
            ));
        }
        Ok(v as usize)
    }

    /// `n` angles, increasing.
    fn angles(&mut self, what: &str, n: usize) -> Result<Vec<f64>> {
        let mut out: Vec<f64> = Vec::with_capacity(n);
        for _ in 0..n {
            let (a, line) = self.number(what)?;
            if let Some(&before) = out.last() {
                if a <= before {
                    return Err(Error::scene(
                        self.path,
                        Some(line),
                        format!("{what} out of order: {a} after {before}"),
                    ));
                }
            }
            out.push(a);
        }
        Ok(out)
    }
}

impl Photometry {
    /// Reads an IES file's text; `path` names it in errors.
    pub fn parse(path: &Path, text: &str) -> Result<Photometry> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let lines: Vec<(usize, &str)> = text.lines().enumerate().map(|(i, l)| (i + 1, l)).collect();
        let fail = |line: usize, problem: String| Err(Error::scene(path, Some(line), problem));
        // Keyword lines up to TILT=.
        let Some(tilt_at) = lines
            .iter()
            .position(|(_, l)| l.trim_start().to_ascii_uppercase().starts_with("TILT"))
        else {
            return fail(
                lines.len().max(1),
                "no TILT= line: is this an IES LM-63 file?".into(),
            );
        };
        let (tilt_line, tilt_text) = lines[tilt_at];
        let tilt = tilt_text
            .split_once('=')
            .map(|(_, v)| v.trim().to_ascii_uppercase())
            .unwrap_or_default();
        let mut numbers = Numbers::new(path, lines[tilt_at + 1..].iter().copied());
        numbers.tilt(&tilt, tilt_line)?;
        numbers.number("the number of lamps")?;
        let (lumens, _) = numbers.number("lumens per lamp")?;
        let (multiplier, multiplier_line) = numbers.number("the candela multiplier")?;
        if multiplier < 0.0 {
            return fail(
                multiplier_line,
                format!("the candela multiplier {multiplier} is negative"),
            );
        }
        let nv = numbers.count("the number of vertical angles", 100_000)?;
        let nh = numbers.count("the number of horizontal angles", 100_000)?;
        let (kind, kind_line) = numbers.number("the photometric type")?;
        if kind != 1.0 {
            return fail(
                kind_line,
                format!("photometric type {kind}: only type C (1) is read, the one interior luminaires use"),
            );
        }
        for what in ["the units type", "the width", "the length", "the height"] {
            numbers.number(what)?;
        }
        let mut factor = |what: &str| -> Result<f64> {
            let (f, line) = numbers.number(what)?;
            if f < 0.0 {
                return Err(Error::scene(
                    path,
                    Some(line),
                    format!("{what} {f} is negative"),
                ));
            }
            Ok(f)
        };
        let ballast = factor("the ballast factor")?;
        let ballast_lamp = factor("the ballast-lamp photometric factor")?;
        let (input_watts, _) = numbers.number("the input watts")?;
        let vertical = numbers.angles("vertical angles", nv)?;
        let horizontal = numbers.angles("horizontal angles", nh)?;
        numbers.check_angles(&vertical, &horizontal)?;
        let scale = multiplier * ballast * ballast_lamp;
        let candela = numbers.candela(nv, nh, scale)?;
        Ok(Photometry {
            vertical,
            horizontal,
            candela,
            absolute: lumens == -1.0,
            source: path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            ),
            input_watts: (input_watts.is_finite() && input_watts > 0.0).then_some(input_watts),
            flux: std::sync::OnceLock::new(),
        })
    }

    /// A distribution symmetric about its axis: candela `candela[i]` at γ = `vertical[i]`
    /// (degrees, increasing from 0 to at most 180), none beyond the last angle.
    pub(crate) fn symmetric(source: String, vertical: Vec<f64>, candela: Vec<f64>) -> Photometry {
        Photometry {
            vertical,
            horizontal: vec![0.0],
            candela,
            absolute: true,
            source,
            input_watts: None,
            flux: std::sync::OnceLock::new(),
        }
    }

    /// Intensity (candela) towards horizontal angle `c` and vertical angle `gamma`, degrees:
    /// the file's symmetry applied, bilinear between its angles, 0 outside its γ range.
    pub fn intensity(&self, c: f64, gamma: f64) -> f64 {
        let (v, h) = (&self.vertical, &self.horizontal);
        if !(gamma >= v[0] && gamma <= v[v.len() - 1]) {
            return 0.0;
        }
        let nv = v.len();
        let at = |hi: usize, vi: usize| self.candela[hi * nv + vi];
        let (v_lo, v_t) = bracket(v, gamma);
        let along = |hi: usize| {
            let a = at(hi, v_lo);
            if v_t == 0.0 {
                a
            } else {
                a + (at(hi, v_lo + 1) - a) * v_t
            }
        };
        if h.len() == 1 {
            return along(0);
        }
        let c = self.folded(c);
        let (h_lo, h_t) = bracket(h, c);
        let a = along(h_lo);
        if h_t == 0.0 {
            a
        } else {
            a + (along(h_lo + 1) - a) * h_t
        }
    }

    /// `c` (any angle) folded into the file's horizontal range by its symmetry.
    fn folded(&self, c: f64) -> f64 {
        let h = &self.horizontal;
        let mut c = if c.is_finite() {
            c.rem_euclid(360.0)
        } else {
            0.0
        };
        let (first, last) = (h[0], h[h.len() - 1]);
        // Mirrored about the 0–180 plane (C ↦ 360 − C), and for a quadrant also about the
        // 90–270 plane (C ↦ 180 − C).
        if first == 0.0 && (last == 90.0 || last == 180.0) && c > 180.0 {
            c = 360.0 - c;
        }
        if first == 0.0 && last == 90.0 && c > 90.0 {
            c = 180.0 - c;
        }
        if first == 90.0 && last == 270.0 {
            if c < 90.0 {
                c = 180.0 - c;
            } else if c > 270.0 {
                c = 540.0 - c;
            }
        }
        c
    }

    /// The luminous flux (lumens): ∫ I dΩ over the sphere, by the midpoint rule on a
    /// 0.1° × 0.25° grid of the interpolated distribution (integrated once, then kept).
    pub fn flux(&self) -> f64 {
        *self.flux.get_or_init(|| self.integrate())
    }

    fn integrate(&self) -> f64 {
        let (ng, nc) = (1800usize, 1440usize);
        let (dg, dc) = (
            std::f64::consts::PI / ng as f64,
            std::f64::consts::TAU / nc as f64,
        );
        let mut sum = 0.0;
        for i in 0..ng {
            let gamma = (i as f64 + 0.5) * dg;
            let ring: f64 = if self.horizontal.len() == 1 {
                self.intensity(0.0, gamma.to_degrees()) * nc as f64
            } else {
                (0..nc)
                    .map(|j| {
                        self.intensity(((j as f64 + 0.5) * dc).to_degrees(), gamma.to_degrees())
                    })
                    .sum()
            };
            sum += ring * gamma.sin();
        }
        sum * dg * dc
    }
}

/// The interval of increasing `angles` holding `x` (within their range): its first index and
/// where `x` lies in it, in [0, 1].
fn bracket(angles: &[f64], x: f64) -> (usize, f64) {
    let n = angles.len();
    if n == 1 || x <= angles[0] {
        return (0, 0.0);
    }
    if x >= angles[n - 1] {
        return (n - 1, 0.0);
    }
    let i = angles.partition_point(|&a| a <= x) - 1;
    (i, (x - angles[i]) / (angles[i + 1] - angles[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Photometry> {
        Photometry::parse(Path::new("l.ies"), text)
    }

    /// A file with the given angles and candela rows (one per horizontal angle).
    fn file(multiplier: f64, lumens: f64, v: &[f64], h: &[f64], rows: &[Vec<f64>]) -> String {
        let join = |x: &[f64]| {
            x.iter()
                .map(|a| a.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        };
        let mut s = format!(
            "IESNA:LM-63-2002\n[TEST] by hand\nTILT=NONE\n1 {lumens} {multiplier} {} {} 1 2 0 0 0\n1.0 1.0 50\n{}\n{}\n",
            v.len(),
            h.len(),
            join(v),
            join(h)
        );
        for r in rows {
            s.push_str(&join(r));
            s.push('\n');
        }
        s
    }

    #[test]
    fn one_c_plane_interpolates_in_gamma_and_is_dark_beyond_its_range() {
        let p = parse(&file(
            2.0,
            1000.0,
            &[0.0, 45.0, 90.0],
            &[0.0],
            &[vec![100.0, 60.0, 0.0]],
        ))
        .unwrap();
        // × 2 (the multiplier); at 22.5°: halfway between 200 and 120.
        assert_eq!(p.intensity(0.0, 0.0), 200.0);
        assert_eq!(p.intensity(123.0, 22.5), 160.0);
        assert_eq!(p.intensity(300.0, 67.5), 60.0);
        assert_eq!(p.intensity(0.0, 120.0), 0.0);
        assert!(!p.absolute);
    }

    #[test]
    fn quadrant_bilateral_and_full_symmetries_fold_c() {
        let v = [0.0, 90.0];
        // 0–90: C 0 → 100, C 90 → 300 at γ 0; C 45 halfway; C 135 mirrors 45; C 270 mirrors 90.
        let q = parse(&file(
            1.0,
            -1.0,
            &v,
            &[0.0, 90.0],
            &[vec![100.0, 0.0], vec![300.0, 0.0]],
        ))
        .unwrap();
        assert!(q.absolute);
        assert_eq!(q.intensity(45.0, 0.0), 200.0);
        assert_eq!(q.intensity(135.0, 0.0), 200.0);
        assert_eq!(q.intensity(270.0, 0.0), 300.0);
        // C 330 folds to 30: a third of the way from 100 to 300.
        assert!((q.intensity(330.0, 0.0) - (100.0 + 200.0 / 3.0)).abs() < 1e-9);
        // 0–180: C 0 → 100, 90 → 200, 180 → 400; C 270 mirrors 90, C 315 mirrors 45 (150).
        let b = parse(&file(
            1.0,
            1.0,
            &v,
            &[0.0, 90.0, 180.0],
            &[vec![100.0, 0.0], vec![200.0, 0.0], vec![400.0, 0.0]],
        ))
        .unwrap();
        assert_eq!(b.intensity(270.0, 0.0), 200.0);
        assert_eq!(b.intensity(315.0, 0.0), 150.0);
        assert_eq!(b.intensity(135.0, 0.0), 300.0);
        // 0–360: no folding; C 350 between 270 (40) and 360 (= C 0, 10).
        let f = parse(&file(
            1.0,
            1.0,
            &v,
            &[0.0, 90.0, 180.0, 270.0, 360.0],
            &[
                vec![10.0, 0.0],
                vec![20.0, 0.0],
                vec![30.0, 0.0],
                vec![40.0, 0.0],
                vec![10.0, 0.0],
            ],
        ))
        .unwrap();
        assert_eq!(f.intensity(315.0, 0.0), 25.0);
        assert!((f.intensity(350.0, 0.0) - (40.0 - 30.0 * 80.0 / 90.0)).abs() < 1e-9);
        // 90–270: mirrored about that plane, C ↦ 180 − C.
        let m = parse(&file(
            1.0,
            1.0,
            &v,
            &[90.0, 180.0, 270.0],
            &[vec![10.0, 0.0], vec![20.0, 0.0], vec![30.0, 0.0]],
        ))
        .unwrap();
        assert_eq!(m.intensity(0.0, 0.0), 20.0);
        assert_eq!(m.intensity(45.0, 0.0), 15.0);
        assert!((m.intensity(300.0, 0.0) - (20.0 + 10.0 * 60.0 / 90.0)).abs() < 1e-9);
        // Bilinear: C 45, γ 45 in the quadrant file: halfway in both.
        assert_eq!(q.intensity(45.0, 45.0), 100.0);
    }

    #[test]
    fn a_cosine_distribution_carries_pi_times_its_peak() {
        // I = I₀ cos γ on the lower hemisphere, tabulated every 5°: Φ = π I₀.
        let v: Vec<f64> = (0..=18).map(|i| f64::from(i) * 5.0).collect();
        let row: Vec<f64> = v.iter().map(|g| 1000.0 * g.to_radians().cos()).collect();
        let p = parse(&file(1.0, 1.0, &v, &[0.0], &[row])).unwrap();
        let flux = p.flux();
        let exact = std::f64::consts::PI * 1000.0;
        eprintln!(
            "flux {flux:.3} vs π I₀ {exact:.3}: {:+.3}%",
            100.0 * (flux / exact - 1.0)
        );
        assert!((flux / exact - 1.0).abs() < 0.005, "{flux} vs {exact}");
    }

    #[test]
    fn malformed_files_name_their_line() {
        let good = file(1.0, 1.0, &[0.0, 90.0], &[0.0], &[vec![10.0, 5.0]]);
        let cases = [
            (
                good.replace("10 5", "10"),
                "l.ies:8:",
                "the file ends before its 2 candela values",
            ),
            (
                good.replace("10 5", "10 5 7"),
                "l.ies:8:",
                "'7' after the 2 candela values",
            ),
            (
                good.replace("10 5", "10 x"),
                "l.ies:8:",
                "'x' is not a number",
            ),
            (
                good.replace("\n0 90\n", "\n90 0\n"),
                "l.ies:6:",
                "vertical angles out of order",
            ),
            (
                good.replace("10 5", "10 -5"),
                "l.ies:8:",
                "candela value -5 is negative",
            ),
            (
                good.replace("TILT=NONE", "TILT=lamp.tlt"),
                "l.ies:3:",
                "TILT=LAMP.TLT",
            ),
            (good.replace("TILT=NONE\n", ""), "l.ies:", "no TILT= line"),
            (
                good.replace(" 1 2 0 0 0", " 2 2 0 0 0"),
                "l.ies:4:",
                "photometric type 2",
            ),
            (
                good.replace("1 1 1 2 1", "1 1 -3 2 1"),
                "l.ies:4:",
                "candela multiplier -3 is negative",
            ),
            (
                good.replace("1.0 1.0 50", "-1 1.0 50"),
                "l.ies:5:",
                "ballast factor -1 is negative",
            ),
        ];
        for (text, at, problem) in cases {
            let e = parse(&text).unwrap_err().to_string();
            assert!(
                e.starts_with(at) && e.contains(problem),
                "expected {at} … {problem}: {e}"
            );
        }
    }

    #[test]
    fn nonsense_angles_give_no_light_and_no_panic() {
        let p = parse(&file(
            1.0,
            1.0,
            &[0.0, 90.0],
            &[0.0, 90.0],
            &[vec![1.0, 0.0], vec![3.0, 0.0]],
        ))
        .unwrap();
        assert_eq!(p.intensity(f64::NAN, 0.0), 1.0);
        assert_eq!(p.intensity(0.0, f64::NAN), 0.0);
        assert_eq!(p.intensity(f64::INFINITY, 0.0), 1.0);
        // Counts far beyond the values present: refused, not allocated.
        let huge = "TILT=NONE\n1 1 1 100000 100000 1 2 0 0 0\n1 1 1\n0\n";
        assert!(parse(huge)
            .unwrap_err()
            .to_string()
            .contains("the file ends"));
    }

    #[test]
    fn mutated_files_parse_or_fail_but_never_panic() {
        // 20,000 mutations of a valid file (bytes replaced, dropped, duplicated, cut short):
        // each parses or is an error naming the file, and what parses gives sane intensities.
        let good = file(
            1.5,
            -1.0,
            &[0.0, 30.0, 60.0, 90.0],
            &[0.0, 90.0],
            &[vec![9.0, 8.0, 4.0, 0.0], vec![7.0, 6.0, 3.0, 0.0]],
        );
        let alphabet = b"0123456789 .-,\nTILE=NOXAe+";
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = |n: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as usize
        };
        for _ in 0..20_000 {
            let mut bytes = good.as_bytes().to_vec();
            for _ in 0..1 + next(4) {
                let at = next(bytes.len().max(1));
                match next(4) {
                    0 if !bytes.is_empty() => bytes[at] = alphabet[next(alphabet.len())],
                    1 if !bytes.is_empty() => {
                        bytes.remove(at);
                    }
                    2 => bytes.insert(at.min(bytes.len()), alphabet[next(alphabet.len())]),
                    _ => bytes.truncate(at),
                }
            }
            let text = String::from_utf8_lossy(&bytes);
            match parse(&text) {
                Ok(p) => {
                    for (c, g) in [(0.0, 0.0), (45.0, 45.0), (300.0, 89.0), (10.0, 170.0)] {
                        let i = p.intensity(c, g);
                        assert!(i.is_finite() && i >= 0.0, "{i}: {text}");
                    }
                }
                Err(e) => assert!(e.to_string().starts_with("l.ies"), "{e}"),
            }
        }
    }

    #[test]
    fn tilt_tables_are_read_through() {
        let text = "IESNA:LM-63-1995\nTILT=INCLUDE\n1\n3\n0 45 90\n1 0.9 0.8\n1 1000 1 2 1 1 2 0 0 0\n1 1 40\n0 90\n0\n50 25\n";
        let p = parse(text).unwrap();
        assert_eq!(p.intensity(0.0, 45.0), 37.5);
    }
}
