//! Writes a synthetic material as a BTF store: every (view slot, light) normtexture, in
//! parallel over view slots (each slot's view-ray hits are computed once and shared by its
//! lights), deterministic for a seed, resumable and with a progress bar; or one shard's
//! view slots of it, into the store every shard of the job fills (issue #23).

use super::{Material, MaterialSpec};
use crate::Result;
use btf_core::store::{BtfMeta, BtfWriter};
use btf_core::zarr::{Compression, DType};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde_json::json;
use std::path::Path;
use std::time::Instant;

/// How to write the store.
#[derive(Debug, Clone, Copy)]
pub struct GenerateOptions {
    /// Keep images already written by an interrupted run.
    pub resume: bool,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Element type on disk (`F32` or `F16`).
    pub dtype: DType,
    /// Write only this shard's view slots into the store that every shard fills
    /// (issue #23); the store is committed by `btf finalize`, not here.
    pub shard: Option<btf_core::shard::Shard>,
    /// Chunk codec of the normtextures ([`Compression::DEFAULT`]: blosc; `None`: raw, which
    /// `btf compress` maps in place instead of decoding).
    pub codec: Compression,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        GenerateOptions {
            resume: false,
            progress: false,
            dtype: DType::F32,
            shard: None,
            codec: Compression::DEFAULT,
        }
    }
}

/// What a generation run did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GenerateReport {
    /// Images rendered and written in this run.
    pub images_written: usize,
    /// Images kept from an earlier, interrupted run.
    pub images_skipped: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Synthesises `spec` and writes it as a BTF store at `out` (see [`btf_core::store`]).
pub fn generate(spec: &MaterialSpec, out: &Path, opts: &GenerateOptions) -> Result<GenerateReport> {
    let t0 = Instant::now();
    let material = Material::build(spec)?;
    let sampling = spec.sampling.clone().validated()?;
    let mut meta = BtfMeta::new(sampling.clone(), sampling.clone(), spec.size, spec.size);
    meta.provenance = json!({
        "generator": "datasets::material",
        "version": env!("CARGO_PKG_VERSION"),
        "kind": spec.kind.name(),
        "seed": spec.seed,
        "size": spec.size,
        "params": material.params(),
        "model": "height field; view ray marched (parallax, masking), light ray marched \
                  (self-shadowing), Lambert + GGX + Charlie sheen, energy-conserving coupling",
    });
    let n = sampling.len();
    let (writer, views) = match opts.shard {
        Some(shard) => {
            let job = json!({ "shards": shard.count });
            let w = BtfWriter::join_for_job_compressed(out, meta, opts.dtype, job, opts.codec)?;
            (w, shard.range(n))
        }
        None => {
            let (dtype, resume, codec) = (opts.dtype, opts.resume, opts.codec);
            (BtfWriter::create_compressed(out, meta, dtype, resume, json!(null), codec)?, 0..n)
        }
    };
    let bar = if opts.progress {
        ProgressBar::new((views.len() * n) as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} images, {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(format!("{} {}²", spec.kind.name(), spec.size));
    let counts = views
        .into_par_iter()
        .map(|view| -> Result<(usize, usize)> {
            // A shard checks the checksums of what an earlier run of it left.
            let kept = |l: usize| match opts.shard {
                Some(_) => writer.has_sound_image(view, l),
                None => writer.has_image(view, l),
            };
            let missing: Vec<usize> = (0..n).filter(|&l| !kept(l)).collect();
            bar.inc((n - missing.len()) as u64);
            if missing.is_empty() {
                return Ok((0, n));
            }
            let view_vec = sampling.direction(view).to_vector();
            let hits = material.view_hits(view_vec);
            let mut img = vec![0f32; hits.len() * 3];
            for &light in &missing {
                let light_vec = sampling.direction(light).to_vector();
                for (px, hit) in img.chunks_exact_mut(3).zip(&hits) {
                    let v = material.shade(hit, view_vec, light_vec);
                    px.copy_from_slice(&v.map(|c| c as f32));
                }
                writer.write_image(view, light, &img)?;
                bar.inc(1);
            }
            Ok((missing.len(), n - missing.len()))
        })
        .collect::<Result<Vec<_>>>()?;
    if opts.shard.is_none() {
        writer.finish()?;
    }
    bar.finish_and_clear();
    let (written, skipped) = counts.iter().fold((0, 0), |a, c| (a.0 + c.0, a.1 + c.1));
    Ok(GenerateReport {
        images_written: written,
        images_skipped: skipped,
        seconds: t0.elapsed().as_secs_f64(),
    })
}
