// fiber_lod (compute, one invocation per yarn segment): conservative culling on the hull
// of the segment's Bézier points inflated by the fiber reach (DESIGN §2.3 item 8: the
// Catmull–Rom control points themselves do not bound the curve), then the level of detail
// λ of [W19 eq. 4] from the projected fiber and ply widths at the segment midpoint, the
// fiber count n = max(1, round(λ²·n_max)) per ply — the outermost n by R_i, since the
// table is sorted and [W19 §5] drops fibers from the ply centre outwards — and the
// subdivisions max(2, ceil(λ²·n_sub)) (DESIGN §2.3 item 7, the count formula eq. 4 lacks).
// Instances are appended to a compact list and counted into the indirect draw's
// instance_count.
//
// Hair flyaways (ours; [W19] generates no hairs on the GPU): each segment hashes the slots
// its outermost hair_fibers() fibers pass through — FiberTable::period_kind's keys, on the
// GPU — and lists the hairs whose crossing of r_0 lies on it, with the segment's n_sub
// (fiber_draw raises the coverage of the hairs kept to stand for the others). "Lies on
// it" is decided by one comparison that the two segments sharing a boundary evaluate
// identically, so every hair is listed once.
// A hair reaches along the curve beyond its segment, so a culled segment still scans, and
// a hair is culled only when every segment it spans, inflated by the hair's own reach, is
// outside (culling on and off give the same image).

struct DrawArgs {
    vertex_count: u32,
    instance_count: atomic<u32>,
    first_vertex: u32,
    first_instance: u32,
    // Instances that did not fit into the list (reported, never drawn).
    overflow: atomic<u32>,
    // Segments culled.
    culled: atomic<u32>,
    // Hairs listed.
    hairs: atomic<u32>,
}

@group(1) @binding(0) var<uniform> view: View;
@group(1) @binding(1) var<storage, read_write> out_instances: array<vec2<u32>>;
@group(1) @binding(2) var<storage, read_write> args: DrawArgs;

fn outside(p: vec3<f32>, plane: vec4<f32>, reach: f32) -> bool {
    return dot(plane.xyz, p) + plane.w < -reach;
}

// Whether the segment, moved by `shift`, lies outside a frustum plane even when inflated
// by `reach`: its Bézier points bound the curve (DESIGN §2.3 item 8).
fn segment_outside(s: Segment, shift: vec3<f32>, reach: f32) -> bool {
    let b0 = s.p[1].xyz + shift;
    let b1 = s.p[1].xyz + (s.p[2].xyz - s.p[0].xyz) / 6.0 + shift;
    let b2 = s.p[2].xyz - (s.p[3].xyz - s.p[1].xyz) / 6.0 + shift;
    let b3 = s.p[2].xyz + shift;
    for (var i = 0u; i < 6u; i++) {
        let pl = view.planes[i];
        if outside(b0, pl, reach) && outside(b1, pl, reach) && outside(b2, pl, reach)
            && outside(b3, pl, reach) {
            return true;
        }
    }
    return false;
}

// Whether a hair (counted from `seg`) lies outside the frustum: every segment its length
// span crosses, inflated by its reach from the yarn centre — the ply-centre distance plus
// its largest radius on the ply ellipse plus the fiber radius — and f32 slack.
fn hair_outside(seg: u32, hr: Hair, pr: Params, scale: f32) -> bool {
    let d0 = hair_dz(hr, 0.0);
    let d1 = hair_dz(hr, 1.0);
    let a = place_at(seg, min(d0, d1));
    let b = place_at(seg, max(d0, d1));
    let reach = (pr.a.x + hr.reach * pr.g.w + pr.b.y) * 1.001 + 1e-7 * scale;
    let s0 = segments[a.seg];
    let c = curves[s0.ids.x];
    let n = c.keys.w;
    let first = a.seg - s0.ids.y;
    let wrap_shift = segments[first + n - 1u].p[2].xyz - segments[first].p[1].xyz;
    var i = s0.ids.y;
    var shift = a.shift;
    for (var it = 0u; it < 64u; it++) {
        if !segment_outside(segments[first + i], shift, reach) {
            return false;
        }
        if first + i == b.seg && all(shift == b.shift) {
            return true;
        }
        i += 1u;
        if i >= n {
            if c.keys.x == 0u {
                return true;
            }
            i = 0u;
            shift += wrap_shift;
        }
    }
    // A hair across more than 64 segments: kept (conservative).
    return false;
}

