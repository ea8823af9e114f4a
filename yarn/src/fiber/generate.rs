//! `generate_fibers`: explicit fibers of a `YarnSet` as polylines with a radius, for the
//! CPU reference renderer (capsule chains in a BVH) and for exports.
//!
//! **Layout** (flat arrays, ready for a BVH build): `points` (f32 metres), `radii` and
//! `color_ids` per point; `offsets[k]..offsets[k+1]` are the points of fiber `k`; per fiber
//! its `yarn` (curve index), `ply`, `fiber` (sorted index in the ply), `kind` (core, regular,
//! hair) and `params_id`. Positions are computed in f64 ([`super::FiberModel`]) and rounded
//! once.
//!
//! **Sampling.** A curve segment gets `ceil(Δz/step)` uniform parameter steps, with
//! `step = min(|α'|, |α_ply'|)/samples_per_turn` (and at most `max_step`), so every helix
//! turn has the same number of points wherever the curve is. A closed curve is sampled over
//! one wrap, `u ∈ [0, segments]`; its last point is its first translated by `shift`.
//!
//! **Determinism.** Each (curve, ply, fiber) is one independent job whose every random
//! number is a key hash ([`crate::hash`]); rayon runs the jobs and the results are joined
//! in job order, so the output is bit-identical for any thread count.

use super::model::{EffectiveTwist, FiberModel, YarnPoint};
use super::table::{FiberTable, PeriodKind};
use crate::curve::{YarnCurve, YarnSet};
use crate::frame::CurveFrames;
use crate::params::YarnParams;
use crate::{Error, Result};
use rayon::prelude::*;

/// Options of [`generate_fibers`].
#[derive(Debug, Clone, PartialEq)]
pub struct GenOptions {
    /// Seed of every random draw.
    pub seed: u64,
    /// Polyline points per turn of the faster helix (ply or fiber).
    pub samples_per_turn: u32,
    /// Largest step along the length coordinate (metres), if smaller than the turn step.
    pub max_step: Option<f64>,
    /// Emit hair flyaways.
    pub hairs: bool,
    /// Bend fibers out in loop slots.
    pub loops: bool,
    /// Points per hair polyline.
    pub hair_samples: u32,
    /// Frame table resolution (samples per curve segment).
    pub frame_samples_per_segment: usize,
    /// Refuse to produce more points than this.
    pub max_points: usize,
}

impl Default for GenOptions {
    fn default() -> Self {
        GenOptions {
            seed: 1,
            samples_per_turn: 12,
            max_step: None,
            hairs: true,
            loops: true,
            hair_samples: 12,
            frame_samples_per_segment: 16,
            max_points: 1 << 28,
        }
    }
}

/// What a fiber is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum FiberKind {
    /// One of the innermost `core_fraction` of a ply's fibers.
    Core = 0,
    /// Any other regular (migration/loop) fiber.
    Regular = 1,
    /// A hair flyaway.
    Hair = 2,
}

/// Explicit fibers (see the module documentation for the layout).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Fibers {
    /// Polyline points, all fibers concatenated (metres).
    pub points: Vec<[f32; 3]>,
    /// Radius per point (metres).
    pub radii: Vec<f32>,
    /// Colour per point, an index into `palette`.
    pub color_ids: Vec<u32>,
    /// `offsets[k]..offsets[k + 1]` index the points of fiber `k` (length `fibers + 1`).
    pub offsets: Vec<u32>,
    /// Curve index per fiber.
    pub yarn: Vec<u32>,
    /// Ply per fiber.
    pub ply: Vec<u16>,
    /// Sorted fiber index within its ply (a hair: the fiber whose slot emitted it).
    pub fiber: Vec<u32>,
    /// Kind per fiber.
    pub kind: Vec<FiberKind>,
    /// Yarn-params id per fiber.
    pub params_id: Vec<u32>,
    /// Distinct colours (linear RGB).
    pub palette: Vec<[f32; 3]>,
    /// The set's period, if periodic.
    pub period: Option<[f64; 2]>,
    /// Pitches used, per curve.
    pub twists: Vec<EffectiveTwist>,
    /// Loop slots inside the generated range (all curves).
    pub loop_count: usize,
}

