//! Fuzzes opening an eigen store (`btf render`, `reconstruct`, `export` read these): the
//! input is split at `0xFF` into the group's `zarr.json` and the `zarr.json` of its five
//! arrays, written into a store folder on a tmpfs; the store is opened and slot 0 read.
#![no_main]

use btf_core::eigen::EigenStore;
use libfuzzer_sys::fuzz_target;

const ARRAYS: [&str; 5] = ["mean", "eigentextures", "scale_offset", "weights", "eigenvalues"];

fuzz_target!(|data: &[u8]| {
    let p = btf_fuzz::parts(data, 6);
    let dir = btf_fuzz::fresh_dir("s.eig");
    let _ = std::fs::write(dir.join("zarr.json"), p[0].unwrap_or(&[]));
    for (name, part) in ARRAYS.iter().zip(&p[1..]) {
        if let Some(bytes) = part {
            let _ = std::fs::create_dir_all(dir.join(name));
            let _ = std::fs::write(dir.join(name).join("zarr.json"), bytes);
        }
    }
    let Ok(s) = EigenStore::open(&dir) else { return };
    let _ = s.bytes();
    let _ = s.read_slot(0);
});
