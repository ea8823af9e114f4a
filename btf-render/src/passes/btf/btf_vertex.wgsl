// Per-vertex evaluation, appended to interp.wgsl + btf_pass.wgsl: the paper's blending of
// the three vertices' per-vertex reconstructions ([S03 §4.2, eq. 2–5] with the
// coefficients folded per vertex on the CPU, per_vertex.rs), and the environment light's
// per-vertex coefficients ([S03 eq. 11]) added to per-pixel lights.

// per-vertex mode: per (vertex, light, slot m): mean coefficient, bias, 3G coefficient vec4
// f32 vec4s (bitcast), or with GROUPS > 0 f16 halves and a scale per entry; SEPARABLE: the
// scalars [ωΣτ, ωΣτ b], γ per group, f32 or (PACKED) f16 (per_vertex.rs)
@group(2) @binding(0) var<storage, read> vertex_coef: array<vec4<u32>>;
@group(2) @binding(1) var<storage, read> vertex_slots: array<vec4<u32>>;
// SEPARABLE: e_l per (vertex, light), rgb
@group(2) @binding(2) var<storage, read> vertex_irradiance: array<vec4<f32>>;

// vs_main plus the triangle's slot sets for the per-vertex layout: loaded once per corner
// instead of once per fragment (flat varyings cost lavapipe next to nothing per fragment).
@vertex
fn vs_vertex(v: CornerIn) -> VertexOut {
    var out = corner_out(v);
    out.slots0 = vertex_slots[v.tri.x];
    out.slots1 = vertex_slots[v.tri.y];
    out.slots2 = vertex_slots[v.tri.z];
    return out;
}

// ---- per-vertex evaluation (the paper's blending) ----

var<private> vis: vec4<f32>;
// SEPARABLE: vis[l] · e_l of the triangle's vertex k at 4k + l
var<private> virr: array<vec3<f32>, 12>;

// vec4s per (vertex, light, slot) entry of the per-vertex layout (per_vertex.rs)
fn entry_stride() -> u32 {
    let g = frame.info.z;
    if (SEPARABLE) {
        return select(1u + g, (4u + 2u * g) / 4u, PACKED);
    }
    return select(2u + 3u * g, (4u + 6u * g + 3u) / 4u, GROUPS > 0u);
}

// Fills virr for the n_entries lights of the separable layout (once per fragment: the
// lights' irradiance is shared by the vertex's four slots).
fn load_irradiance(in: VertexOut, n_entries: u32) {
    for (var k = 0u; k < 3u; k = k + 1u) {
        for (var l = 0u; l < n_entries; l = l + 1u) {
            virr[4u * k + l] = vis[l] * vertex_irradiance[in.tri[k] * frame.info.w + l].rgb;
        }
    }
}

// A separable entry: h = (ωΣτ, ωΣτ b), gam[g] = group g's ωΣτ γ.
struct ScalarEntry {
    h: vec2<f32>,
    gam: array<vec4<f32>, 4>,
}

// The separable entry at b (GROUPS > 0): f32 vec4s, or packed halves loaded in ⌈(1 + 2G)/4⌉
// vec4s (word 0 the head, words 1 + 2g and 2 + 2g group g).
fn scalar_entry(b: u32) -> ScalarEntry {
    var out: ScalarEntry;
    if (PACKED) {
        var w: array<u32, 12>;
        for (var q = 0u; q < min((4u + 2u * GROUPS) / 4u, 3u); q = q + 1u) {
            let v = vertex_coef[b + q];
            w[4u * q] = v.x;
            w[4u * q + 1u] = v.y;
            w[4u * q + 2u] = v.z;
            w[4u * q + 3u] = v.w;
        }
        out.h = unpack2x16float(w[0]);
        for (var g = 0u; g < min(GROUPS, 4u); g = g + 1u) {
            out.gam[g] = vec4<f32>(unpack2x16float(w[1u + 2u * g]), unpack2x16float(w[2u + 2u * g]));
        }
    } else {
        out.h = bitcast<vec4<f32>>(vertex_coef[b]).xy;
        for (var g = 0u; g < min(GROUPS, 4u); g = g + 1u) {
            out.gam[g] = bitcast<vec4<f32>>(vertex_coef[b + 1u + g]);
        }
    }
    return out;
}

// 1, 2, 4, 8 where `b` holds: the four slots of a vertex as four bits.
fn pack_bits(b: vec4<bool>) -> u32 {
    return dot(select(vec4<u32>(0u), vec4<u32>(1u, 2u, 4u, 8u), b), vec4<u32>(1u));
}

