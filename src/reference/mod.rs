//! What meshless results are checked against, sharing no code with the solver: an unbiased
//! path tracer.

mod path;

pub use path::{path_trace, PathImage, PathOptions, PathProgress};
