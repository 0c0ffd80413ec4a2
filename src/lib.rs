//! meshlight computes how light inter-reflects between diffuse surfaces without meshing the
//! scene into patches: the meshless method of Dobashi, Yamamoto and Nishita (sample points,
//! representative areas, progressive radiosity with ray-cast visibility, adaptive samples,
//! rendering by interpolation), with a hierarchy of sample clusters beyond the paper
//! (`docs/method.md`).
//!
//! The data flows scene → visibility → solver → field → render: [`solve`] places the samples
//! (Poisson disk), gives them representative areas, lights them (direct, specular, daylight)
//! and shoots their light between them, and leaves a [`Field`] (the samples and their light);
//! [`render()`], [`lux::illuminance`] and [`ply`] read that field and nothing else of the solve:
//!
//! ```
//! use meshlight::{Backend, Control, Options, RenderOptions, Scene};
//!
//! // The furnace: a closed cube whose faces all emit Ke 0.1 and reflect Kd 0.5.
//! let scene = Scene::load("scenes/box/scene.toml")?;
//! let vis = Backend::default_backend().build(&scene)?;
//! let options = Options { rounds: 1, ..Options::default() };
//! let solution = meshlight::solve(&scene, vis.as_ref(), &options, &mut |progress| {
//!     // Stop ends the solve at the next shot; the estimate so far can be rendered.
//!     if progress.shots > 100_000 { Control::Stop } else { Control::Continue }
//! })?;
//! let render = RenderOptions::default();
//! let (image, _stats) =
//!     meshlight::render(&scene, &solution, vis.as_ref(), &render, &mut |_| Control::Continue)?;
//! // Everywhere the radiance Ke / (1 − Kd) = 0.2.
//! assert!((image.mean() - 0.2).abs() < 0.002, "{}", image.mean());
//! image.write_exr(&std::env::temp_dir().join("meshlight-furnace.exr"))?;
//! # Ok::<(), meshlight::Error>(())
//! ```
//!
//! # What a host uses
//! - [`Scene`]: [`Scene::load`] a scene file, or [`Scene::from_parts`] a host's own triangles
//!   ([`scene`]); read through accessors, changed only through checked setters.
//! - [`Visibility`]: [`Backend`] builds Embree's or obvhs's, or a host implements its own
//!   ([`visibility`]).
//! - [`solve`] with [`Options`] (or a [`Preset`]) gives a [`Solution`]; [`render()`] draws its
//!   camera view; [`lux::illuminance`] measures grids; [`reference`](mod@reference) has the path tracer and the
//!   patch baseline; [`metrics`] compares images.
//! - Every long call takes the one progress callback of [`progress`], which may stop it and
//!   get the estimate so far.
//! - Everything fails with [`Error`], naming the file, line or option and the problem; nothing
//!   a host passes in makes the library panic.
//!
//! # Stability
//! The items above are the interface; stage internals (sampling, areas, direct light, the
//! cluster tree) are private, and results are read through accessors, so they can change
//! without breaking a host. Structs that may grow fields are `#[non_exhaustive]`. Before 1.0 a
//! minor version may still change the interface, and its notes say how.

pub mod annual;
mod area;
pub mod budget;
pub mod daylight;
pub mod diagnose;
pub mod distributed;
pub mod error;
mod exec;
pub mod field;
pub mod ies;
mod light;
pub mod lux;
mod material;
pub mod metrics;
mod parallel;
pub mod ply;
pub mod progress;
pub mod reference;
pub mod render;
mod sampling;
pub mod scene;
pub mod solver;
mod specular;
pub mod visibility;

pub use error::{Error, Result};
pub use field::Field;
pub use light::MAX_LIGHT_SAMPLES;
pub use progress::{Control, Phase, Progress};
pub use render::{render, Direct, Image, Quantity, RenderOptions};
pub use scene::Scene;
pub use solver::{solve, Options, Preset, Solution};
pub use visibility::{Backend, Visibility};
