//! The hours of a year: each weather row's sun (SPA, at the middle of the hour) and light, the
//! sky's luminance over the patches, and each hour's illuminance at the grid points from the
//! coefficients (`docs/method.md` §24).

use glam::Vec3;

use super::coefficients::GridCoefficients;
use super::{Dome, Frame, HourStamp};
use crate::daylight::epw::Weather;
use crate::daylight::patches::Patches;
use crate::daylight::spa::{delta_t, sun_position, LocalTime, Observer};
use crate::daylight::{AnnualSettings, Sky, SkyModel};
use crate::error::Result;
use crate::light::DirectLight;
use crate::lux::LuxOptions;
use crate::progress::Control;
use crate::scene::luminance;
use crate::visibility::Visibility;

/// One hour's light from the weather file.
#[derive(Clone, Debug)]
pub(super) struct Hour {
    pub(super) stamp: HourStamp,
    pub(super) occupied: bool,
    /// The sun's zenith and azimuth (degrees) when it is up.
    pub(super) sun: Option<(f64, f64)>,
    /// Direct normal and diffuse horizontal illuminance (lx), when the sun is up and the file
    /// gives them.
    pub(super) light: Option<(f64, f64)>,
    day_of_year: u32,
}

/// Every hour of `weather` at `frame`: the sun's place at the middle of the hour (EPW hour h
/// covers (h−1):00 to h:00 local standard time) and its light.
pub(super) fn hours(weather: &Weather, frame: &Frame, settings: &AnnualSettings) -> Vec<Hour> {
    let observer = Observer {
        latitude: frame.latitude,
        longitude: frame.longitude,
        elevation: 0.0,
        pressure: 1010.0,
        temperature: 10.0,
    };
    let (start, end) = settings.hours;
    weather
        .hours
        .iter()
        .map(|w| {
            let time = LocalTime {
                year: w.year,
                month: w.month,
                day: w.day,
                hour: w.hour - 1,
                minute: 30,
                second: 0.0,
                timezone: frame.timezone,
            };
            let year = f64::from(w.year) + (f64::from(w.month) - 0.5) / 12.0;
            let sun = sun_position(&time, &observer, delta_t(year));
            let day_of_year = crate::daylight::day_of_year(w.year, w.month, w.day);
            let up = sun.zenith < 90.0;
            Hour {
                stamp: HourStamp {
                    month: w.month,
                    day: w.day,
                    hour: w.hour,
                },
                occupied: start < w.hour && w.hour <= end,
                sun: up.then_some((sun.zenith, sun.azimuth)),
                light: if up {
                    w.illuminance(sun.zenith, day_of_year)
                        .filter(|&(_, dh)| dh > 0.0)
                } else {
                    None
                },
                day_of_year,
            }
        })
        .collect()
}

/// Points on the sky at which an hour's luminance is taken: 2 × 2 per patch of the fine
/// subdivision (equal solid angles), each with its fine and coarse patch.
pub(super) struct SkyPoints {
    /// (zenith angle, azimuth) in radians.
    angles: Vec<(f64, f64)>,
    /// cos θ × dω of each point.
    cos_solid: Vec<f64>,
    fine: Vec<u32>,
    coarse: Vec<u32>,
    fine_len: usize,
    coarse_len: usize,
    /// Σ dω of each coarse patch's points.
    coarse_solid: Vec<f64>,
}

impl SkyPoints {
    pub(super) fn new(fine: &Patches, coarse: &Patches) -> SkyPoints {
        let mut p = SkyPoints {
            angles: Vec::new(),
            cos_solid: Vec::new(),
            fine: Vec::new(),
            coarse: Vec::new(),
            fine_len: fine.len(),
            coarse_len: coarse.len(),
            coarse_solid: vec![0.0; coarse.len()],
        };
        for (f, ((low, high), (a, b))) in fine.bounds().into_iter().enumerate() {
            let (s0, s1) = (low.to_radians().sin(), high.to_radians().sin());
            let solid = (s1 - s0) * (b - a).to_radians() / 4.0;
            for i in 0..2 {
                // Uniform in sin(altitude): equal solid angles.
                let s = s0 + (s1 - s0) * (i as f64 + 0.5) / 2.0;
                let alt = s.asin().to_degrees();
                for j in 0..2 {
                    let az = a + (b - a) * (j as f64 + 0.5) / 2.0;
                    let c = coarse.of(alt, az);
                    p.angles.push(((90.0 - alt).to_radians(), az.to_radians()));
                    p.cos_solid.push(s * solid);
                    p.fine.push(f as u32);
                    p.coarse.push(c as u32);
                    p.coarse_solid[c] += solid;
                }
            }
        }
        p
    }

    /// An hour's mean luminance over each fine and each coarse patch, its sky scaled to
    /// `diffuse_horizontal` over these points.
    pub(super) fn luminances(&self, sky: &Sky, diffuse_horizontal: f64) -> (Vec<f64>, Vec<f64>) {
        let shape: Vec<f64> = self
            .angles
            .iter()
            .map(|&(t, p)| sky.luminance(t, p))
            .collect();
        let horizontal: f64 = shape.iter().zip(&self.cos_solid).map(|(l, w)| l * w).sum();
        let scale = if horizontal > 0.0 {
            diffuse_horizontal / horizontal
        } else {
            0.0
        };
        let (mut fine, mut coarse) = (vec![0.0; self.fine_len], vec![0.0; self.coarse_len]);
        for (i, l) in shape.iter().enumerate() {
            fine[self.fine[i] as usize] += scale * l / 4.0;
            coarse[self.coarse[i] as usize] += scale * l;
        }
        // Each point of a coarse patch stands for the same solid angle: the mean is the sum
        // over the count, which is Σ dω / dω.
        let counts = self.coarse_counts();
        for (c, n) in coarse.iter_mut().zip(counts) {
            if n > 0 {
                *c /= n as f64;
            }
        }
        (fine, coarse)
    }

