//! ꟻLIP's colour spaces, all in `f32` as in the reference implementation (so that maps agree
//! with it to float rounding): linear sRGB ↔ CIE XYZ (D65), XYZ ↔ YCxCz (the linearised
//! opponent space in which the contrast sensitivity filters act, `[A20, colour pipeline]`),
//! XYZ → CIE L*a*b*, the Hunt adjustment of the chroma (`a*·L*/100`), the HyAB distance
//! (`|ΔL| + ‖Δ(a, b)‖`, Abasi et al. 2020) and the largest such distance between two
//! displayable colours (pure green against pure blue), which normalises ΔE to `[0, 1]`.

/// The D65 white point in XYZ (`Y = 1`).
#[allow(clippy::excessive_precision)]
const WHITE_D65: [f32; 3] = [0.950_428_545, 1.0, 1.088_900_371];
/// Its reciprocal, as the reference writes it (not recomputed, to keep its rounding).
#[allow(clippy::excessive_precision)]
const INV_WHITE_D65: [f32; 3] = [1.052_156_925, 1.0, 0.918_357_670];

/// Linear sRGB (D65) → CIE XYZ. The matrix entries are exact ratios of integers (the
/// sRGB primaries and white in rational form), rounded once to `f32`.
#[rustfmt::skip]
const RGB_TO_XYZ: [[f32; 3]; 3] = [
    [10_135_552.0 / 24_577_794.0, 8_788_810.0 / 24_577_794.0, 4_435_075.0 / 24_577_794.0],
    [2_613_072.0 / 12_288_897.0, 8_788_810.0 / 12_288_897.0, 887_015.0 / 12_288_897.0],
    [1_425_312.0 / 73_733_382.0, 8_788_810.0 / 73_733_382.0, 70_074_185.0 / 73_733_382.0],
];

/// CIE XYZ → linear sRGB (D65), the reference's decimals.
#[rustfmt::skip]
#[allow(clippy::excessive_precision)]
const XYZ_TO_RGB: [[f32; 3]; 3] = [
    [3.241_003_275, -1.537_398_934, -0.498_615_861],
    [-0.969_224_334, 1.875_930_071, 0.041_554_224],
    [0.055_639_423, -0.204_011_202, 1.057_148_933],
];

fn mat3(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

/// Linear sRGB → XYZ.
pub(crate) fn linear_rgb_to_xyz(rgb: [f32; 3]) -> [f32; 3] {
    mat3(&RGB_TO_XYZ, rgb)
}

/// XYZ → linear sRGB.
pub(crate) fn xyz_to_linear_rgb(xyz: [f32; 3]) -> [f32; 3] {
    mat3(&XYZ_TO_RGB, xyz)
}

/// XYZ → YCxCz: `Y = 116·y − 16`, `Cx = 500·(x − y)`, `Cz = 200·(y − z)` on the white-
/// normalised `(x, y, z)` — L*a*b* without the cube root, so linear and filterable.
pub(crate) fn xyz_to_ycxcz(xyz: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = [0, 1, 2].map(|i| xyz[i] * INV_WHITE_D65[i]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// YCxCz → XYZ (the inverse of [`xyz_to_ycxcz`]).
pub(crate) fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let (cx, cz) = (c[1] / 500.0, c[2] / 200.0);
    let xyz = [y + cx, y, y - cz];
    [0, 1, 2].map(|i| xyz[i] * WHITE_D65[i])
}

/// XYZ → CIE L*a*b* (D65 white; the linear segment below `(6/29)³`).
pub(crate) fn xyz_to_lab(xyz: [f32; 3]) -> [f32; 3] {
    const DELTA: f32 = 6.0 / 29.0;
    let delta_cube = DELTA * (DELTA * DELTA);
    let slope = 1.0 / (3.0 * (DELTA * DELTA));
    let f = |t: f32| if t > delta_cube { t.powf(1.0 / 3.0) } else { slope * t + 4.0 / 29.0 };
    let [x, y, z] = [0, 1, 2].map(|i| f(xyz[i] * INV_WHITE_D65[i]));
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// The Hunt effect (chroma looks stronger when lighter): `(L*, a*, b*)` →
/// `(L*, 0.01·L*·a*, 0.01·L*·b*)`.
pub(crate) fn hunt(lab: [f32; 3]) -> [f32; 3] {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

/// Linear sRGB (after the CSF filter, clamped to `[0, 1]`) → Hunt-adjusted L*a*b*.
pub(crate) fn linear_rgb_to_hunt_lab(rgb: [f32; 3]) -> [f32; 3] {
    hunt(xyz_to_lab(linear_rgb_to_xyz(rgb)))
}

/// HyAB distance: city-block in lightness plus Euclidean in chroma.
pub(crate) fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    let (da, db) = (a[1] - b[1], a[2] - b[2]);
    (a[0] - b[0]).abs() + (da * da + db * db).sqrt()
}

/// `HyAB(green, blue)^q_c`: the largest colour difference between displayable colours
/// after the exponent, the `c_max` that maps ΔE into `[0, 1]`.
pub(crate) fn max_distance(qc: f32) -> f32 {
    let green = linear_rgb_to_hunt_lab([0.0, 1.0, 0.0]);
    let blue = linear_rgb_to_hunt_lab([0.0, 0.0, 1.0]);
    hyab(green, blue).powf(qc)
}

/// Relative luminance of linear sRGB (Rec. 709 weights).
pub(crate) fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_maps_to_l100_and_the_round_trips_hold() {
        let white = linear_rgb_to_xyz([1.0; 3]);
        for i in 0..3 {
            assert!((white[i] - WHITE_D65[i]).abs() < 1e-6, "{white:?}");
            assert!((WHITE_D65[i] * INV_WHITE_D65[i] - 1.0).abs() < 1e-7);
        }
        let lab = xyz_to_lab(white);
        assert!((lab[0] - 100.0).abs() < 1e-4 && lab[1].abs() < 1e-3 && lab[2].abs() < 1e-3);
        let ycc = xyz_to_ycxcz(white);
        assert!((ycc[0] - 100.0).abs() < 1e-4 && ycc[1].abs() < 1e-3, "{ycc:?}");
        for rgb in [[0.2, 0.5, 0.9], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.7, 0.7, 0.1]] {
            let back = xyz_to_linear_rgb(ycxcz_to_xyz(xyz_to_ycxcz(linear_rgb_to_xyz(rgb))));
            for i in 0..3 {
                assert!((back[i] - rgb[i]).abs() < 1e-5, "{rgb:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn green_blue_distance_is_the_published_cmax() {
        // Green L*a*b* ≈ (87.74, −86.18, 83.18), blue ≈ (32.30, 79.19, −107.86); with the
        // Hunt factor L*/100 the HyAB distance is ≈ 203.3 and c_max = 203.3^0.7 ≈ 41.2.
        let g = xyz_to_lab(linear_rgb_to_xyz([0.0, 1.0, 0.0]));
        assert!((g[0] - 87.735).abs() < 0.01 && (g[1] + 86.18).abs() < 0.05, "{g:?}");
        let d = hyab(hunt(g), linear_rgb_to_hunt_lab([0.0, 0.0, 1.0]));
        assert!((d - 203.3).abs() < 0.2, "{d}");
        assert!((max_distance(0.7) - d.powf(0.7)).abs() < 1e-5);
    }
}
