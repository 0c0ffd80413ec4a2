//! Daylight (scene-format v4): where the sun is ([`spa`], NREL's Solar Position Algorithm) and
//! how bright each part of the sky is ([`sky`]: CIE overcast, uniform, the 15 ISO 15469 general
//! skies, Perez all-weather).

pub(crate) mod entering;
mod site;
pub mod sky;
pub mod spa;
mod spa_tables;
mod view;

pub use site::{Daylight, MAX_ILLUMINANCE, SUN_RADIUS_DEGREES};
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
