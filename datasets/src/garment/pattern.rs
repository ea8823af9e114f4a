//! Sewing patterns: flat panels whose outlines are chains of named edges (counter-clockwise,
//! seen from the garment's outer side, so `∂P/∂u × ∂P/∂v` is the outward normal once
//! placed), the grain (warp) along each panel's `+y`, seams that join one panel's edge
//! running forward to another's running backward (so the sewn surface is orientable), and
//! a placement that puts each panel around the body before sewing.
//!
//! [`Pattern::new`] draws the panels of a [`GarmentKind`] for a body's measurements;
//! lengths follow ordinary block-pattern drafting (ease over the body's girths, a sleeve
//! cap whose half-length equals the armhole it is sewn into, trouser inseams of equal
//! length front and back), with seam allowances left out.

use super::body::{Landmarks, Measurements};
use super::mesher::{P2, polygon_area};
use crate::vec3::{V3, add, cross, length, normalize_or, scale, sub};
use crate::{Error, Result};
use std::f64::consts::PI;

/// The garments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GarmentKind {
    /// Short-sleeved T-shirt: front, back, two sleeves.
    TShirt,
    /// Long-sleeved shirt: front, back, two long sleeves.
    Shirt,
    /// Trousers: front and back of each leg.
    Trousers,
    /// A-line skirt: front and back.
    Skirt,
    /// Scarf: one long rectangle laid round the neck.
    Scarf,
    /// Curtain panel hanging from a rod (no body).
    Curtain,
}

impl GarmentKind {
    /// Parses `tshirt`, `shirt`, `trousers`, `skirt`, `scarf` or `curtain`.
    pub fn from_name(name: &str) -> Result<Self> {
        Ok(match name {
            "tshirt" | "t-shirt" => GarmentKind::TShirt,
            "shirt" => GarmentKind::Shirt,
            "trousers" => GarmentKind::Trousers,
            "skirt" => GarmentKind::Skirt,
            "scarf" => GarmentKind::Scarf,
            "curtain" => GarmentKind::Curtain,
            other => {
                return Err(Error::Invalid(format!(
                    "garment kind '{other}' (known: tshirt, shirt, trousers, skirt, scarf, curtain)"
                )));
            }
        })
    }

    /// The name `from_name` parses.
    pub fn name(self) -> &'static str {
        match self {
            GarmentKind::TShirt => "tshirt",
            GarmentKind::Shirt => "shirt",
            GarmentKind::Trousers => "trousers",
            GarmentKind::Skirt => "skirt",
            GarmentKind::Scarf => "scarf",
            GarmentKind::Curtain => "curtain",
        }
    }

    /// Whether the garment is worn (draped on the body).
    pub fn on_body(self) -> bool {
        self != GarmentKind::Curtain
    }
}

/// Optional overrides of the drafted lengths (metres).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PatternOptions {
    /// Sleeve length from the shoulder point to the cuff.
    pub sleeve_length_m: Option<f64>,
    /// Garment length (T-shirt and shirt from the neck side point, skirt and trousers
    /// from the waist, scarf and curtain overall).
    pub length_m: Option<f64>,
    /// Ease added to the chest (tops), hip (skirt, trousers) girth.
    pub ease_m: Option<f64>,
}

/// One edge of a panel outline: a dense polyline from its start corner to its end corner.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    /// Name (`hem`, `side_r`, `armhole_l`, …).
    pub name: String,
    /// Points, both corners included.
    pub points: Vec<P2>,
}

impl Edge {
    fn new(name: &str, points: Vec<P2>) -> Edge {
        Edge { name: name.into(), points }
    }

    /// Arc length (m).
    pub fn length(&self) -> f64 {
        self.points.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).sum()
    }

    /// `n + 1` points at equal arc-length steps (both corners included).
    pub fn resample(&self, n: usize) -> Vec<P2> {
        let total = self.length();
        let mut out = Vec::with_capacity(n + 1);
        let mut seg = 0;
        let mut acc = 0.0;
        for i in 0..=n {
            let target = total * i as f64 / n as f64;
            while seg + 1 < self.points.len() - 1 {
                let l = dist2(self.points[seg], self.points[seg + 1]);
                if acc + l >= target {
                    break;
                }
                acc += l;
                seg += 1;
            }
            let (a, b) = (self.points[seg], self.points[seg + 1]);
            let l = dist2(a, b).max(1e-300);
            let t = ((target - acc) / l).clamp(0.0, 1.0);
            out.push([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]);
        }
        *out.last_mut().unwrap() = *self.points.last().unwrap();
        out
    }
}

fn dist2(a: P2, b: P2) -> f64 {
    (b[0] - a[0]).hypot(b[1] - a[1])
}

