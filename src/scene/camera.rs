//! A pinhole camera: eye, target, up and vertical field of view.

use super::Scene;
use crate::error::{Error, Result};
use crate::geometry::{in_range, MAX_COORDINATE};
use glam::Vec3;

/// The vertical field of view, in degrees, of a camera that names none: a `[camera]` without
/// `fov`, a scene with no camera (framed by [`fitted_camera`]).
pub const DEFAULT_FOV: f32 = 40.0;

/// Where the camera is and where it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position of the pinhole.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
}

/// A camera prepared for a given image size: generates primary rays.
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    width: f32,
    height: f32,
}

impl Camera {
    /// Checks the camera and prepares it for a `width`×`height` image.
    pub fn prepare(&self, width: u32, height: u32) -> Result<CameraRays> {
        let bad = |f: &str, m: &str| Err(Error::setting(f, m));
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return bad("camera", "eye, target and up must be finite");
        }
        if !in_range(self.eye) {
            return Err(Error::setting(
                "camera.eye",
                format!(
                    "{} is outside ±{MAX_COORDINATE:e}, the range photonwave supports (a camera fitted to a \
                     scene this large lies there too: scale the scene down with `scale` in the scene file)",
                    self.eye
                ),
            ));
        }
        let Some(forward) = (self.target - self.eye).try_normalize() else {
            return bad("camera.target", "target must differ from eye");
        };
        let Some(right) = forward.cross(self.up).try_normalize() else {
            return bad("camera.up", "up must not be parallel to the view direction");
        };
        if !(self.fov_deg > 0.0 && self.fov_deg < 179.0) {
            return bad("fov", "vertical field of view must be between 0 and 179 degrees");
        }
        let up = right.cross(forward);
        let tan_half = (self.fov_deg.to_radians() * 0.5).tan();
        let aspect = width as f32 / height as f32;
        Ok(CameraRays {
            eye: self.eye,
            forward,
            right: right * tan_half * aspect,
            up: up * tan_half,
            width: width as f32,
            height: height as f32,
        })
    }
}

impl CameraRays {
    /// Origin and unit direction of the ray through film position (x, y) in pixels, y down.
    #[must_use]
    pub fn ray(&self, x: f32, y: f32) -> (Vec3, Vec3) {
        let sx = 2.0 * x / self.width - 1.0;
        let sy = 1.0 - 2.0 * y / self.height;
        (self.eye, (self.forward + self.right * sx + self.up * sy).normalize())
    }
}

/// A camera that frames the bounding sphere of the scene's triangles from +z, looking down −z, for an image of
/// `aspect` = width / height: the sphere fits the narrower of the two fields of view.
#[must_use]
pub fn fitted_camera(scene: &Scene, fov_deg: f32, aspect: f32) -> Camera {
    fitted_camera_to(scene.mesh_bounds(), fov_deg, aspect)
}

/// [`fitted_camera`] for a bounding box (lo, hi).
#[must_use]
pub fn fitted_camera_to((lo, hi): (Vec3, Vec3), fov_deg: f32, aspect: f32) -> Camera {
    let c = (lo + hi) * 0.5;
    let r = ((hi - lo) * 0.5).length().max(f32::MIN_POSITIVE);
    let half_v = fov_deg.to_radians() * 0.5;
    let half = if aspect >= 1.0 { half_v } else { (half_v.tan() * aspect).atan() };
    let dist = r / half.sin() * 1.05;
    Camera { eye: c + Vec3::Z * dist, target: c, up: Vec3::Y, fov_deg }
}
