//! `btf demo`'s report, for a reader who is not a developer: `report.{md,html}` say in
//! plain words what was done, show the material as a swatch and the garment renders large
//! with captions, and state what accuracy costs (components → error, quality in dB, size,
//! time); `details.{md,html}` hold the developer tables (stages, passes, the compression
//! sweep, the GPU cost sweep with its read bounds and targets), each column explained. The
//! headline numbers are computed from the stores themselves (the per-slot statistics the
//! compressor wrote), so a resumed demo reports the same figures.

use crate::demo::scene::{RenderFact, Renders};
use crate::report::doc::{Block, html, markdown};
use anyhow::{Context, Result};
use btf_core::Direction;
use btf_core::eigen::EigenStore;
use btf_core::reconstruct::{ReconstructParams, reconstruct};
use btf_core::store::BtfStore;
use btf_image::compose::captioned_strip;
use btf_image::write::{to_srgb_image, write_png, write_text};
use std::path::Path;

/// One demo stage: name, seconds, reused.
pub struct StageTime {
    /// Stage name.
    pub name: &'static str,
    /// Wall-clock seconds (≈ 0 when reused).
    pub seconds: f64,
    /// Whether its output was reused from an earlier run.
    pub reused: bool,
}

/// The headline numbers, from the stores.
#[derive(Debug, Clone, Copy)]
pub struct Headline {
    /// Components per view slot in the eigen store.
    pub components: usize,
    /// Relative RMSE of the stored representation over the whole BTF.
    pub rel_rmse: f64,
    /// PSNR in dB (peak: the brightest value of the BTF).
    pub psnr_db: f64,
    /// Bytes of the BTF store.
    pub btf_bytes: u64,
    /// Bytes of the eigen store.
    pub eig_bytes: u64,
}

/// The error of `eig` from its per-slot statistics (the sums [`btf_core::compress`]
/// reports): `sqrt(Σ sse / Σ energy)` and `10 log10(peak² / mse)`.
pub fn headline(btf: &BtfStore, eig: &EigenStore) -> Result<Headline> {
    let m = &eig.meta().btf;
    let (mut sse, mut energy, mut peak) = (0.0, 0.0, 0f64);
    for j in 0..m.n_views() {
        let s = eig.slot_stats(j).with_context(|| {
            format!("{}: no statistics for view slot {j}", eig.path().display())
        })?;
        let f = |k: &str| s[k].as_f64().with_context(|| format!("slot {j} statistics: no '{k}'"));
        sse += f("sse_stored")?;
        energy += f("energy")?;
        peak = peak.max(f("peak")?);
    }
    let values = (m.n_views() * m.n_lights() * m.texel_values()) as f64;
    Ok(Headline {
        components: eig.meta().components,
        rel_rmse: btf_core::metrics::rel_rmse_from(sse, energy),
        psnr_db: btf_core::metrics::psnr_db(sse / values, peak),
        btf_bytes: btf.bytes(),
        eig_bytes: eig.bytes(),
    })
}

/// Megabytes (10⁶ bytes), one decimal.
pub fn mb(bytes: u64) -> String {
    format!("{:.1} MB", bytes as f64 / 1e6)
}

