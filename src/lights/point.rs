//! `LightSource "point"`: light from one point, the same intensity every way.
//!
//! ```text
//! LightSource "point" "rgb I" [10 10 10] "point from" [0 4 0] "float scale" 1
//! LightSource "point" "blackbody I" [3000] "point3 from" [0 4 0] "float power" 100   # v4
//! ```
//! pbrt-v3 adds `from` in world space after the CTM; pbrt-v4 transforms it by the CTM.
//! v4's `power` (watts) sets I = power / 4π times the emission as read.

use super::bounds::LightBounds;
use super::params::{LightContext, emission, in_range, point3, power};
use super::{Emission, LightKind, LightSample};
use crate::math::{Point3, Ray, Vector3};
use crate::mitsuba::LightOut;
use crate::parser::Syntax;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::sampling::uniform_sphere;
use crate::spectrum::{Rgb, luminance};
use crate::values::Res;
use glam::{DMat4, DVec3, Vec3};
use std::f32::consts::PI;

pub const NAME: &str = "point";

/// A point light as read: its world position and intensity.
#[derive(Clone, Debug)]
pub struct Point {
    pub position: DVec3,
    pub i: Rgb,
}

pub fn read(p: &ParamList, m: &DMat4, span: Span, ctx: &mut LightContext) -> Res<LightKind> {
    let from = point3(p, "from", [0.0; 3])?;
    let position = match ctx.syntax {
        Syntax::V3 => m.transform_point3(DVec3::ZERO) + from,
        Syntax::V4 => m.transform_point3(from),
    };
    let mut i = emission(p, "I", &ctx.spectra, span)?;
    if let Some(w) = power(p)? {
        i = in_range(p, "I", i * (w / (4.0 * PI)), span)?;
    }
    Ok(LightKind::Point(Point { position, i }))
}

impl Point {
    pub fn mitsuba(&self) -> LightOut {
        LightOut::Point { position: self.position.as_vec3().to_array(), intensity: self.i.to_array() }
    }
}

/// A point light ready to sample.
#[derive(Clone, Debug)]
pub struct PointLight {
    pub p: Vec3,
    pub i: Rgb,
}

impl PointLight {
    pub fn new(d: &Point) -> PointLight {
        PointLight { p: d.position.as_vec3(), i: d.i }
    }

    /// The intensity leaving along any direction.
    #[inline]
    pub fn intensity(&self) -> Rgb {
        self.i
    }

    #[inline]
    pub fn power(&self) -> f64 {
        4.0 * std::f64::consts::PI * luminance(self.i) as f64
    }

    /// Bounds for choosing lights (pbrt-v4's `PointLight::Bounds`).
    pub fn bounds(&self) -> LightBounds {
        LightBounds::isotropic(self.p, self.power() as f32)
    }

    #[inline]
    pub fn sample_li(&self, p: Vec3) -> Option<LightSample> {
        let d = self.p - p;
        let d2 = d.length_squared();
        (d2 > 0.0).then(|| LightSample::delta(d / d2.sqrt(), self.i / d2, Some(self.p)))
    }

    #[inline]
    pub fn sample_le(&self, u: [f32; 2]) -> Emission {
        let d = uniform_sphere(u);
        let ray = Ray::new(Point3(self.p), Vector3(d));
        Emission { ray, n: d, pdf_pos: 1.0, pdf_dir: 1.0 / (4.0 * PI), le: self.i, surface: None }
    }

    /// (position, direction) densities of an emission along `d`: the position is a
    /// delta (0, as pbrt's `Pdf_Le` reports it), the direction uniform.
    #[inline]
    pub fn pdf_le(&self) -> (f32, f32) {
        (0.0, 1.0 / (4.0 * PI))
    }
}
