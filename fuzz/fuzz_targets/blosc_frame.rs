//! Fuzzes the blosc1 frame decoder (`btf_core::blosc`, the Zarr `blosc` codec's chunks):
//! the input is one frame, decoded into a buffer of the size its header claims (up to
//! 1 MiB; the store reader passes the chunk's known size, so a larger claim is refused
//! there before decoding). A frame that decodes is re-encoded with its own settings and
//! must decode to the same bytes.
#![no_main]

use btf_core::blosc::{self, Settings};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let claim = data.get(4..8).map_or(0, |b| u32::from_le_bytes(b.try_into().unwrap()));
    let n = if claim <= 1 << 20 { claim as usize } else { data.len() };
    let mut out = vec![0u8; n];
    let Ok(h) = blosc::decode_to(data, &mut out) else { return };
    assert_eq!(h.nbytes, n);
    let settings = Settings {
        clevel: 1,
        shuffle: h.flags & 1 != 0,
        blocksize: h.blocksize as u32,
        split: h.flags & 0x10 == 0,
    };
    let frame = blosc::encode(&out, h.typesize, &settings).expect("encodes");
    let mut back = vec![0u8; n];
    blosc::decode_to(&frame, &mut back).expect("our own frame decodes");
    assert!(back == out);
});