impl Fibers {
    /// Number of fibers.
    pub fn fiber_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The points of fiber `k`.
    pub fn fiber_points(&self, k: usize) -> &[[f32; 3]] {
        &self.points[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }

    /// Number of hair fibers.
    pub fn hair_count(&self) -> usize {
        self.kind.iter().filter(|k| **k == FiberKind::Hair).count()
    }
}

/// One curve, ready for its fiber jobs.
struct Prepared<'a> {
    curve: &'a YarnCurve,
    params: &'a YarnParams,
    params_id: u32,
    table: FiberTable,
    twist: EffectiveTwist,
    frames: CurveFrames,
    samples: Vec<YarnPoint>,
    /// Palette index per sample.
    colors: Vec<u32>,
    /// Palette index per control point.
    cp_colors: Vec<u32>,
    z_range: (f64, f64),
}

/// Output of one (curve, ply, fiber) job.
struct JobOut {
    regular: Vec<[f32; 3]>,
    regular_colors: Vec<u32>,
    hairs: Vec<(Vec<[f32; 3]>, Vec<u32>)>,
    loops: usize,
}

/// Generates the explicit fibers of `set`; curve `i` uses `params[params_id]` of its
/// control points (all of a curve's points must carry the same id).
pub fn generate_fibers(set: &YarnSet, params: &[YarnParams], opts: &GenOptions) -> Result<Fibers> {
    set.validate()?;
    if opts.samples_per_turn == 0 || opts.hair_samples < 2 {
        return Err(Error::Invalid("samples_per_turn must be ≥ 1 and hair_samples ≥ 2".to_owned()));
    }
    let mut palette: Vec<[f32; 3]> = Vec::new();
    for c in &set.curves {
        for col in &c.colors {
            if !palette.contains(col) {
                palette.push(*col);
            }
        }
    }
    let mut ids = Vec::with_capacity(set.curves.len());
    for (i, c) in set.curves.iter().enumerate() {
        let id = c.params_ids[0];
        if let Some(k) = c.params_ids.iter().position(|&x| x != id) {
            return Err(Error::Unsupported(format!(
                "curve {i}: control point {k} has yarn params id {} after {id} (one yarn \
                 description per curve)",
                c.params_ids[k]
            )));
        }
        let p = params.get(id as usize).ok_or_else(|| {
            Error::Invalid(format!(
                "curve {i}: yarn params id {id}, but {} params given",
                params.len()
            ))
        })?;
        p.validate()?;
        ids.push(id);
    }
    let prepared: Vec<Prepared> = set
        .curves
        .par_iter()
        .enumerate()
        .map(|(i, c)| prepare(i, c, &params[ids[i] as usize], ids[i], &palette, opts))
        .collect::<Result<_>>()?;
    let regular_points: usize = prepared
        .iter()
        .map(|p| p.samples.len() * (p.params.ply_count * p.params.fibers_per_ply) as usize)
        .sum();
    if regular_points > opts.max_points || regular_points > u32::MAX as usize / 2 {
        return Err(Error::Limit(format!(
            "the fibers would have {regular_points} points (limit {}); lower \
             samples_per_turn or raise GenOptions::max_points",
            opts.max_points.min(u32::MAX as usize / 2)
        )));
    }
    let jobs: Vec<(usize, usize, usize)> = prepared
        .iter()
        .enumerate()
        .flat_map(|(ci, p)| {
            let (np, nf) = (p.params.ply_count as usize, p.params.fibers_per_ply as usize);
            (0..np).flat_map(move |ply| (0..nf).map(move |f| (ci, ply, f)))
        })
        .collect();
    let outs: Vec<JobOut> =
        jobs.par_iter().map(|&(ci, ply, f)| fiber_job(&prepared[ci], ply, f, opts)).collect();
    let mut fib = Fibers {
        palette,
        period: set.period,
        twists: prepared.iter().map(|p| p.twist).collect(),
        offsets: vec![0],
        ..Fibers::default()
    };
    for (&(ci, ply, f), out) in jobs.iter().zip(outs) {
        let p = &prepared[ci];
        let kind = if p.table.fiber(ply, f).core { FiberKind::Core } else { FiberKind::Regular };
        push(&mut fib, &out.regular, &out.regular_colors, p, ci, ply, f, kind);
        for (pts, cols) in &out.hairs {
            push(&mut fib, pts, cols, p, ci, ply, f, FiberKind::Hair);
        }
        fib.loop_count += out.loops;
        if fib.points.len() > opts.max_points {
            return Err(Error::Limit(format!(
                "the fibers (with hairs) exceed {} points; lower the hair density or raise \
                 GenOptions::max_points",
                opts.max_points
            )));
        }
    }
    Ok(fib)
}

