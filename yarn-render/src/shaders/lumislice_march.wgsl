// lumislice_march (render): Chen et al.'s lumislice yarn [C03 §5] as ray-marched straight
// pieces (DESIGN §1.3 item 12, §1.4). One instance per piece of a yarn segment (n_sub per
// segment, sorted back to front on the CPU), drawn as the back faces of the piece's
// bounding box; the fragment intersects its ray with the piece's tube (radius = the
// density's reach, end planes ⟂ the curve tangent there, shared with the neighbour so the
// pieces tile the yarn) and marches [C03 eq. 9] front to back: per step σ⊥ from the slice
// turned by the twist, the view extinction σ⊥·sin β_o (anisotropic) or σ⊥, the table V of
// yarn_precompute::Lumislice (the VRF of [C03 eq. 8], times the irradiance: [C03 eq. 7])
// for every light (bilinear in the voxel and over the four
// nearest of the 32 × 21 light directions), other yarns' shadow by [C03 eq. 10] from the
// centre-line maps (lumislice_centerline), and the step's own attenuation (DESIGN item 11).
// Output is premultiplied colour and coverage, blended "over" in the sorted order.

struct SliceHeader {
    // Levels, finest resolution, 1 = isotropic extinction, unused.
    dims: vec4<u32>,
    // Half width of the grid (m), reach (m), unused ×2.
    size: vec4<f32>,
    // First σ⊥ float of levels 0..7.
    sig_off: array<vec4<u32>, 2>,
    // First V record (vec4) of levels 0..7.
    vrf_off: array<vec4<u32>, 2>,
}

struct MarchParams {
    // n_sub, max steps, flags (bit 0 eq. 10 shadows, bit 1 the physical variant), maps.
    n: vec4<u32>,
    // Step (cells of the level), level bias, shadow-map size (texels), LUT entries.
    f: vec4<f32>,
    // Light-space view-projection per map.
    view_proj: array<mat4x4<f32>, 4>,
    // Per map: the light it belongs to.
    light: vec4<u32>,
    // Per map: light-clip depth per metre.
    dpm: vec4<f32>,
    // Slices per piece in the paper's slice mode (0: the ray march), unused ×3.
    slices: vec4<u32>,
}

@group(1) @binding(0) var<uniform> view: View;
@group(1) @binding(1) var<uniform> mp: MarchParams;
@group(1) @binding(2) var<storage, read> headers: array<SliceHeader>;
@group(1) @binding(3) var<storage, read> sigma_grid: array<f32>;
@group(1) @binding(4) var<storage, read> vrf: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read> order: array<u32>;
@group(1) @binding(6) var<storage, read> lut: array<f32>;
@group(1) @binding(7) var centre_maps: texture_2d_array<f32>;

const LONGITUDES: u32 = 32u;
const ALTITUDES: u32 = 21u;

struct PieceOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    // Piece start (xyz) and twist angle there (w).
    @location(1) @interpolate(flat) pa: vec4<f32>,
    // Piece end and twist angle there.
    @location(2) @interpolate(flat) pb: vec4<f32>,
    // Curve tangent at the start (end plane), reach (w).
    @location(3) @interpolate(flat) ta: vec4<f32>,
    // Curve tangent at the end.
    @location(4) @interpolate(flat) tb: vec4<f32>,
    // Slice axis e1 (the frame normal ⟂ the piece axis).
    @location(5) @interpolate(flat) e1: vec4<f32>,
    // Piece, params id, level, unused.
    @location(6) @interpolate(flat) ids: vec4<u32>,
}

// The cube's 36 corners (x along the axis, y along e1, z along e2), faces counter-clockwise
// seen from outside.
const CUBE: array<u32, 36> = array<u32, 36>(
    0u, 4u, 6u, 0u, 6u, 2u,
    1u, 3u, 7u, 1u, 7u, 5u,
    0u, 1u, 5u, 0u, 5u, 4u,
    2u, 6u, 7u, 2u, 7u, 3u,
    0u, 2u, 3u, 0u, 3u, 1u,
    4u, 5u, 7u, 4u, 7u, 6u,
);

