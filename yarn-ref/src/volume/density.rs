//! Cross-section densities and extinction laws (DESIGN §1.3 item 10, §2.3 item 10).
//!
//! A density gives `n_A(x, y)`, fiber centres per m² in the slice frame that turns with
//! the plies. The extinction for direction `ω` at a point whose yarn tangent is `T`:
//! - **anisotropic** (physical; fibers along the yarn): `σ = 2 r_f n_A · sin∠(ω, T)`;
//! - **isotropic** ([C03]'s literal `γρ`): `σ = 2 r_f n_A`;
//! - **tilted**: fibers are helices, tilted from the yarn axis; the local fiber direction
//!   `T_f ∝ T + v`, `v` the velocity per unit length coordinate of the fiber through the
//!   point — the ply's turn `2π/α_ply` about the yarn axis plus the fiber's turn `2π/α`
//!   about its (nearest) ply centre on the ply ellipse [W19 eq. 1] — so
//!   `σ = 2 r_f n_A cos τ · sin∠(ω, T_f)` with `cos τ = 1/|T + v|` (the fibers crossing a
//!   unit area ⟂ T are denser by `1/cos τ` than those crossing a unit area ⟂ T_f). The
//!   migration's radial motion and the curve's own bending are neglected.

use std::f64::consts::TAU;
use yarn::density::CrossSectionDensity;
use yarn::params::YarnParams;
use yarn::vec3::{self, V3};

/// Fiber-centre density on the slice plane.
pub trait SliceDensity: Send + Sync {
    /// `n_A` (m⁻²) at slice coordinates `(x, y)`.
    fn n_a(&self, x: f64, y: f64) -> f64;
    /// Radius beyond which `n_A = 0` (the tube radius).
    fn reach(&self) -> f64;
    /// Fiber radius `r_f`.
    fn fiber_radius(&self) -> f64;
}

impl SliceDensity for CrossSectionDensity {
    fn n_a(&self, x: f64, y: f64) -> f64 {
        self.n_a_at(x, y)
    }
    fn reach(&self) -> f64 {
        // The circle through the grid corners: every non-zero cell lies inside it.
        self.half_width * std::f64::consts::SQRT_2
    }
    fn fiber_radius(&self) -> f64 {
        self.fiber_radius
    }
}

/// A uniform density inside a disk (the closed-form tests of DESIGN §1.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UniformDisk {
    /// `n_A` inside.
    pub n_a: f64,
    /// Disk radius.
    pub radius: f64,
    /// Fiber radius.
    pub fiber_radius: f64,
}

impl SliceDensity for UniformDisk {
    fn n_a(&self, x: f64, y: f64) -> f64 {
        if x * x + y * y <= self.radius * self.radius { self.n_a } else { 0.0 }
    }
    fn reach(&self) -> f64 {
        self.radius
    }
    fn fiber_radius(&self) -> f64 {
        self.fiber_radius
    }
}

/// The ply geometry the tilt correction needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TiltModel {
    /// Plies.
    pub plies: u32,
    /// Ply centre distance from the yarn axis.
    pub ply_distance: f64,
    /// Ply ellipse semi-axes `(e_N, e_B)`.
    pub ellipse: [f64; 2],
    /// Ply pitch α_ply (signed).
    pub ply_pitch: f64,
    /// Fiber pitch α (signed).
    pub fiber_pitch: f64,
}

impl TiltModel {
    /// From yarn parameters with the given (effective) pitches.
    pub fn new(p: &YarnParams, ply_pitch: f64, fiber_pitch: f64) -> Self {
        TiltModel {
            plies: p.ply_count.max(1),
            ply_distance: p.ply_center_distance,
            ellipse: [p.ply_ellipse_n.max(1e-30), p.ply_ellipse_b.max(1e-30)],
            ply_pitch,
            fiber_pitch,
        }
    }

