// Stencil shadow volumes (Crow 1977, z-fail counting) as Sattler et al. 2003 §4.3 use them,
// with one closed prism per triangle so that open cloth meshes stay consistent: a depth
// prepass of the scene, then per light the prisms counted into the stencil buffer where
// they lie behind the visible surface (back faces +1, front faces −1), then a full-screen
// pass writing 0 into the light's mask wherever the count is not zero.

struct Camera {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

@vertex
fn vs_depth(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return camera.view_proj * vec4<f32>(position, 1.0);
}

@vertex
fn vs_volume(@location(0) position: vec4<f32>) -> @builtin(position) vec4<f32> {
    return camera.view_proj * position;
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.5, 1.0);
}

@fragment
fn fs_shadowed() -> @location(0) vec4<f32> {
    return vec4<f32>(0.0);
}
