//! Fuzzes the BDI parser and decoder: the first byte picks the signature, the rest
//! follows it. Any input must give `Ok` or an error, never a panic or an allocation
//! beyond the limits.
#![no_main]

use libfuzzer_sys::fuzz_target;

const SIGNATURES: [&[u8]; 1] = [b"!BDIF06R2!"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let mut bytes = SIGNATURES[pick as usize % SIGNATURES.len()].to_vec();
    bytes.extend_from_slice(rest);
    let _ = btf_capture::bonn::ubo2014::parse_all(&bytes);
});
