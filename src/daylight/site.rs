//! A scene's daylight for one moment: where the building stands (its north and zenith in scene
//! directions), the sky, and the ground below the horizon (scene-format v4 `[site]`, `[sky]`).

use glam::{DVec3, Vec3};

use super::sky::{Sky, MAX_ILLUMINANCE};
use crate::error::{Error, Result};

/// Where a building stands (`[site]`): each key optional, with the defaults scene-format v4
/// gives (north −z, up +y, ground reflectance 0.2).
#[derive(Clone, Debug, PartialEq)]
pub struct Site {
    /// Degrees, north positive.
    pub latitude: Option<f64>,
    /// Degrees, east positive.
    pub longitude: Option<f64>,
    /// Hours east of UTC of the local standard time.
    pub timezone: Option<f64>,
    /// The horizontal scene direction of true north.
    pub north: Vec3,
    /// The zenith.
    pub up: Vec3,
    /// The ground's reflectance outside the model.
    pub ground_reflectance: f64,
}

impl Default for Site {
    fn default() -> Self {
        Site {
            latitude: None,
            longitude: None,
            timezone: None,
            north: -Vec3::Z,
            up: Vec3::Y,
            ground_reflectance: 0.2,
        }
    }
}

/// A year of weather (`[annual]`): what `meshlight annual` computes.
#[derive(Clone, Debug, PartialEq)]
pub struct AnnualSettings {
    /// The EnergyPlus weather file.
    pub weather: std::path::PathBuf,
    /// Occupied hours [start, end), local standard time.
    pub hours: (u32, u32),
    /// Reinhart's MF (1: Tregenza's 145 patches).
    pub sky_subdivision: u32,
    /// The `[site]` (its latitude, longitude and time zone default to the weather file's).
    pub site: Site,
}

impl AnnualSettings {
    /// The CIE overcast sky of 10,000 lx over this site, without sun: the daylight factor's
    /// sky, under which a year's solve places its samples.
    pub fn overcast(&self) -> Result<Daylight> {
        Daylight::new(
            Sky::new(super::SkyModel::CieOvercast, 0.0, 0.0, 10_000.0)?,
            self.site.up,
            self.site.north,
            self.site.ground_reflectance,
            10_000.0,
            None,
            0.0,
        )
    }
}

/// The daylight outside a scene: what a ray leaving the model sees.
#[derive(Clone, Debug, PartialEq)]
pub struct Daylight {
    up: DVec3,
    north: DVec3,
    east: DVec3,
    sky: Sky,
    /// The sky's illuminance on an unobstructed horizontal plane (the daylight factor's
    /// denominator).
    diffuse_horizontal: f64,
    /// Uniform luminance of the ground below the horizon.
    ground: f64,
    /// The sun's zenith angle and azimuth (degrees), where the sky has one.
    sun: Option<(f64, f64)>,
    /// The sun's illuminance on a plane facing it (0: no sunlight).
    direct_normal: f64,
}

/// The sun's apparent radius seen from the Earth: half of 0.533°.
pub const SUN_RADIUS_DEGREES: f64 = 0.2665;

impl Daylight {
    /// Daylight from `sky` over a site whose zenith is `up` and whose north is `north` (scene
    /// directions; north need not be horizontal: its horizontal part is taken), with the sun at
    /// `sun` (zenith angle and azimuth, degrees) delivering `direct_normal` on a plane facing
    /// it, and the ground below the horizon reflecting `ground_reflectance` of the sky's and
    /// the sun's light on the horizontal.
    pub fn new(
        sky: Sky,
        up: Vec3,
        north: Vec3,
        ground_reflectance: f64,
        diffuse_horizontal: f64,
        sun: Option<(f64, f64)>,
        direct_normal: f64,
    ) -> Result<Daylight> {
        let bad = |problem: String| {
            Err(Error::Option {
                option: "site",
                problem,
            })
        };
        let up = up.as_dvec3();
        if !(up.is_finite() && up.length() > 1e-6) {
            return bad(format!("up {up} is not a direction"));
        }
        let up = up.normalize();
        let north = north.as_dvec3();
        let horizontal = north - up * north.dot(up);
        if !(horizontal.is_finite() && horizontal.length() > 1e-3 * north.length().max(1e-30)) {
            return bad(format!(
                "north {north} has no horizontal part (up is {up}): it must point along the \
                 ground"
            ));
        }
        if !(0.0..=1.0).contains(&ground_reflectance) {
            return bad(format!(
                "ground_reflectance {ground_reflectance} is not within 0 to 1"
            ));
        }
        if !((0.0..=MAX_ILLUMINANCE).contains(&diffuse_horizontal)
            && (0.0..=MAX_ILLUMINANCE).contains(&direct_normal))
        {
            return bad(format!(
                "the sky's and the sun's illuminance ({}, {}) must lie in 0 to \
                 {MAX_ILLUMINANCE:e} (the sun at noon gives about 1.3e5 lx)",
                super::human(diffuse_horizontal),
                super::human(direct_normal)
            ));
        }
        if let Some((zenith, azimuth)) = sun {
            if !(zenith.is_finite() && azimuth.is_finite()) {
                return bad("the sun's position is not finite".into());
            }
        }
        if direct_normal > 0.0 && sun.is_none() {
            return bad("direct_normal > 0 needs the sun's position".into());
        }
        let direct_horizontal =
            sun.map_or(0.0, |(z, _)| direct_normal * z.to_radians().cos().max(0.0));
        let north = horizontal.normalize();
        Ok(Daylight {
            up,
            north,
            east: north.cross(up),
            sky,
            diffuse_horizontal,
            ground: ground_reflectance * (diffuse_horizontal + direct_horizontal)
                / std::f64::consts::PI,
            sun,
            direct_normal,
        })
    }

