
// ---- Thin semi-transparent cloth (transmission/mod.rs; [TC eq. 7–9]) ----
// Appended to interp.wgsl + btf_pass.wgsl + btf_vertex.wgsl; reuses vs_main / vs_vertex,
// tangent_frame, slot_pixel, vertex_sum.
// Output: rgb = Σ_front share(τ, μ, μ₀) · BTF · E  +  Σ_back ϖ₀ p/(4π) · F_t(τ, μ, μ₀) · μ₀ · E,
// alpha = e^{−τ/μ}; blended as L = L_dst · alpha + L_src ([TC eq. 9]).

struct ThinRaw {
    // x: τ₁ (scale of the texture), y: Henyey–Greenstein g, z: 1 = τ texture bound,
    // w: the environment's entry in the per-vertex layout
    params: vec4<f32>,
    // rgb: single-scattering albedo ϖ₀, w: τ_max, the scale of the environment's τ nodes
    albedo: vec4<f32>,
}

@group(3) @binding(0) var<uniform> thin: ThinRaw;
@group(3) @binding(1) var tau_tex: texture_2d<f32>;
// Per vertex, side (0 = +N, 1 = −N) and τ node τ_j = τ_max (j/7)²: A_s, then T_s(μ_k) at
// μ_k = (k/15)² (env.rs).
@group(3) @binding(2) var<storage, read> thin_env: array<vec4<f32>>;

const THIN_MIN_COS: f32 = 1e-4;

// φ₁(x) = (1 − e^{−x})/x, by its series below 0.1 (truncation < x⁵/720 ≈ 1.4e-8).
fn thin_phi1(x: f32) -> f32 {
    if (x < 0.1) {
        return 1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x / 120.0)));
    }
    return (1.0 - exp(-x)) / x;
}

// f_r(τ) / f_r(∞) = 1 − e^{−τ(1/μ + 1/μ₀)}, without cancellation for small τ.
fn thin_reflection_share(tau: f32, mu: f32, mu0: f32) -> f32 {
    let x = tau / mu + tau / mu0;
    return x * thin_phi1(x);
}

// [e^{−τ/μ} − e^{−τ/μ₀}] / (μ − μ₀), the removable singularity at μ = μ₀ by the series.
fn thin_transmission_factor(tau: f32, mu: f32, mu0: f32) -> f32 {
    let a = tau / mu;
    let b = tau / mu0;
    let d = tau * abs(mu0 - mu) / (mu * mu0);
    if (d > 1.0) {
        return (exp(-a) - exp(-b)) / (mu - mu0);
    }
    return a * exp(-min(a, b)) / mu0 * thin_phi1(d);
}

fn thin_phase(cos_scatter: f32) -> f32 {
    let g = thin.params.y;
    if (abs(g) < 1e-4) {
        return 1.0;
    }
    let d = max(1.0 + g * g - 2.0 * g * cos_scatter, 1e-6);
    return (1.0 - g * g) / (d * sqrt(d));
}

fn thin_tau(uv: vec2<f32>) -> f32 {
    if (thin.params.z > 0.5) {
        return thin.params.x * textureSampleLevel(tau_tex, tex_sampler, uv, 0.0).r;
    }
    return thin.params.x;
}

// gather_lights of the BTF pass with each front light's irradiance scaled by the share of
// the thick-cloth reflection that a slab of thickness τ reflects.
fn gather_lights_thin(in: VertexOut, f: Frame3, tau: f32, mu: f32) {
    n_active = 0u;
    for (var l = 0u; l < frame.info.x; l = l + 1u) {
        let ld = light_dir(l, in.world);
        let a = dir_angles(vec3<f32>(dot(ld.xyz, f.t), dot(ld.xyz, f.b), dot(ld.xyz, f.n)));
        let w = light_weights(a, LIGHT_FOUR);
        if (w.n == 0u) {
            continue;
        }
        let mu0 = max(dot(ld.xyz, f.n), THIN_MIN_COS);
        let share = thin_reflection_share(tau, mu, mu0);
        let e = frame.lights[l].color.rgb * ld.w * visibility(l, in, f.back) * share;
        if (all(e == vec3<f32>(0.0))) {
            continue;
        }
        lw[n_active] = w;
        le[n_active] = e;
        n_active = n_active + 1u;
    }
}

// Shadowing of the transmitted light: shadow maps only (a shadow-volume mask belongs to
// the nearest surface of the pixel and the cloth's own prisms; the eq. 6 boundary would
// remove exactly the back-lit light we want).
fn thin_back_visibility(l: u32, in: VertexOut) -> f32 {
    let L = frame.lights[l];
    if (L.color.w > 1.5) {
        return shadow_map_visibility(L, in.world);
    }
    return 1.0;
}

fn thin_transmitted(in: VertexOut, f: Frame3, v: vec3<f32>, tau: f32, mu: f32) -> vec3<f32> {
    var rgb = vec3<f32>(0.0);
    for (var l = 0u; l < frame.info.x; l = l + 1u) {
        let ld = light_dir(l, in.world);
        let mu0 = -dot(ld.xyz, f.n);
        if (mu0 <= 0.0) {
            continue;
        }
        // cos Θ = −l·v: the beam travels along −l and leaves towards v.
        let k = thin_phase(-dot(ld.xyz, v)) / (4.0 * PI)
            * thin_transmission_factor(tau, mu, max(mu0, THIN_MIN_COS)) * mu0;
        rgb = rgb + k * thin_back_visibility(l, in) * frame.lights[l].color.rgb * ld.w;
    }
    return thin.albedo.rgb * rgb;
}

