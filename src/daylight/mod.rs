//! Daylight (scene-format v4): where the sun is ([`spa`], NREL's Solar Position Algorithm) and
//! how bright each part of the sky is ([`sky`]: CIE overcast, uniform, the 15 ISO 15469 general
//! skies, Perez all-weather).

pub(crate) mod entering;
pub mod epw;
pub mod patches;
mod site;
pub mod sky;
pub mod spa;
mod spa_tables;
mod view;

pub use site::{AnnualSettings, Daylight, Site, SUN_RADIUS_DEGREES};
pub use sky::MAX_ILLUMINANCE;
pub use sky::{Sky, SkyModel};
pub use spa::{sun_position, LocalTime, Observer, SunPosition};
pub use view::{sky_view, SkyView};

/// A number for messages: as Rust prints it between 0.001 and a million, in scientific
/// notation outside.
pub(crate) fn human(x: f64) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The days in a month (1-12) of a Gregorian year.
pub fn days_in_month(year: i32, month: u32) -> u32 {
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    match month {
        2 if leap => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// The day of the year (1-366) of a date.
pub fn day_of_year(year: i32, month: u32, day: u32) -> u32 {
    (1..month).map(|m| days_in_month(year, m)).sum::<u32>() + day
}
