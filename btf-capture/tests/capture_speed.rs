//! Capture-processing throughput against plain decoding of the same PNGs, in the same run
//! (ignored by default; a release measurement for BENCHMARKS.md):
//!
//! ```text
//! btf synth capture --material knit --size 256 --sampling rings:0x1,30x4,60x4,75x4 \
//!     --resolution 1280,960 --supersample 2 --pose-noise 1,1 --out /tmp/hr
//! BTF_CAPTURE_RAW=/tmp/hr cargo test --release -p btf-capture --test capture_speed \
//!     -- --ignored --nocapture
//! ```
//!
//! (a) every raw image is read and decoded to 16-bit RGB with the `image` crate, in
//! parallel over view slots as processing does — the floor of any processing; (b) the full
//! `process` (registration, rectification with each filter, blending, f32 store writes).
//! Runs alternate (decode, process, decode, process) and the faster of each pair is kept.

use btf_capture::capture::{CaptureLayout, Filter, ProcessOptions, process};
use rayon::prelude::*;
use std::time::Instant;

fn decode_all(layout: &CaptureLayout) -> f64 {
    let n = layout.sampling.len();
    let t = Instant::now();
    let sum: u64 = (0..n)
        .into_par_iter()
        .map(|v| {
            (0..n)
                .map(|l| {
                    image::open(layout.image_path(v, l)).unwrap().to_rgb16().as_raw()[0] as u64
                })
                .sum::<u64>()
        })
        .sum();
    std::hint::black_box(sum);
    t.elapsed().as_secs_f64()
}

#[test]
#[ignore = "a measurement (minutes, release build, needs BTF_CAPTURE_RAW): run for BENCHMARKS.md"]
fn processing_vs_plain_decoding() {
    let raw = std::path::PathBuf::from(
        std::env::var("BTF_CAPTURE_RAW").expect("set BTF_CAPTURE_RAW to a capture folder"),
    );
    let layout = CaptureLayout::read(&raw).unwrap();
    let n = layout.sampling.len();
    let out_dir = tempfile::tempdir_in("/tmp").unwrap();
    let mut rows = Vec::new();
    for filter in [Filter::Bilinear, Filter::Footprint] {
        let opt = ProcessOptions { filter, blend_width: 16, ..ProcessOptions::default() };
        let (mut dec, mut proc) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..2 {
            dec = dec.min(decode_all(&layout));
            let t = Instant::now();
            process(&raw, &out_dir.path().join("m.btf"), &opt, &|| {}).unwrap();
            proc = proc.min(t.elapsed().as_secs_f64());
        }
        rows.push((filter.name(), dec, proc));
    }
    println!(
        "{} images {}x{} -> 256² (+16 blend), rayon threads {}",
        n * n,
        layout.camera.width,
        layout.camera.height,
        rayon::current_num_threads()
    );
    println!("| filter | plain decode | process | process / decode | images/s |");
    println!("|---|---:|---:|---:|---:|");
    for (f, dec, proc) in rows {
        println!(
            "| {f} | {dec:.2} s | {proc:.2} s | {:.2} | {:.1} |",
            proc / dec,
            (n * n) as f64 / proc
        );
    }
}
