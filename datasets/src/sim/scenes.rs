//! The two scarf scenes of Chen et al. 2003 Fig. 13, run with [`super::knit::KnitSim`] and
//! recorded at 25 fps with per-frame step reports:
//!
//! - [`ScarfDrop`]: a scarf falls flat (tilted by a few degrees) onto a table (a box, with
//!   a third of the scarf over the edge) or a body proxy (a horizontal capsule, an "arm",
//!   or a ball), [C03 Fig. 13 top: "approximately 15000 triangles", 40 s at 25 fps];
//! - [`ScarfStretch`]: both end courses are pinned and pulled apart along the scarf, held,
//!   then released and the scarf springs back under gravity
//!   [C03 Fig. 13 bottom: "about 11000 triangles", 3 s].
//!
//! [`ScarfSize::FULL`] is 250 courses × 30 wales = 15 000 triangles (1.25 m × 0.18 m with
//! the default 5 × 6 mm loops); tests use a few loops. The scarf runs along `+x` (its
//! wales), across along `+y` (its courses), normal `+z`, world z-up. Frames hold raw
//! positions; [`SceneRun::smoothed`] applies the render-only filter of [`super::smooth`].

use super::Collider;
use super::knit::{KnitSim, KnitSimParams, LoopGrid, flat_positions};
use super::shapes::Shape;
use super::smooth::moving_average;
use super::step::AdvanceReport;
use crate::vec3::V3;
use crate::{Error, Result};

/// The scarf's loop grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScarfSize(pub LoopGrid);

impl ScarfSize {
    /// 250 courses × 30 wales: 15 000 triangles, as the paper's falling scarf.
    pub const FULL: ScarfSize = ScarfSize(LoopGrid { courses: 250, wales: 30 });

    /// The smallest grid with about `triangles` triangles at the full size's aspect ratio
    /// (at least 2 × 2 loops).
    pub fn with_triangles(triangles: usize) -> ScarfSize {
        let loops = (triangles / 2).max(4) as f64;
        let wales = (loops * 30.0 / 250.0).sqrt().round().max(2.0) as usize;
        let courses = ((loops / wales as f64).round() as usize).max(2);
        ScarfSize(LoopGrid { courses, wales })
    }
}

/// What the dropped scarf lands on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DropTarget {
    /// A table top (box) with a third of the scarf over its edge.
    Table,
    /// A horizontal capsule across the scarf's middle (an arm or a shoulder).
    Arm,
    /// A ball under the scarf's middle.
    Ball,
}

/// Recording settings shared by both scenes.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Simulated length (s).
    pub seconds: f64,
    /// Frames per second (25 in the paper).
    pub fps: f64,
    /// Steps allowed per frame before the run is declared stuck.
    pub max_steps_per_frame: usize,
}

impl Default for Recording {
    fn default() -> Self {
        Recording { seconds: 3.0, fps: 25.0, max_steps_per_frame: 200_000 }
    }
}

/// One recorded frame.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFrame {
    /// Simulated time of the frame (s).
    pub time_s: f64,
    /// Node positions in the `StitchMesh::corners` order (m).
    pub positions: Vec<V3>,
    /// Steps, halvings and wall time since the previous frame.
    pub report: AdvanceReport,
}

/// A recorded scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneRun {
    /// The loop grid (nodes `(courses+1)·(wales+1)`).
    pub grid: LoopGrid,
    /// Two triangles per loop.
    pub triangles: Vec<[u32; 3]>,
    /// The colliders of the scene.
    pub colliders: Vec<Shape>,
    /// Frame 0 is the initial state, then one per `1/fps`.
    pub frames: Vec<SceneFrame>,
}

impl SceneRun {
    /// Positions for rendering: the window-3 moving average over frames.
    pub fn smoothed(&self) -> Result<Vec<Vec<V3>>> {
        let raw: Vec<Vec<V3>> = self.frames.iter().map(|f| f.positions.clone()).collect();
        moving_average(&raw)
    }

    /// Total steps over the run.
    pub fn steps(&self) -> usize {
        self.frames.iter().map(|f| f.report.steps).sum()
    }

    /// Total halvings over the run.
    pub fn halvings(&self) -> usize {
        self.frames.iter().map(|f| f.report.halvings).sum()
    }
}

