//! A parametric mannequin: torso, neck, head, arms and legs as a smooth union of implicit
//! primitives — the torso a stack of ellipses swept along the height (girths at hip, waist,
//! chest; sloping shoulders up to the neck base), limbs as tapered capsules in an A-pose,
//! the head an ellipsoid — meshed closed and manifold by marching tetrahedra
//! ([`super::isosurface`]), with a signed distance grid ([`super::sdf`]) as the collision
//! proxy of the drape.
//!
//! Sizes S, M, L or four measurements (height and the chest, waist and hip girths) set
//! every other length by ordinary anthropometric proportions of the height. World `+z` is
//! up from the floor, the body faces `−y`, its left side is at `+x`. UVs are cylindrical
//! about the `z` axis (one unit per metre, the cut at the back) — the body carries a
//! neutral material whose look does not depend on them.

use super::isosurface::{improve, marching_tetrahedra};
use super::sdf::SdfGrid;
use crate::mesh::Mesh;
use crate::vec3::{V3, add, dot, length, scale, sub};
use crate::{Error, Result};
use std::f64::consts::PI;

/// A garment size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Size {
    /// Small.
    S,
    /// Medium.
    M,
    /// Large.
    L,
}

impl Size {
    /// Parses `S`, `M` or `L` (either case).
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "S" | "s" => Ok(Size::S),
            "M" | "m" => Ok(Size::M),
            "L" | "l" => Ok(Size::L),
            other => Err(Error::Invalid(format!("size '{other}' (known: S, M, L)"))),
        }
    }
}

/// Body measurements (metres; girths are circumferences).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurements {
    /// Standing height.
    pub height_m: f64,
    /// Chest girth under the arms.
    pub chest_m: f64,
    /// Waist girth.
    pub waist_m: f64,
    /// Hip girth over the seat.
    pub hip_m: f64,
}

impl Measurements {
    /// The measurements of a size.
    pub fn of(size: Size) -> Self {
        let (height_m, chest_m, waist_m, hip_m) = match size {
            Size::S => (1.68, 0.90, 0.76, 0.93),
            Size::M => (1.76, 0.98, 0.84, 1.00),
            Size::L => (1.84, 1.07, 0.95, 1.08),
        };
        Measurements { height_m, chest_m, waist_m, hip_m }
    }

    /// Refuses measurements no body has, naming the parameter.
    pub fn validate(&self) -> Result<()> {
        let check = |name: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(Error::Invalid(format!(
                    "body {name} (--{name}) = {v} m is outside {lo} … {hi} m"
                )))
            }
        };
        check("height", self.height_m, 1.2, 2.2)?;
        check("chest", self.chest_m, 0.5, 1.6)?;
        check("waist", self.waist_m, 0.45, 1.6)?;
        check("hip", self.hip_m, 0.5, 1.7)?;
        let h = self.height_m;
        for (name, g) in [("chest", self.chest_m), ("waist", self.waist_m), ("hip", self.hip_m)] {
            if g > 0.85 * h || g < 0.3 * h {
                return Err(Error::Invalid(format!(
                    "body {name} (--{name}) = {g} m does not fit a height of {h} m (expected {:.2} … {:.2} m)",
                    0.3 * h,
                    0.85 * h
                )));
            }
        }
        Ok(())
    }
}

/// Landmarks of the mannequin (metres, world frame), for placing panels and checking fits.
#[derive(Debug, Clone, PartialEq)]
pub struct Landmarks {
    /// Top of the torso where the neck starts.
    pub neck_base_z: f64,
    /// Neck radius.
    pub neck_radius: f64,
    /// Shoulder points (left `+x`, right `−x`).
    pub shoulder: [V3; 2],
    /// Height of the armpits.
    pub armpit_z: f64,
    /// Height of the chest girth.
    pub chest_z: f64,
    /// Height of the waist girth.
    pub waist_z: f64,
    /// Height of the hip girth.
    pub hip_z: f64,
    /// Height of the crotch.
    pub crotch_z: f64,
    /// Half-width and half-depth of the torso at the chest, waist and hip.
    pub chest_ab: [f64; 2],
    /// Waist half-width, half-depth.
    pub waist_ab: [f64; 2],
    /// Hip half-width, half-depth.
    pub hip_ab: [f64; 2],
    /// Shoulder joint, elbow and wrist of each arm (left, right).
    pub arm: [[V3; 3]; 2],
    /// Radii of the arm at the shoulder joint, elbow and wrist.
    pub arm_radius: [f64; 3],
    /// Hip joint, knee and ankle of each leg (left, right).
    pub leg: [[V3; 3]; 2],
    /// Radii of the leg at the hip joint, knee and ankle.
    pub leg_radius: [f64; 3],
    /// Standing height.
    pub height: f64,
}

