//! Fuzzes the UBO2014 `.btf` reader as `btf import ubo2014` opens a file: the first byte
//! picks one of the seven signatures (FMF, DFMF, PVF, BDI), the rest follows it in a file on
//! a tmpfs, opened with the default limits; the first texture is then decoded.
#![no_main]

use btf_capture::bonn::bytes::Limits;
use btf_capture::bonn::svd::{decode_dfmf, decode_fmf};
use btf_capture::bonn::ubo2014::{self, Ubo2014};
use libfuzzer_sys::fuzz_target;

const SIGNATURES: [&[u8]; 8] = [
    b"!FMF06FC", b"!FMF06FCR", b"!FMF12FCER", b"!DFMF08FCR", b"!PVF06FC", b"!PVF06FCR",
    b"!BDIF06R2!", b"",
];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let mut bytes = SIGNATURES[pick as usize % SIGNATURES.len()].to_vec();
    bytes.extend_from_slice(rest);
    let path = btf_fuzz::put("in.btf", &bytes);
    let Ok(mut src) = ubo2014::open(&path, Limits::default()) else { return };
    let h = src.header().clone();
    let n = h.width * h.height * h.channels();
    // The importer allocates one texture of this size; the header was checked against the
    // file's length, so a large n here means a large file, which the fuzzer does not make.
    let mut img = vec![0f32; n.min(1 << 24)];
    if img.len() != n {
        return;
    }
    match &mut src {
        Ubo2014::Fmf(h, f, lay) => decode_fmf(h, f, *lay, 0, 0, &mut img),
        Ubo2014::Dfmf(h, d, lay) => decode_dfmf(h, d, *lay, 0, 0, &mut img),
        Ubo2014::Pvf(p) => {
            while let Ok(Some(s)) = p.next_slot() {
                s.decode(0, h.channels(), &mut img);
            }
        }
        Ubo2014::Bdi(b) => {
            if let Ok(v) = b.read_views(&[0]) {
                img.copy_from_slice(&v[0][..n]);
            }
        }
    }
});
