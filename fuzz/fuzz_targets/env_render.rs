//! Fuzzes `btf_render::envlight::envmap::EnvMap::load`, the environment-map loader of
//! `btf render`: the first input byte picks the extension (`.hdr` or `.exr`), the rest is
//! the file, written to a tmpfs. Any input must load or give an error, never panic, abort
//! or allocate beyond the limit.
#![no_main]

use btf_render::envlight::envmap::EnvMap;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let name = if pick & 1 == 0 { "env.hdr" } else { "env.exr" };
    let path = btf_fuzz::put(name, rest);
    if let Ok(m) = EnvMap::load(&path) {
        assert_eq!(m.pixels.len(), m.width * m.height);
    }
});
