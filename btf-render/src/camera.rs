//! The camera of a frame: the scene's `[camera]` turned into world → clip matrices fitted
//! to the mesh (near and far planes around its bounding sphere, moved back for
//! shadow-volume caps), and their GPU mirror ([`CameraSetup::to_raw`]). Every pass that
//! needs the camera reads this one type. No equation of the paper lives here.

use crate::math::{self, Mat4, Vec3, v3};
use crate::scene::{Projection, Scene};
use crate::uniforms::CameraRaw;
use btf_light::mesh::Mesh;

/// Camera matrices and the quantities shaders need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSetup {
    /// World → clip.
    pub view_proj: Mat4,
    /// Eye position.
    pub eye: Vec3,
    /// Direction towards the camera for orthographic projections.
    pub ortho_to_camera: Option<Vec3>,
}

impl CameraSetup {
    /// The scene's camera for `mesh`, with the far plane `extra_depth` further back (shadow
    /// volumes' back caps; 0 otherwise).
    pub fn new(scene: &Scene, mesh: &Mesh, extra_depth: f32) -> CameraSetup {
        let (lo, hi) = mesh.bounds();
        Self::with_bounds(scene, (lo, hi), extra_depth)
    }

    /// The scene's camera with near and far planes around the box `(lo, hi)` (the mesh's
    /// bounds, grown by what overlays draw), the far plane `extra_depth` further back.
    pub fn with_bounds(scene: &Scene, (lo, hi): ([f32; 3], [f32; 3]), extra_depth: f32) -> Self {
        let c = &scene.camera;
        let center = (v3(lo) + v3(hi)) * 0.5;
        let radius = ((v3(hi) - v3(lo)).norm() * 0.5).max(1e-6);
        let (eye, target) = (v3(c.eye), v3(c.target));
        let dir = target - eye;
        let view = math::look_at(eye, target, math::safe_up(dir, v3(c.up)));
        let aspect = scene.output.width as f32 / scene.output.height as f32;
        let dist = (center - eye).norm();
        let far = dist + radius * 1.05 + extra_depth;
        match c.projection {
            Projection::Perspective => {
                let near = (dist - radius * 1.05).max(far * 1e-4);
                CameraSetup {
                    view_proj: math::perspective(c.fov_y_deg, aspect, near, far) * view,
                    eye,
                    ortho_to_camera: None,
                }
            }
            Projection::Orthographic => {
                let near = dist - radius * 1.05 - extra_depth;
                let proj = math::orthographic(c.ortho_height * aspect, c.ortho_height, near, far);
                CameraSetup { view_proj: proj * view, eye, ortho_to_camera: Some(-dir.normalize()) }
            }
        }
    }

    /// The camera part of the frame uniform.
    pub fn to_raw(&self) -> CameraRaw {
        let e = self.eye;
        let mut raw = CameraRaw {
            view_proj: math::to_cols(&self.view_proj),
            eye: [e.x, e.y, e.z, 1.0],
            to_camera: [0.0; 4],
        };
        if let Some(d) = self.ortho_to_camera {
            raw.eye[3] = 0.0;
            raw.to_camera = [d.x, d.y, d.z, 0.0];
        }
        raw
    }
}