    /// The sun as a light: the unit scene direction towards its centre and its illuminance on
    /// a plane facing it; `None` when it is below the horizon or sends nothing.
    pub fn sun_light(&self) -> Option<(Vec3, f64)> {
        let (zenith, azimuth) = self.sun?;
        (zenith < 90.0 && self.direct_normal > 0.0)
            .then(|| (self.direction(zenith, azimuth), self.direct_normal))
    }

    /// The sky.
    pub fn sky(&self) -> &Sky {
        &self.sky
    }

    /// The zenith, a unit scene direction.
    pub fn up(&self) -> Vec3 {
        self.up.as_vec3()
    }

    /// True north along the ground, a unit scene direction.
    pub fn north(&self) -> Vec3 {
        self.north.as_vec3()
    }

    /// The sky's illuminance on an unobstructed horizontal plane.
    pub fn diffuse_horizontal(&self) -> f64 {
        self.diffuse_horizontal
    }

    /// The luminance of the ground below the horizon.
    pub fn ground_luminance(&self) -> f64 {
        self.ground
    }

    /// The sun's zenith angle and azimuth (degrees, clockwise from north), if the sky has one.
    pub fn sun(&self) -> Option<(f64, f64)> {
        self.sun
    }

    /// The scene direction of a zenith angle and azimuth (degrees).
    pub fn direction(&self, zenith: f64, azimuth: f64) -> Vec3 {
        let (t, a) = (zenith.to_radians(), azimuth.to_radians());
        (self.up * t.cos() + (self.north * a.cos() + self.east * a.sin()) * t.sin()).as_vec3()
    }

    /// The luminance seen looking along scene direction `dir` (need not be unit) from inside
    /// the model out: the sky above the horizon, the ground below (a sharp horizon).
    pub fn radiance(&self, dir: Vec3) -> f64 {
        let d = dir.as_dvec3().normalize_or_zero();
        let up = d.dot(self.up);
        if up <= 0.0 {
            return if d == DVec3::ZERO { 0.0 } else { self.ground };
        }
        let theta = up.clamp(-1.0, 1.0).acos();
        let phi = d.dot(self.east).atan2(d.dot(self.north));
        self.sky.luminance(theta, phi)
    }

    /// The sun's disc seen along `dir`: its luminance E_n / Ω (Ω its solid angle) inside the
    /// disc, else 0. Only what no light sampling reaches adds it (a camera ray, a path after a
    /// pane or a mirror): elsewhere the sun's rays count it.
    pub fn sun_radiance(&self, dir: Vec3) -> f64 {
        let Some((towards, illuminance)) = self.sun_light() else {
            return 0.0;
        };
        let cos_max = SUN_RADIUS_DEGREES.to_radians().cos();
        let d = dir.as_dvec3().normalize_or_zero();
        if d.dot(towards.as_dvec3()) >= cos_max {
            illuminance / (std::f64::consts::TAU * (1.0 - cos_max))
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daylight::SkyModel;

    #[test]
    fn scene_directions_turn_into_the_skys() {
        // y up, north −z: east is +x. A CIE type 12 sky with the sun due south at 40° altitude
        // is brightest towards the sun.
        let sky = Sky::new(SkyModel::Cie(12), 50.0, 180.0, 10_000.0).unwrap();
        let d = Daylight::new(
            sky,
            Vec3::Y,
            -Vec3::Z,
            0.2,
            10_000.0,
            Some((50.0, 180.0)),
            0.0,
        )
        .unwrap();
        let south = d.direction(50.0, 180.0);
        assert!(
            south.abs_diff_eq(Vec3::new(0.0, 0.643, 0.766), 1e-3),
            "{south}"
        );
        let east = d.direction(90.0, 90.0);
        assert!(east.abs_diff_eq(Vec3::X, 1e-6), "{east}");
        let near_sun = d.radiance(south);
        let north = d.radiance(d.direction(50.0, 0.0));
        assert!(near_sun > 3.0 * north, "{near_sun} vs {north}");
        // Below the horizon the ground: ρ E_h / π.
        let ground = d.radiance(Vec3::new(0.3, -1.0, 0.2));
        assert!((ground - 0.2 * 10_000.0 / std::f64::consts::PI).abs() < 1e-9);
        // A tilted north is taken along the ground.
        let tilted = Daylight::new(
            Sky::new(SkyModel::Uniform, 0.0, 0.0, 1.0).unwrap(),
            Vec3::Y,
            Vec3::new(0.0, 0.5, -1.0),
            0.2,
            1.0,
            None,
            0.0,
        )
        .unwrap();
        assert!(tilted.north().abs_diff_eq(-Vec3::Z, 1e-6));
        // North along up is refused.
        let sky = Sky::new(SkyModel::Uniform, 0.0, 0.0, 1.0).unwrap();
        assert!(Daylight::new(sky, Vec3::Y, Vec3::Y, 0.2, 1.0, None, 0.0).is_err());
    }
}
