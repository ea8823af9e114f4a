// Shows the renderer's linear HDR frame on the window: exposure, clip to [0, 1], sRGB
// encoding in the shader when the surface format does not encode by itself. Nearest texel
// (the frame is drawn at its own size or scaled by the viewport).

struct Params {
    exposure: f32,
    encode_srgb: u32,
    _pad: vec2<f32>,
}

@group(0) @binding(0) var frame_tex: texture_2d<f32>;
@group(0) @binding(1) var<uniform> params: Params;

struct VsOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

// One triangle covering the viewport; uv = (0, 0) at the top left.
@vertex
fn vs(@builtin(vertex_index) i: u32) -> VsOut {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var out: VsOut;
    out.pos = vec4<f32>(uv * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0), 0.0, 1.0);
    out.uv = uv;
    return out;
}

fn srgb(x: f32) -> f32 {
    if x <= 0.0031308 {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs(in: VsOut) -> @location(0) vec4<f32> {
    let dims = textureDimensions(frame_tex);
    let texel = min(vec2<u32>(in.uv * vec2<f32>(dims)), dims - vec2<u32>(1u, 1u));
    let linear = textureLoad(frame_tex, texel, 0).rgb * params.exposure;
    var c = clamp(select(linear, vec3<f32>(0.0), linear != linear), vec3<f32>(0.0), vec3<f32>(1.0));
    if params.encode_srgb == 1u {
        c = vec3<f32>(srgb(c.r), srgb(c.g), srgb(c.b));
    }
    return vec4<f32>(c, 1.0);
}