/// `swatch.png`: the compressed material tiled 3 × 3, seen from θ = 20°, under a light from
/// θ = 35° and under a grazing light (θ = 70°, across the texture's rows) that shows the
/// relief, each exposed so its brightest texel is 0.9 of white, enlarged to 360 px.
fn swatch(eig: &EigenStore, out: &Path) -> Result<()> {
    let m = &eig.meta().btf;
    let (w, h) = (m.width, m.height);
    let mut panels = Vec::new();
    for (theta, phi) in [(35.0, 60.0), (70.0, 0.0)] {
        let rgb = reconstruct(
            eig,
            Direction::new(20.0, 270.0),
            Direction::new(theta, phi),
            ReconstructParams::default(),
        )?;
        let peak = rgb.iter().copied().fold(0f32, f32::max).max(1e-12);
        let tile = to_srgb_image(w, h, &rgb, 0.9 / peak);
        let mut big = image::RgbImage::new(3 * w as u32, 3 * h as u32);
        for k in 0..9u32 {
            image::imageops::replace(
                &mut big,
                &tile,
                (k % 3 * w as u32) as i64,
                (k / 3 * h as u32) as i64,
            );
        }
        let side = 360u32;
        let sh = (side as f64 * h as f64 / w as f64).round() as u32;
        panels.push(image::imageops::resize(
            &big,
            side,
            sh,
            image::imageops::FilterType::CatmullRom,
        ));
    }
    let strip = captioned_strip(
        &[(&panels[0], "soft light from above"), (&panels[1], "grazing light")],
        12,
    );
    Ok(write_png(&out.join("swatch.png"), &strip)?)
}

/// `compare-garments.png`: the draped garment's render beside the tube shirt's.
fn compare_png(out: &Path, draped: &RenderFact, tube: &RenderFact) -> Result<()> {
    let a = image::open(out.join(&draped.png))?.to_rgb8();
    let b = image::open(out.join(&tube.png))?.to_rgb8();
    let strip = captioned_strip(&[(&a, "sewn and draped"), (&b, "tube shirt")], 12);
    Ok(write_png(&out.join("compare-garments.png"), &strip)?)
}

/// Sweep rows from `sweep/sweep.csv`: (c, rel. RMSE, PSNR dB, compress s, CPU ms, bytes).
fn sweep_rows(out: &Path) -> Result<Vec<[f64; 6]>> {
    let path = out.join("sweep/sweep.csv");
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut rows = Vec::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let get = |k: usize| -> Result<f64> {
            cells
                .get(k)
                .and_then(|c| c.parse().ok())
                .with_context(|| format!("{}: line {}, column {}", path.display(), n + 1, k + 1))
        };
        rows.push([get(1)?, get(2)?, get(3)?, get(4)?, get(5)?, get(6)?]);
    }
    Ok(rows)
}

/// What the knit stage of the demo recorded (`knit/knit.json`).
struct KnitDemo {
    png: String,
    stitches: String,
    instances: u64,
    control_points: u64,
    yarn_bytes: u64,
    fibers_ms: f64,
    tubes_ms: f64,
    /// The knot-solver panel: image, strain, faces, solve ms, clearance / 2r with the
    /// relaxed rest and (newer reports) without it.
    stretch: Option<(String, f64, u64, f64, f64, Option<f64>)>,
    /// The strips panel: image, strips ms, bake seconds.
    strips: Option<(String, f64, f64)>,
    /// The lumislices of the same panel: ms, table seconds.
    lumislices: Option<(f64, f64)>,
    /// The shadows panel: image, ms with fiber shadow maps, fibers drawn into the maps, ms
    /// at 4 × 4 frames a pixel (older reports have none).
    shadows: Option<(String, f64, u64, Option<f64>)>,
}

