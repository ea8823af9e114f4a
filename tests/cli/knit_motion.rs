//! End-to-end tests of the lumislice and animation commands (issue #21, with #20's
//! `btf knit animate`): `btf knit lumislice` on a tiny patch against the volumetric
//! reference (its CSV rows and numbers, the tubes baseline, the sheets), and `btf knit
//! animate` on a tiny scarf — BCC and PNG frames, the report, a second run that resumes
//! from the cached simulation and the frames on disk, and refusals that name the flag.
//! GPU runs are skipped without an adapter unless `BTF_REQUIRE_GPU=1`.

use crate::common::Dir;
use crate::knit_sweep::rows;

fn run_gpu(d: &Dir, args: &[&str]) -> Option<(String, String)> {
    let o = d.btf(args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    if !o.status.success() && err.contains("no GPU adapter") {
        assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "{err}");
        eprintln!("skipped: {err}");
        return None;
    }
    assert!(o.status.success(), "btf {args:?} failed:\n{err}");
    Some((String::from_utf8(o.stdout).unwrap(), err))
}

#[test]
fn knit_lumislice_scores_variants_against_the_volume_reference() {
    let d = Dir::new();
    let args = [
        "knit",
        "lumislice",
        "--size",
        "24,24",
        "--spp",
        "2",
        "--repeat",
        "1",
        "--distances",
        "16",
        "--variants",
        "default,no-shadow,res16",
        "-o",
        "ls",
    ];
    let Some((out, _)) = run_gpu(&d, &args) else { return };
    assert!(out.contains("what accuracy costs in time"), "{out}");
    let csv = std::fs::read_to_string(d.path("ls/lumislice.csv")).unwrap();
    let r = rows(&csv);
    assert_eq!(r.len(), 3, "{csv}");
    for (row, v) in r.iter().zip(["default", "no-shadow", "res16"]) {
        assert_eq!(row["variant"], v);
        let e: f64 = row["rel_rmse"].parse().unwrap();
        let m: f64 = row["mean_ratio"].parse().unwrap();
        let t: f64 = row["ratio_tubes"].parse().unwrap();
        // A bug detector, not an accuracy claim: the same yarns, light and camera.
        assert!(e.is_finite() && e < 1.0, "{csv}");
        assert!((0.6..1.6).contains(&m), "{csv}");
        assert!(t.is_finite() && t > 0.0, "{csv}");
    }
    // Without eq. 10 the patch is brighter than with it (other yarns' shadows are gone).
    let m = |i: usize| r[i]["mean_ratio"].parse::<f64>().unwrap();
    assert!(m(1) > m(0), "{csv}");
    // A 16² table is a quarter of a 32² one (two levels against three).
    let b = |i: usize| r[i]["table_bytes"].parse::<f64>().unwrap();
    assert!((b(2) / b(0) - 0.25 * (1.0 + 0.25) / (1.0 + 0.25 + 0.0625)).abs() < 1e-9, "{csv}");
    for f in
        ["ls/lumislice.md", "ls/lumislice.png", "ls/sheet-persp-16px.png", "ls/ref-persp-16px.exr"]
    {
        assert!(d.path(f).is_file(), "{f}");
    }
    let e = d.fails(&["knit", "lumislice", "--variants", "shiny", "-o", "ls2"]);
    assert!(e.contains("--variants shiny"), "{e}");
    let e = d.fails(&["knit", "lumislice", "--stitches", "400,4", "-o", "ls2"]);
    assert!(e.contains("--stitches 400,4"), "{e}");
    let e = d.fails(&["knit", "lumislice", "--albedo", "1.5", "-o", "ls2"]);
    assert!(e.contains("--albedo 1.5"), "{e}");
    assert!(!d.path("ls2").exists());
}

