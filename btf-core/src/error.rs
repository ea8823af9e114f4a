//! The error type of `btf-core`: invalid input, unsupported data, limits, corruption and I/O
//! are kept apart so that callers can tell a user what to fix.

use std::path::PathBuf;

/// Everything that can go wrong in `btf-core`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The caller or a file handed us something that does not make sense.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// Well-formed, but not something this version handles.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A size or count beyond what we are willing to allocate.
    #[error("limit exceeded: {0}")]
    Limit(String),
    /// Data on disk does not match its checksum or its declared size.
    #[error("corrupt store {path}: {what}")]
    Corrupt {
        /// The file at fault.
        path: PathBuf,
        /// What is wrong with it.
        what: String,
    },
    /// A non-finite value in data that must be finite.
    #[error("non-finite value (NaN or Inf) in view slot {view}, light {light}{}", .at.as_ref().map(|s| format!(" ({s})")).unwrap_or_default())]
    NonFinite {
        /// View slot index.
        view: usize,
        /// Light index.
        light: usize,
        /// Optional extra location (file, texel).
        at: Option<String>,
    },
    /// An I/O error with the path it happened on.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A JSON metadata document that does not parse.
    #[error("{path}: bad metadata: {source}")]
    Json {
        /// The metadata file.
        path: PathBuf,
        /// The parser's complaint.
        source: serde_json::Error,
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
