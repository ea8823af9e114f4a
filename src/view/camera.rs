//! Orbit / zoom / pan camera of `btf view` and the light drag: the scene camera written as
//! a target, a distance and two angles about the scene's up axis, so that a mouse drag maps
//! to angles and a wheel step to a distance factor. The same spherical motion turns a light
//! (point-light position about the target, or a directional light's direction).
//!
//! No equation of the paper lives here; this is interaction geometry.

use btf_render::scene::{Camera, Light};

/// Degrees of turn per pixel of mouse drag.
pub const DEG_PER_PIXEL: f32 = 0.4;
/// Distance factor per wheel line (`exp(-ZOOM_PER_LINE)` closer).
pub const ZOOM_PER_LINE: f32 = 0.1;
/// Elevation limit, degrees (keeps the view off the pole where the up vector degenerates).
const MAX_PITCH_DEG: f32 = 89.0;

type V3 = [f32; 3];

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: V3, s: f32) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn norm(a: V3) -> f32 {
    dot(a, a).sqrt()
}
fn unit(a: V3) -> V3 {
    let n = norm(a);
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}

/// An orthonormal frame about an up axis: `(east, up, north)` with `east = up × north`.
#[derive(Debug, Clone, Copy)]
struct UpFrame {
    east: V3,
    up: V3,
    north: V3,
}

impl UpFrame {
    /// The frame whose `north` is the part of `v` perpendicular to `up` (any, if none).
    fn new(up: V3, v: V3) -> UpFrame {
        let up = unit(up);
        let mut north = sub(v, scale(up, dot(v, up)));
        if norm(north) < 1e-6 * norm(v).max(1e-12) {
            north = if up[0].abs() < 0.9 { cross(up, [1.0, 0.0, 0.0]) } else { [0.0, 0.0, 1.0] };
        }
        let north = unit(north);
        UpFrame { east: cross(up, north), up, north }
    }

    /// Azimuth (from north towards east) and elevation of `v`, degrees, and its length.
    fn angles(&self, v: V3) -> (f32, f32, f32) {
        let r = norm(v).max(1e-12);
        let yaw = dot(v, self.east).atan2(dot(v, self.north)).to_degrees();
        let pitch = (dot(v, self.up) / r).clamp(-1.0, 1.0).asin().to_degrees();
        (yaw, pitch, r)
    }

    /// The vector of length `r` at azimuth `yaw_deg` and elevation `pitch_deg`.
    fn vector(&self, yaw_deg: f32, pitch_deg: f32, r: f32) -> V3 {
        let (y, p) = (yaw_deg.to_radians(), pitch_deg.to_radians());
        let horizontal = add(scale(self.north, y.cos()), scale(self.east, y.sin()));
        scale(add(scale(horizontal, p.cos()), scale(self.up, p.sin())), r)
    }
}

/// Turns `v` by `d_yaw_deg` about `up` and raises it by `d_pitch_deg` (elevation clamped
/// to ±89°); its length is kept.
pub fn turn(v: V3, up: V3, d_yaw_deg: f32, d_pitch_deg: f32) -> V3 {
    let frame = UpFrame::new(up, v);
    let (yaw, pitch, r) = frame.angles(v);
    let pitch = (pitch + d_pitch_deg).clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
    frame.vector(yaw + d_yaw_deg, pitch, r)
}

/// The interactive camera: the scene camera plus the orbit state.
#[derive(Debug, Clone)]
pub struct Orbit {
    /// The camera as the scene file gave it (for reset).
    pub home: Camera,
    /// The current camera.
    pub camera: Camera,
}

impl Orbit {
    /// Starts at the scene's camera.
    pub fn new(camera: &Camera) -> Orbit {
        Orbit { home: camera.clone(), camera: camera.clone() }
    }

    /// Back to the scene's camera.
    pub fn reset(&mut self) {
        self.camera = self.home.clone();
    }

    /// Eye offset from the target.
    fn offset(&self) -> V3 {
        sub(self.camera.eye, self.camera.target)
    }

    /// Orbits the eye about the target: `d_yaw_deg` about up, `d_pitch_deg` up/down.
    pub fn orbit(&mut self, d_yaw_deg: f32, d_pitch_deg: f32) {
        let offset = turn(self.offset(), self.camera.up, d_yaw_deg, d_pitch_deg);
        self.camera.eye = add(self.camera.target, offset);
    }

    /// A mouse drag of `(dx, dy)` pixels: right turns the garment right, down tilts it.
    pub fn drag(&mut self, dx_px: f32, dy_px: f32) {
        self.orbit(-dx_px * DEG_PER_PIXEL, dy_px * DEG_PER_PIXEL);
    }

    /// Moves the eye towards the target by `exp(-lines · ZOOM_PER_LINE)` (positive lines:
    /// closer); the distance stays above a thousandth of the start distance.
    pub fn zoom(&mut self, lines: f32) {
        let start = norm(sub(self.home.eye, self.home.target));
        let offset = self.offset();
        let r = norm(offset);
        let r_new = (r * (-lines * ZOOM_PER_LINE).exp()).clamp(start * 1e-3, start * 1e3);
        self.camera.eye = add(self.camera.target, scale(offset, r_new / r.max(1e-12)));
        if self.camera.projection == btf_render::scene::Projection::Orthographic {
            self.camera.ortho_height *= r_new / r.max(1e-12);
        }
    }

