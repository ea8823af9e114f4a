//! An explicit mass–spring cloth simulation after Chen et al. 2003 §4 ("knitwear
//! animation"), written to be extended (the knit animation builds on it):
//!
//! - [`springs`]: the spring laws with a slack interval ([C03 §4.1.1], corrected);
//! - [`field`]: the thickness force field and its C¹ barrier ([C03 eq. 1–2], corrected);
//! - [`friction`]: static and dynamic Coulomb friction ([C03 eq. 3]) plus air viscosity;
//! - [`hashgrid`], [`collide`]: self-collision through a hash grid instead of all pairs;
//! - [`angles`]: bending and shear as angle springs ([C03 §4.1.1], `c₂`, `c₃`, `c₄`);
//! - [`step`]: the time step — forces, a CFL-type bound on `dt`, halving while a node
//!   would pass into the body or through a triangle ([C03 §4.2]), and one of three
//!   explicit integrators ([`step::Integrator`]: symplectic Euler, velocity Verlet, and
//!   the paper's midpoint RK2);
//! - [`shapes`]: analytic colliders (plane, sphere, capsule, box);
//! - [`knit`]: the knit animation of [C03 §4]: a loop grid with two triangles per loop,
//!   the paper's §6 constants in SI ([`knit::KnitSimParams`]), built into a simulator;
//! - [`smooth`]: the render-only moving average over time ([C03 §4.2]'s jitter filter);
//! - [`scenes`]: the two scarf scenes of [C03 Fig. 13] (dropped, stretched and released).
//!
//! A [`Cloth`] is the static part (masses, springs, angle springs, triangles, pins); a
//! [`step::Simulator`] holds positions and velocities and advances them. Forces are
//! computed per spring and per angle spring and gathered per node over adjacency lists in
//! a fixed order (no atomics), so results are bit-identical for any number of threads.

pub mod angles;
pub mod collide;
pub mod field;
pub mod friction;
pub mod hashgrid;
pub mod knit;
#[cfg(test)]
mod regression;
pub mod scenes;
pub mod shapes;
pub mod smooth;
pub mod springs;
pub mod step;
#[cfg(test)]
mod tests;

use crate::vec3::V3;
use angles::AngleSpring;
use springs::{Spring, SpringLaw};

/// Anything the cloth collides with: signed distance (negative inside) and outward normal.
pub trait Collider: Sync {
    /// Distance from `p` to the surface (m) and the unit outward normal there.
    fn query(&self, p: V3) -> (f64, V3);
}

impl Collider for crate::garment::sdf::SdfGrid {
    fn query(&self, p: V3) -> (f64, V3) {
        crate::garment::sdf::SdfGrid::query(self, p)
    }
}

/// The static description of a cloth.
#[derive(Debug, Clone, Default)]
pub struct Cloth {
    /// Node masses (kg).
    pub mass: Vec<f64>,
    /// Springs.
    pub springs: Vec<Spring>,
    /// Spring laws, indexed by `Spring::law`.
    pub laws: Vec<SpringLaw>,
    /// Triangles (for self-collision).
    pub triangles: Vec<[u32; 3]>,
    /// Nodes held in place (or moved at a prescribed velocity, see
    /// [`step::Simulator::pin_velocity`]).
    pub pinned: Vec<bool>,
    /// Bending and shear angle springs (none for the older drape).
    pub angles: Vec<AngleSpring>,
    /// Springs at each node: `incident[starts[i]..starts[i + 1]]`, as `(spring, +1 | −1)`.
    starts: Vec<u32>,
    incident: Vec<(u32, f64)>,
    /// Angle springs at each node, as `(angle spring, slot 0..3)`.
    angle_starts: Vec<u32>,
    angle_incident: Vec<(u32, u8)>,
}

impl Cloth {
    /// A cloth of `mass.len()` nodes; call [`Cloth::finish`] after adding springs.
    pub fn new(mass: Vec<f64>, triangles: Vec<[u32; 3]>, laws: Vec<SpringLaw>) -> Self {
        let n = mass.len();
        Cloth {
            mass,
            springs: Vec::new(),
            laws,
            triangles,
            pinned: vec![false; n],
            angles: Vec::new(),
            starts: Vec::new(),
            incident: Vec::new(),
            angle_starts: Vec::new(),
            angle_incident: Vec::new(),
        }
    }

    /// Builds the per-node spring and angle-spring lists (in element order, so gathers are
    /// deterministic).
    pub fn finish(&mut self) {
        let n = self.mass.len();
        let mut count = vec![0u32; n + 1];
        for s in &self.springs {
            count[s.a as usize + 1] += 1;
            count[s.b as usize + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        self.incident = vec![(0, 0.0); count[n] as usize];
        for (si, s) in self.springs.iter().enumerate() {
            self.incident[fill[s.a as usize] as usize] = (si as u32, 1.0);
            fill[s.a as usize] += 1;
            self.incident[fill[s.b as usize] as usize] = (si as u32, -1.0);
            fill[s.b as usize] += 1;
        }
        self.starts = count;
        let mut count = vec![0u32; n + 1];
        for a in &self.angles {
            for &node in &a.nodes {
                count[node as usize + 1] += 1;
            }
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        self.angle_incident = vec![(0, 0); count[n] as usize];
        for (ai, a) in self.angles.iter().enumerate() {
            for (slot, &node) in a.nodes.iter().enumerate() {
                self.angle_incident[fill[node as usize] as usize] = (ai as u32, slot as u8);
                fill[node as usize] += 1;
            }
        }
        self.angle_starts = count;
    }

    /// The springs at node `i` with the sign of their force on it.
    pub fn springs_at(&self, i: usize) -> &[(u32, f64)] {
        &self.incident[self.starts[i] as usize..self.starts[i + 1] as usize]
    }

    /// The angle springs at node `i` with the node's slot in each (empty before
    /// [`Cloth::finish`]).
    pub fn angles_at(&self, i: usize) -> &[(u32, u8)] {
        if self.angle_starts.len() <= i + 1 {
            return &[];
        }
        &self.angle_incident[self.angle_starts[i] as usize..self.angle_starts[i + 1] as usize]
    }
}
