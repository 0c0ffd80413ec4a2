//! What meshless results are checked against, sharing no code with the solver: an unbiased
//! path tracer, and the paper's baseline of radiosity on patches.

mod patches;
mod path;

pub use patches::{patch_radiosity, PatchImage, PatchOptions};

pub use path::{path_trace, PathImage, PathOptions};
