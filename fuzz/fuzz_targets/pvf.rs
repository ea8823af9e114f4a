//! Fuzzes PVF files (per-view PCA, read by `btf import ubo2014` straight into an eigen
//! store): the first byte picks the signature (current or legacy layout), the rest follows
//! it in a file on a tmpfs; every slot is read and decoded.
#![no_main]

use btf_capture::bonn::bytes::Limits;
use btf_capture::bonn::ubo2014::{self, Ubo2014};
use libfuzzer_sys::fuzz_target;

const SIGNATURES: [&[u8]; 2] = [b"!PVF06FC", b"!PVF06FCR"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let mut bytes = SIGNATURES[pick as usize % SIGNATURES.len()].to_vec();
    bytes.extend_from_slice(rest);
    let path = btf_fuzz::put("in.pvf", &bytes);
    let Ok(Ubo2014::Pvf(mut p)) = ubo2014::open(&path, Limits::default()) else { return };
    let h = p.header.clone();
    let n = h.width * h.height * h.channels();
    let mut img = vec![0f32; n.min(1 << 24)];
    if img.len() != n {
        return;
    }
    while let Ok(Some(s)) = p.next_slot() {
        for l in 0..h.lights.len().min(4) {
            s.decode(l, h.channels(), &mut img);
        }
    }
});
