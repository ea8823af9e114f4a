// The BTF pass: reconstructs the BTF of each fragment from per-view-slot PCA data and
// lights it ([S03 eq. 2–5]), with the smooth shadow boundary of [S03 eq. 6] and
// shadow-volume masks or shadow maps as per-light visibility.
//
//   T = Σ_m ω_m [ (Σ_l e_l Σ_n τ_ln) μ_j + Σ_l e_l Σ_n τ_ln b_{j,i_n} + Σ_k γ_kj B_kj ],
//   γ_kj = Σ_l e_l Σ_n τ_ln p'_{i_n,k,j}
// with e_l = RGB irradiance (directional) or intensity / d² (point) times visibility.
// Components come in groups of four packed in three RGBA layers (see material.rs).
// fs_pixel evaluates directions, slots and weights per fragment; fs_vertex (btf_vertex.wgsl,
// appended) blends the three vertices' per-vertex reconstructions with barycentric weights
// (the paper's three-pass blending in one pass), merging identical slots so each slot is
// read once. An environment light (eq. 11: e·γ* folded per vertex on the CPU) is always in
// the per-vertex layout; fs_pixel_env (btf_vertex.wgsl) adds it to the per-pixel lights.

const MAX_LIGHTS: u32 = 4u;
const NONE: u32 = 0xffffffffu;
const PI: f32 = 3.14159265358979;

override VIEW_FOUR: bool = true;
override LIGHT_FOUR: bool = true;
override COUNT_READS: bool = false;
// Which visibility code exists (lavapipe runs both sides of every branch, so code for a
// shadow technique the scene does not use is compiled out, not skipped): 0 no shadowing
// light, 1 shadow-volume masks, 2 shadow maps (flat and cube), 3 any (chosen per light at
// run time). SMOOTH_BOUNDARY false: eq. 6 off; true: as frame.info.y says.
override SHADOWS: u32 = 3u;
override SMOOTH_BOUNDARY: bool = true;
// The scene's lights (frame.info.x, fixed per renderer): constant loops over lights unroll,
// so per-light data lives in registers, not in dynamically indexed arrays. Entries beyond
// the active lights have weight 0, so the default (all four) is correct, only slower.
override N_LIGHTS: u32 = 4u;
// Groups of four components G of every material the pipeline draws (0: each material's own,
// samplings.info.x, at run time). A constant G makes the group loops fixed-length, which
// llvmpipe compiles to straight-line reads: at c = 4 the pass took 1.80–1.93× its read bound
// against 2.28–2.32× with G read at run time (BENCHMARKS.md #5, session 6).
override GROUPS: u32 = 0u;
// The weights in material.rs's packed f16 layout (set only with GROUPS > 0).
override PACKED: bool = false;
// Per-vertex mode without an environment light: the per-vertex coefficients in the
// separable layout (scalars per slot, the irradiance once per vertex and light; per_vertex.rs).
override SEPARABLE: bool = false;

struct LightRaw {
    // xyz: position (w = 1, point) or direction towards the light (w = 0, directional)
    pos: vec4<f32>,
    // rgb: intensity or irradiance; w: 0 unshadowed, 1 shadow-volume mask, 2 shadow map,
    // 3 cube shadow map (point light inside the scene; view_proj = the faces' projection)
    color: vec4<f32>,
    // x: mask / map layer (cube: face +x), y: shadow-map texel size, z: depth bias (cube:
    // fraction of the light distance)
    shadow: vec4<f32>,
    view_proj: mat4x4<f32>,
}

struct FrameRaw {
    view_proj: mat4x4<f32>,
    // xyz: eye; w: 1 perspective, 0 orthographic
    eye: vec4<f32>,
    // xyz: direction towards the camera (orthographic)
    to_camera: vec4<f32>,
    // x: lights, y: smooth boundary on (1/0), z: per-vertex coefficient stride G,
    // w: lights in the per-vertex layout
    info: vec4<u32>,
    // x: alpha in radians
    terminator: vec4<f32>,
    lights: array<LightRaw, 4>,
}

