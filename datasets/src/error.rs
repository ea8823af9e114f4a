//! The error type of `datasets`: invalid parameters, unsupported files, I/O and errors
//! passed up from the BTF store are kept apart so that a caller can tell a user what to fix.

use std::path::PathBuf;

/// Everything that can go wrong while synthesising or loading data.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter or an input file that does not make sense.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// Well-formed, but not something this crate handles.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// An I/O error with the path it happened on.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An image file that could not be decoded or encoded.
    #[error("{path}: {what}")]
    Image {
        /// The image file.
        path: PathBuf,
        /// The codec's complaint.
        what: String,
    },
    /// An error from the BTF store.
    #[error(transparent)]
    Store(#[from] btf_core::Error),
    /// An error reading or writing an image or environment map.
    #[error(transparent)]
    Imaging(#[from] btf_image::Error),
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
}