// The slice frame's twist at a point of segment `seg`: ply turns plus the frame's turn.
fn twist_angle(seg: u32, dz: f32) -> f32 {
    let s = segments[seg];
    let c = curves[s.ids.x];
    return TAU * (s.phase.x + dz / c.pitch.x);
}

@vertex
fn vs_piece(@builtin(vertex_index) vi: u32, @builtin(instance_index) inst: u32) -> PieceOut {
    let n_sub = max(mp.n.x, 1u);
    let piece = order[inst];
    let seg = piece / n_sub;
    let sub = piece % n_sub;
    let ya = yarn_point(seg, f32(sub) / f32(n_sub));
    let yb = yarn_point(seg, f32(sub + 1u) / f32(n_sub));
    let s = segments[seg];
    let c = curves[s.ids.x];
    let pid = c.ids.x;
    let h = headers[pid];
    let reach = h.size.y;
    let ab = yb.pos - ya.pos;
    let len = length(ab);
    let a = normalize_or(ab, ya.t);
    let e1 = normalize_or(ya.n - a * dot(ya.n, a), any_perpendicular(a));
    let e2 = cross(a, e1);
    // The frame's own turn over the piece: the end normal's angle about the axis.
    let nb = yb.n - a * dot(yb.n, a);
    let delta = atan2(dot(cross(e1, nb), a), dot(e1, nb));
    let corner = CUBE[vi % 36u];
    let bx = f32(corner & 1u);
    let by = f32((corner >> 1u) & 1u) * 2.0 - 1.0;
    let bz = f32((corner >> 2u) & 1u) * 2.0 - 1.0;
    let p = ya.pos + a * (mix(-reach, len + reach, bx)) + e1 * (by * reach) + e2 * (bz * reach);
    // Level: the smallest 2ⁿ ≥ the slice's projected size [C03 §5.2.2], plus the bias.
    let m = max(pixels_of(view, 2.0 * h.size.x, 0.5 * (ya.pos + yb.pos)), 1.0);
    let want = ceil(log2(m));
    let finest = log2(f32(h.dims.y));
    let level = u32(clamp(finest - want + mp.f.y, 0.0, f32(h.dims.x - 1u)));
    var out: PieceOut;
    out.clip = view.view_proj * vec4<f32>(p, 1.0);
    out.world = p;
    out.pa = vec4<f32>(ya.pos, twist_angle(seg, ya.dz));
    out.pb = vec4<f32>(yb.pos, twist_angle(seg, yb.dz) + delta);
    out.ta = vec4<f32>(ya.t, reach);
    out.tb = vec4<f32>(yb.t, 0.0);
    out.e1 = vec4<f32>(e1, len);
    out.ids = vec4<u32>(piece, pid, level, 0u);
    return out;
}

// σ⊥ of level `lv` at slice coordinates (bilinear between cell centres, 0 outside).
fn sigma_at(h: SliceHeader, lv: u32, x: f32, y: f32) -> f32 {
    let res = h.dims.y >> lv;
    let cell = 2.0 * h.size.x / f32(res);
    let g = vec2<f32>((x + h.size.x) / cell - 0.5, (y + h.size.x) / cell - 0.5);
    let g0 = floor(g);
    let f = g - g0;
    let base = h.sig_off[lv / 4u][lv % 4u];
    var acc = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let dx = f32(k & 1u);
        let dy = f32(k >> 1u);
        let i = g0.x + dx;
        let j = g0.y + dy;
        if i < 0.0 || j < 0.0 || i >= f32(res) || j >= f32(res) {
            continue;
        }
        let w = select(1.0 - f.x, f.x, dx > 0.5) * select(1.0 - f.y, f.y, dy > 0.5);
        acc += w * sigma_grid[base + u32(j) * res + u32(i)];
    }
    return acc;
}

