// strip_regular (render, vertex pulling): the fiber-textured yarn strips of
// [H25 §4.3, §5.2] — one instance per yarn segment, a camera-facing triangle strip of
// 2·(n_sub + 1) vertices on the yarn centre line (yarn_point of the generator), 2H wide
// (H the baked strip half-width), in place of [H25]'s geometry shader. The fragment reads
// the strip bake (yarn_precompute::StripBake) at the screw-symmetric texture coordinate
// u = frac(z/α_ply − ψ_e/2π) (ψ_e the eye azimuth about the yarn in its (N, B) frame) and
// v across, and shades [H25 eq. 11] as DESIGN §3.3 item 10 reads it:
//   L = Σ_lights E · V_yarn · Ψ_M(θ_i) Ψ_N(φ) · ξ_M(θ_i) ξ_N(φ) · (1/K) Σ_k f(ω_i, ω_o; t_k) cos θ_i · tint
// with V_yarn the strip shadow map (yarn_tube_shadow) filtered by PCSS, θ_i the light's
// angle from the yarn's normal plane and φ its signed azimuth about the yarn from the
// view's projection (both as baked). Coverage α becomes a hashed sample mask, as for
// sub-pixel fibers. Constant ambient: ambient · A(θ_o) · AO · tint.

struct StripHeader {
    // Texels along u, along v, directions D, tangents K.
    dims: vec4<u32>,
    // First float of the texels, first float of the ambient table, floats per texel,
    // ambient entries.
    offs: vec4<u32>,
    // Strip half-width H, flyaway strip half-width H_f (metres), unused ×2.
    f: vec4<f32>,
    // Flyaway textures (yarn_precompute::FlyawayBake): first float, texels along u, across,
    // count (0: none).
    fly: vec4<u32>,
}

// Maps: the directional lights' (light i) and one per SRBF (light 8 + j).

@group(1) @binding(0) var<uniform> view: View;
@group(1) @binding(1) var<storage, read> headers: array<StripHeader>;
@group(1) @binding(2) var<storage, read> texels: array<f32>;
@group(1) @binding(3) var<storage, read> lobes: array<Lobe>;
@group(1) @binding(4) var<storage, read> q_nodes: array<f32>;
@group(1) @binding(5) var shadow_maps: texture_depth_2d_array;
@group(1) @binding(6) var shadow_cmp: sampler_comparison;
@group(1) @binding(7) var<uniform> shadow_views: ShadowViews;
// The environment (strips.rs set_environment): count, λ, unused ×2; per SRBF its direction
// (xyz, 0) and weight (rgb, 0); then I_M on 16³ nodes (θ_j, θ_o, Δφ), RGB.
@group(1) @binding(8) var<storage, read> env: array<f32>;
// Flyaway texels: per texture, per texel (t_T, t_w, t_e, coverage).
@group(1) @binding(9) var<storage, read> fly_texels: array<vec4<f32>>;

struct StripOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) centre: vec3<f32>,
    @location(1) tangent: vec3<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) color: vec3<f32>,
    // v across in [−widen, widen], ply turns z/α_ply (unwrapped), widen (≥ 1), unused.
    // Centroid: a thin strip must read its texture inside the covered samples, not at a
    // pixel centre outside it (where v would clamp to the empty border texels).
    @location(4) @interpolate(perspective, centroid) uv: vec4<f32>,
    // Identity hash, params id.
    @location(5) @interpolate(flat) ids: vec4<u32>,
}

