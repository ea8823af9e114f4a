// The environment map behind the scene (`[output] show_environment`): per pixel, the
// radiance f · L_env(R_{−δ} ω) of the camera ray's world direction ω, with the environment
// light's rotation δ about +z and exposure f — the map, turned the same way, that lights
// the scene. A full-screen triangle; the map is read with textureLoad and filtered
// bilinearly here, as the CPU reference does (rows θ from +z, columns φ from +x towards
// +y, wrapping in φ), so any float format and any sample count work.

const PI: f32 = 3.14159265358979;

struct Background {
    // clip → world of the camera
    inv_view_proj: mat4x4<f32>,
    // x, y: frame size in pixels; z: exposure f
    frame: vec4<f32>,
    // x: cos δ, y: sin δ
    rotation: vec4<f32>,
}

@group(0) @binding(0) var<uniform> bg: Background;
@group(0) @binding(1) var env_map: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

fn unproject(n: vec2<f32>, z: f32) -> vec3<f32> {
    let p = bg.inv_view_proj * vec4<f32>(n, z, 1.0);
    return p.xyz / p.w;
}

fn texel(col: f32, row: f32, dims: vec2<u32>) -> vec3<f32> {
    let w = i32(dims.x);
    let c = ((i32(col) % w) + w) % w;
    let r = min(u32(row), dims.y - 1u);
    return textureLoad(env_map, vec2<i32>(c, i32(r)), 0).rgb;
}

// Bilinear radiance of the map in world direction d (unit).
fn radiance(d: vec3<f32>) -> vec3<f32> {
    let dims = textureDimensions(env_map);
    let w = f32(dims.x);
    let h = f32(dims.y);
    let theta = acos(clamp(d.z, -1.0, 1.0));
    var phi = atan2(d.y, d.x);
    if (phi < 0.0) {
        phi = phi + 2.0 * PI;
    }
    let u = phi / (2.0 * PI) * w - 0.5;
    let v = clamp(theta / PI * h - 0.5, 0.0, h - 1.0);
    let c0 = floor(u);
    let r0 = floor(v);
    let fu = u - c0;
    let fv = v - r0;
    var out = (1.0 - fu) * (1.0 - fv) * texel(c0, r0, dims);
    out = out + fu * (1.0 - fv) * texel(c0 + 1.0, r0, dims);
    out = out + (1.0 - fu) * fv * texel(c0, r0 + 1.0, dims);
    out = out + fu * fv * texel(c0 + 1.0, r0 + 1.0, dims);
    return out;
}

@fragment
fn fs_background(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let n = vec2<f32>(pos.x / bg.frame.x * 2.0 - 1.0, 1.0 - pos.y / bg.frame.y * 2.0);
    let ray = unproject(n, 0.75) - unproject(n, 0.25);
    let len = length(ray);
    var d = vec3<f32>(0.0, 0.0, 1.0);
    if (len > 0.0) {
        d = ray / len;
    }
    // the environment turned by δ: world direction ω sees the map at R_{−δ} ω
    let c = bg.rotation.x;
    let s = bg.rotation.y;
    let e = vec3<f32>(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);
    return vec4<f32>(bg.frame.z * radiance(e), 1.0);
}
