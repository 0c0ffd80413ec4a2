//! meshlight computes how light inter-reflects between diffuse surfaces without meshing the
//! scene into patches: the meshless method of Dobashi, Yamamoto and Nishita (sample points,
//! representative areas, progressive radiosity with ray-cast visibility, adaptive samples,
//! rendering by interpolation).
//!
//! The data flows scene → visibility → samples → areas → solver → render:
//!
//! ```no_run
//! use meshlight::{Backend, Scene};
//!
//! let scene = Scene::load("scenes/room/scene.toml")?;
//! let visibility = Backend::default_backend().build(&scene)?;
//! println!("{} triangles on {} surfaces", scene.triangles.len(), scene.surfaces.len());
//! # Ok::<(), meshlight::Error>(())
//! ```

pub mod area;
pub mod error;
pub mod light;
mod parallel;
pub mod ply;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod solver;
pub mod visibility;

pub use error::{Error, Result};
pub use render::{render, Image, RenderOptions};
pub use scene::Scene;
pub use solver::{solve, Options, Solution};
pub use visibility::{Backend, Visibility};
