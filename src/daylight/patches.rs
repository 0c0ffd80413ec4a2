//! The sky divided into patches: Tregenza's 145 and Reinhart's subdivisions MF:n (n² × 144 + 1:
//! 577 for MF:2, 2,305 for MF:4), as Radiance's `reinhart.cal` draws them: 7n rows of
//! 90 / (7n + ½) degrees of altitude from the horizon, row r holding n × (30, 30, 24, 24, 18,
//! 12, 6)[r / n] patches of equal azimuth, and one cap at the zenith half a row high. Here
//! patch 0 of each row starts at north and the patches go clockwise (east next), the order in
//! which rows are listed bottom up.

/// Patches per row of Tregenza's sky, from the horizon up (the zenith cap apart).
const TREGENZA: [u32; 7] = [30, 30, 24, 24, 18, 12, 6];

/// One row of patches.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Row {
    /// Altitude of its lower edge, degrees.
    low: f64,
    /// Altitude of its upper edge, degrees.
    high: f64,
    /// Patches in it.
    count: u32,
    /// The index of its first patch.
    first: u32,
}

/// A sky subdivision.
#[derive(Clone, Debug, PartialEq)]
pub struct Patches {
    rows: Vec<Row>,
    len: usize,
}

impl Patches {
    /// Reinhart's MF:`n` subdivision (n = 1: Tregenza's 145 patches); `n` at least 1.
    pub fn new(n: u32) -> Patches {
        let n = n.max(1);
        let height = 90.0 / (7.0 * f64::from(n) + 0.5);
        let mut rows = Vec::new();
        let mut first = 0;
        for r in 0..=7 * n {
            let count = if r == 7 * n {
                1
            } else {
                n * TREGENZA[(r / n) as usize]
            };
            let low = f64::from(r) * height;
            let high = if r == 7 * n { 90.0 } else { low + height };
            rows.push(Row {
                low,
                high,
                count,
                first,
            });
            first += count;
        }
        Patches {
            rows,
            len: first as usize,
        }
    }

    /// How many patches.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none (never: every subdivision has a zenith cap).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The patch holding altitude `alt` and azimuth `az` (degrees, clockwise from north);
    /// altitudes below 0 are the lowest row's.
    pub fn of(&self, alt: f64, az: f64) -> usize {
        let alt = alt.clamp(0.0, 90.0);
        let r = self
            .rows
            .partition_point(|row| row.high <= alt)
            .min(self.rows.len() - 1);
        let row = self.rows[r];
        let step = 360.0 / f64::from(row.count);
        let j = ((az.rem_euclid(360.0) / step) as u32).min(row.count - 1);
        (row.first + j) as usize
    }

    /// Every patch's (altitude range, azimuth range) in degrees, in index order.
    pub fn bounds(&self) -> Vec<((f64, f64), (f64, f64))> {
        let mut out = Vec::with_capacity(self.len);
        for row in &self.rows {
            let step = 360.0 / f64::from(row.count);
            for j in 0..row.count {
                let a = f64::from(j) * step;
                out.push(((row.low, row.high), (a, a + step)));
            }
        }
        out
    }

    /// Each patch's solid angle (sr).
    pub fn solid_angles(&self) -> Vec<f64> {
        self.bounds()
            .iter()
            .map(|&((low, high), (a, b))| {
                (high.to_radians().sin() - low.to_radians().sin()) * (b - a).to_radians()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_subdivisions_have_reinharts_counts_and_cover_the_sky() {
        for (n, count) in [(1, 145), (2, 577), (4, 2305)] {
            let p = Patches::new(n);
            assert_eq!(p.len(), count);
            // The solid angles sum to the hemisphere's 2π.
            let total: f64 = p.solid_angles().iter().sum();
            assert!((total - std::f64::consts::TAU).abs() < 1e-9, "{total}");
        }
        // Tregenza: rows 12° high, the cap from 84° up.
        let p = Patches::new(1);
        assert_eq!(p.of(0.0, 0.0), 0);
        assert_eq!(p.of(5.0, 11.9), 0);
        assert_eq!(p.of(5.0, 12.1), 1);
        assert_eq!(p.of(5.0, 359.0), 29);
        assert_eq!(p.of(12.5, 0.0), 30);
        assert_eq!(p.of(83.9, 359.0), 143);
        assert_eq!(p.of(84.1, 10.0), 144);
        assert_eq!(p.of(90.0, 0.0), 144);
        // Every patch's own centre lies in it.
        for n in [1, 2, 4] {
            let p = Patches::new(n);
            for (i, ((low, high), (a, b))) in p.bounds().into_iter().enumerate() {
                assert_eq!(p.of((low + high) / 2.0, (a + b) / 2.0), i);
            }
        }
    }
}
