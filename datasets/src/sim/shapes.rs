//! Analytic colliders for the knit scenes: a plane, a sphere, a capsule (a body proxy such
//! as an arm or a neck) and an axis-aligned box (a table), each as an exact signed distance
//! (negative inside) with the outward unit normal, so the thickness field of [C03 eq. 1–2]
//! acts along the distance vector, which lies on the surface normal and therefore always
//! inside the 45° influence cone of [C03 §4.1.2].

use super::Collider;
use crate::vec3::{V3, add, dot, length, normalize_or, scale, sub};
use crate::{Error, Result};

/// A closed set of analytic shapes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// The half-space below the plane through `point` with unit `normal` pointing out.
    Plane {
        /// A point on the plane (m).
        point: V3,
        /// Outward unit normal.
        normal: V3,
    },
    /// A ball.
    Sphere {
        /// Centre (m).
        centre: V3,
        /// Radius (m).
        radius: f64,
    },
    /// All points within `radius` of the segment `a–b`.
    Capsule {
        /// One end of the axis (m).
        a: V3,
        /// The other end (m).
        b: V3,
        /// Radius (m).
        radius: f64,
    },
    /// An axis-aligned box.
    Box {
        /// Lower corner (m).
        min: V3,
        /// Upper corner (m).
        max: V3,
    },
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl Shape {
    /// Checks the shape's numbers: finite, positive radii, a non-zero plane normal (which
    /// is normalised), `min < max` for a box.
    pub fn validated(self) -> Result<Shape> {
        let bad = |what: &str| Err(Error::Invalid(format!("collider {self:?}: {what}")));
        match self {
            Shape::Plane { point, normal } => {
                let l = length(normal);
                if !(finite(&point) && l.is_finite() && l > 0.0) {
                    return bad("needs a finite point and a non-zero normal");
                }
                Ok(Shape::Plane { point, normal: scale(normal, 1.0 / l) })
            }
            Shape::Sphere { centre, radius } | Shape::Capsule { a: centre, radius, .. } => {
                let ok = finite(&centre) && radius.is_finite() && radius > 0.0;
                let ok = ok && if let Shape::Capsule { b, .. } = self { finite(&b) } else { true };
                if ok { Ok(self) } else { bad("needs finite centres and a positive radius") }
            }
            Shape::Box { min, max } => {
                if finite(&min) && finite(&max) && (0..3).all(|k| min[k] < max[k]) {
                    Ok(self)
                } else {
                    bad("needs finite corners with min < max on every axis")
                }
            }
        }
    }
}

impl Collider for Shape {
    fn query(&self, p: V3) -> (f64, V3) {
        match *self {
            Shape::Plane { point, normal } => (dot(sub(p, point), normal), normal),
            Shape::Sphere { centre, radius } => {
                let d = sub(p, centre);
                (length(d) - radius, normalize_or(d, [0.0, 0.0, 1.0]))
            }
            Shape::Capsule { a, b, radius } => {
                let ab = sub(b, a);
                let len2 = dot(ab, ab);
                let t = if len2 > 0.0 { (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
                let d = sub(p, add(a, scale(ab, t)));
                (length(d) - radius, normalize_or(d, [0.0, 0.0, 1.0]))
            }
            Shape::Box { min, max } => box_distance(p, min, max),
        }
    }
}

/// Signed distance to an axis-aligned box and its gradient.
fn box_distance(p: V3, min: V3, max: V3) -> (f64, V3) {
    let centre = scale(add(min, max), 0.5);
    let half = scale(sub(max, min), 0.5);
    let q: V3 = [0, 1, 2].map(|k| (p[k] - centre[k]).abs() - half[k]);
    let sign: V3 = [0, 1, 2].map(|k| if p[k] >= centre[k] { 1.0 } else { -1.0 });
    let outside: V3 = q.map(|v| v.max(0.0));
    let lo = length(outside);
    if lo > 0.0 {
        let n = [0, 1, 2].map(|k| outside[k] * sign[k] / lo);
        return (lo, n);
    }
    // Inside: the nearest face.
    let k = (0..3).max_by(|&i, &j| q[i].total_cmp(&q[j])).unwrap_or(2);
    let mut n = [0.0; 3];
    n[k] = sign[k];
    (q[k], n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_and_normals_are_exact() {
        let table = Shape::Box { min: [-0.5, -0.5, -0.05], max: [0.5, 0.5, 0.0] };
        assert_eq!(table.query([0.1, 0.2, 0.03]), (0.03, [0.0, 0.0, 1.0]));
        let (d, n) = table.query([0.1, 0.2, -0.01]);
        assert!((d + 0.01).abs() < 1e-12 && n == [0.0, 0.0, 1.0]);
        // Beyond the edge: distance to the edge line.
        let (d, n) = table.query([0.53, 0.0, 0.04]);
        assert!(
            (d - 0.05).abs() < 1e-12 && (n[0] - 0.6).abs() < 1e-12 && (n[2] - 0.8).abs() < 1e-12
        );
        let arm = Shape::Capsule { a: [0.0, -1.0, 0.0], b: [0.0, 1.0, 0.0], radius: 0.05 };
        let (d, n) = arm.query([0.0, 0.3, 0.08]);
        assert!((d - 0.03).abs() < 1e-12 && (n[2] - 1.0).abs() < 1e-12);
        let (d, _) = arm.query([0.0, 1.1, 0.0]);
        assert!((d - 0.05).abs() < 1e-12);
        let ball = Shape::Sphere { centre: [0.0; 3], radius: 0.1 };
        assert!((ball.query([0.0, 0.3, 0.4]).0 - 0.4).abs() < 1e-12);
        let floor = Shape::Plane { point: [0.0; 3], normal: [0.0, 0.0, 2.0] }.validated().unwrap();
        assert_eq!(floor.query([1.0, 2.0, -0.25]), (-0.25, [0.0, 0.0, 1.0]));
        assert!(Shape::Sphere { centre: [0.0; 3], radius: -1.0 }.validated().is_err());
        assert!(Shape::Box { min: [0.0; 3], max: [1.0, 0.0, 1.0] }.validated().is_err());
    }
}
