//! The report of `btf knit sweep` (issue #19, DESIGN §2.5 "What accuracy costs in time"):
//! the cells as CSV and a Markdown table, the LoD crossover — with e₀ the error at the
//! finest threshold swept, the largest ω^LoD ([W19 eq. 4]) whose error and that of every
//! finer threshold stay within ±10 % of e₀ — and the error-against-time-ratio plot.

use super::knit_sweep::{Cam, Cell, SweepArgs};
use btf_image::plot::{Plot, Series};
use std::fmt::Write as _;

pub(crate) fn n_max_text(n: u32) -> String {
    if n == u32::MAX { "all".into() } else { n.to_string() }
}

pub(crate) fn csv(cells: &[Cell], cams: &[Cam]) -> String {
    let mut s = String::from(
        "camera,stitch_px,shading,n_max,method,lod_px,segments,culled,instances,triangles,yarn_bytes,\
         rel_rmse_interior,interior_px,rel_rmse_band,band_px,rel_rmse_all,all_px,rel_rmse_vs_full,frame_ms,tubes_ms,ratio_tubes,\
         mean_ratio,fibers_ms,ratio_fibers,bake_s\n",
    );
    for c in cells {
        let px = cams.iter().find(|k| k.name == c.camera).and_then(|k| k.stitch_px);
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{:.6e},{},{:.6e},{},{:.6e},{},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.2}",
            c.camera,
            px.map(|p| p.to_string()).unwrap_or_default(),
            c.shading,
            n_max_text(c.n_max),
            method(c),
            c.lod_px.map(|l| l.to_string()).unwrap_or_default(),
            c.stats.segments,
            c.stats.culled,
            c.stats.instances,
            c.stats.triangles,
            c.stats.yarn_bytes,
            c.interior.0,
            c.interior.1,
            c.band.0,
            c.band.1,
            c.all.0,
            c.all.1,
            if c.vs_full.is_finite() { format!("{:.6e}", c.vs_full) } else { String::new() },
            c.ms,
            c.tubes_ms,
            c.ms / c.tubes_ms,
            c.mean_ratio,
            c.fibers_ms,
            c.ms / c.fibers_ms,
            c.bake_s
        );
    }
    s
}

/// `fibers`, `tubes` or `strips-VARIANT`.
fn method(c: &Cell) -> String {
    match (&c.strips, c.lod_px) {
        (Some(v), _) => format!("strips-{v}"),
        (None, Some(_)) => "fibers".into(),
        (None, None) => "tubes".into(),
    }
}

/// The LoD crossover of one (camera, shading, n_max) series: with `e₀` the covered-pixel error
/// at the smallest threshold swept (full detail when 0 is swept), the largest ω^LoD such
/// that it and every smaller threshold keep the error within ±10 % of e₀ — the most LoD
/// that changes the error by at most 10 % either way (a large drop is as much a change of
/// appearance as a rise while e₀ is large). A NaN error counts as outside the band.
pub fn crossover(series: &[(f32, f64)]) -> Option<Crossover> {
    let mut s: Vec<(f32, f64)> = series.to_vec();
    s.sort_by(|a, b| a.0.total_cmp(&b.0));
    let &(l0, e0) = s.first()?;
    let mut lod = l0;
    for &(l, e) in &s[1..] {
        let within = (e - e0).abs().partial_cmp(&(0.1 * e0)).is_some_and(|o| o.is_le());
        if !within {
            return Some(Crossover { lod, e0, next: Some((l, e)) });
        }
        lod = l;
    }
    Some(Crossover { lod, e0, next: None })
}

/// The LoD crossover of one series (see [`crossover`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossover {
    /// The crossover threshold ω^LoD (px).
    pub lod: f32,
    /// The error at the smallest threshold swept.
    pub e0: f64,
    /// The first threshold past the crossover and its error.
    pub next: Option<(f32, f64)>,
}

/// One crossover per (camera, shading, n_max).
type CrossoverRow = (String, String, u32, Option<Crossover>);

fn crossovers(cells: &[Cell]) -> Vec<CrossoverRow> {
    let mut keys: Vec<(String, String, u32)> = Vec::new();
    for c in cells.iter().filter(|c| c.lod_px.is_some()) {
        let k = (c.camera.clone(), c.shading.clone(), c.n_max);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(cam, sh, n)| {
            let series: Vec<(f32, f64)> = cells
                .iter()
                .filter(|c| c.camera == cam && c.shading == sh && c.n_max == n)
                .filter_map(|c| c.lod_px.map(|l| (l, c.all.0)))
                .collect();
            let x = crossover(&series);
            (cam, sh, n, x)
        })
        .collect()
}

