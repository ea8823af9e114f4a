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
// Groups of four components (3 eigentexture layers each): a pipeline constant, as in the BTF
// pass, so both run fixed-length group loops of the same three reads.
override GROUPS: u32 = 1u;

fn pixel_hash(p: vec2<u32>) -> f32 {
    var h = (p.x * 0x27d4eb2du) ^ ((p.y + 0x165667b1u) * 0x9e3779b9u);
    h = (h ^ (h >> 15u)) * 0x85ebca6bu;
    h = h ^ (h >> 13u);
    return f32(h & 0xffffu) / 65536.0;
}

struct BoundSetup {
    uv: vec2<f32>,
    ddx: vec2<f32>,
    ddy: vec2<f32>,
    slots: u32,
    eigen_per_slot: u32,
}

fn bound_setup(in: BaseOut) -> BoundSetup {
    let uv = base_uv(in.uv);
    let extra = select(0u, 1u, pixel_hash(vec2<u32>(in.clip.xy)) < rb.frac.x);
    return BoundSetup(uv, dpdx(uv), dpdy(uv), rb.counts.x + extra, max(rb.counts.y, 1u) - 1u);
}

fn bound_colour(acc: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(acc.rgb + vec3<f32>(acc.a * 1e-6), 1.0);
}

// ReadForm::Loop: one eigentexture read per iteration, the count from the uniform.
@fragment
fn fs_read_bound(in: BaseOut) -> @location(0) vec4<f32> {
    let b = bound_setup(in);
    var acc = vec4<f32>(0.0);
    for (var s = 0u; s < b.slots; s = s + 1u) {
        let mean_layer = min(s, rb.counts.w - 1u);
        acc = acc + textureSampleGrad(mean_tex, tex_sampler, b.uv, mean_layer, b.ddx, b.ddy);
        let first = s * b.eigen_per_slot;
        for (var r = 0u; r < b.eigen_per_slot; r = r + 1u) {
            let layer = min(first + r, rb.counts.z - 1u);
            acc = acc + textureSampleGrad(eigen_tex, tex_sampler, b.uv, layer, b.ddx, b.ddy);
        }
    }
    return bound_colour(acc);
}

// ReadForm::Groups: three reads per iteration of a GROUPS-long loop, as the BTF pass does
// when its group count is a pipeline constant.
@fragment
fn fs_read_bound_groups(in: BaseOut) -> @location(0) vec4<f32> {
    let b = bound_setup(in);
    let last = rb.counts.z - 1u;
    var acc = vec4<f32>(0.0);
    for (var s = 0u; s < b.slots; s = s + 1u) {
        let mean_layer = min(s, rb.counts.w - 1u);
        acc = acc + textureSampleGrad(mean_tex, tex_sampler, b.uv, mean_layer, b.ddx, b.ddy);
        let first = s * b.eigen_per_slot;
        for (var g = 0u; g < GROUPS; g = g + 1u) {
            let layer = first + 3u * g;
            acc = acc + textureSampleGrad(eigen_tex, tex_sampler, b.uv, min(layer, last), b.ddx, b.ddy);
            acc = acc + textureSampleGrad(eigen_tex, tex_sampler, b.uv, min(layer + 1u, last), b.ddx, b.ddy);
            acc = acc + textureSampleGrad(eigen_tex, tex_sampler, b.uv, min(layer + 2u, last), b.ddx, b.ddy);
        }
    }
    return bound_colour(acc);
}
