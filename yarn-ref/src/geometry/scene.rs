//! `FiberScene`: the explicit fibers of a [`yarn::fiber::Fibers`] as capsule chains in one
//! BVH, with closest-hit and any-hit (shadow) queries, the periodic wrap of a patch and an
//! optional opaque black backing plane.
//!
//! **Capsules.** Fiber `k`'s polyline points `p_i` give segments `[p_i, p_{i+1}]` of radius
//! `max(r_i, r_{i+1})`; a one-point fiber is a ball. Points must be finite and radii finite
//! and ≥ 0 (a zero radius never hits: `r_f → 0` makes fibers vanish, DESIGN §4.4).
//!
//! **Periodic wrap** (DESIGN §4.2: the reference tracer wraps ray coordinates modulo the
//! period). The scene holds every capsule of the infinite tiling `x + (i P_x, j P_y)` that
//! overlaps the period box `[x0, x0 + P_x) × [y0, y0 + P_y)` (the originals and the
//! translated copies of those crossing the box's walls). A ray is moved into the box
//! (its tile recorded), first advanced to the slab `z ∈ [z_min, z_max]` of the geometry,
//! then queried up to the box wall it leaves through; without a hit it re-enters through
//! the opposite wall, until it hits, leaves the slab or reaches `t_max`. This is exactly
//! the infinite tiling without instancing. Hits are reported in box coordinates with the
//! tile shift, so a point light keeps its one position in the world (`world = box + shift·P`).
//! A ray that stays inside the slab for more than [`MAX_TILES`] walls (a ray parallel to
//! the patch) is taken to escape.
//!
//! **Backing.** An opaque plane at `z = z_back` ends every ray that reaches it; the
//! renderer gives it albedo 0 (DESIGN §4.2's black holder) and counts the camera rays that
//! reach it (the patch's direct transmittance).
//!
//! **Self-intersection** (see [`super::capsule`]): a ray spawned inside a capsule never
//! hits that capsule; [`Skip`] also ignores the segments of the leaving fiber within two
//! points of the scattering point, which a ray spawned on the axis of a smoothly bent fiber
//! could otherwise enter at a joint.

use super::bvh::{Aabb, Bvh, SlabRay};
use super::capsule::entry;
use crate::{Error, Result};
use yarn::fiber::Fibers;
use yarn::vec3::{self, V3};

/// Walls a ray may cross inside the slab before it is taken to escape.
pub const MAX_TILES: usize = 1 << 12;

/// One capsule (32 bytes).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Segment {
    /// Start (metres; translated for periodic copies).
    pub a: [f32; 3],
    /// End.
    pub b: [f32; 3],
    /// Radius.
    pub radius: f32,
    /// Index of `a` in the fiber points (the segment joins points `point` and `point + 1`,
    /// or is the ball of a one-point fiber).
    pub point: u32,
}

/// The period box of a patch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Period {
    /// Lower corner `(x0, y0)` (metres).
    pub origin: [f64; 2],
    /// `(P_x, P_y)` (metres).
    pub size: [f64; 2],
}

/// How to build a scene.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SceneOptions {
    /// Wrap periodically (`None`: no wrap; the fibers' own period is not used unless given).
    pub period: Option<Period>,
    /// Height of an opaque black backing plane, if any.
    pub backing_z: Option<f64>,
}

/// Which fiber segments a ray spawned on a fiber ignores.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Skip {
    /// Fiber index.
    pub fiber: u32,
    /// Point index of the scattering segment's start.
    pub point: u32,
}

/// What a ray hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HitKind {
    /// A fiber segment at segment parameter `v`.
    Fiber {
        /// Segment index.
        segment: u32,
        /// Position along the segment, `[0, 1]`.
        v: f64,
    },
    /// The backing plane.
    Backing,
}

/// A hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray distance.
    pub t: f64,
    /// Hit point in box coordinates (world coordinates without a period).
    pub position: V3,
    /// Tiles crossed: the world point is `position + shift·P`.
    pub shift: [i64; 2],
    /// Fiber or backing.
    pub kind: HitKind,
}

