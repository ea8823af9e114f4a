//! Fuzzes scene files (`btf render S.toml`): `Scene::from_toml`, the parser and validator
//! behind `Scene::load`, on arbitrary text. Nothing is read from disk and no GPU is touched.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = btf_render::Scene::from_toml(text, Path::new("/fuzz/scene.toml"));
});
