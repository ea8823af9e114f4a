//! Ratio and one-thread encode/decode rates of candidate chunk codecs on the byte-shuffled
//! chunks of a store's array (BENCHMARKS.md, "Session 29"): `codec_probe ARRAY_DIR
//! [CHUNKS]` reads CHUNKS chunks (default 12) spread over the array's grid, shuffles each as
//! blosc does (all first bytes of the elements, then all second bytes, …), and prints one
//! row per codec: ratio, encode and decode GB/s of shuffled bytes, best of three rounds.
//! "hi" is the second half of a shuffled 2-byte chunk (the `f16` values' sign, exponent and
//! top mantissa bits), "lo" the first (their low mantissa bits).

use btf_core::blosc;
use btf_core::zarr::{Limits, ZarrArray};
use std::path::Path;
use std::time::Instant;
use zstd::zstd_safe::{CParameter, Strategy};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

#[derive(Clone, Copy)]
enum Codec {
    /// zstd at a level (negative: zstd's fast modes).
    Zstd(i32),
    /// zstd level 1 with this hash log and minimum match.
    ZstdTuned(u32, u32),
    /// LZ4 block format over the whole chunk.
    Lz4,
    /// The low bytes stored raw, the high bytes by LZ4 (2-byte elements only).
    Lz4HiRawLo,
    /// The low bytes stored raw, the high bytes by zstd level 1 (2-byte elements only).
    ZstdHiRawLo,
}

fn encode(codec: Codec, c: &[u8]) -> Res<Vec<Vec<u8>>> {
    let half = c.len() / 2;
    Ok(match codec {
        Codec::Zstd(level) => vec![zstd::bulk::compress(c, level)?],
        Codec::ZstdTuned(hash_log, min_match) => {
            let mut z = zstd::bulk::Compressor::new(1)?;
            z.set_parameter(CParameter::Strategy(Strategy::ZSTD_fast))?;
            z.set_parameter(CParameter::HashLog(hash_log))?;
            z.set_parameter(CParameter::MinMatch(min_match))?;
            vec![z.compress(c)?]
        }
        Codec::Lz4 => vec![lz4_flex::block::compress(c)],
        Codec::Lz4HiRawLo => vec![c[..half].to_vec(), lz4_flex::block::compress(&c[half..])],
        Codec::ZstdHiRawLo => vec![c[..half].to_vec(), zstd::bulk::compress(&c[half..], 1)?],
    })
}

fn decode(codec: Codec, e: &[Vec<u8>], out: &mut [u8]) -> Res<()> {
    let half = out.len() / 2;
    match codec {
        Codec::Zstd(_) | Codec::ZstdTuned(..) => {
            zstd::bulk::decompress_to_buffer(&e[0], out)?;
        }
        Codec::Lz4 => {
            lz4_flex::block::decompress_into(&e[0], out)?;
        }
        Codec::Lz4HiRawLo => {
            out[..half].copy_from_slice(&e[0]);
            lz4_flex::block::decompress_into(&e[1], &mut out[half..])?;
        }
        Codec::ZstdHiRawLo => {
            out[..half].copy_from_slice(&e[0]);
            zstd::bulk::decompress_to_buffer(&e[1], &mut out[half..])?;
        }
    }
    Ok(())
}

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().collect();
    if !(2..=3).contains(&args.len()) {
        return Err("usage: codec_probe ARRAY_DIR [CHUNKS]".into());
    }
    let n_chunks: u64 = args.get(2).map_or(Ok(12), |s| s.parse())?;
    let arr = ZarrArray::open(Path::new(&args[1]), &Limits::default())?;
    let m = arr.meta();
    let ts = m.dtype.size();
    let grid: Vec<u64> = m.shape.iter().zip(&m.chunk_shape).map(|(s, c)| s.div_ceil(*c)).collect();
    let total: u64 = grid.iter().product();
    let mut chunks = Vec::new();
    for k in 0..n_chunks.min(total) {
        let mut flat = k * total / n_chunks;
        let mut idx = vec![0u64; grid.len()];
        for d in (0..grid.len()).rev() {
            idx[d] = flat % grid[d];
            flat /= grid[d];
        }
        let raw = arr.read_chunk(&idx)?;
        let mut shuffled = vec![0u8; raw.len()];
        blosc::shuffle_block(ts, &raw, &mut shuffled);
        chunks.push(shuffled);
    }
    let raw: usize = chunks.iter().map(Vec::len).sum();
    println!("{}: {} chunks, {raw} bytes, typesize {ts}", args[1], chunks.len());
    let mut codecs = vec![("zstd 1 (blosc clevel 1)".to_string(), Codec::Zstd(1))];
    for level in [-1, -3, -5, -10, -20] {
        codecs.push((format!("zstd {level}"), Codec::Zstd(level)));
    }
    for (h, mm) in [(13, 6), (13, 7), (12, 6), (12, 7), (11, 7)] {
        codecs.push((format!("zstd 1, hashLog {h}, minMatch {mm}"), Codec::ZstdTuned(h, mm)));
    }
    codecs.push(("lz4".into(), Codec::Lz4));
    if ts == 2 {
        codecs.push(("lo raw, hi zstd 1".into(), Codec::ZstdHiRawLo));
        codecs.push(("lo raw, hi lz4".into(), Codec::Lz4HiRawLo));
    }
    println!("| codec | ratio | encode GB/s | decode GB/s |");
    println!("|---|---:|---:|---:|");
    for (name, codec) in codecs {
        let (mut te, mut td, mut stored) = (f64::MAX, f64::MAX, 0);
        // Decoded into the same buffers every round: the first round faults their pages in.
        let mut outs: Vec<Vec<u8>> = chunks.iter().map(|c| vec![0u8; c.len()]).collect();
        for _ in 0..3 {
            let t = Instant::now();
            let enc = chunks.iter().map(|c| encode(codec, c)).collect::<Res<Vec<_>>>()?;
            te = te.min(t.elapsed().as_secs_f64());
            stored = enc.iter().flatten().map(Vec::len).sum();
            let t = Instant::now();
            for (e, out) in enc.iter().zip(&mut outs) {
                decode(codec, e, out)?;
            }
            td = td.min(t.elapsed().as_secs_f64());
            if outs != chunks {
                return Err(format!("{name}: round trip differs").into());
            }
        }
        let (r, gb) = (raw as f64, 1e9);
        println!("| {name} | {:.3} | {:.2} | {:.2} |", r / stored as f64, r / te / gb, r / td / gb);
    }
    Ok(())
}
