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
    let e = d.fails(&[
        "synth",
        "material",
        "--kind",
        "yarn",
        "--method",
        "lumislice",
        "--size",
        "4",
        "-o",
        "x.btf",
    ]);
    assert!(e.contains("lumislice"), "{e}");
    let e =
        d.fails(&["synth", "material", "--kind", "lambert", "--chart", "garter", "-o", "x.btf"]);
    assert!(e.contains("--kind yarn"), "{e}");
}