fn knit_json(out: &Path) -> Option<KnitDemo> {
    let text = std::fs::read_to_string(out.join("knit/knit.json")).ok()?;
    let j: serde_json::Value = serde_json::from_str(&text).ok()?;
    let s = j.get("stitches")?.as_array()?;
    Some(KnitDemo {
        png: j.get("png")?.as_str()?.to_owned(),
        stitches: format!("{} × {}", s.first()?.as_u64()?, s.get(1)?.as_u64()?),
        instances: j.get("fiber_instances")?.as_u64()?,
        control_points: j.get("control_points")?.as_u64()?,
        yarn_bytes: j.get("yarn_bytes")?.as_u64()?,
        fibers_ms: j.get("fibers_ms")?.as_f64()?,
        tubes_ms: j.get("tubes_ms")?.as_f64()?,
        stretch: (|| {
            Some((
                j.get("stretch_png")?.as_str()?.to_owned(),
                j.get("stretch")?.as_f64()?,
                j.get("knot_faces")?.as_u64()?,
                j.get("knot_solve_ms")?.as_f64()?,
                j.get("stretch_clearance")?.as_f64()?,
                j.get("stretch_clearance_plain").and_then(|v| v.as_f64()),
            ))
        })(),
        strips: (|| {
            Some((
                j.get("strips_png")?.as_str()?.to_owned(),
                j.get("strips_ms")?.as_f64()?,
                j.get("strips_bake_s")?.as_f64()?,
            ))
        })(),
        lumislices: (|| {
            Some((j.get("lumislice_ms")?.as_f64()?, j.get("lumislice_table_s")?.as_f64()?))
        })(),
        shadows: (|| {
            Some((
                j.get("shadows_png")?.as_str()?.to_owned(),
                j.get("fiber_shadows_ms")?.as_f64()?,
                j.get("fiber_shadow_instances")?.as_u64()?,
                j.get("fiber_shadows_supersampled_ms").and_then(|v| v.as_f64()),
            ))
        })(),
    })
}