@group(0) @binding(0) var<uniform> frame: FrameRaw;
@group(0) @binding(1) var terminator_tex: texture_2d<f32>;
@group(0) @binding(2) var linear_clamp: sampler;
@group(0) @binding(3) var shadow_masks: texture_2d_array<f32>;
@group(0) @binding(4) var shadow_maps: texture_depth_2d_array;
@group(0) @binding(5) var shadow_cmp: sampler_comparison;
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>, 4>;

@group(1) @binding(0) var<uniform> samplings: Samplings;
@group(1) @binding(1) var eigen_tex: texture_2d_array<f32>;
@group(1) @binding(2) var mean_tex: texture_2d_array<f32>;
@group(1) @binding(3) var tex_sampler: sampler;
// f32 rows (bitcast), or f16 halves when PACKED (material.rs)
@group(1) @binding(4) var<storage, read> weights: array<vec4<u32>>;

struct CornerIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) tangent: vec4<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) tri: vec3<u32>,
    @location(5) corner: u32,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) tangent: vec4<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) u_front: vec4<f32>,
    @location(5) u_back: vec4<f32>,
    @location(6) bary: vec3<f32>,
    @location(7) @interpolate(flat) tri: vec3<u32>,
    // the three vertices' view slots (vs_vertex only; zero from vs_main)
    @location(8) @interpolate(flat) slots0: vec4<u32>,
    @location(9) @interpolate(flat) slots1: vec4<u32>,
    @location(10) @interpolate(flat) slots2: vec4<u32>,
}

fn light_dir(l: u32, world: vec3<f32>) -> vec4<f32> {
    let L = frame.lights[l];
    if (L.pos.w > 0.5) {
        let d = L.pos.xyz - world;
        let d2 = max(dot(d, d), 1e-12);
        return vec4<f32>(d * inverseSqrt(d2), 1.0 / d2);
    }
    return vec4<f32>(normalize(L.pos.xyz), 1.0);
}

@vertex
fn vs_main(v: CornerIn) -> VertexOut {
    return corner_out(v);
}

// The corner-id pass (camera_sides.rs): the three vertex indices of the triangle in front at
// each sample, rasterised by the same vertex stage as the BTF pass.
struct CornerIds {
    @location(0) a: f32,
    @location(1) b: f32,
    @location(2) c: f32,
}

@fragment
fn fs_corner_ids(in: VertexOut) -> CornerIds {
    return CornerIds(f32(in.tri.x), f32(in.tri.y), f32(in.tri.z));
}

fn corner_out(v: CornerIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.tangent = v.tangent;
    out.uv = v.uv;
    out.bary = vec3<f32>(f32(v.corner == 0u), f32(v.corner == 1u), f32(v.corner == 2u));
    out.tri = v.tri;
    // [S03 eq. 6]: u = (1 + cos(α + ∠(n, l))) / 2, for both sides of a two-sided sheet; compiled
    // out where the pass does not apply the smooth boundary (at 128² on the sweep's mesh this
    // per-corner work was 0.25× the read bound of a c = 4 frame)
    if (SHADOWS != 0u && SMOOTH_BOUNDARY) {
        let n = normalize(v.normal);
        let alpha = frame.terminator.x;
        for (var l = 0u; l < frame.info.x; l = l + 1u) {
            let ang = acos(clamp(dot(n, light_dir(l, v.position).xyz), -1.0, 1.0));
            out.u_front[l] = 0.5 * (1.0 + cos(alpha + ang));
            out.u_back[l] = 0.5 * (1.0 + cos(alpha + PI - ang));
        }
    }
    return out;
}

fn shadow_map_visibility(L: LightRaw, world: vec3<f32>) -> f32 {
    let c = L.view_proj * vec4<f32>(world, 1.0);
    let ndc = c.xyz / c.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if (c.w <= 0.0 || any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) || ndc.z > 1.0) {
        return 1.0;
    }
    return pcf(uv, i32(L.shadow.x), ndc.z - L.shadow.z, L.shadow.y);
}

