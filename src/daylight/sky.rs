//! Sky luminance distributions (scene-format v4, "The sky and the sun"): the CIE overcast and
//! uniform skies, the 15 standard general skies of ISO 15469:2004 / CIE S 011, and the Perez,
//! Seals and Michalsky (1993) all-weather model with its parameters from the direct normal and
//! diffuse horizontal illuminance as Radiance's `gendaylit -L` finds them. Every sky is scaled
//! so that its illuminance on an unobstructed horizontal plane is the diffuse horizontal
//! illuminance asked for, by integration over the upper hemisphere.
//!
//! Directions are given in the sky's own terms: the zenith angle of a sky element and its
//! azimuth (clockwise from north); a scene's `north` and `up` (its `[site]`) will turn scene
//! directions into these.

use crate::error::{Error, Result};

/// The largest sky or sun illuminance a site takes: ten times the brightest the Earth sees,
/// so a unit slip (W/m² for lx, say) passes but an overflow does not.
pub const MAX_ILLUMINANCE: f64 = 1e6;

/// A sky's shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SkyModel {
    /// Constant luminance.
    Uniform,
    /// The CIE standard overcast sky: L(θ) ∝ 1 + 2 cos θ.
    CieOvercast,
    /// ISO 15469 / CIE S 011 standard general sky of this type, 1–15.
    Cie(u8),
    /// Perez 1993 all-weather, from the sky's clearness ε and brightness Δ.
    Perez {
        /// Sky clearness ε, 1 (overcast) to 12 (clear).
        clearness: f64,
        /// Sky brightness Δ, 0.01 to 0.6.
        brightness: f64,
    },
}

/// Gradation a, b and indicatrix c, d, e of the 15 standard general skies (ISO 15469:2004
/// Table 1; CIE S 011/E:2003): types 1–5 overcast, 6–10 intermediate, 11–15 clear.
pub const CIE_GENERAL: [[f64; 5]; 15] = [
    [4.0, -0.70, 0.0, -1.0, 0.00],
    [4.0, -0.70, 2.0, -1.5, 0.15],
    [1.1, -0.80, 0.0, -1.0, 0.00],
    [1.1, -0.80, 2.0, -1.5, 0.15],
    [0.0, -1.00, 0.0, -1.0, 0.00],
    [0.0, -1.00, 2.0, -1.5, 0.15],
    [0.0, -1.00, 5.0, -2.5, 0.30],
    [0.0, -1.00, 10.0, -3.0, 0.45],
    [-1.0, -0.55, 2.0, -1.5, 0.15],
    [-1.0, -0.55, 5.0, -2.5, 0.30],
    [-1.0, -0.55, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 24.0, -2.8, 0.15],
];

