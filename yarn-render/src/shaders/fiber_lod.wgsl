// fiber_lod (compute, one invocation per yarn segment): conservative culling on the hull
// of the segment's Bézier points inflated by the fiber reach (DESIGN §2.3 item 8: the
// Catmull–Rom control points themselves do not bound the curve), then the level of detail
// λ of [W19 eq. 4] from the projected fiber and ply widths at the segment midpoint, the
// fiber count n = max(1, round(λ²·n_max)) per ply — the outermost n by R_i, since the
// table is sorted and [W19 §5] drops fibers from the ply centre outwards — and the
// subdivisions max(2, ceil(λ²·n_sub)) (DESIGN §2.3 item 7, the count formula eq. 4 lacks).
// Instances are appended to a compact list and counted into the indirect draw's
// instance_count.

struct DrawArgs {
    vertex_count: u32,
    instance_count: atomic<u32>,
    first_vertex: u32,
    first_instance: u32,
    // Instances that did not fit into the list (reported, never drawn).
    overflow: atomic<u32>,
    // Segments culled.
    culled: atomic<u32>,
}

@group(1) @binding(0) var<uniform> view: View;
@group(1) @binding(1) var<storage, read_write> out_instances: array<vec2<u32>>;
@group(1) @binding(2) var<storage, read_write> args: DrawArgs;

// [W19 eq. 4]: 1 when the fiber is at least ω^LoD wide, 0 when the ply is at most, and in
// between (ω_f/ω_L)(ω_p − ω_L)/(ω_p − ω_f). Mirrored by lod::lambda.
fn lod_lambda(w_fiber: f32, w_ply: f32, w_lod: f32) -> f32 {
    if w_lod <= 0.0 || w_lod <= w_fiber {
        return 1.0;
    }
    if w_ply <= w_lod {
        return 0.0;
    }
    return clamp((w_fiber / w_lod) * (w_ply - w_lod) / (w_ply - w_fiber), 0.0, 1.0);
}

fn outside(p: vec3<f32>, plane: vec4<f32>, reach: f32) -> bool {
    return dot(plane.xyz, p) + plane.w < -reach;
}

@compute @workgroup_size(64)
fn lod(@builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>) {
    let seg = gid.x + gid.y * nwg.x * 64u;
    if seg >= arrayLength(&segments) || seg >= view.counts.z {
        return;
    }
    let s = segments[seg];
    let c = curves[s.ids.x];
    let pr = yarn_params[c.ids.x];
    if (view.lod.z & 1u) != 0u {
        // The segment's Bézier points; the curve lies in their convex hull.
        let b0 = s.p[1].xyz;
        let b1 = s.p[1].xyz + (s.p[2].xyz - s.p[0].xyz) / 6.0;
        let b2 = s.p[2].xyz - (s.p[3].xyz - s.p[1].xyz) / 6.0;
        let b3 = s.p[2].xyz;
        // Fiber reach (flyaways included) plus f32 slack.
        let reach = pr.c.w * 1.001 + 1e-7 * c.frame.z;
        for (var i = 0u; i < 6u; i++) {
            let pl = view.planes[i];
            if outside(b0, pl, reach) && outside(b1, pl, reach) && outside(b2, pl, reach)
                && outside(b3, pl, reach) {
                atomicAdd(&args.culled, 1u);
                return;
            }
        }
    }
    if (view.lod.z & 8u) != 0u {
        // Plain tubes (the baseline of DESIGN §2.5): one strip of the yarn's diameter per
        // segment, at full subdivision; fiber index 0xffff marks it.
        let k = atomicAdd(&args.instance_count, 1u);
        if k < view.lod.w {
            out_instances[k] = vec2<u32>(seg, 0xffffu | (view.lod.y << 24u));
        } else {
            atomicAdd(&args.overflow, 1u);
        }
        return;
    }
    let mid = combine(s, cr_basis(0.5));
    let w_fiber = pixels_of(view, 2.0 * pr.b.y, mid);
    let ply_radius = max(pr.a.y, pr.a.z) * pr.b.x;
    let w_ply = pixels_of(view, 2.0 * ply_radius, mid);
    let lambda = lod_lambda(w_fiber, w_ply, view.viewport.w);
    let l2 = lambda * lambda;
    let n_fib = pr.d.y;
    // Core mode [W19 §3.2]: one textured core strip per ply stands for the innermost
    // pr.d.z fibers; the regular fibers are the rest, and may all be dropped.
    let core = select(0u, pr.d.z, (view.lod.z & 128u) != 0u);
    let first = core;
    let n_max = min(view.lod.x, n_fib - first);
    var n = clamp(u32(round(l2 * f32(n_max))), 1u, max(n_max, 1u));
    if core > 0u {
        n = min(u32(round(l2 * f32(n_max))), n_max);
    }
    let n_sub = clamp(u32(ceil(l2 * f32(view.lod.y))), 2u, view.lod.y);
    let n_ply = pr.d.x;
    let per_ply = n + select(0u, 1u, core > 0u);
    let total = per_ply * n_ply;
    // Reservations are contiguous from 0, so every slot below the capacity is written by
    // whoever reserved it; what lies beyond is counted and dropped, and `clamp_count`
    // (run after this pass) cuts instance_count back to the capacity.
    let cap = view.lod.w;
    let base = atomicAdd(&args.instance_count, total);
    if base + total > cap {
        atomicAdd(&args.overflow, base + total - max(base, cap));
    }
    var k = base;
    for (var ply = 0u; ply < n_ply; ply++) {
        if core > 0u {
            // The core strip keeps full subdivision: its texture twists along the segment.
            if k < cap {
                out_instances[k] = vec2<u32>(seg, 0xfffeu | (ply << 16u) | (view.lod.y << 24u));
            }
            k++;
        }
        for (var f = n_fib - n; f < n_fib; f++) {
            if k < cap {
                out_instances[k] = vec2<u32>(seg, f | (ply << 16u) | (n_sub << 24u));
            }
            k++;
        }
    }
}

@compute @workgroup_size(1)
fn clamp_count() {
    let n = atomicLoad(&args.instance_count);
    atomicStore(&args.instance_count, min(n, view.lod.w));
}
