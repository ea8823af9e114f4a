// fiber_draw (render, vertex pulling): one instance per listed (segment, ply, fiber) or
// hair flyaway (instance_sample of the generator: a hair's points walk along the curve by
// their length coordinate) — or, for the plain-tube baseline (fiber index 0xffff), per
// segment with the yarn's width — a
// triangle strip of 2·(n_sub_max + 1) vertices; vertex k of an instance with fewer
// subdivisions collapses onto its last point. Each vertex evaluates the generator
// (instance_sample, the function fiber_expand writes) and is pushed ± half the fiber width
// along T × (eye − p): the camera-facing strip [W19 §5] made by the geometry shader there.
// A strip narrower than `view.strip.x` pixels is widened to it and keeps only its coverage
// fraction of the MSAA samples: a sample mask of round(coverage·samples + u) samples,
// chosen with u and a rotation hashed from (fiber, pixel). Alpha-to-coverage would
// pick the same samples for every fiber of equal alpha (overlapping fibers would cover
// the union of one), and would store the alpha too, counting coverage twice; hashed masks
// make overlapping sub-pixel fibers cover independent samples, as real ones do. The fragment shader evaluates the fiber BCSDF of yarn::bcsdf
// (any lobe sum: simple [W19 eq. 5] + diffuse, Khungurn R + TT [W19 eq. 6] + diffuse,
// R + TT + D [H25 eq. 7]) for each light, as the CPU reference does at a fiber hit: the
// fiber scatters as a line, so the radiance does not depend on where across its width it
// is seen.

@group(1) @binding(0) var<uniform> view: View;
@group(1) @binding(1) var<storage, read> instances: array<vec2<u32>>;
@group(1) @binding(2) var<storage, read> lobes: array<Lobe>;
@group(1) @binding(3) var<storage, read> q_nodes: array<f32>;

struct Effects {
    shadow: vec4<u32>,
    shadow_f: vec4<f32>,
    ao: vec4<u32>,
    ao_f: vec4<f32>,
    cubic: vec4<f32>,
    core: vec4<u32>,
    core_f: vec4<f32>,
    sigma: vec4<u32>,
    sigma_f: vec4<f32>,
}

@group(1) @binding(4) var<storage, read> effects: array<Effects>;
@group(1) @binding(5) var<storage, read> effect_data: array<f32>;
@group(1) @binding(6) var shadow_maps: texture_depth_2d_array;
@group(1) @binding(7) var shadow_cmp: sampler_comparison;
@group(1) @binding(8) var<uniform> shadow_views: ShadowViews;

// The environment (renderer.rs set_environment): count, λ, unused ×2; per SRBF its
// direction (xyz, 0) and weight (rgb, 0); then I_M on 16³ nodes (θ_j, θ_o, Δφ), RGB.
@group(1) @binding(9) var<storage, read> env: array<f32>;
// The fiber shadow maps' fiber keys (fs_shadow), layer by layer as shadow_maps; 0: none.
@group(1) @binding(10) var shadow_ids: texture_2d_array<u32>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    // Origin-relative position on the fiber axis (core strips: on the ply centre line).
    @location(0) axis: vec3<f32>,
    @location(1) tangent: vec3<f32>,
    @location(2) color: vec3<f32>,
    // Coverage of a widened strip (1 when the fiber is at least the minimum width); the
    // core strip's v across and its stretch, or a fiber's side (−1…1) and the clip depth
    // one fiber radius behind it (fs_shadow); unused.
    @location(3) misc: vec4<f32>,
    // The fiber's identity hash (sample masks), params id, kind (0 fiber, 1 core, 2 tube),
    // and the key of the whole fiber (fiber_key) the fiber shadow maps store.
    @location(4) @interpolate(flat) ids: vec4<u32>,
    // The yarn centre and the cross-section point in the frame that turns with the plies.
    @location(5) centre: vec3<f32>,
    @location(6) q: vec2<f32>,
    @location(7) n_slice: vec3<f32>,
    @location(8) b_slice: vec3<f32>,
    // Core strips: (cos, sin) of 2πu and of the texture azimuth ψ'.
    @location(9) core_angles: vec4<f32>,
    // Core strips: the ply frame N̂, B̂.
    @location(10) n_ply: vec3<f32>,
    @location(11) b_ply: vec3<f32>,
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @builtin(sample_mask) mask: u32,
}

