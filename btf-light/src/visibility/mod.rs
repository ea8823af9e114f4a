//! Per-vertex visibility maps (Sattler et al. 2003, §5.2): for every vertex side, which
//! pixels of its tangent-space hemicube see the environment past the whole mesh — the
//! factor `V(x, p_α)` of [S03 eq. 9] that gives macroscopic self-shadowing.
//!
//! Definition: one any-hit ray per hemicube pixel centre against the mesh
//! ([`VisibilityMaps::compute_ray_cast`], a [`Bvh`] query per ray). The fast path
//! ([`VisibilityMaps::compute`]) gives the same bits by a CPU rasteriser per vertex side:
//! BVH nodes below the tangent plane or hidden behind already-occluded pixels are skipped,
//! surviving triangles are projected onto the five faces and only the pixels they may cover
//! get the ray test (see `raster`). Vertices in parallel with rayon. Cloth is double-sided: any triangle occludes,
//! whichever way it faces. Rays start a small offset (`1e-4` of the mesh diagonal) above
//! the vertex along the side's normal so the vertex's own triangles do not shadow it.
//!
//! Maps are bit sets, cached on disk under a key hashing the mesh, the frames and the
//! resolution; the file is written to a temporary name and renamed into place. A scene's
//! camera needs only some frames ([`VisibilityMaps::compute_some`], `camera_sides.rs`): the
//! others stay all-occluded, and such a subset is cached under its own key (maps of all
//! frames, when cached, serve it too).

pub mod bvh;
mod raster;
mod raster_face;
mod ray_lanes;

use crate::hemicube::{Hemicube, HemicubeFrame};
use crate::{Error, Result};
use bvh::Bvh;
use raster::FrameRaster;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// File magic and format version of the cache.
const MAGIC: &[u8; 8] = b"BTFVIS01";

/// Visibility bit sets of all frames (bit set = pixel sees the environment).
#[derive(Debug, Clone, PartialEq)]
pub struct VisibilityMaps {
    /// Hemicube resolution.
    pub res: u32,
    /// Number of frames.
    pub frames: usize,
    /// 64-bit words per frame.
    pub words: usize,
    /// `frames · words` words.
    pub bits: Vec<u64>,
}

impl VisibilityMaps {
    /// The maps of every frame: the answer of [`VisibilityMaps::compute_ray_cast`], found by
    /// projecting the culled mesh onto each hemicube (see `raster`) and testing only the
    /// still-visible pixels a triangle may cover.
    pub fn compute(
        cube: &Hemicube,
        frames: &[HemicubeFrame],
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
    ) -> VisibilityMaps {
        let bvh = Bvh::new(positions, triangles);
        let eps = offset(positions);
        let words = cube.len().div_ceil(64);
        let mut bits = vec![0u64; frames.len() * words];
        bits.par_chunks_mut(words).zip(frames.par_iter()).for_each_init(
            || FrameRaster::new(cube),
            |raster, (out, f)| raster.run(&bvh, f, eps, out),
        );
        VisibilityMaps { res: cube.res, frames: frames.len(), words, bits }
    }

    /// [`VisibilityMaps::compute`] for the frames with `wanted[f]` only; the others are
    /// left all-occluded (zero bits) — what a scene gets for vertex sides its camera never
    /// shows (see `Renderer`'s camera sides). Same bits as the full computation on every
    /// wanted frame.
    pub fn compute_some(
        cube: &Hemicube,
        frames: &[HemicubeFrame],
        wanted: &[bool],
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
    ) -> VisibilityMaps {
        assert_eq!(wanted.len(), frames.len(), "one wanted flag per frame");
        let bvh = Bvh::new(positions, triangles);
        let eps = offset(positions);
        let words = cube.len().div_ceil(64);
        let mut bits = vec![0u64; frames.len() * words];
        bits.par_chunks_mut(words)
            .zip(frames.par_iter().zip(wanted.par_iter()))
            .filter(|(_, (_, w))| **w)
            .for_each_init(
                || FrameRaster::new(cube),
                |raster, (out, (f, _))| raster.run(&bvh, f, eps, out),
            );
        VisibilityMaps { res: cube.res, frames: frames.len(), words, bits }
    }

    /// Copies the bits of every frame with `take[f]` from `other` (same frames and
    /// resolution).
    pub fn merge_from(&mut self, other: &VisibilityMaps, take: &[bool]) {
        assert!(other.frames == self.frames && other.words == self.words);
        let w = self.words;
        for (f, _) in take.iter().enumerate().filter(|(_, t)| **t) {
            self.bits[f * w..(f + 1) * w].copy_from_slice(&other.bits[f * w..(f + 1) * w]);
        }
    }

    /// The reference: one any-hit ray per pixel of every frame against the mesh.
    pub fn compute_ray_cast(
        cube: &Hemicube,
        frames: &[HemicubeFrame],
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
    ) -> VisibilityMaps {
        let bvh = Bvh::new(positions, triangles);
        let eps = offset(positions);
        let words = cube.len().div_ceil(64);
        let mut bits = vec![0u64; frames.len() * words];
        bits.par_chunks_mut(words).zip(frames.par_iter()).for_each(|(out, f)| {
            let o = [0, 1, 2].map(|a| f.origin[a] + eps * f.axes[2][a]);
            for (p, d) in cube.dirs.iter().enumerate() {
                if !bvh.occluded(o, f.to_world(*d), eps) {
                    out[p / 64] |= 1 << (p % 64);
                }
            }
        });
        VisibilityMaps { res: cube.res, frames: frames.len(), words, bits }
    }

