//! The error type of `btf-light`: invalid input (a mesh, a coefficient matrix, a cache
//! file), unsupported requests, limits and I/O, kept apart so that a user knows what to
//! fix; every message about a file names it.

use std::path::PathBuf;

/// Everything that can go wrong while loading meshes or lighting them.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A mesh, a parameter or a file that does not make sense; names the file and place.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// A well-formed request this crate does not handle.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A size beyond what we are willing to allocate.
    #[error("limit exceeded: {0}")]
    Limit(String),
    /// An error from the BTF data layer.
    #[error(transparent)]
    Core(#[from] btf_core::Error),
    /// An error reading an environment map.
    #[error(transparent)]
    Imaging(#[from] btf_image::Error),
    /// An I/O error with the path it happened on.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
}
