//! Stitch meshes ([C03 §3]'s knitwear model): a grid of loop cells `(course, wale)`, each with
//! a stitch kind from a chart, on a surface given by the 3-D positions and normals of the
//! cell corners.
//!
//! - [`StitchMesh::flat`]: a flat `W × H` patch in the `xy` plane (normal `+z`), wales along
//!   `+x`, courses along `+y`, exactly periodic with lattice vectors `(W·s_w, 0, 0)` and
//!   `(0, H·s_c, 0)`; W and H must be multiples of the chart's size so the stitches repeat
//!   too.
//! - [`StitchMesh::map_affine`]: the affine test maps of DESIGN §3.6 (stretch
//!   `diag(1+ε_u, 1+ε_v)` by [`StitchMesh::stretch`], shear `[[1, γ], [0, 1]]` by
//!   [`StitchMesh::shear`]) applied to corners and lattice vectors, so every corner lands
//!   exactly where the matrix says.
//! - [`StitchMesh::on_surface`]: the chart mapped onto a garment through its UVs: corner
//!   `(c, w)` has `uv = origin + (w·Δu, c·Δv)` and its 3-D point and normal by inverse UV
//!   lookup ([`super::uv_lookup`]). A cell with a corner that has no preimage (outside the
//!   UV chart or across a seam) is an error naming the cell and that uv (DESIGN §1.6), never
//!   skipped.
//!
//! [`StitchMesh::eval`] maps stitch coordinates `(w, c)` (real: `w = 2.5` is the middle of
//! wale 2) to a point and normal: bilinear inside a cell (Chen's key points fall inside,
//! on the edges and up to 0.35 of a cell beyond); periodic meshes wrap by the lattice,
//! others continue their boundary cells' bilinear maps (affine extrapolation).

use super::chart::{Chart, Stitch};
use super::uv_lookup::{SurfaceMesh, UvLocator};
use crate::vec3::{self, V3};
use crate::{Error, Result};

/// One loop cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StitchCell {
    /// Course (row, along the normal-to-wale direction), 0 at the bottom.
    pub course: usize,
    /// Wale (column), 0 at the left.
    pub wale: usize,
    /// The stitch.
    pub stitch: Stitch,
    /// UV of the cell centre (flat patches: `((w+½)/W, (c+½)/H)`).
    pub uv: [f64; 2],
}

/// How a chart is laid out in a surface's UV space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvLayout {
    /// UV of corner `(course 0, wale 0)`.
    pub origin: [f64; 2],
    /// UV step per wale (along u).
    pub wale_du: f64,
    /// UV step per course (along v).
    pub course_dv: f64,
    /// Wales.
    pub wales: usize,
    /// Courses.
    pub courses: usize,
}

/// A grid of loop cells on a surface (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct StitchMesh {
    /// The chart the stitches come from.
    pub chart: Chart,
    /// Courses (cell rows).
    pub courses: usize,
    /// Wales (cell columns).
    pub wales: usize,
    /// Corner positions, `(courses + 1) × (wales + 1)`, index `c·(wales+1) + w`.
    pub corners: Vec<V3>,
    /// Unit surface normals at the corners.
    pub normals: Vec<V3>,
    /// UV per corner.
    pub corner_uvs: Vec<[f64; 2]>,
    /// Cells, course-major.
    pub cells: Vec<StitchCell>,
    /// Lattice vectors of a periodic patch: one period along the wales (`wales` cells) and
    /// along the courses.
    pub lattice: Option<[V3; 2]>,
}

impl StitchMesh {
    fn cells_of(
        chart: &Chart,
        courses: usize,
        wales: usize,
        uv: impl Fn(usize, usize) -> [f64; 2],
    ) -> Vec<StitchCell> {
        (0..courses)
            .flat_map(|c| (0..wales).map(move |w| (c, w)))
            .map(|(c, w)| StitchCell {
                course: c,
                wale: w,
                stitch: chart.at(c as i64, w as i64),
                uv: uv(c, w),
            })
            .collect()
    }

