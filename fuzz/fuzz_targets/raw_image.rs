//! Fuzzes the raw-image reader of `btf capture process` (`capture::raw`): the first byte
//! picks the extension (PNG, TIFF, EXR), the rest is the file on a tmpfs; its size is read
//! from the header, then the image is decoded.
#![no_main]

use btf_capture::capture::raw;
use libfuzzer_sys::fuzz_target;

const NAMES: [&str; 3] = ["raw.png", "raw.tiff", "raw.exr"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let path = btf_fuzz::put(NAMES[pick as usize % NAMES.len()], rest);
    let _ = raw::dimensions(&path);
    if let Ok(img) = raw::read(&path, 12) {
        assert_eq!(img.rgb.len(), img.width * img.height);
    }
});