@vertex
fn vs_strip(@builtin(vertex_index) vi: u32, @builtin(instance_index) seg: u32) -> StripOut {
    let n_sub = max(view.lod.y, 1u);
    let k = min(vi / 2u, n_sub);
    let side = select(-1.0, 1.0, (vi & 1u) == 1u);
    let t = f32(k) / f32(n_sub);
    let yp = yarn_point(seg, t);
    let s = segments[seg];
    let c = curves[s.ids.x];
    let h = headers[c.ids.x];
    let e = view_dir(yp.pos);
    let across = normalize_or(cross(yp.t, e), any_perpendicular(yp.t));
    // A strip narrower than the minimum width (px) is widened to it and keeps its coverage
    // fraction of the samples (as fiber_draw's strips): `widen` ≥ 1 scales v.
    // The flyaway overlay (flag 16) draws the same strips H_f wide.
    let fly = (view.lod.z & 16u) != 0u;
    let hw = select(h.f.x, h.f.y, fly);
    let px = pixels_of(view, 2.0 * hw, yp.pos);
    var widen = 1.0;
    if px < view.strip.x && px > 0.0 {
        widen = view.strip.x / px;
    }
    var out: StripOut;
    out.clip = view.view_proj * vec4<f32>(yp.pos + across * (hw * widen * side), 1.0);
    out.centre = yp.pos;
    out.tangent = yp.t;
    out.normal = yp.n;
    out.color = select(s.color[0].rgb, s.color[1].rgb, t >= 0.5);
    out.uv = vec4<f32>(side * widen, s.phase.x + yp.dz / c.pitch.x, widen, 0.0);
    out.ids = vec4<u32>(pcg(seg), c.ids.x, 0u, 0u);
    return out;
}

fn tex(i: u32) -> f32 {
    return texels[i];
}

// The texel at (u, v) (StripBake::texel_at): nearest, u repeats, v ∈ [−1, 1] clamps.
// Nearest, not bilinear: the texels hold box-filtered means and the shading is non-linear
// in them — bilinear inputs raised the radiance of the baked yarn by 44 % over the bake
// (tests/gpu/strips.rs), nearest keeps it within 2 %.
fn texel_at(h: StripHeader, u: f32, v: f32) -> u32 {
    let w = h.dims.x;
    let hh = h.dims.y;
    let i = u32((i32(floor(fract(u) * f32(w))) % i32(w) + i32(w)) % i32(w));
    let j = u32(clamp(floor((v + 1.0) * 0.5 * f32(hh)), 0.0, f32(hh - 1u)));
    return j * w + i;
}

// Float `off` of texel `t`.
fn tap(h: StripHeader, t: u32, off: u32) -> f32 {
    return tex(h.offs.x + t * h.offs.z + off);
}

// Linear bin weights (StripBake::bin_weights): θ clamps, φ wraps.
struct Bins {
    b: vec2<u32>,
    w: vec2<f32>,
}

fn bins_theta(d: u32, theta: f32) -> Bins {
    let x = clamp((theta + 0.5 * PI) / (PI / f32(d)) - 0.5, 0.0, f32(d - 1u));
    let b0 = min(u32(floor(x)), d - 2u);
    let f = x - f32(b0);
    return Bins(vec2<u32>(b0, b0 + 1u), vec2<f32>(1.0 - f, f));
}

fn bins_phi(d: u32, phi: f32) -> Bins {
    let x = (phi + PI) / (TAU / f32(d)) - 0.5;
    let x0 = floor(x);
    let f = x - x0;
    let b0 = u32((i32(x0) % i32(d) + i32(d)) % i32(d));
    return Bins(vec2<u32>(b0, (b0 + 1u) % d), vec2<f32>(1.0 - f, f));
}

fn factor1(h: StripHeader, t: u32, first: u32, b: Bins) -> f32 {
    return b.w.x * tap(h, t, first + b.b.x) + b.w.y * tap(h, t, first + b.b.y);
}

fn factor3(h: StripHeader, t: u32, first: u32, b: Bins) -> vec3<f32> {
    var o = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        o[c] = b.w.x * tap(h, t, first + 3u * b.b.x + c) + b.w.y * tap(h, t, first + 3u * b.b.y + c);
    }
    return o;
}

