//! Import speed against plain image decoding of the same files, in the same run (ignored by
//! default; run in release, see the crate README under "Measured"):
//! `BTF_SPEED_SIZE=256 cargo test --release -p btf-capture --test import_speed -- --ignored --nocapture`.
//!
//! A full `ubo81 × ubo81` UBO2003 folder (6561 JPEGs, quality 90) is written first; then
//! the same files are (a) read and decoded to 8-bit RGB with the `image` crate — the
//! baseline any importer must do — and (b) imported into an `f16` store (decode, sRGB
//! linearisation, name parsing, direction mapping, chunk writes with checksums).

use btf_capture::bonn::export::{ImageEncoding, export_ubo2003};
use btf_capture::bonn::ubo2003;
use btf_core::Sampling;
use btf_core::store::{BtfMeta, BtfStore, BtfWriter};
use btf_core::zarr::DType;
use std::time::Instant;

#[test]
#[ignore = "a measurement (minutes, release build): run for BENCHMARKS.md"]
fn ubo2003_import_vs_plain_decoding() {
    let size: usize =
        std::env::var("BTF_SPEED_SIZE").ok().and_then(|s| s.parse().ok()).unwrap_or(128);
    let dir =
        tempfile::tempdir_in(std::env::var("BTF_SPEED_DIR").unwrap_or_else(|_| "/tmp".into()))
            .unwrap();
    let s = Sampling::ubo81();
    let src = dir.path().join("src.zarr");
    let w =
        BtfWriter::create(&src, BtfMeta::new(s.clone(), s.clone(), size, size), DType::F16, false)
            .unwrap();
    for v in 0..81 {
        for l in 0..81 {
            let img: Vec<f32> = (0..size * size * 3)
                .map(|i| {
                    0.4 + 0.3
                        * ((i / 3 % size) as f32 * 0.11 + l as f32 * 0.3 + v as f32 * 0.07).sin()
                        + 0.1 * ((i % 3) as f32)
                })
                .collect();
            w.write_image(v, l, &img).unwrap();
        }
    }
    w.finish().unwrap();
    let folder = dir.path().join("Wool");
    export_ubo2003(&BtfStore::open(&src).unwrap(), &folder, "Wool", ImageEncoding::Jpeg(90))
        .unwrap();
    let mut files = Vec::new();
    for d in std::fs::read_dir(&folder).unwrap() {
        let p = d.unwrap().path();
        if p.is_dir() {
            files.extend(std::fs::read_dir(&p).unwrap().map(|e| e.unwrap().path()));
        }
    }
    assert_eq!(files.len(), 6561);
    let bytes: u64 = files.iter().map(|p| p.metadata().unwrap().len()).sum();

    let t = Instant::now();
    let mut checksum = 0u64;
    for p in &files {
        let img = image::open(p).unwrap().to_rgb8();
        checksum += img.as_raw()[0] as u64;
    }
    let plain = t.elapsed().as_secs_f64();

    // The store-writing floor: the same number of f16 images written without decoding.
    let t = Instant::now();
    let floor = dir.path().join("floor.zarr");
    let fw = BtfWriter::create(
        &floor,
        BtfMeta::new(s.clone(), s.clone(), size, size),
        DType::F16,
        false,
    )
    .unwrap();
    let img = vec![0.25f32; size * size * 3];
    for v in 0..81 {
        for l in 0..81 {
            fw.write_image(v, l, &img).unwrap();
        }
    }
    fw.finish().unwrap();
    let write_only = t.elapsed().as_secs_f64();
    std::fs::remove_dir_all(&floor).unwrap();

    let t = Instant::now();
    let rep = ubo2003::import(&folder, &dir.path().join("imported.zarr"), DType::F16).unwrap();
    let import = t.elapsed().as_secs_f64();
    assert_eq!(rep.images, 6561);
    println!(
        "{} JPEGs of {size}x{size} ({:.1} MB): plain decode {plain:.2} s ({:.0} images/s), store write only {write_only:.2} s ({:.0} MB/s), import {import:.2} s ({:.0} images/s), import/plain = {:.2}, import/(plain + write) = {:.2} (checksum {checksum})",
        files.len(),
        bytes as f64 / 1e6,
        files.len() as f64 / plain,
        (6561 * size * size * 6) as f64 / 1e6 / write_only,
        files.len() as f64 / import,
        import / plain,
        import / (plain + write_only)
    );
}
