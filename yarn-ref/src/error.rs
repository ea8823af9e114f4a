//! The error type of `yarn-ref`: invalid input (a NaN fiber point, a camera looking up
//! from below the patch), unsupported requests, limits, and the errors of the crates it
//! calls (`yarn`, `btf-core`, `btf-image`), each message naming the fiber, curve, file or
//! field at fault.

/// Everything that can go wrong in `yarn-ref`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Input that does not make sense (names the fiber, point, light or field).
    #[error("invalid input: {0}")]
    Invalid(String),
    /// Well-formed, but not handled by this version.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A size beyond what we are willing to allocate.
    #[error("limit exceeded: {0}")]
    Limit(String),
    /// From the `yarn` crate (charts, curves, fibers, BCSDFs, density).
    #[error(transparent)]
    Yarn(#[from] yarn::Error),
    /// From the store (`btf_core::store`).
    #[error(transparent)]
    Core(#[from] btf_core::Error),
    /// From the image layer (EXR/PNG writers, environment maps).
    #[error(transparent)]
    Image(#[from] btf_image::Error),
}

/// `Result` with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;