fn pcf(uv: vec2<f32>, layer: i32, depth: f32, texel: f32) -> f32 {
    var sum = 0.0;
    for (var dy = -1; dy <= 1; dy = dy + 1) {
        for (var dx = -1; dx <= 1; dx = dx + 1) {
            let o = vec2<f32>(f32(dx), f32(dy)) * texel;
            sum = sum + textureSampleCompareLevel(shadow_maps, shadow_cmp, uv + o, layer, depth);
        }
    }
    return sum / 9.0;
}

// Cube faces in layer order +x, −x, +y, −y, +z, −z (mirrors shadow_cube.rs).
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1u, 0u, d.x >= 0.0);
    }
    if (a.y >= a.z) {
        return select(3u, 2u, d.y >= 0.0);
    }
    return select(5u, 4u, d.z >= 0.0);
}

fn cube_map_visibility(L: LightRaw, world: vec3<f32>) -> f32 {
    let to_world = world - L.pos.xyz;
    let face = cube_face(to_world);
    let s = select(-1.0, 1.0, face % 2u == 0u);
    var axis = vec3<f32>(0.0, 0.0, s);
    var up = vec3<f32>(0.0, 1.0, 0.0);
    if (face < 2u) {
        axis = vec3<f32>(s, 0.0, 0.0);
    } else if (face < 4u) {
        axis = vec3<f32>(0.0, s, 0.0);
        up = vec3<f32>(0.0, 0.0, 1.0);
    }
    // the face's look-at frame (as math::look_at), receiver moved towards the light by the bias
    let right = normalize(cross(axis, up));
    let up2 = cross(right, axis);
    let d = to_world * (1.0 - L.shadow.z);
    let c = L.view_proj * vec4<f32>(dot(d, right), dot(d, up2), -dot(d, axis), 1.0);
    if (c.w <= 0.0) {
        return 1.0;
    }
    let ndc = c.xyz / c.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    return pcf(uv, i32(L.shadow.x) + i32(face), ndc.z, L.shadow.y);
}

// Visibility of light l at a fragment: smooth boundary (eq. 6) times volume mask or map.
fn visibility(l: u32, in: VertexOut, back: bool) -> f32 {
    if (SHADOWS == 0u) {
        return 1.0;
    }
    let L = frame.lights[l];
    if (L.color.w < 0.5) {
        return 1.0;
    }
    var s = 1.0;
    if (SMOOTH_BOUNDARY && frame.info.y == 1u) {
        var u = in.u_front[l];
        if (back) {
            u = in.u_back[l];
        }
        s = textureSampleLevel(terminator_tex, linear_clamp, vec2<f32>(u, 0.5), 0.0).r;
    }
    if (SHADOWS == 1u || (SHADOWS == 3u && L.color.w < 1.5)) {
        s = s * textureLoad(shadow_masks, vec2<i32>(in.clip.xy), i32(L.shadow.x), 0).r;
    } else if (L.color.w < 2.5) {
        s = s * shadow_map_visibility(L, in.world);
    } else {
        s = s * cube_map_visibility(L, in.world);
    }
    return s;
}

fn to_camera(world: vec3<f32>) -> vec3<f32> {
    if (frame.eye.w > 0.5) {
        return normalize(frame.eye.xyz - world);
    }
    return normalize(frame.to_camera.xyz);
}

fn tex_uv(uv: vec2<f32>) -> vec2<f32> {
    // OBJ v grows upwards, texture rows downwards: row = (1 − v) · h
    return vec2<f32>(uv.x, 1.0 - uv.y) * samplings.params.x;
}

// Tangent frame (T, B, N) with N turned towards the camera (two-sided cloth).
struct Frame3 {
    t: vec3<f32>,
    b: vec3<f32>,
    n: vec3<f32>,
    back: bool,
}

fn tangent_frame(in: VertexOut, v: vec3<f32>) -> Frame3 {
    var n = normalize(in.normal);
    var t = in.tangent.xyz - n * dot(n, in.tangent.xyz);
    if (dot(t, t) < 1e-20) {
        t = cross(n, select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(n.x) > 0.9));
    }
    t = normalize(t);
    let b = cross(n, t) * in.tangent.w;
    let back = dot(n, v) < 0.0;
    if (back) {
        n = -n;
    }
    return Frame3(t, b, n, back);
}