/// How to build the mannequin.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyParams {
    /// Measurements.
    pub measurements: Measurements,
    /// Arm angle from the vertical (degrees; an A-pose).
    pub arm_angle_deg: f64,
    /// Leg angle from the vertical (degrees).
    pub leg_angle_deg: f64,
    /// Grid step of the mesh (m).
    pub mesh_step_m: f64,
    /// Grid step of the collision distance field (m).
    pub sdf_step_m: f64,
}

impl BodyParams {
    /// Defaults for a size: arms 45° and legs 4° from the vertical, a 12 mm mesh and a
    /// 6 mm distance grid.
    pub fn new(size: Size) -> Self {
        BodyParams {
            measurements: Measurements::of(size),
            arm_angle_deg: 45.0,
            leg_angle_deg: 4.0,
            mesh_step_m: 0.012,
            sdf_step_m: 0.006,
        }
    }
}

/// The mannequin: its mesh, collision proxy and landmarks.
#[derive(Debug, Clone)]
pub struct Body {
    /// Closed manifold mesh (UVs cylindrical, one unit per metre).
    pub mesh: Mesh,
    /// Signed distance to the surface (negative inside), on a grid.
    pub sdf: SdfGrid,
    /// Landmarks (from the parameters; absent for a body read from a file).
    pub landmarks: Option<Landmarks>,
}

/// Ellipse semi-axes `(a, a·ρ)` of girth `g` (Ramanujan's perimeter).
fn ellipse_of_girth(g: f64, rho: f64) -> [f64; 2] {
    let k = PI * (3.0 * (1.0 + rho) - ((3.0 + rho) * (1.0 + 3.0 * rho)).sqrt());
    let a = g / k;
    [a, a * rho]
}

/// Polynomial smooth minimum of blend width `k`.
fn smin(a: f64, b: f64, k: f64) -> f64 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

fn smax(a: f64, b: f64, k: f64) -> f64 {
    -smin(-a, -b, k)
}

/// Distance to a capsule from `a` to `b` whose radius goes from `ra` to `rb`.
fn tapered_capsule(p: V3, a: V3, b: V3, ra: f64, rb: f64) -> f64 {
    let ab = sub(b, a);
    let t = (dot(sub(p, a), ab) / dot(ab, ab)).clamp(0.0, 1.0);
    length(sub(p, add(a, scale(ab, t)))) - (ra + (rb - ra) * t)
}

/// Approximate signed distance to an ellipse of semi-axes `a, b` in the plane.
fn ellipse_distance(x: f64, y: f64, a: f64, b: f64) -> f64 {
    let r = ((x / a).powi(2) + (y / b).powi(2)).sqrt();
    let g = ((x / (a * a)).powi(2) + (y / (b * b)).powi(2)).sqrt();
    if g < 1e-9 { -a.min(b) } else { r * (r - 1.0) / g }
}

fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The implicit mannequin.
#[derive(Debug, Clone)]
pub struct Mannequin {
    /// Its landmarks.
    pub landmarks: Landmarks,
    /// Torso sections `(z, a, b)` from the crotch to the neck base.
    sections: Vec<[f64; 3]>,
    head_centre: V3,
    head_radii: V3,
    feet: [[V3; 2]; 2],
}