/// Local geometry of a fiber hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The point on the segment axis (where the fiber BCSDF scatters).
    pub axis_point: V3,
    /// Outward unit normal of the capsule at the hit (Lambert shading).
    pub normal: V3,
    /// Unit fiber tangent, interpolated between the polyline's vertex tangents.
    pub tangent: V3,
    /// Fiber index.
    pub fiber: u32,
    /// Linear RGB colour of the fiber there.
    pub color: [f32; 3],
    /// Capsule radius.
    pub radius: f64,
    /// Skip rule for rays leaving this point along the fiber.
    pub skip: Skip,
}

/// Explicit fibers ready for ray queries (see the module documentation).
#[derive(Debug, Clone)]
pub struct FiberScene {
    segments: Vec<Segment>,
    bvh: Bvh,
    points: Vec<[f32; 3]>,
    point_fiber: Vec<u32>,
    point_color: Vec<u32>,
    offsets: Vec<u32>,
    palette: Vec<[f32; 3]>,
    period: Option<Period>,
    z_range: [f64; 2],
    backing_z: Option<f64>,
    original_segments: usize,
}

impl FiberScene {
    /// Builds the scene of `fibers` (checked: finite points, finite radii ≥ 0, consistent
    /// offsets and colours; the error names the fiber and point).
    pub fn new(fibers: &Fibers, opts: &SceneOptions) -> Result<Self> {
        let n_fib = fibers.fiber_count();
        let n_pts = fibers.points.len();
        if fibers.offsets.first().copied().unwrap_or(0) != 0
            || fibers.offsets.last().copied().unwrap_or(0) as usize != n_pts
            || fibers.offsets.windows(2).any(|w| w[1] < w[0])
            || fibers.radii.len() != n_pts
            || fibers.color_ids.len() != n_pts
        {
            return Err(Error::Invalid(format!(
                "fibers: {} offsets, {} radii and {} colour ids do not index {} points",
                fibers.offsets.len(),
                fibers.radii.len(),
                fibers.color_ids.len(),
                n_pts
            )));
        }
        if n_pts >= u32::MAX as usize / 2 {
            return Err(Error::Limit(format!("{n_pts} fiber points (at most 2^31)")));
        }
        if let Some(p) = opts.period
            && !(p.size.iter().all(|s| *s > 0.0 && s.is_finite())
                && p.origin.iter().all(|o| o.is_finite()))
        {
            return Err(Error::Invalid(format!("period box {p:?} must be finite and positive")));
        }
        let mut point_fiber = vec![0u32; n_pts];
        let mut segments = Vec::with_capacity(n_pts);
        for k in 0..n_fib {
            let (s, e) = (fibers.offsets[k] as usize, fibers.offsets[k + 1] as usize);
            for i in s..e {
                point_fiber[i] = k as u32;
                let (p, r) = (fibers.points[i], fibers.radii[i]);
                if !(p.iter().all(|x| x.is_finite()) && r.is_finite() && r >= 0.0) {
                    return Err(Error::Invalid(format!(
                        "fiber {k} (curve {}), point {}: position {p:?}, radius {r} (finite \
                         coordinates and a finite radius ≥ 0 expected)",
                        fibers.yarn.get(k).copied().unwrap_or(0),
                        i - s
                    )));
                }
                if let Some(c) = fibers.color_ids.get(i)
                    && *c as usize >= fibers.palette.len().max(1)
                {
                    return Err(Error::Invalid(format!(
                        "fiber {k}, point {}: colour id {c} beyond the palette of {}",
                        i - s,
                        fibers.palette.len()
                    )));
                }
            }
            if e == s + 1 {
                segments.push(Segment {
                    a: fibers.points[s],
                    b: fibers.points[s],
                    radius: fibers.radii[s],
                    point: s as u32,
                });
            }
            for i in s..e.saturating_sub(1) {
                let radius = fibers.radii[i].max(fibers.radii[i + 1]);
                if radius > 0.0 {
                    segments.push(Segment {
                        a: fibers.points[i],
                        b: fibers.points[i + 1],
                        radius,
                        point: i as u32,
                    });
                }
            }
        }
        let original_segments = segments.len();
        if let Some(p) = opts.period {
            segments = wrap_copies(&segments, &p);
        }
        let boxes: Vec<Aabb> = segments.iter().map(seg_box).collect();
        let bvh = Bvh::build(&boxes);
        let b = bvh.bounds();
        let z_range =
            if segments.is_empty() { [0.0, 0.0] } else { [b.min[2] as f64, b.max[2] as f64] };
        let palette = if fibers.palette.is_empty() {
            vec![yarn::curve::DEFAULT_COLOR]
        } else {
            fibers.palette.clone()
        };
        Ok(FiberScene {
            segments,
            bvh,
            points: fibers.points.clone(),
            point_fiber,
            point_color: fibers.color_ids.clone(),
            offsets: fibers.offsets.clone(),
            palette,
            period: opts.period,
            z_range,
            backing_z: opts.backing_z,
            original_segments,
        })
    }