/// Where a panel goes before sewing.
#[derive(Debug, Clone, PartialEq)]
pub enum Placement {
    /// Wrapped round an axis: panel row `y` sits at `origin + axis·(y − y0)`, panel `x`
    /// runs round an ellipse of semi-axes `semi(y)` (along `reference` and
    /// `axis × reference`), mapped linearly from `[x0, x1]` onto angles `[phi0, phi1]`.
    Wrap {
        /// A point of the axis (at panel row `y0`).
        origin: V3,
        /// Unit axis, along the panel's `+y`.
        axis: V3,
        /// Unit direction of angle 0, perpendicular to the axis.
        reference: V3,
        /// Panel row at `origin`.
        y0: f64,
        /// Panel `x` range and the angle range it maps to (radians, increasing).
        x_range: [f64; 2],
        /// Angles of `x_range`.
        phi_range: [f64; 2],
        /// Ellipse semi-axes at panel rows `ys[i]` (interpolated linearly).
        semi: Vec<(f64, [f64; 2])>,
    },
    /// Two wraps blended by panel row: `lower` up to `y_blend[0]`, `upper` from `y_blend[1]`.
    Blend {
        /// Wrap used low on the panel.
        lower: Box<Placement>,
        /// Wrap used high on the panel.
        upper: Box<Placement>,
        /// Rows where the blend starts and ends.
        y_blend: [f64; 2],
    },
    /// Along a space curve: panel `y` is arc length along `path` (starting at `y0`), panel
    /// `x` an offset along the unit `side` vectors (one per path point).
    Path {
        /// Path points.
        path: Vec<V3>,
        /// Offset direction at each path point.
        side: Vec<V3>,
        /// Panel row of the first path point.
        y0: f64,
    },
    /// A cone's development (an annulus sector with its apex at `apex` in the panel)
    /// wrapped round an axis: panel point `p` at distance `ρ` from the apex and angle `θ`
    /// from the sector's middle (`−half_angle … half_angle`) sits at
    /// `origin + axis·(r_out − ρ)`, on the ellipse `semi(r_out − ρ)` at angle
    /// `centre + θ / half_angle · half_span`. Every arc of the sector then spans the same
    /// angles round the axis. (The skirt was first wrapped by [`Placement::Wrap`], whose
    /// angle follows panel `x` alone: its short waist arc lay on a fraction of the waist's
    /// ellipse, compressed by 39 % with the side seams 19 cm apart, and at 40 000 vertices
    /// the sewing's release of that threw the skirt down to the ankles.)
    Cone {
        /// The axis's point at the outer arc (`ρ = r_out`).
        origin: V3,
        /// Unit axis, from the outer arc towards the apex.
        axis: V3,
        /// Unit direction of angle 0, perpendicular to the axis.
        reference: V3,
        /// The sector's apex in panel coordinates; its middle runs along panel `−y`.
        apex: P2,
        /// Radius of the outer arc (m).
        r_out: f64,
        /// Half the sector's angle.
        half_angle: f64,
        /// Angle (round the axis) of the sector's middle.
        centre: f64,
        /// Half the angle round the axis each arc spans.
        half_span: f64,
        /// Ellipse semi-axes at heights `r_out − ρ` (interpolated linearly).
        semi: Vec<(f64, [f64; 2])>,
    },
    /// Hung in pleats: panel `y` runs along `ey`, panel `x` along the wave
    /// `origin + X·ex + A sin(2π n X / span)·ez` ([`Pleats`]), at arc length `x` from its
    /// start — isometric, so a panel `width` wide is gathered onto `span`.
    Pleated {
        /// Position of the panel's origin.
        origin: V3,
        /// Direction of the rod (the gathered panel's `+x`).
        ex: V3,
        /// Image of the panel's `+y`.
        ey: V3,
        /// Direction the pleats stand out in.
        ez: V3,
        /// The wave.
        pleats: Pleats,
    },
}

/// A sine wave `Y = A sin(2π n X / span)`, `0 ≤ X ≤ span`, whose arc length is a given
/// width: a panel that wide gathered into `n` pleats over `span`.
#[derive(Debug, Clone, PartialEq)]
pub struct Pleats {
    /// Amplitude `A` (m).
    pub amplitude: f64,
    /// Wave number `2π n / span` (1/m).
    wave_number: f64,
    /// Arc length at `X = span·i / (len − 1)` (m).
    arc: Vec<f64>,
    span: f64,
}

impl Pleats {
    /// `n` pleats gathering `width` onto `span < width` (the amplitude found by bisection on
    /// the wave's arc length).
    pub fn new(width: f64, span: f64, n: usize) -> Pleats {
        let k = 2.0 * PI * n as f64 / span;
        const SAMPLES: usize = 4097;
        let arc_of = |a: f64| {
            let dx = span / (SAMPLES - 1) as f64;
            let slope = |x: f64| (1.0 + (a * k * (k * x).cos()).powi(2)).sqrt();
            let mut arc = vec![0.0; SAMPLES];
            for i in 1..SAMPLES {
                let x = (i - 1) as f64 * dx;
                // Simpson's rule on each sample interval.
                arc[i] =
                    arc[i - 1] + dx / 6.0 * (slope(x) + 4.0 * slope(x + 0.5 * dx) + slope(x + dx));
            }
            arc
        };
        let (mut lo, mut hi) = (0.0, width);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if arc_of(mid)[SAMPLES - 1] < width {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let amplitude = 0.5 * (lo + hi);
        Pleats { amplitude, wave_number: k, arc: arc_of(amplitude), span }
    }

    /// The point `(X, Y)` at arc length `s` along the wave (clamped to its ends).
    pub fn at(&self, s: f64) -> [f64; 2] {
        let last = self.arc.len() - 1;
        let i = self.arc.partition_point(|&a| a <= s).clamp(1, last);
        let (a0, a1) = (self.arc[i - 1], self.arc[i]);
        let t = ((s - a0) / (a1 - a0)).clamp(0.0, 1.0);
        let x = self.span * ((i - 1) as f64 + t) / last as f64;
        [x, self.amplitude * (self.wave_number * x).sin()]
    }
}

impl Placement {
    /// The 3-D position of panel point `p`.
    pub fn place(&self, p: P2) -> V3 {
        match self {
            Placement::Wrap { origin, axis, reference, y0, x_range, phi_range, semi } => {
                let t = p[1] - y0;
                let s = interpolate_semi(semi, p[1]);
                let f = (p[0] - x_range[0]) / (x_range[1] - x_range[0]);
                let phi = phi_range[0] + f * (phi_range[1] - phi_range[0]);
                let w = cross(*axis, *reference);
                let radial = add(scale(*reference, s[0] * phi.cos()), scale(w, s[1] * phi.sin()));
                add(add(*origin, scale(*axis, t)), radial)
            }
            Placement::Blend { lower, upper, y_blend } => {
                let t = ((p[1] - y_blend[0]) / (y_blend[1] - y_blend[0])).clamp(0.0, 1.0);
                let t = t * t * (3.0 - 2.0 * t);
                let (a, b) = (lower.place(p), upper.place(p));
                add(scale(a, 1.0 - t), scale(b, t))
            }
            Placement::Path { path, side, y0 } => {
                let mut s = p[1] - y0;
                for i in 0..path.len() - 1 {
                    let l = length(sub(path[i + 1], path[i]));
                    if s <= l || i + 2 == path.len() {
                        let t = (s / l.max(1e-12)).clamp(0.0, 1.5);
                        let c = add(path[i], scale(sub(path[i + 1], path[i]), t));
                        let sd = normalize_or(
                            add(scale(side[i], 1.0 - t.min(1.0)), scale(side[i + 1], t.min(1.0))),
                            side[i],
                        );
                        return add(c, scale(sd, p[0]));
                    }
                    s -= l;
                }
                path[0]
            }
            Placement::Cone {
                origin,
                axis,
                reference,
                apex,
                r_out,
                half_angle,
                centre,
                half_span,
                semi,
            } => {
                let (dx, dy) = (p[0] - apex[0], apex[1] - p[1]);
                let rho = (dx * dx + dy * dy).sqrt();
                let theta = dx.atan2(dy);
                let t = r_out - rho;
                let e = interpolate_semi(semi, t);
                let phi = centre + theta / half_angle * half_span;
                let w = cross(*axis, *reference);
                let radial = add(scale(*reference, e[0] * phi.cos()), scale(w, e[1] * phi.sin()));
                add(add(*origin, scale(*axis, t)), radial)
            }
            Placement::Pleated { origin, ex, ey, ez, pleats } => {
                let [x, y] = pleats.at(p[0]);
                add(*origin, add(add(scale(*ex, x), scale(*ez, y)), scale(*ey, p[1])))
            }
        }
    }
}

fn interpolate_semi(semi: &[(f64, [f64; 2])], y: f64) -> [f64; 2] {
    if y <= semi[0].0 {
        return semi[0].1;
    }
    for w in semi.windows(2) {
        if y <= w[1].0 {
            let t = (y - w[0].0) / (w[1].0 - w[0].0);
            return [
                w[0].1[0] + (w[1].1[0] - w[0].1[0]) * t,
                w[0].1[1] + (w[1].1[1] - w[0].1[1]) * t,
            ];
        }
    }
    semi[semi.len() - 1].1
}

/// A flat panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Name (`front`, `back`, `sleeve_l`, …).
    pub name: String,
    /// Outline edges, counter-clockwise; edge `i` ends where edge `i + 1` starts.
    pub edges: Vec<Edge>,
    /// Where it goes before sewing.
    pub placement: Placement,
}

