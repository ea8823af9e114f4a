//! The contact-relaxed stitch templates as the knot model's rest (DESIGN §3.3 item 1):
//! a rest *detail* layer on top of [H25 eq. 1–2]'s knots.
//!
//! **Why a layer and not the rest itself.** DESIGN §3.3 item 1 asks for the templates to
//! be relaxed once with the eq. 5–6 energies plus a yarn–yarn contact penalty and for the
//! result to be the rest `x₀`. [`super::relax`] computes that relaxation (it lifts the flat
//! stockinette's clearance from 0.88 to 0.996 × 2r), but the relaxed CPs are not in the
//! knots' family: between a crossing contact (`±h` along the normal) and the side points
//! (`2r` apart in the face plane) eq. 1–2 fix the chords `√2 r` apart at `h = r` (the
//! module documentation of [`super`]), while the relaxation moves every CP freely. Taken
//! as the rest of eq. 5–6, `x₀` would not be a fixed point of the solve (the rest mesh's
//! initial guess is the template, not `x₀`, and no `Θ` reaches `x₀`) — the design is wrong
//! there, and we do this instead:
//!
//! - the knot solve keeps the template as its rest (so the rest mesh stays an exact fixed
//!   point, [H25 eq. 4] holds by construction and every solver test is unchanged);
//! - the relaxation's displacement of every CP from the template, `δᵢ = x₀ᵢ − x̄ᵢ`, is
//!   stored in the CP's local frame on the flat rest patch and added after each solve in
//!   the CP's frame on the deformed mesh: `xᵢ ← xᵢ + δᵢ·t tᵢ + δᵢ·u uᵢ + δᵢ·n nᵢ`, where
//!   `nᵢ` is the CP's surface normal (the one the solve placed it with), `tᵢ` the face map's
//!   `∂x/∂w` at the CP's rest stitch coordinates made ⟂ `nᵢ`, and `uᵢ = ±nᵢ × tᵢ` with the
//!   sign of `∂x/∂c` (a mirrored layout mirrors the detail as it mirrors the knots).
//!
//! The frame is orthonormal: the detail is a yarn-scale correction (where two yarns touch)
//! and is carried rigidly, not stretched with the stitch — a 50 % stretch moves the
//! crossing points apart through the knots, it does not make the yarn's cross-section
//! wider. Consequences, tested in `detail_tests.rs`: on the rest mesh the solve plus the
//! detail is the relaxed template to rounding; a rigid motion of the mesh moves the result
//! rigidly; the detail never changes the solve (energies, `Θ`, guard counts are those of
//! the knots alone). Measured (BENCHMARKS.md): it lifts the clearance under the analytic
//! stretch and shear maps (0.845 → 0.936 × 2r at 30 % shear) but *lowers* it on the draped
//! cloth (stockinette 0.69–0.71 → 0.60–0.62), where bent and compressed stitches meet the
//! displacements relaxed for a flat one — so the commands take it only when asked
//! (`--relaxed-rest`).
//!
//! **Where it comes from.** The relaxation runs once on a flat periodic patch of the
//! chart (the smallest multiple of the chart's repeat with at least 4 × 4 stitches, so
//! that every contact's lattice images are distinct yarns) at the model's gauge, and every
//! CP of the model takes the detail of the CP with the same skeleton key in the patch's
//! cell `(course mod P_c, loop mod P_w)` — the chart repeats, so the stitches agree. On an
//! open mesh the bottom course (no loop below, no knots) and the top course (no loop
//! above) take their key's detail too: the contact it was relaxed for is missing there,
//! and the displacement is at most [`RestDetail::max_offset_over_r`].

use super::{ContactParams, KnotFrame, KnotModel, KnotParams, RelaxStats};
use crate::knit::stitch_mesh::StitchMesh;
use crate::vec3::{self, V3};
use crate::{Error, Result};
use rayon::prelude::*;
use std::collections::HashMap;

/// Stitches of the relaxation patch per direction at least.
const MIN_PATCH: usize = 4;

/// The rest detail of a [`KnotModel`] (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct RestDetail {
    /// Per CP of the model: the relaxed template's displacement in the CP's local frame
    /// `(t, u, n)` (metres).
    offsets: Vec<V3>,
    /// The relaxation patch, `(wales, courses)` stitches.
    pub patch: (usize, usize),
    /// What the relaxation of the patch did (clearance before and after, steps, seconds).
    pub stats: RelaxStats,
    r: f64,
}

