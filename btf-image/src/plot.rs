//! Line plots rendered straight to 8-bit images (axes, ticks, labels in an 8×8 bitmap font,
//! linear or logarithmic axes, a legend), so reports need no plotting toolchain or system
//! fonts: the accuracy-against-time curves of every sweep, the eigenweightset error and
//! coefficient plots of `[S03 Fig. 12]`, the registration table's fractions.

use image::{Rgb, RgbImage};

/// One named polyline.
pub struct Series {
    /// Legend text.
    pub name: String,
    /// `(x, y)` points; non-finite or (on a log axis) non-positive ones are skipped.
    pub points: Vec<(f64, f64)>,
}

/// A plot description.
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// The lines.
    pub series: Vec<Series>,
}

const COLORS: [[u8; 3]; 6] =
    [[31, 119, 180], [214, 39, 40], [44, 160, 44], [148, 103, 189], [255, 127, 14], [23, 190, 207]];
const W: u32 = 720;
const H: u32 = 460;
const L: i64 = 90;
const R: i64 = 20;
const T: i64 = 40;
const B: i64 = 60;

fn text(img: &mut RgbImage, x: i64, y: i64, s: &str, color: [u8; 3]) {
    for (k, ch) in s.chars().enumerate() {
        let glyph = font8x8::legacy::BASIC_LEGACY.get(ch as usize).copied().unwrap_or([0; 8]);
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) != 0 {
                    put(img, x + k as i64 * 8 + col, y + row as i64, color);
                }
            }
        }
    }
}

fn put(img: &mut RgbImage, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, Rgb(c));
    }
}

fn line(img: &mut RgbImage, (x0, y0): (f64, f64), (x1, y1): (f64, f64), c: [u8; 3], thick: i64) {
    let n = ((x1 - x0).abs().max((y1 - y0).abs()).ceil() as i64).max(1);
    for i in 0..=n {
        let t = i as f64 / n as f64;
        let (x, y) = (x0 + t * (x1 - x0), y0 + t * (y1 - y0));
        for dx in 0..thick {
            for dy in 0..thick {
                put(img, x.round() as i64 + dx - thick / 2, y.round() as i64 + dy - thick / 2, c);
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
        let pad = ((hi - lo) * 0.05).max(1e-12);
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
        v.push(t);
        t += step;
    }
    v
}

/// Renders the plot.
pub fn render(p: &Plot) -> RgbImage {
    let mut img = RgbImage::from_pixel(W, H, Rgb([255, 255, 255]));
    let ok = |x: f64, y: f64| {
        x.is_finite() && y.is_finite() && (!p.log_y || y > 0.0) && (!p.log_x || x > 0.0)
    };
    let pts = || p.series.iter().flat_map(|s| s.points.iter().copied()).filter(|&(x, y)| ok(x, y));
    let (x0, x1) = axis_range(pts().map(|q| q.0), p.log_x);
    let (y0, y1) = axis_range(pts().map(|q| q.1), p.log_y);
    let (pw, ph) = ((W as i64 - L - R) as f64, (H as i64 - T - B) as f64);
    let map = |x: f64, y: f64| {
        let (x, y) = (if p.log_x { x.log10() } else { x }, if p.log_y { y.log10() } else { y });
        (L as f64 + (x - x0) / (x1 - x0) * pw, T as f64 + ph - (y - y0) / (y1 - y0) * ph)
    };
    let grey = [200, 200, 200];
    for t in ticks(y0, y1, p.log_y) {
        let yy = T as f64 + ph - (t - y0) / (y1 - y0) * ph;
        line(&mut img, (L as f64, yy), (L as f64 + pw, yy), grey, 1);
        let label = fmt_tick(if p.log_y { 10f64.powf(t) } else { t });
        text(&mut img, L - 8 - 8 * label.len() as i64, yy as i64 - 4, &label, [0, 0, 0]);
    }
    for t in ticks(x0, x1, p.log_x) {
        let xx = L as f64 + (t - x0) / (x1 - x0) * pw;
        line(&mut img, (xx, T as f64), (xx, T as f64 + ph), grey, 1);
        let label = fmt_tick(if p.log_x { 10f64.powf(t) } else { t });
        text(&mut img, xx as i64 - 4 * label.len() as i64, T + ph as i64 + 8, &label, [0, 0, 0]);
    }
    let black = [0, 0, 0];
    line(&mut img, (L as f64, T as f64), (L as f64, T as f64 + ph), black, 1);
    line(&mut img, (L as f64, T as f64 + ph), (L as f64 + pw, T as f64 + ph), black, 1);
    for (k, s) in p.series.iter().enumerate() {
        let c = COLORS[k % COLORS.len()];
        let mapped: Vec<(f64, f64)> =
            s.points.iter().filter(|q| ok(q.0, q.1)).map(|q| map(q.0, q.1)).collect();
        for w in mapped.windows(2) {
            line(&mut img, w[0], w[1], c, 2);
        }
        for &(x, y) in &mapped {
            for d in -2..=2 {
                put(&mut img, x as i64 + d, y as i64, c);
                put(&mut img, x as i64, y as i64 + d, c);
            }
        }
        let ly = T + 8 + 14 * k as i64;
        line(
            &mut img,
            ((W as i64 - R - 170) as f64, ly as f64 + 3.0),
            ((W as i64 - R - 150) as f64, ly as f64 + 3.0),
            c,
            3,
        );
        text(&mut img, W as i64 - R - 144, ly, &s.name, black);
    }
    text(&mut img, L, 14, &p.title, black);
    text(
        &mut img,
        L + (pw as i64 - 8 * p.x_label.len() as i64) / 2,
        H as i64 - 22,
        &p.x_label,
        black,
    );
    text(&mut img, 6, T - 18, &p.y_label, black);
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_series_inside_the_frame() {
        let p = Plot {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_y: true,
            log_x: false,
            series: vec![Series {
                name: "a".into(),
                points: vec![(1.0, 1e-3), (2.0, 1e-1), (3.0, f64::NAN), (4.0, 0.0)],
            }],
        };
        let img = render(&p);
        let blue = img.pixels().filter(|px| px.0 == COLORS[0]).count();
        assert!(blue > 50, "{blue} series pixels");
        assert_eq!(ticks(-3.0, -1.0, true), vec![-3.0, -2.0, -1.0]);
    }
}
