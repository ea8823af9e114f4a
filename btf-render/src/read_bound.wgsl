// Baseline 2 of the cost sweep: the read bound. Makes the same number and kind of texture
// reads per pixel as the BTF pass for the same settings — filtered reads with explicit
// gradients from the same mean and eigentexture arrays at the same uv, one mean read then
// 3G eigentexture layers per slot — and only sums them, so its time is what the reads alone
// cost. The BTF pass reads whole slots; the bound reads `floor` slots everywhere and one
// more on a hashed fraction `frac` of the pixels, the BTF pass's measured mean. No branch
// picks the texture (lavapipe runs both sides of every branch, which would execute two
// samples per read) and no integer division per read.

struct ReadBound {
    // x: whole slots (floor), y: reads per slot (1 + 3G), z: eigentexture layers, w: mean
    // layers
    counts: vec4<u32>,
    // x: fraction of pixels with one slot more
    frac: vec4<f32>,
}

@group(2) @binding(0) var<uniform> rb: ReadBound;

fn pixel_hash(p: vec2<u32>) -> f32 {
    var h = (p.x * 0x27d4eb2du) ^ ((p.y + 0x165667b1u) * 0x9e3779b9u);
    h = (h ^ (h >> 15u)) * 0x85ebca6bu;
    h = h ^ (h >> 13u);
    return f32(h & 0xffffu) / 65536.0;
}

@fragment
fn fs_read_bound(in: BaseOut) -> @location(0) vec4<f32> {
    let uv = base_uv(in.uv);
    let ddx = dpdx(uv);
    let ddy = dpdy(uv);
    let extra = select(0u, 1u, pixel_hash(vec2<u32>(in.clip.xy)) < rb.frac.x);
    let slots = rb.counts.x + extra;
    let eigen_per_slot = max(rb.counts.y, 1u) - 1u;
    var acc = vec4<f32>(0.0);
    for (var s = 0u; s < slots; s = s + 1u) {
        let mean_layer = min(s, rb.counts.w - 1u);
        acc = acc + textureSampleGrad(mean_tex, tex_sampler, uv, mean_layer, ddx, ddy);
        let first = s * eigen_per_slot;
        for (var r = 0u; r < eigen_per_slot; r = r + 1u) {
            let layer = min(first + r, rb.counts.z - 1u);
            acc = acc + textureSampleGrad(eigen_tex, tex_sampler, uv, layer, ddx, ddy);
        }
    }
    return vec4<f32>(acc.rgb + vec3<f32>(acc.a * 1e-6), 1.0);
}