impl Mannequin {
    /// The mannequin of `p`'s measurements and pose.
    pub fn new(p: &BodyParams) -> Result<Self> {
        let m = &p.measurements;
        m.validate()?;
        for (name, v, lo, hi) in [
            ("arm angle", p.arm_angle_deg, 20.0, 80.0),
            ("leg angle", p.leg_angle_deg, 0.0, 15.0),
            ("mesh step", p.mesh_step_m, 0.003, 0.05),
            ("sdf step", p.sdf_step_m, 0.002, 0.03),
        ] {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return Err(Error::Invalid(format!("body {name} = {v} is outside {lo} … {hi}")));
            }
        }
        let h = m.height_m;
        let s = h / 1.76;
        // Girth scale for the limbs and neck (a heavier chest, thicker limbs).
        let g = (m.chest_m / 0.98).sqrt();
        let chest_ab = ellipse_of_girth(m.chest_m, 0.68);
        let waist_ab = ellipse_of_girth(m.waist_m, 0.74);
        let hip_ab = ellipse_of_girth(m.hip_m, 0.72);
        let neck_radius = 0.058 * g * s.sqrt();
        let (crotch_z, hip_z, waist_z, chest_z) = (0.468 * h, 0.505 * h, 0.61 * h, 0.72 * h);
        let (armpit_z, shoulder_z, neck_base_z) = (0.745 * h, 0.815 * h, 0.842 * h);
        let shoulder_half = (0.113 * h).max(chest_ab[0] + 0.02);
        let upper_r = 0.05 * g * s;
        let sections = vec![
            [crotch_z - 0.03 * s, 0.82 * hip_ab[0], 0.80 * hip_ab[1]],
            [crotch_z + 0.03 * s, 0.97 * hip_ab[0], 0.96 * hip_ab[1]],
            [hip_z, hip_ab[0], hip_ab[1]],
            [waist_z, waist_ab[0], waist_ab[1]],
            [chest_z, chest_ab[0], chest_ab[1]],
            [armpit_z, 0.97 * chest_ab[0], 0.98 * chest_ab[1]],
            [shoulder_z - 0.03 * s, shoulder_half - upper_r * 0.9, 0.80 * chest_ab[1]],
            [shoulder_z + 0.005 * s, 0.60 * (shoulder_half - upper_r), 0.60 * chest_ab[1]],
            [neck_base_z, 1.25 * neck_radius, 1.15 * neck_radius],
        ];
        let arm_angle = p.arm_angle_deg.to_radians();
        let leg_angle = p.leg_angle_deg.to_radians();
        let mut arm = [[[0.0; 3]; 3]; 2];
        let mut leg = [[[0.0; 3]; 3]; 2];
        let mut feet = [[[0.0; 3]; 2]; 2];
        for (i, side) in [1.0f64, -1.0].into_iter().enumerate() {
            let joint = [side * (shoulder_half - upper_r * 0.85), 0.0, shoulder_z - 0.045 * s];
            let dir = [side * arm_angle.sin(), 0.0, -arm_angle.cos()];
            let elbow = add(joint, scale(dir, 0.186 * h));
            let wrist = add(elbow, scale(dir, 0.146 * h));
            arm[i] = [joint, elbow, wrist];
            let hip_joint = [side * 0.52 * hip_ab[0], 0.0, crotch_z + 0.06 * s];
            let ldir = [side * leg_angle.sin(), 0.0, -leg_angle.cos()];
            let knee_len = (hip_joint[2] - 0.285 * h) / leg_angle.cos();
            let knee = add(hip_joint, scale(ldir, knee_len));
            let ankle_len = (0.285 * h - 0.055 * h) / leg_angle.cos();
            let ankle = add(knee, scale(ldir, ankle_len));
            leg[i] = [hip_joint, knee, ankle];
            feet[i] = [
                [ankle[0], ankle[1] + 0.03 * s, 0.03 * s],
                [ankle[0] + side * 0.02 * s, ankle[1] - 0.15 * s, 0.025 * s],
            ];
        }
        let landmarks = Landmarks {
            neck_base_z,
            neck_radius,
            shoulder: [[shoulder_half, 0.0, shoulder_z], [-shoulder_half, 0.0, shoulder_z]],
            armpit_z,
            chest_z,
            waist_z,
            hip_z,
            crotch_z,
            chest_ab,
            waist_ab,
            hip_ab,
            arm,
            arm_radius: [upper_r, 0.041 * g * s, 0.029 * g * s],
            leg,
            leg_radius: [0.60 * hip_ab[0], 0.058 * g * s, 0.036 * g * s],
            height: h,
        };
        Ok(Mannequin {
            landmarks,
            sections,
            head_centre: [0.0, 0.01 * s, 0.932 * h],
            head_radii: [0.077 * s, 0.095 * s, 0.112 * s],
            feet,
        })
    }

    /// Torso half-width and half-depth at height `z` (clamped to the torso's range).
    pub fn torso_section(&self, z: f64) -> [f64; 2] {
        let s = &self.sections;
        let z = z.clamp(s[0][0], s[s.len() - 1][0]);
        let i = s.windows(2).position(|w| z <= w[1][0]).unwrap_or(s.len() - 2);
        let t = smoothstep((z - s[i][0]) / (s[i + 1][0] - s[i][0]));
        [s[i][1] + (s[i + 1][1] - s[i][1]) * t, s[i][2] + (s[i + 1][2] - s[i][2]) * t]
    }

    /// Approximate signed distance (negative inside).
    pub fn field(&self, p: V3) -> f64 {
        let l = &self.landmarks;
        let s = l.height / 1.76;
        let [a, b] = self.torso_section(p[2]);
        let z0 = self.sections[0][0];
        let z1 = self.sections[self.sections.len() - 1][0];
        let torso = smax(
            smax(ellipse_distance(p[0], p[1], a, b), z0 - p[2], 0.04 * s),
            p[2] - z1,
            0.02 * s,
        );
        let neck = tapered_capsule(
            p,
            [0.0, 0.0, l.neck_base_z - 0.04 * s],
            [0.0, 0.008 * s, l.neck_base_z + 0.09 * s],
            l.neck_radius * 1.05,
            l.neck_radius * 0.95,
        );
        let q = sub(p, self.head_centre);
        let hr = self.head_radii;
        let kq = length([q[0] / hr[0], q[1] / hr[1], q[2] / hr[2]]);
        let head = (kq - 1.0) * hr[0].min(hr[1]).min(hr[2]);
        let mut d = smin(torso, neck, 0.03 * s);
        d = smin(d, head, 0.04 * s);
        let [r0, r1, r2] = l.arm_radius;
        for i in 0..2 {
            let [j, e, w] = l.arm[i];
            let upper = tapered_capsule(p, j, e, r0, r1);
            let fore = tapered_capsule(p, e, w, r1, r2);
            let dir = scale(sub(w, e), 1.0 / length(sub(w, e)));
            let hand = tapered_capsule(p, w, add(w, scale(dir, 0.15 * s)), r2 * 1.05, r2 * 0.8);
            let limb = smin(smin(upper, fore, 0.02 * s), hand, 0.02 * s);
            d = smin(d, limb, 0.035 * s);
            let [hj, k, an] = l.leg[i];
            let [q0, q1, q2] = l.leg_radius;
            let thigh = tapered_capsule(p, hj, k, q0, q1);
            let shin = tapered_capsule(p, k, an, q1 * 1.02, q2);
            let [f0, f1] = self.feet[i];
            let foot = tapered_capsule(p, f0, f1, 0.033 * s, 0.028 * s);
            let limb = smin(
                smin(thigh, shin, 0.03 * s),
                smin(foot, tapered_capsule(p, an, f0, q2, 0.033 * s), 0.02 * s),
                0.03 * s,
            );
            d = smin(d, limb, 0.03 * s);
        }
        d
    }

    /// Bounding box of the body with a margin.
    pub fn bounds(&self) -> (V3, V3) {
        let l = &self.landmarks;
        let reach = l.arm[0][2][0] + 0.2 * l.height / 1.76;
        ([-reach, -0.35 * l.height / 1.76, -0.02], [reach, 0.3 * l.height / 1.76, l.height + 0.03])
    }
}

