//! Fuzzes `capture.toml` (`btf capture process RAW`): the input is written as
//! `RAW/capture.toml` on a tmpfs and read with `CaptureLayout::read`.
#![no_main]

use btf_capture::capture::CaptureLayout;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = btf_fuzz::put("raw/capture.toml", data);
    let _ = CaptureLayout::read(path.parent().unwrap());
});