impl Panel {
    /// The outline as one closed polygon (corners once).
    pub fn outline(&self) -> Vec<P2> {
        self.edges.iter().flat_map(|e| e.points[..e.points.len() - 1].iter().copied()).collect()
    }

    /// Area (m²).
    pub fn area(&self) -> f64 {
        polygon_area(&self.outline())
    }

    /// Index of the edge called `name`.
    pub fn edge(&self, name: &str) -> usize {
        self.edges
            .iter()
            .position(|e| e.name == name)
            .unwrap_or_else(|| panic!("panel {} has no edge {name}", self.name))
    }
}

/// An edge of a panel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeRef {
    /// Panel index.
    pub panel: usize,
    /// Edge index in the panel.
    pub edge: usize,
}

/// A seam: edge `a` running forward is sewn to edge `b` running backward.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Seam {
    /// First edge.
    pub a: EdgeRef,
    /// Second edge (traversed backwards).
    pub b: EdgeRef,
}

/// The panels and seams of a garment.
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    /// Which garment.
    pub kind: GarmentKind,
    /// Panels.
    pub panels: Vec<Panel>,
    /// Seams.
    pub seams: Vec<Seam>,
    /// The openings left after sewing (neck, hem, cuffs …), one per boundary loop.
    pub openings: Vec<&'static str>,
    /// Vertices pinned in place (curtain heading): `(panel, edge)` whose points stay put.
    pub pinned_edges: Vec<EdgeRef>,
}

fn line(a: P2, b: P2, n: usize) -> Vec<P2> {
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
        })
        .collect()
}

fn bezier(p: [P2; 4], n: usize) -> Vec<P2> {
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            let u = 1.0 - t;
            let w = [u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t];
            [(0..4).map(|k| w[k] * p[k][0]).sum(), (0..4).map(|k| w[k] * p[k][1]).sum()]
        })
        .collect()
}

fn mirror_x(points: &[P2]) -> Vec<P2> {
    points.iter().rev().map(|p| [-p[0], p[1]]).collect()
}

/// Mirrors a panel's outline in `x` (reversing the edge order to stay counter-clockwise);
/// edge names ending in `_l`/`_r` swap.
fn mirror_edges(edges: &[Edge]) -> Vec<Edge> {
    edges
        .iter()
        .rev()
        .map(|e| {
            let name = if let Some(s) = e.name.strip_suffix("_l") {
                format!("{s}_r")
            } else if let Some(s) = e.name.strip_suffix("_r") {
                format!("{s}_l")
            } else {
                e.name.clone()
            };
            Edge { name, points: mirror_x(&e.points) }
        })
        .collect()
}

fn positive(name: &str, v: Option<f64>) -> Result<Option<f64>> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => {
            Err(Error::Invalid(format!("{name} = {x} m must be a positive length")))
        }
        _ => Ok(v),
    }
}

