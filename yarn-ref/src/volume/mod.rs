//! Volumetric ray marcher (in progress).
