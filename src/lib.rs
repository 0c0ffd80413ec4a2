//! meshlight computes how light inter-reflects between diffuse surfaces without meshing the
//! scene into patches: the meshless method of Dobashi, Yamamoto and Nishita (sample points,
//! representative areas, progressive radiosity with ray-cast visibility, adaptive samples,
//! rendering by interpolation).
//!
//! The data flows scene → visibility → samples → areas → solver → render:
//!
//! ```
//! use meshlight::solver::{Control, Options};
//! use meshlight::{Backend, RenderOptions, Scene};
//!
//! // The furnace: a closed cube whose faces all emit Ke 0.1 and reflect Kd 0.5.
//! let scene = Scene::load("scenes/box/scene.toml")?;
//! let vis = Backend::default_backend().build(&scene)?;
//! let options = Options { rounds: 1, ..Options::default() };
//! let solution = meshlight::solve(&scene, vis.as_ref(), &options, &mut |progress| {
//!     // Stop ends the solve at the next shot; the estimate so far can be rendered.
//!     if progress.shots > 100_000 { Control::Stop } else { Control::Continue }
//! })?;
//! let (image, _stats) = meshlight::render(&scene, &solution, vis.as_ref(), &RenderOptions::default())?;
//! // Everywhere the radiance Ke / (1 − Kd) = 0.2.
//! assert!((image.mean() - 0.2).abs() < 0.002, "{}", image.mean());
//! image.write_exr(&std::env::temp_dir().join("meshlight-furnace.exr"))?;
//! # Ok::<(), meshlight::Error>(())
//! ```

mod area;
pub mod budget;
pub mod error;
pub mod ies;
mod light;
pub mod lux;
pub mod metrics;
mod parallel;
pub mod ply;
pub mod progress;
pub mod reference;
pub mod render;
mod sampling;
pub mod scene;
pub mod solver;
pub mod visibility;

pub use error::{Error, Result};
pub use light::MAX_LIGHT_SAMPLES;
pub use progress::{Control, Phase, Progress};
pub use render::{render, Direct, Image, Quantity, RenderOptions};
pub use scene::Scene;
pub use solver::{solve, Options, Preset, Solution};
pub use visibility::{Backend, Visibility};