// Per component of `j`: whether `held` holds it.
fn in_set(held: vec4<u32>, j: vec4<u32>) -> vec4<bool> {
    return (j == held.xxxx) | (j == held.yyyy) | (j == held.zzzz) | (j == held.wwww);
}

// Component m of v (v[m] with a computed m, as selects).
fn component(v: vec4<u32>, m: u32) -> u32 {
    return dot(select(vec4<u32>(0u), v, vec4<u32>(m) == vec4<u32>(0u, 1u, 2u, 3u)), vec4<u32>(1u));
}

// The triangle's slot sets, with vertices that weigh nothing at this fragment (barycentric
// ≤ 0) emptied.
struct SlotSets {
    s0: vec4<u32>,
    s1: vec4<u32>,
    s2: vec4<u32>,
}

fn slot_sets(in: VertexOut) -> SlotSets {
    let none = vec4<u32>(NONE);
    return SlotSets(
        select(in.slots0, none, in.bary.x <= 0.0),
        select(in.slots1, none, in.bary.y <= 0.0),
        select(in.slots2, none, in.bary.z <= 0.0),
    );
}

// Bit 4k + m: vertex k's slot m is the first occurrence of its slot (a vertex's own slots
// are distinct, so only an earlier vertex can repeat it). Vector compares, no branches:
// lavapipe runs both sides of every branch, so the shader loops over these bits instead of
// masking twelve candidates.
fn first_occurrences(s: SlotSets) -> u32 {
    let none = vec4<u32>(NONE);
    let f0 = s.s0 != none;
    let f1 = (s.s1 != none) & !in_set(s.s0, s.s1);
    let f2 = (s.s2 != none) & !in_set(s.s0, s.s2) & !in_set(s.s1, s.s2);
    return pack_bits(f0) | (pack_bits(f1) << 4u) | (pack_bits(f2) << 8u);
}

// Σ over the triangle's vertices and the `n_entries` lights of the per-vertex layout, each
// entry weighted by vis[l]: the paper's barycentric blending of per-vertex reconstructions,
// each distinct slot read once. Per slot j, its members are the vertices holding it (bit k
// of `members`) at coefficient offset base[k] (light 0; light l adds l·4·stride).
fn vertex_sum(in: VertexOut, uv: vec2<f32>, n_entries: u32) -> vec3<f32> {
    let g_count = group_count();
    let stride = entry_stride();
    let light_step = 4u * stride;
    let s = slot_sets(in);
    var todo = first_occurrences(s);
    var rgb = vec3<f32>(0.0);
    loop {
        if (todo == 0u) {
            break;
        }
        let e = firstTrailingBit(todo);
        todo = todo & (todo - 1u);
        let k_first = e / 4u;
        let j = component(select(select(s.s2, s.s1, k_first == 1u), s.s0, k_first == 0u), e % 4u);
        let jv = vec4<u32>(j);
        let hit = vec3<u32>(pack_bits(s.s0 == jv), pack_bits(s.s1 == jv), pack_bits(s.s2 == jv));
        let members = pack_bits(vec4<bool>(hit != vec3<u32>(0u), false));
        // slot index m of each member = trailing bit of its hit mask
        let base = ((in.tri * frame.info.w) * 4u + firstTrailingBit(hit)) * stride;
        if (GROUPS > 0u) {
            rgb = rgb + slot_fixed(in, uv, j, members, base, n_entries, light_step);
        } else {
            rgb = rgb + slot_looped(in, uv, j, members, base, n_entries, light_step);
        }
        reads = reads + 1u + 3u * g_count;
    }
    return rgb;
}

