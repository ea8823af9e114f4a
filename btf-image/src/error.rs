//! The error type of `btf-image`: invalid input (a map that is not 2:1, a NaN pixel),
//! unsupported formats, sizes beyond the limits, codec failures and I/O, kept apart so
//! that a user knows what to fix. Every message names the file.

use std::path::PathBuf;

/// Everything that can go wrong while reading or writing an image.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An image or map that does not make sense (wrong aspect, NaN or negative pixel, size
    /// mismatch); names the file and the pixel.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// A format this crate does not read or write.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A size beyond what we are willing to allocate.
    #[error("limit exceeded: {0}")]
    Limit(String),
    /// An image that could not be decoded or encoded.
    #[error("{path}: {what}")]
    Image {
        /// The image file.
        path: PathBuf,
        /// The codec's complaint.
        what: String,
    },
    /// An I/O error with the path it happened on.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An error from the atomic writer (`btf_core::fs`).
    #[error(transparent)]
    Core(#[from] btf_core::Error),
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
}
