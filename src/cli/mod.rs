//! The command line's pieces: arguments and their resolution (`args`), progress (`progress`),
//! reports (`report`), and the commands with more to them than a call and a report.

pub mod args;
pub mod bench;
pub mod lux;
pub mod memory;
pub mod plot;
pub mod progress;
pub mod reference;
pub mod report;
pub mod scale;
pub mod sweep;

pub use args::*;
pub use progress::solve_with_progress;
pub use report::*;