/// Perez et al. (1993) Table 1: per clearness bin (ε bounds 1, 1.065, 1.23, 1.5, 1.95, 2.8,
/// 4.5, 6.2), the coefficients of a, b, c, d, e, each x1 + x2 Z + Δ (x3 + x4 Z) with Z the
/// sun's zenith angle in radians (bin 1's c and d take another form: [`perez_coefficients`]).
const PEREZ: [[[f64; 4]; 5]; 8] = [
    [
        [1.3525, -0.2576, -0.2690, -1.4366],
        [-0.7670, 0.0007, 1.2734, -0.1233],
        [2.8000, 0.6004, 1.2375, 1.0000],
        [1.8734, 0.6297, 0.9738, 0.2809],
        [0.0356, -0.1246, -0.5718, 0.9938],
    ],
    [
        [-1.2219, -0.7730, 1.4148, 1.1016],
        [-0.2054, 0.0367, -3.9128, 0.9156],
        [6.9750, 0.1774, 6.4477, -0.1239],
        [-1.5798, -0.5081, -1.7812, 0.1080],
        [0.2624, 0.0672, -0.2190, -0.4285],
    ],
    [
        [-1.1000, -0.2515, 0.8952, 0.0156],
        [0.2782, -0.1812, -4.5000, 1.1766],
        [24.7219, -13.0812, -37.7000, 34.8438],
        [-5.0000, 1.5218, 3.9229, -2.6204],
        [-0.0156, 0.1597, 0.4199, -0.5562],
    ],
    [
        [-0.5484, -0.6654, -0.2672, 0.7117],
        [0.7234, -0.6219, -5.6812, 2.6297],
        [33.3389, -18.3000, -62.2500, 52.0781],
        [-3.5000, 0.0016, 1.1477, 0.1062],
        [0.4659, -0.3296, -0.0876, -0.0329],
    ],
    [
        [-0.6000, -0.3566, -2.5000, 2.3250],
        [0.2937, 0.0496, -5.6812, 1.8415],
        [21.0000, -4.7656, -21.5906, 7.2492],
        [-3.5000, -0.1554, 1.4062, 0.3988],
        [0.0032, 0.0766, -0.0656, -0.1294],
    ],
    [
        [-1.0156, -0.3670, 1.0078, 1.4051],
        [0.2875, -0.5328, -3.8500, 3.3750],
        [14.0000, -0.9999, -7.1406, 7.5469],
        [-3.4000, -0.1078, -1.0750, 1.5702],
        [-0.0672, 0.4016, 0.3017, -0.4844],
    ],
    [
        [-1.0000, 0.0211, 0.5025, -0.5119],
        [-0.3000, 0.1922, 0.7023, -1.6317],
        [19.0000, -5.0000, 1.2438, -1.9094],
        [-4.0000, 0.0250, 0.3844, 0.2656],
        [1.0468, -0.3788, -2.4517, 1.4656],
    ],
    [
        [-1.0500, 0.0289, 0.4260, 0.3590],
        [-0.3250, 0.1156, 0.7781, 0.0025],
        [31.0625, -14.5000, -46.1148, 55.3750],
        [-7.2312, 0.4050, 13.3500, 0.6234],
        [1.5000, -0.6426, 1.8564, 0.5636],
    ],
];

/// The upper bounds of the Perez clearness bins (the last bin is open).
const CLEARNESS_BINS: [f64; 7] = [1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200];

/// The ranges `gendaylit` holds ε and Δ to.
const CLEARNESS_RANGE: (f64, f64) = (1.0, 12.01 - 0.001);
const BRIGHTNESS_RANGE: (f64, f64) = (0.01, 0.6);

/// The solar constant (W/m²) and its illuminance (lx) as `gendaylit` takes them.
const SOLAR_CONSTANT_W: f64 = 1367.0;
const SOLAR_CONSTANT_LX: f64 = 127_500.0;

/// Perez 1990 luminous efficacy per clearness bin (a, b, c, d), diffuse horizontal:
/// K = a + b W + c cos Z + d ln Δ (lm/W).
const DIFFUSE_EFFICACY: [[f64; 4]; 8] = [
    [97.24, -0.46, 12.00, -8.91],
    [107.22, 1.15, 0.59, -3.95],
    [104.97, 2.96, -5.53, -8.77],
    [102.39, 5.59, -13.95, -13.90],
    [100.71, 5.94, -22.75, -23.74],
    [106.42, 3.83, -36.15, -28.83],
    [141.88, 1.90, -53.24, -14.03],
    [152.23, 0.35, -45.27, -7.98],
];

/// Perez 1990 luminous efficacy per clearness bin, direct normal:
/// K = a + b W + c exp(5.73 Z − 5) + d Δ (lm/W, at least 0).
const DIRECT_EFFICACY: [[f64; 4]; 8] = [
    [57.20, -4.55, -2.98, 117.12],
    [98.99, -3.46, -1.21, 12.38],
    [109.83, -4.90, -1.71, -8.81],
    [110.34, -5.84, -1.99, -4.56],
    [106.36, -3.97, -1.75, -6.16],
    [107.19, -1.25, -1.51, -26.73],
    [105.75, 0.77, -1.26, -34.44],
    [101.18, 1.58, -1.10, -8.29],
];

