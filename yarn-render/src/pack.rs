//! `PackedYarns`: a [`YarnSet`] and its [`YarnParams`] laid out for the GPU fiber passes —
//! everything the WGSL generator (`shaders/fiber_gen.wgsl`) needs to evaluate any fiber
//! of any segment at any parameter, and nothing per fiber point ([W19 §5]: fibers are
//! generated, never stored).
//!
//! Per **segment** (the yarn's Catmull–Rom segment `P_1 → P_2` with its window
//! `P_0..P_3`, [W19 §3.1]): the four control points relative to the set's origin, their
//! length coordinates relative to `z(P_1)`, the interpolated surface normals, the colour,
//! and the **phases** of the two helices and of the fiber-type slots at `P_1`, reduced in
//! f64 on the CPU. The GPU therefore only ever adds a small `Δz/α` to a fraction in
//! `[0, 1)`, so f32 keeps every fiber's phase to ~1e-7 of a turn however long the yarn
//! is; `2πz/α` in f32 would lose 1e-5 rad per 10 cm of yarn at a 2 mm pitch (DESIGN §2.5's
//! 1e-5 × yarn-radius bound for CPU = GPU positions would not hold).
//!
//! Per **curve**: the effective pitches of [`EffectiveTwist::for_curve`] (closed curves
//! carry whole turns), the frame table of [`CurveFrames`] (the surface-anchored,
//! rotation-minimising frame of DESIGN §0 / §2.3 item 9, repeated in WGSL from its
//! samples), the hash prefix of `(seed, curve)` for the slot types of
//! [`FiberTable::period_kind`], and where its fiber table starts.
//!
//! Per **curve × ply × fiber**: `R_i, θ_i, φ_i` and the core flag, sorted by `R_i` in each
//! ply (the order in which LoD drops fibers, [W19 §5]).
//!
//! Memory is `O(control points)`: 192 B a segment + 48 B a frame sample (4 per segment by
//! default) + 16 B a table fiber per curve; [`PackedYarns::bytes`] reports it. Flyaways
//! cost nothing more: loops and hairs are found by hashing a slot's keys on the GPU
//! (`fiber_lod` scans the slots each segment spans for hairs, `fiber_gen.wgsl` draws their
//! shapes), so hair polylines are never stored either.

use crate::{Error, Result};
use yarn::fiber::{EffectiveTwist, FiberTable};
use yarn::hash::{hash_keys, mix64};
use yarn::vec3::V3;
use yarn::{CurveFrames, YarnCurve, YarnParams, YarnSet};

/// One curve segment as the shaders read it (std430, 192 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SegmentRaw {
    /// `P_0..P_3` relative to [`PackedYarns::origin`]; `w` = `z_j − z_1`.
    pub p: [[f32; 4]; 4],
    /// Surface normals of the window (unit; `w` = 1 when the curve has normals).
    pub n: [[f32; 4]; 4],
    /// `frac(z_1/α_ply')`, `frac(z_1/α')`, `frac(s_r·z_1/α')` (slot phase), unused.
    pub phase: [f32; 4],
    /// Curve record (one per curve and tile), segment index within the curve, slot base `floor(s_r·z_1/α')` (i32
    /// bits), flags (bit 0: the curve has normals).
    pub ids: [u32; 4],
    /// Linear RGB of `P_1` and `P_2`: the CPU generator colours a point by its nearest
    /// control point, so the segment's first half takes `P_1`'s and its second `P_2`'s.
    pub color: [[f32; 4]; 2],
}

/// One curve as the shaders read it (std430, 64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CurveRaw {
    /// `α_ply'`, `α'`, `s'`, the slot rate `s_r` (`s'`, or 1 when `s' = 0`).
    pub pitch: [f32; 4],
    /// Params id, first fiber-table record, first frame sample, samples per segment.
    pub ids: [u32; 4],
    /// Slots per wrap (0: open curve), hash prefix of `(seed, curve)` (lo, hi), segments.
    pub keys: [u32; 4],
    /// Holonomy angle, samples per period `M`, length scale (tangent fallback), unused.
    pub frame: [f32; 4],
}

/// One frame-table sample (std430, 48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleRaw {
    /// Curve point relative to the origin; `w` = the unwrapped anchoring angle.
    pub x: [f32; 4],
    /// Unit tangent.
    pub t: [f32; 4],
    /// Carried (rotation-minimising) normal.
    pub carry: [f32; 4],
}

