//! [`Camera`]: a pinhole camera looking from `eye` at `target`, and the one primary-ray
//! convention every renderer (CPU and GPU) uses.

use glam::{Vec2, Vec3};

use crate::{Error, Result};

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Approximate up direction (orthogonalized against the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f32,
}

/// The camera's orthonormal frame and the image-plane scale, precomputed for ray generation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrame {
    /// Eye position.
    pub eye: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Unit right vector scaled by tan(fov/2)·aspect.
    pub right: Vec3,
    /// Unit up vector scaled by tan(fov/2).
    pub up: Vec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A look-at camera.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, fov_y_deg: f32) -> Self {
        Self { eye, target, up, fov_y_deg }
    }

    /// A camera at `eye` looking at `target` that sees the sphere `(center, radius)` whole:
    /// the eye is moved along the view direction until the sphere fits the vertical FOV.
    pub fn framing(direction: Vec3, center: Vec3, radius: f32, fov_y_deg: f32) -> Self {
        let half = (fov_y_deg.to_radians() * 0.5).sin().max(1e-3);
        let dist = radius / half * 1.05;
        let dir = direction.try_normalize().unwrap_or(Vec3::Z);
        let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
        Self { eye: center + dir * dist, target: center, up, fov_y_deg }
    }

    /// Checks that the camera defines a frame: finite vectors, eye ≠ target, up not parallel
    /// to the view direction, FOV in (0, 180) degrees.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, value: String, reason: &str| {
            Err(Error::InvalidParameter { name: name.into(), value, reason: reason.into() })
        };
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return bad("camera", format!("{self:?}"), "eye, target and up must be finite");
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return bad("camera fov", self.fov_y_deg.to_string(), "must be in (0, 180) degrees");
        }
        let forward = self.target - self.eye;
        if forward.length_squared() <= f32::MIN_POSITIVE {
            return bad("camera target", format!("{}", self.target), "equals the eye position");
        }
        if forward.normalize().cross(self.up).length_squared() < 1e-12 {
            return bad("camera up", format!("{}", self.up), "is parallel to the view direction");
        }
        Ok(())
    }

    /// The frame for an image of `width × height` pixels. Call [`Camera::validate`] first:
    /// a degenerate camera gives a frame with NaNs.
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let tan = (self.fov_y_deg.to_radians() * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        CameraFrame {
            eye: self.eye,
            forward,
            right: right * tan * aspect,
            up: up * tan,
            width,
            height,
        }
    }
}

impl CameraFrame {
    /// The unit direction of the primary ray through image point `p`, in pixels from the
    /// image's top-left corner (`(x + 0.5, y + 0.5)` is the centre of pixel `(x, y)`).
    #[inline]
    pub fn ray_dir(&self, p: Vec2) -> Vec3 {
        let ndc_x = 2.0 * p.x / self.width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * p.y / self.height as f32;
        (self.forward + self.right * ndc_x + self.up * ndc_y).normalize()
    }

    /// The image point a world position projects to (pixels from the top-left), and its depth
    /// along the view direction; `None` behind the eye.
    pub fn project(&self, world: Vec3) -> Option<(Vec2, f32)> {
        let d = world - self.eye;
        let depth = d.dot(self.forward);
        if depth <= 0.0 {
            return None;
        }
        let x = d.dot(self.right) / self.right.length_squared() / depth;
        let y = d.dot(self.up) / self.up.length_squared() / depth;
        Some((
            Vec2::new((x + 1.0) * 0.5 * self.width as f32, (1.0 - y) * 0.5 * self.height as f32),
            depth,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_target_and_projection_inverts_it() {
        let cam =
            Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0);
        cam.validate().unwrap();
        let f = cam.frame(64, 32);
        assert!((f.ray_dir(Vec2::new(32.0, 16.0)) - Vec3::NEG_Z).length() < 1e-6);
        // Top-left corner ray goes left and up.
        let d = f.ray_dir(Vec2::ZERO);
        assert!(d.x < 0.0 && d.y > 0.0);
        let p = Vec2::new(10.5, 3.5);
        let world = f.eye + f.ray_dir(p) * 7.0;
        let (q, _) = f.project(world).unwrap();
        assert!((p - q).length() < 1e-3, "{p} vs {q}");
    }

    #[test]
    fn degenerate_cameras_are_rejected() {
        assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0).validate().is_err());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0).validate().is_err());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::X, Vec3::Y, 180.0).validate().is_err());
        assert!(Camera::look_at(Vec3::NAN, Vec3::X, Vec3::Y, 40.0).validate().is_err());
    }
}
