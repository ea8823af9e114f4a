// Fiber shading shared by fiber_draw and strip_regular (both declare `view`, `lobes`,
// `q_nodes`, the SRBF environment `env` and the tube shadow maps `shadow_maps`,
// `shadow_cmp`, `shadow_views` in their own group 1): the lobe records of bcsdf.rs, the
// fiber BCSDF of yarn::bcsdf evaluated as FiberBcsdf::eval does, the view direction, the
// hashed sample masks of strips narrower than their coverage, the SRBF environment's I_M
// table [H25 eq. 16] with the fiber-frame angles it is read at, and the layout of the tube
// shadow maps' uniform.

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

fn view_dir(p: vec3<f32>) -> vec3<f32> {
    if view.eye.w == 0.0 {
        return -view.forward.xyz;
    }
    return normalize(view.eye.xyz - p);
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

// I_M at (θ_j, θ_o, Δφ), trilinear on the 16³ nodes (yarn_precompute::ImTable::at).
fn im_at(first: u32, theta_j: f32, theta_o: f32, dphi: f32) -> vec3<f32> {
    let n = 16u;
    let cj = clamp((theta_j + 0.5 * PI) / PI * 15.0, 0.0, 15.0);
    let co = clamp((theta_o + 0.5 * PI) / PI * 15.0, 0.0, 15.0);
    let cp = clamp(dphi / PI * 15.0, 0.0, 15.0);
    let j = min(u32(floor(cj)), 14u);
    let o = min(u32(floor(co)), 14u);
    let p = min(u32(floor(cp)), 14u);
    let f = vec3<f32>(cj - f32(j), co - f32(o), cp - f32(p));
    var out = vec3<f32>(0.0);
    for (var c = 0u; c < 8u; c++) {
        let d = vec3<u32>(c & 1u, (c >> 1u) & 1u, (c >> 2u) & 1u);
        let w = select(1.0 - f.x, f.x, d.x == 1u) * select(1.0 - f.y, f.y, d.y == 1u)
            * select(1.0 - f.z, f.z, d.z == 1u);
        let a = first + 3u * (((j + d.x) * n + o + d.y) * n + p + d.z);
        out += w * vec3<f32>(env[a], env[a + 1u], env[a + 2u]);
    }
    return out;
}

// The angles of ω in a fiber frame with tangent t: θ from the normal plane, and the
// in-plane unit projection (for Δφ).
fn fiber_angles(w: vec3<f32>, t: vec3<f32>) -> vec4<f32> {
    let s = clamp(dot(w, t), -1.0, 1.0);
    let p = w - t * s;
    let l = length(p);
    let q = select(vec3<f32>(0.0), p / l, l > 1e-6);
    return vec4<f32>(q, asin(s));
}

// The tube shadow maps of a frame (passes/shadow.rs ShadowViewsRaw): world (origin-
// relative) → light clip per map, the count, per map the light it belongs to (light i, or
// SRBF j as 8 + j), its PCSS scale and its biases.
struct ShadowViews {
    view_proj: array<mat4x4<f32>, 56>,
    // Maps in use, unused ×3.
    n: vec4<u32>,
    light: array<vec4<u32>, 14>,
    // 1/size, unused ×3.
    texel: vec4<f32>,
    // Per map: PCSS penumbra texels per unit of light-clip depth gap (0: hard).
    pcss: array<vec4<f32>, 14>,
    // Per map: depth bias (clip depth), bias along the light ray (metres), 3 × 3 PCF tap
    // spacing in texels (fibers), unused.
    bias: array<vec4<f32>, 56>,
}

// Where a point lands in the first shadow map of a light.
struct MapHit {
    uv: vec2<f32>,
    // Light-clip depth, the map's depth bias subtracted.
    depth: f32,
    // The map (a layer of the shaders' shadow_maps), −1 when none of the light sees it.
    m: i32,
}

// The first shadow map of light `li` (or SRBF j as 8 + j; a point light may have six cube
// faces) that sees `point` moved along `wi` (towards the light) by `offset` plus the map's
// bias along the ray, with the shaders' `shadow_views`.
fn first_map(li: u32, point: vec3<f32>, wi: vec3<f32>, offset: f32) -> MapHit {
    var hit: MapHit;
    hit.m = -1;
    for (var m = 0u; m < shadow_views.n.x; m++) {
        if shadow_views.light[m / 4u][m % 4u] != li {
            continue;
        }
        let b = shadow_views.bias[m];
        let c = shadow_views.view_proj[m] * vec4<f32>(point + wi * (offset + b.y), 1.0);
        if c.w <= 0.0 {
            continue;
        }
        let ndc = c.xyz / c.w;
        let uv = vec2<f32>(0.5 * ndc.x + 0.5, 0.5 - 0.5 * ndc.y);
        if any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) {
            continue;
        }
        hit.uv = uv;
        hit.depth = ndc.z - b.x;
        hit.m = i32(m);
        return hit;
    }
    return hit;
}