// V at slice point (x, y) for the slice-frame light direction l (bilinear in the voxel and
// over the four nearest table directions: yarn_precompute::Lumislice::vrf_at).
fn vrf_at(h: SliceHeader, lv: u32, x: f32, y: f32, l: vec3<f32>) -> vec3<f32> {
    let res = h.dims.y >> lv;
    let n = res * res;
    let cell = 2.0 * h.size.x / f32(res);
    let g = vec2<f32>((x + h.size.x) / cell - 0.5, (y + h.size.x) / cell - 0.5);
    let g0 = floor(g);
    let f = g - g0;
    let th = atan2(l.y, l.x);
    let ph = asin(clamp(l.z, -1.0, 1.0));
    let dx = (th + select(0.0, TAU, th < 0.0)) / (TAU / f32(LONGITUDES));
    let dy = clamp((ph + 0.5 * PI) / (PI / f32(ALTITUDES - 1u)), 0.0, f32(ALTITUDES - 1u));
    let x0 = floor(dx);
    let y0 = min(floor(dy), f32(ALTITUDES - 2u));
    let fx = dx - x0;
    let fy = dy - y0;
    let i0 = u32(x0) % LONGITUDES;
    let i1 = (i0 + 1u) % LONGITUDES;
    let j0 = u32(y0);
    let dirs = array<u32, 4>(j0 * LONGITUDES + i0, j0 * LONGITUDES + i1,
        (j0 + 1u) * LONGITUDES + i0, (j0 + 1u) * LONGITUDES + i1);
    let dw = array<f32, 4>((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
    let base = h.vrf_off[lv / 4u][lv % 4u];
    var acc = vec3<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let ox = f32(k & 1u);
        let oy = f32(k >> 1u);
        let i = g0.x + ox;
        let j = g0.y + oy;
        if i < 0.0 || j < 0.0 || i >= f32(res) || j >= f32(res) {
            continue;
        }
        let w = select(1.0 - f.x, f.x, ox > 0.5) * select(1.0 - f.y, f.y, oy > 0.5);
        let v = u32(j) * res + u32(i);
        for (var d = 0u; d < 4u; d++) {
            acc += (w * dw[d]) * vrf[base + dirs[d] * n + v].rgb;
        }
    }
    return acc;
}

// [C03 eq. 10] for light i at origin-relative point p of piece `piece`: the nearest other
// yarn's centre line between p and the light, by its distance (1 where none).
fn yarn_shadow(i: u32, p: vec3<f32>, piece: u32, reach: f32) -> f32 {
    if (mp.n.z & 1u) == 0u {
        return 1.0;
    }
    for (var m = 0u; m < mp.n.w; m++) {
        if mp.light[m] != i {
            continue;
        }
        let c = mp.view_proj[m] * vec4<f32>(p, 1.0);
        let uv = vec2<f32>(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5);
        let size = mp.f.z;
        if any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0)) {
            return 1.0;
        }
        let t = textureLoad(centre_maps, vec2<i32>(uv * size), i32(m), 0);
        if t.w <= 0.0 {
            return 1.0;
        }
        let other = u32(t.y + 0.5);
        let own = piece;
        let near = (other + 1u == own) || (own + 1u == other) || other == own;
        if near || t.z >= c.z - reach * mp.dpm[m] {
            return 1.0;
        }
        let entries = u32(mp.f.w);
        let x = clamp(t.x / reach, 0.0, 1.0) * f32(entries - 1u);
        let k = min(u32(floor(x)), entries - 2u);
        let first = select(0u, entries, (mp.n.z & 2u) != 0u);
        return mix(lut[first + k], lut[first + k + 1u], x - f32(k));
    }
    return 1.0;
}