    fn coarse_counts(&self) -> Vec<usize> {
        let mut counts = vec![0; self.coarse_len];
        for &c in &self.coarse {
            counts[c as usize] += 1;
        }
        counts
    }
}

/// One hour's illuminance and direct sunlight (lx) at every grid's points.
pub(super) fn hour_values(
    hour: &Hour,
    grids: &[GridCoefficients],
    dome: &Dome,
    sun_light: &mut DirectLight,
    vis: &dyn Visibility,
    lux: &LuxOptions,
) -> Result<Vec<(Vec<f32>, Vec<f32>)>> {
    let (frame, sky_points, lattice) = (&dome.frame, &dome.points, &dome.lattice);
    let (Some((zenith, azimuth)), Some((dn, dh))) = (hour.sun, hour.light) else {
        return Ok(Vec::new());
    };
    let (clearness, brightness) =
        crate::daylight::sky::perez_parameters(dh, dn, zenith.min(90.0), Some(hour.day_of_year));
    let shape = Sky::unscaled(
        SkyModel::Perez {
            clearness,
            brightness,
        },
        zenith,
        azimuth,
    )?;
    let (fine, coarse) = sky_points.luminances(&shape, dh);
    let ground = frame.ground_reflectance * (dh + dn * zenith.to_radians().cos().max(0.0))
        / std::f64::consts::PI;
    let altitude = 90.0 - zenith;
    let around = lattice.around(altitude, azimuth);
    sun_light.aim_sun(frame.direction(altitude, azimuth));
    let mut out = Vec::with_capacity(grids.len());
    for g in grids {
        let n = g.points.len();
        let at: Vec<(Vec3, Vec3)> = g.points.iter().map(|&p| (p, g.normal)).collect();
        let ids: Vec<u32> = (0..n as u32).collect();
        let mut quiet = |_: f64| Control::Continue;
        let sun_direct = if dn > 0.0 {
            let (arrivals, _) = sun_light.at(vis, &at, &ids, lux.seed, 1, &mut quiet)?;
            arrivals
                .iter()
                .map(|a| dn * f64::from(luminance(a.irradiance.as_vec3())))
                .collect()
        } else {
            vec![0.0; n]
        };
        let stride = coarse.len() + 1;
        let mut e = Vec::with_capacity(n);
        for (i, &sun) in sun_direct.iter().enumerate() {
            let mut v = sun;
            for &(f, w) in &g.direct[i] {
                let l = fine.get(f as usize).copied().unwrap_or(ground);
                v += f64::from(w) * l;
            }
            let bounced = &g.bounced[i * stride..(i + 1) * stride];
            v += bounced[..coarse.len()]
                .iter()
                .zip(&coarse)
                .map(|(&c, &l)| f64::from(c) * l)
                .sum::<f64>();
            v += f64::from(bounced[coarse.len()]) * ground;
            let suns = &g.sun_bounced[i * lattice.len()..(i + 1) * lattice.len()];
            v += dn
                * around
                    .iter()
                    .map(|&(node, w)| w * f64::from(suns[node]))
                    .sum::<f64>();
            e.push(v as f32);
        }
        out.push((e, sun_direct.iter().map(|&s| s as f32).collect()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daylight::patches::Patches;

    #[test]
    fn an_hours_sky_scaled_on_its_points_matches_the_skys_own_integral() {
        // The year scales each hour's sky on 9,220 points; a one-moment sky on 259,200 cells.
        let sky_points = SkyPoints::new(&Patches::new(4), &Patches::new(1));
        let mut worst: f64 = 0.0;
        for (dn, dh, zenith, azimuth) in [
            (60_000.0, 10_000.0, 30.0, 180.0),
            (20_000.0, 25_000.0, 70.0, 100.0),
            (0.0, 15_000.0, 50.0, 250.0),
            (80_000.0, 8_000.0, 85.0, 280.0),
        ] {
            let (clearness, brightness) =
                crate::daylight::sky::perez_parameters(dh, dn, zenith, Some(172));
            let model = SkyModel::Perez {
                clearness,
                brightness,
            };
            let exact = Sky::new(model, zenith, azimuth, dh).unwrap();
            let shape = Sky::unscaled(model, zenith, azimuth).unwrap();
            let (fine, _) = sky_points.luminances(&shape, dh);
            // The zenith patch's mean, against the exact sky's over the same 4 points.
            let zenith_patch = fine.len() - 1;
            let mean_exact: f64 = (0..sky_points.angles.len())
                .filter(|&i| sky_points.fine[i] as usize == zenith_patch)
                .map(|i| {
                    let (t, p) = sky_points.angles[i];
                    exact.luminance(t, p) / 4.0
                })
                .sum();
            worst = worst.max((fine[zenith_patch] / mean_exact - 1.0).abs());
        }
        assert!(worst < 1e-3, "{worst}");
    }
}
