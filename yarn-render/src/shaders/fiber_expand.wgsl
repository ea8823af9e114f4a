// fiber_expand: every listed fiber instance evaluated at n_sub + 1 points of its segment
// (u = k/n_sub; a hair at its own parameter k/n_sub), written to a storage buffer — the compute alternative to vertex pulling
// of DESIGN §2.4 item 4, and the read-back the CPU = GPU test compares with
// yarn::fiber::FiberModel::fiber_point. One invocation per (instance, point).

struct ExpandParams {
    // Instances, points per instance (n_sub + 1), loops on (1) / off (0), output: 0 fiber
    // points, 1 (frame N, z − z_1), 2 (normalised radius, ψ, φ_ply) — probes for tests.
    counts: vec4<u32>,
}

@group(1) @binding(0) var<uniform> ep: ExpandParams;
@group(1) @binding(1) var<storage, read> instances: array<vec2<u32>>;
@group(1) @binding(2) var<storage, read_write> points: array<vec4<f32>>;

@compute @workgroup_size(64)
fn expand(@builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>) {
    let idx = gid.x + gid.y * nwg.x * 64u;
    let per = ep.counts.y;
    if idx >= ep.counts.x * per {
        return;
    }
    let inst = instances[idx / per];
    let k = idx % per;
    let t = f32(k) / f32(per - 1u);
    let ply = (inst.y >> 16u) & 0xffu;
    let fib = inst.y & 0xffffu;
    let loops = ep.counts.z != 0u;
    switch ep.counts.w {
        case 1u: {
            let yp = yarn_point(inst.x, t);
            points[idx] = vec4<f32>(yp.n, yp.dz);
        }
        case 2u: {
            let yp = yarn_point(inst.x, t);
            let fs = fiber_slot(inst.x, ply, fib, yp.dz, loops);
            points[idx] = vec4<f32>(fs.radius, fs.psi, fs.ply_angle, 0.0);
        }
        default: {
            points[idx] = vec4<f32>(instance_sample(inst, t, loops).pos, 1.0);
        }
    }
}
