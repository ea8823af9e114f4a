// Interpolation weights between measured directions, exactly as btf_core::interp
// ([S03 eq. 3] for lights, [S03 eq. 5] for views): bracket θ between two rings,
// on each ring bracket φ between two neighbours (with wrap-around), the pole ring has a
// single sample; lights beyond the last ring fade by cos θ / cos θ_last and vanish at or
// below the horizon; views clamp. "Nearest" takes the nearest ring in θ, then the nearest
// sample in φ. The including shader declares `samplings: Samplings`.

const MAX_RINGS: u32 = 16u;
const VIEW: u32 = 0u;
const LIGHT: u32 = 1u;

struct Samplings {
    // (theta_deg, count, phi_offset_deg, first index); view rings 0..16, light rings 16..32
    rings: array<vec4<f32>, 32>,
    // ring counts: view, light
    n_rings: vec4<u32>,
    // groups G, light directions, view slots, unused
    info: vec4<u32>,
    // uv scale, unused
    params: vec4<f32>,
}

// Up to four (index, weight) pairs, weights > 0.
struct W4 {
    idx: vec4<u32>,
    w: vec4<f32>,
    n: u32,
}

struct Pair {
    i0: u32,
    i1: u32,
    s: f32,
}

fn wrap_phi(p: f32) -> f32 {
    var q = p - 360.0 * floor(p / 360.0);
    if (q >= 360.0) {
        q = 0.0;
    }
    return q;
}

// (theta_deg, phi_deg) of a tangent-space vector (need not be unit length).
fn dir_angles(d: vec3<f32>) -> vec2<f32> {
    let rho = length(d.xy);
    let theta = degrees(atan2(rho, d.z));
    var phi = 0.0;
    if (rho > length(d) * 1e-7) {
        phi = wrap_phi(degrees(atan2(d.y, d.x)));
    }
    return vec2<f32>(theta, phi);
}

fn ring_of(which: u32, r: u32) -> vec4<f32> {
    return samplings.rings[which * MAX_RINGS + r];
}

// (inner ring, outer ring, weight t of the outer ring)
fn ring_bracket(which: u32, theta: f32) -> vec3<f32> {
    let last = samplings.n_rings[which] - 1u;
    if (theta <= ring_of(which, 0u).x) {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    if (theta >= ring_of(which, last).x) {
        return vec3<f32>(f32(last), f32(last), 0.0);
    }
    var r = 0u;
    for (var k = 1u; k < last; k = k + 1u) {
        if (ring_of(which, k).x <= theta) {
            r = k;
        }
    }
    let t0 = ring_of(which, r).x;
    let t1 = ring_of(which, r + 1u).x;
    return vec3<f32>(f32(r), f32(r + 1u), clamp((theta - t0) / (t1 - t0), 0.0, 1.0));
}

fn ring_neighbours(which: u32, r: u32, phi: f32) -> Pair {
    let ring = ring_of(which, r);
    let count = u32(ring.y);
    let start = u32(ring.w);
    if (count == 1u) {
        return Pair(start, start, 0.0);
    }
    let u = wrap_phi(phi - ring.z) / (360.0 / ring.y);
    let k = floor(u);
    let frac = clamp(u - k, 0.0, 1.0);
    // u lies in [0, count] (count only by rounding), so `% count` is one conditional
    // subtraction (integer division is scalarised and slow on lavapipe)
    let ki = wrap_index(u32(k), count);
    return Pair(start + ki, start + wrap_index(ki + 1u, count), frac);
}

// i % count for i ≤ count.
fn wrap_index(i: u32, count: u32) -> u32 {
    return select(i, i - count, i >= count);
}

fn nearest_on_ring(which: u32, r: u32, phi: f32) -> u32 {
    let ring = ring_of(which, r);
    let count = u32(ring.y);
    let u = wrap_phi(phi - ring.z) / (360.0 / ring.y);
    return u32(ring.w) + wrap_index(u32(floor(u + 0.5)), count);
}

// Appends (i, w) if w > 0. The directions interp_weights gives a positive weight are always
// distinct (two rings share no index, and a one-sample ring gives its second neighbour weight
// 0), so nothing needs merging; btf_core::interp merges anyway, to the same weights.
fn w4_push(p: ptr<function, W4>, i: u32, w: f32) {
    if (w > 0.0) {
        let k = (*p).n;
        (*p).idx[k] = i;
        (*p).w[k] = w;
        (*p).n = k + 1u;
    }
}

// The weights in fixed places, not compacted: four-way, the two neighbours on each of the
// two bracketing rings (an entry of weight 0 keeps a valid index: at a one-sample ring, or
// when both rings are the same one); nearest, the one direction in idx.x. n is 4 or 1.
fn fixed_weights(which: u32, a: vec2<f32>, four: bool) -> W4 {
    let b = ring_bracket(which, a.x);
    let r0 = u32(b.x);
    let r1 = u32(b.y);
    let t = b.z;
    if (four) {
        let p = ring_neighbours(which, r0, a.y);
        let q = ring_neighbours(which, r1, a.y);
        let w = vec4<f32>((1.0 - t) * (1.0 - p.s), (1.0 - t) * p.s, t * (1.0 - q.s), t * q.s);
        return W4(vec4<u32>(p.i0, p.i1, q.i0, q.i1), w, 4u);
    }
    let i = nearest_on_ring(which, select(r0, r1, t > 0.5), a.y);
    return W4(vec4<u32>(i, 0u, 0u, 0u), vec4<f32>(1.0, 0.0, 0.0, 0.0), 1u);
}

// fixed_weights with the zero-weight entries dropped (for views, each entry costs a slot's
// reads).
fn interp_weights(which: u32, a: vec2<f32>, four: bool) -> W4 {
    let f = fixed_weights(which, a, four);
    var w = W4(vec4<u32>(0u), vec4<f32>(0.0), 0u);
    for (var k = 0u; k < f.n; k = k + 1u) {
        w4_push(&w, f.idx[k], f.w[k]);
    }
    return w;
}

// View-slot weights ω ([S03 eq. 5]); `a` = (theta_deg, phi_deg) in tangent space.
fn view_weights(a: vec2<f32>, four: bool) -> W4 {
    return interp_weights(VIEW, a, four);
}

// Light weights τ ([S03 eq. 3]) with the horizon fade.
fn light_weights(a: vec2<f32>, four: bool) -> W4 {
    if (!(a.x < 90.0)) {
        return W4(vec4<u32>(0u), vec4<f32>(0.0), 0u);
    }
    // not compacted: the light sums run over all four entries anyway
    var w = fixed_weights(LIGHT, a, four);
    let last = ring_of(LIGHT, samplings.n_rings[LIGHT] - 1u).x;
    if (a.x > last) {
        let f = cos(radians(a.x)) / cos(radians(last));
        w.w = w.w * f;
        if (f <= 0.0) {
            w.n = 0u;
        }
    }
    return w;
}
