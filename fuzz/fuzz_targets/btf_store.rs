//! Fuzzes opening a BTF store: the input is split at `0xFF` into the group's `zarr.json`
//! (the `btf` attributes), `normtextures/zarr.json` and the chunk of view slot 0, light 0,
//! written into a store folder on a tmpfs; the store is opened and slot 0 read as
//! `btf compress` reads it. A store claiming more than its chunk files hold must be refused
//! before anything is allocated.
#![no_main]

use btf_core::store::BtfStore;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let p = btf_fuzz::parts(data, 3);
    let dir = btf_fuzz::fresh_dir("s.btf");
    let _ = std::fs::write(dir.join("zarr.json"), p[0].unwrap_or(&[]));
    std::fs::create_dir_all(dir.join("normtextures/c/0/0/0/0")).unwrap();
    if let Some(a) = p[1] {
        let _ = std::fs::write(dir.join("normtextures/zarr.json"), a);
    }
    if let Some(c) = p[2] {
        // both chunk key layouts: `/` (before issue #25) and `.` (since)
        let _ = std::fs::write(dir.join("normtextures/c/0/0/0/0/0"), c);
        let _ = std::fs::write(dir.join("normtextures/c.0.0.0.0.0"), c);
    }
    let Ok(s) = BtfStore::open(&dir) else { return };
    let _ = s.read_image(0, 0);
    let _ = s.map_slot(0);
    let _ = s.read_slot(0);
});
