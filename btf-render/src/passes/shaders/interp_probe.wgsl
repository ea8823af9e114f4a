// Test probe: evaluates interp.wgsl's view and light weights for a list of tangent-space
// directions so that they can be compared with btf_core::interp on the CPU.

@group(0) @binding(0) var<uniform> samplings: Samplings;
@group(0) @binding(1) var<storage, read> dirs: array<vec4<f32>>;
// per direction: view four, view nearest, light four, light nearest; each idx vec4 + w vec4
@group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;

fn put(base: u32, w: W4) {
    out[base] = bitcast<vec4<f32>>(w.idx);
    var ww = w.w;
    for (var k = w.n; k < 4u; k = k + 1u) {
        ww[k] = 0.0;
    }
    out[base + 1u] = ww;
}

@compute @workgroup_size(64)
fn probe(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&dirs)) {
        return;
    }
    let a = dir_angles(dirs[i].xyz);
    put(i * 8u, view_weights(a, true));
    put(i * 8u + 2u, view_weights(a, false));
    put(i * 8u + 4u, light_weights(a, true));
    put(i * 8u + 6u, light_weights(a, false));
}
