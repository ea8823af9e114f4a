//! The demo's knitwear stage: a stockinette patch of cotton yarn rendered fiber by fiber
//! on the GPU ([W19], `yarn-render`: fibers generated every frame, level of detail with
//! core strips, self-shadows with shadow hiding, yarn shadows), next to the plain-tube
//! baseline timed in the same run; then the same patch at rest and stretched 30 % along its
//! wales with the yarns moved by the knot solver ([H25], `yarn::knit::knot`), side by side;
//! then the rest patch by the fibers and by [H25]'s yarn strips (`yarn_render::strips`,
//! textures baked once into `knit/bake-cache`) and by [C03]'s lumislices
//! (`yarn_render::lumislice`, the table computed once into the same cache), each timed.
//! Writes `knit/knit.png`, `knit/knit-stretch.png`, `knit/knit-strips.png`,
//! `knit/knit-shadows.png` (the close-up with [W19]'s tube maps and self-shadow volume
//! beside shadows of every fiber, and those at 4 × 4 frames a pixel) and
//! `knit/knit.json` (what the report shows); no equation lives here.

use anyhow::Result;
use std::path::Path;
use std::time::Instant;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::knit::{Chart, KnotModel, KnotParams, SkeletonParams, StitchMesh, chen_skeleton};
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns,
};