/// The orthonormal frame `(t, u, n)` of CP `i` on `mesh` with normal `n` (see the module
/// documentation); `None` where the face map is degenerate there.
fn local_frame(model: &KnotModel, mesh: &StitchMesh, i: usize, n: V3) -> Option<[V3; 3]> {
    let p = model.rest().points[i];
    let (sw, sc) = model.spacing();
    let (dw, dc) = mesh.derivatives(p[0] / sw, p[1] / sc);
    let n = vec3::normalize(n)?;
    let t = vec3::normalize(vec3::reject(dw, n))?;
    let u = vec3::cross(n, t);
    let side = vec3::dot(dc, u);
    if side == 0.0 || side.is_nan() {
        return None;
    }
    Some([t, if side > 0.0 { u } else { vec3::scale(u, -1.0) }, n])
}

impl RestDetail {
    /// Relaxes the chart's template on a flat periodic patch at `model`'s gauge with the
    /// eq. 5–6 weights of `p` and the contact of `c` ([`KnotModel::relaxed_rest`]) and
    /// assigns every CP of `model` its detail. `mesh` is any stitch mesh of the model (its
    /// chart gives the stitches).
    pub fn relax(
        model: &KnotModel,
        mesh: &StitchMesh,
        p: &KnotParams,
        c: &ContactParams,
    ) -> Result<Self> {
        let chart = &mesh.chart;
        let patch_of = |repeat: usize| repeat * MIN_PATCH.div_ceil(repeat.max(1));
        let (pw, pc) = (patch_of(chart.width), patch_of(chart.height));
        let (sw, sc) = model.spacing();
        let patch_mesh = StitchMesh::flat(chart, pw, pc, sw, sc)?;
        let patch = KnotModel::new(&patch_mesh, model.skeleton(), (sw, sc))?;
        let (relaxed, stats) = patch.relaxed_rest(p, c)?;
        let mut local = Vec::with_capacity(patch.cp_count());
        for i in 0..patch.cp_count() {
            let frame =
                local_frame(&patch, &patch_mesh, i, patch.rest().normals[i]).ok_or_else(|| {
                    Error::Invalid(format!("rest detail: CP {i} of the flat patch has no frame"))
                })?;
            let d = vec3::sub(relaxed.points[i], patch.rest().points[i]);
            local.push(frame.map(|e| vec3::dot(d, e)));
        }
        let by_key: HashMap<[u32; 3], usize> =
            (0..patch.cp_count()).map(|i| (patch.cp_cell(i), i)).collect();
        let offsets = (0..model.cp_count())
            .map(|i| {
                let [cc, w, k] = model.cp_cell(i);
                let key = [cc % pc as u32, w % pw as u32, k];
                by_key.get(&key).map(|&j| local[j]).ok_or_else(|| {
                    Error::Invalid(format!(
                        "rest detail: CP {i} (course {cc}, loop {w}, key {k}) has no counterpart \
                         in the {pw} × {pc} relaxation patch of chart '{}'",
                        chart.name
                    ))
                })
            })
            .collect::<Result<Vec<V3>>>()?;
        Ok(RestDetail { offsets, patch: (pw, pc), stats, r: model.radius() })
    }

    /// The detail of every CP in its local frame `(t, u, n)` (metres).
    pub fn offsets(&self) -> &[V3] {
        &self.offsets
    }

    /// The largest detail displacement / r.
    pub fn max_offset_over_r(&self) -> f64 {
        self.offsets.iter().map(|d| vec3::length(*d)).fold(0.0, f64::max) / self.r
    }

    /// `frame` (a solve of `model` on `mesh`) with every CP moved by its detail in its
    /// frame on `mesh`; normals, `Θ`, statistics and lattice unchanged. The error names
    /// the CP where the face map is degenerate.
    pub fn apply(
        &self,
        model: &KnotModel,
        mesh: &StitchMesh,
        frame: &KnotFrame,
    ) -> Result<KnotFrame> {
        if self.offsets.len() != model.cp_count() || frame.points.len() != model.cp_count() {
            return Err(Error::Invalid(format!(
                "rest detail of {} CPs applied to a model of {} and a frame of {}",
                self.offsets.len(),
                model.cp_count(),
                frame.points.len()
            )));
        }
        let points = (0..model.cp_count())
            .into_par_iter()
            .map(|i| {
                let d = self.offsets[i];
                let [t, u, n] = local_frame(model, mesh, i, frame.normals[i]).ok_or_else(|| {
                    let [c, w, k] = model.cp_cell(i);
                    Error::Invalid(format!(
                        "rest detail: CP {i} (course {c}, loop {w}, key {k}): the stitch face \
                         map has no tangent frame there (normal {:?})",
                        frame.normals[i]
                    ))
                })?;
                let mut q = frame.points[i];
                for (e, s) in [(t, d[0]), (u, d[1]), (n, d[2])] {
                    q = vec3::add_scaled(q, e, s);
                }
                Ok(q)
            })
            .collect::<Result<Vec<V3>>>()?;
        Ok(KnotFrame { points, ..frame.clone() })
    }
}
