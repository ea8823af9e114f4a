// The procedural fiber generator on the GPU: the WGSL mirror of yarn::fiber::FiberModel
// (the CPU reference it is tested against to 1e-5 of the yarn radius) — Catmull–Rom centre
// line, surface-anchored rotation-minimising frame (yarn::frame::CurveFrames::frame_at),
// ply displacement [W19 §3.1], elliptical fiber displacement with migration [W19 eq. 1–2],
// loops, hair flyaways (the slot's shape drawn from its hash, placed along the curve by
// its length coordinate), and the keyed SplitMix64 hash that gives every (fiber, slot) its
// type.
// Prepended to every fiber pass; group 0 is the packed yarn data (pack.rs).

struct Segment {
    p: array<vec4<f32>, 4>,
    n: array<vec4<f32>, 4>,
    phase: vec4<f32>,
    ids: vec4<u32>,
    color: array<vec4<f32>, 2>,
}

struct Curve {
    pitch: vec4<f32>,
    ids: vec4<u32>,
    keys: vec4<u32>,
    frame: vec4<f32>,
}

struct Sample {
    x: vec4<f32>,
    t: vec4<f32>,
    carry: vec4<f32>,
}

struct Params {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    d: vec4<u32>,
    e: vec4<f32>,
    f: vec4<f32>,
    g: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> segments: array<Segment>;
@group(0) @binding(1) var<storage, read> curves: array<Curve>;
@group(0) @binding(2) var<storage, read> samples: array<Sample>;
@group(0) @binding(3) var<storage, read> fiber_table: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> yarn_params: array<Params>;

const TAU: f32 = 6.283185307179586;
const PI: f32 = 3.141592653589793;

// ---- 64-bit integers as vec2<u32>(lo, hi), for yarn::hash ----

fn mul32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    let lo = (p00 & 0xffffu) | (mid << 16u);
    let hi = p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u);
    return vec2<u32>(lo, hi);
}

fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let l = mul32(a.x, b.x);
    return vec2<u32>(l.x, l.y + a.x * b.y + a.y * b.x);
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    let carry = select(0u, 1u, lo < a.x);
    return vec2<u32>(lo, a.y + b.y + carry);
}

