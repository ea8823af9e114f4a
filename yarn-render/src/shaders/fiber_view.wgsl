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

// Projected size in pixels of a length `r` at origin-relative point `p`.
fn pixels_of(view: View, r: f32, p: vec3<f32>) -> f32 {
    if view.eye.w == 0.0 {
        return r * view.viewport.z;
    }
    let depth = max(dot(p - view.eye.xyz, view.forward.xyz), 1e-9);
    return r * view.viewport.z / depth;
}