// PCSS [H25 §4.5] of light li's strip shadow map (the first of its maps that sees the
// point: a point light among the yarns has cube faces) at the yarn centre moved towards the
// light by the yarn radius: a 4 × 4 blocker search over the widest penumbra, then a 4 × 4
// comparison PCF over the penumbra the mean blocker depth gives; pcss = 0 is the hard
// shadow map with one comparison tap (DESIGN §3.5's PCSS limit).
fn strip_visibility(li: u32, centre: vec3<f32>, wi: vec3<f32>, radius: f32) -> f32 {
    let h = first_map(li, centre, wi, radius * 1.05);
    if h.m >= 0 {
        let m = u32(h.m);
        let uv = h.uv;
        let depth = h.depth;
        let k = shadow_views.pcss[m / 4u][m % 4u];
        let texel = shadow_views.texel.x;
        if k <= 0.0 {
            return textureSampleCompareLevel(shadow_maps, shadow_cmp, uv, i32(m), depth);
        }
        let size = i32(round(1.0 / texel));
        let search = clamp(k * depth, 1.0, 32.0);
        var blockers = 0.0;
        var sum = 0.0;
        for (var j = 0; j < 4; j++) {
            for (var i = 0; i < 4; i++) {
                let o = (vec2<f32>(f32(i), f32(j)) - 1.5) / 1.5 * search;
                let q = clamp(vec2<i32>(floor(uv / texel + o)), vec2<i32>(0), vec2<i32>(size - 1));
                let d = textureLoad(shadow_maps, q, i32(m), 0);
                if d < depth {
                    blockers += 1.0;
                    sum += d;
                }
            }
        }
        if blockers == 0.0 {
            return 1.0;
        }
        let penumbra = clamp(k * (depth - sum / blockers), 0.5, 32.0);
        var v = 0.0;
        for (var j = 0; j < 4; j++) {
            for (var i = 0; i < 4; i++) {
                let o = (vec2<f32>(f32(i), f32(j)) - 1.5) / 1.5 * penumbra * texel;
                v += textureSampleCompareLevel(shadow_maps, shadow_cmp, uv + o, i32(m), depth);
            }
        }
        return v / 16.0;
    }
    return 1.0;
}

// Light i seen from p: the unit direction towards it and the factor on its value (1 for
// a directional light's irradiance, 1/d² for a point light's intensity).
fn light_at(i: u32, p: vec3<f32>) -> vec4<f32> {
    let light = view.lights[i];
    if light.pos_dir.w == 0.0 {
        return vec4<f32>(light.pos_dir.xyz, 1.0);
    }
    let dl = light.pos_dir.xyz - p;
    let d2 = max(dot(dl, dl), 1e-20);
    return vec4<f32>(dl / sqrt(d2), 1.0 / d2);
}

fn ambient_at(h: StripHeader, theta_o: f32) -> vec3<f32> {
    let n = h.offs.w;
    let x = clamp((theta_o + 0.5 * PI) / PI * f32(n - 1u), 0.0, f32(n - 1u));
    let k = min(u32(floor(x)), n - 2u);
    let f = x - f32(k);
    let a = h.offs.y + 3u * k;
    let v0 = vec3<f32>(tex(a), tex(a + 1u), tex(a + 2u));
    let v1 = vec3<f32>(tex(a + 3u), tex(a + 4u), tex(a + 5u));
    return mix(v0, v1, f);
}

