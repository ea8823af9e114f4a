// Baseline 2 of the cost sweep: the read bound. Makes the same number and kind of texture
// reads per pixel as the BTF pass for the same settings — filtered reads with explicit
// gradients from the same mean and eigentexture arrays at the same uv, one mean read then
// 3G eigentexture layers per slot — and only sums them, so its time is what the reads alone
// cost. The count is the BTF pass's measured mean: `floor` reads everywhere and one more
// on a hashed fraction `frac` of the pixels.

struct ReadBound {
    // x: reads (floor), y: reads per slot (1 + 3G), z: eigentexture layers, w: mean layers
    counts: vec4<u32>,
    // x: fraction of pixels with one read more
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
    var n = rb.counts.x;
    if (pixel_hash(vec2<u32>(in.clip.xy)) < rb.frac.x) {
        n = n + 1u;
    }
    let per_slot = max(rb.counts.y, 1u);
    var acc = vec4<f32>(0.0);
    for (var i = 0u; i < n; i = i + 1u) {
        let slot = i / per_slot;
        let r = i % per_slot;
        if (r == 0u) {
            acc = acc + textureSampleGrad(mean_tex, tex_sampler, uv, slot % rb.counts.w, ddx, ddy);
        } else {
            let layer = (slot * (per_slot - 1u) + r - 1u) % rb.counts.z;
            acc = acc + textureSampleGrad(eigen_tex, tex_sampler, uv, layer, ddx, ddy);
        }
    }
    return vec4<f32>(acc.rgb + vec3<f32>(acc.a * 1e-6), 1.0);
}
