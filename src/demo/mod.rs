//! The demos: `btf demo`'s garment renders ([`scene`]) and knit close-up ([`knit`]), and
//! `btf thin demo`'s curtain ([`thin`]).

pub mod knit;
pub mod scene;
pub mod thin;
