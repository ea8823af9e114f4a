// The frame's view for the fiber passes (group 1, binding 0): camera relative to the packed
// origin, viewport and LoD settings [W19 §3.3 eq. 4], frustum planes for conservative
// culling (DESIGN §2.3 item 8), lights. Mirrored by view.rs (ViewRaw).

struct Light {
    // xyz: unit direction towards the light (w = 0) or position (w = 1).
    pos_dir: vec4<f32>,
    // Directional: perpendicular irradiance; point: radiant intensity (linear RGB).
    value: vec4<f32>,
}

struct View {
    view_proj: mat4x4<f32>,
    // Eye relative to the origin; w = 1 perspective, 0 orthographic.
    eye: vec4<f32>,
    // Unit viewing direction (from the eye into the scene).
    forward: vec4<f32>,
    // Width, height (px), pixels per metre at unit depth (perspective) or per metre
    // (orthographic), ω^LoD (px; ≤ 0: LoD off).
    viewport: vec4<f32>,
    // Frustum planes (inside: dot(n, p) + w ≥ 0), normalised.
    planes: array<vec4<f32>, 6>,
    // Regular fibers per ply at λ = 1 (n_max), subdivisions at λ = 1, flags (bit 0 cull,
    // bit 1 loops, bit 2 tint by the yarn colour, bit 3 plain tubes, bit 4 self-shadows,
    // bits 5–6 AO mode: 0 off, 1 cubic, 2 texture, bit 7 core strips, bit 8 shadow
    // hiding, bit 9 helix-marched self-shadows, bit 10 hair flyaways), instance capacity.
    lod: vec4<u32>,
    // Lights in use, lobes in use, unused, unused.
    counts: vec4<u32>,
    // Smallest strip width (px) before coverage becomes a sample mask, MSAA samples,
    // unused ×2.
    strip: vec4<f32>,
    lights: array<Light, 8>,
    // Constant environment radiance for the ambient term (linear RGB), unused.
    ambient: vec4<f32>,
}

// [W19 eq. 4]: 1 when the fiber is at least ω^LoD wide, 0 when the ply is at most, and in
// between (ω_f/ω_L)(ω_p − ω_L)/(ω_p − ω_f). Mirrored by lod::lambda.
fn lod_lambda(w_fiber: f32, w_ply: f32, w_lod: f32) -> f32 {
    if w_lod <= 0.0 || w_lod <= w_fiber {
        return 1.0;
    }
    if w_ply <= w_lod {
        return 0.0;
    }
    return clamp((w_fiber / w_lod) * (w_ply - w_lod) / (w_ply - w_fiber), 0.0, 1.0);
}

// The projected fiber and ply widths (px) at segment `seg`'s midpoint.
fn segment_widths(v: View, seg: u32) -> vec2<f32> {
    let s = segments[seg];
    let pr = yarn_params[curves[s.ids.x].ids.x];
    let mid = combine(s, cr_basis(0.5));
    let w_fiber = pixels_of(v, 2.0 * pr.b.y, mid);
    let w_ply = pixels_of(v, 2.0 * max(pr.a.y, pr.a.z) * pr.b.x, mid);
    return vec2<f32>(w_fiber, w_ply);
}

// λ at segment `seg`'s midpoint: what fiber_lod lists by, and what the draw pass
// recomputes (the same f32 operations) for core strips and hairs.
fn segment_lambda(v: View, seg: u32) -> f32 {
    let w = segment_widths(v, seg);
    return lod_lambda(w.x, w.y, v.viewport.w);
}

// Fibers per ply (the outermost) whose hairs segment `seg` draws: a fraction
// φ = max(λ, ω_f/ω_min) of n_fib, rounded up. The hairs kept stand for the others with
// their coverage divided by the fraction kept (stochastic simplification: the expected
// fuzz is kept). A sub-pixel hair is ω_f wide and drawn ω_min wide with coverage ω_f/ω_min,
// so dividing by φ ≥ ω_f/ω_min keeps it within one pixel's samples; thinning as the regular
// fibers (by λ², or by λ alone once the ply falls below ω^LoD and λ = 0) would not.
// `lambda` and `w_fiber` are the segment's (segment_widths, lod_lambda).
fn hair_fibers(v: View, lambda: f32, w_fiber: f32, n_fib: u32) -> u32 {
    let phi = clamp(max(lambda, w_fiber / max(v.strip.x, 1e-6)), 0.0, 1.0);
    return min(u32(ceil(phi * f32(n_fib))), n_fib);
}

// Projected size in pixels of a length `r` at origin-relative point `p`.
fn pixels_of(view: View, r: f32, p: vec3<f32>) -> f32 {
    if view.eye.w == 0.0 {
        return r * view.viewport.z;
    }
    let depth = max(dot(p - view.eye.xyz, view.forward.xyz), 1e-9);
    return r * view.viewport.z / depth;
}
