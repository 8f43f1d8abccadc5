//! Perspective and orthographic cameras with pbrt's conventions.
//!
//! ```text
//! LookAt 0 1 5  0 1 0  0 1 0
//! Camera "perspective" "float fov" 40 "float lensradius" 0.05 "float focaldistance" 5
//! Camera "orthographic" "float screenwindow" [-2 2 -1.5 1.5]
//! ```
//! Camera space is left-handed: +x is image right, +y up, +z the viewing direction. The
//! screen window spans [−1, 1] on the image's shorter axis, so `fov` is the full angle
//! of the shorter axis. Raster (0, 0) is the top-left pixel corner and y grows
//! downward. With `LookAt`, world +x appears on the image's left (pbrt's orientation).

use crate::math::ray::RayDifferential;
use crate::math::{Point3, Ray, Vector3};
use crate::scene::{Camera as CameraDesc, CameraKind, Film};
use glam::{DMat4, DVec3, Vec2};

/// A camera ready to generate rays.
#[derive(Clone, Debug)]
pub struct Camera {
    kind: CameraKind,
    world_from_camera: DMat4,
    /// Screen window [x0, x1, y0, y1] and the full film resolution.
    window: [f32; 4],
    resolution: [f32; 2],
    tan_half_fov: f32,
    lens_radius: f32,
    focal_distance: f32,
}

/// Concentric mapping of the unit square to the unit disk (Shirley–Chiu).
pub fn concentric_disk(u: [f32; 2]) -> Vec2 {
    let o = Vec2::new(2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if o == Vec2::ZERO {
        return o;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, std::f32::consts::FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

impl Camera {
    pub fn new(desc: &CameraDesc, film: &Film) -> Camera {
        Camera {
            kind: desc.kind,
            world_from_camera: desc.camera_from_world.inverse(),
            window: desc.screen_window,
            resolution: [film.x_resolution as f32, film.y_resolution as f32],
            tan_half_fov: (desc.fov.to_radians() / 2.0).tan(),
            lens_radius: desc.lens_radius,
            focal_distance: desc.focal_distance,
        }
    }

    /// The screen-space point of a raster position.
    fn screen(&self, p_raster: [f32; 2]) -> [f32; 2] {
        let [x0, x1, y0, y1] = self.window;
        [x0 + p_raster[0] / self.resolution[0] * (x1 - x0), y1 - p_raster[1] / self.resolution[1] * (y1 - y0)]
    }

    /// The ray through `p_raster` and its differentials: the rays through the same lens
    /// point from one pixel over in x and in y, their offsets scaled by `scale`.
    pub fn generate_ray_differential(
        &self,
        p_raster: [f32; 2],
        u_lens: [f32; 2],
        scale: f32,
    ) -> (Ray, RayDifferential) {
        let ray = self.generate_ray(p_raster, u_lens);
        let rx = self.generate_ray([p_raster[0] + 1.0, p_raster[1]], u_lens);
        let ry = self.generate_ray([p_raster[0], p_raster[1] + 1.0], u_lens);
        (ray, RayDifferential { rx, ry }.scaled(&ray, scale))
    }

    /// A world-space ray through raster position `p_raster`; `u_lens` picks the lens
    /// point (ignored for a pinhole). Directions are unit length.
    pub fn generate_ray(&self, p_raster: [f32; 2], u_lens: [f32; 2]) -> Ray {
        let [sx, sy] = self.screen(p_raster);
        let (mut o, mut d) = match self.kind {
            CameraKind::Perspective => (
                DVec3::ZERO,
                DVec3::new((sx * self.tan_half_fov) as f64, (sy * self.tan_half_fov) as f64, 1.0).normalize(),
            ),
            CameraKind::Orthographic => (DVec3::new(sx as f64, sy as f64, 0.0), DVec3::Z),
        };
        if self.lens_radius > 0.0 {
            let lens = (self.lens_radius * concentric_disk(u_lens)).as_dvec2();
            let ft = self.focal_distance as f64 / d.z;
            let focus = o + d * ft;
            o = DVec3::new(o.x + lens.x, o.y + lens.y, 0.0);
            d = (focus - o).normalize();
        }
        let ow = self.world_from_camera.transform_point3(o);
        let dw = self.world_from_camera.transform_vector3(d).normalize();
        Ray::new(Point3(ow.as_vec3()), Vector3(dw.as_vec3()))
    }
}