fn check_recording(r: &Recording) -> Result<usize> {
    if !(r.fps.is_finite() && r.fps > 0.0 && r.seconds.is_finite() && r.seconds >= 0.0) {
        return Err(Error::Invalid(format!(
            "scene: {} s at {} fps must be finite, the rate positive",
            r.seconds, r.fps
        )));
    }
    let frames = (r.seconds * r.fps).round() as usize;
    if frames > 1_000_000 {
        return Err(Error::Invalid(format!("scene: {frames} frames are too many")));
    }
    Ok(frames)
}

fn frame0(sim: &KnitSim<'_>) -> SceneFrame {
    SceneFrame {
        time_s: 0.0,
        positions: sim.positions().to_vec(),
        report: AdvanceReport::default(),
    }
}

/// A scarf dropped onto a table or a body proxy.
#[derive(Debug, Clone, PartialEq)]
pub struct ScarfDrop {
    /// The loop grid.
    pub size: ScarfSize,
    /// What it falls on.
    pub target: DropTarget,
    /// Height of the scarf's centre above the target's top at the start (m).
    pub height_m: f64,
    /// Tilt about the scarf's long axis and across it (degrees), so it does not land flat.
    pub tilt_deg: [f64; 2],
    /// Knit constants.
    pub knit: KnitSimParams,
    /// Length and frame rate.
    pub recording: Recording,
}

impl ScarfDrop {
    /// The scene at `size` onto `target`, 5 cm above it, tilted by 4° and 3°.
    pub fn new(size: ScarfSize, target: DropTarget) -> Self {
        ScarfDrop {
            size,
            target,
            height_m: 0.05,
            tilt_deg: [4.0, 3.0],
            knit: KnitSimParams::default(),
            recording: Recording::default(),
        }
    }

    fn extent(&self) -> (f64, f64) {
        let g = self.size.0;
        (g.courses as f64 * self.knit.course_spacing_m, g.wales as f64 * self.knit.wale_spacing_m)
    }

    /// The collider; its top is at `z = 0`, the scarf's centre above `x = y = 0`.
    pub fn collider(&self) -> Shape {
        let (len, width) = self.extent();
        match self.target {
            // The edge is at x = len/6, so a third of the scarf hangs over it.
            DropTarget::Table => Shape::Box {
                min: [-len - 0.5, -width - 0.5, -0.75],
                max: [len / 6.0, width + 0.5, 0.0],
            },
            DropTarget::Arm => {
                let r = 0.05;
                let half = width + 0.2;
                Shape::Capsule { a: [0.0, -half, -r], b: [0.0, half, -r], radius: r }
            }
            DropTarget::Ball => {
                let r = (0.25 * len).clamp(0.02, 0.12);
                Shape::Sphere { centre: [0.0, 0.0, -r], radius: r }
            }
        }
    }

    /// Initial corner positions: the flat scarf, tilted, centred above the origin.
    pub fn initial_positions(&self) -> Result<Vec<V3>> {
        if !(self.height_m.is_finite() && self.height_m > 0.0) {
            return Err(Error::Invalid(format!(
                "scarf drop: height {} m must be > 0",
                self.height_m
            )));
        }
        let (len, width) = self.extent();
        let [a, b] = self.tilt_deg.map(f64::to_radians);
        if !(a.abs() < 1.0 && b.abs() < 1.0) {
            return Err(Error::Invalid(format!(
                "scarf drop: tilts {:?}° must be below 57°",
                self.tilt_deg
            )));
        }
        // Along the scarf: x tilted by b about y; across: y tilted by a about x.
        let along = [b.cos(), 0.0, b.sin()];
        let across = [0.0, a.cos(), a.sin()];
        let origin = [0, 1, 2].map(|k| -0.5 * len * along[k] - 0.5 * width * across[k]);
        let origin = [origin[0], origin[1], origin[2] + self.height_m];
        flat_positions(self.size.0, &self.knit, origin, across, along)
    }