// One slot j of vertex_sum with a run-time group count: the members are visited once for
// the mean and bias and once per group.
fn slot_looped(in: VertexOut, uv: vec2<f32>, j: u32, members: u32, base: vec3<u32>, n_entries: u32, light_step: u32) -> vec3<f32> {
    let g_count = group_count();
    var mc = vec3<f32>(0.0);
    var bias = vec3<f32>(0.0);
    var todo_m = members;
    loop {
        if (todo_m == 0u) {
            break;
        }
        let k = firstTrailingBit(todo_m);
        todo_m = todo_m & (todo_m - 1u);
        for (var l = 0u; l < n_entries; l = l + 1u) {
            let b = base[k] + l * light_step;
            if (SEPARABLE) {
                let e = in.bary[k] * virr[4u * k + l];
                let h = bitcast<vec4<f32>>(vertex_coef[b]).xy;
                mc = mc + h.x * e;
                bias = bias + h.y * e;
            } else {
                let w = in.bary[k] * vis[l];
                mc = mc + w * bitcast<vec4<f32>>(vertex_coef[b]).rgb;
                bias = bias + w * bitcast<vec4<f32>>(vertex_coef[b + 1u]).rgb;
            }
        }
    }
    var col = mc * textureSampleGrad(mean_tex, tex_sampler, uv, j, duv_dx, duv_dy).rgb + bias;
    var acc_a = vec4<f32>(0.0);
    var acc_b = vec4<f32>(0.0);
    var acc_c = vec4<f32>(0.0);
    for (var g = 0u; g < g_count; g = g + 1u) {
        var ca = vec4<f32>(0.0);
        var cb = vec4<f32>(0.0);
        var cc = vec4<f32>(0.0);
        var todo_g = members;
        loop {
            if (todo_g == 0u) {
                break;
            }
            let k = firstTrailingBit(todo_g);
            todo_g = todo_g & (todo_g - 1u);
            for (var l = 0u; l < n_entries; l = l + 1u) {
                if (SEPARABLE) {
                    let e = in.bary[k] * virr[4u * k + l];
                    let c = spread(bitcast<vec4<f32>>(vertex_coef[base[k] + l * light_step + 1u + g]), e);
                    ca = ca + c[0];
                    cb = cb + c[1];
                    cc = cc + c[2];
                } else {
                    let w = in.bary[k] * vis[l];
                    let b = base[k] + l * light_step + 2u + 3u * g;
                    ca = ca + w * bitcast<vec4<f32>>(vertex_coef[b]);
                    cb = cb + w * bitcast<vec4<f32>>(vertex_coef[b + 1u]);
                    cc = cc + w * bitcast<vec4<f32>>(vertex_coef[b + 2u]);
                }
            }
        }
        let layer = j * 3u * g_count + 3u * g;
        acc_a = acc_a + ca * textureSampleGrad(eigen_tex, tex_sampler, uv, layer, duv_dx, duv_dy);
        acc_b = acc_b + cb * textureSampleGrad(eigen_tex, tex_sampler, uv, layer + 1u, duv_dx, duv_dy);
        acc_c = acc_c + cc * textureSampleGrad(eigen_tex, tex_sampler, uv, layer + 2u, duv_dx, duv_dy);
    }
    return col + combine(acc_a, acc_b, acc_c);
}

// The 12 coefficients of group g of the packed entry at b (per_vertex::pack_f16): six u32
// from word 4 + 6g on, over two loads (groups 2k and 2k + 1 share the middle one).
fn group_coefficients(b: u32, g: u32) -> array<vec4<f32>, 3> {
    let first = b + 1u + (3u * g) / 2u;
    let q0 = vertex_coef[first];
    let q1 = vertex_coef[first + 1u];
    var u: array<u32, 6>;
    if ((g & 1u) == 0u) {
        u = array<u32, 6>(q0.x, q0.y, q0.z, q0.w, q1.x, q1.y);
    } else {
        u = array<u32, 6>(q0.z, q0.w, q1.x, q1.y, q1.z, q1.w);
    }
    return array<vec4<f32>, 3>(
        vec4<f32>(unpack2x16float(u[0]), unpack2x16float(u[1])),
        vec4<f32>(unpack2x16float(u[2]), unpack2x16float(u[3])),
        vec4<f32>(unpack2x16float(u[4]), unpack2x16float(u[5])),
    );
}

// The (vertex k, light l) entry at b of the per-vertex layout (GROUPS > 0), weighted by the
// vertex's barycentric and the light's visibility: mean coefficient, bias and each group's
// three coefficient vec4 (separable: the scalars spread over vis·e_l; else the packed full
// layout times its scale).
struct EntryTerms {
    mean: vec3<f32>,
    bias: vec3<f32>,
    a: array<vec4<f32>, 4>,
    b: array<vec4<f32>, 4>,
    c: array<vec4<f32>, 4>,
}

