//! The swept yarn tubes: where the density lives and how a ray crosses it.
//!
//! Each curve is sampled at `k` uniform parameter steps per segment into centre-line points
//! with their frame `(T, N, B)` (`yarn::frame`, the frame the fibers are generated in) and
//! length coordinate `z`; consecutive samples bound a capsule of radius `R` = the
//! density's reach, and the capsules go into one BVH. The density at a point `x` is, for
//! every yarn whose tube contains it, the density of its nearest centre-line point
//! (segment projection, frame and `z` interpolated linearly): with
//! `(a, b) = ((x − C)·N, (x − C)·B)` and `θ = 2πz/α_ply` (the curve's effective pitch),
//! the slice coordinates are `(a cos θ + b sin θ, −a sin θ + b cos θ)` — the rotation
//! `yarn::density` accumulated its grid with. Overlapping yarns add.

use super::density::{ExtinctionLaw, SliceDensity, TiltModel, sigma};
use crate::geometry::bvh::{Aabb, Bvh, SlabRay};
use crate::geometry::capsule::segment_distance2;
use crate::{Error, Result};
use std::f64::consts::TAU;
use std::sync::Arc;
use yarn::curve::YarnSet;
use yarn::fiber::EffectiveTwist;
use yarn::frame::CurveFrames;
use yarn::params::YarnParams;
use yarn::vec3::{self, V3};

#[derive(Debug, Clone, Copy)]
struct Sample {
    p: V3,
    t: V3,
    n: V3,
    z: f64,
}

struct Tube {
    samples: Vec<Sample>,
    density: Arc<dyn SliceDensity>,
    ply_pitch: f64,
    tilt: Option<TiltModel>,
}

/// The union of swept yarn tubes with their densities.
pub struct VolumeScene {
    tubes: Vec<Tube>,
    caps: Vec<(u32, u32)>,
    bvh: Bvh,
    /// Extinction law.
    pub law: ExtinctionLaw,
}

impl std::fmt::Debug for VolumeScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "VolumeScene({} tubes, {} capsules, {:?})",
            self.tubes.len(),
            self.caps.len(),
            self.law
        )
    }
}

impl VolumeScene {
    /// Tubes of `set`, curve `i` with `densities[params_id]` and the effective ply pitch
    /// of `params[params_id]`; `samples_per_segment` centre-line samples per segment.
    pub fn new(
        set: &YarnSet,
        params: &[YarnParams],
        densities: &[Arc<dyn SliceDensity>],
        law: ExtinctionLaw,
        samples_per_segment: usize,
    ) -> Result<Self> {
        set.validate()?;
        let k = samples_per_segment.clamp(1, 4096);
        let mut tubes = Vec::with_capacity(set.curves.len());
        for (i, c) in set.curves.iter().enumerate() {
            let id = c.params_ids[0] as usize;
            let (Some(p), Some(dens)) = (params.get(id), densities.get(id)) else {
                return Err(Error::Invalid(format!(
                    "curve {i}: yarn params id {id}, but {} params and {} densities given",
                    params.len(),
                    densities.len()
                )));
            };
            let twist = EffectiveTwist::for_curve(p, c);
            let frames = CurveFrames::new(c, 16);
            let m = c.segment_count();
            let samples = (0..=m * k)
                .map(|j| {
                    let u = j as f64 / k as f64;
                    let f = frames.frame_at(c, u);
                    Sample { p: c.point(u), t: f.t, n: f.n, z: c.length_coord(u) }
                })
                .collect();
            tubes.push(Tube {
                samples,
                density: dens.clone(),
                ply_pitch: twist.ply_pitch,
                tilt: Some(TiltModel::new(p, twist.ply_pitch, twist.fiber_pitch)),
            });
        }
        Ok(Self::from_tubes(tubes, law))
    }