/// Precipitable water (cm) from `gendaylit`'s default dew point (10.97 °C), Perez 1990.
fn precipitable_water() -> f64 {
    (0.07 * 10.973_531_15 - 0.075f64).exp()
}

fn clearness_bin(clearness: f64) -> usize {
    CLEARNESS_BINS
        .iter()
        .position(|&bound| clearness < bound)
        .unwrap_or(CLEARNESS_BINS.len())
}

/// The relative air mass at a sun zenith angle (degrees), Kasten (1966) as `gendaylit` takes it.
pub fn air_mass(zenith: f64) -> f64 {
    let z = zenith.min(90.0);
    1.0 / (z.to_radians().cos() + 0.15 * (93.885 - z).powf(-1.253))
}

/// The Earth's orbital eccentricity correction for a day of the year (1–366), Spencer (1971).
pub fn eccentricity(day_of_year: u32) -> f64 {
    let g = std::f64::consts::TAU * (f64::from(day_of_year) - 1.0) / 365.0;
    1.00011
        + 0.034221 * g.cos()
        + 0.00128 * g.sin()
        + 0.000719 * (2.0 * g).cos()
        + 0.000077 * (2.0 * g).sin()
}

/// Perez's ε from diffuse horizontal and direct normal (same units) at a sun zenith (degrees).
fn clearness(diffuse: f64, direct: f64, zenith: f64) -> f64 {
    let z3 = 1.041 * zenith.to_radians().powi(3);
    ((diffuse + direct) / diffuse + z3) / (1.0 + z3)
}

/// The Perez sky's clearness ε and brightness Δ from the diffuse horizontal and direct normal
/// illuminance (lx) at a sun zenith angle (degrees) on a day of the year (`None`: no
/// eccentricity correction): `gendaylit -L`'s conversion, which turns illuminance into
/// irradiance by the Perez 1990 efficacies found by nine rounds of iteration from the solar
/// constant's ratio.
pub fn perez_parameters(
    diffuse_horizontal: f64,
    direct_normal: f64,
    zenith: f64,
    day_of_year: Option<u32>,
) -> (f64, f64) {
    let extraterrestrial = SOLAR_CONSTANT_W * day_of_year.map_or(1.0, eccentricity);
    let m = air_mass(zenith);
    let parameters = |diffuse: f64, direct: f64| {
        let e = clearness(diffuse, direct, zenith).clamp(CLEARNESS_RANGE.0, CLEARNESS_RANGE.1);
        let d = (diffuse * m / extraterrestrial).clamp(BRIGHTNESS_RANGE.0, BRIGHTNESS_RANGE.1);
        (e, d)
    };
    let mut diffuse = diffuse_horizontal * SOLAR_CONSTANT_W / SOLAR_CONSTANT_LX;
    let mut direct = direct_normal * SOLAR_CONSTANT_W / SOLAR_CONSTANT_LX;
    let (mut e, mut d) = parameters(diffuse, direct);
    let w = precipitable_water();
    let cos_z = zenith.to_radians().cos();
    for _ in 0..9 {
        let bin = clearness_bin(e);
        let [a, b, c, dd] = DIFFUSE_EFFICACY[bin];
        diffuse = diffuse_horizontal / (a + b * w + c * cos_z + dd * d.ln());
        let [a, b, c, dd] = DIRECT_EFFICACY[bin];
        let k = (a + b * w + c * (5.73 * zenith.to_radians() - 5.0).exp() + dd * d).max(0.0);
        direct = if k < 0.1 { 0.0 } else { direct_normal / k };
        (e, d) = parameters(diffuse, direct);
    }
    (e, d)
}