fn entry_terms(in: VertexOut, b: u32, k: u32, l: u32) -> EntryTerms {
    var t: EntryTerms;
    if (SEPARABLE) {
        let e = in.bary[k] * virr[4u * k + l];
        let s = scalar_entry(b);
        t.mean = s.h.x * e;
        t.bias = s.h.y * e;
        for (var g = 0u; g < min(GROUPS, 4u); g = g + 1u) {
            let c = spread(s.gam[g], e);
            t.a[g] = c[0];
            t.b[g] = c[1];
            t.c[g] = c[2];
        }
    } else {
        let head = vertex_coef[b];
        let w = in.bary[k] * vis[l] * bitcast<f32>(head.x);
        t.mean = w * vec3<f32>(unpack2x16float(head.y), unpack2x16float(head.z).x);
        t.bias = w * vec3<f32>(unpack2x16float(head.z).y, unpack2x16float(head.w));
        for (var g = 0u; g < min(GROUPS, 4u); g = g + 1u) {
            let c = group_coefficients(b, g);
            t.a[g] = w * c[0];
            t.b[g] = w * c[1];
            t.c[g] = w * c[2];
        }
    }
    return t;
}

// slot_looped with the group count a pipeline constant (GROUPS ≤ 4): the members are visited
// once, summing every group's coefficients into registers, then the slot's layers are read.
// At c = 8 this took per-vertex four blending from 1.8–2.1× to 1.6–1.7× the read bound.
fn slot_fixed(in: VertexOut, uv: vec2<f32>, j: u32, members: u32, base: vec3<u32>, n_entries: u32, light_step: u32) -> vec3<f32> {
    var mc = vec3<f32>(0.0);
    var bias = vec3<f32>(0.0);
    var ca: array<vec4<f32>, 4>;
    var cb: array<vec4<f32>, 4>;
    var cc: array<vec4<f32>, 4>;
    var todo_m = members;
    loop {
        if (todo_m == 0u) {
            break;
        }
        let k = firstTrailingBit(todo_m);
        todo_m = todo_m & (todo_m - 1u);
        for (var l = 0u; l < n_entries; l = l + 1u) {
            let t = entry_terms(in, base[k] + l * light_step, k, l);
            mc = mc + t.mean;
            bias = bias + t.bias;
            for (var g = 0u; g < min(GROUPS, 4u); g = g + 1u) {
                ca[g] = ca[g] + t.a[g];
                cb[g] = cb[g] + t.b[g];
                cc[g] = cc[g] + t.c[g];
            }
        }
    }
    let col = mc * textureSampleGrad(mean_tex, tex_sampler, uv, j, duv_dx, duv_dy).rgb + bias;
    var acc_a = vec4<f32>(0.0);
    var acc_b = vec4<f32>(0.0);
    var acc_c = vec4<f32>(0.0);
    for (var g = 0u; g < min(GROUPS, 4u); g = g + 1u) {
        let layer = (j * GROUPS + g) * 3u;
        acc_a = acc_a + ca[g] * textureSampleGrad(eigen_tex, tex_sampler, uv, layer, duv_dx, duv_dy);
        acc_b = acc_b + cb[g] * textureSampleGrad(eigen_tex, tex_sampler, uv, layer + 1u, duv_dx, duv_dy);
        acc_c = acc_c + cc[g] * textureSampleGrad(eigen_tex, tex_sampler, uv, layer + 2u, duv_dx, duv_dy);
    }
    return col + combine(acc_a, acc_b, acc_c);
}

// Per-vertex mode: every light (an environment light included) is in the per-vertex
// layout, frame.info.w = frame.info.x entries.
@fragment
fn fs_vertex(in: VertexOut) -> @location(0) vec4<f32> {
    let v = to_camera(in.world);
    let f = tangent_frame(in, v);
    let uv = tex_uv(in.uv);
    duv_dx = dpdx(uv);
    duv_dy = dpdy(uv);
    for (var l = 0u; l < N_LIGHTS; l = l + 1u) {
        vis[l] = visibility(l, in, f.back);
    }
    if (SEPARABLE) {
        load_irradiance(in, N_LIGHTS);
    }
    reads = 0u;
    let rgb = vertex_sum(in, uv, N_LIGHTS);
    count_reads();
    return vec4<f32>(rgb, 1.0);
}

// Per-pixel mode with an environment light: point/directional lights per pixel (the
// environment's frame light has zero power), plus the environment's per-vertex
// coefficients, the only entry of the per-vertex layout (frame.info.w = 1).
@fragment
fn fs_pixel_env(in: VertexOut) -> @location(0) vec4<f32> {
    var rgb = pixel_lights(in);
    vis[0] = 1.0;
    rgb = rgb + vertex_sum(in, tex_uv(in.uv), 1u);
    count_reads();
    return vec4<f32>(rgb, 1.0);
}