// A core strip vertex [W19 §3.2] (yarn_precompute::CoreTexture::view): the strip follows
// the ply centre, faces the eye, is H·|A w| wide (widened towards the whole ply as λ falls,
// DESIGN §2.3 item 7) and reads u = frac((θ_fib − ψ')/2π) with the ellipse-corrected eye
// azimuth ψ'.
fn core_vertex(seg: u32, ply: u32, t: f32, side: f32, rec: vec2<u32>) -> VertexOut {
    let s = segments[seg];
    let c = curves[s.ids.x];
    let pr = yarn_params[c.ids.x];
    let ef = effects[c.ids.x];
    let n_sub = max(rec.y >> 24u, 1u);
    let h = 0.25 / f32(n_sub);
    let t2 = select(t + h, t - h, t + h > 1.0);
    let ya = yarn_point(seg, t);
    let yb = yarn_point(seg, t2);
    let phi = TAU * fract(f32(ply) / f32(pr.d.x) + s.phase.x + ya.dz / c.pitch.x);
    let phib = TAU * fract(f32(ply) / f32(pr.d.x) + s.phase.x + yb.dz / c.pitch.x);
    let d = pr.a.x;
    let radial = cos(phi) * ya.n + sin(phi) * ya.b;
    let p = ya.pos + d * radial;
    let pb = yb.pos + d * (cos(phib) * yb.n + sin(phib) * yb.b);
    var tp = normalize_or(pb - p, ya.t);
    if t2 < t {
        tp = -tp;
    }
    let n_ply = normalize_or(radial - tp * dot(radial, tp), ya.n);
    let b_ply = cross(tp, n_ply);
    let e = view_dir(p);
    var eye = vec2<f32>(dot(e, n_ply), dot(e, b_ply));
    let el = length(eye);
    eye = select(vec2<f32>(1.0, 0.0), eye / el, el > 1e-6);
    let en = ef.core_f.y;
    let eb = ef.core_f.z;
    let g = sqrt(en * eb);
    let psi_tex = atan2(eye.y / eb, eye.x / en);
    let u = s.phase.y + ya.dz / c.pitch.y - psi_tex / TAU;
    let across_e = sqrt((en * eye.y) * (en * eye.y) + (eb * eye.x) * (eb * eye.x));
    let hw = ef.core_f.x * across_e / g;
    // λ at the segment midpoint, as fiber_lod computes it.
    let lam = segment_lambda(view, seg);
    let l2 = lam * lam;
    let hp = pr.b.x * across_e + pr.b.y;
    let half = l2 * hw + (1.0 - l2) * max(hp, hw);
    let across = normalize_or(cross(tp, e), any_perpendicular(tp));
    var out: VertexOut;
    out.clip = view.view_proj * vec4<f32>(p + across * (half * side), 1.0);
    out.axis = p;
    out.tangent = tp;
    out.color = select(s.color[0].rgb, s.color[1].rgb, t >= 0.5);
    // A widened strip stretches the texture across its whole width ([W19 §3.3]: λ² scales
    // the core's thickness); misc.z is the stretch, for the surface point.
    out.misc = vec4<f32>(1.0, 0.5 + 0.5 * side, half / max(hw, 1e-12), 0.0);
    out.ids = vec4<u32>(pcg(seg) ^ (rec.y & 0xffffffu), c.ids.x, 1u, fiber_key(s.ids.x, rec));
    out.centre = ya.pos;
    out.q = vec2<f32>(0.0);
    let phi0 = phi - TAU * f32(ply) / f32(pr.d.x);
    out.n_slice = cos(phi0) * ya.n + sin(phi0) * ya.b;
    out.b_slice = -sin(phi0) * ya.n + cos(phi0) * ya.b;
    out.core_angles = vec4<f32>(cos(TAU * u), sin(TAU * u), cos(psi_tex), sin(psi_tex));
    out.n_ply = n_ply;
    out.b_ply = b_ply;
    return out;
}

// The key of a whole fiber — curve, ply and fiber (or core strip, 0xfffe; or tube, 0xffff)
// — the same on every segment of its curve (a hair is one instance: its own hash); never 0.
fn fiber_key(curve: u32, rec: vec2<u32>) -> u32 {
    return pcg(pcg(curve) ^ (rec.y & 0xffffffu)) | 1u;
}

// The segment parameter of strip vertex `vi` of instance record `rec`: vertex pair k at
// u = k/n_sub, pairs beyond the instance's n_sub collapsed onto its end.
fn strip_t(rec: vec2<u32>, vi: u32) -> f32 {
    let n_sub = max(rec.y >> 24u, 1u);
    return f32(min(vi / 2u, n_sub)) / f32(n_sub);
}