fn push(
    fib: &mut Fibers,
    pts: &[[f32; 3]],
    cols: &[u32],
    p: &Prepared,
    ci: usize,
    ply: usize,
    f: usize,
    kind: FiberKind,
) {
    fib.points.extend_from_slice(pts);
    fib.color_ids.extend_from_slice(cols);
    fib.radii.extend(std::iter::repeat_n(p.params.fiber_radius as f32, pts.len()));
    fib.offsets.push(fib.points.len() as u32);
    fib.yarn.push(ci as u32);
    fib.ply.push(ply as u16);
    fib.fiber.push(f as u32);
    fib.kind.push(kind);
    fib.params_id.push(p.params_id);
}

fn prepare<'a>(
    index: usize,
    curve: &'a YarnCurve,
    params: &'a YarnParams,
    params_id: u32,
    palette: &[[f32; 3]],
    opts: &GenOptions,
) -> Result<Prepared<'a>> {
    let table = FiberTable::new(params, opts.seed, index as u64);
    let twist = EffectiveTwist::for_curve(params, curve);
    let frames = CurveFrames::new(curve, opts.frame_samples_per_segment);
    let mut step =
        twist.fiber_pitch.abs().min(twist.ply_pitch.abs()) / opts.samples_per_turn as f64;
    if let Some(m) = opts.max_step.filter(|m| *m > 0.0) {
        step = step.min(m);
    }
    let segs = curve.segment_count();
    let per_segment = |i: usize| {
        let dz = (curve.length_coord_at(i as isize + 1) - curve.length_coord_at(i as isize)).abs();
        ((dz / step).ceil().min(usize::MAX as f64 / 4.0) as usize).max(1)
    };
    // The limit before anything is allocated: a huge samples_per_turn (or a tiny step)
    // would otherwise allocate the samples first (the total is checked again over all
    // curves by the caller).
    let fibers = (params.ply_count * params.fibers_per_ply).max(1) as usize;
    let count = (0..segs).fold(1usize, |n, i| n.saturating_add(per_segment(i)));
    let limit = opts.max_points.min(u32::MAX as usize / 2);
    if count.saturating_mul(fibers) > limit {
        return Err(Error::Limit(format!(
            "curve {index}: its fibers would have {} points (limit {limit}); lower \
             samples_per_turn or raise GenOptions::max_points",
            count.saturating_mul(fibers)
        )));
    }
    let mut us = Vec::with_capacity(count);
    for i in 0..segs {
        let c = per_segment(i);
        us.extend((0..c).map(|j| i as f64 + j as f64 / c as f64));
    }
    us.push(segs as f64);
    let samples: Vec<YarnPoint> = us.iter().map(|&u| YarnPoint::at(curve, &frames, u)).collect();
    let cp_colors: Vec<u32> = curve
        .colors
        .iter()
        .map(|col| palette.iter().position(|c| c == col).unwrap_or(0) as u32)
        .collect();
    let colors = us.iter().map(|&u| cp_colors[nearest_cp(curve, u)]).collect();
    let z_range = (curve.length_coord(0.0), curve.length_coord(segs as f64));
    Ok(Prepared {
        curve,
        params,
        params_id,
        table,
        twist,
        frames,
        samples,
        colors,
        cp_colors,
        z_range,
    })
}

