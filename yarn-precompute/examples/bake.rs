//! Bakes the default precomputation of a yarn preset, prints the time per part, and writes
//! pictures: the core texture (alpha, height, normal, direction), one self-shadow slice
//! (transmittance) and the AO texture.
//!
//! `cargo run --release -p yarn-precompute --example bake -- [preset] [out_dir]`

use std::path::PathBuf;
use yarn::YarnParams;
use yarn_precompute::{BakeSettings, Precomputed};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let preset = args.next().unwrap_or_else(|| "cotton-2ply".into());
    let out = PathBuf::from(args.next().unwrap_or_else(|| "target/yarn-precompute".into()));
    std::fs::create_dir_all(&out)?;
    let params = YarnParams::preset(&preset)?;
    let t = std::time::Instant::now();
    let p = Precomputed::bake(&params, &BakeSettings::default())?;
    println!("{preset}: default bake {:.2} s ({:?})", t.elapsed().as_secs_f64(), p.times);
    println!("AO cubic {:?}, rms residual {:.4}", p.ao_cubic.coeffs, p.ao_cubic.rms_residual);
    let c = &p.core;
    let (w, h) = (c.width, c.height);
    let grey = |v: f64| [v as f32; 3];
    let mut rows: Vec<[f32; 3]> = Vec::new();
    // Four panels stacked: alpha, height, normal (w, e, T) → RGB, direction (T, w, e) → RGB.
    for panel in 0..4 {
        for j in 0..h {
            for i in 0..w {
                let k = 4 * (j * w + i);
                let (a, b) = (&c.tex_a[k..k + 4], &c.tex_b[k..k + 4]);
                rows.push(match panel {
                    0 => grey(a[0] as f64),
                    1 => grey(0.5 + 0.5 * a[1] as f64),
                    2 => [a[2], b[3], a[3]].map(|x| 0.5 + 0.5 * x),
                    _ => [b[0], b[1], b[2]].map(|x| 0.5 + 0.5 * x),
                });
            }
        }
    }
    let flat: Vec<f32> = rows.iter().flatten().copied().collect();
    btf_image::write::write_png_linear(&out.join("core.png"), w, 4 * h, &flat, 1.0)?;
    let s = &p.self_shadow;
    let slice: Vec<f32> = s.depth[..s.res * s.res].iter().flat_map(|d| [(-d).exp(); 3]).collect();
    btf_image::write::write_png_linear(
        &out.join("self_shadow_slice0.png"),
        s.res,
        s.res,
        &slice,
        1.0,
    )?;
    let a = &p.ao_texture;
    let ao: Vec<f32> = a.ao.iter().flat_map(|v| [*v; 3]).collect();
    btf_image::write::write_png_linear(&out.join("ao.png"), a.res, a.res, &ao, 1.0)?;
    println!("wrote {}", out.display());
    Ok(())
}
