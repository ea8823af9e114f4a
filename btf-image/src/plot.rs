//! Line plots rendered straight to 8-bit images (axes, ticks, labels in an 8×8 bitmap font,
//! linear or logarithmic axes, a legend), so reports need no plotting toolchain or system
//! fonts: the accuracy-against-time curves of every sweep, the eigenweightset error and
//! coefficient plots of `[S03 Fig. 12]`, the registration table's fractions.
//!
//! Rules the layout keeps (and the tests check): the legend sits to the right of the data
//! area, never over it, and the image grows so that it is never clipped; series take the
//! eight colours of Okabe & Ito (distinguishable with every common colour-vision
//! deficiency, pairwise CIELAB ΔE ≥ 26), then repeat with dashed and dotted lines, and each
//! series has its own marker shape; points may carry labels (the `c` of a sweep); a series
//! whose x is not monotone in its parameter is drawn as labelled points, not as a zig-zag.

use crate::text::{self, put};
use image::{Rgb, RgbImage};

/// One named series.
#[derive(Debug, Clone, Default)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// `(x, y)` points; non-finite or (on a log axis) non-positive ones are skipped.
    pub points: Vec<(f64, f64)>,
    /// Text drawn beside each point (empty: none; else as many as `points`).
    pub labels: Vec<String>,
    /// Markers only, no connecting line.
    pub points_only: bool,
}

impl Series {
    /// A polyline through `points`.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series { name: name.into(), points, ..Default::default() }
    }

    /// Points `(t, x, y)` of a parameter `t` (e.g. components `c`), each labelled
    /// `label(t)`: sorted by `t` and joined in that order when `x` grows with `t`; when it
    /// does not (measured times are noisy), joining them would draw a zig-zag that is no
    /// curve of anything, so they are drawn as labelled points only.
    pub fn parametric(
        name: impl Into<String>,
        mut points: Vec<(f64, f64, f64)>,
        label: impl Fn(f64) -> String,
    ) -> Series {
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let monotone = points.windows(2).all(|w| w[1].1 >= w[0].1);
        Series {
            name: name.into(),
            labels: points.iter().map(|p| label(p.0)).collect(),
            points: points.iter().map(|p| (p.1, p.2)).collect(),
            points_only: !monotone,
        }
    }
}

/// A plot description.
#[derive(Debug, Clone, Default)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// x-axis label, with its one unit: `"time to compress (s)"`.
    pub x_label: String,
    /// y-axis label, with its one unit.
    pub y_label: String,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// The lines.
    pub series: Vec<Series>,
}

/// Okabe & Ito's colour-blind-safe palette (2008), darkest-on-white first, yellow last.
pub const PALETTE: [[u8; 3]; 8] = [
    [0, 114, 178],   // blue
    [213, 94, 0],    // vermillion
    [0, 158, 115],   // bluish green
    [204, 121, 167], // reddish purple
    [86, 180, 233],  // sky blue
    [230, 159, 0],   // orange
    [0, 0, 0],       // black
    [240, 228, 66],  // yellow
];

/// Line pattern of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dash {
    /// Continuous.
    Solid,
    /// 8 on, 5 off.
    Dashed,
    /// 2 on, 4 off.
    Dotted,
}

/// Marker shapes, one per series modulo 5.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled disc.
    Disc,
    /// Filled square.
    Square,
    /// Filled triangle.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// Cross.
    Cross,
}

/// How series `k` is drawn: colour `k mod 8`, marker `k mod 5`, dash `⌊k / 8⌋ mod 3` — the
/// first 24 series all differ.
pub fn style(k: usize) -> ([u8; 3], Marker, Dash) {
    let markers = [Marker::Disc, Marker::Square, Marker::Triangle, Marker::Diamond, Marker::Cross];
    let dashes = [Dash::Solid, Dash::Dashed, Dash::Dotted];
    (PALETTE[k % 8], markers[k % 5], dashes[(k / 8) % 3])
}

/// A pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    /// Left edge.
    pub x0: i64,
    /// Top edge.
    pub y0: i64,
    /// Right edge (exclusive).
    pub x1: i64,
    /// Bottom edge (exclusive).
    pub y1: i64,
}