    /// Number of capsules, periodic copies included.
    pub fn segment_count(&self) -> usize {
        self.segments.len()
    }

    /// Capsules before the periodic copies were added.
    pub fn original_segment_count(&self) -> usize {
        self.original_segments
    }

    /// Number of fibers.
    pub fn fiber_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Bytes held by capsules, the BVH and the per-point tables.
    pub fn bytes(&self) -> usize {
        self.segments.len() * std::mem::size_of::<Segment>()
            + self.bvh.bytes()
            + self.points.len() * (12 + 4 + 4)
            + self.offsets.len() * 4
    }

    /// The BVH.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// `[z_min, z_max]` of the capsules.
    pub fn z_range(&self) -> [f64; 2] {
        self.z_range
    }

    /// The period box, if wrapped.
    pub fn period(&self) -> Option<Period> {
        self.period
    }

    /// The backing plane height.
    pub fn backing_z(&self) -> Option<f64> {
        self.backing_z
    }

    /// The bounds of all capsules.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    /// Closest hit of the ray `o + t·d` (`d` unit), `0 < t < t_max`.
    pub fn intersect(&self, o: V3, d: V3, t_max: f64, skip: Option<Skip>) -> Option<Hit> {
        let r = self.walk(o, d, t_max, |p, tm| self.query_closest(p, d, tm, skip));
        match r {
            Walk::Hit((seg, v), t, shift, p) => Some(Hit {
                t: t.0 + t.1,
                position: vec3::add_scaled(p, d, t.1),
                shift,
                kind: HitKind::Fiber { segment: seg, v },
            }),
            Walk::Backing(t) => {
                let (position, shift) = self.canonical(vec3::add_scaled(o, d, t));
                Some(Hit { t, position, shift, kind: HitKind::Backing })
            }
            Walk::Escaped => None,
        }
    }

    /// True if anything (fiber or backing) lies on the ray within `0 < t < t_max`.
    pub fn occluded(&self, o: V3, d: V3, t_max: f64, skip: Option<Skip>) -> bool {
        let r = self
            .walk(o, d, t_max, |p, tm| self.query_any(p, d, tm, skip).then_some(((0, 0.0), 0.0)));
        !matches!(r, Walk::Escaped)
    }

    /// A point moved into the period box, and the tiles it moved by.
    pub fn canonical(&self, p: V3) -> (V3, [i64; 2]) {
        let Some(per) = self.period else { return (p, [0, 0]) };
        let mut q = p;
        let mut shift = [0i64; 2];
        for k in 0..2 {
            let f = ((p[k] - per.origin[k]) / per.size[k]).floor();
            shift[k] = f as i64;
            q[k] = p[k] - f * per.size[k];
            // Rounding may land exactly on the upper wall; keep the half-open box.
            if q[k] >= per.origin[k] + per.size[k] {
                q[k] -= per.size[k];
                shift[k] += 1;
            }
            q[k] = q[k].max(per.origin[k]);
        }
        (q, shift)
    }

    /// The world position of a box point with its tile shift.
    pub fn world(&self, p: V3, shift: [i64; 2]) -> V3 {
        match self.period {
            Some(per) => {
                [p[0] + shift[0] as f64 * per.size[0], p[1] + shift[1] as f64 * per.size[1], p[2]]
            }
            None => p,
        }
    }

