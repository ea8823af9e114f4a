// Marks every vertex index found in the three corner-id targets (corner_ids/mod.rs): per
// pixel and sample, the front triangle's three vertices (ids < 0: nothing drawn there).
// One entry point per target kind, so that no shader text is generated: `mark` reads
// single-sampled targets, `mark_multisampled` SAMPLES samples of multisampled ones (the two
// sets of textures share bindings 0–2; each entry point uses only its own).

override SAMPLES: u32 = 4u;

@group(0) @binding(0) var ids_a: texture_2d<f32>;
@group(0) @binding(1) var ids_b: texture_2d<f32>;
@group(0) @binding(2) var ids_c: texture_2d<f32>;
@group(0) @binding(0) var ids_a_ms: texture_multisampled_2d<f32>;
@group(0) @binding(1) var ids_b_ms: texture_multisampled_2d<f32>;
@group(0) @binding(2) var ids_c_ms: texture_multisampled_2d<f32>;
@group(0) @binding(3) var<storage, read_write> seen: array<atomic<u32>>;

fn mark_triangle(a: f32, b: f32, c: f32) {
    if (a >= 0.0) {
        atomicStore(&seen[u32(a)], 1u);
        atomicStore(&seen[u32(b)], 1u);
        atomicStore(&seen[u32(c)], 1u);
    }
}

@compute @workgroup_size(8, 8)
fn mark(@builtin(global_invocation_id) g: vec3<u32>) {
    let size = textureDimensions(ids_a);
    if (g.x >= size.x || g.y >= size.y) {
        return;
    }
    let p = vec2<i32>(g.xy);
    mark_triangle(
        textureLoad(ids_a, p, 0).x,
        textureLoad(ids_b, p, 0).x,
        textureLoad(ids_c, p, 0).x
    );
}

@compute @workgroup_size(8, 8)
fn mark_multisampled(@builtin(global_invocation_id) g: vec3<u32>) {
    let size = textureDimensions(ids_a_ms);
    if (g.x >= size.x || g.y >= size.y) {
        return;
    }
    let p = vec2<i32>(g.xy);
    for (var s = 0u; s < SAMPLES; s = s + 1u) {
        mark_triangle(
            textureLoad(ids_a_ms, p, i32(s)).x,
            textureLoad(ids_b_ms, p, i32(s)).x,
            textureLoad(ids_c_ms, p, i32(s)).x
        );
    }
}
