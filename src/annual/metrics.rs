//! The climate-based metrics of a year of hourly illuminance at a grid's points (scene-format
//! v4, "A year of weather"): daylight autonomy (IES LM-83's DA and sDA300/50%), useful
//! daylight illuminance (UDI 100-3000 lx), annual sunlight exposure (ASE1000,250h), the
//! EN 17037 target (300 lx over half the grid for half the daylight hours) and the yearly
//! exposure in lux-hours that CIE 157 limits for light-sensitive objects.

/// Illuminance a point must reach for daylight autonomy unless the grid says otherwise (lx).
pub const DA_TARGET: f64 = 300.0;
/// Useful daylight illuminance: from this (lx)...
pub const UDI_LOW: f64 = 100.0;
/// ...to this (lx).
pub const UDI_HIGH: f64 = 3000.0;
/// Direct sunlight that counts towards ASE (lx).
pub const ASE_SUN: f64 = 1000.0;
/// Hours of such sun beyond which a point counts towards ASE.
pub const ASE_HOURS: u32 = 250;
/// EN 17037's target illuminance (lx), over half the grid for half the daylight hours.
pub const EN17037_TARGET: f64 = 300.0;

/// CIE 157:2004's limiting annual exposures for museum objects (lx·h a year), by their
/// responsivity to light, most responsive first; irresponsive objects have none.
pub const CIE157_LIMITS: [(&str, f64); 3] = [
    ("high", 15_000.0),
    ("medium", 150_000.0),
    ("low", 600_000.0),
];

/// The most light-responsive class of museum object (CIE 157) whose yearly limit `exposure`
/// (lx·h) stays within; `None` beyond every limit (irresponsive objects only).
pub fn cie157_class(exposure: f64) -> Option<&'static str> {
    CIE157_LIMITS
        .iter()
        .find(|(_, limit)| exposure <= *limit)
        .map(|(class, _)| *class)
}

/// What a year gives one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct PointYear {
    /// Daylight autonomy: % of occupied hours at or above the target.
    pub da: f64,
    /// Useful daylight illuminance: % of occupied hours within 100-3000 lx.
    pub udi: f64,
    /// Occupied hours whose direct sun alone gives at least 1000 lx.
    pub sun_hours: u32,
    /// The year's exposure over all hours (lx·h).
    pub exposure: f64,
}

/// What a year gives a grid.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct GridSummary {
    /// Points counted (those not inside a solid).
    pub points: usize,
    /// Occupied hours counted (hours left out for missing weather are not).
    pub occupied_hours: u32,
    /// Hours with the sun above the horizon counted.
    pub daylight_hours: u32,
    /// Spatial daylight autonomy: % of points with DA ≥ 50%.
    pub sda: f64,
    /// Annual sunlight exposure: % of points with more than 250 sun hours.
    pub ase: f64,
    /// % of daylight hours in which at least half the points reach 300 lx.
    pub en17037_hours: f64,
    /// Whether that is at least half of them (EN 17037's target for the grid).
    pub en17037_met: bool,
    /// The largest exposure of a point (lx·h).
    pub max_exposure: f64,
}

/// Hour-by-hour counts towards the metrics of one grid.
#[derive(Clone, Debug)]
pub(crate) struct Tally {
    target: f64,
    counted: Vec<bool>,
    above: Vec<u32>,
    useful: Vec<u32>,
    sun: Vec<u32>,
    exposure: Vec<f64>,
    occupied: u32,
    daylight: u32,
    en17037: u32,
}

impl Tally {
    /// Counts for points of which `counted` says which count, with the DA target `target`.
    pub(crate) fn new(counted: Vec<bool>, target: f64) -> Tally {
        let n = counted.len();
        Tally {
            target,
            counted,
            above: vec![0; n],
            useful: vec![0; n],
            sun: vec![0; n],
            exposure: vec![0.0; n],
            occupied: 0,
            daylight: 0,
            en17037: 0,
        }
    }

