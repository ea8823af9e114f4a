//! Bending and shear as angle springs, Chen et al. 2003 §4.1.1 ("bending and shear forces
//! are proportional to the angle between neighbouring loops", constants `c₂`, `c₃`, `c₄` of
//! [C03 §6]). The paper gives no formula; the knit design (§1.1 step 4 and its unit table)
//! makes bending torque-like (N·m/rad) and shear force-like (N/rad). We use one element for
//! both [choice]:
//!
//! - an [`AngleSpring`] over three nodes `(a, m, b)` measures the angle `φ` at the middle
//!   node `m` between the arms `a − m` and `b − m`, and stores the energy
//!   `E = ½ κ (φ − φ₀)²`, so the forces are `F = −κ (φ − φ₀) ∇φ`;
//! - **bending** is a hinge between neighbouring loops along a wale or a course: three
//!   consecutive nodes of a grid line, `φ₀ = π` (the knit's rest state is flat), `κ = c₂`
//!   (N·m/rad²): a bend of `θ = π − φ` costs a torque `c₂ θ` at the middle node;
//! - **shear** is the angle between the wale edge and the course edge at a loop corner,
//!   `φ₀` = the rest angle (π/2 on a rectangular grid), `κ = c₃ λ` with `λ` the mean rest
//!   length of the two arms, so a shear of `Δφ` pushes the arm ends with about `c₃ Δφ` (N).
//!   We prefer the corner angle to the two cell diagonals: a diagonal spring also resists
//!   stretch along the diagonal, which would stiffen the knit's stretch that `c₀` sets.
//!
//! The gradient of `φ` is singular where the arms are parallel (`sin φ = 0`). For a flat
//! rest (`φ₀ = π`) the product `(φ − φ₀)/sin φ` has the finite limit −1 there and is
//! evaluated as `−θ/sin θ`; elsewhere `sin φ` is bounded below by [`MIN_SIN`], so a folded
//! or collapsed corner gets a large but finite force. The three forces sum to zero by
//! construction (the middle node takes minus the sum of the arms), so angle springs
//! conserve linear momentum.

use crate::vec3::{V3, add, cross, dot, length, scale, sub};
use std::f64::consts::PI;

/// The smallest `sin φ` used in the gradient away from a flat rest.
pub const MIN_SIN: f64 = 0.05;

/// Which kind of angle spring (for bookkeeping and reports; the law is the same).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AngleKind {
    /// Hinge between neighbouring loops (`c₂`).
    Bend,
    /// Wale–course corner angle (`c₃`, `c₄`).
    Shear,
}

/// An angle spring over nodes `[a, m, b]`, the angle measured at `m`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleSpring {
    /// Arm end, middle node, arm end.
    pub nodes: [u32; 3],
    /// Rest angle `φ₀` (rad).
    pub rest: f64,
    /// Stiffness `κ` of `E = ½ κ (φ − φ₀)²` (N·m/rad²).
    pub kappa: f64,
    /// Bend or shear.
    pub kind: AngleKind,
}

/// Forces of one angle spring on its three nodes, and a stiffness estimate per node
/// (N/m, for the time-step bound).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleForce {
    /// Forces on `[a, m, b]` (N).
    pub force: [V3; 3],
    /// Stiffness estimates on `[a, m, b]` (N/m).
    pub stiffness: [f64; 3],
}

/// The angle between `u` and `w` (rad, in `[0, π]`) and its sine.
fn angle(u: V3, w: V3) -> (f64, f64) {
    let s = length(cross(u, w));
    let c = dot(u, w);
    (s.atan2(c), s / (length(u) * length(w)))
}

impl AngleSpring {
    fn arms(&self, x: &[V3]) -> (V3, V3) {
        let [a, m, b] = self.nodes.map(|i| x[i as usize]);
        (sub(a, m), sub(b, m))
    }

    /// The current angle `φ` at the middle node (rad).
    pub fn angle(&self, x: &[V3]) -> f64 {
        let (u, w) = self.arms(x);
        angle(u, w).0
    }

    /// The stored energy `½ κ (φ − φ₀)²` (J).
    pub fn energy(&self, x: &[V3]) -> f64 {
        let d = self.angle(x) - self.rest;
        0.5 * self.kappa * d * d
    }

