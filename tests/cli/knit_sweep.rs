//! End-to-end tests of the GPU fiber commands (issue #19): `btf knit render` with its
//! `--json` stats, its hairs (`--no-hairs` drops exactly them) and `--compare` (a render
//! against an identical render scores exactly 0),
//! and `btf knit sweep` on a tiny grid (32², ω^LoD ∈ {0, 2}, 4 spp): its CSV rows and
//! numbers (finite errors, the tubes row at ratio 1, fewer instances at the coarser LoD,
//! triangles = instances·2·n_sub), the Markdown, plot and reference images; and refusals
//! that name the flag; `knit render --env` (the fibers lit by the map's SRBF lobes).
//! GPU runs are skipped without an adapter unless `BTF_REQUIRE_GPU=1`.

use crate::common::Dir;

/// `btf ARGS`: stdout, or `None` when there is no GPU adapter and none is required.
fn run_gpu(d: &Dir, args: &[&str]) -> Option<String> {
    let o = d.btf(args);
    let err = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() && err.contains("no GPU adapter") {
        assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "{err}");
        eprintln!("skipped: {err}");
        return None;
    }
    assert!(o.status.success(), "btf {args:?} failed:\n{err}");
    Some(String::from_utf8(o.stdout).unwrap())
}

const RENDER: [&str; 10] =
    ["knit", "render", "--size", "32,32", "--light", "dir:30,45", "--lod-px", "0", "--json", "-o"];

#[test]
fn knit_render_stats_and_compare_against_itself_is_zero() {
    let d = Dir::new();
    let Some(js) = run_gpu(&d, &[&RENDER[..], &["a.exr"]].concat()) else { return };
    let j: serde_json::Value = serde_json::from_str(&js).unwrap();
    let (seg, inst, tri) = (
        j["segments"].as_u64().unwrap(),
        j["instances"].as_u64().unwrap(),
        j["triangles"].as_u64().unwrap(),
    );
    // 3 × 3 periods of the stockinette repeat; full detail: many fibers per segment.
    assert!(seg > 0 && inst > 10 * (seg - j["culled"].as_u64().unwrap()), "{j}");
    assert_eq!(tri, inst * 2 * 8, "triangles = instances · 2 · n_sub");
    let bpc = j["bytes_per_control_point"].as_f64().unwrap();
    assert!((100.0..1000.0).contains(&bpc), "{bpc} bytes per control point");
    assert!(j["coverage"].as_f64().unwrap() > 0.3, "{j}");
    let js = run_gpu(&d, &[&RENDER[..], &["b.exr", "--compare", "a.exr"]].concat()).unwrap();
    let j: serde_json::Value = serde_json::from_str(&js).unwrap();
    assert_eq!(j["rel_rmse"].as_f64(), Some(0.0), "{j}");
    // The yarn's hair flyaways are drawn unless --no-hairs; they are all the difference.
    let hairs = j["hairs"].as_u64().unwrap();
    let js = run_gpu(&d, &[&RENDER[..], &["c.exr", "--no-hairs"]].concat()).unwrap();
    let bare: serde_json::Value = serde_json::from_str(&js).unwrap();
    assert!(hairs > 0 && bare["hairs"].as_u64() == Some(0), "{j}\n{bare}");
    assert_eq!(bare["instances"].as_u64().unwrap() + hairs, inst, "{bare}");
}

/// `btf knit render --fiber-shadows`: every fiber drawn into each light's map (the JSON
/// counts them), which shadows the patch more than the tube maps and the self-shadow
/// volume do at this scale (measured against the reference in `yarn-render`'s
/// `tests/gpu/fiber_shadows.rs`); a map side out of range is refused naming the flag.
#[test]
fn knit_render_fiber_shadows_draw_every_fiber_into_the_map() {
    let d = Dir::new();
    let Some(js) = run_gpu(&d, &[&RENDER[..], &["tubes.exr", "--no-hairs"]].concat()) else {
        return;
    };
    let tubes: serde_json::Value = serde_json::from_str(&js).unwrap();
    let args = ["fibers.exr", "--no-hairs", "--fiber-shadows", "--shadow-map", "512"];
    let js = run_gpu(&d, &[&RENDER[..], &args].concat()).unwrap();
    let fibers: serde_json::Value = serde_json::from_str(&js).unwrap();
    assert_eq!(tubes["shadow_instances"].as_u64(), Some(0), "{tubes}");
    assert_eq!(fibers["fiber_shadows"].as_bool(), Some(true), "{fibers}");
    // The light sees the patch's fibers (and its neighbours' that shadow it).
    let (cast, drawn) =
        (fibers["shadow_instances"].as_u64().unwrap(), fibers["instances"].as_u64().unwrap());
    assert!(cast >= drawn / 2, "{cast} fibers cast shadows, {drawn} drawn");
    let mean = |j: &serde_json::Value| j["mean_radiance"].as_f64().unwrap();
    assert!(mean(&fibers) > 0.0 && mean(&fibers) != mean(&tubes), "{fibers}\n{tubes}");
    let e = d.fails(&[&RENDER[..], &["x.exr", "--fiber-shadows", "--shadow-map", "8"]].concat());
    assert!(e.contains("--shadow-map"), "{e}");
    let e = d.fails(&[&RENDER[..], &["x.exr", "--fiber-shadows", "--no-yarn-shadows"]].concat());
    assert!(e.contains("--fiber-shadows") && e.contains("--no-yarn-shadows"), "{e}");
}

