// knot_solve: the per-face guarded Gauss–Newton of [H25 §5.2] (yarn::knit::knot's
// solve.rs, DESIGN §3.3 items 3–4) in f32, one invocation per knot face. Each face moves
// its two knots' parameters Θ = (θ1, l1/r, θ2, l2/r) with every other point of its stencil
// held at the initial guess (the CPU solver's Jacobi iterations); the residuals are the
// signed, weighted relative lengths [H25 eq. 6] and turn cosines [H25 eq. 5]; the knot
// points are [H25 eq. 1–2] with the per-knot frames the CPU prepared. Positions are
// relative to an origin the host chose near the mesh (f32 keeps ~1e-7 of the extent).

const MAXL: u32 = 48u;
const MAX_HALVINGS: u32 = 20u;

struct Params {
    // Lattice vectors (zero on open meshes), relative to nothing: periods.
    l0: vec4<f32>,
    l1: vec4<f32>,
    r: f32,
    h: f32,
    sqrt_w_length: f32,
    sqrt_w_angle: f32,
    iterations: u32,
    faces: u32,
    // Face energy treated as converged (rounding of the f32 residuals).
    converged: f32,
    row_stride: u32,
};

struct Face {
    sigma: f32,
    b_own0: f32,
    b_own1: f32,
    local_start: u32,
    local_count: u32,
    res_start: u32,
    res_count: u32,
    _pad: u32,
};

// Per knot k: xk (w = the orientation o on xk0), e1, e2, n.
struct Frame {
    xk0: vec4<f32>,
    xk1: vec4<f32>,
    e1_0: vec4<f32>,
    e1_1: vec4<f32>,
    e2_0: vec4<f32>,
    e2_1: vec4<f32>,
    n0: vec4<f32>,
    n1: vec4<f32>,
};

// flags: bit 0 owned, bit 1 knot, bits 2–3 role (0 c0, 1 c1, 2 p), bit 4 own yarn.
struct Local {
    global: u32,
    flags: u32,
    wrap: i32,
    course_wrap: i32,
};