#[test]
fn knit_animate_writes_frames_and_resumes() {
    let d = Dir::new();
    let args =
        ["knit", "animate", "--loops", "4,4", "--seconds", "0.12", "--render", "32,24", "-o", "an"];
    let Some((out, _)) = run_gpu(&d, &args) else { return };
    assert!(out.contains("Knit animation"), "{out}");
    let csv = std::fs::read_to_string(d.path("an/animate.csv")).unwrap();
    let r = rows(&csv);
    assert_eq!(r.len(), 4, "frames at 0, 0.04, 0.08, 0.12 s: {csv}");
    for (k, row) in r.iter().enumerate() {
        let bcc = d.path(&format!("an/frames/frame-{k:04}.bcc"));
        assert!(bcc.is_file());
        let png = std::fs::read(d.path(&format!("an/frames/frame-{k:04}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        let ms: f64 = row["solve_ms"].parse().unwrap();
        assert!(ms.is_finite() && ms >= 0.0, "{csv}");
        if k > 0 {
            assert!(row["steps"].parse::<usize>().unwrap() > 0, "{csv}");
        }
    }
    // The frames' curves move: the scarf falls.
    let z = |k: usize| {
        let set = yarn::io::read_bcc(&d.path(&format!("an/frames/frame-{k:04}.bcc"))).unwrap().set;
        let pts: Vec<f64> = set.curves.iter().flat_map(|c| c.points.iter().map(|p| p[2])).collect();
        pts.iter().sum::<f64>() / pts.len() as f64
    };
    assert!(z(3) < z(0) - 1e-3, "falls: {} → {}", z(0), z(3));
    assert!(d.path("an/sheet.png").is_file() && d.path("an/animate.png").is_file());
    // Again: the simulation from the cache, every frame already there.
    let (_, err) = run_gpu(&d, &args).unwrap();
    assert!(err.contains("from the cache"), "{err}");
    let csv = std::fs::read_to_string(d.path("an/animate.csv")).unwrap();
    assert!(rows(&csv).iter().all(|r| r["solve_ms"].is_empty()), "nothing redone: {csv}");
    // --relaxed-rest: the chart's contact-relaxed template rides on every solve; the flat
    // start's yarns move apart (the template's 0.88 × 2r, the relaxed rest's ~1.0).
    let out = d.ok(&[
        "knit",
        "animate",
        "--loops",
        "4,4",
        "--seconds",
        "0.04",
        "--relaxed-rest",
        "-o",
        "an3",
    ]);
    assert!(out.contains("rest detail relaxed"), "{out}");
    let clearance = |dir: &str| {
        let set = yarn::io::read_bcc(&d.path(&format!("{dir}/frames/frame-0000.bcc"))).unwrap().set;
        let r = yarn::params::YarnParams::preset("cotton-2ply").unwrap().yarn_radius();
        yarn::knit::knot::min_clearance(&set, None, r, 8).ratio
    };
    let (plain, relaxed) = (clearance("an"), clearance("an3"));
    eprintln!("flat start: clearance {plain:.3} → {relaxed:.3} × 2r with --relaxed-rest");
    assert!(plain < 0.9 && relaxed > 0.95, "{plain} → {relaxed}");
    let e = d.fails(&["knit", "animate", "--loops", "5,4", "-o", "an2"]);
    assert!(e.contains("--loops 5,4"), "{e}");
    let e = d.fails(&["knit", "animate", "--seconds", "0", "-o", "an2"]);
    assert!(e.contains("--seconds 0"), "{e}");
}

/// `btf synth material --kind yarn --method lumislice`: the yarn BTF by the lumislices, an
/// ordinary store with its provenance; the head-on view under the head-on light is brighter
/// than under a grazing one (the yarns shade each other).
#[test]
fn synth_material_yarn_by_lumislices() {
    let d = Dir::new();
    let args = [
        "synth",
        "material",
        "--kind",
        "yarn",
        "--method",
        "lumislice",
        "--size",
        "8",
        "--sampling",
        "rings:0x1,60x4",
        "-o",
        "y.btf",
    ];
    let Some(_) = run_gpu(&d, &args) else { return };
    let st = btf_core::store::BtfStore::open(&d.path("y.btf")).unwrap();
    let prov = &st.meta().provenance;
    assert_eq!(prov["method"], "lumislice", "{prov}");
    assert_eq!(prov["table"]["res"], 32, "{prov}");
    let mean = |l: usize| {
        let img = st.read_image(0, l).unwrap();
        assert!(img.iter().all(|x| x.is_finite() && *x >= 0.0));
        img.iter().map(|x| *x as f64).sum::<f64>() / img.len() as f64
    };
    let (head_on, grazing) = (mean(0), mean(1));
    assert!(head_on > 0.0 && grazing < head_on, "{head_on} vs {grazing}");
    assert!(d.path(".yarn-cache").is_dir(), "the table is cached beside the store");
}

/// `btf knit render --method lumislice`: the patch by the lumislices, its JSON naming the
/// method, a covered and lit frame; without yarn shadows (eq. 10 off) it is brighter.
#[test]
fn knit_render_draws_lumislices() {
    let d = Dir::new();
    let base = [
        "knit",
        "render",
        "--method",
        "lumislice",
        "--size",
        "32,32",
        "--light",
        "dir:40,30,3",
        "--cache",
        "cache",
        "--json",
        "-o",
    ];
    let Some((out, err)) = run_gpu(&d, &[&base[..], &["a.exr"]].concat()) else { return };
    assert!(err.contains("lumislice pieces"), "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["method"], "lumislice", "{j}");
    let cov = j["coverage"].as_f64().unwrap();
    assert!(cov > 0.3 && cov <= 1.0 + 1e-6, "{j}");
    // The default btf:0,0 camera is an exactly vertical orthographic view of a flat patch:
    // box faces edge-on to it are zero-area triangles with non-finite interpolants, which
    // once put a NaN into this very frame. Every pixel is finite.
    let (_, _, px) = crate::common::read_exr(&d.path("a.exr"));
    assert!(px.iter().all(|v| v.is_finite()), "a non-finite pixel");
    let (out2, _) = run_gpu(&d, &[&base[..], &["b.exr", "--no-yarn-shadows"]].concat()).unwrap();
    let j2: serde_json::Value = serde_json::from_str(&out2).unwrap();
    let (m, m2) = (j["mean_radiance"].as_f64().unwrap(), j2["mean_radiance"].as_f64().unwrap());
    assert!(m > 0.0 && m2 > m, "eq. 10 shades: {m} with, {m2} without");
    assert!(d.path("cache").is_dir(), "the table is cached in --cache");
}