/// `btf knit render --supersample 2` is the frame drawn at twice the side with its
/// thresholds in output pixels, box-filtered: the 64² render at `--lod-px 2 --min-strip-px 2`
/// averaged over 2 × 2 blocks (the same fibers, sample masks and maps: equal), and not the
/// 32² frame at one frame a pixel. Out-of-range counts and the
/// lumislices are refused naming the flag.
#[test]
fn knit_render_supersample_is_the_larger_frame_box_filtered() {
    let d = Dir::new();
    let base = ["knit", "render", "--light", "dir:30,45", "--no-hairs", "--json"];
    let small = ["--size", "32,32", "--lod-px", "1", "--min-strip-px", "1"];
    let Some(js) =
        run_gpu(&d, &[&base[..], &small, &["--supersample", "2", "-o", "ss.exr"]].concat())
    else {
        return;
    };
    let j: serde_json::Value = serde_json::from_str(&js).unwrap();
    assert_eq!(j["supersample"].as_u64(), Some(2), "{j}");
    assert_eq!((j["width"].as_u64(), j["height"].as_u64()), (Some(32), Some(32)), "{j}");
    run_gpu(&d, &[&base[..], &small, &["-o", "one.exr"]].concat()).unwrap();
    let big = ["--size", "64,64", "--lod-px", "2", "--min-strip-px", "2", "-o", "big.exr"];
    run_gpu(&d, &[&base[..], &big].concat()).unwrap();
    let read = |f: &str| crate::common::read_exr(&d.path(f)).2;
    let (ss, one, big) = (read("ss.exr"), read("one.exr"), read("big.exr"));
    let mut filtered = vec![0.0f64; 32 * 32 * 3];
    for y in 0..64 {
        for x in 0..64 {
            for c in 0..3 {
                filtered[((y / 2) * 32 + x / 2) * 3 + c] += 0.25 * big[(y * 64 + x) * 3 + c] as f64;
            }
        }
    }
    let rel = |a: &[f32], b: &[f64]| {
        let num: f64 = a.iter().zip(b).map(|(x, y)| (*x as f64 - y).powi(2)).sum();
        let den: f64 = b.iter().map(|y| y * y).sum();
        (num / den).sqrt()
    };
    let one64: Vec<f64> = one.iter().map(|x| *x as f64).collect();
    let (e, e_one) = (rel(&ss, &filtered), rel(&ss, &one64));
    eprintln!("--supersample 2 against the 64² frame filtered: {e:.2e}; against 32²: {e_one:.4}");
    // Measured 0 (f32 EXRs; the same big frame averaged in the same order).
    assert!(e < 1e-6, "{e}");
    assert!(e_one > 10.0 * e, "the samples changed nothing: {e_one} against {e}");
    for k in ["0", "17"] {
        let err = d.fails(&[&base[..], &small, &["--supersample", k, "-o", "x.exr"]].concat());
        assert!(err.contains(&format!("--supersample {k}")), "{err}");
    }
    let ls = ["--method", "lumislice", "--supersample", "2", "-o", "x.exr"];
    let err = d.fails(&[&base[..], &small, &ls].concat());
    assert!(err.contains("--supersample 2"), "{err}");
    // A frame drawn beyond the adapter's or the renderer's limits is refused before
    // anything is allocated, and nothing is written.
    let huge = ["--size", "2048,2048", "--supersample", "16", "-o", "huge.exr"];
    let err = d.fails(&[&base[..], &huge].concat());
    assert!(err.contains("supersample 16") && err.contains("32768 × 32768"), "{err}");
    assert!(!d.path("huge.exr").exists());
}

