//! The error type of `btf-capture`. As in image-rs/exrs, *invalid input*, *unsupported*
//! data, *limits* and *I/O* are kept apart, and every variant about a file names the file
//! and, for binary formats, the header field at fault, so that a user knows what to fix.

use std::path::PathBuf;

/// Everything that can go wrong while reading or writing captures and Bonn formats.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Malformed bytes or names: truncated data, wrong signature, inconsistent sizes.
    #[error("{file}: field '{field}': {what}")]
    Invalid {
        /// The file (or archive member) at fault.
        file: String,
        /// The header field or name part being read.
        field: String,
        /// What is wrong with it.
        what: String,
    },
    /// Well-formed, but a variant this version does not handle.
    #[error("{file}: unsupported: {what}")]
    Unsupported {
        /// The file at fault.
        file: String,
        /// What is not supported.
        what: String,
    },
    /// A size or count beyond what we are willing to allocate.
    #[error("{file}: field '{field}': limit exceeded: {what}")]
    Limit {
        /// The file at fault.
        file: String,
        /// The field claiming the size.
        field: String,
        /// The claimed size and the limit.
        what: String,
    },
    /// An image that the decoder refused.
    #[error("{file}: cannot decode image: {what}")]
    Image {
        /// The image file or archive member.
        file: String,
        /// The decoder's complaint.
        what: String,
    },
    /// A raw image (or view slot) that could not be registered to the marker layout.
    #[error("{file}: cannot register: {what}")]
    Registration {
        /// The image(s) or view-slot folder at fault.
        file: String,
        /// Which markers were missing and why.
        what: String,
    },
    /// A configuration file (`capture.toml`, `truth.toml`) whose key holds a value out of
    /// range: names the file, the key (`[table] key`) and the value.
    #[error("{file}: {key} = {value}: {what}")]
    ConfigValue {
        /// The file at fault.
        file: String,
        /// The key, as `[table] key` (or `key` at the top level).
        key: String,
        /// The value as written.
        value: String,
        /// The rule it breaks.
        what: String,
    },
    /// A configuration file that does not parse, has a key or table it does not know, or
    /// lacks one it needs: names the file and the key or line.
    #[error("{file}: {key}: {what}")]
    Config {
        /// The file at fault.
        file: String,
        /// The key (`[table] key`), table or line at fault.
        key: String,
        /// What is wrong.
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
    /// An error from the BTF or eigen store.
    #[error(transparent)]
    Store(#[from] btf_core::Error),
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }

    /// An [`Error::Invalid`] for `file` and `field`.
    pub fn invalid(file: &str, field: &str, what: impl Into<String>) -> Self {
        Error::Invalid { file: file.into(), field: field.into(), what: what.into() }
    }

    /// An [`Error::Unsupported`] for `file`.
    pub fn unsupported(file: &str, what: impl Into<String>) -> Self {
        Error::Unsupported { file: file.into(), what: what.into() }
    }

    /// An [`Error::ConfigValue`]: `key` of `file` holds `value`, which breaks `what`.
    pub fn config_value(
        file: &str,
        key: &str,
        value: impl std::fmt::Display,
        what: impl Into<String>,
    ) -> Self {
        Error::ConfigValue {
            file: file.into(),
            key: key.into(),
            value: value.to_string(),
            what: what.into(),
        }
    }

    /// An [`Error::Config`] for `key` of `file`.
    pub fn config(file: &str, key: &str, what: impl Into<String>) -> Self {
        Error::Config { file: file.into(), key: key.into(), what: what.into() }
    }

    /// An [`Error::Limit`] for `file` and `field`.
    pub fn limit(file: &str, field: &str, what: impl Into<String>) -> Self {
        Error::Limit { file: file.into(), field: field.into(), what: what.into() }
    }
}
