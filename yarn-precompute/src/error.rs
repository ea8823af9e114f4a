//! The crate's one error type: invalid input (bad bake settings, the field named), limits
//! (sizes that would allocate too much), errors of the crates below, and I/O. A corrupt
//! or mismatched cache file is not an error: [`crate::cache`] rebuilds it.

use std::path::PathBuf;

/// Everything that can go wrong in a bake.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A bake setting or an input is out of its domain (the message names the field).
    #[error("invalid input: {0}")]
    Invalid(String),
    /// A size that would allocate more than the crate allows (the message names the field).
    #[error("limit exceeded: {0}")]
    Limit(String),
    /// From the `yarn` crate (parameter validation, density).
    #[error(transparent)]
    Yarn(#[from] yarn::Error),
    /// From the reference renderer (scene building).
    #[error(transparent)]
    Ref(#[from] yarn_ref::Error),
    /// From `btf-core` (atomic writes).
    #[error(transparent)]
    Core(#[from] btf_core::Error),
    /// Reading a cache file or its folder.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
}

/// The crate's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An I/O error with its path.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
}