/// Direct normal and diffuse horizontal illuminance (lx) from the irradiances (W/m²) at a sun
/// zenith angle (degrees) on a day of the year, by Perez's 1990 luminous efficacies (the
/// clearness bin, brightness and precipitable water as in [`perez_parameters`]): how a weather
/// file without illuminance is read.
pub(crate) fn illuminance_of_irradiance(
    direct_normal: f64,
    diffuse_horizontal: f64,
    zenith: f64,
    day_of_year: u32,
) -> (f64, f64) {
    if diffuse_horizontal <= 0.0 && direct_normal <= 0.0 {
        return (0.0, 0.0);
    }
    let zenith = zenith.clamp(0.0, 90.0);
    let e = if diffuse_horizontal > 0.0 {
        clearness(diffuse_horizontal, direct_normal, zenith)
            .clamp(CLEARNESS_RANGE.0, CLEARNESS_RANGE.1)
    } else {
        CLEARNESS_RANGE.1
    };
    let extraterrestrial = SOLAR_CONSTANT_W * eccentricity(day_of_year);
    let d = (diffuse_horizontal * air_mass(zenith) / extraterrestrial)
        .clamp(BRIGHTNESS_RANGE.0, BRIGHTNESS_RANGE.1);
    let (w, cos_z) = (precipitable_water(), zenith.to_radians().cos());
    let bin = clearness_bin(e);
    let [a, b, c, dd] = DIFFUSE_EFFICACY[bin];
    let diffuse = diffuse_horizontal * (a + b * w + c * cos_z + dd * d.ln()).max(0.0);
    let [a, b, c, dd] = DIRECT_EFFICACY[bin];
    let k = (a + b * w + c * (5.73 * zenith.to_radians() - 5.0).exp() + dd * d).max(0.0);
    (direct_normal * k, diffuse)
}

/// The five Perez coefficients a–e for clearness ε, brightness Δ and sun zenith Z (radians),
/// with the 1993 paper's correction Δ ≥ 0.2 for 1.065 < ε < 2.8, as `gendaylit` applies it.
pub fn perez_coefficients(clearness: f64, brightness: f64, sun_zenith: f64) -> [f64; 5] {
    let delta = if clearness > 1.065 && clearness < 2.8 {
        brightness.max(0.2)
    } else {
        brightness
    };
    let bin = clearness_bin(clearness);
    let x = &PEREZ[bin];
    let z = sun_zenith;
    let linear = |r: &[f64; 4]| r[0] + r[1] * z + delta * (r[2] + r[3] * z);
    let mut k = [0.0; 5];
    for (i, row) in x.iter().enumerate() {
        k[i] = linear(row);
    }
    if bin == 0 {
        k[2] = (delta * (x[2][0] + x[2][1] * z)).powf(x[2][2]).exp() - x[2][3];
        k[3] = -(delta * (x[3][0] + x[3][1] * z)).exp() + x[3][2] + delta * x[3][3];
    }
    k
}

/// A sky: its shape, the sun's place, and the scale that makes its horizontal illuminance the
/// one asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct Sky {
    model: SkyModel,
    /// The sun's zenith angle and azimuth (radians); used by the skies that depend on it.
    sun: (f64, f64),
    /// The Perez coefficients, or the CIE general sky's a–e.
    coefficients: [f64; 5],
    /// Luminance = scale × shape.
    scale: f64,
}

/// Zenith-angle rings and azimuth steps of the normalising integral. The integrand is smooth
/// (the skies' circumsolar peaks are exponentials of the angle, not spikes): 360 × 720 cells
/// hold the horizontal illuminance of every sky to 10⁻⁵ of a grid 3× finer each way (unit test).
const RINGS: usize = 360;
const STEPS: usize = 720;

impl Sky {
    /// The sky of `model` with the sun at zenith angle `sun_zenith` and `sun_azimuth`
    /// (degrees, clockwise from north), scaled so that its horizontal illuminance is
    /// `diffuse_horizontal`.
    pub fn new(
        model: SkyModel,
        sun_zenith: f64,
        sun_azimuth: f64,
        diffuse_horizontal: f64,
    ) -> Result<Sky> {
        if !(0.0..=MAX_ILLUMINANCE).contains(&diffuse_horizontal) {
            return Err(Error::Option {
                option: "sky",
                problem: format!(
                    "diffuse_horizontal {} is not an illuminance in 0 to {:e}",
                    super::human(diffuse_horizontal),
                    MAX_ILLUMINANCE
                ),
            });
        }
        let mut sky = Sky::unscaled(model, sun_zenith, sun_azimuth)?;
        let unscaled = sky.horizontal_illuminance();
        sky.scale = if unscaled > 0.0 {
            diffuse_horizontal / unscaled
        } else {
            0.0
        };
        Ok(sky)
    }

