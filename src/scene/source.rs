//! Where scene files come from: the disk, or memory (for hosts that hold scenes in memory, and
//! for fuzzing the parsers without touching the file system).

use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

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

/// Reads a whole file as UTF-8 text; errors name the file and, for bad UTF-8, the line.
pub(super) fn read_text(files: &dyn Source, path: &Path) -> Result<String> {
    let bytes = files.read(path).map_err(|source| Error::Read {
        path: path.into(),
        cause: source,
    })?;
    // A UTF-8 byte-order mark (some Windows tools write one) is not part of the first line.
    let bytes = match bytes.strip_prefix(b"\xEF\xBB\xBF") {
        Some(rest) => rest.to_vec(),
        None => bytes,
    };
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        Error::scene(
            path,
            Some(line),
            "not valid UTF-8 text (is this a binary file?)",
        )
    })
}
