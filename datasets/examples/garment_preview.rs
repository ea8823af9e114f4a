//! Development pictures of the mannequin and the draped garments: software-rasterised
//! previews (front and back) and the garment OBJ, with the checks' figures printed.
//! `cargo run --release -p datasets --example garment_preview` writes them to
//! `$GARMENT_PREVIEW_DIR` (default /tmp); `GARMENT_KINDS=tshirt,trousers`,
//! `GARMENT_VERTICES` (default 2000) and `GARMENT_DRAPE_S` choose what is draped. (The
//! garments' properties are asserted by `datasets::garment` tests and `tests/cli/garment.rs`;
//! this only makes pictures.)

use datasets::garment::body::{Body, BodyParams, Size};
use datasets::garment::preview::{PreviewItem, render_png};
use std::path::PathBuf;

fn out(name: &str) -> PathBuf {
    PathBuf::from(std::env::var("GARMENT_PREVIEW_DIR").unwrap_or_else(|_| "/tmp".into())).join(name)
}

fn preview_body() {
    let t = std::time::Instant::now();
    let body = Body::new(&BodyParams::new(Size::M)).unwrap();
    eprintln!(
        "body: {} vertices, {} triangles, {:.2} s",
        body.mesh.positions.len(),
        body.mesh.triangles.len(),
        t.elapsed().as_secs_f64()
    );
    let items = [PreviewItem { mesh: &body.mesh, colour: [0.6, 0.6, 0.6], stripe_m: 0.0 }];
    render_png(&items, [0.9, -3.2, 1.2], [0.0, 0.0, 0.95], 38.0, 400, 500, &out("body-front.png"))
        .unwrap();
    render_png(&items, [3.3, -0.6, 1.1], [0.0, 0.0, 0.95], 38.0, 400, 500, &out("body-side.png"))
        .unwrap();
}

fn preview_garment(kind: &str, vertices: usize) {
    use datasets::garment::{GarmentKind, GarmentOptions, check, make};
    let kind = GarmentKind::from_name(kind).unwrap();
    let mut o = GarmentOptions::new(Size::M);
    o.vertices = vertices;
    if let Ok(v) = std::env::var("GARMENT_DRAPE_S") {
        o.drape.drape_max_s = v.parse().unwrap();
    }
    let t = std::time::Instant::now();
    let mut last = String::new();
    let (g, body) = make(kind, &o, None, &mut |stage, f| {
        let s = format!("{stage} {:.0}", f * 10.0);
        if s != last {
            eprintln!("  {stage} {:.0} % at {:.1} s", f * 100.0, t.elapsed().as_secs_f64());
            last = s;
        }
    })
    .unwrap();
    eprintln!(
        "{}: {} vertices, h {:.4}, sewing {:?} gap {:.4}, drape {:?}, {:.1} s",
        kind.name(),
        g.mesh.positions.len(),
        g.spacing_m,
        g.sewing,
        g.seam_gap_at_weld_m,
        g.drape,
        t.elapsed().as_secs_f64()
    );
    let topo = check::topology(g.mesh.positions.len(), &g.mesh.triangles);
    eprintln!("topology {topo:?}");
    eprintln!("min body distance {:.5}", check::min_body_distance(&g.mesh, &body.sdf));
    eprintln!("self intersections {}", check::self_intersections(&g.mesh).len());
    let d = check::area_distortion(&g.mesh);
    eprintln!(
        "area distortion {:.4} … {:.4}",
        d.iter().copied().fold(f64::MAX, f64::min),
        d.iter().copied().fold(f64::MIN, f64::max)
    );
    eprintln!("grain {:?}", check::grain(&g.mesh, &g.triangle_panel));
    let items = [
        PreviewItem { mesh: &body.mesh, colour: [0.55, 0.55, 0.55], stripe_m: 0.0 },
        PreviewItem { mesh: &g.mesh, colour: [0.75, 0.35, 0.2], stripe_m: 0.02 },
    ];
    let name = kind.name();
    render_png(
        &items,
        [0.9, -3.2, 1.2],
        [0.0, 0.0, 0.95],
        38.0,
        400,
        500,
        &out(&format!("{name}-front.png")),
    )
    .unwrap();
    render_png(
        &items,
        [-2.4, 2.4, 1.5],
        [0.0, 0.0, 0.95],
        38.0,
        400,
        500,
        &out(&format!("{name}-back.png")),
    )
    .unwrap();
    datasets::write_obj(&g.mesh, &out(&format!("{name}.obj")), name).unwrap();
}

fn main() {
    preview_body();
    let kinds = std::env::var("GARMENT_KINDS").unwrap_or_else(|_| "tshirt".into());
    let n: usize =
        std::env::var("GARMENT_VERTICES").ok().and_then(|v| v.parse().ok()).unwrap_or(2000);
    for k in kinds.split(',') {
        preview_garment(k, n);
    }
}