impl Rect {
    /// Whether the two rectangles share a pixel.
    pub fn intersects(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
}

/// Where a plot's parts go.
#[derive(Debug, Clone, Copy)]
pub struct Layout {
    /// Image size.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The data area (inside the axes).
    pub plot: Rect,
    /// The legend box (none for a single unnamed series).
    pub legend: Option<Rect>,
}

const W: i64 = 800;
const H: i64 = 480;
const LEFT: i64 = 84;
const TOP: i64 = 64;
const BOTTOM: i64 = 56;
const RIGHT: i64 = 16;
const ROW: i64 = 16;
const SAMPLE: i64 = 28;

/// The layout of `p`: the legend to the right of the data area; image wider/taller when
/// the names or the number of series need it.
pub fn layout(p: &Plot) -> Layout {
    let named = p.series.len() > 1 || p.series.iter().any(|s| !s.name.is_empty());
    let legend_w = if named {
        let longest = p.series.iter().map(|s| text::width(&s.name, 1)).max().unwrap_or(0);
        SAMPLE + 8 + longest + 16
    } else {
        0
    };
    let legend_h = p.series.len() as i64 * ROW + 12;
    let min_plot_w = 420;
    let width = W.max(LEFT + min_plot_w + 24 + legend_w + RIGHT);
    let height = H.max(TOP + legend_h + BOTTOM);
    let title_w = text::width(&p.title, 2) + LEFT;
    let width = width.max(title_w + RIGHT);
    let legend_x0 = width - RIGHT - legend_w;
    let plot = Rect {
        x0: LEFT,
        y0: TOP,
        x1: if named { legend_x0 - 24 } else { width - RIGHT - 8 },
        y1: height - BOTTOM,
    };
    let legend = named.then_some(Rect {
        x0: legend_x0,
        y0: TOP,
        x1: legend_x0 + legend_w,
        y1: TOP + legend_h,
    });
    Layout { width: width as u32, height: height as u32, plot, legend }
}

fn line(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), c: [u8; 3], thick: i64, dash: Dash) {
    let (on, period) = match dash {
        Dash::Solid => (1.0, 1.0),
        Dash::Dashed => (8.0, 13.0),
        Dash::Dotted => (2.0, 6.0),
    };
    let len = (b.0 - a.0).hypot(b.1 - a.1);
    let n = (len.ceil() as i64).max(1);
    for i in 0..=n {
        let t = i as f64 / n as f64;
        if dash != Dash::Solid && (t * len) % period >= on {
            continue;
        }
        let (x, y) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
        for dx in 0..thick {
            for dy in 0..thick {
                put(img, x.round() as i64 + dx - thick / 2, y.round() as i64 + dy - thick / 2, c);
            }
        }
    }
}

fn marker(img: &mut RgbImage, (x, y): (f64, f64), m: Marker, c: [u8; 3]) {
    let (cx, cy) = (x.round() as i64, y.round() as i64);
    let r = 4i64;
    for dy in -r..=r {
        for dx in -r..=r {
            let inside = match m {
                Marker::Disc => dx * dx + dy * dy <= r * r,
                Marker::Square => dx.abs() < r && dy.abs() < r,
                Marker::Triangle => dy >= -r && 2 * dx.abs() <= dy + r,
                Marker::Diamond => dx.abs() + dy.abs() <= r,
                Marker::Cross => (dx - dy).abs() <= 1 || (dx + dy).abs() <= 1,
            };
            if inside {
                put(img, cx + dx, cy + dy, c);
            }
        }
    }
}

fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e4 || v.abs() < 1e-2 {
        format!("{v:.0e}")
    } else if v.fract() == 0.0 {
        format!("{v:.0}")
    } else if (v * 10.0).fract().abs() < 1e-9 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

fn axis_range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for v in vals {
        let v = if log { v.log10() } else { v };
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return (0.0, 1.0);
    }
    if log {
        (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
    } else {
        let pad = ((hi - lo) * 0.08).max(1e-12);
        (if lo >= 0.0 && lo - pad < 0.0 { 0.0 } else { lo - pad }, hi + pad)
    }
}

fn ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    if log {
        let step = ((hi - lo) / 8.0).ceil().max(1.0);
        let mut v = Vec::new();
        let mut e = lo;
        while e <= hi + 1e-9 {
            v.push(e);
            e += step;
        }
        return v;
    }
    let raw = (hi - lo) / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step =
        [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(mag * 10.0);
    let mut v = Vec::new();
    let mut t = (lo / step).ceil() * step;
    while t <= hi + step * 1e-9 {
        v.push(if t.abs() < step * 1e-9 { 0.0 } else { t });
        t += step;
    }
    v
}

/// Where a point label `w` pixels wide goes: the first of eight places around the point
/// (right-above, right-below, left-above, left-below, then further out) that overlaps no
/// label placed before and stays in the data area; the last resort is the first place.
fn place_label(placed: &mut Vec<Rect>, (x, y): (f64, f64), w: i64, area: &Rect) -> (i64, i64) {
    let (x, y) = (x as i64, y as i64);
    let candidates = [
        (x + 7, y - 13),
        (x + 7, y + 5),
        (x - 7 - w, y - 13),
        (x - 7 - w, y + 5),
        (x + 7, y - 25),
        (x + 7, y + 17),
        (x - 7 - w, y - 25),
        (x - 7 - w, y + 17),
    ];
    let rect = |(cx, cy): (i64, i64)| Rect { x0: cx - 1, y0: cy - 1, x1: cx + w + 1, y1: cy + 9 };
    let fits = |q: &Rect| q.x0 >= area.x0 && q.x1 <= area.x1 + 40 && q.y0 >= area.y0 - 12;
    let at = candidates
        .iter()
        .copied()
        .find(|&c| fits(&rect(c)) && !placed.iter().any(|p| p.intersects(&rect(c))))
        .unwrap_or(candidates[0]);
    placed.push(rect(at));
    at
}

