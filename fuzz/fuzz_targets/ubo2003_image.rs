//! Fuzzes the image decoding of `btf import ubo2003` (`ubo2003::decode_image`, which reads
//! folder files and zip members from memory): the first byte picks the name's extension
//! (JPEG, PNG, BMP, Radiance HDR, EXR), the rest is the image.
#![no_main]

use btf_capture::bonn::ubo2003;
use libfuzzer_sys::fuzz_target;

const NAMES: [&str; 5] = ["a.jpg", "a.png", "a.bmp", "a.hdr", "a.exr"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let name = NAMES[pick as usize % NAMES.len()];
    if let Ok((w, h, px)) = ubo2003::decode_image(rest, name) {
        assert_eq!(px.len(), w * h * 3);
    }
});