/// The control point nearest to parameter `u` (wrapped on closed curves).
fn nearest_cp(curve: &YarnCurve, u: f64) -> usize {
    let n = curve.points.len() as i64;
    let k = u.round() as i64;
    if curve.closed { k.rem_euclid(n) as usize } else { k.clamp(0, n - 1) as usize }
}

fn fiber_job(p: &Prepared, ply: usize, f: usize, opts: &GenOptions) -> JobOut {
    let model = FiberModel { params: p.params, table: &p.table, twist: p.twist };
    let fiber = p.table.fiber(ply, f);
    // The slot's type changes once per period: cache it.
    let mut cached: Option<(i64, PeriodKind)> = None;
    let mut regular = Vec::with_capacity(p.samples.len());
    for yp in &p.samples {
        let sigma = model.slot_coord(yp.z, ply, f);
        let k = sigma.floor() as i64;
        let kind = match cached {
            Some((ck, kind)) if ck == k => kind,
            _ => {
                let kind =
                    if opts.loops { model.period_kind(ply, f, k) } else { PeriodKind::Migration };
                cached = Some((k, kind));
                kind
            }
        };
        let r = model.radius_in(yp.z, ply, f, sigma, &kind);
        let psi = fiber.theta + model.fiber_turn(yp.z);
        let q = yp.offset(model.ellipse_offset(yp.z, ply, r, psi));
        regular.push(q.map(|x| x as f32));
    }
    // Slots overlapping the generated range, and the flyaways among them.
    let (z0, z1) = p.z_range;
    let (s0, s1) = (model.slot_coord(z0, ply, f), model.slot_coord(z1, ply, f));
    let (lo, hi) = (s0.min(s1).floor() as i64, s0.max(s1).floor() as i64);
    let inside = |z: f64| z >= z0.min(z1) && z < z0.max(z1);
    let mut hairs = Vec::new();
    let mut loops = 0;
    for k in lo..=hi {
        match model.period_kind(ply, f, k) {
            PeriodKind::Loop { .. } if inside(model.z_of_slot_coord(k as f64 + 0.5, ply, f)) => {
                loops += 1
            }
            PeriodKind::Hair(shape) if opts.hairs => {
                let sigma0 = k as f64 + shape.slot_fraction;
                if inside(model.z_of_slot_coord(sigma0, ply, f)) {
                    let h = hair_polyline(p, &model, &shape, ply, f, sigma0, opts.hair_samples);
                    if h.0.len() >= 2 {
                        hairs.push(h);
                    }
                }
            }
            _ => {}
        }
    }
    JobOut { regular, regular_colors: p.colors.clone(), hairs, loops }
}

fn hair_polyline(
    p: &Prepared,
    model: &FiberModel,
    shape: &super::table::HairShape,
    ply: usize,
    f: usize,
    sigma0: f64,
    samples: u32,
) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut pts = Vec::new();
    let mut cols = Vec::new();
    for j in 0..samples {
        let t = j as f64 / (samples - 1) as f64;
        let (z, ab) = model.hair_offset(shape, ply, f, sigma0, t);
        // Open curves crop hairs at their ends ([Z16] crops at the yarn's box).
        let Some(u) = p.curve.param_at_length_coord(z) else {
            if pts.is_empty() { continue } else { break }
        };
        let yp = YarnPoint::at(p.curve, &p.frames, u);
        pts.push(yp.offset(ab).map(|x| x as f32));
        cols.push(p.cp_colors[nearest_cp(p.curve, u)]);
    }
    (pts, cols)
}