// The slice frame at a point: e1, e2 at the piece start, the axis, and (cos, sin) of the
// twist angle that turns them into the slice's (x, y).
struct SliceFrame {
    e1: vec3<f32>,
    e2: vec3<f32>,
    axis: vec3<f32>,
    twist: vec2<f32>,
}

// Σ over the lights of irradiance × [C03 eq. 10]'s shadow × V at slice point `q` of the
// world point `p` (the light turned into the slice frame first).
fn scattered(h: SliceHeader, lv: u32, q: vec2<f32>, p: vec3<f32>, f: SliceFrame, piece: u32,
    reach: f32) -> vec3<f32> {
    var l = vec3<f32>(0.0);
    for (var i = 0u; i < view.counts.x; i++) {
        let light = view.lights[i];
        var wi = light.pos_dir.xyz;
        var e = light.value.rgb;
        if light.pos_dir.w != 0.0 {
            let dl = light.pos_dir.xyz - p;
            let d2 = max(dot(dl, dl), 1e-20);
            wi = dl / sqrt(d2);
            e = e / d2;
        }
        let wa = dot(wi, f.e1);
        let wb = dot(wi, f.e2);
        let c = f.twist.x;
        let s = f.twist.y;
        let ls = vec3<f32>(wa * c + wb * s, -wa * s + wb * c, dot(wi, f.axis));
        l += yarn_shadow(i, p, piece, reach) * e * vrf_at(h, lv, q.x, q.y, ls);
    }
    return l;
}

struct MarchOut {
    @location(0) color: vec4<f32>,
}

// Whether every component is finite (exponent bits, not `v != v`: a fast-math compiler may
// fold that away).
fn finite4(v: vec4<f32>) -> bool {
    return all(((bitcast<vec4<u32>>(v) >> vec4<u32>(23u)) & vec4<u32>(0xffu)) != vec4<u32>(0xffu));
}

// A box face or slice quad exactly edge-on to an orthographic view (a flat patch's pieces
// seen from straight above: their frame's e1 is the surface normal, which is the view
// direction) is a zero-area triangle that lavapipe still rasterizes, with non-finite
// interpolants; the proper faces cover the same pixels, so its fragments are dropped.
fn degenerate(world: vec3<f32>) -> bool {
    return !finite4(vec4<f32>(world, 0.0));
}