    /// Straight-or-not tubes of one density and ply pitch, without a yarn description (the
    /// closed-form tests: a uniform disk swept along a curve; no tilt model).
    pub fn with_density(
        set: &YarnSet,
        density: Arc<dyn SliceDensity>,
        ply_pitch: f64,
        law: ExtinctionLaw,
        samples_per_segment: usize,
    ) -> Result<Self> {
        let k = samples_per_segment.clamp(1, 4096);
        set.validate()?;
        let tubes = set
            .curves
            .iter()
            .map(|c| {
                let frames = CurveFrames::new(c, 16);
                let samples = (0..=c.segment_count() * k)
                    .map(|j| {
                        let u = j as f64 / k as f64;
                        let f = frames.frame_at(c, u);
                        Sample { p: c.point(u), t: f.t, n: f.n, z: c.length_coord(u) }
                    })
                    .collect();
                Tube { samples, density: density.clone(), ply_pitch, tilt: None }
            })
            .collect();
        Ok(Self::from_tubes(tubes, law))
    }

    fn from_tubes(tubes: Vec<Tube>, law: ExtinctionLaw) -> Self {
        let mut caps = Vec::new();
        let mut boxes = Vec::new();
        for (ti, t) in tubes.iter().enumerate() {
            let r = t.density.reach();
            for i in 0..t.samples.len().saturating_sub(1) {
                caps.push((ti as u32, i as u32));
                boxes.push(Aabb::of_capsule(t.samples[i].p, t.samples[i + 1].p, r));
            }
        }
        let bvh = Bvh::build(&boxes);
        VolumeScene { tubes, caps, bvh, law }
    }

    /// Bounds of all tubes.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    /// Extinction (m⁻¹) at `x` for unit direction `w`, summed over the yarns there.
    pub fn sigma_at(&self, x: V3, w: V3) -> f64 {
        self.sum_over_tubes(x, |tube, n_a, t, v| {
            sigma(self.law, tube.density.fiber_radius(), n_a, w, t, v)
        })
    }

    /// The local yarn tangent of the densest tube at `x` (for the Kajiya–Kay phase), if any.
    pub fn tangent_at(&self, x: V3) -> Option<V3> {
        let mut best: Option<(f64, V3)> = None;
        self.sum_over_tubes(x, |_, n_a, t, _| {
            if best.is_none_or(|b| n_a > b.0) {
                best = Some((n_a, t));
            }
            0.0
        });
        best.map(|b| b.1)
    }

    fn sum_over_tubes(&self, x: V3, mut f: impl FnMut(&Tube, f64, V3, V3) -> f64) -> f64 {
        // Nearest segment per tube among the capsules containing x.
        let mut near: [(u32, u32, f64, f64); 8] = [(u32::MAX, 0, f64::INFINITY, 0.0); 8];
        let mut count = 0usize;
        let mut extra: Vec<(u32, u32, f64, f64)> = Vec::new();
        self.bvh.points_query(x, |c| {
            let (ti, si) = self.caps[c as usize];
            let tube = &self.tubes[ti as usize];
            let (a, b) = (tube.samples[si as usize].p, tube.samples[si as usize + 1].p);
            let (d2, v) = segment_distance2(a, b, x);
            let r = tube.density.reach();
            if d2 > r * r {
                return;
            }
            let slot = near[..count].iter().position(|e| e.0 == ti);
            match slot {
                Some(k) if d2 < near[k].2 => near[k] = (ti, si, d2, v),
                Some(_) => {}
                None if count < near.len() => {
                    near[count] = (ti, si, d2, v);
                    count += 1;
                }
                None => match extra.iter_mut().find(|e| e.0 == ti) {
                    Some(e) if d2 < e.2 => *e = (ti, si, d2, v),
                    Some(_) => {}
                    None => extra.push((ti, si, d2, v)),
                },
            }
        });
        let mut total = 0.0;
        for &(ti, si, _, v) in near[..count].iter().chain(extra.iter()) {
            let tube = &self.tubes[ti as usize];
            let (s0, s1) = (tube.samples[si as usize], tube.samples[si as usize + 1]);
            let c = vec3::add(vec3::scale(s0.p, 1.0 - v), vec3::scale(s1.p, v));
            let t = vec3::normalize_or(
                vec3::add(vec3::scale(s0.t, 1.0 - v), vec3::scale(s1.t, v)),
                s0.t,
            );
            let n0 = vec3::add(vec3::scale(s0.n, 1.0 - v), vec3::scale(s1.n, v));
            let n = vec3::normalize_or(vec3::add_scaled(n0, t, -vec3::dot(n0, t)), s0.n);
            let b = vec3::cross(t, n);
            let z = s0.z + (s1.z - s0.z) * v;
            let q = vec3::sub(x, c);
            let (a_, b_) = (vec3::dot(q, n), vec3::dot(q, b));
            let th = if tube.ply_pitch != 0.0 { TAU * z / tube.ply_pitch } else { 0.0 };
            let (sn, cs) = th.sin_cos();
            let (xs, ys) = (cs * a_ + sn * b_, -sn * a_ + cs * b_);
            let n_a = tube.density.n_a(xs, ys);
            if n_a <= 0.0 {
                continue;
            }
            let vw = match (self.law, tube.tilt) {
                (ExtinctionLaw::Tilted, Some(m)) => {
                    let [vx, vy] = m.velocity(xs, ys);
                    // Slice → yarn frame (rotate by +θ), then to world.
                    let (va, vb) = (cs * vx - sn * vy, sn * vx + cs * vy);
                    vec3::add(vec3::scale(n, va), vec3::scale(b, vb))
                }
                _ => [0.0; 3],
            };
            total += f(tube, n_a, t, vw);
        }
        total
    }

