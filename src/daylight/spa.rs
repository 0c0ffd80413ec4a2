//! The sun's position: NREL's Solar Position Algorithm, Reda and Andreas (2004), "Solar position
//! algorithm for solar radiation applications" (NREL/TP-560-34302), §3.1–3.14, written from the
//! paper. Its stated uncertainty is ±0.0003° over the years −2000 to 6000.
//!
//! The steps follow the paper's numbering: Julian day (3.1), Earth's heliocentric position
//! (3.2), the geocentric Sun (3.3), nutation (3.4), the ecliptic's obliquity (3.5), aberration
//! (3.6), the apparent longitude (3.7), sidereal time (3.8), right ascension and declination
//! (3.9–3.10), hour angle (3.11), the topocentric corrections for parallax (3.12–3.13) and
//! refraction (3.14), and the azimuth (3.15).

use super::spa_tables::{
    B0, B1, L0, L1, L2, L3, L4, L5, NUTATION_ABCD, NUTATION_Y, R0, R1, R2, R3, R4,
};

/// A moment in the local standard time of a time zone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalTime {
    /// Year (Gregorian calendar).
    pub year: i32,
    /// Month, 1–12.
    pub month: u32,
    /// Day of the month, 1–31.
    pub day: u32,
    /// Hour, 0–23.
    pub hour: u32,
    /// Minute, 0–59.
    pub minute: u32,
    /// Second, 0 up to 60.
    pub second: f64,
    /// Hours east of UTC of the standard time (no daylight saving).
    pub timezone: f64,
}

/// Where the sun is seen from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observer {
    /// Degrees, north positive.
    pub latitude: f64,
    /// Degrees, east positive.
    pub longitude: f64,
    /// Metres above sea level.
    pub elevation: f64,
    /// Mean annual pressure, millibars (hPa): the refraction's.
    pub pressure: f64,
    /// Mean annual temperature, °C: the refraction's.
    pub temperature: f64,
}

/// The sun as the observer sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunPosition {
    /// Topocentric zenith angle, degrees, with refraction.
    pub zenith: f64,
    /// Topocentric azimuth, degrees clockwise from north (eastward).
    pub azimuth: f64,
    /// Apparent altitude above the horizon, degrees: 90° − zenith.
    pub altitude: f64,
    /// Earth–sun distance, astronomical units.
    pub distance: f64,
}

/// The atmospheric refraction at sunrise and sunset the paper takes (degrees).
const SUNRISE_REFRACTION: f64 = 0.5667;
/// The sun's apparent radius (degrees), for when refraction applies.
const SUN_RADIUS: f64 = 0.26667;

/// Reduces an angle in degrees to [0, 360).
fn limit(degrees: f64) -> f64 {
    degrees.rem_euclid(360.0)
}

/// The Julian day of a moment (eq. 4): UT, with `fraction` of a day added to the date.
pub fn julian_day(year: i32, month: u32, day: f64) -> f64 {
    let (mut y, mut m) = (f64::from(year), f64::from(month));
    if m < 3.0 {
        y -= 1.0;
        m += 12.0;
    }
    let jd = (365.25 * (y + 4716.0)).floor() + (30.6001 * (m + 1.0)).floor() + day - 1524.5;
    // The Gregorian calendar's correction from 1582-10-15 on.
    if jd > 2_299_160.0 {
        let a = (y / 100.0).floor();
        jd + 2.0 - a + (a / 4.0).floor()
    } else {
        jd
    }
}

/// ΔT = TT − UT (seconds) for a year: the polynomials of Espenak and Meeus (NASA, 2006) from
/// 1986 to 2150, and their long-term parabola outside. An error of a minute in ΔT moves the sun by
/// under 0.001°: ΔT only enters the ephemeris time, not the Earth's rotation.
pub fn delta_t(year: f64) -> f64 {
    if (1986.0..2005.0).contains(&year) {
        let t = year - 2000.0;
        63.86 + 0.3345 * t - 0.060374 * t.powi(2)
            + 0.0017275 * t.powi(3)
            + 0.000651814 * t.powi(4)
            + 0.00002373599 * t.powi(5)
    } else if (2005.0..2050.0).contains(&year) {
        let t = year - 2000.0;
        62.92 + 0.32217 * t + 0.005589 * t * t
    } else if (2050.0..2150.0).contains(&year) {
        -20.0 + 32.0 * ((year - 1820.0) / 100.0).powi(2) - 0.5628 * (2150.0 - year)
    } else {
        -20.0 + 32.0 * ((year - 1820.0) / 100.0).powi(2)
    }
}

/// Σ A cos(B + C τ) over a table's rows.
fn series(terms: &[[f64; 3]], tau: f64) -> f64 {
    terms.iter().map(|[a, b, c]| a * (b + c * tau).cos()).sum()
}

/// A quantity from its tables of powers of τ (eqs. 9–11), / 10⁸.
fn heliocentric(tables: &[&[[f64; 3]]], tau: f64) -> f64 {
    let mut power = 1.0;
    let mut sum = 0.0;
    for table in tables {
        sum += series(table, tau) * power;
        power *= tau;
    }
    sum / 1e8
}