    /// Velocity per unit z of the fiber through slice point `(x, y)`, in slice
    /// coordinates.
    pub fn velocity(&self, x: f64, y: f64) -> [f64; 2] {
        let n = self.plies as usize;
        let mut best = (f64::INFINITY, 0usize);
        for j in 0..n {
            let a = TAU * j as f64 / n as f64;
            let (cx, cy) = (self.ply_distance * a.cos(), self.ply_distance * a.sin());
            let d = (x - cx).powi(2) + (y - cy).powi(2);
            if d < best.0 {
                best = (d, j);
            }
        }
        let a = TAU * best.1 as f64 / n as f64;
        let (ca, sa) = (a.cos(), a.sin());
        let (qx, qy) = (x - self.ply_distance * ca, y - self.ply_distance * sa);
        let (u, v) = (qx * ca + qy * sa, -qx * sa + qy * ca);
        let [en, eb] = self.ellipse;
        let wf = if self.fiber_pitch != 0.0 { TAU / self.fiber_pitch } else { 0.0 };
        let (du, dv) = (-wf * (en / eb) * v, wf * (eb / en) * u);
        let wp = if self.ply_pitch != 0.0 { TAU / self.ply_pitch } else { 0.0 };
        // Back to slice axes, plus the slice frame's own turn ω_p × q.
        [du * ca - dv * sa - wp * y, du * sa + dv * ca + wp * x]
    }
}

/// Which extinction law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ExtinctionLaw {
    /// `2 r_f n_A sin∠(ω, T)`.
    Anisotropic,
    /// `2 r_f n_A`.
    Isotropic,
    /// `2 r_f n_A cos τ sin∠(ω, T_f)` (helix tilt).
    Tilted,
}

/// `sin∠(ω, t)` for unit vectors.
#[inline]
pub fn sin_angle(w: V3, t: V3) -> f64 {
    vec3::length(vec3::cross(w, t)).min(1.0)
}

/// Extinction at a point: `n_a` there, unit direction `w`, yarn tangent `t`, the slice
/// velocity already rotated to world (`v_world`, ⟂ t; zero for the untilted laws).
#[inline]
pub fn sigma(law: ExtinctionLaw, r_f: f64, n_a: f64, w: V3, t: V3, v_world: V3) -> f64 {
    let s = 2.0 * r_f * n_a;
    match law {
        ExtinctionLaw::Isotropic => s,
        ExtinctionLaw::Anisotropic => s * sin_angle(w, t),
        ExtinctionLaw::Tilted => {
            let tf = vec3::add(t, v_world);
            let len = vec3::length(tf);
            s / len * sin_angle(w, vec3::scale(tf, 1.0 / len))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tilt_of_a_single_circular_ply_is_the_helix_angle() {
        // One ply on the axis, circular: a fiber at radius ρ turns at 2π/α about it, the
        // slice frame at 2π/α_ply: |v| = 2πρ·|1/α + 1/α_ply|, tan τ = |v|.
        let m = TiltModel {
            plies: 1,
            ply_distance: 0.0,
            ellipse: [1.0, 1.0],
            ply_pitch: 4.0,
            fiber_pitch: -5.0,
        };
        let v = m.velocity(0.3, 0.4);
        let want = TAU * 0.5 * (1.0 / -5.0 + 1.0 / 4.0);
        assert!(((v[0].hypot(v[1])) - want.abs()).abs() < 1e-12, "{v:?} {want}");
        // Perpendicular to the radius.
        assert!((v[0] * 0.3 + v[1] * 0.4).abs() < 1e-12);
        // σ along the tilted fiber is 0; across it 2 r_f n_A cos τ.
        let t = [0.0, 0.0, 1.0];
        let vw = [v[0], v[1], 0.0];
        let tf = vec3::normalize(vec3::add(t, vw)).unwrap();
        assert!(sigma(ExtinctionLaw::Tilted, 1.0, 1.0, tf, t, vw).abs() < 1e-12);
        let across = vec3::normalize(vec3::cross(tf, [1.0, 0.0, 0.0])).unwrap();
        let s = sigma(ExtinctionLaw::Tilted, 1.0, 1.0, across, t, vw);
        assert!((s - 2.0 / (1.0 + want * want).sqrt()).abs() < 1e-12);
        assert_eq!(sigma(ExtinctionLaw::Anisotropic, 1.0, 1.0, t, t, vw), 0.0);
        assert_eq!(sigma(ExtinctionLaw::Isotropic, 1.0, 1.0, t, t, vw), 2.0);
    }
}
