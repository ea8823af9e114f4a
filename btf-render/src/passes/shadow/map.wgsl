// Shadow maps: depth of the mesh as seen from a light (orthographic for directional,
// perspective for point lights). The BTF pass compares against it with 3×3 PCF.

struct LightCamera {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> light_camera: LightCamera;

@vertex
fn vs_light(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return light_camera.view_proj * vec4<f32>(position, 1.0);
}