    /// The local geometry at a fiber hit.
    pub fn surface(&self, segment: u32, v: f64, position: V3) -> SurfacePoint {
        let s = &self.segments[segment as usize];
        let a = s.a.map(f64::from);
        let b = s.b.map(f64::from);
        let axis_point = vec3::add_scaled(a, vec3::sub(b, a), v);
        let i = s.point as usize;
        let fiber = self.point_fiber[i];
        let seg_dir = vec3::normalize(vec3::sub(b, a));
        let t0 = self.vertex_tangent(i);
        let t1 = self.vertex_tangent(i + 1).or(t0);
        let tangent = match (t0, t1) {
            (Some(x), Some(y)) => {
                vec3::normalize(vec3::add(vec3::scale(x, 1.0 - v), vec3::scale(y, v)))
            }
            _ => None,
        }
        .or(seg_dir)
        .unwrap_or([1.0, 0.0, 0.0]);
        let normal = vec3::normalize(vec3::sub(position, axis_point))
            .unwrap_or_else(|| perpendicular(tangent));
        let color = self.palette[self.point_color[i] as usize];
        SurfacePoint {
            axis_point,
            normal,
            tangent,
            fiber,
            color,
            radius: s.radius as f64,
            skip: Skip { fiber, point: s.point },
        }
    }

    /// Unit tangent at point `i` of its fiber (central difference; one-sided at the ends).
    fn vertex_tangent(&self, i: usize) -> Option<V3> {
        let f = *self.point_fiber.get(i)? as usize;
        let (s, e) = (self.offsets[f] as usize, self.offsets[f + 1] as usize);
        if e - s < 2 {
            return None;
        }
        let (lo, hi) = (i.saturating_sub(1).max(s), (i + 1).min(e - 1));
        let d = vec3::sub(self.points[hi].map(f64::from), self.points[lo].map(f64::from));
        vec3::normalize(d)
    }

    fn skipped(&self, seg: &Segment, skip: Option<Skip>) -> bool {
        skip.is_some_and(|s| {
            self.point_fiber[seg.point as usize] == s.fiber && seg.point.abs_diff(s.point) <= 2
        })
    }

    fn query_closest(
        &self,
        o: V3,
        d: V3,
        t_max: f64,
        skip: Option<Skip>,
    ) -> Option<((u32, f64), f64)> {
        let ray = SlabRay::new(o, d);
        let mut best_v = 0.0;
        let hit = self.bvh.closest(&ray, t_max, |p, tm| {
            let s = &self.segments[p as usize];
            if self.skipped(s, skip) {
                return None;
            }
            let h = entry(s.a.map(f64::from), s.b.map(f64::from), s.radius as f64, o, d, 0.0, tm)?;
            best_v = h.v;
            Some(h.t)
        })?;
        // `best_v` belongs to the last accepted hit, which is the closest.
        Some(((hit.0, best_v), hit.1))
    }

    fn query_any(&self, o: V3, d: V3, t_max: f64, skip: Option<Skip>) -> bool {
        let ray = SlabRay::new(o, d);
        self.bvh.any(&ray, t_max, |p| {
            let s = &self.segments[p as usize];
            !self.skipped(s, skip)
                && entry(s.a.map(f64::from), s.b.map(f64::from), s.radius as f64, o, d, 0.0, t_max)
                    .is_some()
        })
    }

