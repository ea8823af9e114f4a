//! The demos: `btf demo`'s garment renders ([`scene`]) and `btf thin demo`'s curtain
//! ([`thin`]).

pub mod scene;
pub mod thin;