    /// Forces `−κ (φ − φ₀) ∇φ` on the three nodes.
    pub fn force(&self, x: &[V3]) -> AngleForce {
        let (u, w) = self.arms(x);
        let (lu, lw) = (length(u), length(w));
        if lu < 1e-12 || lw < 1e-12 {
            return AngleForce { force: [[0.0; 3]; 3], stiffness: [0.0; 3] };
        }
        let (uh, wh) = (scale(u, 1.0 / lu), scale(w, 1.0 / lw));
        let (phi, sin_phi) = angle(u, w);
        let cos_phi = dot(uh, wh);
        // r = (φ − φ₀)/sin φ, with the flat-rest limit handled exactly.
        let flat_rest = (self.rest - PI).abs() < 1e-12;
        let r = if flat_rest && phi > 0.5 * PI {
            let theta = PI - phi;
            if theta < 1e-6 { -(1.0 + theta * theta / 6.0) } else { -theta / sin_phi }
        } else {
            (phi - self.rest) / sin_phi.max(MIN_SIN)
        };
        // ∂φ/∂a = −(ŵ − cos φ û)/(|u| sin φ), ∂φ/∂b likewise with u and w swapped.
        let fa = scale(sub(wh, scale(uh, cos_phi)), self.kappa * r / lu);
        let fb = scale(sub(uh, scale(wh, cos_phi)), self.kappa * r / lw);
        let fm = scale(add(fa, fb), -1.0);
        let (ka, kb) = (self.kappa / (lu * lu), self.kappa / (lw * lw));
        AngleForce { force: [fa, fm, fb], stiffness: [ka, ka + kb, kb] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bend(x: &[V3]) -> AngleSpring {
        let _ = x;
        AngleSpring { nodes: [0, 1, 2], rest: PI, kappa: 0.3, kind: AngleKind::Bend }
    }

    fn numeric_force(s: &AngleSpring, x: &[V3], node: usize) -> V3 {
        let h = 1e-7;
        [0, 1, 2].map(|k| {
            let mut xp = x.to_vec();
            let mut xm = x.to_vec();
            xp[node][k] += h;
            xm[node][k] -= h;
            -(s.energy(&xp) - s.energy(&xm)) / (2.0 * h)
        })
    }

    #[test]
    fn bending_is_zero_when_straight_and_restores_a_bend() {
        let straight = [[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.02, 0.0, 0.0]];
        let s = bend(&straight);
        let f = s.force(&straight);
        for v in f.force {
            assert_eq!(v, [0.0; 3]);
        }
        // Lift the middle node: the hinge pushes it back down, the ends up, sum zero.
        let bent = [[0.0, 0.0, 0.0], [0.01, 0.0, 0.001], [0.02, 0.0, 0.0]];
        let f = s.force(&bent);
        assert!(f.force[1][2] < 0.0 && f.force[0][2] > 0.0 && f.force[2][2] > 0.0);
        let sum = add(add(f.force[0], f.force[1]), f.force[2]);
        assert!(length(sum) < 1e-15 * length(f.force[1]).max(1.0), "{sum:?}");
        // The force is minus the gradient of the energy (and so restoring).
        for node in 0..3 {
            let num = numeric_force(&s, &bent, node);
            let err = length(sub(num, f.force[node]));
            assert!(err < 1e-5 * length(f.force[1]), "node {node}: {num:?} vs {:?}", f.force[node]);
        }
        // Small bends: torque c₂ θ at the middle node, so |F_m| = c₂ θ (1/|u| + 1/|w|).
        let theta = 2.0 * (0.001f64 / 0.01).atan();
        let expected = 0.3 * theta * 2.0 / (0.01f64.hypot(0.001));
        assert!((length(f.force[1]) / expected - 1.0).abs() < 0.01);
    }

    #[test]
    fn shear_is_zero_at_the_rest_angle_and_restores_it() {
        let rest = [[0.01, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.01, 0.0]];
        let s =
            AngleSpring { nodes: [0, 1, 2], rest: 0.5 * PI, kappa: 1e-2, kind: AngleKind::Shear };
        assert!(length(s.force(&rest).force[0]) < 1e-15);
        // Open the corner by 0.1 rad: the arm ends are pulled back towards each other.
        let sheared =
            [[0.01, 0.0, 0.0], [0.0, 0.0, 0.0], [-0.01 * 0.1f64.sin(), 0.01 * 0.1f64.cos(), 0.0]];
        let f = s.force(&sheared);
        assert!((s.angle(&sheared) - (0.5 * PI + 0.1)).abs() < 1e-12);
        assert!(f.force[0][1] > 0.0, "a moves towards b: {:?}", f.force[0]);
        assert!(f.force[2][0] > 0.0, "b moves towards a: {:?}", f.force[2]);
        // |F| at an arm end = κ Δφ / |arm|.
        assert!((length(f.force[0]) / (1e-2 * 0.1 / 0.01) - 1.0).abs() < 1e-9);
        for node in 0..3 {
            let num = numeric_force(&s, &sheared, node);
            assert!(length(sub(num, f.force[node])) < 1e-5 * length(f.force[0]));
        }
    }
}