    /// The sky's shape, luminance 1 × the model's relative luminance (no normalising
    /// integral): for a host that scales many skies itself (a year of daylight).
    pub(crate) fn unscaled(model: SkyModel, sun_zenith: f64, sun_azimuth: f64) -> Result<Sky> {
        let bad = |problem: String| {
            Err(Error::Option {
                option: "sky",
                problem,
            })
        };
        if !(sun_zenith.is_finite() && sun_azimuth.is_finite()) {
            return bad("the sun's position is not finite".into());
        }
        let coefficients = match model {
            SkyModel::Cie(t) if (1..=15).contains(&t) => CIE_GENERAL[usize::from(t) - 1],
            SkyModel::Cie(t) => return bad(format!("CIE general sky type {t} is not 1 to 15")),
            SkyModel::Perez {
                clearness,
                brightness,
            } => {
                if !(clearness.is_finite() && brightness.is_finite()) {
                    return bad("the Perez clearness and brightness must be finite".into());
                }
                let e = clearness.clamp(CLEARNESS_RANGE.0, CLEARNESS_RANGE.1);
                let d = brightness.clamp(BRIGHTNESS_RANGE.0, BRIGHTNESS_RANGE.1);
                // The sun's zenith within the sky: a sun below the horizon shapes the sky as
                // one on it.
                perez_coefficients(e, d, sun_zenith.clamp(0.0, 90.0).to_radians())
            }
            _ => [0.0; 5],
        };
        Ok(Sky {
            model,
            sun: (sun_zenith.to_radians(), sun_azimuth.to_radians()),
            coefficients,
            scale: 1.0,
        })
    }

    /// The model.
    pub fn model(&self) -> SkyModel {
        self.model
    }

    /// The sky's shape at zenith angle `theta` and azimuth `phi` (radians), unscaled.
    fn shape(&self, theta: f64, phi: f64) -> f64 {
        let cos_t = theta.cos();
        let angle_to_sun = || {
            let (zs, azs) = self.sun;
            (cos_t * zs.cos() + theta.sin() * zs.sin() * (phi - azs).cos())
                .clamp(-1.0, 1.0)
                .acos()
        };
        let [a, b, c, d, e] = self.coefficients;
        match self.model {
            SkyModel::Uniform => 1.0,
            SkyModel::CieOvercast => 1.0 + 2.0 * cos_t,
            SkyModel::Cie(_) => {
                // ISO 15469: gradation φ(Z) = 1 + a exp(b / cos Z), φ(90°) = 1; indicatrix
                // f(χ) = 1 + c (exp(d χ) − exp(d π/2)) + e cos² χ.
                let gradation = if cos_t > 0.0 {
                    1.0 + a * (b / cos_t).exp()
                } else {
                    1.0
                };
                let chi = angle_to_sun();
                let indicatrix = 1.0
                    + c * ((d * chi).exp() - (d * std::f64::consts::FRAC_PI_2).exp())
                    + e * chi.cos().powi(2);
                gradation * indicatrix
            }
            SkyModel::Perez { .. } => {
                // Radiance's perezlum.cal holds cos θ at 0.01 near the horizon.
                let gradation = 1.0 + a * (b / cos_t.max(0.01)).exp();
                let gamma = angle_to_sun();
                let indicatrix = 1.0 + c * (d * gamma).exp() + e * gamma.cos().powi(2);
                // The model can dip below zero far from the sun in some bins: no negative
                // light.
                (gradation * indicatrix).max(0.0)
            }
        }
    }