// ---- pull = expand probe (tests, DESIGN §2.5): the vertex stage's fiber point of strip
// vertex vi of instance ii — the same decoding (strip_t) and generator call
// (fiber_sample) as vs_main — drawn as a point into texel ii·(n_sub + 1) + vi/2 of a
// viewport-sized Rgba32Float target. ----

struct ProbeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) p: vec4<f32>,
}

@vertex
fn vs_probe(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> ProbeOut {
    let rec = instances[ii];
    let n_sub = max(rec.y >> 24u, 1u);
    let slot = ii * (n_sub + 1u) + min(vi / 2u, n_sub);
    let w = u32(view.viewport.x);
    let h = u32(view.viewport.y);
    let px = (f32(slot % w) + 0.5) / f32(w);
    let py = (f32(slot / w) + 0.5) / f32(h);
    let loops = (view.lod.z & 2u) != 0u;
    let fs = instance_sample(rec, strip_t(rec, vi), loops);
    var out: ProbeOut;
    out.clip = vec4<f32>(2.0 * px - 1.0, 1.0 - 2.0 * py, 0.5, 1.0);
    out.p = vec4<f32>(fs.pos, 1.0);
    return out;
}

@fragment
fn fs_probe(in: ProbeOut) -> @location(0) vec4<f32> {
    return in.p;
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VertexOut {
    let rec = instances[ii];
    let hair = instance_is_hair(rec);
    let seg = instance_segment(rec);
    let fib = rec.y & 0xffffu;
    let ply = (rec.y >> 16u) & 0xffu;
    let n_sub = max(rec.y >> 24u, 1u);
    let side = select(-1.0, 1.0, (vi & 1u) == 1u);
    let t = strip_t(rec, vi);
    let loops = (view.lod.z & 2u) != 0u;
    let tube = !hair && fib == 0xffffu;
    // Tangent from a neighbour a quarter subdivision away (backwards at the end).
    let h = 0.25 / f32(n_sub);
    let t2 = select(t + h, t - h, t + h > 1.0);
    var p: vec3<f32>;
    var q: vec3<f32>;
    var fsmp: FiberSample;
    if !hair && fib == 0xfffeu {
        return core_vertex(seg, ply, t, side, rec);
    }
    if tube {
        let yp = yarn_point(seg, t);
        p = yp.pos;
        q = yarn_point(seg, t2).pos;
        fsmp.centre = p;
        fsmp.tangent = yp.t;
        fsmp.q = vec2<f32>(0.0);
        fsmp.n_slice = yp.n;
        fsmp.b_slice = yp.b;
        fsmp.seg = seg;
        fsmp.t = t;
    } else if hair {
        // The slot's shape drawn once for both points.
        let hr = instance_hair(rec);
        fsmp = hair_sample(seg, ply, hr, t);
        p = fsmp.pos;
        q = hair_sample(seg, ply, hr, t2).pos;
    } else {
        fsmp = fiber_sample(seg, ply, fib, t, loops);
        p = fsmp.pos;
        q = fiber_point(seg, ply, fib, t2, loops);
    }
    var tan = normalize_or(q - p, fsmp.tangent);
    if t2 < t {
        tan = -tan;
    }
    let s = segments[seg];
    let c = curves[s.ids.x];
    let pr = yarn_params[c.ids.x];
    let e = view_dir(p);
    let across = normalize_or(cross(tan, e), any_perpendicular(tan));
    let width = select(2.0 * pr.b.y, 2.0 * pr.c.z, tube);
    let px = pixels_of(view, width, p);
    let min_px = view.strip.x;
    var w = width;
    var coverage = 1.0;
    if px < min_px && px > 0.0 {
        w = width * min_px / px;
        coverage = px / min_px;
        if hair {
            // fiber_lod kept the hairs of hair_fibers() of n_fib fibers: the kept ones
            // stand for the rest (their coverage divided by the fraction, at most 1).
            let n_fib = pr.d.y;
            let sw = segment_widths(view, seg);
            let lam = lod_lambda(sw.x, sw.y, view.viewport.w);
            let kept = f32(hair_fibers(view, lam, sw.x, n_fib)) / f32(n_fib);
            coverage = min(coverage / max(kept, 1e-6), 1.0);
        }
    }
    var out: VertexOut;
    let q_strip = p + across * (0.5 * w * side);
    out.clip = view.view_proj * vec4<f32>(q_strip, 1.0);
    // In a fiber shadow map's view (flag 4096, fs_shadow): the clip depth a fiber radius
    // further from the eye (the light there); the frame's own passes skip it.
    var dz = 0.0;
    if (view.lod.z & 4096u) != 0u {
        let back = view.view_proj * vec4<f32>(q_strip - e * (0.5 * width), 1.0);
        dz = back.z / back.w - out.clip.z / out.clip.w;
    }
    out.axis = p;
    out.tangent = tan;
    // The colour of the nearest control point (a hair's, where its point lies).
    let sc = segments[fsmp.seg].color;
    out.color = select(sc[0].rgb, sc[1].rgb, fsmp.t >= 0.5);
    out.misc = vec4<f32>(coverage, side, dz, 0.0);
    out.centre = fsmp.centre;
    out.q = fsmp.q;
    out.n_slice = fsmp.n_slice;
    out.b_slice = fsmp.b_slice;
    // The fiber's identity, not its place in the list: culling and LoD reorder the list,
    // and the sample mask must not change with it.
    let key = select(fiber_key(s.ids.x, rec), pcg(rec.x) | 1u, hair);
    out.ids = vec4<u32>(pcg(rec.x) ^ (rec.y & 0xffffffu), c.ids.x, select(0u, 2u, tube), key);
    return out;
}

// ---- effects [W19 §4] (effects.rs) ----

fn fetch(i: u32) -> f32 {
    return effect_data[i];
}

// Bilinear read of a res² grid at `first` spanning [−h, h]², clamp to edge.
fn grid_bilinear(first: u32, res: u32, h: f32, x: f32, y: f32) -> f32 {
    let n = f32(res);
    let gx = clamp((x + h) / (2.0 * h) * n - 0.5, 0.0, n - 1.0);
    let gy = clamp((y + h) / (2.0 * h) * n - 0.5, 0.0, n - 1.0);
    let x0 = u32(floor(gx));
    let y0 = u32(floor(gy));
    let fx = gx - f32(x0);
    let fy = gy - f32(y0);
    let x1 = min(x0 + 1u, res - 1u);
    let y1 = min(y0 + 1u, res - 1u);
    return (1.0 - fx) * (1.0 - fy) * fetch(first + y0 * res + x0)
        + fx * (1.0 - fy) * fetch(first + y0 * res + x1)
        + (1.0 - fx) * fy * fetch(first + y1 * res + x0)
        + fx * fy * fetch(first + y1 * res + x1);
}

// SelfShadowVolume::optical_depth: light travelling at in-plane angle `rel` of the slice
// frame; two slices, each at the point's own light-frame coordinates, blended.
fn self_depth(e: Effects, q: vec2<f32>, rel: f32) -> f32 {
    let period = e.shadow_f.z;
    let g = rel - period * floor(rel / period);
    let slices = e.shadow.z;
    let w = clamp(g / e.shadow_f.y, 0.0, f32(slices - 1u));
    let k0 = min(u32(floor(w)), slices - 2u);
    let f = w - f32(k0);
    let back = g - rel;
    let cb = cos(back);
    let sb = sin(back);
    let xr = q.x * cb - q.y * sb;
    let yr = q.x * sb + q.y * cb;
    let res = e.shadow.y;
    let h = e.shadow_f.x;
    var d = 0.0;
    for (var j = 0u; j < 2u; j++) {
        let k = k0 + j;
        let a = f32(k) * e.shadow_f.y;
        let cg = cos(a);
        let sg = sin(a);
        let v = grid_bilinear(e.shadow.x + k * res * res, res, h, xr * cg + yr * sg,
            -xr * sg + yr * cg);
        d += select(1.0 - f, f, j == 1u) * v;
    }
    return d;
}

// Transmittance towards a light in direction `wi` (towards the light), for a point seen
// along `wo` (towards the eye).
//
// Shadow hiding (ours; [W19] has none, and without it the knit's hot spot is lost — the
// yarn BTF by fibers had 0.50–0.59 of the reference's radiance where light = view). The
// fibers are parallel to the yarn, so occlusion is a 2-D matter in the cross-section: the
// eye's ray and the light's ray leave the point along in-plane directions Δ apart, and
// over their first `2r_f/|sin Δ|` their corridors of width 2r_f overlap (linearly less
// with distance). The point is seen, so no fiber lies in the eye's corridor: the optical
// depth the light would meet there is removed — σ(p)·(7/12)·r_f/rate averaged over where
// the eye ray crosses the fiber, σ(p) the local extinction (the slope of the stored depth
// along the light), at most 3/4 of all of it; `rate` is |sin Δ| plus the parting of rays
// that differ along the yarn, whose fibers are helices. Beyond a few r_f·σ it changes
// nothing.
// σ at slice-frame point q (bilinear, 0 outside the grid): SigmaField::at.
fn sigma_at(e: Effects, q: vec2<f32>) -> f32 {
    let h = e.sigma_f.x;
    if abs(q.x) > h || abs(q.y) > h {
        return 0.0;
    }
    return grid_bilinear(e.sigma.x, e.sigma.y, h, q.x, q.y);
}

// The optical depth from q towards the light through the *twisted* yarn (ours; [W19]'s
// slices assume light ⟂ yarn): the light's in-plane direction `to_l` (unit, slice frame)
// and its rise along the yarn per unit of in-plane travel, `rise`. At in-plane distance s
// the ray is `rise·s` further along the yarn, where the ply pattern (the slice frame) has
// turned by 2π·rise·s/α_ply, so σ is read at R(−2π·rise·s/α_ply)(q + s·to_l). Per unit
// of in-plane length, as the slices: aligned fibers present σ·cos e over the 1/cos e
// longer 3-D path (DESIGN §2.3 item 10).
fn helix_depth(e: Effects, q: vec2<f32>, to_l: vec2<f32>, rise: f32) -> f32 {
    let h = e.sigma_f.x;
    // Leave the grid's circumscribed disk: at most |q| + h√2.
    let reach = length(q) + 1.4143 * h;
    let n = 48u;
    let ds = reach / f32(n);
    let k = TAU * rise / e.sigma_f.y;
    var d = 0.0;
    for (var i = 0u; i < n; i++) {
        let s = (f32(i) + 0.5) * ds;
        let p = q + s * to_l;
        let a = -k * s;
        let c = cos(a);
        let sn = sin(a);
        d += sigma_at(e, vec2<f32>(c * p.x - sn * p.y, sn * p.x + c * p.y));
    }
    return d * ds;
}

fn self_transmittance(e: Effects, in: VertexOut, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if e.shadow_f.w == 0.0 || (view.lod.z & 16u) == 0u {
        return 1.0;
    }
    if (view.lod.z & 512u) != 0u && e.sigma.z != 0u {
        return helix_transmittance(e, in, wi, wo);
    }
    let ns = normalize(in.n_slice);
    let bs = normalize(in.b_slice);
    let tx = -dot(wi, ns);
    let ty = -dot(wi, bs);
    let l = sqrt(tx * tx + ty * ty);
    if l > 1e-4 {
        let angle = atan2(ty, tx);
        let d = self_depth(e, in.q, angle);
        if (view.lod.z & 256u) == 0u {
            return exp(-d);
        }
        // σ at the point: the depth's slope along the light's travel, over a few texels.
        let step = 2.0 * e.shadow_f.x / f32(e.shadow.y);
        let dir = vec2<f32>(tx, ty) / l;
        let before = self_depth(e, in.q - dir * step, angle);
        let sigma = max(d - before, 0.0) / step;
        // In-plane angle between the light's and the eye's travel (both towards the point).
        let ex = -dot(wo, ns);
        let ey = -dot(wo, bs);
        let el = sqrt(ex * ex + ey * ey);
        var removed = 0.0;
        if el > 1e-4 {
            let sin_d = abs(tx * ey - ty * ex) / (l * el);
            let cos_d = (tx * ex + ty * ey) / (l * el);
            if cos_d > 0.0 {
                let pr = yarn_params[in.ids.y];
                let rf = pr.b.y;
                // The fibers are helices, not lines: rays that differ along the yarn part
                // at tan(tilt) per unit length too (tilt of the outer fibers about the
                // yarn axis, 2π·R_yarn/|α_ply|).
                // This yarn's ply pitch (its effect header), not another curve's.
                let tan_tilt = TAU * pr.c.z / max(abs(e.sigma_f.y), 1e-9);
                let t_axis = normalize(cross(ns, bs));
                let along = abs(dot(wi - wo, t_axis));
                let rate = sin_d + tan_tilt * along;
                // The eye ray passes the fiber at an offset h, uniform in [−r_f, r_f], and
                // the light ray leaves from its axis: the corridors overlap over a width
                // 2r_f − |h| − s·rate. Averaged over h: σ·(7/12)·r_f/rate of depth, and at
                // most 3/4 of all of it (rate → 0).
                removed = min(0.75 * d, sigma * (7.0 / 12.0) * rf / max(rate, 1e-6));
            }
        }
        return exp(-(d - removed));
    }
    // Along the yarn: the mean over the stored angles (SelfShadowVolume, limits differ).
    var m = 0.0;
    let n = (e.shadow.z - 1u) * e.shadow.w;
    for (var k = 0u; k < n; k++) {
        m += exp(-self_depth(e, in.q, f32(k) * e.shadow_f.y));
    }
    return m / f32(max(n, 1u));
}

// Self-shadow through the twisted yarn (helix_depth), with the same shadow hiding as the
// slices (self_transmittance), σ(p) read directly.
fn helix_transmittance(e: Effects, in: VertexOut, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let ns = normalize(in.n_slice);
    let bs = normalize(in.b_slice);
    let t_axis = normalize(cross(ns, bs));
    // Towards the light, in the slice frame.
    let lx = dot(wi, ns);
    let ly = dot(wi, bs);
    let lz = dot(wi, t_axis);
    let l = sqrt(lx * lx + ly * ly);
    if l < 1e-4 {
        // Along the yarn: no in-plane travel; the depth of the local column is unbounded
        // in the model — use the local σ over one ply pitch (a ray along the yarn meets
        // what lies along it).
        return exp(-sigma_at(e, in.q) * abs(e.sigma_f.y));
    }
    let d = helix_depth(e, in.q, vec2<f32>(lx, ly) / l, lz / l);
    var removed = 0.0;
    if (view.lod.z & 256u) != 0u {
        let tx = -lx;
        let ty = -ly;
        let ex = -dot(wo, ns);
        let ey = -dot(wo, bs);
        let el = sqrt(ex * ex + ey * ey);
        if el > 1e-4 {
            let sin_d = abs(tx * ey - ty * ex) / (l * el);
            let cos_d = (tx * ex + ty * ey) / (l * el);
            if cos_d > 0.0 {
                let pr = yarn_params[in.ids.y];
                let tan_tilt = TAU * pr.c.z / max(abs(e.sigma_f.y), 1e-9);
                let along = abs(dot(wi - wo, t_axis));
                let rate = sin_d + tan_tilt * along;
                removed = min(0.75 * d,
                    sigma_at(e, in.q) * (7.0 / 12.0) * pr.b.y / max(rate, 1e-6));
            }
        }
    }
    return exp(-(d - removed));
}

fn ambient_occlusion(e: Effects, q: vec2<f32>) -> f32 {
    let mode = (view.lod.z >> 5u) & 3u;
    if e.ao_f.z == 0.0 || mode == 0u {
        return 1.0;
    }
    if mode == 2u {
        return clamp(grid_bilinear(e.ao.x, e.ao.y, e.ao_f.x, q.x, q.y), 0.0, 1.0);
    }
    let d = clamp(length(q) / max(e.ao_f.y, 1e-12), 0.0, 1.0);
    let c = e.cubic;
    return clamp(c.x + d * (c.y + d * (c.z + d * c.w)), 0.0, 1.0);
}

// A(θ_o) = ∫ f cos θ_i dω_i (AmbientTable, linear in θ_o).
fn ambient_integral(e: Effects, theta_o: f32) -> vec3<f32> {
    let n = e.ao.w;
    let x = clamp((theta_o + 0.5 * PI) / PI * f32(n - 1u), 0.0, f32(n - 1u));
    let k = min(u32(floor(x)), n - 2u);
    let f = x - f32(k);
    let a = e.ao.z + 4u * k;
    let v0 = vec3<f32>(fetch(a), fetch(a + 1u), fetch(a + 2u));
    let v1 = vec3<f32>(fetch(a + 4u), fetch(a + 5u), fetch(a + 6u));
    return mix(v0, v1, f);
}

// Visibility of light `li` (or SRBF j as 8 + j) past other yarns, through its tube maps:
// the first map of that light that sees the point (a point light may have six cube faces),
// read at `point` (the yarn centre) moved `offset` (1.05 tube radii, so a yarn never
// shadows itself through its own tube; self-shadows are the volume's) plus the map's bias
// towards the light, 3 × 3 PCF with taps `bias.z` texels apart (1 for a delta light, wider
// for a soft SRBF lobe). Not the strips' PCSS: on llvmpipe a blocker search anywhere in
// this shader made every lobe 3× dearer, taken or not (`benches/lights.rs`).
fn yarn_visibility(li: u32, point: vec3<f32>, wi: vec3<f32>, offset: f32) -> f32 {
    let h = first_map(li, point, wi, offset);
    if h.m < 0 {
        return 1.0;
    }
    let step = shadow_views.texel.x * shadow_views.bias[h.m].z;
    var v = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let o = vec2<f32>(f32(dx), f32(dy)) * step;
            v += textureSampleCompareLevel(shadow_maps, shadow_cmp, h.uv + o, h.m, h.depth);
        }
    }
    return v / 9.0;
}

