//! An environment map binned into the texels of a cube map for the gathers of
//! `[S03 eq. 10]`: the filtered form of `L_env` that the hemicube pixels look up.
//!
//! A hemicube pixel stands for `~(2/res)²` sr; a sun of 1e-5 sr must neither be missed
//! (aliasing: it falls between pixel centres) nor counted twice. Rather than looking the map
//! up at pixel centres, [`EnvCube::new`] bins it into cube texels about as large as the
//! hemicube pixels, each kept as a directional source carrying the texel's exact power
//! `Σ L dω` at the power-weighted centroid of its directions; the gather then drops every
//! source into the one hemicube pixel it falls in. Energy is conserved exactly, a sun keeps
//! its direction, and what remains is the hemicube's own quantisation of directions.

use btf_image::EnvMap;
use std::f64::consts::PI;

/// Face and face coordinates `(a, b) ∈ [−1, 1]²` of a direction on the unit cube.
fn cube_coords(d: [f32; 3]) -> (usize, f32, f32) {
    let [x, y, z] = d;
    let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
    if ax >= ay && ax >= az {
        let m = ax.max(f32::MIN_POSITIVE);
        (if x > 0.0 { 0 } else { 1 }, y / m, z / m)
    } else if ay >= az {
        (if y > 0.0 { 2 } else { 3 }, x / ay, z / ay)
    } else {
        (if z > 0.0 { 4 } else { 5 }, x / az, y / az)
    }
}

/// An environment binned into the texels of a cube map, each kept as a directional
/// source: its power `Σ L dω` (exact: every pixel lands in exactly one texel) at the
/// power-weighted centroid of its directions. Texels without power are dropped.
#[derive(Debug, Clone)]
pub struct EnvCube {
    /// Texels per face side.
    pub res: usize,
    /// Unit direction of every kept texel (world, before rotation).
    pub dirs: Vec<[f32; 3]>,
    /// RGB power `∫ L dω` of every kept texel, W·sr-normalised radiance units × sr.
    pub power: Vec<[f32; 3]>,
}

impl EnvCube {
    /// Bins `env` into `6 res²` cube texels. Each pixel is split into `s × s` parts
    /// (`s = ⌈4 res / H⌉`) so a coarse map still spreads over the texels it covers.
    pub fn new(env: &EnvMap, res: usize) -> EnvCube {
        let res = res.max(1);
        let s = (4 * res).div_ceil(env.height).clamp(1, 32);
        let (w, h) = (env.width * s, env.height * s);
        let cols: Vec<(f64, f64)> =
            (0..w).map(|c| (2.0 * PI * (c as f64 + 0.5) / w as f64).sin_cos()).collect();
        // Per texel: RGB power, then the luminance-power-weighted direction sum.
        let mut acc = vec![[0f64; 6]; 6 * res * res];
        for row in 0..h {
            let (t0, t1) = (PI * row as f64 / h as f64, PI * (row + 1) as f64 / h as f64);
            let om = 2.0 * PI / w as f64 * (t0.cos() - t1.cos());
            let (st, ct) = (PI * (row as f64 + 0.5) / h as f64).sin_cos();
            let src = &env.pixels[row / s * env.width..(row / s + 1) * env.width];
            for (col, &(sp, cp)) in cols.iter().enumerate() {
                let p = src[col / s];
                let d = [st * cp, st * sp, ct];
                let a = &mut acc[texel_of(res, d.map(|c| c as f32))];
                let lum = (p[0] as f64 + p[1] as f64 + p[2] as f64) * om;
                for c in 0..3 {
                    a[c] += p[c] as f64 * om;
                    a[3 + c] += d[c] * lum;
                }
            }
        }
        let mut cube = EnvCube { res, dirs: vec![], power: vec![] };
        for a in &acc {
            let len = (a[3] * a[3] + a[4] * a[4] + a[5] * a[5]).sqrt();
            if len > 0.0 && a[..3].iter().any(|&x| x > 0.0) {
                cube.dirs.push([a[3], a[4], a[5]].map(|c| (c / len) as f32));
                cube.power.push([a[0] as f32, a[1] as f32, a[2] as f32]);
            }
        }
        cube
    }

    /// Total power per channel (equals [`EnvMap::integral`]).
    pub fn total(&self) -> [f64; 3] {
        let mut t = [0.0; 3];
        for p in &self.power {
            (0..3).for_each(|c| t[c] += p[c] as f64);
        }
        t
    }
}

fn texel_of(res: usize, d: [f32; 3]) -> usize {
    let (face, a, b) = cube_coords(d);
    let i = (((a + 1.0) * 0.5 * res as f32) as usize).min(res - 1);
    let j = (((b + 1.0) * 0.5 * res as f32) as usize).min(res - 1);
    face * res * res + j * res + i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_keeps_energy_and_finds_the_sun() {
        let sun = [0.6f64, 0.0, 0.8];
        let env = EnvMap::from_fn(256, |d| {
            let c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
            [if c > 0.9995 { 1e5 } else { 1.0 }; 3]
        })
        .unwrap();
        for res in [4, 16] {
            let cube = EnvCube::new(&env, res);
            let (got, exact) = (cube.total()[0], env.integral()[0]);
            assert!((got / exact - 1.0).abs() < 1e-5, "{got} vs {exact}");
            // The brightest texel sits at the sun, not at a texel centre.
            let k = (0..cube.power.len())
                .max_by(|&a, &b| cube.power[a][0].total_cmp(&cube.power[b][0]))
                .unwrap();
            let d = cube.dirs[k];
            let cos = d[0] as f64 * sun[0] + d[1] as f64 * sun[1] + d[2] as f64 * sun[2];
            assert!(cos > 0.9995, "res {res}: {d:?}");
        }
        let dark = EnvCube::new(&EnvMap::constant(16, [0.0; 3]).unwrap(), 4);
        assert!(dark.dirs.is_empty());
    }
}