/// Writes `report.{md,html}`, `details.{md,html}` and `swatch.png`; returns the summary
/// lines for the terminal (≤ 10).
pub fn write(
    out: &Path,
    kind: &str,
    btf: &BtfStore,
    eig: &EigenStore,
    renders: &Renders,
    stages: &[StageTime],
) -> Result<Vec<String>> {
    let hl = headline(btf, eig)?;
    swatch(eig, out)?;
    let m = btf.meta();
    let sweep = sweep_rows(out)?;
    let ratio = hl.btf_bytes as f64 / hl.eig_bytes.max(1) as f64;
    let main = renders.renders.first();
    let mut page = vec![
        Block::Title(format!("A {kind} fabric, measured, compressed and rendered on a shirt")),
        Block::Para(format!(
            "What was done: the toolkit made a synthetic {kind} sample and photographed it virtually from {} directions under {} lights ({} pictures of {}×{} texels, {}). It compressed these pictures, keeping {} components (\"ingredients\") per viewing direction, and rendered a T-shirt made of the compressed material, sewn from flat pattern panels and draped on a mannequin by cloth simulation.",
            m.n_views(),
            m.n_lights(),
            m.n_views() * m.n_lights(),
            m.width,
            m.height,
            mb(hl.btf_bytes),
            hl.components
        )),
        Block::Keys(vec![
            (
                "File size".into(),
                format!("{} instead of {}", mb(hl.eig_bytes), mb(hl.btf_bytes)),
                format!("{ratio:.1} times smaller"),
            ),
            (
                "Error".into(),
                format!("{:.2} %", 100.0 * hl.rel_rmse),
                format!("{:.1} dB; above about 40 dB the difference is hard to see", hl.psnr_db),
            ),
            match main {
                Some(r) => (
                    "Render time".into(),
                    format!("{:.0} ms per frame", r.steady_frame_ms),
                    format!(
                        "{}×{} pixels, on this machine's software GPU (lavapipe); a graphics card is many times faster",
                        r.size.0, r.size.1
                    ),
                ),
                None => {
                    ("Render time".into(), "not measured".into(), "no GPU on this machine".into())
                }
            },
        ]),
        Block::Figure {
            src: "swatch.png".into(),
            caption: format!(
                "The material: the compressed {kind} tiled 3 × 3, seen from 20° off straight above, lit softly from above (left) and from a grazing angle that shows its relief (right)."
            ),
        },
    ];
    if let Some(why) = &renders.skipped {
        page.push(Block::Para(format!("Renders skipped: {why}.")));
    }
    let tube = renders.renders.iter().find(|r| r.png == "render-tube-environment.png");
    let draped = renders.renders.iter().find(|r| r.png == "render-environment.png");
    for (k, r) in renders.renders.iter().filter(|r| tube.is_none_or(|t| t.png != r.png)).enumerate()
    {
        let fig = Block::Figure {
            src: r.png.clone(),
            caption: format!(
                "{} ({}×{} pixels, scene file {})",
                r.caption, r.size.0, r.size.1, r.scene
            ),
        };
        // The garment first, right under the key numbers; the swatch after it.
        let at = if k == 0 { page.len() - 1 } else { page.len() };
        page.insert(at, fig);
    }
    if let (Some(t), Some(d)) = (tube, draped) {
        compare_png(out, d, t)?;
        page.push(Block::Figure {
            src: "compare-garments.png".into(),
            caption: format!(
                "The same material under the same sky on the T-shirt sewn from pattern panels and draped on a mannequin (left; scene file {}) and on the toolkit's earlier tube shirt (right; {}): on the T-shirt the ribs run down the front along each panel's grain and round the sleeves, and the cloth folds where the sleeve meets the body.",
                d.scene, t.scene
            ),
        });
    }
    page.push(Block::Heading("What accuracy costs".into()));
    page.push(Block::Para("Each viewing direction of the material is stored as a few components. More components make the material more faithful, and the file larger and slower to draw:".into()));
    page.push(Block::Table {
        head: vec![
            "components".into(),
            "error".into(),
            "quality".into(),
            "file size".into(),
            "time to compress".into(),
        ],
        rows: sweep
            .iter()
            .map(|r| {
                vec![
                    format!("{}", r[0]),
                    format!("{:.2} %", 100.0 * r[1]),
                    format!("{:.1} dB", r[2]),
                    mb(r[5] as u64),
                    format!("{:.1} s", r[3]),
                ]
            })
            .collect(),
    });
    page.push(Block::Figure { src: "sweep/error.png".into(), caption: "The error falls as components are added (logarithmic scale: each grid line is ten times less error).".into() });
    page.push(Block::Figure { src: "sweep/heatmaps.png".into(), caption: "Where the error is, for one picture of the material: green = none, red = 10 % of the brightest value or more.".into() });
    if let Some(k) = knit_json(out) {
        page.push(Block::Heading("Knitwear, fiber by fiber".into()));
        page.push(Block::Para(format!(
            "Next to the measured fabric, the toolkit draws knitwear from the yarn itself: {} stitches of a two-ply cotton, whose {} fiber strands, stray hairs among them, are generated on the GPU every frame from {} curve points ({:.0} KB) and never stored; farther stitches get fewer fibers. On this machine's software GPU a frame took {:.0} ms, {:.1} times as long as drawing the yarns as plain tubes.",
            k.stitches,
            k.instances,
            k.control_points,
            k.yarn_bytes as f64 / 1024.0,
            k.fibers_ms,
            k.fibers_ms / k.tubes_ms.max(1e-9)
        )));
        page.push(Block::Figure {
            src: k.png.clone(),
            caption: "A stockinette patch rendered with procedural fibers (Wu & Yuksel): stray hairs, self-shadows inside the yarn, shadows between yarns, level of detail with core fibers.".into(),
        });
        if let Some((png, ms, cast, fine)) = &k.shadows {
            let fine = fine.map_or(String::new(), |f| {
                format!(", and {f:.0} ms with each pixel drawn 4 × 4 times over (right), the fibers antialiased")
            });
            page.push(Block::Para(format!(
                "Shadows two ways: the paper's (Wu & Yuksel) — other yarns as solid tubes, and inside a yarn an average fiber density — or every fiber casting its own shadow: each lamp's view of the fibers drawn first at full detail ({cast} fiber pieces into the two lamps' maps), fitted to what the camera sees. Against a slow exact rendering of a knit patch, each pixel drawn 16 × 16 times over, the second comes within 3.4 % per pixel where the first is 18 % off and 9 % dark (`yarn-render`'s tests); here a frame took {:.0} ms against {:.0} ms{fine}.",
                ms, k.fibers_ms
            )));
            page.push(Block::Figure {
                src: png.clone(),
                caption: "The close-up with tube shadows and the average density (left), with the shadow of every fiber (middle), and that drawn 4 × 4 times a pixel (right).".into(),
            });
        }
        if let Some((png, strain, faces, ms, clearance, plain)) = &k.stretch {
            let without = plain.map_or(String::new(), |p| {
                format!(
                    "; {p:.2} with the fit alone, whose stitch template lets touching yarns overlap"
                )
            });
            page.push(Block::Para(format!(
                "When the knit stretches, its yarns follow the stitches: the patch pulled {:.0} % along its wales, the yarn moved by fitting two crossing \"knots\" per stitch (Huang et al. 2025) and the stitch template, relaxed once so that touching yarns do not overlap, carried on top — {} stitches in {:.1} ms on this machine's CPU. The fit itself keeps no yarn apart from another: at the closest point the yarns' centre lines are {:.2} yarn diameters apart (below 1 they overlap{without}).",
                strain * 100.0,
                faces,
                ms,
                clearance
            )));
            page.push(Block::Figure {
                src: png.clone(),
                caption:
                    "The same patch at rest and stretched; the loops lengthen with the fabric."
                        .into(),
            });
        }
        if let Some((png, ms, bake)) = &k.strips {
            page.push(Block::Para(format!(
                "The same yarns drawn a second way: as flat ribbons facing the camera, painted with what the individual fibers look like (Huang et al. 2025) — the fibers' coverage, direction, shadowing and inner light bouncing, computed once in {:.0} s from a single yarn traced fiber by fiber. A frame took {:.0} ms against {:.0} ms for the fibers (this close, every ribbon pixel is shaded with four fiber directions and the stray hairs are drawn in a second pass; from a distance the ribbons are the cheaper of the two); `btf knit sweep --strips` measures what each costs in accuracy.",
                bake,
                ms,
                k.fibers_ms
            )));
            if let Some((lms, table)) = k.lumislices {
                page.push(Block::Para(format!(
                    "And a third way (right): each yarn as a cloud of light-scattering fibers, its cross-section precomputed once ({:.0} s) for 672 light directions with the light bouncing inside it, then marched through pixel by pixel and shaded by the yarns between it and the lamp (Chen et al. 2003). A frame took {:.0} ms; `btf knit lumislice` measures its accuracy against a slow exact rendering of the same volumes.",
                    table, lms
                )));
            }
            page.push(Block::Figure {
                src: png.clone(),
                caption: "Fibers generated on the GPU (left), fiber-textured yarn strips (middle) and lumislices (right), same yarns, camera and lights.".into(),
            });
        }
    }
    page.push(Block::Links(vec![
        (
            "Developer details (stage and pass timings, cost sweep, read bounds, targets)".into(),
            "details.html".into(),
        ),
        ("Markdown".into(), "details.md".into()),
    ]));
    let details = details(out, stages, renders, &sweep)?;
    let title = format!("btf demo: {kind}");
    write_text(&out.join("report.md"), &markdown(&page))?;
    write_text(&out.join("report.html"), &html(&title, &page))?;
    write_text(&out.join("details.md"), &markdown(&details))?;
    write_text(&out.join("details.html"), &html(&format!("{title}: details"), &details))?;
    let mut lines = vec![
        format!(
            "btf demo: synthetic {kind}, {}×{} texels, {} views × {} lights",
            m.width,
            m.height,
            m.n_views(),
            m.n_lights()
        ),
        format!(
            "compressed {} → {} ({ratio:.1}× smaller) with {} components: error {:.2} %, {:.1} dB",
            mb(hl.btf_bytes),
            mb(hl.eig_bytes),
            hl.components,
            100.0 * hl.rel_rmse,
            hl.psnr_db
        ),
    ];
    match (main, &renders.skipped) {
        (Some(r), _) => lines.push(format!(
            "render: {}×{} frame in {:.0} ms (median of 3, lavapipe)",
            r.size.0, r.size.1, r.steady_frame_ms
        )),
        (None, Some(why)) => lines.push(format!("renders skipped: {why}")),
        _ => {}
    }
    lines.push(format!("report: {} (also report.md)", out.join("report.html").display()));
    lines.push(format!("developer details: {}", out.join("details.html").display()));
    Ok(lines)
}

