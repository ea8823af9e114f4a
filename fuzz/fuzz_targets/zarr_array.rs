//! Fuzzes Zarr v3 metadata: the input is split at `0xFF` into an array's `zarr.json` and
//! its first chunk's bytes, written into a folder on a tmpfs; the array is opened with the
//! default limits and the chunk read. The same `zarr.json` is also read as a group.
#![no_main]

use btf_core::zarr::{self, Limits, ZarrArray};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let p = btf_fuzz::parts(data, 2);
    let dir = btf_fuzz::fresh_dir("array");
    let _ = std::fs::write(dir.join("zarr.json"), p[0].unwrap_or(&[]));
    let _ = zarr::read_group(&dir);
    let Ok(a) = ZarrArray::open(&dir, &Limits::default()) else { return };
    let idx = vec![0u64; a.meta().shape.len()];
    if let Some(chunk) = p[1] {
        let path = a.chunk_path(&idx);
        let _ = std::fs::create_dir_all(path.parent().unwrap());
        let _ = std::fs::write(&path, chunk);
    }
    if let Ok(raw) = a.read_chunk(&idx) {
        assert_eq!(raw.len() as u64 + 4, a.meta().chunk_bytes().unwrap());
    }
});
