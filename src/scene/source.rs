//! Where scene files come from: the disk, or memory (for hosts that hold scenes in memory, and
//! for fuzzing the parsers without touching the file system).

use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};

/// Reads the bytes of a file a scene refers to.
pub trait Source {
    /// The whole file.
    fn read(&self, path: &Path) -> io::Result<Vec<u8>>;
}

/// Files on disk.
#[derive(Clone, Copy, Debug, Default)]
pub struct Disk;

impl Source for Disk {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        // A FIFO would block the read until a writer came, a device (/dev/zero) would never
        // end: only regular files are read.
        if !std::fs::metadata(path)?.is_file() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "not a regular file (a directory, a FIFO or a device)",
            ));
        }
        std::fs::read(path)
    }
}

/// Files held in memory, by path.
#[derive(Clone, Debug, Default)]
pub struct Memory {
    /// The files.
    pub files: HashMap<PathBuf, Vec<u8>>,
}

impl Memory {
    /// Adds a file.
    pub fn with(mut self, path: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) -> Self {
        self.files.insert(path.into(), bytes.into());
        self
    }
}

impl Source for Memory {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        self.files
            .get(path)
            .cloned()
            .ok_or_else(|| io::Error::new(io::ErrorKind::NotFound, "no such file"))
    }
}