    /// Runs `step(origin, t_max)` over the box-sized pieces of the ray (see the module
    /// documentation); `step` returns a payload and the distance from its origin.
    fn walk<R>(
        &self,
        o: V3,
        d: V3,
        t_max: f64,
        mut step: impl FnMut(V3, f64) -> Option<(R, f64)>,
    ) -> Walk<R> {
        let mut t_end = t_max;
        let mut backing = false;
        if let Some(zb) = self.backing_z
            && d[2] < 0.0
            && o[2] > zb
        {
            let tb = (zb - o[2]) / d[2];
            if tb < t_end {
                t_end = tb;
                backing = true;
            }
        }
        let end = |backing: bool| if backing { Walk::Backing(t_end) } else { Walk::Escaped };
        if self.segments.is_empty() {
            return end(backing);
        }
        let Some(per) = self.period else {
            return match step(o, t_end) {
                Some((r, t)) => Walk::Hit(r, (0.0, t), [0, 0], o),
                None => end(backing),
            };
        };
        // Advance to the slab of the geometry.
        let [zmin, zmax] = self.z_range;
        let mut t_acc = 0.0;
        if o[2] > zmax {
            if d[2] >= 0.0 {
                return end(backing);
            }
            t_acc = (zmax - o[2]) / d[2];
        } else if o[2] < zmin {
            if d[2] <= 0.0 {
                return end(backing);
            }
            t_acc = (zmin - o[2]) / d[2];
        }
        if t_acc >= t_end {
            return end(backing);
        }
        let (mut p, mut shift) = self.canonical(vec3::add_scaled(o, d, t_acc));
        let hi = [per.origin[0] + per.size[0], per.origin[1] + per.size[1]];
        let wall = |p: V3, k: usize| {
            if d[k] > 0.0 {
                (hi[k] - p[k]) / d[k]
            } else if d[k] < 0.0 {
                (per.origin[k] - p[k]) / d[k]
            } else {
                f64::INFINITY
            }
        };
        for _ in 0..MAX_TILES {
            let (tx, ty) = (wall(p, 0).max(0.0), wall(p, 1).max(0.0));
            let t_exit = tx.min(ty);
            let tz = if d[2] > 0.0 {
                (zmax - p[2]) / d[2]
            } else if d[2] < 0.0 {
                (zmin - p[2]) / d[2]
            } else {
                f64::INFINITY
            };
            let limit = t_exit.min(t_end - t_acc).min(tz.max(0.0) * (1.0 + 1e-12) + 1e-300);
            if let Some((r, t)) = step(p, limit) {
                return Walk::Hit(r, (t_acc, t), shift, p);
            }
            if tz <= t_exit || t_exit >= t_end - t_acc {
                break;
            }
            p = vec3::add_scaled(p, d, t_exit);
            t_acc += t_exit;
            for (k, tk) in [(0, tx), (1, ty)] {
                if tk <= t_exit {
                    if d[k] > 0.0 {
                        p[k] = per.origin[k];
                        shift[k] += 1;
                    } else {
                        p[k] = hi[k];
                        shift[k] -= 1;
                    }
                }
            }
        }
        end(backing)
    }
}

enum Walk<R> {
    /// Payload, (distance to the piece's origin, distance within the piece), tile shift,
    /// the piece's origin in box coordinates.
    Hit(R, (f64, f64), [i64; 2], V3),
    Backing(f64),
    Escaped,
}

fn seg_box(s: &Segment) -> Aabb {
    Aabb::of_capsule(s.a.map(f64::from), s.b.map(f64::from), s.radius as f64)
}

/// The capsules of the infinite tiling that overlap the period box.
fn wrap_copies(segments: &[Segment], per: &Period) -> Vec<Segment> {
    let mut out = Vec::with_capacity(segments.len() + segments.len() / 8);
    for s in segments {
        let b = seg_box(s);
        let range = |k: usize| {
            let (lo, hi) = (per.origin[k], per.origin[k] + per.size[k]);
            // Copy i overlaps iff min + i·P < hi and max + i·P > lo.
            let i0 = ((lo - b.max[k] as f64) / per.size[k]).floor() as i64;
            let i1 = ((hi - b.min[k] as f64) / per.size[k]).ceil() as i64;
            (i0..=i1).filter(move |i| {
                b.min[k] as f64 + *i as f64 * per.size[k] < hi
                    && b.max[k] as f64 + *i as f64 * per.size[k] > lo
            })
        };
        for i in range(0) {
            for j in range(1) {
                let (dx, dy) = ((i as f64 * per.size[0]) as f32, (j as f64 * per.size[1]) as f32);
                if i == 0 && j == 0 {
                    out.push(*s);
                } else {
                    let mv = |p: [f32; 3]| [p[0] + dx, p[1] + dy, p[2]];
                    out.push(Segment { a: mv(s.a), b: mv(s.b), ..*s });
                }
            }
        }
    }
    out
}

/// A unit vector perpendicular to unit `t`.
pub fn perpendicular(t: V3) -> V3 {
    let h = if t[2].abs() < 0.9 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
    vec3::normalize(vec3::cross(t, h)).unwrap_or([0.0, 1.0, 0.0])
}

#[cfg(test)]
mod tests;