// Bilinear core texel (CoreTexture::sample): 8 channels, u repeats, v clamps.
fn core_texel(ef: Effects, u: f32, v: f32) -> array<f32, 8> {
    let w = ef.core.z;
    let h = ef.core.w;
    let x = fract(u) * f32(w) - 0.5;
    let y = clamp(v * f32(h) - 0.5, 0.0, f32(h - 1u));
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let i0 = u32((i32(x0) % i32(w) + i32(w)) % i32(w));
    let i1 = (i0 + 1u) % w;
    let j0 = u32(y0);
    let j1 = min(j0 + 1u, h - 1u);
    var out: array<f32, 8>;
    for (var k = 0u; k < 4u; k++) {
        let a = ef.core.x + k;
        let b = ef.core.y + k;
        let w00 = (1.0 - fx) * (1.0 - fy);
        let w10 = fx * (1.0 - fy);
        let w01 = (1.0 - fx) * fy;
        let w11 = fx * fy;
        out[k] = w00 * fetch(a + 4u * (j0 * w + i0)) + w10 * fetch(a + 4u * (j0 * w + i1))
            + w01 * fetch(a + 4u * (j1 * w + i0)) + w11 * fetch(a + 4u * (j1 * w + i1));
        out[k + 4u] = w00 * fetch(b + 4u * (j0 * w + i0)) + w10 * fetch(b + 4u * (j0 * w + i1))
            + w01 * fetch(b + 4u * (j1 * w + i0)) + w11 * fetch(b + 4u * (j1 * w + i1));
    }
    return out;
}