// c = 0xffffffff: the relative length of a → b; else the turn cosine at b of a → b → c.
struct Res {
    a: u32,
    b: u32,
    c: u32,
    rest: f32,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(2) var<storage, read> locals: array<Local>;
@group(0) @binding(3) var<storage, read> residuals: array<Res>;
@group(0) @binding(4) var<storage, read> frames: array<Frame>;
@group(0) @binding(5) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> theta_in: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> theta_out: array<vec4<f32>>;
// Per face: guard triggers, rejected steps.
@group(0) @binding(8) var<storage, read_write> counts: array<vec2<u32>>;

var<private> pos: array<vec3<f32>, MAXL>;
var<private> dknot: array<i32, MAXL>;
var<private> d_theta: array<vec3<f32>, MAXL>;
var<private> d_lambda: array<vec3<f32>, MAXL>;
var<private> mat_a: mat4x4<f32>;
var<private> vec_g: vec4<f32>;

// The stencil's points at `t` (and with `jac` their derivatives by their knot's θ, λ).
fn place(fc: Face, fr: Frame, t: vec4<f32>, jac: bool) {
    let o = fr.xk0.w;
    let r = params.r;
    for (var i = 0u; i < fc.local_count; i++) {
        let lc = locals[fc.local_start + i];
        let shift = params.l0.xyz * f32(lc.wrap) + params.l1.xyz * f32(lc.course_wrap);
        if ((lc.flags & 1u) == 0u) {
            pos[i] = points[lc.global].xyz + shift;
            dknot[i] = -1;
            continue;
        }
        let k = (lc.flags >> 1u) & 1u;
        let role = (lc.flags >> 2u) & 3u;
        let own = ((lc.flags >> 4u) & 1u) == 1u;
        var xk = fr.xk0.xyz;
        var e1 = fr.e1_0.xyz;
        var e2 = fr.e2_0.xyz;
        var n = fr.n0.xyz;
        var th = t.x;
        var lam = t.y;
        var b_own = fc.b_own0;
        if (k == 1u) {
            xk = fr.xk1.xyz;
            e1 = fr.e1_1.xyz;
            e2 = fr.e2_1.xyz;
            n = fr.n1.xyz;
            th = t.z;
            lam = t.w;
            b_own = fc.b_own1;
        }
        let sn = sin(th);
        let cs = cos(th);
        let d = e1 * cs + e2 * sn;
        let dd = e2 * cs - e1 * sn;
        let l = lam * r;
        let side = select(-fc.sigma, fc.sigma, own);
        var q: vec3<f32>;
        var gt = vec3<f32>(0.0);
        var gl = vec3<f32>(0.0);
        if (role == 0u) {
            q = xk + d * l + n * (side * params.h);
            gt = dd * l;
            gl = d * r;
        } else if (role == 1u) {
            q = xk - d * l - n * (side * params.h);
            gt = -dd * l;
            gl = -d * r;
        } else {
            let sb = select(-b_own, b_own, own);
            q = xk + cross(d, n) * (o * sb * r);
            gt = cross(dd, n) * (o * sb * r);
        }
        pos[i] = q + shift;
        dknot[i] = i32(k);
        if (jac) {
            d_theta[i] = gt;
            d_lambda[i] = gl;
        }
    }
}

// Adds ∂r/∂x_i · ∂x_i/∂Θ to a Jacobian row.
fn add_grad(row: ptr<function, vec4<f32>>, i: u32, grad: vec3<f32>) {
    let k = dknot[i];
    if (k == 0) {
        (*row).x += dot(grad, d_theta[i]);
        (*row).y += dot(grad, d_lambda[i]);
    } else if (k == 1) {
        (*row).z += dot(grad, d_theta[i]);
        (*row).w += dot(grad, d_lambda[i]);
    }
}

// The face energy Σ r² at `t`; with `jac` also A = JᵀJ and g = Jᵀr.
fn energy(fc: Face, fr: Frame, t: vec4<f32>, jac: bool) -> f32 {
    place(fc, fr, t, jac);
    if (jac) {
        mat_a = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        vec_g = vec4<f32>(0.0);
    }
    let sl = params.sqrt_w_length;
    let sa = params.sqrt_w_angle;
    var e = 0.0;
    for (var j = 0u; j < fc.res_count; j++) {
        let rd = residuals[fc.res_start + j];
        var res: f32;
        var row = vec4<f32>(0.0);
        if (rd.c == 0xffffffffu) {
            let ev = pos[rd.b] - pos[rd.a];
            let len = length(ev);
            res = sl * (len - rd.rest) / rd.rest;
            if (jac && len > 0.0) {
                let u = ev * (sl / (len * rd.rest));
                add_grad(&row, rd.b, u);
                add_grad(&row, rd.a, -u);
            }
        } else {
            let p = pos[rd.b] - pos[rd.a];
            let q = pos[rd.c] - pos[rd.b];
            let lp = length(p);
            let lq = length(q);
            let den = lp * lq;
            var cs = 1.0;
            if (den > 0.0) {
                cs = dot(p, q) / den;
            }
            res = sa * (cs - rd.rest);
            if (jac && den > 0.0) {
                let gp = (q / den - p * (cs / (lp * lp))) * sa;
                let gq = (p / den - q * (cs / (lq * lq))) * sa;
                add_grad(&row, rd.a, -gp);
                add_grad(&row, rd.b, gp - gq);
                add_grad(&row, rd.c, gq);
            }
        }
        e += res * res;
        if (jac) {
            vec_g += row * res;
            mat_a += mat4x4<f32>(row * row.x, row * row.y, row * row.z, row * row.w);
        }
    }
    return e;
}

// a x = b for the symmetric positive semi-definite a, by Cholesky with a damping of 1e-6 of
// the trace (f32: the CPU's 1e-12 is below its rounding); 0 when it breaks down.
fn solve4(a_in: mat4x4<f32>, b: vec4<f32>) -> vec4<f32> {
    var a = a_in;
    let tr = a[0][0] + a[1][1] + a[2][2] + a[3][3];
    if (!(tr > 0.0)) {
        return vec4<f32>(0.0);
    }
    for (var i = 0u; i < 4u; i++) {
        a[i][i] += 1e-6 * tr;
    }
    var l = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    for (var i = 0u; i < 4u; i++) {
        for (var j = 0u; j <= i; j++) {
            var s = a[i][j];
            for (var k = 0u; k < j; k++) {
                s -= l[i][k] * l[j][k];
            }
            if (i == j) {
                if (s <= 0.0) {
                    return vec4<f32>(0.0);
                }
                l[i][i] = sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    var y = vec4<f32>(0.0);
    for (var i = 0u; i < 4u; i++) {
        var s = b[i];
        for (var k = 0u; k < i; k++) {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    var x = vec4<f32>(0.0);
    for (var ii = 0u; ii < 4u; ii++) {
        let i = 3u - ii;
        var s = y[i];
        for (var k = i + 1u; k < 4u; k++) {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    return x;
}

@compute @workgroup_size(64)
fn solve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let f = gid.x + gid.y * params.row_stride;
    if (f >= params.faces) {
        return;
    }
    let fc = faces[f];
    let fr = frames[f];
    var t = theta_in[f];
    var guard = 0u;
    var rejected = 0u;
    var e = energy(fc, fr, t, params.iterations > 0u);
    for (var it = 0u; it < params.iterations; it++) {
        if (e <= params.converged) {
            continue;
        }
        if (it > 0u) {
            e = energy(fc, fr, t, true);
        }
        let step = solve4(mat_a, -vec_g);
        var scale = 1.0;
        var accepted = false;
        for (var h = 0u; h <= MAX_HALVINGS; h++) {
            let trial = t + step * scale;
            let et = energy(fc, fr, trial, false);
            if (et <= e) {
                t = trial;
                e = et;
                accepted = true;
                if (h > 0u) {
                    guard += 1u;
                }
                break;
            }
            scale *= 0.5;
        }
        if (!accepted) {
            rejected += 1u;
        }
    }
    theta_out[f] = t;
    counts[f] = vec2<u32>(guard, rejected);
}