// Whether slot coordinate σ_0 = slot + (x + (φ_i − π)/2π) lies after (≥, or > when
// `strict`) a segment start S = base + phase + (φ_i − π)/2π: (x − phase) against
// base − slot, both exact as the two segments of a boundary compute them.
fn after_start(base: i32, phase: f32, x: f32, slot: i32, strict: bool) -> bool {
    let d = x - phase;
    let m = f32(base - slot);
    return select(d >= m, d > m, strict);
}

// The hairs of fiber `fib` of ply `ply` whose crossing lies on segment `seg`, listed.
fn list_hairs(seg: u32, ply: u32, fib: u32, n_sub: u32, visible: bool) {
    let s = segments[seg];
    let c = curves[s.ids.x];
    let pr = yarn_params[c.ids.x];
    let rec = fiber_table[c.ids.y + ply * pr.d.y + fib];
    let ft = (rec.z - PI) / TAU;
    let base = bitcast<i32>(s.ids.z);
    // The next segment's start (a closed curve's last segment: the first, one wrap on).
    var has_next = true;
    var next_base = 0;
    var next_phase = 0.0;
    if s.ids.y + 1u < c.keys.w {
        let nx = segments[seg + 1u];
        next_base = bitcast<i32>(nx.ids.z);
        next_phase = nx.phase.z;
    } else if c.keys.x > 0u {
        let f0 = segments[seg - s.ids.y];
        // σ runs backwards along z when α' < 0.
        let wrap = select(i32(c.keys.x), -i32(c.keys.x), c.pitch.y < 0.0);
        next_base = bitcast<i32>(f0.ids.z) + wrap;
        next_phase = f0.phase.z;
    } else {
        has_next = false;
    }
    let len = s.p[2].w;
    let a = s.phase.z + ft;
    var b = a + c.pitch.w * len / c.pitch.y;
    if has_next {
        b = f32(next_base - base) + next_phase + ft;
    }
    let lo = max(i32(floor(min(a, b))) - 1, -32);
    let hi = min(i32(floor(max(a, b))) + 1, 31);
    let forward = c.pitch.y > 0.0;
    for (var j = lo; j <= hi; j++) {
        let slot = base + j;
        let h = slot_state(c, ply, fib, slot);
        if !slot_is_hair(pr, h) {
            continue;
        }
        let x = hair_slot_fraction(h) - ft;
        var inside: bool;
        if forward {
            inside = after_start(base, s.phase.z, x, slot, false);
        } else {
            inside = !after_start(base, s.phase.z, x, slot, true);
        }
        if inside {
            if has_next {
                if forward {
                    inside = !after_start(next_base, next_phase, x, slot, false);
                } else {
                    inside = after_start(next_base, next_phase, x, slot, true);
                }
            } else {
                let dz = (f32(j) + (x - s.phase.z)) * c.pitch.y / c.pitch.w;
                inside = dz < len;
            }
        }
        if !inside {
            continue;
        }
        if !visible && hair_outside(seg, hair_of(seg, ply, fib, j), pr, c.frame.z) {
            continue;
        }
        atomicAdd(&args.hairs, 1u);
        let k = atomicAdd(&args.instance_count, 1u);
        if k < view.lod.w {
            out_instances[k] = vec2<u32>(seg | (u32(j + 32) << 25u) | HAIR_BIT,
                fib | (ply << 16u) | (n_sub << 24u));
        } else {
            atomicAdd(&args.overflow, 1u);
        }
    }
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
    var visible = true;
    if (view.lod.z & 1u) != 0u {
        // Fiber reach (flyaways included) plus f32 slack.
        let reach = pr.c.w * 1.001 + 1e-7 * c.frame.z;
        visible = !segment_outside(s, vec3<f32>(0.0), reach);
    }
    let hairs = (view.lod.z & 1024u) != 0u && pr.d.w != 0u && pr.g.x > pr.b.z
        && seg < 0x2000000u && (view.lod.z & 8u) == 0u;
    if !visible {
        atomicAdd(&args.culled, 1u);
        if !hairs {
            return;
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
    let widths = segment_widths(view, seg);
    let lambda = lod_lambda(widths.x, widths.y, view.viewport.w);
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
    if hairs {
        // The hairs of the outermost hair_fibers() fibers: all at full detail; fiber_draw
        // divides the coverage of the hairs kept by the fraction kept.
        let n_hair_fibers = hair_fibers(view, lambda, widths.x, n_fib);
        for (var ply = 0u; ply < n_ply; ply++) {
            for (var f = n_fib - n_hair_fibers; f < n_fib; f++) {
                list_hairs(seg, ply, f, n_sub, visible);
            }
        }
    }
    if !visible {
        return;
    }
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
