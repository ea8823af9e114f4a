//! Renders a Crane plain-knit patch of cotton yarn with the GPU fiber renderer and writes
//! `fiber_preview.png` (tone-mapped linear RGB) into the directory given (default `.`):
//! `cargo run --release -p yarn-render --example fiber_preview -- OUT_DIR [lod_px]`.

use btf_render::Gpu;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::knit::crane::CraneKnit;
use yarn::{YarnParams, YarnSet};
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = std::path::PathBuf::from(args.get(1).map(String::as_str).unwrap_or("."));
    let lod_px: f32 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(1.0);
    let p = YarnParams::preset("cotton-2ply")?;
    let k = CraneKnit::for_yarn_radius(p.yarn_radius());
    let mut set: YarnSet = k.yarn_set(4, 4, 8)?;
    set.period = None;
    let colors = [[0.8, 0.25, 0.2], [0.85, 0.8, 0.7]];
    for (i, c) in set.curves.iter_mut().enumerate() {
        *c = c.clone().with_color(colors[i % 2]);
    }
    let packed = PackedYarns::new(&set, std::slice::from_ref(&p), &PackOptions::default())?;
    let gpu = Gpu::new()?;
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default())?;
    let settings = FiberSettings { lod_px, ..Default::default() };
    let r = FiberRenderer::new(&gpu, &packed, &bcsdf, settings)?;
    let (lo, hi) = packed.bounds;
    let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
    let cam = FiberCamera::perspective([c[0], c[1] - 0.012, c[2] + 0.02], c, [0.0, 0.0, 1.0], 30.0);
    let lights = [FiberLight::Directional { to_light: [0.3, -0.5, 1.0], irradiance: [3.0; 3] }];
    let t = std::time::Instant::now();
    let img = r.render(&gpu, &cam, &lights, (512, 512), [0.0, 0.0, 0.0, 1.0])?;
    eprintln!("{:?} in {:.2} s", img.stats, t.elapsed().as_secs_f64());
    let mut rgb = image::RgbImage::new(img.width, img.height);
    for (i, px) in img.pixels.iter().enumerate() {
        let tm = |x: f32| ((x / (1.0 + x)).powf(1.0 / 2.2) * 255.0).round() as u8;
        rgb.put_pixel(
            i as u32 % img.width,
            i as u32 / img.width,
            image::Rgb([tm(px[0]), tm(px[1]), tm(px[2])]),
        );
    }
    std::fs::create_dir_all(&out)?;
    rgb.save(out.join("fiber_preview.png"))?;
    Ok(())
}
