// Baseline 1 of the cost sweep: plain texture mapping of one mean texture on the mesh, the
// cheapest textured frame of the same mesh and resolution (one filtered read per pixel, no
// lighting). Shares the BTF pass's bind groups (frame uniform, material) and vertices; the
// read-bound baseline (read_bound.wgsl) includes this file for its vertex stage and uv.

struct FrameHead {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> frame: FrameHead;
@group(1) @binding(0) var<uniform> samplings: Samplings;
@group(1) @binding(1) var eigen_tex: texture_2d_array<f32>;
@group(1) @binding(2) var mean_tex: texture_2d_array<f32>;
@group(1) @binding(3) var tex_sampler: sampler;

struct BaseIn {
    @location(0) position: vec3<f32>,
    @location(3) uv: vec2<f32>,
}

struct BaseOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_base(v: BaseIn) -> BaseOut {
    var out: BaseOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.uv = v.uv;
    return out;
}

fn base_uv(uv: vec2<f32>) -> vec2<f32> {
    // as tex_uv in btf_pass.wgsl: row = (1 − v) · h, scaled
    return vec2<f32>(uv.x, 1.0 - uv.y) * samplings.params.x;
}

@fragment
fn fs_plain(in: BaseOut) -> @location(0) vec4<f32> {
    let uv = base_uv(in.uv);
    let c = textureSampleGrad(mean_tex, tex_sampler, uv, 0u, dpdx(uv), dpdy(uv));
    return vec4<f32>(c.rgb, 1.0);
}