    /// A flat periodic patch of `wales × courses` cells of size `wale_spacing ×
    /// course_spacing` (metres).
    pub fn flat(
        chart: &Chart,
        wales: usize,
        courses: usize,
        wale_spacing: f64,
        course_spacing: f64,
    ) -> Result<Self> {
        if wales == 0
            || courses == 0
            || !wales.is_multiple_of(chart.width)
            || !courses.is_multiple_of(chart.height)
        {
            return Err(Error::Invalid(format!(
                "a periodic patch of {wales} × {courses} cells needs positive multiples of chart \
                 '{}''s {} × {} stitches",
                chart.name, chart.width, chart.height
            )));
        }
        if !(wale_spacing > 0.0
            && course_spacing > 0.0
            && wale_spacing.is_finite()
            && course_spacing.is_finite())
        {
            return Err(Error::Invalid(format!(
                "stitch spacing {wale_spacing} × {course_spacing} m must be finite and positive"
            )));
        }
        let mut corners = Vec::with_capacity((courses + 1) * (wales + 1));
        let mut uvs = Vec::with_capacity(corners.capacity());
        for c in 0..=courses {
            for w in 0..=wales {
                corners.push([w as f64 * wale_spacing, c as f64 * course_spacing, 0.0]);
                uvs.push([w as f64 / wales as f64, c as f64 / courses as f64]);
            }
        }
        let cells = Self::cells_of(chart, courses, wales, |c, w| {
            [(w as f64 + 0.5) / wales as f64, (c as f64 + 0.5) / courses as f64]
        });
        Ok(StitchMesh {
            chart: chart.clone(),
            courses,
            wales,
            normals: vec![[0.0, 0.0, 1.0]; corners.len()],
            corners,
            corner_uvs: uvs,
            cells,
            lattice: Some([
                [wales as f64 * wale_spacing, 0.0, 0.0],
                [0.0, courses as f64 * course_spacing, 0.0],
            ]),
        })
    }

    /// Applies `x' = a·(x, y)` in the `xy` plane to corners and lattice (normals of a flat
    /// patch stay `±z`, flipped if `det a < 0`).
    pub fn map_affine(&self, a: [[f64; 2]; 2]) -> Result<Self> {
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        if !(det.is_finite() && det != 0.0) {
            return Err(Error::Invalid(format!("affine map {a:?} is singular")));
        }
        let f = |p: V3| [a[0][0] * p[0] + a[0][1] * p[1], a[1][0] * p[0] + a[1][1] * p[1], p[2]];
        let mut m = self.clone();
        m.corners = self.corners.iter().map(|&p| f(p)).collect();
        m.lattice = self.lattice.map(|l| [f(l[0]), f(l[1])]);
        if det < 0.0 {
            m.normals.iter_mut().for_each(|n| *n = vec3::scale(*n, -1.0));
        }
        Ok(m)
    }

    /// Stretch by `diag(1 + eu, 1 + ev)`.
    pub fn stretch(&self, eu: f64, ev: f64) -> Result<Self> {
        self.map_affine([[1.0 + eu, 0.0], [0.0, 1.0 + ev]])
    }

    /// Shear by `[[1, g], [0, 1]]` (courses lean along the wales).
    pub fn shear(&self, g: f64) -> Result<Self> {
        self.map_affine([[1.0, g], [0.0, 1.0]])
    }