// The flyaway overlay [H25 §4.4]: texture `ids.x % count` (one per segment), u = the ply
// turns (view-independent, as [H25]), nearest texel; where a hair was the first fiber seen,
// the BCSDF at its direction under every light (no Ψ or ξ: hairs stand apart), the strip
// shadow map, the environment through I_M; elsewhere no sample.
fn fs_flyaway(in: StripOut, h: StripHeader) -> FragmentOut {
    var out: FragmentOut;
    out.color = vec4<f32>(0.0);
    out.mask = 0u;
    if h.fly.w == 0u {
        return out;
    }
    let w = h.fly.y;
    let hh = h.fly.z;
    let widen = max(in.uv.z, 1.0);
    let v = in.uv.x / widen;
    let i = u32((i32(floor(fract(in.uv.y) * f32(w))) % i32(w) + i32(w)) % i32(w));
    let j = u32(clamp(floor((v + 1.0) * 0.5 * f32(hh)), 0.0, f32(hh - 1u)));
    let k = in.ids.x % h.fly.w;
    let tx = fly_texels[h.fly.x + (k * hh + j) * w + i];
    if tx.w <= 0.0 {
        return out;
    }
    let tt = normalize_or(in.tangent, vec3<f32>(1.0, 0.0, 0.0));
    let wo = view_dir(in.centre);
    let nn = normalize_or(in.normal - tt * dot(in.normal, tt), any_perpendicular(tt));
    let e = normalize_or(wo - tt * dot(wo, tt), nn);
    let ww = cross(tt, e);
    let tw = normalize_or(tx.x * tt + tx.y * ww + tx.z * e, tt);
    let radius = yarn_params[in.ids.y].c.z;
    var l = vec3<f32>(0.0);
    for (var li = 0u; li < view.counts.x; li++) {
        let ls = light_at(li, in.centre);
        let wi = ls.xyz;
        let el = view.lights[li].value.rgb * ls.w;
        l += bcsdf_cos(wi, wo, tw) * el * strip_visibility(li, in.centre, wi, radius);
    }
    let n_env = u32(env[0]);
    if n_env > 0u {
        let first_im = 4u + 8u * n_env;
        let ao_ = fiber_angles(wo, tw);
        for (var jj = 0u; jj < n_env; jj++) {
            let wj = vec3<f32>(env[4u + 8u * jj], env[5u + 8u * jj], env[6u + 8u * jj]);
            let weight = vec3<f32>(env[8u + 8u * jj], env[9u + 8u * jj], env[10u + 8u * jj]);
            let aj = fiber_angles(wj, tw);
            let im = im_at(first_im, aj.w, ao_.w, acos(clamp(dot(aj.xyz, ao_.xyz), -1.0, 1.0)));
            l += weight * im * strip_visibility(8u + jj, in.centre, wj, radius);
        }
    } else if any(view.ambient.rgb > vec3<f32>(0.0)) {
        l += view.ambient.rgb * ambient_at(h, asin(clamp(dot(wo, tw), -1.0, 1.0)));
    }
    if (view.lod.z & 4u) != 0u {
        l *= in.color;
    }
    out.color = vec4<f32>(l, 1.0);
    out.mask = coverage_mask(tx.w / widen,
        in.ids.x ^ 0x9e3779b9u ^ pcg(u32(in.clip.x) * 7919u + u32(in.clip.y)), vec2<u32>(in.clip.xy));
    return out;
}

