// yarn_tube_shadow (render, depth only): the shadow map of the yarns as thick tubes
// [W19 §4.1] for one light (a directional light, an SRBF lobe, or a point light's
// perspective map or cube face) — each segment a light-facing strip of the yarn
// diameter (flyaways left out, DESIGN §2.3 item 14), vertex-pulled from the same control
// points as the fibers (yarn_point of the generator), n_sub + 1 points per segment.

struct ShadowPass {
    view_proj: mat4x4<f32>,
    // Unit direction towards the light (w = 0) or the point light's origin-relative
    // position (w = 1).
    to_light: vec4<f32>,
    // Subdivisions per segment, unused ×3.
    n: vec4<u32>,
}

@group(1) @binding(0) var<uniform> sp: ShadowPass;

@vertex
fn vs_shadow(@builtin(vertex_index) vi: u32, @builtin(instance_index) seg: u32)
    -> @builtin(position) vec4<f32> {
    let n_sub = max(sp.n.x, 1u);
    let k = min(vi / 2u, n_sub);
    let side = select(-1.0, 1.0, (vi & 1u) == 1u);
    let t = f32(k) / f32(n_sub);
    let yp = yarn_point(seg, t);
    let c = curves[segments[seg].ids.x];
    let radius = yarn_params[c.ids.x].c.z;
    let wl = select(sp.to_light.xyz, sp.to_light.xyz - yp.pos, sp.to_light.w != 0.0);
    let across = normalize_or(cross(yp.t, wl), any_perpendicular(yp.t));
    return sp.view_proj * vec4<f32>(yp.pos + across * (radius * side), 1.0);
}
