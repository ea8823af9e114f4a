//! The error type of `btf-render`: invalid input (scene, mesh, material), unsupported
//! requests, limits of the GPU, GPU failures and I/O are kept apart so that a user knows
//! what to fix.

use std::path::PathBuf;

/// Everything that can go wrong while loading or rendering a scene.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene, mesh or material that does not make sense; names the file and place.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// A scene key that is missing or has a bad value.
    #[error("{path}: scene key '{key}': {what}")]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// Dotted key, e.g. `lights[1].direction`.
        key: String,
        /// What is wrong with it.
        what: String,
    },
    /// A well-formed request this renderer does not handle.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A size beyond what the GPU (or we) can allocate.
    #[error("limit exceeded: {0}")]
    Limit(String),
    /// No GPU adapter could be created (no Vulkan/GL driver, not even lavapipe).
    #[error("no GPU adapter available: {0}")]
    NoAdapter(String),
    /// The GPU reported an error (validation, out of memory, lost device).
    #[error("GPU error: {0}")]
    Gpu(String),
    /// An error from the BTF data layer (eigen store).
    #[error(transparent)]
    Core(#[from] btf_core::Error),
    /// An error reading or writing an image or environment map.
    #[error(transparent)]
    Imaging(#[from] btf_image::Error),
    /// An error from the CPU lighting (meshes, visibility, environment).
    #[error(transparent)]
    Light(#[from] btf_light::Error),
    /// An I/O error with the path it happened on.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An image could not be encoded or written.
    #[error("{path}: {what}")]
    Image {
        /// The output file.
        path: PathBuf,
        /// The encoder's complaint.
        what: String,
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