struct CoreHit {
    alpha: f32,
    // The surface point (origin-relative).
    point: vec3<f32>,
    // World fiber direction (the BCSDF's tangent).
    direction: vec3<f32>,
    // The cross-section point in the slice frame (for self-shadows and AO).
    q: vec2<f32>,
}

// CoreTexture::surface on the GPU: the texel's fiber direction and surface point placed on
// the real (elliptical) ply.
fn core_hit(ef: Effects, in: VertexOut) -> CoreHit {
    let u = atan2(in.core_angles.y, in.core_angles.x) / TAU;
    let v = in.misc.y;
    let t = core_texel(ef, u, v);
    let psi = atan2(in.core_angles.w, in.core_angles.z);
    let e1 = vec2<f32>(cos(psi), sin(psi));
    let w1 = vec2<f32>(-sin(psi), cos(psi));
    let en = ef.core_f.y;
    let eb = ef.core_f.z;
    let g = sqrt(en * eb);
    let a = vec2<f32>(en / g, eb / g);
    let d2 = t[5] * w1 + t[6] * e1;
    let dp = normalize_or(vec3<f32>(d2.x * a.x, d2.y * a.y, t[4]), vec3<f32>(0.0, 0.0, 1.0));
    let tp = normalize_or(in.tangent, vec3<f32>(1.0, 0.0, 0.0));
    var hit: CoreHit;
    hit.alpha = clamp(t[0], 0.0, 1.0);
    hit.direction = normalize_or(dp.x * in.n_ply + dp.y * in.b_ply + dp.z * tp, tp);
    let hh = ef.core_f.x;
    let c = (2.0 * clamp(v, 0.0, 1.0) - 1.0) * hh * w1 + t[1] * hh * e1;
    let off = vec2<f32>(c.x * a.x, c.y * a.y) * in.misc.z;
    let pt = in.axis + off.x * in.n_ply + off.y * in.b_ply;
    hit.point = pt;
    let rel = pt - in.centre;
    hit.q = vec2<f32>(dot(rel, normalize(in.n_slice)), dot(rel, normalize(in.b_slice)));
    return hit;
}

