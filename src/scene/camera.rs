//! The pinhole camera of the scene format: image orientation and the ray through any point of
//! the image plane.

use glam::Vec3;

/// A pinhole camera. Pixel (0, 0) is the top-left corner; `up` points to the top of the image
/// and the image's right is forward × up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    /// A point the camera looks at.
    pub look_at: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y: f32,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
}

/// Largest image side accepted: keeps width × height allocations sane.
pub(crate) const MAX_IMAGE_SIDE: u32 = 32768;

impl Camera {
    /// An error if this camera cannot make an image: for renderers, since a host may change a
    /// loaded scene's camera.
    pub(crate) fn check(&self) -> crate::error::Result<()> {
        match self.problem() {
            Some(problem) => Err(crate::error::Error::Option {
                option: "camera",
                problem,
            }),
            None => Ok(()),
        }
    }

    /// Why this camera cannot make an image, if it cannot.
    pub fn problem(&self) -> Option<String> {
        let finite = self.position.is_finite() && self.look_at.is_finite() && self.up.is_finite();
        if !finite {
            return Some("camera position, look_at and up must be finite numbers".into());
        }
        if self.width == 0 || self.height == 0 {
            return Some(format!(
                "camera image size {}x{} is empty: width and height must be at least 1",
                self.width, self.height
            ));
        }
        if self.width > MAX_IMAGE_SIDE || self.height > MAX_IMAGE_SIDE {
            return Some(format!(
                "camera image size {}x{} is too large (at most {MAX_IMAGE_SIDE} per side)",
                self.width, self.height
            ));
        }
        if !(self.fov_y > 0.0 && self.fov_y < 180.0) {
            return Some(format!(
                "camera fov_y = {} degrees: it must lie strictly between 0 and 180",
                self.fov_y
            ));
        }
        let forward = self.look_at - self.position;
        let scale = self
            .position
            .abs()
            .max(self.look_at.abs())
            .max_element()
            .max(1e-30);
        if forward.length() <= 1e-6 * scale {
            return Some(
                "camera look_at equals its position: the view direction is undefined".into(),
            );
        }
        let cross = forward.normalize().cross(self.up.normalize_or_zero());
        if cross.length() < 1e-4 {
            return Some("camera up is zero or parallel to the view direction".into());
        }
        None
    }

    /// Orthonormal frame: (forward, right, up), right = forward × up.
    pub fn frame(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        (forward, right, up)
    }

    /// Unit direction of the ray through image point (x, y), in pixels from the top-left corner
    /// (pixel centres sit at half-integers).
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        let (forward, right, up) = self.frame();
        let tan_half = (self.fov_y.to_radians() * 0.5).tan();
        let h = self.height as f32;
        let sx = (2.0 * x - self.width as f32) / h * tan_half;
        let sy = (h - 2.0 * y) / h * tan_half;
        (forward + sx * right + sy * up).normalize()
    }

    /// One ray through each pixel's centre, row by row from the top-left: the points a
    /// rendered image's pixels see, for measuring an image region by region.
    pub fn pixel_centres(&self) -> impl Iterator<Item = crate::visibility::Ray> + '_ {
        let w = self.width as usize;
        (0..w * self.height as usize).map(move |p| crate::visibility::Ray {
            origin: self.position,
            dir: self.direction((p % w) as f32 + 0.5, (p / w) as f32 + 0.5),
            t_min: 0.0,
            t_max: f32::INFINITY,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            position: Vec3::ZERO,
            look_at: Vec3::Z,
            up: Vec3::Y,
            fov_y: 90.0,
            width: 200,
            height: 100,
        }
    }

    #[test]
    fn image_right_is_forward_cross_up_and_top_is_up() {
        let c = camera();
        // Looking along +z with +y up, +x is on the image's left (`docs/scene-format.md`, "What the image means").
        let left = c.direction(0.0, 50.0);
        assert!(
            (left - Vec3::new(2.0, 0.0, 1.0).normalize()).length() < 1e-6,
            "{left}"
        );
        let top = c.direction(100.0, 0.0);
        assert!(
            (top - Vec3::new(0.0, 1.0, 1.0).normalize()).length() < 1e-6,
            "{top}"
        );
        let centre = c.direction(100.0, 50.0);
        assert!((centre - Vec3::Z).length() < 1e-6);
        // Pixels are square: the image is twice as wide as tall at 90° vertical fov.
        let right_edge = c.direction(200.0, 50.0);
        assert!((right_edge - Vec3::new(-2.0, 0.0, 1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn degenerate_cameras_are_refused() {
        let ok = camera();
        assert_eq!(ok.problem(), None);
        assert!(Camera { width: 0, ..ok }
            .problem()
            .unwrap()
            .contains("empty"));
        assert!(Camera { fov_y: 180.0, ..ok }
            .problem()
            .unwrap()
            .contains("fov_y"));
        assert!(Camera {
            look_at: Vec3::ZERO,
            ..ok
        }
        .problem()
        .unwrap()
        .contains("look_at"));
        assert!(Camera { up: Vec3::Z, ..ok }
            .problem()
            .unwrap()
            .contains("parallel"));
        assert!(Camera {
            up: Vec3::ZERO,
            ..ok
        }
        .problem()
        .unwrap()
        .contains("parallel"));
        let nan = Camera {
            position: Vec3::new(f32::NAN, 0.0, 0.0),
            ..ok
        };
        assert!(nan.problem().unwrap().contains("finite"));
    }
}
