//! End-to-end tests of `btf knit …` and `btf synth material --kind yarn`: a 5×5-direction
//! yarn BTF at 16² that `btf inspect` opens and `btf compress` compresses with
//! Eckart–Young holding per slot; the knit exports; refusals.

use crate::common::Dir;

#[test]
fn yarn_btf_is_an_ordinary_store_and_compresses_with_eckart_young() {
    let d = Dir::new();
    d.ok(&[
        "synth",
        "material",
        "--kind",
        "yarn",
        "--chart",
        "stockinette",
        "--yarn",
        "fine-2ply",
        "--size",
        "16",
        "--sampling",
        "rings:0x1,45x4",
        "--spp",
        "4",
        "--bounces",
        "3",
        "-o",
        "y.btf",
    ]);
    let st = btf_core::store::BtfStore::open(&d.path("y.btf")).unwrap();
    assert_eq!((st.meta().n_views(), st.meta().n_lights(), st.meta().width), (5, 5, 16));
    let prov = &st.meta().provenance;
    assert_eq!(prov["kind"], "yarn");
    assert_eq!(prov["method"], "reference");
    assert_eq!(prov["spp"], 4);
    assert_eq!(prov["chart"]["name"], "stockinette");
    assert_eq!(prov["yarn"]["preset"], "fine-2ply");
    let t = prov["transmittance"]["per_view"].as_array().unwrap();
    assert_eq!(t.len(), 5);
    assert!(t.iter().all(|v| (0.0..1.0).contains(&v.as_f64().unwrap())));
    let inspect = d.ok(&["inspect", "y.btf"]);
    assert!(inspect.contains("5 views × 5 lights"), "{inspect}");
    // Two of four possible components: the discarded eigenvalues are what is lost.
    let out = d.ok(&["compress", "y.btf", "-c", "2", "-o", "y.eig", "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    for slot in j["slots"].as_array().unwrap() {
        let (sse, disc) =
            (slot["sse"].as_f64().unwrap(), slot["discarded_eigen_sum"].as_f64().unwrap());
        assert!(disc > 0.0, "{slot}");
        assert!((sse - disc).abs() <= 1e-6 * disc, "Eckart–Young: sse {sse} vs discarded {disc}");
    }
}

#[test]
fn knit_exports_and_reference_render() {
    let d = Dir::new();
    let chart = d.ok(&["knit", "chart", "rib2x2", "-o", "rib.chart"]);
    assert!(chart.contains("kkpp"), "{chart}");
    d.ok(&["knit", "mesh", "--chart", "rib.chart", "--stitches", "4,4", "-o", "m.obj"]);
    let obj = std::fs::read_to_string(d.path("m.obj")).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("f ")).count(), 16);
    d.ok(&["knit", "skeleton", "--chart", "rib2x2", "--yarn", "fine-2ply", "-o", "s.bcc"]);
    let bcc = yarn::io::read_bcc(&d.path("s.bcc")).unwrap();
    assert_eq!(bcc.set.curves.len(), 2);
    d.ok(&[
        "knit",
        "fibers",
        "--chart",
        "garter",
        "--yarn",
        "fine-2ply",
        "--no-hairs",
        "-o",
        "f.txt",
    ]);
    let txt = std::fs::read_to_string(d.path("f.txt")).unwrap();
    assert!(txt.lines().filter(|l| l.is_empty()).count() >= 99, "one blank line between fibers");
    let js = d.ok(&[
        "knit",
        "ref",
        "--chart",
        "stockinette",
        "--yarn",
        "fine-2ply",
        "--size",
        "16,12",
        "--spp",
        "2",
        "--light",
        "dir:30,45",
        "--camera",
        "btf:20,90",
        "--json",
        "-i",
        "r.exr",
    ]);
    let j: serde_json::Value = serde_json::from_str(&js).unwrap();
    assert!(
        j["rays_per_second"].as_f64().unwrap() > 0.0 && j["coverage"].as_f64().unwrap() > 0.3,
        "{j}"
    );
    assert!(d.path("r.exr").is_file());
}