pub(crate) fn markdown(
    a: &SweepArgs,
    cells: &[Cell],
    cams: &[Cam],
    st: [usize; 2],
    (w, h): (u32, u32),
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## What accuracy costs in time: GPU fibers against the reference ({} × {} stitches of {}, {}, {w}×{h}, MSAA {}, reference {} spp, {} bounce{})\n",
        st[0],
        st[1],
        a.chart,
        a.yarn,
        a.msaa,
        a.spp,
        a.bounces,
        if a.bounces == 1 { "" } else { "s" }
    );
    let tiles: Vec<String> =
        cams.iter().map(|c| format!("{} ({}×{} periods)", c.name, c.tiles, c.tiles)).collect();
    let _ = writeln!(
        s,
        "Cameras (viewing direction θ,φ = {}° for all): {}. {} Shadows of the fibers: {} ({}² maps). Core strips: {}. Fiber strips widened to {} px; {} × {} frames a pixel at MSAA {} ({} samples); the reference's fibers at {} points a helix turn, the GPU's at {} subdivisions a segment. Frame ms: median of {} interleaved frames; × tubes: against the plain tubes of the same camera and shading in this run.\n",
        a.view,
        tiles.join(", "),
        if a.hairs {
            "Hair flyaways on (`--hairs`): in the reference, the GPU fibers (the same hairs) and the strips (their flyaway overlay)."
        } else {
            "Hair flyaways off in both (R-approx)."
        },
        if a.fiber_shadows {
            "every fiber casts (`--fiber-shadows`)"
        } else {
            "tube maps and the self-shadow volume [W19 §4.1]"
        },
        a.shadow_map,
        if a.no_core { "off (`--no-core`: every fiber explicit)" } else { "on [W19 §3.2]" },
        a.min_strip_px,
        a.supersample,
        a.supersample,
        a.msaa,
        a.supersample * a.supersample * a.msaa,
        a.samples_per_turn,
        a.n_sub,
        a.repeat
    );
    s.push_str("| camera | shading | n_max | method | ω^LoD px | instances | triangles | rel. RMSE interior | (px) | rel. RMSE silhouette | (px) | rel. RMSE covered | vs full detail | mean / ref | frame ms | × tubes | × fibers |\n");
    s.push_str(
        "|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let e = |v: f64| if v.is_finite() { format!("{v:.4}") } else { "—".into() };
    for c in cells {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} | {:.2} | {} |",
            c.camera,
            c.shading,
            n_max_text(c.n_max),
            method(c),
            c.lod_px.map_or("—".into(), |l| l.to_string()),
            c.stats.instances,
            c.stats.triangles,
            e(c.interior.0),
            c.interior.1,
            e(c.band.0),
            c.band.1,
            e(c.all.0),
            e(c.vs_full),
            e(c.mean_ratio),
            c.ms,
            c.ms / c.tubes_ms,
            e(c.ms / c.fibers_ms)
        );
    }
    if cells.iter().any(|c| c.strips.is_some()) {
        s.push_str("\nYarn strips [H25] (`--strips`): baked textures of a straight yarn of this one, at the variant's settings; bake seconds (as baked, also when read from DIR/bake-cache): ");
        let mut seen: Vec<&str> = Vec::new();
        let mut bakes: Vec<String> = Vec::new();
        for c in cells {
            if let Some(v) = &c.strips
                && !seen.contains(&v.as_str())
            {
                seen.push(v);
                bakes.push(format!("{v} {:.1} s", c.bake_s));
            }
        }
        let _ = writeln!(
            s,
            "{}. × fibers: frame time against the finest fiber cell of the same camera and shading.",
            bakes.join(", ")
        );
    }
    s.push_str("\nInterior: reference coverage ≥ 0.99 and GPU alpha ≥ 0.99; silhouette: the other pixels either image covers by more than 0.01; covered: both together (a LoD that thins the yarn moves pixels out of the interior, so the crossover is judged on this one); vs full detail: the frame against the finest threshold's GPU image (what the LoD alone changes). LoD crossover: the largest ω^LoD whose covered-pixel error, and that of every smaller threshold, stays within ±10 % of the error at the smallest threshold swept (full detail at 0). Two-sided: while the full-detail error is large, a LoD that drops most fibers can score *lower* against the reference (a near-black frame scores ≈ 1), and that is a change of appearance, not a gain.\n\n");
    for (cam, sh, n, x) in crossovers(cells) {
        match x {
            Some(Crossover { lod: l, e0, next }) => {
                let after = next.map_or("no threshold swept leaves the band".into(), |(l2, e2)| {
                    format!("ω^LoD = {l2} px gives {e2:.4}")
                });
                let _ = writeln!(
                    s,
                    "- {cam}, {sh}, n_max {}: crossover ω^LoD = **{l} px** (full-detail error {e0:.4}; {after})",
                    n_max_text(n)
                );
            }
            None => {
                let _ = writeln!(s, "- {cam}, {sh}: no fiber cells");
            }
        }
    }
    s.push_str("\n![error against time](sweep.png)\n");
    s
}