/// `btf knit render --env`: an environment map alone lights the fibers through its SRBF
/// lobes, whose tube shadow maps darken the patch (against `--no-yarn-shadows`); the
/// lumislices and an SRBF count out of range are refused naming the flag.
#[test]
fn knit_render_lights_the_fibers_by_an_environment_map() {
    let d = Dir::new();
    d.ok(&["synth", "env", "--kind", "sky", "--width", "32", "-o", "sky.exr"]);
    let base = ["knit", "render", "--size", "32,32", "--lod-px", "1", "--env", "sky.exr"];
    let Some(_) = run_gpu(&d, &[&base[..], &["-o", "env.exr"]].concat()) else { return };
    run_gpu(&d, &[&base[..], &["--no-yarn-shadows", "-o", "free.exr"]].concat()).unwrap();
    let mean = |f: &str| {
        let (_, _, px) = crate::common::read_exr(&d.path(f));
        px.iter().map(|&x| x as f64).sum::<f64>() / px.len() as f64
    };
    let (shadowed, free) = (mean("env.exr"), mean("free.exr"));
    eprintln!("knit render --env: mean radiance {shadowed:.4e}, without yarn shadows {free:.4e}");
    assert!(shadowed > 0.0 && shadowed.is_finite(), "{shadowed}");
    assert!(shadowed < 0.98 * free, "the lobes' yarn shadows darken: {shadowed} vs {free}");
    let e = d.fails(&[&base[..], &["--method", "lumislice", "-o", "ls.exr"]].concat());
    assert!(e.contains("--env"), "{e}");
    let e = d.fails(&[&base[..], &["--srbfs", "0", "-o", "x.exr"]].concat());
    assert!(e.contains("--srbfs"), "{e}");
    let e = d.fails(&["knit", "sweep", "--ambient-fibers", "-o", "sw"]);
    assert!(e.contains("--ambient-fibers") && e.contains("--env"), "{e}");
}

/// The CSV as rows of named cells.
pub(crate) fn rows(csv: &str) -> Vec<std::collections::HashMap<String, String>> {
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), head.len(), "{l}");
            head.iter().zip(cells).map(|(h, c)| (h.to_string(), c.to_string())).collect()
        })
        .collect()
}