#[test]
fn knit_refusals_name_what_is_wrong() {
    let d = Dir::new();
    std::fs::write(d.path("bad.chart"), "name: bad\nkkq\n").unwrap();
    let e = d.fails(&["knit", "chart", "bad.chart"]);
    assert!(e.contains("bad.chart"), "{e}");
    let e =
        d.fails(&["knit", "ref", "--yarn", "no-such-yarn", "--light", "dir:0,0", "-o", "r.exr"]);
    assert!(e.contains("no-such-yarn"), "{e}");
    let e = d.fails(&["knit", "ref", "--chart", "stockinette", "-o", "r.exr"]);
    assert!(e.contains("no light"), "{e}");
    // An output that is an input.
    std::fs::write(d.path("c.chart"), "name: c\nkp\n").unwrap();
    let e = d.fails(&["knit", "fibers", "--chart", "c.chart", "-o", "c.chart"]);
    assert!(e.contains("c.chart"), "{e}");
    let e =
        d.fails(&["synth", "material", "--kind", "lambert", "--chart", "garter", "-o", "x.btf"]);
    assert!(e.contains("--kind yarn"), "{e}");
}

#[test]
fn knit_deform_scores_knots_against_the_reference_and_writes_the_yarns() {
    let d = Dir::new();
    // One stretch-course and one shear case besides the wale stretches.
    let deform = |stitches: &str, stretch: &str, more: &[&str]| -> String {
        let mut args = vec!["knit", "deform", "--chart", "rib1x1", "--stitches", stitches];
        args.extend(["--stretch", stretch, "--stretch-course", "0.2", "--shear", "0.3"]);
        args.extend(["--repeat", "1"]);
        args.extend(more);
        d.ok(&args)
    };
    let out = deform("4,4", "0,0.3", &["-o", "def"]);
    assert!(out.contains("4 cases"), "{out}");
    let csv = std::fs::read_to_string(d.path("def/deform.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4);
    let num = |r: &Vec<&str>, i: usize| r[i].parse::<f64>().unwrap();
    // Rest: a fixed point, every deviation zero.
    assert_eq!(rows[0][0], "rest");
    assert_eq!(num(&rows[0], 4), 0.0);
    for i in 6..12 {
        assert_eq!(num(&rows[0], i), 0.0, "rest column {i}");
    }
    for r in &rows[1..] {
        let (e0, e3, einf) = (num(r, 3), num(r, 4), num(r, 5));
        assert!(einf <= e3 * (1.0 + 1e-9) && e3 <= e0, "{r:?}: E_∞ ≤ E₃ ≤ E₀");
        // [H25 Fig. 9]: naive > knots > knots + GN in RMS deviation from the reference.
        assert!(num(r, 6) > num(r, 7) && num(r, 7) > num(r, 8), "{r:?}");
        for i in 13..16 {
            let c = num(r, i);
            assert!(c > 0.5 && c < 1.5, "clearance / 2r {c} in {r:?}");
        }
    }
    for name in ["report.md", "clearance.png", "deviation.png", "yarns.png"] {
        assert!(d.path(&format!("def/{name}")).is_file(), "{name}");
    }
    // The solved yarns are BCC that the reference renderer reads back.
    let f = yarn::io::read_bcc(&d.path("def/yarns/shear-0.3.bcc")).unwrap();
    assert_eq!(f.set.curves.len(), 4);
    assert!(d.path("def/yarns/shear-0.3-reference.bcc").is_file());
    // Without --contact and --relaxed-rest their columns are empty (never NaN).
    assert!(rows.iter().all(|r| r.len() == 28 && r[19..].iter().all(|c| c.is_empty())), "{csv}");
    // --contact: each converged reference relaxed with the yarn–yarn contact penalty
    // (DESIGN §3.3 item 1) reaches the clearance the knots lack (0.88 × 2r at rest).
    // --relaxed-rest: the template relaxed once on a 4 × 4 patch and carried on every
    // solve (yarn::knit::knot::detail) lifts the solve's clearance too.
    let out = deform(
        "4,2",
        "0",
        &["--contact", "--contact-iterations", "120", "--relaxed-rest", "-o", "con"],
    );
    assert!(out.contains("rest detail: 4 × 4 patch"), "{out}");
    let csv = std::fs::read_to_string(d.path("con/deform.csv")).unwrap();
    for r in csv.lines().skip(1).map(|l| l.split(',').collect::<Vec<_>>()) {
        let (reference, contact) = (num(&r, 15), num(&r, 19));
        let (gn, gn_detail) = (num(&r, 14), num(&r, 24));
        eprintln!(
            "{}: clearance reference {reference:.3}, contact reference {contact:.3}, GN {gn:.3}, \
             GN + rest detail {gn_detail:.3}; RMS from the contact reference GN {:.3} r, GN + \
             detail {:.3} r",
            r[0],
            num(&r, 20),
            num(&r, 26)
        );
        assert!(contact >= 0.95 && contact > reference, "{r:?}");
        assert!(num(&r, 21) > 0.0, "the knot solve is off the contact reference: {r:?}");
        // Measured: 0.997, 0.962, 0.896 (rest, 20 % course stretch, 30 % shear).
        assert!(gn_detail > gn && gn_detail >= 0.88, "{r:?}");
        assert!(num(&r, 25) >= 0.0 && num(&r, 27) >= num(&r, 26), "{r:?}");
        if r[0] == "rest" {
            assert!(num(&r, 26) < num(&r, 20), "the relaxed rest is nearer: {r:?}");
        }
    }
    assert!(d.path("con/yarns/rest-detail.bcc").is_file());
    assert!(std::fs::read_to_string(d.path("con/report.md")).unwrap().contains("relaxed rest"));
    assert!(
        std::fs::read_to_string(d.path("con/report.md")).unwrap().contains("contact reference")
    );
    assert!(d.path("con/yarns/rest-contact.bcc").is_file());
    // Cables are refused with the reason.
    let e = d.fails(&["knit", "deform", "--chart", "cable2x2", "--stitches", "8,4", "-o", "cab"]);
    assert!(e.contains("cable") && e.contains("unsupported"), "{e}");
}

#[test]
fn knit_deform_follows_the_drape_frame_by_frame() {
    let d = Dir::new();
    let out = d.ok(&[
        "knit",
        "deform",
        "--chart",
        "rib1x1",
        "--drape",
        "2",
        "--wales",
        "8",
        "--cloth-res",
        "12",
        "--max-sweeps",
        "30",
        "-o",
        "dr",
    ]);
    assert!(out.contains("knot faces"), "{out}");
    let csv = std::fs::read_to_string(d.path("dr/drape.csv")).unwrap();
    let rows: Vec<Vec<f64>> =
        csv.lines().skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 3, "the flat start and two frames");
    // The flat start is the rest: no energy, no strain, the template's clearance.
    assert!(rows[0][3] < 1e-18 && rows[0][6] < 1e-9 && rows[0][7] < 1e-9, "{:?}", rows[0]);
    assert!((rows[0][8] - rows[0][9]).abs() < 1e-9, "knots = naive at rest");
    for r in &rows[1..] {
        assert!(r[4] <= r[3], "the iterations lower the energy: {r:?}");
        assert!(r[7] > 0.0, "the cloth deforms: {r:?}");
        assert!(r[2].is_finite() && r[2] > 0.0);
    }
    for k in 0..3 {
        assert!(d.path(&format!("dr/drape/frame-{k:03}.bcc")).is_file());
    }
    assert!(d.path("dr/drape-strain.png").is_file() && d.path("dr/drape.md").is_file());
    // --relaxed-rest: the flat start carries the relaxed template (the yarns touch instead
    // of overlapping); the drape's bent frames are what BENCHMARKS.md reports.
    d.ok(&[
        "knit",
        "deform",
        "--chart",
        "rib1x1",
        "--drape",
        "1",
        "--wales",
        "8",
        "--cloth-res",
        "12",
        "--max-sweeps",
        "30",
        "--relaxed-rest",
        "-o",
        "drr",
    ]);
    let csv = std::fs::read_to_string(d.path("drr/drape.csv")).unwrap();
    let relaxed: Vec<Vec<f64>> =
        csv.lines().skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    assert_eq!(relaxed.len(), 2);
    eprintln!("flat start: clearance {:.3} → {:.3} with --relaxed-rest", rows[0][8], relaxed[0][8]);
    assert!(relaxed[0][8] > 0.95 && rows[0][8] < 0.9, "{csv}");
    assert!(relaxed[0][3] < 1e-18, "the solve itself is untouched at rest: {csv}");
}