// ---- per-pixel evaluation ----

// per light: weights τ (eq. 3) and e_l; a light that does not reach the fragment keeps
// weight 0 (its indices stay valid rows), so the sums need no compaction
var<private> lw: array<W4, 4>;
var<private> le: array<vec3<f32>, 4>;
// lights in lw / le when they are filled compacted (the transmission pass)
var<private> n_active: u32;
var<private> reads: u32;
// uv derivatives, taken at the entry points (uniform control flow) for mip selection
var<private> duv_dx: vec2<f32>;
var<private> duv_dy: vec2<f32>;

// Fills lw / le; returns whether any light reaches the fragment.
fn gather_lights(in: VertexOut, f: Frame3) -> bool {
    var lit_any = false;
    for (var l = 0u; l < N_LIGHTS; l = l + 1u) {
        let ld = light_dir(l, in.world);
        let a = dir_angles(vec3<f32>(dot(ld.xyz, f.t), dot(ld.xyz, f.b), dot(ld.xyz, f.n)));
        let w = light_weights(a, LIGHT_FOUR);
        let e = frame.lights[l].color.rgb * ld.w * visibility(l, in, f.back);
        let lit = w.n > 0u && any(e != vec3<f32>(0.0));
        lw[l] = W4(w.idx, select(vec4<f32>(0.0), w.w, lit), w.n);
        le[l] = select(vec3<f32>(0.0), e, lit);
        lit_any = lit_any || lit;
    }
    return lit_any;
}

fn combine(acc_a: vec4<f32>, acc_b: vec4<f32>, acc_c: vec4<f32>) -> vec3<f32> {
    return vec3<f32>(
        acc_a.x + acc_a.w + acc_b.z + acc_c.y,
        acc_a.y + acc_b.x + acc_b.w + acc_c.z,
        acc_a.z + acc_b.y + acc_c.x + acc_c.w,
    );
}

// Four components' scalar coefficients γ times an RGB irradiance e, in the three layers'
// order (R G B R | G B R G | B R G B, combine's inverse).
fn spread(gam: vec4<f32>, e: vec3<f32>) -> array<vec4<f32>, 3> {
    return array<vec4<f32>, 3>(
        vec4<f32>(gam.x * e, gam.y * e.r),
        vec4<f32>(gam.y * e.gb, gam.z * e.rg),
        vec4<f32>(gam.z * e.b, gam.w * e),
    );
}

fn group_count() -> u32 {
    return select(samplings.info.x, GROUPS, GROUPS > 0u);
}

// First rows of the weight entries of slot j and the four light samples of `w`.
fn weight_entries(j: u32, w: W4) -> vec4<u32> {
    let g = group_count();
    let stride = select(g + 1u, (4u * g + 8u) / 8u, PACKED);
    return (vec4<u32>(j * samplings.info.y) + w.idx) * stride;
}

// The scaled weights of group g of the entry at row e.
fn gamma_row(e: u32, g: u32) -> vec4<f32> {
    if (PACKED) {
        let q = weights[e + g / 2u];
        let h = select(q.xy, q.zw, (g & 1u) == 1u);
        return vec4<f32>(unpack2x16float(h.x), unpack2x16float(h.y));
    }
    return bitcast<vec4<f32>>(weights[e + g]);
}

// The bias b_ij of the entry at row e (packed: half 4G, in the same load as group G − 1's
// weights when G is odd).
fn bias_of(e: u32) -> f32 {
    let g = group_count();
    if (PACKED) {
        let q = weights[e + g / 2u];
        return unpack2x16float(select(q.x, q.z, (g & 1u) == 1u)).x;
    }
    return bitcast<f32>(weights[e + g].x);
}

