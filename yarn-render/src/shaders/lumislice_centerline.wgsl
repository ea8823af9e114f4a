// lumislice_centerline (render): the centre-line maps of [C03 eq. 10] (DESIGN §1.3 item
// 13), one per directional light — every piece of every yarn a light-facing strip of half
// width R_y (the density's reach) about its centre line, depth-tested LESS so a texel keeps
// the yarn nearest the light: its distance from the centre line, its piece and the centre
// line's light depth. The march reads them (lumislice_march.wgsl, yarn_shadow).

struct CentreOut {
    @builtin(position) clip: vec4<f32>,
    // Signed distance from the centre line across the strip (m), piece.
    @location(0) @interpolate(linear) across: f32,
    @location(1) @interpolate(flat) piece: u32,
}

struct CentreParams {
    view_proj: mat4x4<f32>,
    // Unit direction towards the light, reach R_y.
    to_light: vec4<f32>,
    // n_sub, unused ×3.
    n: vec4<u32>,
}

@group(1) @binding(0) var<uniform> cp: CentreParams;

@vertex
fn vs_centre(@builtin(vertex_index) vi: u32, @builtin(instance_index) piece: u32) -> CentreOut {
    let n_sub = max(cp.n.x, 1u);
    let seg = piece / n_sub;
    let sub = piece % n_sub;
    let k = min(vi / 2u, 1u);
    let side = select(-1.0, 1.0, (vi & 1u) == 1u);
    let ya = yarn_point(seg, f32(sub) / f32(n_sub));
    let yb = yarn_point(seg, f32(sub + 1u) / f32(n_sub));
    let p = select(ya.pos, yb.pos, k == 1u);
    let axis = normalize_or(yb.pos - ya.pos, ya.t);
    let across = normalize_or(cross(axis, cp.to_light.xyz), any_perpendicular(axis));
    let r = cp.to_light.w;
    var out: CentreOut;
    // Offsets ⟂ the light keep the centre line's light depth across the strip.
    out.clip = cp.view_proj * vec4<f32>(p + across * (r * side), 1.0);
    out.across = r * side;
    out.piece = piece;
    return out;
}

@fragment
fn fs_centre(in: CentreOut) -> @location(0) vec4<f32> {
    return vec4<f32>(abs(in.across), f32(in.piece), in.clip.z, 1.0);
}