    /// One hour: each point's illuminance and its direct sunlight alone (lx); whether the hour
    /// is occupied and whether the sun is up.
    pub(crate) fn add(&mut self, values: &[f64], sun: &[f64], occupied: bool, sun_up: bool) {
        if occupied {
            self.occupied += 1;
            for i in 0..values.len() {
                let e = values[i];
                self.above[i] += u32::from(e >= self.target);
                self.useful[i] += u32::from((UDI_LOW..=UDI_HIGH).contains(&e));
                self.sun[i] += u32::from(sun[i] >= ASE_SUN);
            }
        }
        for (x, &e) in self.exposure.iter_mut().zip(values) {
            *x += e;
        }
        if sun_up {
            self.daylight += 1;
            let counted = self.counted.iter().filter(|&&c| c).count();
            let lit = (0..values.len())
                .filter(|&i| self.counted[i] && values[i] >= EN17037_TARGET)
                .count();
            self.en17037 += u32::from(counted > 0 && 2 * lit >= counted);
        }
    }

    /// The per-point metrics (`None` for points not counted) and the summary.
    pub(crate) fn finish(&self) -> (Vec<Option<PointYear>>, GridSummary) {
        let pct = |k: u32, of: u32| {
            if of > 0 {
                100.0 * f64::from(k) / f64::from(of)
            } else {
                0.0
            }
        };
        let points: Vec<Option<PointYear>> = (0..self.counted.len())
            .map(|i| {
                self.counted[i].then(|| PointYear {
                    da: pct(self.above[i], self.occupied),
                    udi: pct(self.useful[i], self.occupied),
                    sun_hours: self.sun[i],
                    exposure: self.exposure[i],
                })
            })
            .collect();
        let counted: Vec<PointYear> = points.iter().flatten().copied().collect();
        let n = counted.len() as u32;
        let share =
            |f: &dyn Fn(&PointYear) -> bool| pct(counted.iter().filter(|p| f(p)).count() as u32, n);
        let en17037_hours = pct(self.en17037, self.daylight);
        let summary = GridSummary {
            points: counted.len(),
            occupied_hours: self.occupied,
            daylight_hours: self.daylight,
            sda: share(&|p| p.da >= 50.0),
            ase: share(&|p| p.sun_hours > ASE_HOURS),
            en17037_hours,
            en17037_met: self.daylight > 0 && 2 * self.en17037 >= self.daylight,
            max_exposure: counted.iter().map(|p| p.exposure).fold(0.0, f64::max),
        };
        (points, summary)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_year_counted_by_hand() {
        // Three points, the third inside a solid. 10 occupied hours: point 0 at 500 lx with
        // 2000 lx of sun in 4 of them, 50 lx in the rest; point 1 at 4000 lx throughout.
        // Plus 6 unoccupied daylight hours at 200 lx everywhere, and 4 dark hours.
        let mut t = Tally::new(vec![true, true, false], 300.0);
        for h in 0..10 {
            let e0 = if h < 4 { 500.0 } else { 50.0 };
            let sun0 = if h < 4 { 2000.0 } else { 0.0 };
            t.add(&[e0, 4000.0, 9e9], &[sun0, 0.0, 0.0], true, true);
        }
        for _ in 0..6 {
            t.add(&[200.0, 200.0, 9e9], &[0.0; 3], false, true);
        }
        for _ in 0..4 {
            t.add(&[0.0; 3], &[0.0; 3], false, false);
        }
        let (points, s) = t.finish();
        let p0 = points[0].unwrap();
        assert_eq!(p0.da, 40.0);
        // 500 lx in 4 hours is useful, 50 lx is not.
        assert_eq!(p0.udi, 40.0);
        assert_eq!(p0.sun_hours, 4);
        assert_eq!(p0.exposure, 4.0 * 500.0 + 6.0 * 50.0 + 6.0 * 200.0);
        let p1 = points[1].unwrap();
        assert_eq!((p1.da, p1.udi), (100.0, 0.0));
        assert_eq!(points[2], None);
        assert_eq!((s.points, s.occupied_hours, s.daylight_hours), (2, 10, 16));
        // sDA: point 1 alone has DA ≥ 50%.
        assert_eq!(s.sda, 50.0);
        assert_eq!(s.ase, 0.0);
        // EN 17037: every occupied hour has half the counted points at 300 lx or more (point 1);
        // the 6 others none: 10 of 16 daylight hours.
        assert_eq!(s.en17037_hours, 62.5);
        assert!(s.en17037_met);
        assert_eq!(s.max_exposure, 40_000.0 + 6.0 * 200.0);
    }

    #[test]
    fn cie_157_classes_follow_its_limits() {
        assert_eq!(cie157_class(15_000.0), Some("high"));
        assert_eq!(cie157_class(15_001.0), Some("medium"));
        assert_eq!(cie157_class(600_000.0), Some("low"));
        assert_eq!(cie157_class(600_001.0), None);
    }
}