    /// Whether pixel `p` of frame `f` sees the environment.
    pub fn visible(&self, f: usize, p: usize) -> bool {
        self.bits[f * self.words + p / 64] >> (p % 64) & 1 == 1
    }

    /// The bit set of frame `f`.
    pub fn frame_bits(&self, f: usize) -> &[u64] {
        &self.bits[f * self.words..(f + 1) * self.words]
    }

    /// Fraction of frame `f`'s hemisphere (by solid angle) that is visible.
    pub fn visible_fraction(&self, cube: &Hemicube, f: usize) -> f64 {
        let s: f64 =
            (0..cube.len()).filter(|&p| self.visible(f, p)).map(|p| cube.solid_angle[p]).sum();
        s / (2.0 * std::f64::consts::PI)
    }

    /// Loads the maps for `key` from `dir`, or computes and stores them. Returns the maps
    /// and whether they came from the cache.
    pub fn cached(
        dir: &Path,
        cube: &Hemicube,
        frames: &[HemicubeFrame],
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<(VisibilityMaps, bool)> {
        let key = cache_key(cube.res, frames, triangles);
        let path = cache_path(dir, key);
        if let Some(m) = read_cache(&path, cube, frames.len()) {
            return Ok((m, true));
        }
        let maps = VisibilityMaps::compute(cube, frames, positions, triangles);
        maps.write(&path)?;
        Ok((maps, false))
    }

    /// [`VisibilityMaps::cached`] for the `wanted` frames only (`None`: all). Maps of all
    /// frames already in the cache serve any subset; a subset is cached under its own key.
    /// Returns the maps, whether they came from the cache, and whether they hold every
    /// frame.
    pub fn cached_some(
        dir: &Path,
        cube: &Hemicube,
        frames: &[HemicubeFrame],
        wanted: Option<&[bool]>,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<(VisibilityMaps, bool, bool)> {
        let Some(wanted) = wanted.filter(|w| !w.iter().all(|&x| x)) else {
            let (m, hit) = VisibilityMaps::cached(dir, cube, frames, positions, triangles)?;
            return Ok((m, hit, true));
        };
        let full = cache_key(cube.res, frames, triangles);
        if let Some(m) = read_cache(&cache_path(dir, full), cube, frames.len()) {
            return Ok((m, true, true));
        }
        let mut h = fnv1a(full, b"subset");
        for &w in wanted {
            h = fnv1a(h, &[w as u8]);
        }
        let path = cache_path(dir, h);
        if let Some(m) = read_cache(&path, cube, frames.len()) {
            return Ok((m, true, false));
        }
        let maps = VisibilityMaps::compute_some(cube, frames, wanted, positions, triangles);
        maps.write(&path)?;
        Ok((maps, false, false))
    }

    /// Writes the maps atomically (temporary file, then rename).
    pub fn write(&self, path: &Path) -> Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let mut bytes = Vec::with_capacity(24 + self.bits.len() * 8);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&self.res.to_le_bytes());
        bytes.extend_from_slice(&(self.frames as u64).to_le_bytes());
        for w in &self.bits {
            bytes.extend_from_slice(&w.to_le_bytes());
        }
        let check = fnv1a(FNV_OFFSET, &bytes);
        bytes.extend_from_slice(&check.to_le_bytes());
        Ok(btf_core::fs::write_atomic(path, &bytes)?)
    }
}

fn offset(positions: &[[f32; 3]]) -> f32 {
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in positions {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let diag = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f32>().sqrt();
    (1e-4 * diag).max(1e-7)
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Hash of everything the maps depend on: resolution, frames (positions and axes) and
/// triangles.
pub fn cache_key(res: u32, frames: &[HemicubeFrame], triangles: &[[u32; 3]]) -> u64 {
    let mut h = fnv1a(FNV_OFFSET, MAGIC);
    h = fnv1a(h, &res.to_le_bytes());
    for f in frames {
        for c in f.origin.iter().chain(f.axes.iter().flatten()) {
            h = fnv1a(h, &c.to_bits().to_le_bytes());
        }
    }
    for t in triangles {
        for i in t {
            h = fnv1a(h, &i.to_le_bytes());
        }
    }
    h
}

/// `dir/visibility-<key>.bin`.
pub fn cache_path(dir: &Path, key: u64) -> PathBuf {
    dir.join(format!("visibility-{key:016x}.bin"))
}

fn read_cache(path: &Path, cube: &Hemicube, frames: usize) -> Option<VisibilityMaps> {
    let bytes = std::fs::read(path).ok()?;
    let words = cube.len().div_ceil(64);
    let expect = 20 + frames * words * 8 + 8;
    if bytes.len() != expect || &bytes[..8] != MAGIC {
        return None;
    }
    let (body, check) = bytes.split_at(expect - 8);
    if fnv1a(FNV_OFFSET, body).to_le_bytes() != check {
        return None;
    }
    let res = u32::from_le_bytes(body[8..12].try_into().ok()?);
    let n = u64::from_le_bytes(body[12..20].try_into().ok()?) as usize;
    if res != cube.res || n != frames {
        return None;
    }
    let bits = body[20..]
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
        .collect();
    Some(VisibilityMaps { res, frames, words, bits })
}