// ---- fiber shadow maps (passes/fiber_shadow.rs): vs_main with the light as the camera,
// so every strip faces the light. A fiber stores the depth of its cylinder's far side,
// where a shadow ray from behind it enters it (at side x of the strip, sqrt(1 − x²) radii
// behind the axis), so that a point is shadowed exactly when a ray from it towards the
// light enters another fiber (the reference's test); and its key (fiber_key), which the
// fiber's own points skip. A core strip keeps a texel where its texture's coverage
// exceeds a uniform hashed from the strip and the texel (stochastic transparency: the
// expected occlusion is the coverage), at the strip's depth. ----

struct ShadowOut {
    @location(0) key: u32,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_shadow(in: VertexOut) -> ShadowOut {
    var out: ShadowOut;
    out.key = in.ids.w;
    out.depth = in.clip.z;
    if in.ids.z == 1u {
        let hit = core_hit(effects[in.ids.y], in);
        let px = vec2<u32>(in.clip.xy);
        let u = f32(pcg(in.ids.x ^ pcg(px.x + 0x10000u * px.y)) >> 8u) / 16777216.0;
        if hit.alpha <= u {
            discard;
        }
    } else {
        let x = clamp(in.misc.y, -1.0, 1.0);
        out.depth = clamp(in.clip.z + in.misc.z * sqrt(1.0 - x * x), 0.0, 1.0);
    }
    return out;
}

// Visibility of delta light `li` from `point` (a fiber's axis) on the fiber of key `key`
// through its fiber maps (the first map of the light that sees the point): 3 × 3 taps
// `bias.z` texels apart, each lit when the fiber nearest the light there is the point's own
// (the reference's shadow ray skips it) or its far side lies beyond the point (the
// reference's ray, from the axis, enters no other fiber).
fn fiber_visibility(li: u32, point: vec3<f32>, wi: vec3<f32>, key: u32) -> f32 {
    let h = first_map(li, point, wi, 0.0);
    if h.m < 0 {
        return 1.0;
    }
    let n = vec2<f32>(textureDimensions(shadow_ids).xy);
    let spread = shadow_views.bias[h.m].z;
    var v = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let t = clamp(h.uv * n + vec2<f32>(f32(dx), f32(dy)) * spread, vec2<f32>(0.0),
                n - 1.0);
            let texel = vec2<i32>(t);
            let id = textureLoad(shadow_ids, texel, h.m, 0).x;
            let d = textureLoad(shadow_maps, texel, h.m, 0);
            v += select(0.0, 1.0, id == key || h.depth <= d);
        }
    }
    return v / 9.0;
}