/// The developer page: stages, passes per render, the compression sweep, the GPU cost
/// sweep, each table's columns explained.
fn details(
    out: &Path,
    stages: &[StageTime],
    renders: &Renders,
    sweep: &[[f64; 6]],
) -> Result<Vec<Block>> {
    let mut d = vec![
        Block::Title("btf demo: developer details".into()),
        Block::Links(vec![("back to the report".into(), "report.html".into()), ("compression sweep".into(), "sweep/report.md".into()), ("GPU cost sweep".into(), "render-cost/render-cost.md".into())]),
        Block::Heading("Stages".into()),
        Block::Table {
            head: vec!["stage".into(), "seconds".into(), "".into()],
            rows: stages.iter().map(|s| vec![s.name.to_string(), format!("{:.2}", s.seconds), if s.reused { "reused".into() } else { String::new() }]).collect(),
        },
        Block::Terms(vec![
            ("seconds".into(), "wall-clock time of the stage in this run".into()),
            ("reused".into(), "the stage's output was complete from an earlier run and was kept (delete the folder or pass --fresh to redo it)".into()),
        ]),
        Block::Heading("Render passes".into()),
    ];
    for r in &renders.renders {
        let mut rows: Vec<Vec<String>> = r
            .stats
            .setup
            .iter()
            .map(|p| vec![format!("{} (setup, once)", p.name), format!("{:.2}", p.ms)])
            .collect();
        rows.extend(r.stats.passes.iter().map(|p| vec![p.name.clone(), format!("{:.2}", p.ms)]));
        rows.push(vec!["frame (first)".into(), format!("{:.2}", r.stats.frame_ms)]);
        rows.push(vec!["frame (median of 3 more)".into(), format!("{:.2}", r.steady_frame_ms)]);
        d.push(Block::Para(format!("{} ({}, {}×{}):", r.png, r.scene, r.size.0, r.size.1)));
        d.push(Block::Table {
            head: vec!["pass".into(), format!("ms ({})", r.stats.timing)],
            rows,
        });
    }
    d.push(Block::Terms(vec![
        ("setup, once".into(), "work done when the scene is loaded (environment visibility maps, gathers), not per frame".into()),
        ("ms".into(), "time of the pass on the GPU (gpu-timestamps) or measured on the CPU around it".into()),
        ("frame (first)".into(), "wall-clock time of the first frame, including shader compilation".into()),
    ]));
    d.push(Block::Heading("Compression sweep".into()));
    d.push(Block::Table {
        head: ["c", "rel. RMSE", "PSNR dB", "compress s", "CPU reconstruct ms", "store MB"]
            .map(String::from)
            .to_vec(),
        rows: sweep
            .iter()
            .map(|r| {
                vec![
                    format!("{}", r[0]),
                    format!("{:.3e}", r[1]),
                    format!("{:.2}", r[2]),
                    format!("{:.3}", r[3]),
                    format!("{:.2}", r[4]),
                    format!("{:.2}", r[5] / 1e6),
                ]
            })
            .collect(),
    });
    d.push(Block::Terms(vec![
        ("c".into(), "components (eigentextures) kept per view slot by the PCA [S03 eq. 1]".into()),
        (
            "rel. RMSE".into(),
            "root of the summed squared error over the summed squared values of the whole BTF"
                .into(),
        ),
        (
            "PSNR dB".into(),
            "10·log10(peak² / mean squared error), peak = brightest value of the BTF".into(),
        ),
        ("compress s".into(), "seconds to compress the whole BTF with this c".into()),
        (
            "CPU reconstruct ms".into(),
            "milliseconds to reconstruct one texture on the CPU (four views × four lights blended)"
                .into(),
        ),
        ("store MB".into(), "size of the eigen store on disk, 10⁶ bytes".into()),
    ]));
    d.push(Block::Figure {
        src: "sweep/accuracy_vs_time.png".into(),
        caption: "Error against compression time; each point labelled with its c.".into(),
    });
    d.push(Block::Figure {
        src: "sweep/size_time.png".into(),
        caption: "Store size and CPU reconstruction time against c.".into(),
    });
    d.push(Block::Figure {
        src: "sweep/reconstructions.png".into(),
        caption: "One picture of the material: original and reconstructions.".into(),
    });
    cost_sweep(out, &mut d)?;
    Ok(d)
}