@fragment
fn fs_piece(in: PieceOut) -> MarchOut {
    if degenerate(in.world) {
        discard;
    }
    let h = headers[in.ids.y];
    let lv = in.ids.z;
    let reach = in.ta.w;
    let a_pos = in.pa.xyz;
    let b_pos = in.pb.xyz;
    let len = in.e1.w;
    let axis = normalize_or(b_pos - a_pos, in.ta.xyz);
    let e1 = in.e1.xyz;
    let e2 = cross(axis, e1);
    var o: vec3<f32>;
    var d: vec3<f32>;
    if view.eye.w == 0.0 {
        d = view.forward.xyz;
        o = in.world - d * (4.0 * (len + 2.0 * reach) + 1.0);
    } else {
        o = view.eye.xyz;
        d = normalize(in.world - o);
    }
    // The infinite cylinder about the piece axis.
    let oc = o - a_pos;
    let dp = d - axis * dot(d, axis);
    let op = oc - axis * dot(oc, axis);
    let qa = dot(dp, dp);
    let qb = 2.0 * dot(dp, op);
    let qc = dot(op, op) - reach * reach;
    var t0 = -1e30;
    var t1 = 1e30;
    if qa > 1e-12 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc <= 0.0 {
            discard;
        }
        let sq = sqrt(disc);
        t0 = (-qb - sq) / (2.0 * qa);
        t1 = (-qb + sq) / (2.0 * qa);
    } else if qc > 0.0 {
        discard;
    }
    // The end planes (⟂ the curve's tangents; shared with the neighbouring pieces).
    let ta = in.ta.xyz;
    let dta = dot(d, ta);
    let sa = dot(a_pos - o, ta);
    if abs(dta) > 1e-9 {
        let t = sa / dta;
        if dta > 0.0 { t0 = max(t0, t); } else { t1 = min(t1, t); }
    } else if sa > 0.0 {
        discard;
    }
    let tb = in.tb.xyz;
    let dtb = dot(d, tb);
    let sb = dot(b_pos - o, tb);
    if abs(dtb) > 1e-9 {
        let t = sb / dtb;
        if dtb > 0.0 { t1 = min(t1, t); } else { t0 = max(t0, t); }
    } else if sb < 0.0 {
        discard;
    }
    if view.eye.w != 0.0 {
        t0 = max(t0, 0.0);
    }
    if t1 <= t0 {
        discard;
    }
    let res = h.dims.y >> lv;
    let cell = 2.0 * h.size.x / f32(res);
    let n = u32(clamp(ceil((t1 - t0) / (mp.f.x * cell)), 1.0, f32(max(mp.n.y, 1u))));
    let step = (t1 - t0) / f32(n);
    // View extinction factor: sin β_o (fibers along the axis), 1 when isotropic.
    let view_factor = select(length(cross(d, axis)), 1.0, h.dims.z == 1u);
    var tr = 1.0;
    var l = vec3<f32>(0.0);
    for (var k = 0u; k < n; k++) {
        let p = o + d * (t0 + (f32(k) + 0.5) * step);
        let q = p - a_pos;
        let f = clamp(dot(q, axis) / max(len, 1e-12), 0.0, 1.0);
        let g = mix(in.pa.w, in.pb.w, f);
        let cg = cos(g);
        let sg = sin(g);
        let la = dot(q, e1);
        let lb = dot(q, e2);
        let x = la * cg + lb * sg;
        let y = -la * sg + lb * cg;
        let sig = sigma_at(h, lv, x, y) * view_factor;
        if sig <= 0.0 {
            continue;
        }
        let alpha = 1.0 - exp(-sig * step);
        let frame = SliceFrame(e1, e2, axis, vec2<f32>(cg, sg));
        l += (tr * alpha) * scattered(h, lv, vec2<f32>(x, y), p, frame, in.ids.x, reach);
        tr *= 1.0 - alpha;
        if tr < 1e-4 {
            tr = 0.0;
            break;
        }
    }
    // A safety net: no non-finite sample reaches the blended frame (the one seen came from
    // the degenerate faces dropped above).
    let c = vec4<f32>(l, 1.0 - tr);
    if !finite4(c) {
        discard;
    }
    var out: MarchOut;
    out.color = c;
    return out;
}

// ---- [C03 §5.2]'s instanced slices (the paper's mode, for comparison) ----
// One instance per slice: `slices` quads per piece, ⟂ the piece axis at (k + ½)Δs, spanned by
// the slice frame turned by the twist there, ±half width; within a piece drawn back to
// front. Each slice stands for a slab Δs thick: opacity 1 − e^{−σ⊥ sin β_o Δs/|cos β_o|}
// (the path length through the slab, DESIGN §1.3 item 12's correction; it diverges, and
// the quads vanish, as the slices turn edge-on).

struct SliceOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    // Slice coordinates (x, y), twist angle, unused.
    @location(1) xy: vec4<f32>,
    // Piece axis (xyz), Δs (w).
    @location(2) @interpolate(flat) axis: vec4<f32>,
    // Slice frame e1 at the piece start (xyz), unused.
    @location(3) @interpolate(flat) e1: vec4<f32>,
    // Piece, params id, level, unused.
    @location(4) @interpolate(flat) ids: vec4<u32>,
}