@fragment
fn fs_strip(in: StripOut) -> FragmentOut {
    let h = headers[in.ids.y];
    if (view.lod.z & 16u) != 0u {
        return fs_flyaway(in, h);
    }
    let flags = view.lod.z;
    let textured = (flags & 8u) != 0u;
    let tt = normalize_or(in.tangent, vec3<f32>(1.0, 0.0, 0.0));
    let wo = view_dir(in.centre);
    // The view's projection on the yarn's normal plane, the across axis, the eye azimuth.
    let nn = normalize_or(in.normal - tt * dot(in.normal, tt), any_perpendicular(tt));
    let bb = cross(tt, nn);
    let e = normalize_or(wo - tt * dot(wo, tt), nn);
    let w = cross(tt, e);
    let psi_e = atan2(dot(e, bb), dot(e, nn));
    let u = in.uv.y - psi_e / TAU;
    let widen = max(in.uv.z, 1.0);
    let v = in.uv.x / widen;
    let taps = texel_at(h, u, v);
    let d = h.dims.z;
    let kt = h.dims.w;
    var alpha = 1.0;
    var ao = 1.0;
    if textured {
        alpha = clamp(tap(h, taps, 0u), 0.0, 1.0);
        ao = clamp(tap(h, taps, 1u), 0.0, 1.0);
    } else if abs(v) > 1.0 {
        alpha = 0.0;
    }
    let first_psi = 2u + 3u * kt;
    let first_xi = first_psi + 2u * d;
    let radius = yarn_params[in.ids.y].c.z;
    var l = vec3<f32>(0.0);
    for (var i = 0u; i < view.counts.x; i++) {
        let ls = light_at(i, in.centre);
        let wi = ls.xyz;
        let el = view.lights[i].value.rgb * ls.w;
        var f = vec3<f32>(0.0);
        if textured {
            for (var k = 0u; k < kt; k++) {
                let tk = vec3<f32>(tap(h, taps, 2u + 3u * k), tap(h, taps, 3u + 3u * k),
                    tap(h, taps, 4u + 3u * k));
                let tw = normalize_or(tk.x * tt + tk.y * w + tk.z * e, tt);
                f += bcsdf_cos(wi, wo, tw);
            }
            f /= f32(kt);
            let theta = asin(clamp(dot(wi, tt), -1.0, 1.0));
            let phi = atan2(dot(wi, w), dot(wi, e));
            let bt = bins_theta(d, theta);
            let bp = bins_phi(d, phi);
            if (flags & 2u) != 0u {
                f *= factor1(h, taps, first_psi, bt) * factor1(h, taps, first_psi + d, bp);
            }
            if (flags & 1u) != 0u {
                f *= factor3(h, taps, first_xi, bt) * factor3(h, taps, first_xi + 3u * d, bp);
            }
        } else {
            f = bcsdf_cos(wi, wo, tt);
        }
        l += f * el * strip_visibility(i, in.centre, wi, radius);
    }
    let n_env = u32(env[0]);
    if n_env > 0u {
        let first_im = 4u + 8u * n_env;
        for (var j = 0u; j < n_env; j++) {
            let wj = vec3<f32>(env[4u + 8u * j], env[5u + 8u * j], env[6u + 8u * j]);
            let weight = vec3<f32>(env[8u + 8u * j], env[9u + 8u * j], env[10u + 8u * j]);
            var im = vec3<f32>(0.0);
            var fac = vec3<f32>(1.0);
            if textured {
                for (var k = 0u; k < kt; k++) {
                    let tk = vec3<f32>(tap(h, taps, 2u + 3u * k), tap(h, taps, 3u + 3u * k),
                        tap(h, taps, 4u + 3u * k));
                    let tw = normalize_or(tk.x * tt + tk.y * w + tk.z * e, tt);
                    let aj = fiber_angles(wj, tw);
                    let ao_ = fiber_angles(wo, tw);
                    let dphi = acos(clamp(dot(aj.xyz, ao_.xyz), -1.0, 1.0));
                    im += im_at(first_im, aj.w, ao_.w, dphi);
                }
                im /= f32(kt);
                let theta = asin(clamp(dot(wj, tt), -1.0, 1.0));
                let phi = atan2(dot(wj, w), dot(wj, e));
                let bt = bins_theta(d, theta);
                let bp = bins_phi(d, phi);
                if (flags & 2u) != 0u {
                    fac *= factor1(h, taps, first_psi, bt) * factor1(h, taps, first_psi + d, bp);
                }
                if (flags & 1u) != 0u {
                    fac *= factor3(h, taps, first_xi, bt) * factor3(h, taps, first_xi + 3u * d, bp);
                }
            } else {
                let aj = fiber_angles(wj, tt);
                let ao_ = fiber_angles(wo, tt);
                im = im_at(first_im, aj.w, ao_.w, acos(clamp(dot(aj.xyz, ao_.xyz), -1.0, 1.0)));
            }
            l += weight * im * fac * strip_visibility(8u + j, in.centre, wj, radius);
        }
    } else if any(view.ambient.rgb > vec3<f32>(0.0)) {
        let to = asin(clamp(dot(wo, tt), -1.0, 1.0));
        l += view.ambient.rgb * ambient_at(h, to) * ao;
    }
    if (flags & 4u) != 0u {
        l *= in.color;
    }
    var out: FragmentOut;
    out.color = vec4<f32>(l, 1.0);
    out.mask = coverage_mask(alpha / widen, in.ids.x ^ pcg(u32(in.clip.x) * 7919u + u32(in.clip.y)),
        vec2<u32>(in.clip.xy));
    return out;
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @builtin(sample_mask) mask: u32,
}