    /// Luminance at zenith angle `theta` and azimuth `phi` (radians, clockwise from north);
    /// 0 below the horizon (the ground is not the sky's).
    pub fn luminance(&self, theta: f64, phi: f64) -> f64 {
        if theta.cos() <= 0.0 {
            return 0.0;
        }
        self.scale * self.shape(theta, phi)
    }

    /// Luminance at the zenith.
    pub fn zenith_luminance(&self) -> f64 {
        self.luminance(0.0, 0.0)
    }

    /// ∫ L cos θ dω over the upper hemisphere, by the midpoint rule in (cos θ, φ): what the sky
    /// gives an unobstructed horizontal plane.
    pub fn horizontal_illuminance(&self) -> f64 {
        self.integrate(RINGS, STEPS)
    }

    fn integrate(&self, rings: usize, steps: usize) -> f64 {
        let (dmu, dphi) = (1.0 / rings as f64, std::f64::consts::TAU / steps as f64);
        let mut sum = 0.0;
        for i in 0..rings {
            // μ = cos θ at the ring's middle; dω = dμ dφ, times the cosine μ.
            let mu = (i as f64 + 0.5) * dmu;
            let theta = mu.acos();
            let ring: f64 = (0..steps)
                .map(|j| self.scale * self.shape(theta, (j as f64 + 0.5) * dphi))
                .sum();
            sum += ring * mu;
        }
        sum * dmu * dphi
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn every_sky_gives_its_diffuse_horizontal_illuminance() {
        let mut skies = vec![SkyModel::Uniform, SkyModel::CieOvercast];
        skies.extend((1..=15).map(SkyModel::Cie));
        skies.push(SkyModel::Perez {
            clearness: 1.0,
            brightness: 0.2,
        });
        skies.push(SkyModel::Perez {
            clearness: 6.5,
            brightness: 0.15,
        });
        let mut worst: f64 = 0.0;
        for model in skies {
            for (zenith, azimuth) in [(30.0, 180.0), (75.0, 250.0)] {
                let sky = Sky::new(model, zenith, azimuth, 10_000.0).unwrap();
                // A grid three times finer each way, independent of the one that scaled.
                let fine = sky.integrate(3 * RINGS, 3 * STEPS);
                worst = worst.max((fine / 10_000.0 - 1.0).abs());
                assert!(
                    (fine / 10_000.0 - 1.0).abs() < 1e-4,
                    "{model:?} at {zenith}°: {fine}"
                );
            }
        }
        println!("worst relative difference {worst:e}");
    }

    #[test]
    fn the_overcast_and_uniform_skies_in_closed_form() {
        // Overcast: E_h = ∫ Lz (1 + 2 cos θ) / 3 · cos θ dω = Lz (π + 4π/3) / 3 = 7π Lz / 9.
        let sky = Sky::new(SkyModel::CieOvercast, 0.0, 0.0, 10_000.0).unwrap();
        let lz = 9.0 * 10_000.0 / (7.0 * PI);
        assert!((sky.zenith_luminance() / lz - 1.0).abs() < 1e-4);
        // Three times brighter at the zenith than at the horizon.
        let horizon = sky.luminance(PI / 2.0 - 1e-9, 0.0);
        assert!((sky.zenith_luminance() / horizon - 3.0).abs() < 1e-6);
        // Uniform: E_h = π L.
        let sky = Sky::new(SkyModel::Uniform, 0.0, 0.0, 10_000.0).unwrap();
        assert!((sky.luminance(1.0, 2.0) - 10_000.0 / PI).abs() < 1e-3);
    }

    #[test]
    fn a_cie_general_sky_follows_the_standards_formula() {
        // Type 12 (CIE standard clear sky, low turbidity) with the sun at 40° altitude: the ratio
        // of the luminance at an element to the zenith's is f(χ) φ(Z) / (f(Zs) φ(0)),
        // ISO 15469 eq. (1), written here from the standard.
        let (a, b, c, d, e) = (-1.0, -0.32, 10.0, -3.0, 0.45);
        let phi = |z: f64| 1.0 + a * (b / z.cos()).exp();
        let f = |x: f64| 1.0 + c * ((d * x).exp() - (d * PI / 2.0).exp()) + e * x.cos().powi(2);
        let zs = 50f64.to_radians();
        let sky = Sky::new(SkyModel::Cie(12), 50.0, 180.0, 10_000.0).unwrap();
        for (z, az) in [(0.3f64, 1.0), (1.2, 3.0), (0.8, PI)] {
            let chi = (z.cos() * zs.cos() + z.sin() * zs.sin() * (az - PI).cos()).acos();
            let expected = f(chi) * phi(z) / (f(zs) * phi(0.0));
            let got = sky.luminance(z, az) / sky.zenith_luminance();
            assert!((got / expected - 1.0).abs() < 1e-9, "{got} vs {expected}");
        }
    }

    #[test]
    fn perez_coefficients_from_the_published_table() {
        // ε = 3.2 (bin 6), Δ = 0.25, sun zenith 0.6 rad: a = x1 + x2 Z + Δ (x3 + x4 Z) with the
        // 1993 paper's row for 2.8 ≤ ε < 4.5, written out here.
        let (z, dl) = (0.6, 0.25);
        let row = |x1: f64, x2: f64, x3: f64, x4: f64| x1 + x2 * z + dl * (x3 + x4 * z);
        let expected = [
            row(-1.0156, -0.3670, 1.0078, 1.4051),
            row(0.2875, -0.5328, -3.8500, 3.3750),
            row(14.0000, -0.9999, -7.1406, 7.5469),
            row(-3.4000, -0.1078, -1.0750, 1.5702),
            row(-0.0672, 0.4016, 0.3017, -0.4844),
        ];
        let got = perez_coefficients(3.2, dl, z);
        for (g, e) in got.iter().zip(expected) {
            assert!((g - e).abs() < 1e-12, "{got:?} vs {expected:?}");
        }
        // Bin 1 (overcast), its own c and d.
        let (z, dl) = (1.0, 0.3);
        let got = perez_coefficients(1.02, dl, z);
        let c = (dl * (2.8 + 0.6004 * z)).powf(1.2375).exp() - 1.0;
        let d = -(dl * (1.8734 + 0.6297 * z)).exp() + 0.9738 + dl * 0.2809;
        assert!((got[2] - c).abs() < 1e-12 && (got[3] - d).abs() < 1e-12);
        // The sky's luminance is (1 + a e^{b/cos θ})(1 + c e^{dγ} + e cos²γ), scaled.
        let [a, b, c, d, e] = perez_coefficients(3.2, 0.25, 0.6);
        let sky = Sky::new(
            SkyModel::Perez {
                clearness: 3.2,
                brightness: 0.25,
            },
            0.6f64.to_degrees(),
            180.0,
            10_000.0,
        )
        .unwrap();
        let l = |t: f64, g: f64| {
            (1.0 + a * (b / t.cos()).exp()) * (1.0 + c * (d * g).exp() + e * g.cos().powi(2))
        };
        // At the zenith γ = Z; straight away from the sun at θ = 0.9: γ = 0.9 + 0.6.
        let ratio = sky.luminance(0.9, 0.0) / sky.zenith_luminance();
        assert!((ratio / (l(0.9, 1.5) / l(0.0, 0.6)) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn perez_parameters_are_those_of_the_definitions_for_irradiance_like_input() {
        // With no direct light, ε = 1; Δ grows with the diffuse light and the air mass.
        let (e, d) = perez_parameters(20_000.0, 0.0, 40.0, Some(172));
        assert_eq!(e, 1.0);
        assert!(d > 0.05 && d < 0.6, "{d}");
        // A bright sun in a clear sky: ε in the clear bins.
        let (e, _) = perez_parameters(12_000.0, 80_000.0, 35.0, Some(172));
        assert!(e > 4.5, "{e}");
    }
}