#[test]
fn knit_sweep_writes_the_grid_with_tubes_at_ratio_one() {
    let d = Dir::new();
    let args = [
        "knit",
        "sweep",
        "--size",
        "32,32",
        "--spp",
        "4",
        "--lod-px",
        "0,2",
        "--distances",
        "12",
        "--shading",
        "simple",
        "--repeat",
        "1",
        "-o",
        "sw",
    ];
    let Some(out) = run_gpu(&d, &args) else { return };
    assert!(out.contains("LoD crossover"), "{out}");
    let csv = std::fs::read_to_string(d.path("sw/sweep.csv")).unwrap();
    let r = rows(&csv);
    // 2 cameras × 1 shading × (tubes + 2 thresholds).
    assert_eq!(r.len(), 6, "{csv}");
    let f = |row: &std::collections::HashMap<String, String>, k: &str| -> f64 {
        row[k].parse().unwrap_or_else(|_| panic!("{k} = '{}'", row[k]))
    };
    for cam in ["btf", "persp-12px"] {
        let of = |m: &str, lod: &str| {
            r.iter().find(|x| x["camera"] == cam && x["method"] == m && x["lod_px"] == lod).unwrap()
        };
        let (tubes, full, coarse) = (of("tubes", ""), of("fibers", "0"), of("fibers", "2"));
        assert_eq!(f(tubes, "ratio_tubes"), 1.0, "{csv}");
        assert!(f(coarse, "instances") < f(full, "instances"), "{csv}");
        for x in [tubes, full, coarse] {
            let all = f(x, "rel_rmse_all");
            assert!(all.is_finite() && all >= 0.0, "{csv}");
            if f(x, "interior_px") > 0.0 {
                let e = f(x, "rel_rmse_interior");
                assert!(e.is_finite() && e >= 0.0, "{csv}");
            }
            assert_eq!(f(x, "triangles"), f(x, "instances") * 16.0, "{csv}");
            assert!(f(x, "frame_ms") > 0.0 && f(x, "ratio_tubes") > 0.0, "{csv}");
            // The same packed yarns for every cell of a camera: O(control points) bytes.
            assert_eq!(f(x, "yarn_bytes"), f(tubes, "yarn_bytes"), "{csv}");
        }
        // Full detail draws every fiber: its interior exists and is scored; it is its own
        // full-detail image, and the coarser LoD changes the frame.
        assert!(f(full, "interior_px") > 0.0, "{csv}");
        assert_eq!(f(full, "rel_rmse_vs_full"), 0.0, "{csv}");
        assert!(f(coarse, "rel_rmse_vs_full") > 0.01, "{csv}");
    }
    let md = std::fs::read_to_string(d.path("sw/sweep.md")).unwrap();
    assert!(md.contains("| persp-12px | simple | all | tubes |"), "{md}");
    let png = std::fs::read(d.path("sw/sweep.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    for f in ["ref-btf-simple.exr", "ref-persp-12px-simple.exr"] {
        assert!(d.path("sw").join(f).is_file(), "{f}");
    }
    // The converged comparison's knobs reach both renderers (the same patch and cameras):
    // every fiber explicit (more instances than with core strips), the reference's fibers
    // at 24 points a turn (another reference image; the reference is seeded), 2 × 2 frames
    // a pixel at the true strip width (another GPU image), all stated in sweep.md.
    let knobs = ["--no-core", "--min-strip-px", "0", "--supersample", "2"];
    let more = ["--samples-per-turn", "24", "-o", "conv"];
    let conv = [&args[..args.len() - 2], &knobs[..], &more[..]].concat();
    run_gpu(&d, &conv).unwrap();
    let c = rows(&std::fs::read_to_string(d.path("conv/sweep.csv")).unwrap());
    let full = |rows: &[std::collections::HashMap<String, String>]| {
        let x = rows
            .iter()
            .find(|x| x["camera"] == "btf" && x["method"] == "fibers" && x["lod_px"] == "0")
            .unwrap();
        f(x, "instances")
    };
    assert!(full(&c) > full(&r), "no core strips: {} instances against {}", full(&c), full(&r));
    let read = |f: &str| crate::common::read_exr(&d.path(f)).2;
    assert_ne!(read("conv/ref-btf-simple.exr"), read("sw/ref-btf-simple.exr"));
    assert_ne!(read("conv/gpu-btf-simple-lod0.exr"), read("sw/gpu-btf-simple-lod0.exr"));
    let md = std::fs::read_to_string(d.path("conv/sweep.md")).unwrap();
    for s in ["Core strips: off", "widened to 0 px", "2 × 2 frames a pixel", "24 points a helix"] {
        assert!(md.contains(s), "{s}: {md}");
    }
}

#[test]
fn knit_sweep_strips_cells_are_scored_and_timed_against_the_fibers() {
    let d = Dir::new();
    let args = [
        "knit",
        "sweep",
        "--size",
        "32,32",
        "--spp",
        "4",
        "--bounces",
        "2",
        "--lod-px",
        "0",
        "--distances",
        "",
        "--shading",
        "khungurn",
        "--strips",
        "tex32,plain,no-psi",
        "--bake-spp",
        "2",
        "--repeat",
        "1",
        "-o",
        "sw",
    ];
    let Some(out) = run_gpu(&d, &args) else { return };
    assert!(out.contains("Yarn strips"), "{out}");
    let csv = std::fs::read_to_string(d.path("sw/sweep.csv")).unwrap();
    let r = rows(&csv);
    // One camera: full-detail fibers, tubes, three strip variants.
    assert_eq!(r.len(), 5, "{csv}");
    let f = |m: &str, k: &str| -> f64 {
        let row = r.iter().find(|x| x["method"] == m).unwrap_or_else(|| panic!("{m}: {csv}"));
        row[k].parse().unwrap_or_else(|_| panic!("{m} {k} = '{}'", row[k]))
    };
    for m in ["strips-tex32", "strips-plain", "strips-no-psi"] {
        let e = f(m, "rel_rmse_all");
        assert!(e.is_finite() && e > 0.0, "{csv}");
        assert!(f(m, "frame_ms") > 0.0 && f(m, "mean_ratio") > 0.0, "{csv}");
        assert!(f(m, "bake_s") > 0.0, "{csv}");
        // One strip per segment and period: 2·n_sub triangles each (n_sub = 4).
        assert_eq!(f(m, "triangles"), f(m, "instances") * 8.0, "{csv}");
    }
    // Fiber shadowing Ψ ≤ 1 darkens: the strips without it are brighter.
    assert!(f("strips-no-psi", "mean_ratio") > f("strips-tex32", "mean_ratio"), "{csv}");
    assert_eq!(f("fibers", "ratio_fibers"), 1.0, "{csv}");
    for x in ["gpu-btf-khungurn-strips-tex32.exr", "bake-cache"] {
        assert!(d.path("sw").join(x).exists(), "{x}");
    }
    // --hairs: the reference with the yarn's hair flyaways, the strips with and without
    // their flyaway overlay ([H25 §4.4]); no-flyaways needs --hairs.
    let mut hairy: Vec<&str> = args.to_vec();
    let i = hairy.iter().position(|x| *x == "tex32,plain,no-psi").unwrap();
    hairy[i] = "full,no-flyaways";
    hairy.pop();
    hairy.extend(["sw-hairs", "--hairs"]);
    let Some(out) = run_gpu(&d, &hairy) else { return };
    assert!(out.contains("Hair flyaways on (`--hairs`)"), "{out}");
    let csv = std::fs::read_to_string(d.path("sw-hairs/sweep.csv")).unwrap();
    let h = rows(&csv);
    let g = |m: &str, k: &str| -> f64 {
        let row = h.iter().find(|x| x["method"] == m).unwrap_or_else(|| panic!("{m}: {csv}"));
        row[k].parse().unwrap()
    };
    // The overlay adds the hairs' coverage: the strips with it are brighter.
    eprintln!(
        "--hairs: mean / reference strips {:.4}, without the overlay {:.4}; rel. RMSE {:.4} / {:.4}",
        g("strips-full", "mean_ratio"),
        g("strips-no-flyaways", "mean_ratio"),
        g("strips-full", "rel_rmse_all"),
        g("strips-no-flyaways", "rel_rmse_all")
    );
    // The same bake, so only the overlay differs.
    assert!(g("strips-full", "mean_ratio") > g("strips-no-flyaways", "mean_ratio"), "{csv}");
    let e = d.fails(&["knit", "sweep", "--strips", "no-flyaways", "-o", "nf"]);
    assert!(e.contains("--hairs"), "{e}");
    // srbfN under an environment: the strips with N SRBFs beside the default 16.
    d.ok(&["synth", "env", "--kind", "sky", "--width", "32", "-o", "sky.exr"]);
    let mut sky: Vec<&str> = args.to_vec();
    let i = sky.iter().position(|x| *x == "tex32,plain,no-psi").unwrap();
    sky[i] = "full,srbf16,srbf4";
    sky.pop();
    sky.extend(["sw-sky", "--env", "sky.exr"]);
    let Some(out) = run_gpu(&d, &sky) else { return };
    assert!(out.contains("strips-srbf4") || out.contains("srbf4"), "{out}");
    let csv = std::fs::read_to_string(d.path("sw-sky/sweep.csv")).unwrap();
    let k = rows(&csv);
    let m = |name: &str| -> f64 {
        let row = k.iter().find(|x| x["method"] == name).unwrap_or_else(|| panic!("{name}: {csv}"));
        row["mean_ratio"].parse().unwrap()
    };
    eprintln!(
        "sky: mean / reference, 16 SRBFs (full) {:.4}, srbf16 {:.4}, 4 SRBFs {:.4}",
        m("strips-full"),
        m("strips-srbf16"),
        m("strips-srbf4")
    );
    // srbf16 is the default count fitted again: the same frame; 4 lobes another.
    assert_eq!(m("strips-srbf16"), m("strips-full"), "{csv}");
    assert!(m("strips-srbf4") > 0.0 && m("strips-srbf4") != m("strips-full"), "{csv}");
    let e = d.fails(&["knit", "sweep", "--strips", "srbf4", "-o", "nf"]);
    assert!(e.contains("--env"), "{e}");
    let e = d.fails(&["knit", "sweep", "--strips", "srbf64", "-o", "nf"]);
    assert!(e.contains("srbfN"), "{e}");
    // --method strips: the yarn BTF by the strips, an ordinary store.
    let Some(_) = run_gpu(
        &d,
        &[
            "synth",
            "material",
            "--kind",
            "yarn",
            "--method",
            "strips",
            "--chart",
            "stockinette",
            "--size",
            "8",
            "--sampling",
            "rings:0x1,45x4",
            "--spp",
            "1",
            "--bounces",
            "2",
            "-o",
            "y.btf",
        ],
    ) else {
        return;
    };
    let st = btf_core::store::BtfStore::open(&d.path("y.btf")).unwrap();
    let prov = &st.meta().provenance;
    assert_eq!(prov["method"], "strips", "{prov}");
    assert_eq!(prov["bake"]["directions"], 8, "{prov}");
    let img = st.read_image(0, 0).unwrap();
    assert!(img.iter().all(|x| x.is_finite()) && img.iter().any(|&x| x > 0.0));
}

/// `btf knit strips`: one bake per grid point, each with a finite residual in [0, 1) where
/// the yarn covers texels, its time and its picture; bad sizes are refused by name.
#[test]
fn knit_strips_bakes_the_grid_with_residuals_and_pictures() {
    let d = Dir::new();
    let out = d.ok(&[
        "knit",
        "strips",
        "--spp",
        "2",
        "--directions",
        "2",
        "--texels",
        "8x4",
        "--tangents",
        "1,2",
        "-o",
        "bk",
    ]);
    assert!(out.contains("Yarn-strip bakes"), "{out}");
    let csv = std::fs::read_to_string(d.path("bk/bake.csv")).unwrap();
    let r = rows(&csv);
    assert_eq!(r.len(), 2, "{csv}");
    for (row, k) in r.iter().zip(["1", "2"]) {
        assert_eq!(row["tangents"], k, "{csv}");
        let res: f64 = row["mean_residual"].parse().unwrap();
        assert!(res.is_finite() && (0.0..1.5).contains(&res), "{csv}");
        let s: f64 = row["seconds"].parse().unwrap();
        assert!(s > 0.0, "{csv}");
        // 8 × 4 texels × (2 + 3K + 8·2) floats + the ambient table, 4 bytes each.
        let k: usize = k.parse().unwrap();
        let bytes: usize = row["gpu_bytes"].parse().unwrap();
        assert_eq!(bytes, 4 * (32 * (2 + 3 * k + 16) + 3 * 64), "{csv}");
        let png = std::fs::read(d.path(&format!("bk/bake-spp2-d2-8x4-k{k}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }
    let e = d.fails(&["knit", "strips", "--texels", "8by4", "-o", "bk2"]);
    assert!(e.contains("--texels 8by4"), "{e}");
    let e = d.fails(&["knit", "strips", "--directions", "1", "-o", "bk2"]);
    assert!(e.contains("directions"), "{e}");
}

#[test]
fn knit_gpu_refusals_name_the_flag() {
    let d = Dir::new();
    let e = d.fails(&["knit", "sweep", "--msaa", "3", "-o", "o"]);
    assert!(e.contains("--msaa 3"), "{e}");
    let e = d.fails(&["knit", "render", "--msaa", "3", "--light", "dir:0,0", "-o", "r.exr"]);
    assert!(e.contains("--msaa 3"), "{e}");
    let e = d.fails(&["knit", "sweep", "--yarn", "no-such-yarn", "-o", "o"]);
    assert!(e.contains("no-such-yarn"), "{e}");
    let e = d.fails(&["knit", "sweep", "--lod-px=0,-1", "-o", "o"]);
    assert!(e.contains("--lod-px -1"), "{e}");
    let e = d.fails(&["knit", "sweep", "--shading", "lambert", "-o", "o"]);
    assert!(e.contains("--shading lambert"), "{e}");
    let e = d.fails(&["knit", "sweep", "--strips", "shiny", "-o", "o"]);
    assert!(e.contains("--strips shiny"), "{e}");
    let e = d.fails(&["knit", "sweep", "--distances", "0", "-o", "o"]);
    assert!(e.contains("--distances 0"), "{e}");
    let e = d.fails(&["knit", "sweep", "--supersample", "2", "--strips", "full", "-o", "o"]);
    assert!(e.contains("--supersample 2") && e.contains("--strips"), "{e}");
    let e = d.fails(&["knit", "sweep", "--supersample", "17", "-o", "o"]);
    assert!(e.contains("--supersample 17"), "{e}");
    let e = d.fails(&["knit", "sweep", "--min-strip-px=-1", "-o", "o"]);
    assert!(e.contains("--min-strip-px -1"), "{e}");
    std::fs::write(d.path("c.chart"), "name: c\nkp\n").unwrap();
    let e = d.fails(&["knit", "sweep", "--chart", "c.chart", "-o", "c.chart"]);
    assert!(e.contains("c.chart"), "{e}");
    // Nothing was written for a refused sweep.
    assert!(!d.path("o").exists());
}

/// `btf knit compare` (DESIGN §4.2's headline study) on a tiny garment: a 5 × 5 yarn BTF at
/// 8², 8 wales on the drape, one 64² camera. Every representation has its row with finite
/// errors, the plain texture is its own time unit, the BTF made by the reference keeps the
/// reference's mean radiance on the garment, and one bounce is darker than eight; the yarn
/// strips (R2) have their row and their bake is cached; the BTF from fibers (R4, the same
/// patch rendered by the GPU fibers at full detail) keeps the GPU fibers' own mean radiance
/// on the garment. Then the whole study as one command: no `--btf` (the study makes it),
/// two strains, the final table and its Pareto plot.
#[test]
fn knit_compare_scores_every_representation_against_the_reference() {
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
        "8",
        "--sampling",
        "rings:0x1,45x4",
        "--spp",
        "2",
        "--bounces",
        "3",
        "-o",
        "y.btf",
    ]);
    let args = [
        "knit",
        "compare",
        "--btf",
        "y.btf",
        "--wales",
        "8",
        "--size",
        "64,64",
        "--distances",
        "6",
        "--spp",
        "2",
        "--lod",
        "2",
        "--components",
        "2",
        "--repeat",
        "1",
        "--bake-spp",
        "1",
        "--btf-fibers-lod",
        "0",
        "-o",
        "cmp",
    ];
    let Some(out) = run_gpu(&d, &args) else { return };
    assert!(out.contains("Multiple-scattering gap"), "{out}");
    let csv = std::fs::read_to_string(d.path("cmp/compare.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|s| s.trim_matches('"').to_owned()).collect())
        .collect();
    let reprs: Vec<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    assert_eq!(reprs, ["R1", "R1", "R5", "R2", "R3", "R4", "R4", "R5"], "{csv}");
    let num = |r: &Vec<String>, k: usize| r[k].parse::<f64>().unwrap();
    for r in &rows {
        // interior, band, stitch scale, mean ratio, ꟻLIP interior and band against R0;
        // frame ms and its ratio to the plain texture.
        for k in [3, 4, 5, 6, 7, 8, 12, 13] {
            assert!(num(r, k).is_finite() && num(r, k) > 0.0, "column {k} of {r:?}");
        }
        // ꟻLIP is a per-pixel value in [0, 1], so are its means.
        assert!(num(r, 7) <= 1.0 && num(r, 8) <= 1.0, "{r:?}");
    }
    let heatmaps = std::fs::read_dir(d.path("cmp/images"))
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().starts_with("flip-"))
        .count();
    assert_eq!(heatmaps, rows.len(), "one ꟻLIP heat map per cell");
    let plain = rows.iter().find(|r| r[2].starts_with("plain texture")).unwrap();
    assert_eq!(num(plain, 13), 1.0, "the plain texture is the time unit");
    let btf = rows.iter().find(|r| r[2].starts_with("BTF c")).unwrap();
    let ratio = num(btf, 6);
    assert!((0.6..1.6).contains(&ratio), "BTF mean radiance / reference {ratio}");
    // The BTF from fibers carries the fibers' light transport (one bounce, their shadows):
    // its mean on the garment is the fibers' own (measured 1.01), not the reference's.
    let from_fibers = rows.iter().find(|r| r[2].starts_with("BTF from fibers")).unwrap();
    let fibers = rows.iter().find(|r| r[2] == "fibers full detail").unwrap();
    let ratio = num(from_fibers, 6) / num(fibers, 6);
    assert!((0.75..1.33).contains(&ratio), "BTF from fibers / fibers mean radiance {ratio}");
    assert!(d.path("cmp/btf-fibers.btf").is_dir() && d.path("cmp/btf-fibers-c2.eig").is_dir());
    assert!(d.path("cmp/bake-cache").is_dir(), "the strips' bake is cached");
    for f in ["report.md", "pareto.png", "sheet-6px.png", "images/R0-6px.exr", "garment.obj"] {
        assert!(d.path("cmp").join(f).is_file(), "{f}");
    }
    // The whole study as one command: the reference's BTF made by the study itself (the
    // same as y.btf), the garment and its yarns stretched along the wales by 0 and 50 %.
    let mut st: Vec<&str> = args[4..args.len() - 4].to_vec();
    st.splice(0..0, ["knit", "compare", "--chart", "stockinette", "--yarn", "fine-2ply"]);
    st.extend(["--btf-size", "8", "--btf-sampling", "rings:0x1,45x4", "--btf-spp", "2"]);
    st.extend(["--btf-bounces", "3", "--no-btf-fibers", "--stretch", "0,0.5", "-o", "st"]);
    let out = d.ok(&st);
    assert!(out.contains("Every representation"), "{out}");
    let csv = std::fs::read_to_string(d.path("st/stretch.csv")).unwrap();
    let strains: Vec<&str> = csv.lines().skip(1).map(|l| l.split(',').next().unwrap()).collect();
    assert!(strains.contains(&"0") && strains.contains(&"0.5"), "{csv}");
    // Made by the same command from the same chart, yarn and settings, its BTF is y.btf.
    let (made, given) = (
        btf_core::store::BtfStore::open(&d.path("st/btf-reference.btf")).unwrap(),
        btf_core::store::BtfStore::open(&d.path("y.btf")).unwrap(),
    );
    // (y.btf in f32, the study's in f16: equal to f16's rounding.)
    let (a, b) = (made.read_image(2, 3).unwrap(), given.read_image(2, 3).unwrap());
    assert_eq!(a.len(), b.len());
    assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-3 * y.abs() + 1e-6));
    // The final table: every representation of the rest run, one ꟻLIP column per strain.
    let report = std::fs::read_to_string(d.path("st/report.md")).unwrap();
    let table: Vec<&str> = report.lines().filter(|l| l.starts_with("| R")).collect();
    assert_eq!(table.len(), 8, "R0 one bounce and seven representations: {report}");
    assert!(table[0].starts_with("| R0 | one bounce"), "{report}");
    assert!(report.contains("ꟻLIP 0 %") && report.contains("ꟻLIP 50 %"), "{report}");
    assert!(d.path("st/pareto-6px.png").is_file());
    // A second run reuses the finished BTF (an unfinished one would be resumed: the writer's
    // own tests) and refuses one made with other settings.
    let stamp = || std::fs::metadata(d.path("st/btf-reference.btf/zarr.json")).unwrap().modified();
    let before = stamp().unwrap();
    let mut same: Vec<&str> = st[..st.len() - 3].to_vec();
    same.extend(["0", "-o", "st"]);
    assert_eq!(same[same.len() - 4], "--stretch", "{same:?}");
    d.ok(&same);
    assert_eq!(stamp().unwrap(), before, "the finished reference BTF was made again");
    let mut again: Vec<&str> = st[..st.len() - 13].to_vec();
    again.extend(["--btf-size", "6", "--btf-sampling", "rings:0x1,45x4", "--btf-spp", "2"]);
    again.extend(["--btf-bounces", "3", "--no-btf-fibers", "--stretch", "0", "-o", "st"]);
    let e = d.fails(&again);
    assert!(e.contains("--fresh"), "{e}");
    for l in csv.lines().skip(1) {
        let rmse: f64 = l.split(',').nth(4).unwrap().parse().unwrap();
        assert!(rmse.is_finite() && rmse > 0.0, "{l}");
    }
    assert!(d.path("st/stretch-6px.png").is_file() && d.path("st/stretch.md").is_file());
    let extent = |f: &str| {
        let text = std::fs::read_to_string(d.path(f)).unwrap();
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for l in text.lines().filter(|l| l.starts_with("v ")) {
            let v: Vec<f64> = l[2..].split_whitespace().map(|x| x.parse().unwrap()).collect();
            for k in 0..2 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        [hi[0] - lo[0], hi[1] - lo[1]]
    };
    // Against the rest garment of the run above (the same drape, unstretched).
    let (e0, e5) = (extent("cmp/garment.obj"), extent("st/stretch-0.5/garment.obj"));
    let grow = (e5[0] / e0[0]).max(e5[1] / e0[1]);
    assert!((1.4..1.6).contains(&grow), "the drape stretched by {grow}, not 1.5");
    let e = d.fails(&["knit", "compare", "--btf", "y.btf", "--stretch", "2", "-o", "c4"]);
    assert!(e.contains("--stretch"), "{e}");
    // Refusals: a BTF that is not a yarn BTF; wales that do not repeat the chart.
    crate::common::write_test_btf(&d.path("plain.btf"), 8);
    let e = d.fails(&["knit", "compare", "--btf", "plain.btf", "-o", "c2"]);
    assert!(e.contains("provenance"), "{e}");
    let e = d.fails(&["knit", "compare", "--btf", "y.btf", "--wales", "3", "-o", "c3"]);
    assert!(e.contains("--wales 3"), "{e}");
}