pub(crate) fn plot(cells: &[Cell]) -> Plot {
    let mut series = Vec::new();
    let mut keys: Vec<(String, String, u32)> = Vec::new();
    for c in cells.iter().filter(|c| c.lod_px.is_some()) {
        let k = (c.camera.clone(), c.shading.clone(), c.n_max);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let finite = |x: f64, y: f64| x.is_finite() && y.is_finite() && y > 0.0;
    for (cam, sh, n) in keys {
        let pts: Vec<(f64, f64, f64)> = cells
            .iter()
            .filter(|c| c.camera == cam && c.shading == sh && c.n_max == n)
            .filter_map(|c| c.lod_px.map(|l| (l as f64, c.ms / c.tubes_ms, c.all.0)))
            .filter(|p| finite(p.1, p.2))
            .collect();
        let name = if n == u32::MAX { format!("{cam} {sh}") } else { format!("{cam} {sh} n{n}") };
        // Labels from the f32 threshold as given (0.1, not 0.10000000149…).
        series.push(Series::parametric(name, pts, |l| format!("{}px", l as f32)));
    }
    let mut strip_keys: Vec<(String, String)> = Vec::new();
    for c in cells.iter().filter(|c| c.strips.is_some()) {
        let k = (c.camera.clone(), c.shading.clone());
        if !strip_keys.contains(&k) {
            strip_keys.push(k);
        }
    }
    for (cam, sh) in strip_keys {
        let pts: Vec<(f64, f64)> = cells
            .iter()
            .filter(|c| c.strips.is_some() && c.camera == cam && c.shading == sh)
            .map(|c| (c.ms / c.tubes_ms, c.all.0))
            .filter(|p| finite(p.0, p.1))
            .collect();
        let mut t = Series::new(format!("{cam} {sh} strips"), pts);
        t.points_only = true;
        series.push(t);
    }
    let tubes: Vec<(f64, f64)> = cells
        .iter()
        .filter(|c| c.lod_px.is_none() && c.strips.is_none())
        .map(|c| (1.0, c.all.0))
        .filter(|p| finite(p.0, p.1))
        .collect();
    let mut t = Series::new("plain tubes", tubes);
    t.points_only = true;
    series.push(t);
    Plot {
        title: "GPU fibers and yarn strips: error against frame time".into(),
        x_label: "frame time / plain tubes (same run, log)".into(),
        y_label: "rel. RMSE against the reference, covered pixels (log)".into(),
        log_y: true,
        log_x: true,
        series,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossover_is_the_last_threshold_within_ten_percent() {
        let s = [(0.0, 0.10), (0.5, 0.105), (1.0, 0.109), (2.0, 0.2), (4.0, 0.105)];
        let c = crossover(&s).unwrap();
        assert_eq!((c.lod, c.e0), (1.0, 0.10));
        assert_eq!(c.next, Some((2.0, 0.2)));
        assert_eq!(crossover(&[(0.0, 0.1), (1.0, 0.1)]).unwrap().lod, 1.0);
        assert_eq!(crossover(&[(0.0, 0.1), (1.0, f64::NAN)]).unwrap().lod, 0.0);
        // Two-sided: a 20 % drop leaves the band too.
        assert_eq!(crossover(&[(0.0, 1.0), (0.5, 0.95), (1.0, 0.8)]).unwrap().lod, 0.5);
        assert!(crossover(&[]).is_none());
    }
}
