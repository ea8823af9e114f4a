//! The yarn BTF (in progress).
