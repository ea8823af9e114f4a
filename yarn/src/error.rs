//! The error type of `yarn`: invalid input, unsupported data, limits and I/O are kept
//! apart so that a caller can tell a user what to fix. Messages name the file, the field,
//! the curve index, the chart line and column, or the stitch cell at fault.

use std::path::PathBuf;

/// Everything that can go wrong in `yarn`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The caller or a file handed us something that does not make sense (a negative
    /// radius, a NaN coordinate, a ragged chart row, a curve with too few points).
    #[error("invalid input: {0}")]
    Invalid(String),
    /// Well-formed, but not something this version handles (another BCC curve type, a
    /// cable wider than three stitches).
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A size or count beyond what we are willing to allocate, or a count that the data
    /// cannot hold (a BCC header claiming more points than the file has bytes).
    #[error("limit exceeded: {0}")]
    Limit(String),
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

impl From<btf_core::Error> for Error {
    /// The atomic writer of `btf-core` reports I/O with its path; anything else it reports
    /// is a refusal of the path (a folder, no file name), which is invalid input here.
    fn from(e: btf_core::Error) -> Self {
        match e {
            btf_core::Error::Io { path, source } => Error::Io { path, source },
            btf_core::Error::Limit(m) => Error::Limit(m),
            btf_core::Error::Unsupported(m) => Error::Unsupported(m),
            other => Error::Invalid(other.to_string()),
        }
    }
}
