//! Ratio and single-thread encode/decode rates of chunk codecs on real chunks: today's zstd
//! against blosc (byte shuffle + zstd) at several levels, split or not, whole-chunk or
//! 64 KiB blocks, and the shuffle kernels alone (BENCHMARKS.md, "The blosc codec").
//!
//! `cargo run --release -p btf-core --example codec_rate -- ARRAY_DIR [CHUNKS] [ROUNDS]`
//! reads CHUNKS chunks (default 24) spread over the array's grid with the store reader,
//! then for every codec encodes them all and decodes them all ROUNDS times (default 3,
//! after a warm-up pass), and prints the best rate of each in GB/s of decoded bytes.

use btf_core::blosc::{self, Settings};
use btf_core::zarr::{Limits, ZarrArray};
use std::path::Path;
use std::time::Instant;

#[derive(Clone, Copy)]
enum Codec {
    Zstd(i32),
    Blosc(Settings),
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if !(2..=4).contains(&args.len()) {
        return Err("usage: codec_rate ARRAY_DIR [CHUNKS] [ROUNDS]".into());
    }
    let n_chunks: usize = args.get(2).map_or(Ok(24), |s| s.parse())?;
    let rounds: usize = args.get(3).map_or(Ok(3), |s| s.parse())?;
    let arr = ZarrArray::open(Path::new(&args[1]), &Limits::default())?;
    let m = arr.meta();
    let grid: Vec<u64> = m.shape.iter().zip(&m.chunk_shape).map(|(s, c)| s.div_ceil(*c)).collect();
    let total: u64 = grid.iter().product();
    let ts = m.dtype.size();
    let mut chunks = Vec::new();
    for k in 0..n_chunks as u64 {
        // Spread over the grid: index k · total / n, decomposed row-major.
        let mut flat = k * total / n_chunks as u64 + k % 7;
        let mut idx = vec![0u64; grid.len()];
        for d in (0..grid.len()).rev() {
            idx[d] = flat % grid[d];
            flat /= grid[d];
        }
        chunks.push(arr.read_chunk(&idx)?);
    }
    let raw: usize = chunks.iter().map(Vec::len).sum();
    println!(
        "{}: {} chunks of {} bytes ({:?}, typesize {ts}), {rounds} rounds, best of each",
        args[1],
        chunks.len(),
        chunks[0].len(),
        m.dtype
    );

    // The shuffle kernels alone, in cache (one 64 KiB block) and per chunk.
    let block = &chunks[0][..(64 << 10).min(chunks[0].len())];
    let mut tmp = vec![0u8; block.len()];
    let mut back = vec![0u8; block.len()];
    let reps = 20_000;
    let t = Instant::now();
    for _ in 0..reps {
        blosc::shuffle_block(ts, std::hint::black_box(block), &mut tmp);
    }
    let shuf = (reps * block.len()) as f64 / t.elapsed().as_secs_f64() / 1e9;
    let t = Instant::now();
    for _ in 0..reps {
        blosc::unshuffle_block(ts, std::hint::black_box(&tmp), &mut back);
    }
    let unshuf = (reps * block.len()) as f64 / t.elapsed().as_secs_f64() / 1e9;
    assert_eq!(back, block);
    println!(
        "shuffle {shuf:.1} GB/s, unshuffle {unshuf:.1} GB/s (typesize {ts}, 64 KiB block in cache)"
    );

    let mut codecs =
        vec![("zstd 1".to_string(), Codec::Zstd(1)), ("zstd 3".into(), Codec::Zstd(3))];
    for clevel in [1u8, 2, 3] {
        for (split, blocksize, what) in [
            (false, u32::MAX, "whole chunk"),
            (true, u32::MAX, "whole chunk, split"),
            (false, 64 << 10, "64 KiB blocks"),
            (true, 64 << 10, "64 KiB blocks, split"),
        ] {
            let s = Settings { clevel, shuffle: true, blocksize, split };
            let name = format!(
                "blosc clevel {clevel} (zstd {}) shuffle, {what}",
                blosc::zstd_level(clevel)
            );
            codecs.push((name, Codec::Blosc(s)));
        }
    }
    let noshuf = Settings { clevel: 1, shuffle: false, blocksize: u32::MAX, split: false };
    codecs.push(("blosc clevel 1 noshuffle, whole chunk".into(), Codec::Blosc(noshuf)));

    println!("| codec | ratio | encode GB/s | decode GB/s |");
    println!("|---|---:|---:|---:|");
    for (name, codec) in codecs {
        let mut enc = Vec::new();
        let (mut t_enc, mut t_dec) = (f64::MAX, f64::MAX);
        let mut out = vec![0u8; chunks[0].len()];
        for round in 0..=rounds {
            let t = Instant::now();
            enc = chunks
                .iter()
                .map(|c| match codec {
                    // As the store writes and reads zstd chunks today.
                    Codec::Zstd(level) => zstd::bulk::compress(c, level).unwrap(),
                    Codec::Blosc(s) => blosc::encode(c, ts, &s).unwrap(),
                })
                .collect();
            let te = t.elapsed().as_secs_f64();
            let mut td = 0.0;
            for (e, c) in enc.iter().zip(&chunks) {
                let t = Instant::now();
                match codec {
                    Codec::Zstd(_) => {
                        zstd::bulk::decompress_to_buffer(e, &mut out[..]).unwrap();
                    }
                    Codec::Blosc(_) => {
                        blosc::decode_to(e, &mut out).unwrap();
                    }
                }
                td += t.elapsed().as_secs_f64();
                assert!(out == *c);
            }
            if round > 0 {
                t_enc = t_enc.min(te);
                t_dec = t_dec.min(td);
            }
        }
        let stored: usize = enc.iter().map(Vec::len).sum();
        println!(
            "| {name} | {:.3} | {:.2} | {:.2} |",
            raw as f64 / stored as f64,
            raw as f64 / t_enc / 1e9,
            raw as f64 / t_dec / 1e9
        );
    }
    Ok(())
}