impl Pattern {
    /// Drafts the pattern of `kind` for a body with `measurements` and `landmarks`.
    pub fn new(
        kind: GarmentKind,
        m: &Measurements,
        l: &Landmarks,
        o: &PatternOptions,
    ) -> Result<Pattern> {
        m.validate()?;
        positive("--sleeve-length", o.sleeve_length_m)?;
        positive("--length", o.length_m)?;
        if let Some(e) = o.ease_m
            && !(e.is_finite() && (0.0..=0.5).contains(&e))
        {
            return Err(Error::Invalid(format!("ease = {e} m must be within 0 … 0.5 m")));
        }
        match kind {
            GarmentKind::TShirt => top(m, l, o, false),
            GarmentKind::Shirt => top(m, l, o, true),
            GarmentKind::Trousers => trousers(m, l, o),
            GarmentKind::Skirt => skirt(m, l, o),
            GarmentKind::Scarf => scarf(l, o),
            GarmentKind::Curtain => curtain(o),
        }
    }

    /// Total panel area (m²).
    pub fn area(&self) -> f64 {
        self.panels.iter().map(Panel::area).sum()
    }
}

/// The least sleeve-cap height of a top, in units of the body's height / 1.76 m.
const MIN_CAP: f64 = 0.03;

/// Front and back of a top plus two sleeves.
fn top(m: &Measurements, l: &Landmarks, o: &PatternOptions, long: bool) -> Result<Pattern> {
    let s = l.height / 1.76;
    let ease = o.ease_m.unwrap_or(0.12);
    let w = (m.chest_m + ease) / 4.0;
    let len = o.length_m.unwrap_or(if long { 0.42 } else { 0.39 } * l.height);
    let neck_x = l.neck_radius + 0.03 * s;
    let shoulder_x = l.shoulder[0][0] + 0.02 * s;
    let drop = 0.045 * s;
    let y_sh = len - drop;
    let y_ap_body = y_sh - (l.shoulder[0][2] - l.armpit_z + 0.05 * s);
    if len < (l.neck_base_z - l.armpit_z) + 0.12 {
        return Err(Error::Invalid(format!(
            "--length = {len} m is shorter than the armhole (at least {:.2} m)",
            l.neck_base_z - l.armpit_z + 0.12
        )));
    }
    if len > l.neck_base_z - 0.05 {
        return Err(Error::Invalid(format!(
            "--length = {len} m reaches the floor (at most {:.2} m)",
            l.neck_base_z - 0.05
        )));
    }
    let body_panel = |neck_depth: f64, y_ap: f64| -> Vec<Edge> {
        let armhole_r = bezier(
            [
                [w, y_ap],
                [shoulder_x + 0.15 * (w - shoulder_x), y_ap + 0.005],
                [shoulder_x - 0.012 * s, y_ap + 0.45 * (y_sh - y_ap)],
                [shoulder_x, y_sh],
            ],
            48,
        );
        let neck = {
            let half = bezier(
                [
                    [neck_x, len],
                    [neck_x * 0.9, len - 0.75 * neck_depth],
                    [neck_x * 0.45, len - neck_depth],
                    [0.0, len - neck_depth],
                ],
                24,
            );
            let mut pts = half.clone();
            pts.extend(mirror_x(&half).into_iter().skip(1));
            pts
        };
        vec![
            Edge::new("hem", line([-w, 0.0], [w, 0.0], 8)),
            Edge::new("side_r", line([w, 0.0], [w, y_ap], 8)),
            Edge::new("armhole_r", armhole_r.clone()),
            Edge::new("shoulder_r", line([shoulder_x, y_sh], [neck_x, len], 4)),
            Edge::new("neck", neck),
            Edge::new("shoulder_l", line([-neck_x, len], [-shoulder_x, y_sh], 4)),
            Edge::new("armhole_l", mirror_x(&armhole_r)),
            Edge::new("side_l", line([-w, y_ap], [-w, 0.0], 8)),
        ]
    };
    // Sleeve: bicep width, cap whose half equals the armhole, underarm seam, cuff.
    let upper_r = l.arm_radius[0];
    let bicep = 2.0 * PI * upper_r + 0.07 * s;
    let half_b = bicep / 2.0;
    let cap_half = |cap_h: f64| {
        bezier(
            [[half_b, 0.0], [0.64 * half_b, 0.45 * cap_h], [0.36 * half_b, cap_h], [0.0, cap_h]],
            48,
        )
    };
    // The cap's half is sewn to the armhole, so the armhole must be at least as long as a
    // cap of the least height MIN_CAP. A large size's arm is too thick for the armpit depth
    // of its own body: the armhole is deepened then, as pattern drafting does for a wide
    // bicep (a looser armhole), in 2 mm steps by at most 10 cm; sizes that fit keep theirs.
    let needed = Edge::new("", cap_half(MIN_CAP * s)).length();
    let armhole_of = |y_ap: f64| Edge::new("", body_panel(0.085 * s, y_ap)[2].points.clone());
    let mut y_ap = y_ap_body;
    // (never below 5 cm above the hem: a short --length keeps its side seams)
    while armhole_of(y_ap).length() < needed && y_ap_body - y_ap < 0.1 && y_ap > 0.052 {
        y_ap -= 0.002;
    }
    let front = body_panel(0.085 * s, y_ap);
    let back = body_panel(0.025 * s, y_ap);
    let armhole_len = Edge::new("", front[2].points.clone()).length();
    if half_b >= armhole_len {
        return Err(Error::Invalid(format!(
            "the armhole ({armhole_len:.3} m, deepened by {:.3} m) is shorter than half the \
             sleeve's width ({half_b:.3} m)",
            y_ap_body - y_ap
        )));
    }
    let (mut lo, mut hi) = (0.0, armhole_len);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if Edge::new("", cap_half(mid)).length() < armhole_len {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let cap_h = 0.5 * (lo + hi);
    let arm = l.arm[0];
    let arm_len = length(sub(arm[2], arm[0])) + 0.17 * s;
    let default_sleeve = if long { length(sub(arm[2], arm[0])) + 0.02 * s } else { 0.24 * s };
    let sleeve_len = o.sleeve_length_m.unwrap_or(default_sleeve);
    if sleeve_len > arm_len {
        return Err(Error::Invalid(format!(
            "--sleeve-length = {sleeve_len} m is longer than the arm (at most {arm_len:.2} m from the shoulder to the fingertips)"
        )));
    }
    if sleeve_len < cap_h + 0.03 {
        return Err(Error::Invalid(format!(
            "--sleeve-length = {sleeve_len} m is shorter than the sleeve cap ({:.2} m)",
            cap_h + 0.03
        )));
    }
    let under = sleeve_len - cap_h;
    let wrist_r = l.arm_radius[2];
    let cuff_half = if long {
        (PI * wrist_r + 0.035 * s).min(half_b)
    } else {
        let t = (sleeve_len / length(sub(arm[1], arm[0]))).min(1.0);
        (PI * (upper_r + (l.arm_radius[1] - upper_r) * t) + 0.04 * s).min(half_b)
    };
    let cap_r: Vec<P2> = cap_half(cap_h).into_iter().map(|p| [p[0], p[1] + under]).collect();
    let sleeve_edges = vec![
        Edge::new("cuff", line([-cuff_half, 0.0], [cuff_half, 0.0], 8)),
        Edge::new("under_r", line([cuff_half, 0.0], [half_b, under], 8)),
        Edge::new("cap_r", cap_r.clone()),
        Edge::new("cap_l", mirror_x(&cap_r)),
        Edge::new("under_l", line([-half_b, under], [-cuff_half, 0.0], 8)),
    ];
    // Placement: body panels round an ellipse about z, hem at hem_z.
    let hem_z = l.neck_base_z + 0.015 * s - len;
    let gap = 0.03 * s;
    let ab_chest = l.chest_ab;
    let ab_hip = l.hip_ab;
    let semi = vec![
        (0.0, [ab_hip[0].max(l.leg_radius[0] + l.leg[0][0][0]) + gap, ab_hip[1] + gap]),
        (y_ap, [ab_chest[0] + gap, ab_chest[1] + gap]),
        (len, [ab_chest[0] * 0.8 + gap, ab_chest[1] * 0.75 + gap]),
    ];
    let wrap = |centre: f64| Placement::Wrap {
        origin: [0.0, 0.0, hem_z],
        axis: [0.0, 0.0, 1.0],
        reference: [1.0, 0.0, 0.0],
        y0: 0.0,
        x_range: [-w, w],
        phi_range: [centre - 0.47 * PI, centre + 0.47 * PI],
        semi: semi.clone(),
    };
    let mut panels = vec![
        Panel { name: "front".into(), edges: front, placement: wrap(-PI / 2.0) },
        Panel { name: "back".into(), edges: back, placement: wrap(PI / 2.0) },
    ];
    for (i, side) in [1.0f64, -1.0].into_iter().enumerate() {
        let [joint, elbow, _] = l.arm[i];
        let down = normalize_or(sub(elbow, joint), [0.0, 0.0, -1.0]);
        let up_out = normalize_or([-down[2] * side, 0.0, down[0] * side], [0.0, 0.0, 1.0]);
        let up_out = if up_out[2] < 0.0 { scale(up_out, -1.0) } else { up_out };
        let r = upper_r + 0.03 * s;
        // The sleeve's tube starts 7 cm down the arm, and further until no point of it lies
        // within 1 cm of the body panels' ellipses: a cap placed through the body panels
        // would stay through them (the sewing's cloth–cloth contact keeps every layer on
        // the side it starts on), so the seams are left for the sewing to close.
        let sleeve_at = |shift: f64| Placement::Wrap {
            origin: add(joint, scale(down, 0.07 * s + shift)),
            axis: scale(down, -1.0),
            reference: up_out,
            y0: under + cap_h,
            x_range: [-half_b, half_b],
            phi_range: [-0.96 * PI, 0.96 * PI],
            semi: vec![(0.0, [r * 0.95, r * 0.95]), (under + cap_h, [r, r])],
        };
        let crosses_body = |pl: &Placement| {
            (0..=24).any(|i| {
                (0..=48).any(|j| {
                    let q = [
                        -half_b + 2.0 * half_b * j as f64 / 48.0,
                        (under + cap_h) * i as f64 / 24.0,
                    ];
                    let x = pl.place(q);
                    let y = x[2] - hem_z;
                    let [a, b] = interpolate_semi(&semi, y);
                    (0.0..=len + 0.01).contains(&y)
                        && (x[0] / (a + 0.01)).powi(2) + (x[1] / (b + 0.01)).powi(2) < 1.0
                })
            })
        };
        let mut shift = 0.0;
        while crosses_body(&sleeve_at(shift)) && shift < 0.5 {
            shift += 0.005;
        }
        panels.push(Panel {
            name: if side > 0.0 { "sleeve_l".into() } else { "sleeve_r".into() },
            edges: sleeve_edges.clone(),
            placement: sleeve_at(shift),
        });
    }
    let e = |p: usize, name: &str| EdgeRef { panel: p, edge: panels[p].edge(name) };
    // Left sleeve (panel 2, +x): its +x half faces the back; right sleeve (3): the front.
    let seams = vec![
        Seam { a: e(0, "side_r"), b: e(1, "side_l") },
        Seam { a: e(0, "side_l"), b: e(1, "side_r") },
        Seam { a: e(0, "shoulder_r"), b: e(1, "shoulder_l") },
        Seam { a: e(0, "shoulder_l"), b: e(1, "shoulder_r") },
        Seam { a: e(2, "under_r"), b: e(2, "under_l") },
        Seam { a: e(3, "under_r"), b: e(3, "under_l") },
        Seam { a: e(2, "cap_r"), b: e(1, "armhole_l") },
        Seam { a: e(2, "cap_l"), b: e(0, "armhole_r") },
        Seam { a: e(3, "cap_r"), b: e(0, "armhole_l") },
        Seam { a: e(3, "cap_l"), b: e(1, "armhole_r") },
    ];
    Ok(Pattern {
        kind: if long { GarmentKind::Shirt } else { GarmentKind::TShirt },
        panels,
        seams,
        openings: vec!["neck", "hem", "left cuff", "right cuff"],
        pinned_edges: Vec::new(),
    })
}

/// A-line skirt: front and back, two side seams.
fn skirt(m: &Measurements, l: &Landmarks, o: &PatternOptions) -> Result<Pattern> {
    let s = l.height / 1.76;
    let ease = o.ease_m.unwrap_or(0.03);
    let len = o.length_m.unwrap_or(0.33 * l.height);
    if len > l.waist_z - 0.05 {
        return Err(Error::Invalid(format!(
            "--length = {len} m reaches the floor (at most {:.2} m)",
            l.waist_z - 0.05
        )));
    }
    // A cone through the hip girth (plus ease), 12° from the axis; each panel is half its
    // development (an annulus sector), the waist its upper arc.
    let beta = 12f64.to_radians();
    let hip_r = (m.hip_m + ease) / (2.0 * PI);
    let drop = l.waist_z - l.hip_z;
    let waist_r = (hip_r - drop * beta.tan()).max((m.waist_m + ease) / (2.0 * PI));
    let r1 = waist_r / beta.sin();
    let r2 = r1 + len;
    let half_angle = PI * beta.sin() / 2.0;
    let arc = |r: f64, from: f64, to: f64, n: usize| -> Vec<P2> {
        (0..=n)
            .map(|i| {
                let a = from + (to - from) * i as f64 / n as f64;
                [r * a.sin(), r2 - r * a.cos()]
            })
            .collect()
    };
    let edges = vec![
        Edge::new("hem", arc(r2, -half_angle, half_angle, 64)),
        Edge::new(
            "side_r",
            line(
                [r2 * half_angle.sin(), r2 - r2 * half_angle.cos()],
                [r1 * half_angle.sin(), r2 - r1 * half_angle.cos()],
                8,
            ),
        ),
        Edge::new("waist", arc(r1, half_angle, -half_angle, 64)),
        Edge::new(
            "side_l",
            line(
                [-r1 * half_angle.sin(), r2 - r1 * half_angle.cos()],
                [-r2 * half_angle.sin(), r2 - r2 * half_angle.cos()],
                8,
            ),
        ),
    ];
    let top_y = r2 - r1;
    let hem_z = l.waist_z + 0.01 * s - top_y;
    let gap = 0.025 * s;
    let hip_semi = [l.hip_ab[0] + gap, l.hip_ab[1] + gap];
    let hem_semi = [
        (hip_r + (len - drop) * beta.tan()).max(hip_semi[0]),
        (hip_r + (len - drop) * beta.tan()) * 0.85,
    ];
    let semi = vec![
        (0.0, hem_semi),
        (top_y - drop, hip_semi),
        (top_y, [l.waist_ab[0] + gap, l.waist_ab[1] + gap]),
    ];
    let wrap = |centre: f64| Placement::Cone {
        origin: [0.0, 0.0, hem_z],
        axis: [0.0, 0.0, 1.0],
        reference: [1.0, 0.0, 0.0],
        apex: [0.0, r2],
        r_out: r2,
        half_angle,
        centre,
        half_span: 0.49 * PI,
        semi: semi.clone(),
    };
    let panels = vec![
        Panel { name: "front".into(), edges: edges.clone(), placement: wrap(-PI / 2.0) },
        Panel { name: "back".into(), edges, placement: wrap(PI / 2.0) },
    ];
    let e = |p: usize, name: &str| EdgeRef { panel: p, edge: panels[p].edge(name) };
    let seams = vec![
        Seam { a: e(0, "side_r"), b: e(1, "side_l") },
        Seam { a: e(0, "side_l"), b: e(1, "side_r") },
    ];
    Ok(Pattern {
        kind: GarmentKind::Skirt,
        panels,
        seams,
        openings: vec!["waist", "hem"],
        pinned_edges: Vec::new(),
    })
}

/// Trousers: front and back of each leg; outseams, inseams, centre front and back.
fn trousers(m: &Measurements, l: &Landmarks, o: &PatternOptions) -> Result<Pattern> {
    let s = l.height / 1.76;
    let ease = o.ease_m.unwrap_or(0.06);
    let waist_z = l.waist_z - 0.03 * s;
    let ankle_z = l.leg[0][2][2];
    let len = o.length_m.unwrap_or(waist_z - ankle_z + 0.01);
    if len > waist_z - 0.01 {
        return Err(Error::Invalid(format!(
            "--length = {len} m reaches below the floor (at most {:.2} m)",
            waist_z - 0.01
        )));
    }
    let rise = waist_z - l.crotch_z + 0.02 * s;
    if len < rise + 0.1 {
        return Err(Error::Invalid(format!(
            "--length = {len} m is shorter than the rise ({:.2} m)",
            rise + 0.1
        )));
    }
    let y_c = len - rise;
    let y_w = len;
    let y_h = len - (waist_z - l.hip_z);
    let waist_q = (m.waist_m + 0.03) / 4.0;
    let hip_q = (m.hip_m + ease) / 4.0;
    let hem_half = (PI * l.leg_radius[2] + 0.045 * s).max(0.09 * s);
    let (ext_f, ext_b) = (0.045 * s, 0.09 * s);
    // Front of the left leg; x from the centre front (0) outwards.
    let crease = 0.5 * (hip_q - ext_f) - 0.01;
    let knee_y = y_c - (l.crotch_z - l.leg[0][1][2]);
    let knee_half = hem_half + 0.012 * s;
    let front = |ext: f64, hip_extra: f64, rise_extra: f64, crotch_drop: f64| -> Vec<Edge> {
        let outseam = bezier(
            [
                [crease + hem_half, 0.0],
                [crease + knee_half, knee_y],
                [hip_q + hip_extra, y_h - 0.25 * (y_h - y_c)],
                [waist_q + hip_extra * 0.5, y_w + rise_extra],
            ],
            48,
        );
        let crotch = bezier(
            [
                [0.0, y_w + rise_extra],
                [0.0, y_c + 0.45 * rise],
                [-0.05 * ext, y_c - crotch_drop + 0.1 * rise],
                [-ext, y_c - crotch_drop],
            ],
            32,
        );
        let inseam = bezier(
            [
                [-ext, y_c - crotch_drop],
                [crease - knee_half, knee_y + 0.3 * (y_c - knee_y)],
                [crease - knee_half, knee_y],
                [crease - hem_half, 0.0],
            ],
            48,
        );
        vec![
            Edge::new("hem", line([crease - hem_half, 0.0], [crease + hem_half, 0.0], 8)),
            Edge::new("outseam", outseam),
            Edge::new(
                "waist",
                line([waist_q + hip_extra * 0.5, y_w + rise_extra], [0.0, y_w + rise_extra], 8),
            ),
            Edge::new("crotch", crotch),
            Edge::new("inseam", inseam),
        ]
    };
    let front_l = front(ext_f, 0.0, 0.0, 0.0);
    let inseam_f = Edge::new("", front_l[4].points.clone()).length();
    // The back: wider seat, higher centre back, deeper crotch; its drop makes the inseams equal.
    let (mut lo, mut hi) = (-0.05, 0.08);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if Edge::new("", front(ext_b, 0.02, 0.03, mid)[4].points.clone()).length() > inseam_f {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let back_shape = front(ext_b, 0.02 * s, 0.03 * s, 0.5 * (lo + hi));
    // Placement: round the pelvis above the hip, round each leg below the crotch.
    let gap = 0.025 * s;
    let mut panels = Vec::new();
    for (i, side) in [1.0f64, -1.0].into_iter().enumerate() {
        let [hip_joint, _knee, ankle] = l.leg[i];
        let leg_axis = normalize_or(sub(hip_joint, ankle), [0.0, 0.0, 1.0]);
        let leg_origin = add(ankle, scale(leg_axis, -(ankle_z - (waist_z - len)) / leg_axis[2]));
        let thigh_r = l.leg_radius[0] + gap;
        // The legs' tubes must not cross each other: across the body (along x) each
        // reaches at most to 1 cm short of the centre plane.
        let inner = |y: f64, r: f64| r.min((leg_origin[0] + leg_axis[0] * y).abs() - 0.01);
        let leg_semi = vec![
            (0.0, [inner(0.0, l.leg_radius[2] + 0.035 * s), l.leg_radius[2] + 0.035 * s]),
            (knee_y, [inner(knee_y, l.leg_radius[1] + 0.03 * s), l.leg_radius[1] + 0.03 * s]),
            (y_c, [inner(y_c, thigh_r), thigh_r]),
        ];
        let pelvis_semi = vec![
            (y_c, [l.hip_ab[0] + gap, l.hip_ab[1] + gap]),
            (y_h, [l.hip_ab[0] + gap, l.hip_ab[1] + gap]),
            (y_w, [l.waist_ab[0] + gap, l.waist_ab[1] + gap]),
        ];
        for (is_back, shape) in [(false, &front_l), (true, &back_shape)] {
            // Edges as drawn run from the centre (x = 0) outwards; mirror when the panel's
            // +x must point the other way in the world.
            let world_x_is_panel_x = (side > 0.0) != is_back;
            let edges = if world_x_is_panel_x { shape.clone() } else { mirror_edges(shape) };
            let xs: Vec<f64> = edges.iter().flat_map(|e| e.points.iter().map(|p| p[0])).collect();
            let x_range = [
                xs.iter().copied().fold(f64::MAX, f64::min),
                xs.iter().copied().fold(f64::MIN, f64::max),
            ];
            // Angles: front covers −π … 0 of the leg (inner → outer for the left leg).
            let (leg_phi, pelvis_phi) = match (side > 0.0, is_back) {
                (true, false) => ([-PI, 0.0], [-PI / 2.0 - 0.15, 0.0]),
                (true, true) => ([0.0, PI], [0.0, PI / 2.0 + 0.3]),
                (false, false) => ([-PI, 0.0], [-PI, -PI / 2.0 + 0.15]),
                (false, true) => ([0.0, PI], [PI / 2.0 - 0.3, PI]),
            };
            let leg_phi = if side > 0.0 { leg_phi } else { [leg_phi[0], leg_phi[1]] };
            let lower = Placement::Wrap {
                origin: leg_origin,
                axis: leg_axis,
                reference: [side, 0.0, 0.0],
                y0: 0.0,
                x_range,
                phi_range: if side > 0.0 { leg_phi } else { [leg_phi[0] + PI, leg_phi[1] + PI] },
                semi: leg_semi.clone(),
            };
            let upper = Placement::Wrap {
                origin: [0.0, 0.0, waist_z - len],
                axis: [0.0, 0.0, 1.0],
                reference: [1.0, 0.0, 0.0],
                y0: 0.0,
                x_range,
                phi_range: pelvis_phi,
                semi: pelvis_semi.clone(),
            };
            let name = format!(
                "{}_{}",
                if is_back { "back" } else { "front" },
                if side > 0.0 { "l" } else { "r" }
            );
            panels.push(Panel {
                name,
                edges,
                placement: Placement::Blend {
                    lower: Box::new(lower),
                    upper: Box::new(upper),
                    y_blend: [y_c - 0.02, y_h],
                },
            });
        }
    }
    // Panels: 0 front_l, 1 back_l, 2 front_r, 3 back_r.
    let e = |p: usize, name: &str| EdgeRef { panel: p, edge: panels[p].edge(name) };
    let seams = vec![
        Seam { a: e(0, "outseam"), b: e(1, "outseam") },
        Seam { a: e(0, "inseam"), b: e(1, "inseam") },
        Seam { a: e(2, "outseam"), b: e(3, "outseam") },
        Seam { a: e(2, "inseam"), b: e(3, "inseam") },
        Seam { a: e(0, "crotch"), b: e(2, "crotch") },
        Seam { a: e(1, "crotch"), b: e(3, "crotch") },
    ];
    Ok(Pattern {
        kind: GarmentKind::Trousers,
        panels,
        seams,
        openings: vec!["waist", "left hem", "right hem"],
        pinned_edges: Vec::new(),
    })
}

/// A scarf laid over the shoulders round the back of the neck, both ends hanging in front.
fn scarf(l: &Landmarks, o: &PatternOptions) -> Result<Pattern> {
    let s = l.height / 1.76;
    let len = o.length_m.unwrap_or(1.5 * s);
    let width = 0.12 * s;
    if len > 2.0 * (l.neck_base_z - 0.1) + 0.6 {
        return Err(Error::Invalid(format!(
            "--length = {len} m: the scarf's ends would reach the floor"
        )));
    }
    let edges = vec![
        Edge::new("end_a", line([-width / 2.0, 0.0], [width / 2.0, 0.0], 8)),
        Edge::new("side_r", line([width / 2.0, 0.0], [width / 2.0, len], 8)),
        Edge::new("end_b", line([width / 2.0, len], [-width / 2.0, len], 8)),
        Edge::new("side_l", line([-width / 2.0, len], [-width / 2.0, 0.0], 8)),
    ];
    // Round the back of the neck the band stands as a cowl: a half cylinder of radius `xo`
    // with the width vertical, from 4 cm under the neck's base up to just under the head
    // (a cylinder is developable, so the rectangle lies on it unstretched); in front it
    // turns forward and down, twisting until its width lies across the chest, and hangs
    // straight by `hang`. (A flat ring round the neck, width horizontal, as this pattern had
    // before, squeezed the band's inner edge to 41 % of its length and crumpled it: 586
    // crossing triangle pairs at 10 000 vertices, 3 002 when that edge lay inside the neck.)
    let z_c = l.neck_base_z - 0.04 * s + 0.5 * width;
    let xo = l.neck_radius + 0.03 * s;
    let front_y = -(l.chest_ab[1] + 0.05 * s);
    let path_for = |hang: f64| {
        let mut path = Vec::new();
        let mut side = Vec::new();
        path.push([xo, front_y, z_c - hang]);
        side.push([1.0, 0.0, 0.0]);
        path.push([xo, front_y, z_c - 0.06 * s]);
        side.push([1.0, 0.0, 0.0]);
        // The twist is done halfway to the corner: twisting up to it, the band's edge dipped
        // below the corner into the hanging part (16 crossing pairs as placed in size S).
        path.push([xo, 0.5 * front_y, z_c - 0.03 * s]);
        side.push([1.0, 0.0, 0.0]);
        path.push([xo, 0.0, z_c]);
        side.push([0.0, 0.0, 1.0]);
        for k in 0..=16 {
            let a = PI * k as f64 / 16.0;
            path.push([xo * a.cos(), xo * a.sin(), z_c]);
            side.push([0.0, 0.0, 1.0]);
        }
        path.push([-xo, 0.5 * front_y, z_c - 0.03 * s]);
        side.push([-1.0, 0.0, 0.0]);
        path.push([-xo, front_y, z_c - 0.06 * s]);
        side.push([-1.0, 0.0, 0.0]);
        path.push([-xo, front_y, z_c - hang]);
        side.push([-1.0, 0.0, 0.0]);
        (path, side)
    };
    let path_length = |p: &[V3]| p.windows(2).map(|w| length(sub(w[1], w[0]))).sum::<f64>();
    // The path's length grows by 2 per metre of hang: the hang that makes it as long as the
    // scarf (an estimate from the half circle alone was 0.28 m short at size M, and the
    // placement stacked the last rows of the scarf onto one line at the path's end).
    let hang = (1.0 + (len - path_length(&path_for(1.0).0)) / 2.0).max(0.05);
    let (mut path, side) = path_for(hang);
    path.dedup();
    let panels = vec![Panel {
        name: "scarf".into(),
        edges,
        placement: Placement::Path { path, side, y0: 0.0 },
    }];
    Ok(Pattern {
        kind: GarmentKind::Scarf,
        panels,
        seams: Vec::new(),
        openings: vec!["outline"],
        pinned_edges: Vec::new(),
    })
}

/// A curtain panel 1.2 m wide gathered in six pleats onto a 0.9 m rod, 1.5 m high, hung
/// 0.45 m behind the mannequin (which faces `−y`) with its hem 0.1 m above the floor.
fn curtain(o: &PatternOptions) -> Result<Pattern> {
    let (w, h) = (1.2, o.length_m.unwrap_or(1.5));
    if h > 4.0 {
        return Err(Error::Invalid(format!(
            "--length = {h} m: a curtain panel is at most 4 m high"
        )));
    }
    let span = 0.9;
    let edges = vec![
        Edge::new("hem", line([0.0, 0.0], [w, 0.0], 8)),
        Edge::new("side_r", line([w, 0.0], [w, h], 8)),
        Edge::new("heading", line([w, h], [0.0, h], 8)),
        Edge::new("side_l", line([0.0, h], [0.0, 0.0], 8)),
    ];
    let panels = vec![Panel {
        name: "curtain".into(),
        edges,
        placement: Placement::Pleated {
            origin: [-span / 2.0, 0.45, 0.1],
            ex: [1.0, 0.0, 0.0],
            ey: [0.0, 0.0, 1.0],
            ez: [0.0, 1.0, 0.0],
            pleats: Pleats::new(w, span, 6),
        },
    }];
    Ok(Pattern {
        kind: GarmentKind::Curtain,
        panels,
        seams: Vec::new(),
        openings: vec!["outline"],
        pinned_edges: vec![EdgeRef { panel: 0, edge: 2 }],
    })
}