// Σ_n τ_n · (group g of entry n) over the light weights (one term for nearest light
// interpolation).
fn tau_sum(w: W4, entries: vec4<u32>, g: u32) -> vec4<f32> {
    var sum = w.w.x * gamma_row(entries.x, g);
    if (LIGHT_FOUR) {
        sum = sum + w.w.y * gamma_row(entries.y, g) + w.w.z * gamma_row(entries.z, g)
            + w.w.w * gamma_row(entries.w, g);
    }
    return sum;
}

// Σ_n τ_n b_{j,i_n}.
fn tau_bias(w: W4, entries: vec4<u32>) -> f32 {
    var sum = w.w.x * bias_of(entries.x);
    if (LIGHT_FOUR) {
        sum = sum + w.w.y * bias_of(entries.y) + w.w.z * bias_of(entries.z) + w.w.w * bias_of(entries.w);
    }
    return sum;
}

fn slot_pixel(j: u32, uv: vec2<f32>) -> vec3<f32> {
    let g_count = group_count();
    var mc = vec3<f32>(0.0);
    var bias = vec3<f32>(0.0);
    // the lights' weight entries for this slot, found once for the bias and every group
    var entries: array<vec4<u32>, 4>;
    for (var a = 0u; a < N_LIGHTS; a = a + 1u) {
        let w = lw[a];
        entries[a] = weight_entries(j, w);
        mc = mc + dot(w.w, vec4<f32>(1.0)) * le[a];
        bias = bias + tau_bias(w, entries[a]) * le[a];
    }
    var col = mc * textureSampleGrad(mean_tex, tex_sampler, uv, j, duv_dx, duv_dy).rgb + bias;
    var acc_a = vec4<f32>(0.0);
    var acc_b = vec4<f32>(0.0);
    var acc_c = vec4<f32>(0.0);
    for (var g = 0u; g < g_count; g = g + 1u) {
        var ca = vec4<f32>(0.0);
        var cb = vec4<f32>(0.0);
        var cc = vec4<f32>(0.0);
        for (var a = 0u; a < N_LIGHTS; a = a + 1u) {
            let c = spread(tau_sum(lw[a], entries[a], g), le[a]);
            ca = ca + c[0];
            cb = cb + c[1];
            cc = cc + c[2];
        }
        let layer = j * 3u * g_count + 3u * g;
        acc_a = acc_a + ca * textureSampleGrad(eigen_tex, tex_sampler, uv, layer, duv_dx, duv_dy);
        acc_b = acc_b + cb * textureSampleGrad(eigen_tex, tex_sampler, uv, layer + 1u, duv_dx, duv_dy);
        acc_c = acc_c + cc * textureSampleGrad(eigen_tex, tex_sampler, uv, layer + 2u, duv_dx, duv_dy);
    }
    reads = reads + 1u + 3u * g_count;
    return col + combine(acc_a, acc_b, acc_c);
}

fn count_reads() {
    if (COUNT_READS) {
        atomicAdd(&counters[0], reads);
        atomicAdd(&counters[1], 1u);
    }
}

// The per-pixel lights' reconstruction at a fragment (eq. 2–5, four-slot view blending).
// Call it first in an entry point: it takes the uv derivatives for mip selection, which
// needs uniform control flow.
fn pixel_lights(in: VertexOut) -> vec3<f32> {
    let v = to_camera(in.world);
    let f = tangent_frame(in, v);
    let uv = tex_uv(in.uv);
    duv_dx = dpdx(uv);
    duv_dy = dpdy(uv);
    reads = 0u;
    let lit = gather_lights(in, f);
    var rgb = vec3<f32>(0.0);
    if (lit) {
        let views = view_weights(dir_angles(vec3<f32>(dot(v, f.t), dot(v, f.b), dot(v, f.n))), VIEW_FOUR);
        for (var m = 0u; m < views.n; m = m + 1u) {
            rgb = rgb + views.w[m] * slot_pixel(views.idx[m], uv);
        }
    }
    return rgb;
}

@fragment
fn fs_pixel(in: VertexOut) -> @location(0) vec4<f32> {
    let rgb = pixel_lights(in);
    count_reads();
    return vec4<f32>(rgb, 1.0);
}
