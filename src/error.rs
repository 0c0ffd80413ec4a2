//! The library's error type: every failure names the file (and line or item where known) and the
//! problem, so a user can fix the input without reading code.

use std::fmt;
use std::path::{Path, PathBuf};

/// Everything that can go wrong in meshlight's library.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be opened or read.
    #[error("{}: cannot read: {cause}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the operating system said (in the message already, so not a `source()`:
        /// printing the chain would say it twice).
        cause: std::io::Error,
    },
    /// A file could not be written.
    #[error("{}: cannot write: {cause}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the operating system said (in the message already).
        cause: std::io::Error,
    },
    /// A scene file (TOML, OBJ or MTL) is malformed or describes something invalid.
    #[error("{}: {problem}", Location { path, line: *line })]
    Scene {
        /// The file at fault.
        path: PathBuf,
        /// The 1-based line, where known.
        line: Option<usize>,
        /// What is wrong, in words.
        problem: String,
    },
    /// A visibility backend failed (Embree device errors, an unknown backend name).
    #[error("visibility backend {backend}: {problem}")]
    Backend {
        /// The backend's name.
        backend: &'static str,
        /// What went wrong.
        problem: String,
    },
    /// A worker thread of the solver failed or panicked (in a host's own `Visibility`, say).
    #[error("worker failed: {problem}")]
    Worker {
        /// What happened.
        problem: String,
    },
    /// A host passed the library something it cannot use: a solution of another scene, an
    /// index out of range, an image whose pixels do not match its size.
    #[error("invalid argument {argument}: {problem}")]
    Argument {
        /// The argument's name.
        argument: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// An option value is out of range or inconsistent.
    #[error("invalid option {option}: {problem}")]
    Option {
        /// The option's name, as the options struct spells its field.
        option: &'static str,
        /// What is wrong with its value.
        problem: String,
    },
    /// Work that would need more memory than the budget allows, refused before allocating.
    #[error("memory budget of {}: {problem}", crate::budget::human_bytes(*budget as f64))]
    Budget {
        /// The budget, bytes.
        budget: usize,
        /// What would not fit, and how much it needs.
        problem: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// A bad argument from a host.
    pub(crate) fn argument(argument: &'static str, problem: impl Into<String>) -> Self {
        Error::Argument {
            argument,
            problem: problem.into(),
        }
    }

    /// A problem in a scene file, with or without a line.
    pub(crate) fn scene(path: &Path, line: Option<usize>, problem: impl Into<String>) -> Self {
        Error::Scene {
            path: path.to_path_buf(),
            line,
            problem: problem.into(),
        }
    }
}

/// `file` or `file:line`, as compilers print locations.
struct Location<'a> {
    path: &'a Path,
    line: Option<usize>,
}

impl fmt::Display for Location<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}", self.path.display()),
            None => write!(f, "{}", self.path.display()),
        }
    }
}
