//! `LightSource "distant"`: parallel light from one direction, as from the sun.
//!
//! ```text
//! LightSource "distant" "point3 from" [0 0 0] "point3 to" [0 0 1] "rgb L" [3 3 3]
//! LightSource "distant" "point3 to" [0 -1 0] "float illuminance" 2    # v4
//! ```
//! v4's `illuminance` scales L so that a surface facing the light receives that many
//! lux. Photons start on a disk of the scene's bounding sphere.

use super::params::{LightContext, direction, emission, illuminance, in_range};
use super::{Emission, LightKind, LightSample, WorldSphere};
use crate::math::frame::coordinate_system;
use crate::math::{Point3, Ray, Vector3};
use crate::mitsuba::LightOut;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::sampling::concentric_disk;
use crate::spectrum::{Rgb, luminance};
use crate::values::Res;
use glam::{DMat4, DVec3, Vec3};
use std::f32::consts::PI;

pub const NAME: &str = "distant";

/// A distant light as read; `toward_light` is the unit direction light comes from.
#[derive(Clone, Debug)]
pub struct Distant {
    pub toward_light: DVec3,
    pub l: Rgb,
}

pub fn read(p: &ParamList, m: &DMat4, span: Span, ctx: &mut LightContext) -> Res<LightKind> {
    let (_, d) = direction(p, m, span)?;
    let mut l = emission(p, "L", &ctx.spectra, span)?;
    if let Some(e) = illuminance(p)? {
        l = in_range(p, "L", l * (e / luminance(l).max(1e-9)), span)?;
    }
    Ok(LightKind::Distant(Distant { toward_light: -d, l }))
}

impl Distant {
    pub fn mitsuba(&self) -> LightOut {
        LightOut::Distant { direction: (-self.toward_light.as_vec3()).to_array(), irradiance: self.l.to_array() }
    }
}

/// A distant light ready to sample; `w` points toward the light.
#[derive(Clone, Debug)]
pub struct DistantLight {
    pub w: Vec3,
    pub l: Rgb,
}

impl DistantLight {
    pub fn new(d: &Distant) -> DistantLight {
        DistantLight { w: d.toward_light.as_vec3(), l: d.l }
    }

    #[inline]
    pub fn power(&self, world: WorldSphere) -> f64 {
        luminance(self.l) as f64 * std::f64::consts::PI * (world.radius as f64).powi(2)
    }

    #[inline]
    pub fn sample_li(&self) -> LightSample {
        LightSample::delta(self.w, self.l, None)
    }

    #[inline]
    pub fn sample_le(&self, world: WorldSphere, u: [f32; 2]) -> Emission {
        let (w, r) = (self.w, world.radius);
        let (a, b) = coordinate_system(w);
        let cd = concentric_disk(u);
        let o = world.center + r * (cd.x * a + cd.y * b) + r * w;
        let ray = Ray::new(Point3(o), Vector3(-w));
        Emission { ray, n: -w, pdf_pos: 1.0 / (PI * r * r), pdf_dir: 1.0, le: self.l, surface: None }
    }

    /// The point of the unit square `sample_le` starts the ray through `p` from.
    pub fn start_square(&self, world: WorldSphere, p: Vec3) -> [f32; 2] {
        let (a, b) = coordinate_system(self.w);
        let rel = (p - world.center) / world.radius;
        crate::sampling::invert_concentric_disk(glam::Vec2::new(rel.dot(a), rel.dot(b)))
    }

    /// (position, direction) densities of an emission: uniform over the disk of the
    /// world's radius, the direction a delta (0, as pbrt's `Pdf_Le` reports it).
    #[inline]
    pub fn pdf_le(&self, world: WorldSphere) -> (f32, f32) {
        (1.0 / (PI * world.radius * world.radius), 0.0)
    }
}