/// One yarn description as the shaders read it (std430, 112 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ParamsRaw {
    /// Ply-centre distance, `e_N`, `e_B`, `ρ_min`.
    pub a: [f32; 4],
    /// `ρ_max`, fiber radius, loop chance, `√(e_N e_B)`.
    pub b: [f32; 4],
    /// Loop `r_1` mean and sigma, yarn radius (no flyaways), flyaway reach.
    pub c: [f32; 4],
    /// Plies, fibers per ply, core fibers per ply, bit 0: slots have random types.
    pub d: [u32; 4],
    /// Hair `z_e` mean and sigma, `r_0` mean and sigma ([`FiberTable::period_kind`]).
    pub e: [f32; 4],
    /// Hair `r_e` mean and sigma, `p_e` mean and sigma.
    pub f: [f32; 4],
    /// Loop + hair chance (a slot's first draw below it and above the loop chance is a
    /// hair), the hair curvature α, the smallest `r_e` (5 % of the ply reach), and
    /// `max(e_N, e_B)/√(e_N e_B)` (a hair's reach from its normalised radius).
    pub g: [f32; 4],
}

/// Options of [`PackedYarns::new`]; they must equal the CPU generator's
/// ([`yarn::GenOptions`]) for the two to agree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackOptions {
    /// Seed of the fiber tables and slot types.
    pub seed: u64,
    /// Frame-table samples per segment.
    pub frame_samples_per_segment: usize,
    /// Copies of a periodic set `[nx, ny]` (odd, centred on the original): a 3 × 3
    /// neighbourhood is what a periodic patch needs around its period (DESIGN §4.2); the
    /// copies share the original's fiber tables, so their fibers are the same fibers.
    /// `[1, 1]` for a set without a period.
    pub tiles: [u32; 2],
}

impl Default for PackOptions {
    fn default() -> Self {
        PackOptions { seed: 1, frame_samples_per_segment: 4, tiles: [1, 1] }
    }
}

/// The yarns of a scene, packed (see the module documentation).
#[derive(Debug, Clone)]
pub struct PackedYarns {
    /// World position every packed coordinate is relative to (the set's bounding-box
    /// centre): positions stay small, so f32 keeps them to ~1e-9 m on a garment.
    pub origin: [f64; 3],
    /// Segments.
    pub segments: Vec<SegmentRaw>,
    /// Curves.
    pub curves: Vec<CurveRaw>,
    /// Frame samples of all curves.
    pub samples: Vec<SampleRaw>,
    /// Fiber tables of all curves: `R_i, θ_i, φ_i, core`.
    pub fibers: Vec<[f32; 4]>,
    /// Yarn descriptions.
    pub params: Vec<ParamsRaw>,
    /// Largest fibers per ply over all descriptions.
    pub max_fibers_per_ply: u32,
    /// Largest plies over all descriptions.
    pub max_plies: u32,
    /// Largest reach of any fiber from its yarn centre (metres, flyaways included).
    pub max_reach: f64,
    /// Bounding box of the control points (world, metres).
    pub bounds: ([f64; 3], [f64; 3]),
    /// The yarn descriptions (for the effects' precomputation).
    pub yarn_params: Vec<YarnParams>,
}

/// The reach of flyaways beyond the yarn tube (metres): loops to `r_1 + 3σ` from the ply
/// centre, hairs to `r_0 + r_e` (each + 3σ).
pub fn flyaway_reach(p: &YarnParams) -> f64 {
    let lo = p.loop_r1.mean + 3.0 * p.loop_r1.sigma;
    let hair = p.hair_r0.mean + 3.0 * p.hair_r0.sigma + p.hair_re.mean + 3.0 * p.hair_re.sigma;
    let mut reach = p.yarn_radius();
    if p.loop_chance() > 0.0 {
        reach = reach.max(p.ply_center_distance + lo + p.fiber_radius);
    }
    if p.hair_chance() > 0.0 {
        reach = reach.max(p.ply_center_distance + hair + p.fiber_radius);
    }
    reach
}

fn f4(v: V3, w: f64) -> [f32; 4] {
    [v[0] as f32, v[1] as f32, v[2] as f32, w as f32]
}

fn sub(a: V3, b: [f64; 3]) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `x − floor(x)` in f64.
fn frac(x: f64) -> f64 {
    x - x.floor()
}

