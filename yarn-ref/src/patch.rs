//! Periodic patches and small fiber sets: a knit patch from a chart (chart → flat periodic
//! stitch mesh → Chen skeleton → `generate_fibers`, the `yarn` crate's pipeline), a
//! straight-yarn set, and explicit polylines (tests, exports), with the numbers the yarn
//! BTF needs: the period box and the reference plane `z_ref` (DESIGN §4.2).

use crate::geometry::Period;
use crate::{Error, Result};
use yarn::curve::YarnSet;
use yarn::fiber::{FiberKind, Fibers, GenOptions, generate_fibers};
use yarn::knit::{Chart, SkeletonParams, StitchMesh, chen_skeleton};
use yarn::params::YarnParams;
use yarn::vec3::V3;

/// Explicit fibers from polylines of one radius and colour (each polyline one fiber).
pub fn fibers_from_polylines(lines: &[Vec<V3>], radius: f64, color: [f32; 3]) -> Fibers {
    let mut f = Fibers { offsets: vec![0], palette: vec![color], ..Fibers::default() };
    for (k, line) in lines.iter().enumerate() {
        for p in line {
            f.points.push(p.map(|x| x as f32));
            f.radii.push(radius as f32);
            f.color_ids.push(0);
        }
        f.offsets.push(f.points.len() as u32);
        f.yarn.push(k as u32);
        f.ply.push(0);
        f.fiber.push(0);
        f.kind.push(FiberKind::Regular);
        f.params_id.push(0);
    }
    f
}

/// A periodic knit patch: its yarn curves, fibers and BTF geometry.
#[derive(Debug, Clone)]
pub struct KnitPatch {
    /// The chart.
    pub chart: Chart,
    /// Stitches `(wales, courses)` in the patch (multiples of the chart's size).
    pub stitches: [usize; 2],
    /// The yarn description.
    pub params: YarnParams,
    /// Yarn centre lines (one periodic curve per course).
    pub yarns: YarnSet,
    /// Explicit fibers.
    pub fibers: Fibers,
    /// The period box.
    pub period: Period,
    /// Reference plane: the highest centre-line point plus the yarn radius.
    pub z_ref: f64,
    /// Lowest centre-line point minus the yarn radius.
    pub z_bottom: f64,
}

/// Options of [`KnitPatch::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct PatchOptions {
    /// Stitches `(wales, courses)`; `None`: one chart repeat.
    pub stitches: Option<[usize; 2]>,
    /// Fiber generation.
    pub generation: GenOptions,
    /// Yarn colour (linear RGB).
    pub color: [f32; 3],
}

impl Default for PatchOptions {
    fn default() -> Self {
        PatchOptions {
            stitches: None,
            generation: GenOptions::default(),
            color: yarn::curve::DEFAULT_COLOR,
        }
    }
}

impl KnitPatch {
    /// Builds the patch of `chart` in yarn `params` at the skeleton's default gauge.
    pub fn new(chart: &Chart, params: &YarnParams, opts: &PatchOptions) -> Result<Self> {
        let [wales, courses] = opts.stitches.unwrap_or([chart.width, chart.height]);
        let r = params.yarn_radius();
        let mut sk = SkeletonParams::new(r);
        sk.color = opts.color;
        let (ws, cs) = sk.default_spacing();
        let mesh = StitchMesh::flat(chart, wales, courses, ws, cs)?;
        let yarns = chen_skeleton(&mesh, &sk)?;
        let period = yarns.period.ok_or_else(|| {
            Error::Unsupported(format!(
                "chart '{}': the flat patch has no rectangular period",
                chart.name
            ))
        })?;
        let fibers = generate_fibers(&yarns, std::slice::from_ref(params), &opts.generation)?;
        let (lo, hi) = centre_line_z(&yarns);
        Ok(KnitPatch {
            chart: chart.clone(),
            stitches: [wales, courses],
            params: params.clone(),
            yarns,
            fibers,
            period: Period { origin: [0.0, 0.0], size: period },
            z_ref: hi + r,
            z_bottom: lo - r,
        })
    }

    /// Where the backing plane goes: one yarn radius below the lowest tube, below every
    /// flyaway that hangs down within that.
    pub fn backing_z(&self) -> f64 {
        let low = self.fibers.points.iter().map(|p| p[2] as f64).fold(f64::INFINITY, f64::min);
        self.z_bottom.min(low) - 0.5 * self.params.yarn_radius()
    }
}

/// Lowest and highest z of the centre lines (sampled at 32 points per segment).
pub fn centre_line_z(set: &YarnSet) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for c in &set.curves {
        for p in c.sample_polyline(32) {
            lo = lo.min(p[2]);
            hi = hi.max(p[2]);
        }
    }
    (lo, hi)
}
