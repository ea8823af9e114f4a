//! Explicit fiber geometry: capsule chains ([`capsule`]) in a binned-SAH BVH ([`bvh`]),
//! wrapped periodically for patches and closed below by an optional black backing plane
//! ([`scene`]).

pub mod bvh;
pub mod capsule;
pub mod scene;

pub use bvh::{Aabb, Bvh};
pub use capsule::{CapsuleHit, entry, segment_distance2};
pub use scene::{FiberScene, Hit, HitKind, Period, SceneOptions, Segment, Skip, SurfacePoint};