fn shr64(a: vec2<u32>, n: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// SplitMix64's finaliser (yarn::hash::mix64).
fn mix64(z0: vec2<u32>) -> vec2<u32> {
    var z = z0 ^ shr64(z0, 30u);
    z = mul64(z, vec2<u32>(0x1ce4e5b9u, 0xbf58476du));
    z = z ^ shr64(z, 27u);
    z = mul64(z, vec2<u32>(0x133111ebu, 0x94d049bbu));
    return z ^ shr64(z, 31u);
}

const GOLDEN: vec2<u32> = vec2<u32>(0x7f4a7c15u, 0x9e3779b9u);

// One step of yarn::hash::hash_keys: key `k` at position `i` (GOLDEN·(i+1) given).
fn hash_step(h: vec2<u32>, k: vec2<u32>, golden_i: vec2<u32>) -> vec2<u32> {
    return mix64(h ^ mix64(add64(k, golden_i)));
}

// A uniform number in [0, 1) from 64 bits (f32 from the top bits, as yarn::hash::unit_f64
// takes the top 53).
fn unit_of(bits: vec2<u32>) -> f32 {
    return f32(bits.y >> 8u) * (1.0 / 16777216.0);
}

// 1 − unit_of(bits), never 0.
fn unit_complement(bits: vec2<u32>) -> f32 {
    return f32((0xffffffu - (bits.y >> 8u)) + 1u) * (1.0 / 16777216.0);
}

// ---- Catmull–Rom (yarn::curve::basis) ----

fn cr_basis(t: f32) -> vec4<f32> {
    let t2 = t * t;
    let t3 = t2 * t;
    return 0.5 * vec4<f32>(-t3 + 2.0 * t2 - t, 3.0 * t3 - 5.0 * t2 + 2.0,
        -3.0 * t3 + 4.0 * t2 + t, t3 - t2);
}

fn cr_basis_d1(t: f32) -> vec4<f32> {
    let t2 = t * t;
    return 0.5 * vec4<f32>(-3.0 * t2 + 4.0 * t - 1.0, 9.0 * t2 - 10.0 * t,
        -9.0 * t2 + 8.0 * t + 1.0, 3.0 * t2 - 2.0 * t);
}

fn cr_basis_d2(t: f32) -> vec4<f32> {
    return 0.5 * vec4<f32>(-6.0 * t + 4.0, 18.0 * t - 10.0, -18.0 * t + 8.0, 6.0 * t - 2.0);
}

// Σ w_j p_j as yarn::curve::basis::combine: about P_1, so derivatives of coincident points
// vanish exactly.
fn combine(s: Segment, w: vec4<f32>) -> vec3<f32> {
    let sum = w.x + w.y + w.z + w.w;
    let base = select(0.0, sum, abs(sum) > 0.5);
    let p1 = s.p[1].xyz;
    return p1 * base + w.x * (s.p[0].xyz - p1) + w.z * (s.p[2].xyz - p1)
        + w.w * (s.p[3].xyz - p1);
}

fn seg_tangent(s: Segment, t: f32, scale: f32) -> vec3<f32> {
    let d = combine(s, cr_basis_d1(t));
    if length(d) > 1e-9 * scale {
        return normalize(d);
    }
    let d2 = combine(s, cr_basis_d2(t));
    if length(d2) > 1e-9 * scale {
        return normalize(d2);
    }
    // Zero-length segment: the chord to the next distinct point (yarn's chord fallback,
    // limited to the window).
    let c = s.p[2].xyz - s.p[1].xyz;
    if length(c) > 0.0 {
        return normalize(c);
    }
    let c2 = s.p[1].xyz - s.p[0].xyz;
    if length(c2) > 0.0 {
        return normalize(c2);
    }
    return vec3<f32>(1.0, 0.0, 0.0);
}

fn seg_surface_normal(s: Segment, t: f32) -> vec3<f32> {
    let w = cr_basis(t);
    let n = w.x * s.n[0].xyz + w.y * s.n[1].xyz + w.z * s.n[2].xyz + w.w * s.n[3].xyz;
    if length(n) > 0.0 {
        return normalize(n);
    }
    return s.n[1].xyz;
}

// ---- frames (yarn::frame) ----

fn rotate_about(v: vec3<f32>, axis: vec3<f32>, angle: f32) -> vec3<f32> {
    let c = cos(angle);
    let s = sin(angle);
    return v * c + cross(axis, v) * s + axis * dot(axis, v) * (1.0 - c);
}

fn normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    return select(fallback, v / l, l > 0.0);
}

fn any_perpendicular(t: vec3<f32>) -> vec3<f32> {
    let up = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 0.0, 1.0), abs(t.z) < 0.95);
    return normalize_or(up - t * dot(up, t), vec3<f32>(0.0, 1.0, 0.0));
}

// yarn::frame::double_reflection, with one difference: a step shorter than 1e-6 of the
// curve's scale (`scale`), or a tangent change below 1e-5 rad, counts as none. In f32 the
// evaluation point and the table sample it starts from differ by rounding noise when they
// are the same point (and so do the two tangents); a reflection across the plane normal
// to that noise mirrors the frame. The CPU never sees this: it returns the table sample
// itself at frac = 0. Skipping a reflection of a real change below these sizes changes
// the frame by its square (< 1e-10 rad).
fn double_reflection(x0: vec3<f32>, t0: vec3<f32>, r0: vec3<f32>, x1: vec3<f32>,
    t1: vec3<f32>, scale: f32) -> vec3<f32> {
    let v1 = x1 - x0;
    let c1 = dot(v1, v1);
    var rl = r0;
    var tl = t0;
    if c1 > 1e-12 * scale * scale {
        rl = r0 - v1 * (2.0 / c1 * dot(v1, r0));
        tl = t0 - v1 * (2.0 / c1 * dot(v1, t0));
    }
    let v2 = t1 - tl;
    let c2 = dot(v2, v2);
    var r1 = rl;
    if c2 > 1e-10 {
        r1 = rl - v2 * (2.0 / c2 * dot(v2, rl));
    }
    let rej = r1 - t1 * dot(r1, t1);
    let l = length(rej);
    return select(any_perpendicular(t1), rej / l, l > 0.0);
}