    /// Moves eye and target in the image plane so that the point under the cursor follows
    /// a drag of `(dx, dy)` pixels in an image `height_px` high.
    pub fn pan(&mut self, dx_px: f32, dy_px: f32, height_px: f32) {
        let offset = self.offset();
        let r = norm(offset);
        let world_per_px = match self.camera.projection {
            btf_render::scene::Projection::Perspective => {
                2.0 * r * (self.camera.fov_y_deg.to_radians() * 0.5).tan() / height_px.max(1.0)
            }
            btf_render::scene::Projection::Orthographic => {
                self.camera.ortho_height / height_px.max(1.0)
            }
        };
        let forward = unit(scale(offset, -1.0));
        let right = unit(cross(forward, self.camera.up));
        let up = cross(right, forward);
        let shift = add(scale(right, -dx_px * world_per_px), scale(up, dy_px * world_per_px));
        self.camera.eye = add(self.camera.eye, shift);
        self.camera.target = add(self.camera.target, shift);
    }
}

/// Turns a light about the up axis through `pivot` (point lights) or its direction
/// (directional lights): `d_yaw_deg` about up, `d_pitch_deg` in elevation.
pub fn turn_light(light: &mut Light, pivot: V3, up: V3, d_yaw_deg: f32, d_pitch_deg: f32) {
    // `if let` rather than `match`: other kinds of light (an environment) are left alone.
    if let Light::Point { position, .. } = light {
        *position = add(pivot, turn(sub(*position, pivot), up, d_yaw_deg, d_pitch_deg));
    } else if let Light::Directional { direction, .. } = light {
        *direction = turn(*direction, up, d_yaw_deg, d_pitch_deg);
    }
}

/// Turns a light by a drag of `(dx, dy)` pixels (right: about up, up: higher).
pub fn drag_light(light: &mut Light, pivot: V3, up: V3, dx_px: f32, dy_px: f32) {
    turn_light(light, pivot, up, dx_px * DEG_PER_PIXEL, -dy_px * DEG_PER_PIXEL);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            projection: Default::default(),
            eye: [0.3, 1.2, 2.0],
            target: [0.1, 0.2, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 40.0,
            ortho_height: 1.0,
        }
    }

    fn close(a: V3, b: V3, tol: f32) -> bool {
        norm(sub(a, b)) <= tol
    }

    #[test]
    fn full_turn_returns_and_keeps_distance() {
        let mut o = Orbit::new(&camera());
        let r0 = norm(o.offset());
        o.orbit(90.0, 0.0);
        assert!((norm(o.offset()) - r0).abs() < 1e-5);
        // A quarter turn about +y is perpendicular in the horizontal plane.
        let (a, b) = (sub(camera().eye, camera().target), o.offset());
        assert!((a[0] * b[0] + a[2] * b[2]).abs() < 1e-5, "{a:?} {b:?}");
        assert!((a[1] - b[1]).abs() < 1e-5, "height kept");
        for _ in 0..3 {
            o.orbit(90.0, 0.0);
        }
        assert!(close(o.camera.eye, camera().eye, 1e-5), "{:?}", o.camera.eye);
    }

    #[test]
    fn pitch_is_clamped_below_the_pole() {
        let mut o = Orbit::new(&camera());
        o.orbit(0.0, 500.0);
        let (_, pitch, _) = UpFrame::new([0.0, 1.0, 0.0], o.offset()).angles(o.offset());
        assert!((pitch - MAX_PITCH_DEG).abs() < 1e-3, "{pitch}");
    }

    #[test]
    fn drag_pixels_map_to_degrees() {
        let mut o = Orbit::new(&camera());
        let frame = UpFrame::new([0.0, 1.0, 0.0], o.offset());
        let (yaw0, _, _) = frame.angles(o.offset());
        o.drag(100.0, 0.0);
        let (yaw1, _, _) = frame.angles(o.offset());
        assert!((yaw1 - yaw0 + 100.0 * DEG_PER_PIXEL).abs() < 1e-3, "{yaw0} → {yaw1}");
    }

    #[test]
    fn zoom_and_pan_keep_the_view_direction() {
        let mut o = Orbit::new(&camera());
        let dir0 = unit(o.offset());
        let r0 = norm(o.offset());
        o.zoom(5.0);
        assert!((norm(o.offset()) - r0 * (-0.5f32).exp()).abs() < 1e-5);
        o.pan(10.0, -7.0, 240.0);
        assert!(close(unit(o.offset()), dir0, 1e-5));
        assert!(!close(o.camera.target, camera().target, 1e-4), "target moved");
        o.reset();
        assert!(close(o.camera.eye, camera().eye, 0.0));
    }

    #[test]
    fn lights_turn_about_the_pivot() {
        let mut p = Light::Point { position: [1.0, 1.0, 0.0], intensity: [1.0; 3], shadows: true };
        drag_light(&mut p, [0.0, 1.0, 0.0], [0.0, 1.0, 0.0], 90.0 / DEG_PER_PIXEL, 0.0);
        let Light::Point { position, .. } = p else { unreachable!() };
        assert!(close(position, [0.0, 1.0, -1.0], 1e-5), "{position:?}");
        let mut d =
            Light::Directional { direction: [0.0, 0.0, 2.0], irradiance: [1.0; 3], shadows: true };
        drag_light(&mut d, [0.0; 3], [0.0, 1.0, 0.0], 0.0, -30.0 / DEG_PER_PIXEL);
        let Light::Directional { direction, .. } = d else { unreachable!() };
        let want = [0.0, 2.0 * 30f32.to_radians().sin(), 2.0 * 30f32.to_radians().cos()];
        assert!(close(direction, want, 1e-5), "{direction:?}");
    }
}