    /// Runs the scene and records every frame.
    pub fn run(&self) -> Result<SceneRun> {
        let frames = check_recording(&self.recording)?;
        let shape = self.collider().validated()?;
        let mut sim = KnitSim::new(
            self.size.0,
            self.initial_positions()?,
            &self.knit,
            Some(&shape as &dyn Collider),
        )?;
        let mut out = vec![frame0(&sim)];
        for k in 1..=frames {
            let t = k as f64 / self.recording.fps;
            let report = sim.sim.advance_to(t, self.recording.max_steps_per_frame)?;
            out.push(SceneFrame { time_s: t, positions: sim.positions().to_vec(), report });
        }
        Ok(SceneRun {
            grid: sim.grid,
            triangles: sim.sim.cloth.triangles.clone(),
            colliders: vec![shape],
            frames: out,
        })
    }
}

/// A scarf whose end courses are pulled apart, held and released.
#[derive(Debug, Clone, PartialEq)]
pub struct ScarfStretch {
    /// The loop grid.
    pub size: ScarfSize,
    /// Extra length at the end of the pull, as a fraction of the rest length.
    pub stretch: f64,
    /// Duration of the pull (s).
    pub pull_s: f64,
    /// Duration of the hold before the release (s).
    pub hold_s: f64,
    /// Knit constants.
    pub knit: KnitSimParams,
    /// Length and frame rate.
    pub recording: Recording,
}

impl ScarfStretch {
    /// The scene at `size`: stretched by 30 % over 0.6 s, held 0.2 s, 3 s in all.
    pub fn new(size: ScarfSize) -> Self {
        ScarfStretch {
            size,
            stretch: 0.3,
            pull_s: 0.6,
            hold_s: 0.2,
            knit: KnitSimParams::default(),
            recording: Recording::default(),
        }
    }

    /// Runs the scene and records every frame (no collider: the scarf is in the air).
    pub fn run(&self) -> Result<SceneRun> {
        let frames = check_recording(&self.recording)?;
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !(ok(self.stretch) && self.stretch < 2.0 && ok(self.pull_s) && ok(self.hold_s)) {
            return Err(Error::Invalid(format!(
                "scarf stretch: stretch {} (< 2), pull {} s and hold {} s must be finite and ≥ 0",
                self.stretch, self.pull_s, self.hold_s
            )));
        }
        let g = self.size.0;
        let len = g.courses as f64 * self.knit.course_spacing_m;
        let width = g.wales as f64 * self.knit.wale_spacing_m;
        let x0 = flat_positions(
            g,
            &self.knit,
            [-0.5 * len, -0.5 * width, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
        )?;
        let mut sim = KnitSim::new(g, x0, &self.knit, None)?;
        let speed = if self.pull_s > 0.0 { 0.5 * self.stretch * len / self.pull_s } else { 0.0 };
        sim.pin_course(0, true, [-speed, 0.0, 0.0]);
        sim.pin_course(g.courses, true, [speed, 0.0, 0.0]);
        let mut out = vec![frame0(&sim)];
        let (pull_end, release) = (self.pull_s, self.pull_s + self.hold_s);
        let mut phase = 0;
        for k in 1..=frames {
            let t = k as f64 / self.recording.fps;
            let mut report = AdvanceReport::default();
            // Phase changes land exactly on their times, inside the frame if need be.
            for (edge, next) in [(pull_end, 1), (release, 2)] {
                if phase < next && edge <= t {
                    let r = sim.sim.advance_to(edge, self.recording.max_steps_per_frame)?;
                    add_report(&mut report, &r);
                    phase = next;
                    // After the pull the ends hold still; at the release they are freed.
                    let pinned = next == 1;
                    sim.pin_course(0, pinned, [0.0; 3]);
                    sim.pin_course(g.courses, pinned, [0.0; 3]);
                }
            }
            let r = sim.sim.advance_to(t, self.recording.max_steps_per_frame)?;
            add_report(&mut report, &r);
            out.push(SceneFrame { time_s: t, positions: sim.positions().to_vec(), report });
        }
        Ok(SceneRun {
            grid: g,
            triangles: sim.sim.cloth.triangles.clone(),
            colliders: Vec::new(),
            frames: out,
        })
    }
}

fn add_report(total: &mut AdvanceReport, r: &AdvanceReport) {
    total.steps += r.steps;
    total.halvings += r.halvings;
    total.projected += r.projected;
    total.force_evaluations += r.force_evaluations;
    total.wall_ms += r.wall_ms;
}