fn anchor_weight(n_dot_t: f32) -> f32 {
    let x = clamp((0.95 - abs(n_dot_t)) / 0.05, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// yarn::frame::anchor's output normal.
fn anchor_normal(r: vec3<f32>, t: vec3<f32>, s: vec3<f32>, theta_ref: f32) -> vec3<f32> {
    let rej = s - t * dot(s, t);
    let l = length(rej);
    if !(l > 0.0) {
        return r;
    }
    let target_n = rej / l;
    let w = anchor_weight(dot(s, t));
    if w >= 1.0 {
        return target_n;
    }
    let raw = atan2(dot(cross(r, target_n), t), dot(r, target_n));
    let theta = raw + TAU * round((theta_ref - raw) / TAU);
    if w <= 0.0 {
        return r;
    }
    return normalize_or(rotate_about(r, t, w * theta), target_n);
}

struct YarnPoint {
    pos: vec3<f32>,
    t: vec3<f32>,
    n: vec3<f32>,
    b: vec3<f32>,
    // z − z(P_1) (metres).
    dz: f32,
}

// The yarn centre, frame and relative length coordinate of segment `seg` at local t.
fn yarn_point(seg: u32, t_in: f32) -> YarnPoint {
    let s = segments[seg];
    let c = curves[s.ids.x];
    let t = clamp(t_in, 0.0, 1.0);
    let w = cr_basis(t);
    var yp: YarnPoint;
    yp.pos = combine(s, w);
    yp.dz = w.x * s.p[0].w + w.z * s.p[2].w + w.w * s.p[3].w;
    let tan = seg_tangent(s, t, c.frame.z);
    yp.t = tan;
    // frame_at: carry from the sample at or before (k, frac) by double reflection.
    let sps = c.ids.w;
    let pos = t * f32(sps);
    let kk = min(u32(floor(pos)), sps - 1u);
    let frac = pos - f32(kk);
    let k = c.ids.z + s.ids.y * sps + kk;
    let smp = samples[k];
    let carried = double_reflection(smp.x.xyz, smp.t.xyz, smp.carry.xyz, yp.pos, tan, c.frame.z);
    var n = carried;
    if (s.ids.w & 1u) != 0u {
        n = anchor_normal(carried, tan, seg_surface_normal(s, t), smp.x.w);
    }
    if c.frame.x != 0.0 {
        n = rotate_about(n, tan, c.frame.x * frac / c.frame.y);
    }
    yp.n = n;
    yp.b = cross(tan, n);
    return yp;
}

// ---- fibers (yarn::fiber::model) ----

struct FiberSlot {
    // Normalised radius R(z) with loops.
    radius: f32,
    // ψ = θ_i + θ_fib (radians, reduced).
    psi: f32,
    // Ply angle φ_j (radians, reduced).
    ply_angle: f32,
}

// The KeyRng state of slot `slot_in` of (curve, ply, fiber): hash_keys of (seed, curve,
// ply, fiber, slot reduced per wrap, STREAM_SLOT) — FiberTable::period_kind's generator.
fn slot_state(c: Curve, ply: u32, fib: u32, slot_in: i32) -> vec2<u32> {
    var slot = slot_in;
    let m = c.keys.x;
    if m > 0u {
        let mi = i32(m);
        slot = ((slot % mi) + mi) % mi;
    }
    var h = vec2<u32>(c.keys.y, c.keys.z);
    // keys 2..5: ply, fiber, slot (as u64), STREAM_SLOT = 2; GOLDEN·(i+1).
    h = hash_step(h, vec2<u32>(ply, 0u), vec2<u32>(0x7ddf743fu, 0xdaa66d2cu));
    h = hash_step(h, vec2<u32>(fib, 0u), vec2<u32>(0xfd29f054u, 0x78dde6e5u));
    let slot_bits = vec2<u32>(bitcast<u32>(slot), select(0u, 0xffffffffu, slot < 0));
    h = hash_step(h, slot_bits, vec2<u32>(0x7c746c69u, 0x1715609fu));
    return hash_step(h, vec2<u32>(2u, 0u), vec2<u32>(0xfbbee87eu, 0xb54cda58u));
}

// Draw j (1-based) of a KeyRng whose state is h: mix64(h + j·GOLDEN), so any draw is read
// without the ones before it.
fn draw_bits(h: vec2<u32>, j: u32) -> vec2<u32> {
    return mix64(add64(h, mul64(GOLDEN, vec2<u32>(j, 0u))));
}

// A uniform number as hi + lo from the top 48 of 64 bits (hi: unit_of's top 24).
fn unit_pair(bits: vec2<u32>) -> vec2<f32> {
    let hi = f32(bits.y >> 8u) * (1.0 / 16777216.0);
    let lo = f32(((bits.y & 0xffu) << 16u) | (bits.x >> 16u)) * (1.0 / 281474976710656.0);
    return vec2<f32>(hi, lo);
}

// KeyRng::normal from draws j and j + 1 (Box–Muller, cosine branch). The uniforms keep
// 48 bits as hi + lo and enter to first order in lo: with 24 bits alone, cos(2πu₂) would
// be off by up to 4e-7, and a hair's r_e, drawn as μ + 0.75σn and small where the draw
// cancels the mean, would carry it ten-fold into the hair's length along the yarn.
fn draw_normal(h: vec2<u32>, j: u32) -> f32 {
    let a = unit_pair(draw_bits(h, j));
    let b = unit_pair(draw_bits(h, j + 1u));
    // 1 − u₁ = (1 − hi) − lo; 1 − hi is exact and at least 2^-24.
    let c_hi = 1.0 - a.x;
    let ln_u1 = log(c_hi) + max(-a.y / c_hi, -0.5);
    let angle = TAU * b.x;
    let cs = cos(angle) - sin(angle) * (TAU * b.y);
    return sqrt(-2.0 * ln_u1) * cs;
}

// The slot type of (curve, ply, fiber, slot): the loop peak (normalised), or −1.
fn loop_peak(c: Curve, pr: Params, ply: u32, fib: u32, slot_in: i32, r_i: f32) -> f32 {
    if pr.d.w == 0u || pr.b.z <= 0.0 {
        return -1.0;
    }
    let h = slot_state(c, ply, fib, slot_in);
    let u = unit_of(draw_bits(h, 1u));
    if u >= pr.b.z {
        return -1.0;
    }
    let r1 = pr.c.x + 0.5 * pr.c.y * draw_normal(h, 2u);
    return max(r1 / pr.b.w, 1.05 * pr.b.x * r_i);
}

// ---- hair flyaways (FiberTable::period_kind's Hair, FiberModel::hair_offset) ----

// Whether a slot whose generator state is h carries a hair: its first draw in
// [loop chance, loop + hair chance).
fn slot_is_hair(pr: Params, h: vec2<u32>) -> bool {
    let u = unit_of(draw_bits(h, 1u));
    return u >= pr.b.z && u < pr.g.x;
}

// A hair slot's crossing of r_0 inside its slot: draw 11 (after u, four normals and p_0).
fn hair_slot_fraction(h: vec2<u32>) -> f32 {
    return unit_of(draw_bits(h, 11u));
}

// The hair of one slot, relative to the segment whose slot base it was counted from.
struct Hair {
    // Length coordinate of the crossing of r_0, relative to that segment's z(P_1).
    dz_cross: f32,
    // z_e, r_0/r_e, r_0 + r_e (metres), p_0, p_e.
    ze: f32,
    k: f32,
    reach: f32,
    p0: f32,
    pe: f32,
}

// The hair of slot `slot_rel` (relative to segment `seg`'s slot base) of (ply, fib): the
// draws of FiberTable::period_kind — z_e, r_0, r_e, p_e ~ N(μ, 0.75σ) with r_0 ≥ 0 and r_e
// at least 5 % of the ply reach, p_0 uniform, the crossing uniform in the slot — and the
// crossing's length coordinate z_of_slot_coord.
fn hair_of(seg: u32, ply: u32, fib: u32, slot_rel: i32) -> Hair {
    let s = segments[seg];
    let c = curves[s.ids.x];
    let pr = yarn_params[c.ids.x];
    let rec = fiber_table[c.ids.y + ply * pr.d.y + fib];
    let h = slot_state(c, ply, fib, bitcast<i32>(s.ids.z) + slot_rel);
    let ze = pr.e.x + 0.75 * pr.e.y * draw_normal(h, 2u);
    let r0 = max(pr.e.z + 0.75 * pr.e.w * draw_normal(h, 4u), 0.0);
    let re = max(pr.f.x + 0.75 * pr.f.y * draw_normal(h, 6u), pr.g.z);
    let pe = pr.f.z + 0.75 * pr.f.w * draw_normal(h, 8u);
    let p0 = TAU * unit_of(draw_bits(h, 10u));
    // σ_0 − σ(z_1) = slot_rel + fraction − frac(s_r z_1/α') − (φ_i − π)/2π, in slots;
    // α'/s_r metres per slot.
    let x = hair_slot_fraction(h) - (rec.z - PI) / TAU;
    let d_sigma = f32(slot_rel) + (x - s.phase.z);
    var out: Hair;
    out.dz_cross = d_sigma * c.pitch.y / c.pitch.w;
    out.ze = ze;
    out.k = r0 / re;
    out.reach = r0 + re;
    out.p0 = p0;
    out.pe = pe;
    return out;
}

// The length-coordinate span of a hair (relative, as dz_cross): t = 0 and t = 1.
fn hair_dz(hr: Hair, t: f32) -> f32 {
    return hr.dz_cross - hr.ze * hr.k + hr.ze * (1.0 + hr.k) * t;
}

struct Place {
    seg: u32,
    t: f32,
    // The curve's shift times the wraps crossed (closed periodic curves).
    shift: vec3<f32>,
    // The segment walk ran off an open curve's end.
    clamped: bool,
}

// The segment and local parameter at length coordinate z(P_1 of seg0) + dz0 (the
// curve's length coordinates are those packed; closed curves wrap and add their shift,
// open curves clamp at their ends): YarnCurve::param_at_length_coord, by bisection of the
// Catmull–Rom length coordinate on the segment found.
fn place_at(seg0: u32, dz0: f32) -> Place {
    let s0 = segments[seg0];
    let c = curves[s0.ids.x];
    let n = c.keys.w;
    let first = seg0 - s0.ids.y;
    let closed = c.keys.x > 0u;
    var i = s0.ids.y;
    var dz = dz0;
    var wraps = 0;
    var clamped = false;
    for (var it = 0u; it < 4096u; it++) {
        let len = segments[first + i].p[2].w;
        if dz >= len && len >= 0.0 {
            if i + 1u < n {
                i += 1u;
            } else if closed {
                i = 0u;
                wraps += 1;
            } else {
                clamped = dz > len;
                break;
            }
            dz -= len;
            continue;
        }
        if dz < 0.0 {
            if i > 0u {
                i -= 1u;
            } else if closed {
                i = n - 1u;
                wraps -= 1;
            } else {
                clamped = true;
                break;
            }
            dz += segments[first + i].p[2].w;
            continue;
        }
        break;
    }
    let s = segments[first + i];
    let len = s.p[2].w;
    var out: Place;
    out.seg = first + i;
    out.clamped = clamped;
    out.shift = vec3<f32>(0.0);
    if wraps != 0 {
        out.shift = f32(wraps) * (segments[first + n - 1u].p[2].xyz - segments[first].p[1].xyz);
    }
    if dz <= 0.0 || len <= 0.0 {
        out.t = 0.0;
        return out;
    }
    if dz >= len {
        out.t = 1.0;
        return out;
    }
    var lo = 0.0;
    var hi = 1.0;
    for (var b = 0u; b < 24u; b++) {
        let mid = 0.5 * (lo + hi);
        let w = cr_basis(mid);
        let z = w.x * s.p[0].w + w.z * s.p[2].w + w.w * s.p[3].w;
        if z > dz {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    out.t = 0.5 * (lo + hi);
    return out;
}

fn fiber_slot(seg: u32, ply: u32, fib: u32, dz: f32, loops: bool) -> FiberSlot {
    let s = segments[seg];
    let c = curves[s.ids.x];
    let pr = yarn_params[c.ids.x];
    let rec = fiber_table[c.ids.y + ply * pr.d.y + fib];
    var out: FiberSlot;
    // Turns as fractions first (phases reduced on the CPU), radians last.
    let fib_turn = s.phase.y + dz / c.pitch.y;
    out.psi = rec.y + TAU * fract(fib_turn);
    out.ply_angle = TAU * fract(f32(ply) / f32(pr.d.x) + s.phase.x + dz / c.pitch.x);
    // σ = s_r·z/α' + (φ_i − π)/2π; integer part from the CPU's slot base.
    let local = s.phase.z + c.pitch.w * dz / c.pitch.y + (rec.z - PI) / TAU;
    let fl = floor(local);
    let tfrac = local - fl;
    // cos(s'·θ_fib + φ_i) = −cos(2πσ) when s' > 0; cos φ_i when s' = 0.
    var cm = cos(rec.z);
    if c.pitch.z > 0.0 {
        cm = -cos(TAU * tfrac);
    }
    let rho_min = pr.a.w;
    let rho_max = pr.b.x;
    var r = rec.x * (rho_min + (rho_max - rho_min) * 0.5 * (cm + 1.0));
    if loops {
        let slot = bitcast<i32>(s.ids.z) + i32(fl);
        let peak = loop_peak(c, pr, ply, fib, slot, rec.x);
        if peak >= 0.0 {
            let sn = sin(PI * tfrac);
            r = r + (peak - rho_max * rec.x) * sn * sn;
        }
    }
    out.radius = r;
    return out;
}

// Δc_ply + Δc in the yarn frame (coefficients of N, B): FiberModel::ellipse_offset.
fn ellipse_offset(pr: Params, ply_angle: f32, r: f32, psi: f32) -> vec2<f32> {
    let sp = sin(ply_angle);
    let cp = cos(ply_angle);
    let sf = sin(psi);
    let cf = cos(psi);
    let d = pr.a.x;
    let a = r * pr.a.y * cf;
    let b = r * pr.a.z * sf;
    return vec2<f32>(d * cp + a * cp - b * sp, d * sp + a * sp + b * cp);
}

// The point of fiber `fib` of ply `ply` on segment `seg` at local parameter t (relative
// to the packed origin): FiberModel::fiber_point.
fn fiber_point(seg: u32, ply: u32, fib: u32, t: f32, loops: bool) -> vec3<f32> {
    let yp = yarn_point(seg, t);
    let c = curves[segments[seg].ids.x];
    let pr = yarn_params[c.ids.x];
    let fs = fiber_slot(seg, ply, fib, yp.dz, loops);
    let ab = ellipse_offset(pr, fs.ply_angle, fs.radius, fs.psi);
    return yp.pos + ab.x * yp.n + ab.y * yp.b;
}

// A fiber point with what the lighting effects need: the yarn centre, the point in the
// cross-section frame that turns with the plies (x along ply 0's direction N', as
// yarn::density and yarn-precompute use it), and that frame's N', B' in the world.
struct FiberSample {
    pos: vec3<f32>,
    centre: vec3<f32>,
    tangent: vec3<f32>,
    q: vec2<f32>,
    n_slice: vec3<f32>,
    b_slice: vec3<f32>,
    // The segment and local parameter of the yarn point (a hair's may be another segment
    // than its instance's).
    seg: u32,
    t: f32,
}

fn fiber_sample(seg: u32, ply: u32, fib: u32, t: f32, loops: bool) -> FiberSample {
    let yp = yarn_point(seg, t);
    let c = curves[segments[seg].ids.x];
    let pr = yarn_params[c.ids.x];
    let fs = fiber_slot(seg, ply, fib, yp.dz, loops);
    let ab = ellipse_offset(pr, fs.ply_angle, fs.radius, fs.psi);
    // Ply 0's angle: φ_j − 2πj/n_ply.
    let phi0 = fs.ply_angle - TAU * f32(ply) / f32(pr.d.x);
    let c0 = cos(phi0);
    let s0 = sin(phi0);
    var out: FiberSample;
    out.pos = yp.pos + ab.x * yp.n + ab.y * yp.b;
    out.centre = yp.pos;
    out.tangent = yp.t;
    out.q = vec2<f32>(ab.x * c0 + ab.y * s0, -ab.x * s0 + ab.y * c0);
    out.n_slice = c0 * yp.n + s0 * yp.b;
    out.b_slice = -s0 * yp.n + c0 * yp.b;
    out.seg = seg;
    out.t = t;
    return out;
}

// A hair's point at its parameter t ∈ [0, 1] (FiberModel::hair_offset, [H25 eq. 12–13]):
// from the ply centre outwards, r(t) = (r_0 + r_e)(1 − (1 − t)^α), angle and z linear in
// t, through the ply ellipse as the regular fibers; `seg` is the segment the hair was
// counted from.
fn hair_sample(seg: u32, ply: u32, hr: Hair, t: f32) -> FiberSample {
    let pl = place_at(seg, hair_dz(hr, t));
    let yp = yarn_point(pl.seg, pl.t);
    let s = segments[pl.seg];
    let c = curves[s.ids.x];
    let pr = yarn_params[c.ids.x];
    let p = hr.p0 - hr.pe * hr.k + hr.pe * (1.0 + hr.k) * t;
    let one_t = 1.0 - t;
    let bend = select(pow(one_t, pr.g.y), 0.0, one_t <= 0.0);
    let r = hr.reach * (1.0 - bend) / pr.b.w;
    let phi0 = TAU * fract(s.phase.x + yp.dz / c.pitch.x);
    let ab = ellipse_offset(pr, phi0 + TAU * f32(ply) / f32(pr.d.x), r, p);
    let c0 = cos(phi0);
    let s0 = sin(phi0);
    var out: FiberSample;
    out.centre = yp.pos + pl.shift;
    out.pos = out.centre + ab.x * yp.n + ab.y * yp.b;
    out.tangent = yp.t;
    out.q = vec2<f32>(ab.x * c0 + ab.y * s0, -ab.x * s0 + ab.y * c0);
    out.n_slice = c0 * yp.n + s0 * yp.b;
    out.b_slice = -s0 * yp.n + c0 * yp.b;
    out.seg = pl.seg;
    out.t = pl.t;
    return out;
}

// Instance records of the fiber passes (fiber_lod): x = segment, y = fiber | ply << 16 |
// n_sub << 24 for a regular fiber; a hair sets bit 31 of x and keeps its slot, relative to
// the segment's slot base + 32, in bits 25–30 (so hairs address 2^25 segments).
const HAIR_BIT: u32 = 0x80000000u;

fn instance_is_hair(rec: vec2<u32>) -> bool {
    return (rec.x & HAIR_BIT) != 0u;
}

fn instance_segment(rec: vec2<u32>) -> u32 {
    return select(rec.x, rec.x & 0x1ffffffu, instance_is_hair(rec));
}

fn instance_hair(rec: vec2<u32>) -> Hair {
    let slot_rel = i32((rec.x >> 25u) & 63u) - 32;
    return hair_of(rec.x & 0x1ffffffu, (rec.y >> 16u) & 0xffu, rec.y & 0xffffu, slot_rel);
}

// The point of a listed regular fiber or hair at strip parameter t.
fn instance_sample(rec: vec2<u32>, t: f32, loops: bool) -> FiberSample {
    let ply = (rec.y >> 16u) & 0xffu;
    if instance_is_hair(rec) {
        return hair_sample(rec.x & 0x1ffffffu, ply, instance_hair(rec), t);
    }
    return fiber_sample(rec.x, ply, rec.y & 0xffffu, t, loops);
}
