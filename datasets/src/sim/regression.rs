//! A guard that the symplectic-Euler path of [`super::step::Simulator`] (the one the older
//! drape used) gives bit-identical results after the knit extensions: a small cloth dropped
//! onto a sphere with self-contact, run for a fixed number of steps, hashed bit for bit.
//! The expected numbers were recorded from the code before the knit animation was added.

use super::collide::SelfContact;
use super::field::ThicknessField;
use super::friction::Friction;
use super::springs::{LawKind, Spring, SpringLaw};
use super::step::{BodyContact, SimParams, Simulator};
use super::{Cloth, Collider};
use crate::vec3::{V3, length, normalize_or, sub};

struct Ball {
    centre: V3,
    radius: f64,
}

impl Collider for Ball {
    fn query(&self, p: V3) -> (f64, V3) {
        let d = sub(p, self.centre);
        (length(d) - self.radius, normalize_or(d, [0.0, 0.0, 1.0]))
    }
}

/// The recorded scene: `n × n` nodes 1 cm apart, 2 cm above a 5 cm ball.
pub(crate) fn drape_scene(n: usize) -> (Cloth, Vec<V3>, SimParams) {
    let h = 0.01;
    let law = SpringLaw {
        kind: LawKind::Exponential,
        lo: 0.99,
        hi: 1.01,
        compression: 0.5,
        damping: 0.05,
        max_tension: f64::INFINITY,
    };
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut x = Vec::new();
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let half = 0.5 * (n - 1) as f64 * h;
            x.push([i as f64 * h - half, j as f64 * h - half, 0.07]);
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let mut cloth = Cloth::new(vec![2e-4; n * n], tris, vec![law]);
    for j in 0..n {
        for i in 0..n {
            let mut add = |a: u32, b: u32, rest: f64| {
                cloth.springs.push(Spring { a, b, rest, k: 40.0, law: 0 });
            };
            if i + 1 < n {
                add(id(i, j), id(i + 1, j), h);
            }
            if j + 1 < n {
                add(id(i, j), id(i, j + 1), h);
            }
            if i + 1 < n && j + 1 < n {
                add(id(i, j), id(i + 1, j + 1), h * 2f64.sqrt());
            }
        }
    }
    cloth.finish();
    let params = SimParams {
        body: Some(BodyContact {
            field: ThicknessField::new(2.0, 0.004, 0.0005),
            friction: Friction { static_coef: 1.0, dynamic_coef: 0.5 },
        }),
        self_contact: Some(SelfContact {
            field: ThicknessField::new(2.0, 0.003, 0.0004),
            margin: 0.002,
            dynamic_friction: 0.5,
            cone_cos: 0.0,
        }),
        dt_max: 1.0 / 250.0,
        ..SimParams::default()
    };
    (cloth, x, params)
}

/// FNV-1a over the bits of positions and velocities.
pub(crate) fn state_hash(x: &[V3], v: &[V3]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in x.iter().chain(v) {
        for c in p {
            for b in c.to_bits().to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    h
}

#[test]
fn symplectic_euler_drape_is_bit_identical_to_the_recorded_run() {
    let (cloth, x, params) = drape_scene(10);
    let ball = Ball { centre: [0.0, 0.0, 0.0], radius: 0.05 };
    let mut sim = Simulator::new(cloth, x, params, Some(&ball));
    let mut halvings = 0;
    for _ in 0..300 {
        halvings += sim.step().halvings;
    }
    let hash = state_hash(&sim.x, &sim.v);
    let z_mean = sim.x.iter().map(|p| p[2]).sum::<f64>() / sim.x.len() as f64;
    // Recorded before the knit extensions (any thread count gives the same bits).
    assert_eq!(hash, 0x1d96_4be1_b544_05a1, "state bits changed");
    assert_eq!(sim.time.to_bits(), 0x3fb8_2310_a167_e853, "time {}", sim.time);
    assert_eq!(halvings, 670);
    assert_eq!(z_mean, 0.034_451_259_566_625_11);
}