@fragment
fn fs_main(in_raw: VertexOut) -> FragmentOut {
    var in = in_raw;
    var coverage = in.misc.x;
    let ef = effects[in.ids.y];
    // Where the fiber maps are read from: the fiber's axis, or the core texel's fiber.
    var point = in.axis;
    if in.ids.z == 1u {
        let hit = core_hit(ef, in);
        coverage = hit.alpha;
        in.tangent = hit.direction;
        in.q = hit.q;
        point = hit.point;
    }
    let tan = normalize_or(in.tangent, vec3<f32>(1.0, 0.0, 0.0));
    let wo = view_dir(in.axis);
    var l = vec3<f32>(0.0);
    let radius = yarn_params[in.ids.y].c.z;
    let fiber_maps = (view.lod.z & 2048u) != 0u;
    for (var i = 0u; i < view.counts.x; i++) {
        let light = view.lights[i];
        var wi = light.pos_dir.xyz;
        var e = light.value.rgb;
        if light.pos_dir.w != 0.0 {
            let d = light.pos_dir.xyz - in.axis;
            let d2 = max(dot(d, d), 1e-20);
            wi = d / sqrt(d2);
            e = e / d2;
        }
        var vis: f32;
        if fiber_maps {
            // Every fiber casts: the map replaces the tubes and the self-shadow volume.
            vis = fiber_visibility(i, point, wi, in.ids.w);
        } else {
            vis = self_transmittance(ef, in, wi, wo)
                * yarn_visibility(i, in.centre, wi, radius * 1.05);
        }
        l += bcsdf_cos(wi, wo, tan) * e * vis;
    }
    let n_env = u32(env[0]);
    if n_env > 0u {
        // The environment by SRBFs [H25 eq. 14–17] with the fiber's own tangent: per lobe
        // the BCSDF's integral against it (I_M), the self-shadow towards its centre and its
        // tube shadow map.
        let first_im = 4u + 8u * n_env;
        let ao_ = fiber_angles(wo, tan);
        for (var j = 0u; j < n_env; j++) {
            let wj = vec3<f32>(env[4u + 8u * j], env[5u + 8u * j], env[6u + 8u * j]);
            let weight = vec3<f32>(env[8u + 8u * j], env[9u + 8u * j], env[10u + 8u * j]);
            let aj = fiber_angles(wj, tan);
            let im = im_at(first_im, aj.w, ao_.w, acos(clamp(dot(aj.xyz, ao_.xyz), -1.0, 1.0)));
            let vis = self_transmittance(ef, in, wj, wo)
                * yarn_visibility(8u + j, in.centre, wj, radius * 1.05);
            l += weight * im * vis;
        }
    } else if any(view.ambient.rgb > vec3<f32>(0.0)) {
        let to = asin(clamp(dot(wo, tan), -1.0, 1.0));
        l += view.ambient.rgb * ambient_integral(ef, to) * ambient_occlusion(ef, in.q);
    }
    if (view.lod.z & 4u) != 0u {
        l *= in.color;
    }
    var out: FragmentOut;
    out.color = vec4<f32>(l, 1.0);
    out.mask = coverage_mask(coverage, in.ids.x, vec2<u32>(in.clip.xy));
    return out;
}