    /// The chart laid out on `surface` through its UVs (see the module documentation).
    pub fn on_surface(surface: &SurfaceMesh, chart: &Chart, layout: &UvLayout) -> Result<Self> {
        let UvLayout { origin, wale_du, course_dv, wales, courses } = *layout;
        if wales == 0
            || courses == 0
            || !(wale_du.is_finite() && course_dv.is_finite())
            || wale_du == 0.0
            || course_dv == 0.0
        {
            return Err(Error::Invalid(format!(
                "UV layout {layout:?}: empty grid or zero/non-finite step"
            )));
        }
        if (wales + 1) * (courses + 1) > 1 << 26 {
            return Err(Error::Limit(format!(
                "UV layout of {wales} × {courses} cells is too large"
            )));
        }
        let locator = UvLocator::new(surface)?;
        let uv_of =
            |c: usize, w: usize| [origin[0] + w as f64 * wale_du, origin[1] + c as f64 * course_dv];
        let samples: Vec<Option<(V3, V3)>> = (0..=courses)
            .flat_map(|c| (0..=wales).map(move |w| (c, w)))
            .map(|(c, w)| locator.sample(uv_of(c, w)))
            .collect();
        for c in 0..courses {
            for w in 0..wales {
                for (dc, dw) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    if samples[(c + dc) * (wales + 1) + w + dw].is_none() {
                        let uv = uv_of(c + dc, w + dw);
                        return Err(Error::Invalid(format!(
                            "stitch cell (course {c}, wale {w}): its corner at uv ({:.6}, {:.6}) has \
                             no preimage on the surface (outside the UV chart or across a seam)",
                            uv[0], uv[1]
                        )));
                    }
                }
            }
        }
        let (corners, normals) = samples.into_iter().map(|s| s.expect("checked")).unzip();
        let corner_uvs = (0..=courses)
            .flat_map(|c| (0..=wales).map(move |w| (c, w)))
            .map(|(c, w)| uv_of(c, w))
            .collect();
        let cells = Self::cells_of(chart, courses, wales, |c, w| {
            [origin[0] + (w as f64 + 0.5) * wale_du, origin[1] + (c as f64 + 0.5) * course_dv]
        });
        Ok(StitchMesh {
            chart: chart.clone(),
            courses,
            wales,
            corners,
            normals,
            corner_uvs,
            cells,
            lattice: None,
        })
    }

    /// The corner `(c, w)` for any integers: wrapped by the lattice on periodic meshes.
    fn corner(&self, c: i64, w: i64) -> (V3, V3) {
        let (nc, nw) = (self.courses as i64, self.wales as i64);
        match self.lattice {
            Some(l) => {
                let (qc, rc) = (c.div_euclid(nc), c.rem_euclid(nc));
                let (qw, rw) = (w.div_euclid(nw), w.rem_euclid(nw));
                let i = rc as usize * (self.wales + 1) + rw as usize;
                let p = vec3::add_scaled(
                    vec3::add_scaled(self.corners[i], l[0], qw as f64),
                    l[1],
                    qc as f64,
                );
                (p, self.normals[i])
            }
            None => {
                let i = c.clamp(0, nc) as usize * (self.wales + 1) + w.clamp(0, nw) as usize;
                (self.corners[i], self.normals[i])
            }
        }
    }

    /// The stitch of cell `(course, wale)` for any integers (the chart wraps).
    pub fn stitch(&self, course: i64, wale: i64) -> Stitch {
        self.chart.at(course, wale)
    }

    /// The cell `(i, j)` holding stitch coordinates `(w, c)` (clamped to the mesh on an
    /// open one) and the coordinates `(s, t)` within it.
    fn cell_at(&self, w: f64, c: f64) -> (i64, i64, f64, f64) {
        let (i, j) = (w.floor() as i64, c.floor() as i64);
        let (i, j) = if self.lattice.is_some() {
            (i, j)
        } else {
            (i.clamp(0, self.wales as i64 - 1), j.clamp(0, self.courses as i64 - 1))
        };
        (i, j, w - i as f64, c - j as f64)
    }

    /// Point and unit normal at stitch coordinates `(w, c)` (see the module documentation).
    pub fn eval(&self, w: f64, c: f64) -> (V3, V3) {
        let (i, j, s, t) = self.cell_at(w, c);
        let (p00, n00) = self.corner(j, i);
        let (p10, n10) = self.corner(j, i + 1);
        let (p01, n01) = self.corner(j + 1, i);
        let (p11, n11) = self.corner(j + 1, i + 1);
        let bl = |a: V3, b: V3, cc: V3, d: V3| {
            vec3::add(
                vec3::lerp(a, b, s),
                vec3::scale(vec3::sub(vec3::lerp(cc, d, s), vec3::lerp(a, b, s)), t),
            )
        };
        let p = bl(p00, p10, p01, p11);
        let n = vec3::normalize_or(bl(n00, n10, n01, n11), n00);
        (p, n)
    }

    /// The derivatives `(∂x/∂w, ∂x/∂c)` of the bilinear map [`Self::eval`] at stitch
    /// coordinates `(w, c)` (the cell that `eval` uses there).
    pub fn derivatives(&self, w: f64, c: f64) -> (V3, V3) {
        let (i, j, s, t) = self.cell_at(w, c);
        let p00 = self.corner(j, i).0;
        let p10 = self.corner(j, i + 1).0;
        let p01 = self.corner(j + 1, i).0;
        let p11 = self.corner(j + 1, i + 1).0;
        let dw = vec3::lerp(vec3::sub(p10, p00), vec3::sub(p11, p01), t);
        let dc = vec3::lerp(vec3::sub(p01, p00), vec3::sub(p11, p10), s);
        (dw, dc)
    }
}

#[cfg(test)]
mod tests;