/// Nutation in longitude and obliquity (degrees), from the Julian ephemeris century (§3.4).
fn nutation(jce: f64) -> (f64, f64) {
    let cubic = |a: f64, b: f64, c: f64, d: f64| a + jce * (b + jce * (c + jce * d));
    // Mean elongation of the moon from the sun, mean anomalies of the sun and the moon, the
    // moon's argument of latitude, and the longitude of its ascending node (eqs. 15–19).
    let x = [
        cubic(297.85036, 445_267.111_480, -0.001_914_2, 1.0 / 189_474.0),
        cubic(357.52772, 35_999.050_340, -0.000_160_3, -1.0 / 300_000.0),
        cubic(134.96298, 477_198.867_398, 0.008_697_2, 1.0 / 56_250.0),
        cubic(93.27191, 483_202.017_538, -0.003_682_5, 1.0 / 327_270.0),
        cubic(125.04452, -1_934.136_261, 0.002_070_8, 1.0 / 450_000.0),
    ];
    let (mut psi, mut eps) = (0.0, 0.0);
    for (y, [a, b, c, d]) in NUTATION_Y.iter().zip(NUTATION_ABCD.iter()) {
        let arg: f64 = x
            .iter()
            .zip(y)
            .map(|(xj, &yj)| xj * f64::from(yj))
            .sum::<f64>()
            .to_radians();
        psi += (a + b * jce) * arg.sin();
        eps += (c + d * jce) * arg.cos();
    }
    // The table is in 0.0001″: to degrees.
    (psi / 36_000_000.0, eps / 36_000_000.0)
}

/// The mean obliquity of the ecliptic (arc seconds), eq. 24, U = JME / 10.
fn mean_obliquity(jme: f64) -> f64 {
    const C: [f64; 11] = [
        84_381.448, -4_680.93, -1.55, 1_999.25, -51.38, -249.67, -39.05, 7.12, 27.87, 5.79, 2.45,
    ];
    let u = jme / 10.0;
    C.iter().rev().fold(0.0, |acc, c| acc * u + c)
}

