//! Tests of the plot layout, palette and drawing.

use super::*;

/// CIELAB (D65) of an 8-bit sRGB colour.
fn lab(c: [u8; 3]) -> [f64; 3] {
    let lin = |v: u8| crate::color::srgb_decode(v as f32 / 255.0) as f64;
    let (r, g, b) = (lin(c[0]), lin(c[1]), lin(c[2]));
    let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
    let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
    let d = 6.0f64 / 29.0;
    let f = |t: f64| if t > d.powi(3) { t.cbrt() } else { t / (3.0 * d * d) + 4.0 / 29.0 };
    [116.0 * f(y) - 16.0, 500.0 * (f(x) - f(y)), 200.0 * (f(y) - f(z))]
}

#[test]
fn palette_colours_are_pairwise_distinct_in_cielab() {
    // Okabe–Ito's closest pair is blue / sky blue at ΔE*76 = 26.4; a just-noticeable
    // difference is ≈ 2.3, and ≥ 20 reads as different colours at a glance.
    let mut worst = f64::MAX;
    for i in 0..8 {
        for j in i + 1..8 {
            let (a, b) = (lab(PALETTE[i]), lab(PALETTE[j]));
            let de = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            worst = worst.min(de);
        }
    }
    assert!((worst - 26.43).abs() < 0.1, "closest pair ΔE {worst}");
    // Every colour is visibly darker than the white page (L* ≤ 90).
    assert!(PALETTE.iter().all(|&c| lab(c)[0] <= 90.0));
    // The first 24 series all differ in colour, marker or dash.
    let styles: Vec<_> = (0..24).map(style).collect();
    for i in 0..24 {
        for j in i + 1..24 {
            assert_ne!(styles[i], styles[j], "series {i} and {j}");
        }
    }
}

fn plot_with(n: usize, name_len: usize) -> Plot {
    Plot {
        title: "a title".into(),
        x_label: "x (s)".into(),
        y_label: "y (MiB)".into(),
        series: (0..n)
            .map(|k| {
                let pts = (0..5).map(|i| (i as f64, (i * (k + 1)) as f64 + 1.0)).collect();
                Series::new(format!("{k}{}", "n".repeat(name_len)), pts)
            })
            .collect(),
        ..Default::default()
    }
}

#[test]
fn legend_is_outside_the_data_area_and_inside_the_image() {
    for (n, len) in [(1, 3), (4, 20), (12, 40), (40, 8)] {
        let p = plot_with(n, len);
        let lay = layout(&p);
        let lg = lay.legend.expect("named series have a legend");
        assert!(!lg.intersects(&lay.plot), "{n} series: {lg:?} over {:?}", lay.plot);
        assert!(lg.x0 >= 0 && lg.y0 >= 0, "{lg:?}");
        assert!(lg.x1 <= lay.width as i64 && lg.y1 <= lay.height as i64, "{n}: {lg:?}");
        // The longest name fits inside the box, after the line sample.
        let longest = p.series.iter().map(|s| text::width(&s.name, 1)).max().unwrap();
        assert!(lg.x0 + SAMPLE + 8 + longest <= lg.x1, "{n}: name clipped");
        assert!(lay.width >= 800 && lay.height >= 480, "{}×{}", lay.width, lay.height);
        // The data area keeps at least 420 px of width.
        assert!(lay.plot.x1 - lay.plot.x0 >= 420);
        let img = render(&p);
        assert_eq!((img.width(), img.height()), (lay.width, lay.height));
    }
}

#[test]
fn series_are_drawn_inside_the_data_area_or_the_legend() {
    let p = Plot {
        log_y: true,
        series: vec![Series::new("a", vec![(1.0, 1e-3), (2.0, 1e-1), (3.0, f64::NAN), (4.0, 0.0)])],
        ..plot_with(0, 0)
    };
    let lay = layout(&p);
    let img = render(&p);
    let (r, lg) = (lay.plot, lay.legend.unwrap());
    // Markers (radius 4) may reach 5 px past the data area's edge, no further.
    let near =
        |x: i64, y: i64, q: &Rect| x >= q.x0 - 5 && x < q.x1 + 5 && y >= q.y0 - 5 && y < q.y1 + 5;
    let mut inside = 0;
    for (x, y, px) in img.enumerate_pixels() {
        if px.0 == PALETTE[0] {
            assert!(near(x as i64, y as i64, &r) || near(x as i64, y as i64, &lg), "({x}, {y})");
            inside += usize::from(near(x as i64, y as i64, &r));
        }
    }
    // Two markers (≈ 2 × 49 px) and a 2 px wide line across the plot's height.
    assert!(inside > 2 * 40 + 2 * (r.y1 - r.y0) as usize / 2, "{inside} series pixels");
    assert_eq!(ticks(-3.0, -1.0, true), vec![-3.0, -2.0, -1.0]);
}

#[test]
fn parametric_series_sort_by_parameter_and_refuse_zig_zags() {
    let label = |c: f64| format!("c={c}");
    let s = Series::parametric("t", vec![(4.0, 3.0, 0.1), (1.0, 1.0, 0.5), (2.0, 2.0, 0.3)], label);
    assert_eq!(s.points, vec![(1.0, 0.5), (2.0, 0.3), (3.0, 0.1)]);
    assert_eq!(s.labels, vec!["c=1", "c=2", "c=4"]);
    assert!(!s.points_only);
    let z = Series::parametric("t", vec![(1.0, 1.0, 0.5), (2.0, 0.8, 0.3), (4.0, 3.0, 0.1)], label);
    assert!(z.points_only, "time fell from c = 1 to 2: no line");
}

#[test]
fn labels_of_crowded_points_do_not_overlap() {
    let area = Rect { x0: 0, y0: 0, x1: 400, y1: 300 };
    let mut placed = Vec::new();
    // Three points 3 px apart: each label takes a free place.
    for k in 0..3 {
        place_label(&mut placed, (100.0 + 3.0 * k as f64, 100.0), 32, &area);
    }
    for i in 0..3 {
        for j in i + 1..3 {
            assert!(!placed[i].intersects(&placed[j]), "{:?} {:?}", placed[i], placed[j]);
        }
    }
}
