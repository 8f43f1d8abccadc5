//! What the scene file says of its camera and film, as the builder resolves them
//! (`scene::options` reads the statements); [`super::Camera`] is made from them.
//!
//! ```text
//! Camera "perspective" "float fov" 45 "float lensradius" 0 "float focaldistance" 1e6
//! Film "rgb" "integer xresolution" 1280 "integer yresolution" 720 "float iso" 100
//! ```

use super::clamp::SampleClamp;
use crate::filters::PixelFilter;
use crate::spectrum::buckets::Buckets;
use crate::spectrum::sensor::CameraSensor;
use glam::DMat4;

/// The camera models we render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraKind {
    Perspective,
    Orthographic,
    /// pbrt-v3's `environment`: every direction, by latitude and longitude.
    Environment,
    /// pbrt-v4's `spherical`, by its `mapping`.
    Spherical(SphericalMapping),
    /// pbrt's `realistic`: a lens system ([`Camera::lens`]).
    Realistic,
}

/// How pbrt-v4's spherical camera lays the sphere of directions on the film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SphericalMapping {
    /// Clarberg's equal-area square (pbrt-v4's default).
    EqualArea,
    /// Latitude and longitude, as pbrt-v3's environment camera.
    Equirectangular,
}

impl CameraKind {
    /// The name scenes use.
    pub fn name(self) -> &'static str {
        match self {
            CameraKind::Perspective => "perspective",
            CameraKind::Orthographic => "orthographic",
            CameraKind::Environment => "environment",
            CameraKind::Spherical(_) => "spherical",
            CameraKind::Realistic => "realistic",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub kind: CameraKind,
    /// Full angle (degrees) spanned by the shorter image axis.
    pub fov: f32,
    pub lens_radius: f32,
    pub focal_distance: f32,
    pub frame_aspect_ratio: f32,
    /// [x0, x1, y0, y1] in screen space.
    pub screen_window: [f32; 4],
    pub shutter_open: f32,
    pub shutter_close: f32,
    /// The CTM at the `Camera` statement.
    pub camera_from_world: DMat4,
    /// The end CTM at the `Camera` statement and the `TransformTimes`, when the camera
    /// moves.
    pub camera_from_world_end: Option<(DMat4, [f64; 2])>,
    /// The frame its motion is interpolated in (see [`crate::math::animated`]).
    pub world_from_render: DMat4,
    /// A realistic camera's lens system and settings.
    pub lens: Option<std::sync::Arc<super::realistic::LensDesc>>,
}

impl Camera {
    /// A ray's time for a sample `u` in [0, 1): within the shutter (pbrt's lerp).
    pub fn time(&self, u: f32) -> f32 {
        self.shutter_open + (self.shutter_close - self.shutter_open) * u
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// `image` (v3) or `rgb` (v4); `gbuffer` and `spectral` are written as `rgb`.
    pub ty: String,
    pub x_resolution: u32,
    pub y_resolution: u32,
    pub filename: String,
    /// Where the scene gives `filename` (`file:line:col`), for errors about it.
    pub filename_location: Option<String>,
    /// Where the scene's `Film` statement is (`file:line:col`), for errors about what
    /// it records; none when the file has none.
    pub location: Option<String>,
    /// [x0, x1, y0, y1] in NDC, clamped to [0, 1] and sorted.
    pub crop_window: [f32; 4],
    /// [x0, x1, y0, y1] pixels, half open.
    pub pixel_bounds: [u32; 4],
    /// Output multiplier: v3 `scale`, v4 `iso`/100 × exposure time.
    pub scale: f32,
    /// The film's diagonal in millimetres (a realistic camera's film size).
    pub diagonal_mm: f32,
    /// pbrt-v4's white balance, a matrix on linear sRGB (none: colours as rendered).
    pub white_balance: Option<[[f64; 3]; 3]>,
    /// A named camera's curves, which spectral paths are recorded through (its white
    /// balance is in its matrix).
    pub sensor: Option<CameraSensor>,
    /// pbrt-v4's pixel filter, which blurs its SPPM image (none: rays start uniformly
    /// in the pixel, as pbrt-v3's SPPM starts them).
    pub filter: Option<PixelFilter>,
    /// A `spectral` film's wavelength buckets, written beside R, G, B (paths that
    /// carry wavelengths, rendered by vcm or bdpt).
    pub buckets: Option<Buckets>,
    /// The bound on each camera sample and splat (not applied by SPPM, as in pbrt).
    pub clamp: Option<SampleClamp>,
}

impl Film {
    /// What the film records of an estimate: times `scale`, then white-balanced.
    pub fn respond(&self, rgb: glam::DVec3) -> glam::DVec3 {
        let v = rgb * self.scale as f64;
        match &self.white_balance {
            None => v,
            Some(m) => glam::DVec3::from(crate::spectrum::colorspace::mul_vec(m, v.to_array())),
        }
    }

    pub fn pixel_count(&self) -> u64 {
        let [x0, x1, y0, y1] = self.pixel_bounds;
        (x1 - x0) as u64 * (y1 - y0) as u64
    }
}
