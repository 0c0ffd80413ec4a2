//! The sun positions whose inter-reflected light a year interpolates: a lattice in declination
//! and hour angle over the sun's paths at the site. The sun's direct light is traced at each
//! hour's true position; only the light it sends on, smoother, comes from the lattice.

/// The sun's largest declination (degrees).
const MAX_DECLINATION: f64 = 23.45;

/// Declinations of the lattice.
const DECLINATIONS: usize = 7;
/// Hour angles of the lattice.
const HOUR_ANGLES: usize = 48;
/// The most a sun's altitude differs from a lattice node around it (degrees): an hour angle's
/// step (15°) or a declination's (7.8°) changes the altitude by no more.
pub(crate) const MAX_STEP: f64 = 15.0;
/// The lattice's nodes.
pub(crate) const NODES: usize = DECLINATIONS * HOUR_ANGLES;

/// Declination and hour angle of the lattice's nodes: 7 declinations (7.8° apart) by 24 hour
/// angles (15°, one an hour).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SunLattice {
    latitude: f64,
    declinations: usize,
    hour_angles: usize,
}

impl SunLattice {
    /// The lattice at a site's latitude (degrees).
    pub(crate) fn new(latitude: f64) -> SunLattice {
        SunLattice {
            latitude,
            declinations: DECLINATIONS,
            hour_angles: HOUR_ANGLES,
        }
    }

    /// How many nodes.
    pub(crate) fn len(&self) -> usize {
        self.declinations * self.hour_angles
    }

    fn declination_step(&self) -> f64 {
        2.0 * MAX_DECLINATION / (self.declinations - 1) as f64
    }

    fn hour_step(&self) -> f64 {
        360.0 / self.hour_angles as f64
    }

    /// Node `i`'s (altitude, azimuth) in degrees (azimuth clockwise from north).
    pub(crate) fn position(&self, i: usize) -> (f64, f64) {
        let (d, h) = (i / self.hour_angles, i % self.hour_angles);
        let declination = -MAX_DECLINATION + d as f64 * self.declination_step();
        let hour_angle = -180.0 + h as f64 * self.hour_step();
        horizontal(self.latitude, declination, hour_angle)
    }

    /// The nodes around a sun at (altitude, azimuth) and their bilinear weights.
    pub(crate) fn around(&self, altitude: f64, azimuth: f64) -> [(usize, f64); 4] {
        let (declination, hour_angle) = equatorial(self.latitude, altitude, azimuth);
        let x = ((declination + MAX_DECLINATION) / self.declination_step())
            .clamp(0.0, (self.declinations - 1) as f64);
        let d0 = (x.floor() as usize).min(self.declinations - 2);
        let fd = x - d0 as f64;
        let y = (hour_angle + 180.0).rem_euclid(360.0) / self.hour_step();
        let h0 = (y.floor() as usize) % self.hour_angles;
        let fh = y - y.floor();
        let h1 = (h0 + 1) % self.hour_angles;
        let node = |d: usize, h: usize| d * self.hour_angles + h;
        [
            (node(d0, h0), (1.0 - fd) * (1.0 - fh)),
            (node(d0, h1), (1.0 - fd) * fh),
            (node(d0 + 1, h0), fd * (1.0 - fh)),
            (node(d0 + 1, h1), fd * fh),
        ]
    }
}

/// (altitude, azimuth) in degrees of declination δ and hour angle H (degrees, positive west)
/// at latitude φ.
pub(crate) fn horizontal(latitude: f64, declination: f64, hour_angle: f64) -> (f64, f64) {
    let (p, d, h) = (
        latitude.to_radians(),
        declination.to_radians(),
        hour_angle.to_radians(),
    );
    let sin_alt = p.sin() * d.sin() + p.cos() * d.cos() * h.cos();
    let east = -d.cos() * h.sin();
    let north = p.cos() * d.sin() - p.sin() * d.cos() * h.cos();
    (
        sin_alt.clamp(-1.0, 1.0).asin().to_degrees(),
        east.atan2(north).to_degrees().rem_euclid(360.0),
    )
}

/// (declination, hour angle) in degrees of a sun at (altitude, azimuth) at latitude φ.
pub(crate) fn equatorial(latitude: f64, altitude: f64, azimuth: f64) -> (f64, f64) {
    let (p, a, z) = (
        latitude.to_radians(),
        altitude.to_radians(),
        azimuth.to_radians(),
    );
    let sin_d = p.sin() * a.sin() + p.cos() * a.cos() * z.cos();
    let west = -a.cos() * z.sin();
    let meridian = p.cos() * a.sin() - p.sin() * a.cos() * z.cos();
    (
        sin_d.clamp(-1.0, 1.0).asin().to_degrees(),
        west.atan2(meridian).to_degrees(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horizontal_and_equatorial_are_inverse_and_the_noon_sun_is_due_south() {
        // At noon (H = 0) the sun stands at 90° − φ + δ due south (north of the tropics).
        let (alt, az) = horizontal(52.0, 23.45, 0.0);
        assert!((alt - (90.0 - 52.0 + 23.45)).abs() < 1e-9 && (az - 180.0).abs() < 1e-9);
        // Mornings are east.
        let (_, az) = horizontal(52.0, 0.0, -45.0);
        assert!(az > 90.0 && az < 180.0, "{az}");
        for (lat, d, h) in [
            (52.0, 10.0, -60.0),
            (-33.0, -20.0, 75.0),
            (5.0, 23.0, 150.0),
        ] {
            let (alt, az) = horizontal(lat, d, h);
            let (d2, h2) = equatorial(lat, alt, az);
            assert!((d - d2).abs() < 1e-9 && (h - h2).abs() < 1e-9, "{d2} {h2}");
        }
    }

    #[test]
    fn a_node_is_its_own_interpolation_and_weights_sum_to_one() {
        let lattice = SunLattice::new(40.0);
        for i in [0, 30, 100, lattice.len() - 1] {
            let (alt, az) = lattice.position(i);
            let around = lattice.around(alt, az);
            let w: f64 = around.iter().filter(|(j, _)| *j == i).map(|p| p.1).sum();
            assert!((w - 1.0).abs() < 1e-9, "node {i}: {around:?}");
        }
        let around = lattice.around(35.0, 130.0);
        let total: f64 = around.iter().map(|p| p.1).sum();
        assert!((total - 1.0).abs() < 1e-12);
    }
}