@vertex
fn vs_slice(@builtin(vertex_index) vi: u32, @builtin(instance_index) inst: u32) -> SliceOut {
    let n_sub = max(mp.n.x, 1u);
    let per = max(mp.slices.x, 1u);
    let piece = order[inst / per];
    var k = inst % per;
    let seg = piece / n_sub;
    let sub = piece % n_sub;
    let ya = yarn_point(seg, f32(sub) / f32(n_sub));
    let yb = yarn_point(seg, f32(sub + 1u) / f32(n_sub));
    let s = segments[seg];
    let c = curves[s.ids.x];
    let pid = c.ids.x;
    let h = headers[pid];
    let ab = yb.pos - ya.pos;
    let len = length(ab);
    let axis = normalize_or(ab, ya.t);
    let mid = 0.5 * (ya.pos + yb.pos);
    // Back to front along the piece.
    var toward = view.forward.xyz;
    if view.eye.w != 0.0 {
        toward = normalize_or(mid - view.eye.xyz, view.forward.xyz);
    }
    if dot(toward, axis) > 0.0 {
        k = per - 1u - k;
    }
    let e1 = normalize_or(ya.n - axis * dot(ya.n, axis), any_perpendicular(axis));
    let e2 = cross(axis, e1);
    let nb = yb.n - axis * dot(yb.n, axis);
    let delta = atan2(dot(cross(e1, nb), axis), dot(e1, nb));
    let f = (f32(k) + 0.5) / f32(per);
    let g = mix(twist_angle(seg, ya.dz), twist_angle(seg, yb.dz) + delta, f);
    // Slice axes in the world: (x, y) = rot(−g)(a, b) ⇔ a = x cos g − y sin g, b = x sin g + y cos g.
    let cg = cos(g);
    let sg = sin(g);
    let ex = e1 * cg + e2 * sg;
    let ey = -e1 * sg + e2 * cg;
    let corner = vec2<f32>(select(-1.0, 1.0, (vi & 1u) == 1u), select(-1.0, 1.0, (vi & 2u) == 2u));
    let xy = corner * h.size.x;
    let p = ya.pos + axis * (f * len) + ex * xy.x + ey * xy.y;
    let m = max(pixels_of(view, 2.0 * h.size.x, mid), 1.0);
    let level = u32(clamp(log2(f32(h.dims.y)) - ceil(log2(m)) + mp.f.y, 0.0, f32(h.dims.x - 1u)));
    var out: SliceOut;
    out.clip = view.view_proj * vec4<f32>(p, 1.0);
    out.world = p;
    out.xy = vec4<f32>(xy, g, 0.0);
    out.axis = vec4<f32>(axis, len / f32(per));
    out.e1 = vec4<f32>(e1, 0.0);
    out.ids = vec4<u32>(piece, pid, level, 0u);
    return out;
}

@fragment
fn fs_slice(in: SliceOut) -> MarchOut {
    if degenerate(in.world) {
        discard;
    }
    let h = headers[in.ids.y];
    let lv = in.ids.z;
    let axis = in.axis.xyz;
    var d = view.forward.xyz;
    if view.eye.w != 0.0 {
        d = normalize(in.world - view.eye.xyz);
    }
    let x = in.xy.x;
    let y = in.xy.y;
    let sig = sigma_at(h, lv, x, y);
    if sig <= 0.0 {
        discard;
    }
    let cos_o = max(abs(dot(d, axis)), 1e-3);
    let view_factor = select(length(cross(d, axis)), 1.0, h.dims.z == 1u);
    let alpha = 1.0 - exp(-sig * view_factor * in.axis.w / cos_o);
    let e1 = in.e1.xyz;
    let e2 = cross(axis, e1);
    let cg = cos(in.xy.z);
    let sg = sin(in.xy.z);
    let frame = SliceFrame(e1, e2, axis, vec2<f32>(cg, sg));
    let l = alpha * scattered(h, lv, vec2<f32>(x, y), in.world, frame, in.ids.x, h.size.y);
    var out: MarchOut;
    out.color = vec4<f32>(l, alpha);
    return out;
}