    /// The merged intervals `[t0, t1]` (within `[t_min, t_max]`) where the ray `o + t·d`
    /// is inside some tube, in order.
    pub fn intervals(&self, o: V3, d: V3, t_min: f64, t_max: f64) -> Vec<(f64, f64)> {
        let ray = SlabRay::new(o, d);
        let mut iv = Vec::new();
        self.bvh.any(&ray, f64::INFINITY, |c| {
            let (ti, si) = self.caps[c as usize];
            let tube = &self.tubes[ti as usize];
            let (a, b) = (tube.samples[si as usize].p, tube.samples[si as usize + 1].p);
            if let Some((t0, t1)) = capsule_interval(a, b, tube.density.reach(), o, d) {
                let (t0, t1) = (t0.max(t_min), t1.min(t_max));
                if t1 > t0 {
                    iv.push((t0, t1));
                }
            }
            false
        });
        iv.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut out: Vec<(f64, f64)> = Vec::with_capacity(iv.len());
        for (a, b) in iv {
            match out.last_mut() {
                Some(last) if a <= last.1 => last.1 = last.1.max(b),
                _ => out.push((a, b)),
            }
        }
        out
    }
}

/// The interval of the line `o + t·d` (`d` unit) inside the capsule `(a, b, r)`.
pub fn capsule_interval(a: V3, b: V3, r: f64, o: V3, d: V3) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut ball = |c: V3| {
        let oc = vec3::sub(o, c);
        let bb = vec3::dot(d, oc);
        let h = bb * bb - (vec3::dot(oc, oc) - r * r);
        if h >= 0.0 {
            let s = h.sqrt();
            lo = lo.min(-bb - s);
            hi = hi.max(-bb + s);
        }
    };
    ball(a);
    ball(b);
    let ba = vec3::sub(b, a);
    let baba = vec3::dot(ba, ba);
    if baba > 0.0 {
        let axis = vec3::scale(ba, 1.0 / baba.sqrt());
        let oa = vec3::sub(o, a);
        // Finite cylinder = infinite cylinder ∩ slab 0 ≤ (x − a)·axis ≤ |ba|.
        let dd = vec3::dot(d, axis);
        let od = vec3::dot(oa, axis);
        let (k2, k1, k0) =
            (1.0 - dd * dd, vec3::dot(d, oa) - dd * od, vec3::dot(oa, oa) - od * od - r * r);
        let (mut c0, mut c1) = if k2 > 1e-12 {
            let h = k1 * k1 - k2 * k0;
            if h < 0.0 {
                (f64::INFINITY, f64::NEG_INFINITY)
            } else {
                let s = h.sqrt();
                ((-k1 - s) / k2, (-k1 + s) / k2)
            }
        } else if k0 <= 0.0 {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        };
        let len = baba.sqrt();
        if dd.abs() > 0.0 {
            let (s0, s1) = ((0.0 - od) / dd, (len - od) / dd);
            c0 = c0.max(s0.min(s1));
            c1 = c1.min(s0.max(s1));
        } else if od < 0.0 || od > len {
            c1 = f64::NEG_INFINITY;
        }
        if c1 > c0 {
            lo = lo.min(c0);
            hi = hi.max(c1);
        }
    }
    (hi > lo).then_some((lo, hi))
}