impl PackedYarns {
    /// Packs `set` with `params` (curve `i` uses `params[id]` of its control points).
    pub fn new(set: &YarnSet, params: &[YarnParams], opts: &PackOptions) -> Result<Self> {
        set.validate()?;
        if opts.frame_samples_per_segment == 0 || opts.frame_samples_per_segment > 64 {
            return Err(Error::Invalid(format!(
                "frame_samples_per_segment {} (must be 1..=64)",
                opts.frame_samples_per_segment
            )));
        }
        let [nx, ny] = opts.tiles;
        if nx % 2 == 0 || ny % 2 == 0 || nx > 9 || ny > 9 {
            return Err(Error::Invalid(format!("tiles {nx} × {ny} (odd, at most 9)")));
        }
        let period = match (set.period, nx * ny) {
            (_, 1) => [0.0; 2],
            (Some(p), _) => p,
            (None, _) => {
                return Err(Error::Invalid(format!(
                    "tiles {nx} × {ny} for a yarn set without a period"
                )));
            }
        };
        let offsets: Vec<[f64; 3]> = (0..ny as i64)
            .flat_map(|j| {
                (0..nx as i64).map(move |i| {
                    let (di, dj) = (i - nx as i64 / 2, j - ny as i64 / 2);
                    [di as f64 * period[0], dj as f64 * period[1], 0.0]
                })
            })
            .collect();
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for c in &set.curves {
            for p in &c.points {
                for off in &offsets {
                    for a in 0..3 {
                        lo[a] = lo[a].min(p[a] + off[a]);
                        hi[a] = hi[a].max(p[a] + off[a]);
                    }
                }
            }
        }
        let origin =
            if set.curves.is_empty() { [0.0; 3] } else { [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a])) };
        let mut out = PackedYarns {
            origin,
            segments: Vec::new(),
            curves: Vec::new(),
            samples: Vec::new(),
            fibers: Vec::new(),
            params: Vec::new(),
            max_fibers_per_ply: 0,
            max_plies: 0,
            max_reach: 0.0,
            bounds: (lo, hi),
            yarn_params: params.to_vec(),
        };
        for (i, p) in params.iter().enumerate() {
            p.validate().map_err(|e| Error::Invalid(format!("yarn params {i}: {e}")))?;
            let core = (p.core_fraction * p.fibers_per_ply as f64).round() as u32;
            let random_slots = p.loop_chance() > 0.0 || p.hair_chance() > 0.0;
            out.params.push(ParamsRaw {
                a: [
                    p.ply_center_distance as f32,
                    p.ply_ellipse_n as f32,
                    p.ply_ellipse_b as f32,
                    p.rho_min as f32,
                ],
                b: [
                    p.rho_max as f32,
                    p.fiber_radius as f32,
                    p.loop_chance() as f32,
                    (p.ply_ellipse_n * p.ply_ellipse_b).sqrt() as f32,
                ],
                c: [
                    p.loop_r1.mean as f32,
                    p.loop_r1.sigma as f32,
                    p.yarn_radius() as f32,
                    flyaway_reach(p) as f32,
                ],
                d: [p.ply_count, p.fibers_per_ply, core, random_slots as u32],
                e: [
                    p.hair_ze.mean as f32,
                    p.hair_ze.sigma as f32,
                    p.hair_r0.mean as f32,
                    p.hair_r0.sigma as f32,
                ],
                f: [
                    p.hair_re.mean as f32,
                    p.hair_re.sigma as f32,
                    p.hair_pe.mean as f32,
                    p.hair_pe.sigma as f32,
                ],
                g: [
                    (p.loop_chance() + p.hair_chance()) as f32,
                    p.hair_curvature as f32,
                    (0.05 * p.ply_reach()) as f32,
                    (p.ply_ellipse_n.max(p.ply_ellipse_b)
                        / (p.ply_ellipse_n * p.ply_ellipse_b).sqrt()) as f32,
                ],
            });
            out.max_fibers_per_ply = out.max_fibers_per_ply.max(p.fibers_per_ply);
            out.max_plies = out.max_plies.max(p.ply_count);
        }
        if out.max_fibers_per_ply > 1 << 16 || out.max_plies > 255 {
            return Err(Error::Limit(format!(
                "{} plies × {} fibers per ply: the fiber passes address at most 255 plies and \
                 65 536 fibers per ply",
                out.max_plies, out.max_fibers_per_ply
            )));
        }
        for (ci, curve) in set.curves.iter().enumerate() {
            let id = curve.params_ids[0];
            if let Some(k) = curve.params_ids.iter().position(|&x| x != id) {
                return Err(Error::Invalid(format!(
                    "curve {ci}: control point {k} has yarn params id {} after {id} (one yarn \
                     description per curve)",
                    curve.params_ids[k]
                )));
            }
            let p = params.get(id as usize).ok_or_else(|| {
                Error::Invalid(format!(
                    "curve {ci}: yarn params id {id}, but {} params given",
                    params.len()
                ))
            })?;
            out.max_reach = out.max_reach.max(flyaway_reach(p));
            let table = FiberTable::new(p, opts.seed, ci as u64);
            let first_fiber = out.fibers.len() as u32;
            out.fibers.extend(table.fibers.iter().map(|f| {
                [f.r as f32, f.theta as f32, f.migration_phase as f32, f.core as u32 as f32]
            }));
            // Offset 0 (the original) first, so curve `ci`'s records come first per tile.
            for off in &offsets {
                out.pack_curve(ci, curve, p, id, first_fiber, *off, opts)?;
            }
        }
        Ok(out)
    }

    #[allow(clippy::too_many_arguments)]
    fn pack_curve(
        &mut self,
        ci: usize,
        curve: &YarnCurve,
        p: &YarnParams,
        params_id: u32,
        first_fiber: u32,
        offset: [f64; 3],
        opts: &PackOptions,
    ) -> Result<()> {
        let twist = EffectiveTwist::for_curve(p, curve);
        // Positions of this copy are relative to origin − offset.
        let org = [0, 1, 2].map(|a| self.origin[a] - offset[a]);
        let frames = CurveFrames::new(curve, opts.frame_samples_per_segment);
        let ft = frames.table();
        let slot_rate = if twist.migration_rate > 0.0 { twist.migration_rate } else { 1.0 };
        let segs = curve.segment_count();
        let curve_raw = CurveRaw {
            pitch: [
                twist.ply_pitch as f32,
                twist.fiber_pitch as f32,
                twist.migration_rate as f32,
                slot_rate as f32,
            ],
            ids: [params_id, first_fiber, self.samples.len() as u32, ft.samples_per_segment as u32],
            keys: {
                let h = hash_keys(&[opts.seed, ci as u64]);
                [twist.slots_per_wrap.unwrap_or(0) as u32, h as u32, (h >> 32) as u32, segs as u32]
            },
            frame: [ft.holonomy as f32, (ft.x.len() - 1) as f32, curve.scale() as f32, 0.0],
        };
        if twist.slots_per_wrap.is_some_and(|m| m > u32::MAX as u64) {
            return Err(Error::Limit(format!("curve {ci}: too many fiber slots per wrap")));
        }
        self.curves.push(curve_raw);
        for k in 0..ft.x.len() {
            self.samples.push(SampleRaw {
                x: f4(sub(ft.x[k], org), ft.theta[k]),
                t: f4(ft.frames[k].t, 0.0),
                carry: f4(ft.carry[k], 0.0),
            });
        }
        let has_normals = curve.normals.is_some();
        let n_cp = curve.points.len() as isize;
        for s in 0..segs as isize {
            let z1 = curve.length_coord_at(s);
            let mut seg = SegmentRaw::default();
            for (j, d) in [-1isize, 0, 1, 2].into_iter().enumerate() {
                let z = curve.length_coord_at(s + d) - z1;
                seg.p[j] = f4(sub(curve.control_point(s + d), org), z);
                if let Some(normals) = &curve.normals {
                    let k = if curve.closed {
                        (s + d).rem_euclid(n_cp)
                    } else {
                        (s + d).clamp(0, n_cp - 1)
                    } as usize;
                    let nn = yarn::vec3::normalize_or(normals[k], [0.0, 0.0, 1.0]);
                    seg.n[j] = f4(nn, 1.0);
                }
            }
            let slot = slot_rate * z1 / twist.fiber_pitch;
            let base = slot.floor();
            if base.abs() > i32::MAX as f64 {
                return Err(Error::Limit(format!(
                    "curve {ci}, segment {s}: length coordinate {z1} m is too long for the GPU's \
                     32-bit slot index"
                )));
            }
            seg.phase = [
                frac(z1 / twist.ply_pitch) as f32,
                frac(z1 / twist.fiber_pitch) as f32,
                frac(slot) as f32,
                0.0,
            ];
            seg.ids =
                [self.curves.len() as u32 - 1, s as u32, (base as i32) as u32, has_normals as u32];
            let c1 = curve.colors[s as usize % curve.points.len()];
            let c2 = curve.colors[(s as usize + 1) % curve.points.len()];
            seg.color = [[c1[0], c1[1], c1[2], 1.0], [c2[0], c2[1], c2[2], 1.0]];
            self.segments.push(seg);
        }
        Ok(())
    }

    /// GPU bytes of the packed data.
    pub fn bytes(&self) -> u64 {
        (self.segments.len() * size_of::<SegmentRaw>()
            + self.curves.len() * size_of::<CurveRaw>()
            + self.samples.len() * size_of::<SampleRaw>()
            + self.fibers.len() * 16
            + self.params.len() * size_of::<ParamsRaw>()) as u64
    }

    /// Number of control points packed (one per segment of every curve).
    pub fn control_points(&self) -> usize {
        self.segments.len()
    }
}

/// SplitMix64's finaliser (re-exported for the WGSL mirror's tests).
pub fn mix(z: u64) -> u64 {
    mix64(z)
}