/// The sun's topocentric position at `time` for `observer`, with `delta_t` = TT − UT seconds.
pub fn sun_position(time: &LocalTime, observer: &Observer, delta_t: f64) -> SunPosition {
    // 3.1: Julian day (UT), ephemeris day, centuries and millennium.
    let hours =
        f64::from(time.hour) + f64::from(time.minute) / 60.0 + time.second / 3600.0 - time.timezone;
    let jd = julian_day(time.year, time.month, f64::from(time.day) + hours / 24.0);
    let jde = jd + delta_t / 86_400.0;
    let jc = (jd - 2_451_545.0) / 36_525.0;
    let jce = (jde - 2_451_545.0) / 36_525.0;
    let jme = jce / 10.0;

    // 3.2: Earth's heliocentric longitude, latitude (degrees) and radius vector (AU).
    let l = limit(heliocentric(&[&L0, &L1, &L2, &L3, &L4, &L5], jme).to_degrees());
    let b = heliocentric(&[&B0, &B1], jme).to_degrees();
    let r = heliocentric(&[&R0, &R1, &R2, &R3, &R4], jme);

    // 3.3: the geocentric sun.
    let theta = limit(l + 180.0);
    let beta = -b;

    // 3.4–3.7: nutation, the true obliquity, aberration, the apparent longitude.
    let (dpsi, deps) = nutation(jce);
    let epsilon = mean_obliquity(jme) / 3600.0 + deps;
    let aberration = -20.4898 / (3600.0 * r);
    let lambda = theta + dpsi + aberration;

    // 3.8: apparent sidereal time at Greenwich.
    let nu0 = limit(
        280.460_618_37 + 360.985_647_366_29 * (jd - 2_451_545.0) + 0.000_387_933 * jc * jc
            - jc.powi(3) / 38_710_000.0,
    );
    let nu = nu0 + dpsi * epsilon.to_radians().cos();

    // 3.9–3.10: geocentric right ascension and declination.
    let (lr, er, br) = (lambda.to_radians(), epsilon.to_radians(), beta.to_radians());
    let alpha = limit(
        (lr.sin() * er.cos() - br.tan() * er.sin())
            .atan2(lr.cos())
            .to_degrees(),
    );
    let delta = (br.sin() * er.cos() + br.cos() * er.sin() * lr.sin()).asin();

    // 3.11: the observer's local hour angle.
    let h = limit(nu + observer.longitude - alpha).to_radians();

    // 3.12–3.13: parallax, the topocentric declination and hour angle.
    let xi = (8.794 / (3600.0 * r)).to_radians();
    let phi = observer.latitude.to_radians();
    let u = (0.996_647_19 * phi.tan()).atan();
    let x = u.cos() + observer.elevation / 6_378_140.0 * phi.cos();
    let y = 0.996_647_19 * u.sin() + observer.elevation / 6_378_140.0 * phi.sin();
    let d_alpha = (-x * xi.sin() * h.sin()).atan2(delta.cos() - x * xi.sin() * h.cos());
    let delta_p =
        ((delta.sin() - y * xi.sin()) * d_alpha.cos()).atan2(delta.cos() - x * xi.sin() * h.cos());
    let h_p = h - d_alpha;

    // 3.14: the elevation, refracted where the sun is above the horizon.
    let e0 = (phi.sin() * delta_p.sin() + phi.cos() * delta_p.cos() * h_p.cos())
        .asin()
        .to_degrees();
    let refraction = if e0 >= -(SUN_RADIUS + SUNRISE_REFRACTION) {
        (observer.pressure / 1010.0) * (283.0 / (273.0 + observer.temperature)) * 1.02
            / (60.0 * (e0 + 10.3 / (e0 + 5.11)).to_radians().tan())
    } else {
        0.0
    };
    let e = e0 + refraction;

    // 3.15: the azimuth, from north eastward.
    let gamma = h_p
        .sin()
        .atan2(h_p.cos() * phi.sin() - delta_p.tan() * phi.cos())
        .to_degrees();
    let azimuth = limit(gamma + 180.0);
    SunPosition {
        zenith: 90.0 - e,
        azimuth,
        altitude: e,
        distance: r,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's worked example (its Table A5.1): 2003-10-17 12:30:30 at −7 h, Golden,
    /// Colorado, ΔT = 67 s.
    fn golden() -> (LocalTime, Observer) {
        (
            LocalTime {
                year: 2003,
                month: 10,
                day: 17,
                hour: 12,
                minute: 30,
                second: 30.0,
                timezone: -7.0,
            },
            Observer {
                latitude: 39.742476,
                longitude: -105.1786,
                elevation: 1830.14,
                pressure: 820.0,
                temperature: 11.0,
            },
        )
    }

    #[test]
    fn the_papers_worked_example() {
        let (time, observer) = golden();
        let sun = sun_position(&time, &observer, 67.0);
        // Table A5.1: zenith 50.11162°, azimuth 194.34024°.
        assert!(
            (sun.zenith - 50.11162).abs() < 1e-3,
            "zenith {}",
            sun.zenith
        );
        assert!(
            (sun.azimuth - 194.34024).abs() < 1e-3,
            "azimuth {}",
            sun.azimuth
        );
        // and its intermediate values, to the digits it prints.
        let jd = julian_day(2003, 10, 17.0 + (12.0 + 30.5 / 60.0 + 7.0) / 24.0);
        assert!((jd - 2_452_930.312_847).abs() < 1e-6, "{jd}");
        assert!(
            (sun.distance - 0.996_542_297_4).abs() < 1e-9,
            "{}",
            sun.distance
        );
        let jce = (jd + 67.0 / 86_400.0 - 2_451_545.0) / 36_525.0;
        let (dpsi, deps) = nutation(jce);
        assert!((dpsi + 0.003_998_40).abs() < 1e-8, "{dpsi}");
        assert!((deps - 0.001_666_57).abs() < 1e-8, "{deps}");
    }

    #[test]
    fn the_julian_days_of_the_papers_table_a4_1() {
        // Table A4.1 of the paper.
        for (y, m, d, jd) in [
            (2000, 1, 1.5, 2_451_545.0),
            (1999, 1, 1.0, 2_451_179.5),
            (1987, 1, 27.0, 2_446_822.5),
            (1987, 6, 19.5, 2_446_966.0),
            (1988, 1, 27.0, 2_447_187.5),
            (1988, 6, 19.5, 2_447_332.0),
            (1900, 1, 1.0, 2_415_020.5),
            (1600, 1, 1.0, 2_305_447.5),
            (1600, 12, 31.0, 2_305_812.5),
            (837, 4, 10.3, 2_026_871.8),
            (-123, 12, 31.0, 1_676_496.5),
            (-122, 1, 1.0, 1_676_497.5),
            (-1000, 7, 12.5, 1_356_001.0),
            (-1000, 2, 29.0, 1_355_866.5),
            (-1001, 8, 17.9, 1_355_671.4),
            (-4712, 1, 1.5, 0.0),
        ] {
            let got = julian_day(y, m, d);
            assert!((got - jd).abs() < 1e-6, "{y}-{m}-{d}: {got} != {jd}");
        }
    }

    #[test]
    fn noon_at_the_equinox_on_the_equator_is_nearly_overhead() {
        // 2024-03-20 03:06 UTC was the March equinox: at 12:00 local mean solar time on the
        // equator that day the sun stands within the equation of time (≈ 7.5 min ≈ 1.9°) and
        // the declination's change (≈ 0.2°) of the zenith.
        let time = LocalTime {
            year: 2024,
            month: 3,
            day: 20,
            hour: 12,
            minute: 0,
            second: 0.0,
            timezone: 0.0,
        };
        let observer = Observer {
            latitude: 0.0,
            longitude: 0.0,
            elevation: 0.0,
            pressure: 1010.0,
            temperature: 10.0,
        };
        let sun = sun_position(&time, &observer, delta_t(2024.2));
        assert!(sun.zenith < 2.2, "zenith {}", sun.zenith);
    }
}