// What both thin fragment shaders compute: the fragment's frame, view cosine and τ, and
// the point and directional lights' reflected share of the BTF plus their transmitted term.
struct ThinShade {
    f: Frame3,
    uv: vec2<f32>,
    mu: f32,
    tau: f32,
    rgb: vec3<f32>,
}

// Called first thing in an entry point: the uv derivatives for the BTF's mip selection
// (slot_pixel) must be taken in uniform control flow.
fn thin_shade(in: VertexOut) -> ThinShade {
    let v = to_camera(in.world);
    let f = tangent_frame(in, v);
    let uv = tex_uv(in.uv);
    duv_dx = dpdx(uv);
    duv_dy = dpdy(uv);
    let mu = max(dot(v, f.n), THIN_MIN_COS);
    let tau = thin_tau(uv);
    reads = 0u;
    gather_lights_thin(in, f, tau, mu);
    var rgb = vec3<f32>(0.0);
    if (n_active > 0u) {
        let views = view_weights(dir_angles(vec3<f32>(dot(v, f.t), dot(v, f.b), dot(v, f.n))), VIEW_FOUR);
        for (var m = 0u; m < views.n; m = m + 1u) {
            rgb = rgb + views.w[m] * slot_pixel(views.idx[m], uv);
        }
    }
    rgb = rgb + thin_transmitted(in, f, v, tau, mu);
    return ThinShade(f, uv, mu, tau, rgb);
}

@fragment
fn fs_thin(in: VertexOut) -> @location(0) vec4<f32> {
    let s = thin_shade(in);
    count_reads();
    return vec4<f32>(s.rgb, exp(-s.tau / s.mu));
}

// ---- environment light on thin cloth (transmission/env.rs) ----

const THIN_MU_NODES: u32 = 16u;
const THIN_TAU_NODES: u32 = 8u;

fn thin_env_row(vtx: u32, side: u32, j: u32, i: u32) -> vec3<f32> {
    return thin_env[((vtx * 2u + side) * THIN_TAU_NODES + j) * (1u + THIN_MU_NODES) + i].rgb;
}

// The τ nodes around tau and the weight of the upper one (linear in τ); a scalar τ reads
// the last node alone (env.rs tau_weights).
fn thin_tau_nodes(tau: f32) -> vec3<f32> {
    let last = THIN_TAU_NODES - 1u;
    let scale = thin.albedo.w;
    if (thin.params.z < 0.5 || scale <= 0.0) {
        return vec3<f32>(f32(last), f32(last), 0.0);
    }
    let u = sqrt(clamp(tau / scale, 0.0, 1.0)) * f32(last);
    let j = min(u32(floor(u)), last - 1u);
    let s0 = f32(j) / f32(last);
    let s1 = f32(j + 1u) / f32(last);
    let t0 = scale * s0 * s0;
    let t1 = scale * s1 * s1;
    return vec3<f32>(f32(j), f32(j + 1u), clamp((tau - t0) / (t1 - t0), 0.0, 1.0));
}

// Barycentric blend of the three vertices' A (eye side) and T(μ) (far side), bilinear in
// (√μ, τ).
fn thin_env_terms(in: VertexOut, f: Frame3, mu: f32, tau: f32) -> array<vec3<f32>, 2> {
    let eye = select(0u, 1u, f.back);
    let far = 1u - eye;
    let u = sqrt(clamp(mu, 0.0, 1.0)) * f32(THIN_MU_NODES - 1u);
    let k = min(u32(floor(u)), THIN_MU_NODES - 2u);
    let t = u - f32(k);
    let nodes = thin_tau_nodes(tau);
    let j0 = u32(nodes.x);
    let j1 = u32(nodes.y);
    let w = nodes.z;
    var a = vec3<f32>(0.0);
    var tr = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c = c + 1u) {
        let vtx = in.tri[c];
        let a_c = mix(thin_env_row(vtx, eye, j0, 0u), thin_env_row(vtx, eye, j1, 0u), w);
        let t0 = mix(thin_env_row(vtx, far, j0, 1u + k), thin_env_row(vtx, far, j0, 2u + k), t);
        let t1 = mix(thin_env_row(vtx, far, j1, 1u + k), thin_env_row(vtx, far, j1, 2u + k), t);
        a = a + in.bary[c] * a_c;
        tr = tr + in.bary[c] * mix(t0, t1, w);
    }
    return array<vec3<f32>, 2>(a, tr);
}

// fs_thin plus the environment: its BTF term (the per-vertex coefficients, entry
// thin.params.w alone) scaled by 1 − e^{−τ/μ}·A, and the transmitted T(μ).
@fragment
fn fs_thin_env(in: VertexOut) -> @location(0) vec4<f32> {
    let s = thin_shade(in);
    let entry = u32(thin.params.w);
    for (var l = 0u; l < 4u; l = l + 1u) {
        vis[l] = select(0.0, 1.0, l == entry);
    }
    let terms = thin_env_terms(in, s.f, s.mu, s.tau);
    let share = vec3<f32>(1.0) - exp(-s.tau / s.mu) * terms[0];
    let rgb = s.rgb + share * vertex_sum(in, s.uv, frame.info.w) + terms[1];
    count_reads();
    return vec4<f32>(rgb, exp(-s.tau / s.mu));
}