/// Renders the knit close-up into `out/knit/`.
pub fn run(out: &Path, width: u32) -> Result<()> {
    let dir = out.join("knit");
    std::fs::create_dir_all(&dir)?;
    let chart = Chart::builtin("stockinette")?;
    let params = yarn::YarnParams::preset("cotton-2ply")?;
    let sk =
        SkeletonParams { color: [0.55, 0.16, 0.12], ..SkeletonParams::new(params.yarn_radius()) };
    let (ws, cs) = sk.default_spacing();
    let set = chen_skeleton(&StitchMesh::flat(&chart, 8, 8, ws, cs)?, &sk)?;
    let mut set = set;
    set.period = None;
    let packed = PackedYarns::new(&set, std::slice::from_ref(&params), &PackOptions::default())?;
    let gpu = btf_render::Gpu::new()?;
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default())?;
    let (lo, hi) = packed.bounds;
    let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
    let span = hi[0] - lo[0];
    let cam = FiberCamera::perspective(
        [c[0] + 0.15 * span, c[1] - 0.55 * span, c[2] + 0.45 * span],
        c,
        [0.0, 0.0, 1.0],
        40.0,
    );
    let lights = [
        FiberLight::Directional { to_light: [-0.4, -0.6, 0.7], irradiance: [2.6, 2.4, 2.2] },
        FiberLight::Directional { to_light: [0.7, 0.3, 0.4], irradiance: [0.5, 0.55, 0.7] },
    ];
    let size = (width.max(64), (width.max(64) * 5) / 8);
    let effects = yarn_render::FiberEffects { ambient: [0.15, 0.16, 0.18], ..Default::default() };
    let settings = FiberSettings { effects, ..Default::default() };
    let fibers = FiberRenderer::new(&gpu, &packed, &bcsdf, settings)?;
    let tubes =
        FiberRenderer::new(&gpu, &packed, &bcsdf, FiberSettings { tubes: true, ..settings })?;
    // One warm-up frame each, then interleaved timing.
    let img = fibers.render(&gpu, &cam, &lights, size, [0.02, 0.02, 0.025, 1.0])?;
    tubes.render(&gpu, &cam, &lights, size, [0.0; 4])?;
    let (mut tf, mut tt) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..2 {
        let t = Instant::now();
        fibers.render(&gpu, &cam, &lights, size, [0.0; 4])?;
        tf = tf.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        tubes.render(&gpu, &cam, &lights, size, [0.0; 4])?;
        tt = tt.min(t.elapsed().as_secs_f64());
    }
    let rgb: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    btf_image::write::write_png_linear(
        &dir.join("knit.png"),
        size.0 as usize,
        size.1 as usize,
        &rgb,
        1.0,
    )?;
    // The same close-up with shadows of every fiber (`fiber_shadows`: each light's map drawn
    // from the fibers, fitted to the view) beside [W19]'s tube maps and volume, timed.
    let fx = yarn_render::FiberEffects { fiber_shadows: true, ..effects };
    let cast = FiberRenderer::new(
        &gpu,
        &packed,
        &bcsdf,
        FiberSettings { effects: fx, shadow_map: 2048, ..settings },
    )?;
    let cimg = cast.render(&gpu, &cam, &lights, size, [0.02, 0.02, 0.025, 1.0])?;
    let t = Instant::now();
    cast.render(&gpu, &cam, &lights, size, [0.0; 4])?;
    let tc = t.elapsed().as_secs_f64();
    // And at 4 × 4 frames a pixel (`supersample`): the fibers antialiased, as the converged
    // comparisons draw them.
    let fine = FiberRenderer::new(
        &gpu,
        &packed,
        &bcsdf,
        FiberSettings { effects: fx, shadow_map: 2048, supersample: 4, ..settings },
    )?;
    let simg = fine.render(&gpu, &cam, &lights, size, [0.02, 0.02, 0.025, 1.0])?;
    let t = Instant::now();
    fine.render(&gpu, &cam, &lights, size, [0.0; 4])?;
    let t_fine = t.elapsed().as_secs_f64();
    let srgb = |im: &yarn_render::FiberImage| {
        let rgb: Vec<f32> = im.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        btf_image::write::to_srgb_image(size.0 as usize, size.1 as usize, &rgb, 1.0)
    };
    let (a, b, c) = (srgb(&img), srgb(&cimg), srgb(&simg));
    let la = format!("tubes + density, {:.0} ms", tf * 1e3);
    let lb = format!("every fiber casts, {:.0} ms", tc * 1e3);
    let lc = format!("4 x 4 frames/px, {:.0} ms", t_fine * 1e3);
    btf_image::write::write_png(
        &dir.join("knit-shadows.png"),
        &btf_image::compose::captioned_strip(
            &[(&a, la.as_str()), (&b, lb.as_str()), (&c, lc.as_str())],
            6,
        ),
    )?;
    // The knot solver: the same patch at rest and stretched along its wales.
    let stretch = 0.3;
    let rest_mesh = StitchMesh::flat(&chart, 8, 8, ws, cs)?;
    let model = KnotModel::new(&rest_mesh, &sk, (ws, cs))?;
    let stretched = rest_mesh.stretch(0.0, stretch)?;
    // The stitch template relaxed once with yarn–yarn contact (DESIGN §3.3 item 1), carried
    // on top of every solve: the yarns touch instead of overlapping.
    let kp = KnotParams::default();
    let detail = yarn::knit::knot::RestDetail::relax(
        &model,
        &rest_mesh,
        &kp,
        &yarn::knit::knot::ContactParams::default(),
    )?;
    let t = Instant::now();
    let plain = model.solve(&stretched, &kp)?;
    let frame = detail.apply(&model, &stretched, &plain)?;
    let solve_ms = t.elapsed().as_secs_f64() * 1e3;
    let clear = |f: &yarn::knit::KnotFrame| -> Result<f64> {
        Ok(yarn::knit::knot::min_clearance(
            &model.yarn_set(f, 1)?,
            stretched.lattice,
            sk.yarn_radius,
            8,
        )
        .ratio)
    };
    let (clearance, clearance_plain) = (clear(&frame)?, clear(&plain)?);
    let rest = detail.apply(&model, &rest_mesh, &model.solve(&rest_mesh, &kp)?)?;
    let mut panels = Vec::new();
    for (f, label) in [(&rest, "rest"), (&frame, "stretched 30 % along the wales")] {
        let mut ys = model.yarn_set(f, 1)?;
        ys.period = None;
        let pk = PackedYarns::new(&ys, std::slice::from_ref(&params), &PackOptions::default())?;
        let r = FiberRenderer::new(&gpu, &pk, &bcsdf, settings)?;
        let (lo, hi) = pk.bounds;
        let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
        // The rest patch's camera, moved with the patch centre: the stretch shows.
        let cam = FiberCamera::perspective(
            [c[0] + 0.15 * span, c[1] - 0.55 * span, c[2] + 0.45 * span],
            c,
            [0.0, 0.0, 1.0],
            40.0,
        );
        let im = r.render(&gpu, &cam, &lights, size, [0.02, 0.02, 0.025, 1.0])?;
        let rgb: Vec<f32> = im.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        panels.push((
            btf_image::write::to_srgb_image(size.0 as usize, size.1 as usize, &rgb, 1.0),
            label,
        ));
    }
    let pairs: Vec<(&image::RgbImage, &str)> = panels.iter().map(|(i, l)| (i, *l)).collect();
    btf_image::write::write_png(
        &dir.join("knit-stretch.png"),
        &btf_image::compose::captioned_strip(&pairs, 6),
    )?;
    // Fibers against yarn strips on the rest patch, each timed (best of two frames).
    let t = Instant::now();
    let bakes = yarn_render::strips::bakes_for(
        &set,
        std::slice::from_ref(&params),
        &bcsdf,
        &yarn_precompute::StripBakeSettings { spp: 4, ..Default::default() },
        Some(&dir.join("bake-cache")),
        &|_| {},
    )?;
    let bake_s = if bakes[0].from_cache { bakes[0].seconds } else { t.elapsed().as_secs_f64() };
    let mut strips = yarn_render::StripRenderer::new(
        &gpu,
        &packed,
        &bakes,
        &bcsdf,
        yarn_render::StripSettings::default(),
    )?;
    strips.set_ambient(effects.ambient);
    let fly = yarn_render::strips::flyaways_for(std::slice::from_ref(&params), 1)?;
    strips.set_flyaways(&gpu, &fly)?;
    let simg = strips.render(&gpu, &cam, &lights, size, [0.02, 0.02, 0.025, 1.0])?;
    let mut ts = f64::INFINITY;
    for _ in 0..2 {
        let t = Instant::now();
        strips.render(&gpu, &cam, &lights, size, [0.0; 4])?;
        ts = ts.min(t.elapsed().as_secs_f64());
    }
    let to_img = srgb;
    // And by [C03]'s lumislices (the table computed once into the same cache).
    let t = Instant::now();
    let slice = yarn_precompute::Lumislice::for_params(
        &params,
        sk.color,
        &yarn_precompute::LumisliceSettings::default(),
        Some(&dir.join("bake-cache")),
        &|_| {},
    )?;
    let slice_s = if slice.from_cache { slice.seconds } else { t.elapsed().as_secs_f64() };
    let lum = yarn_render::LumisliceRenderer::new(
        &gpu,
        &packed,
        std::slice::from_ref(&slice),
        yarn_render::LumisliceRenderSettings::default(),
    )?;
    let limg = lum.render(&gpu, &cam, &lights, size, [0.02, 0.02, 0.025, 1.0])?;
    let mut tl = f64::INFINITY;
    for _ in 0..2 {
        let t = Instant::now();
        lum.render(&gpu, &cam, &lights, size, [0.0; 4])?;
        tl = tl.min(t.elapsed().as_secs_f64());
    }
    let (fi, si, li) = (to_img(&img), to_img(&simg), to_img(&limg));
    let fl = format!("fibers {:.0} ms", tf * 1e3);
    let sl = format!("strips {:.0} ms", ts * 1e3);
    let ll = format!("lumislices {:.0} ms", tl * 1e3);
    btf_image::write::write_png(
        &dir.join("knit-strips.png"),
        &btf_image::compose::captioned_strip(
            &[(&fi, fl.as_str()), (&si, sl.as_str()), (&li, ll.as_str())],
            6,
        ),
    )?;
    let st = img.stats;
    let j = serde_json::json!({
        "strips_png": "knit/knit-strips.png",
        "strips_ms": ts * 1e3,
        "strips_bake_s": bake_s,
        "lumislice_ms": tl * 1e3,
        "lumislice_table_s": slice_s,
        "stretch_png": "knit/knit-stretch.png",
        "stretch": stretch,
        "knot_faces": model.knot_faces(),
        "knot_solve_ms": solve_ms,
        "stretch_clearance": clearance,
        "stretch_clearance_plain": clearance_plain,
        "png": "knit/knit.png",
        "width": size.0, "height": size.1,
        "stitches": [8, 8],
        "control_points": packed.control_points(),
        "yarn_bytes": st.yarn_bytes,
        "fiber_instances": st.instances,
        "triangles": st.triangles,
        "fibers_ms": tf * 1e3,
        "tubes_ms": tt * 1e3,
        "shadows_png": "knit/knit-shadows.png",
        "fiber_shadows_ms": tc * 1e3,
        "fiber_shadows_supersampled_ms": t_fine * 1e3,
        "fiber_shadow_instances": cimg.stats.shadow_instances,
    });
    btf_image::write::write_text(&dir.join("knit.json"), &serde_json::to_string_pretty(&j)?)?;
    Ok(())
}