impl Body {
    /// Builds the mannequin of `p`: mesh and distance grid.
    pub fn new(p: &BodyParams) -> Result<Body> {
        let man = Mannequin::new(p)?;
        let f = |q: V3| man.field(q);
        let (lo, hi) = man.bounds();
        let (mut positions, mut triangles) = marching_tetrahedra(&f, lo, hi, p.mesh_step_m);
        improve(&f, &mut positions, &mut triangles, 4, 1e-4);
        let mut mesh = Mesh { positions, triangles, ..Default::default() };
        cylindrical_uvs(&mut mesh);
        mesh.compute_normals();
        let sdf = SdfGrid::from_mesh(&mesh, p.sdf_step_m, 0.04)?;
        Ok(Body { mesh, sdf, landmarks: Some(man.landmarks) })
    }

    /// A body from a closed mesh (read from a file): refused unless closed and manifold.
    pub fn from_mesh(mut mesh: Mesh, sdf_step_m: f64) -> Result<Body> {
        let (boundary, non_manifold) = mesh.edge_counts();
        if boundary > 0 || non_manifold > 0 {
            return Err(Error::Invalid(format!(
                "--body: the mesh is not closed ({boundary} boundary edges, {non_manifold} non-manifold edges)"
            )));
        }
        if mesh.normals.len() != mesh.positions.len() {
            mesh.compute_normals();
        }
        let sdf = SdfGrid::from_mesh(&mesh, sdf_step_m, 0.04)?;
        Ok(Body { mesh, sdf, landmarks: None })
    }
}

/// Cylindrical UVs about the `z` axis: `u` = arc length at radius 0.15 m from the back,
/// `v = z`; triangles across the cut at the back get their own UVs.
fn cylindrical_uvs(mesh: &mut Mesh) {
    let r = 0.15;
    let period = 2.0 * PI * r;
    mesh.uvs = mesh.positions.iter().map(|p| [r * (p[0].atan2(-p[1]) + PI), p[2]]).collect();
    mesh.triangle_uvs = mesh.triangles.clone();
    let n = mesh.triangles.len();
    for t in 0..n {
        let us = mesh.triangle_uvs[t].map(|i| mesh.uvs[i as usize][0]);
        let max = us.iter().copied().fold(f64::MIN, f64::max);
        if max - us.iter().copied().fold(f64::MAX, f64::min) > 0.5 * period {
            for k in 0..3 {
                if us[k] < 0.5 * period {
                    let mut uv = mesh.uvs[mesh.triangle_uvs[t][k] as usize];
                    uv[0] += period;
                    mesh.uvs.push(uv);
                    mesh.triangle_uvs[t][k] = (mesh.uvs.len() - 1) as u32;
                }
            }
        }
    }
}