/// Renders the plot.
pub fn render(p: &Plot) -> RgbImage {
    let lay = layout(p);
    let mut img = RgbImage::from_pixel(lay.width, lay.height, Rgb([255, 255, 255]));
    let ok = |x: f64, y: f64| {
        x.is_finite() && y.is_finite() && (!p.log_y || y > 0.0) && (!p.log_x || x > 0.0)
    };
    let pts = || p.series.iter().flat_map(|s| s.points.iter().copied()).filter(|&(x, y)| ok(x, y));
    let (x0, x1) = axis_range(pts().map(|q| q.0), p.log_x);
    let (y0, y1) = axis_range(pts().map(|q| q.1), p.log_y);
    let r = lay.plot;
    let (pw, ph) = ((r.x1 - r.x0) as f64, (r.y1 - r.y0) as f64);
    let (left, top) = (r.x0 as f64, r.y0 as f64);
    let map = |x: f64, y: f64| {
        let (x, y) = (if p.log_x { x.log10() } else { x }, if p.log_y { y.log10() } else { y });
        (left + (x - x0) / (x1 - x0) * pw, top + ph - (y - y0) / (y1 - y0) * ph)
    };
    let (grey, black, ink) = ([225, 225, 225], [0, 0, 0], [60, 60, 60]);
    for t in ticks(y0, y1, p.log_y) {
        let yy = top + ph - (t - y0) / (y1 - y0) * ph;
        line(&mut img, (left, yy), (left + pw, yy), grey, 1, Dash::Solid);
        let label = fmt_tick(if p.log_y { 10f64.powf(t) } else { t });
        text::draw(&mut img, r.x0 - 8 - text::width(&label, 1), yy as i64 - 4, &label, ink, 1);
    }
    for t in ticks(x0, x1, p.log_x) {
        let xx = left + (t - x0) / (x1 - x0) * pw;
        line(&mut img, (xx, top), (xx, top + ph), grey, 1, Dash::Solid);
        let label = fmt_tick(if p.log_x { 10f64.powf(t) } else { t });
        text::draw_centred(&mut img, xx as i64, r.y1 + 8, &label, ink, 1);
    }
    line(&mut img, (left, top), (left, top + ph), black, 1, Dash::Solid);
    line(&mut img, (left, top + ph), (left + pw, top + ph), black, 1, Dash::Solid);
    let mut placed: Vec<Rect> = Vec::new();
    for (k, s) in p.series.iter().enumerate() {
        let (c, m, dash) = style(k);
        let kept: Vec<usize> =
            (0..s.points.len()).filter(|&i| ok(s.points[i].0, s.points[i].1)).collect();
        let mapped: Vec<(f64, f64)> =
            kept.iter().map(|&i| map(s.points[i].0, s.points[i].1)).collect();
        if !s.points_only {
            for w in mapped.windows(2) {
                line(&mut img, w[0], w[1], c, 2, dash);
            }
        }
        for (&i, &q) in kept.iter().zip(&mapped) {
            marker(&mut img, q, m, c);
            if let Some(l) = s.labels.get(i) {
                let at = place_label(&mut placed, q, text::width(l, 1), &r);
                text::draw(&mut img, at.0, at.1, l, ink, 1);
            }
        }
        if let Some(lg) = lay.legend {
            let ly = (lg.y0 + 6 + ROW * k as i64) as f64 + 4.0;
            let lx = lg.x0 as f64 + 6.0;
            line(&mut img, (lx, ly), (lx + SAMPLE as f64 - 4.0, ly), c, 2, dash);
            marker(&mut img, (lx + (SAMPLE as f64 - 4.0) / 2.0, ly), m, c);
            text::draw(&mut img, lg.x0 + SAMPLE + 8, ly as i64 - 4, &s.name, black, 1);
        }
    }
    if let Some(lg) = lay.legend {
        let (a, b) = ((lg.x0 as f64, lg.y0 as f64), (lg.x1 as f64 - 1.0, lg.y1 as f64 - 1.0));
        let g = [180, 180, 180];
        line(&mut img, a, (b.0, a.1), g, 1, Dash::Solid);
        line(&mut img, (a.0, b.1), b, g, 1, Dash::Solid);
        line(&mut img, a, (a.0, b.1), g, 1, Dash::Solid);
        line(&mut img, (b.0, a.1), b, g, 1, Dash::Solid);
    }
    text::draw(&mut img, r.x0, 14, &p.title, black, 2);
    text::draw(&mut img, r.x0 - 8 - 4 * 8, r.y0 - 20, &p.y_label, black, 1);
    text::draw_centred(
        &mut img,
        r.x0 + pw as i64 / 2,
        lay.height as i64 - 24,
        &p.x_label,
        black,
        1,
    );
    img
}

#[cfg(test)]
mod tests;
