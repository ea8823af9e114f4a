// fiber_draw (render, vertex pulling): one instance per listed (segment, ply, fiber) — or,
// for the plain-tube baseline (fiber index 0xffff), per segment with the yarn's width — a
// triangle strip of 2·(n_sub_max + 1) vertices; vertex k of an instance with fewer
// subdivisions collapses onto its last point. Each vertex evaluates the generator
// (fiber_point, the function fiber_expand writes) and is pushed ± half the fiber width
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

struct Lobe {
    // Colour A_p (linear RGB).
    color: vec4<f32>,
    // β, shift, scale of M (Gaussian: q(θ_i) q(θ_o) exp(−x²/2β²) × scale), κ of N.
    shape: vec4<f32>,
    // M kind (0 constant 2/π, 1 Gaussian), N kind (0 uniform, 1 cos(φ/2)/4, 2 von Mises,
    // 3 Lambertian cylinder), first q node, unused.
    kinds: vec4<u32>,
    // von Mises normalisation, unused ×3.
    extra: vec4<f32>,
}

@group(1) @binding(0) var<uniform> view: View;
@group(1) @binding(1) var<storage, read> instances: array<vec2<u32>>;
@group(1) @binding(2) var<storage, read> lobes: array<Lobe>;
@group(1) @binding(3) var<storage, read> q_nodes: array<f32>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    // Origin-relative position on the fiber axis.
    @location(0) axis: vec3<f32>,
    @location(1) tangent: vec3<f32>,
    @location(2) color: vec3<f32>,
    // Coverage of a widened strip (1 when the fiber is at least the minimum width).
    @location(3) coverage: f32,
    @location(4) @interpolate(flat) instance: u32,
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @builtin(sample_mask) mask: u32,
}

fn view_dir(p: vec3<f32>) -> vec3<f32> {
    if view.eye.w == 0.0 {
        return -view.forward.xyz;
    }
    return normalize(view.eye.xyz - p);
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VertexOut {
    let rec = instances[ii];
    let seg = rec.x;
    let fib = rec.y & 0xffffu;
    let ply = (rec.y >> 16u) & 0xffu;
    let n_sub = max(rec.y >> 24u, 1u);
    let k = min(vi / 2u, n_sub);
    let side = select(-1.0, 1.0, (vi & 1u) == 1u);
    let t = f32(k) / f32(n_sub);
    let loops = (view.lod.z & 2u) != 0u;
    let tube = fib == 0xffffu;
    // Tangent from a neighbour a quarter subdivision away (backwards at the end).
    let h = 0.25 / f32(n_sub);
    let t2 = select(t + h, t - h, t + h > 1.0);
    var p: vec3<f32>;
    var q: vec3<f32>;
    if tube {
        p = yarn_point(seg, t).pos;
        q = yarn_point(seg, t2).pos;
    } else {
        p = fiber_point(seg, ply, fib, t, loops);
        q = fiber_point(seg, ply, fib, t2, loops);
    }
    var tan = normalize_or(q - p, yarn_point(seg, t).t);
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
    }
    var out: VertexOut;
    out.clip = view.view_proj * vec4<f32>(p + across * (0.5 * w * side), 1.0);
    out.axis = p;
    out.tangent = tan;
    out.color = select(s.color[0].rgb, s.color[1].rgb, t >= 0.5);
    out.coverage = coverage;
    // The fiber's identity, not its place in the list: culling and LoD reorder the list,
    // and the sample mask must not change with it.
    out.instance = pcg(seg) ^ (rec.y & 0xffffffu);
    return out;
}

// ---- the fiber BCSDF (yarn::bcsdf) ----

fn q_at(first: u32, theta: f32) -> f32 {
    let x = clamp((theta + 0.5 * PI) / (PI / 256.0) - 0.5, 0.0, 255.0);
    let k = min(u32(floor(x)), 254u);
    let b = cr_basis(x - f32(k));
    let k0 = select(k - 1u, 0u, k == 0u);
    let k3 = min(k + 2u, 255u);
    return b.x * q_nodes[first + k0] + b.y * q_nodes[first + k] + b.z * q_nodes[first + k + 1u]
        + b.w * q_nodes[first + k3];
}

fn lobe_m(l: Lobe, ti: f32, to: f32) -> f32 {
    if l.kinds.x == 0u {
        return 2.0 / PI;
    }
    let x = 0.5 * (ti + to) - l.shape.y;
    let g = exp(-x * x / (2.0 * l.shape.x * l.shape.x));
    return l.shape.z * q_at(l.kinds.z, ti) * q_at(l.kinds.z, to) * g;
}

// dphi ∈ [0, π] (every lobe is even in φ_o − φ_i).
fn lobe_n(l: Lobe, dphi: f32) -> f32 {
    switch l.kinds.y {
        case 0u: {
            return 1.0 / TAU;
        }
        case 1u: {
            return 0.25 * max(cos(0.5 * dphi), 0.0);
        }
        case 2u: {
            return exp(l.shape.w * (cos(dphi - PI) - 1.0)) / l.extra.x;
        }
        default: {
            return max(((PI - dphi) * cos(dphi) + sin(dphi)) / 8.0, 0.0);
        }
    }
}

// f(ω_i, ω_o)·cos θ_i for unit directions and the unit fiber tangent.
fn bcsdf_cos(wi: vec3<f32>, wo: vec3<f32>, tan: vec3<f32>) -> vec3<f32> {
    let si = clamp(dot(wi, tan), -1.0, 1.0);
    let so = clamp(dot(wo, tan), -1.0, 1.0);
    let ti = asin(si);
    let to = asin(so);
    let a = wi - tan * si;
    let b = wo - tan * so;
    let la = length(a);
    let lb = length(b);
    var dphi = 0.0;
    if la > 1e-6 && lb > 1e-6 {
        dphi = acos(clamp(dot(a, b) / (la * lb), -1.0, 1.0));
    }
    var f = vec3<f32>(0.0);
    for (var i = 0u; i < view.counts.y; i++) {
        let l = lobes[i];
        f += l.color.rgb * (lobe_m(l, ti, to) * lobe_n(l, dphi));
    }
    return f * sqrt(max(1.0 - si * si, 0.0));
}

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The samples a fragment of coverage `c` keeps (all when c ≥ 1).
fn coverage_mask(c: f32, instance: u32, pixel: vec2<u32>) -> u32 {
    if c >= 1.0 {
        return 0xffffffffu;
    }
    let n = max(view.strip.y, 1.0);
    let h = pcg(instance ^ pcg(pixel.x ^ pcg(pixel.y)));
    let u = f32(h & 0xffffu) / 65536.0;
    let k = u32(clamp(floor(c * n + u), 0.0, n));
    if k == 0u {
        return 0u;
    }
    let ni = u32(n);
    let bits = (1u << k) - 1u;
    let rot = (h >> 16u) % ni;
    let full = (1u << ni) - 1u;
    return ((bits << rot) | (bits >> (ni - rot))) & full;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let tan = normalize_or(in.tangent, vec3<f32>(1.0, 0.0, 0.0));
    let wo = view_dir(in.axis);
    var l = vec3<f32>(0.0);
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
        l += bcsdf_cos(wi, wo, tan) * e;
    }
    if (view.lod.z & 4u) != 0u {
        l *= in.color;
    }
    var out: FragmentOut;
    out.color = vec4<f32>(l, 1.0);
    out.mask = coverage_mask(in.coverage, in.instance, vec2<u32>(in.clip.xy));
    return out;
}
