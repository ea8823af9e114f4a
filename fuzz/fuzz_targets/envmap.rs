//! Fuzzes `btf_image::EnvMap::load`, the one environment-map loader (`btf demo`, `btf
//! render`, `btf relight`, `btf view`): the first input byte picks the extension (`.hdr` or
//! `.exr`), the rest is the file, written to a tmpfs. Any input must load or give an error,
//! never panic, abort or allocate beyond the limit; a loaded map is 2:1 and finite.
#![no_main]

use btf_image::EnvMap;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let name = if pick & 1 == 0 { "env.hdr" } else { "env.exr" };
    let path = btf_fuzz::put(name, rest);
    if let Ok(m) = EnvMap::load(&path) {
        assert_eq!(m.pixels.len(), m.width * m.height);
        assert_eq!(m.width, 2 * m.height);
        assert!(m.pixels.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    }
});
