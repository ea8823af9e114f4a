//! An explicit mass–spring cloth simulation after Chen et al. 2003 §4 ("knitwear
//! animation"), written to be extended (the knit animation builds on it):
//!
//! - [`springs`]: the spring laws with a slack interval ([C03 §4.1.1], corrected);
//! - [`field`]: the thickness force field and its C¹ barrier ([C03 eq. 1–2], corrected);
//! - [`friction`]: static and dynamic Coulomb friction ([C03 eq. 3]) plus air viscosity;
//! - [`hashgrid`], [`collide`]: self-collision through a hash grid instead of all pairs;
//! - [`step`]: the time step — forces, a CFL-type bound on `dt`, halving while a node
//!   would pass into the body or through a triangle ([C03 §4.2]), symplectic Euler.
//!
//! A [`Cloth`] is the static part (masses, springs, triangles, pins); a [`step::Simulator`]
//! holds positions and velocities and advances them. Forces are computed per spring and
//! gathered per node in a fixed order, so results are bit-identical for any number of
//! threads.

pub mod collide;
pub mod field;
pub mod friction;
pub mod hashgrid;
pub mod springs;
pub mod step;

use crate::vec3::V3;
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
    /// Nodes held in place.
    pub pinned: Vec<bool>,
    /// Springs at each node: `incident[starts[i]..starts[i + 1]]`, as `(spring, +1 | −1)`.
    starts: Vec<u32>,
    incident: Vec<(u32, f64)>,
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
            starts: Vec::new(),
            incident: Vec::new(),
        }
    }

    /// Builds the per-node spring lists (in spring order, so gathers are deterministic).
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
    }

    /// The springs at node `i` with the sign of their force on it.
    pub fn springs_at(&self, i: usize) -> &[(u32, f64)] {
        &self.incident[self.starts[i] as usize..self.starts[i + 1] as usize]
    }
}