/// The GPU cost sweep's table from `render-cost/render-cost.csv`, when it ran.
fn cost_sweep(out: &Path, d: &mut Vec<Block>) -> Result<()> {
    let path = out.join("render-cost/render-cost.csv");
    let Ok(text) = std::fs::read_to_string(&path) else {
        d.push(Block::Para("The GPU cost sweep did not run (no GPU adapter).".into()));
        return Ok(());
    };
    d.push(Block::Heading("GPU cost sweep (96×72 frames)".into()));
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap_or_default().split(',').map(String::from).collect();
    let mut worst = 0f64;
    let rows: Vec<Vec<String>> = lines
        .map(|l| {
            let cells: Vec<String> = l
                .split(',')
                .map(|c| match c.parse::<f64>() {
                    Ok(v) if c.contains('e') => format!("{v:.2e}"),
                    Ok(v) if c.contains('.') => format!("{v:.2}"),
                    _ => c.to_string(),
                })
                .collect();
            worst = worst.max(cells.last().and_then(|c| c.parse().ok()).unwrap_or(0.0));
            cells
        })
        .collect();
    anyhow::ensure!(
        head.len() == 11,
        "{}: expected 11 columns, found {}",
        path.display(),
        head.len()
    );
    d.push(Block::Table { head, rows });
    d.push(Block::Terms(vec![
        ("components, evaluation, blending".into(), "the setting: c, BTF evaluated per pixel or per vertex (as the paper), four-nearest or nearest interpolation of views and lights".into()),
        ("rel_rmse".into(), "error of the frame against the reference setting (per-pixel, all components, four/four)".into()),
        ("reads_per_pixel".into(), "texture reads per covered pixel in the BTF pass".into()),
        ("btf_ms, frame_ms".into(), "GPU time of the BTF pass and wall-clock time of the whole frame, median of 3".into()),
        ("plain_ms".into(), "the same frame with plain texture mapping (one read per pixel): the cheapest possible material".into()),
        ("read_bound_ms".into(), "a pass that only performs the BTF pass's texture reads: the time no evaluation of this data can beat".into()),
        ("ratio_plain, ratio_read_bound".into(), "btf_ms over plain_ms and over read_bound_ms".into()),
    ]));
    let target = btf_render::cost_sweep::READ_BOUND_TARGET;
    d.push(Block::Para(format!(
        "Target: the BTF pass within {target}× of its read bound. Worst setting here: {worst:.2}× — {}.",
        if worst <= target { "met" } else { "not met (measured on lavapipe, a CPU rasteriser)" }
    )));
    d.push(Block::Figure {
        src: "render-cost/render-cost.png".into(),
        caption: "Error against BTF pass time, points labelled with c.".into(),
    });
    d.push(Block::Figure {
        src: "render-cost/cost-vs-components.png".into(),
        caption: "BTF pass time against c, with the read bound.".into(),
    });
    d.push(Block::Figure {
        src: "render-cost/eq6-on-off.png".into(),
        caption:
            "Shadows with the smooth shadow boundary of [S03 eq. 6] (left) and a hard edge (right)."
                .into(),
    });
    Ok(())
}
