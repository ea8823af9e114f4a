//! The error type of `yarn-render`: bad yarn input (named by curve, field or params id),
//! requests beyond the GPU's or our limits, and GPU failures — kept apart so a user knows
//! what to fix.

/// Everything that can go wrong while packing or rendering yarns.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Yarn data or options that do not make sense; names the curve, field or id.
    #[error("invalid yarn input: {0}")]
    Invalid(String),
    /// A size beyond what the GPU (or we) can address or allocate.
    #[error("limit exceeded: {0}")]
    Limit(String),
    /// The GPU reported an error (validation, out of memory, lost device).
    #[error("GPU error: {0}")]
    Gpu(String),
    /// From the renderer this crate draws with.
    #[error(transparent)]
    Render(#[from] btf_render::Error),
    /// From the yarn foundation.
    #[error(transparent)]
    Yarn(#[from] yarn::Error),
    /// From the BTF data layer (the yarn BTF store).
    #[error(transparent)]
    Core(#[from] btf_core::Error),
}

/// The result of this crate.
pub type Result<T> = std::result::Result<T, Error>;
