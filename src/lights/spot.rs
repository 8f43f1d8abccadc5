//! `LightSource "spot"`: a point light limited to a cone.
//!
//! ```text
//! LightSource "spot" "blackbody I" [5500 125] "point from" [0 5 9] "point to" [-5 2.75 0]
//!             "float coneangle" 30 "float conedeltaangle" 5
//! ```
//! Full intensity inside `coneangle − conedeltaangle`, none past `coneangle`, and in
//! between pbrt-v3's quartic falloff in cos θ or pbrt-v4's smoothstep. v4's `power`
//! divides by the cone's effective solid angle.

use super::bounds::LightBounds;
use super::params::{LightContext, direction, emission, in_range, power};
use super::{Emission, LightKind, LightSample};
use crate::math::frame::coordinate_system;
use crate::math::{Point3, Ray, Vector3};
use crate::mitsuba::{LightOut, Unsupported};
use crate::parser::Syntax;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::sampling::uniform_cone;
use crate::spectrum::{Rgb, luminance};
use crate::values::{self, Range, Res};
use glam::{DMat4, DVec3, Vec3};
use std::f32::consts::PI;

pub const NAME: &str = "spot";

/// A spot light as read, in world space.
#[derive(Clone, Debug)]
pub struct Spot {
    pub position: DVec3,
    pub direction: DVec3,
    pub i: Rgb,
    pub cos_total: f32,
    pub cos_start: f32,
    /// pbrt-v4's smoothstep falloff (v3: quartic).
    pub smooth_falloff: bool,
}

pub fn read(p: &ParamList, m: &DMat4, span: Span, ctx: &mut LightContext) -> Res<LightKind> {
    let (from, direction) = direction(p, m, span)?;
    let cone = values::float(p, "coneangle", 30.0, Range::NonNegative)?;
    let delta = values::float(p, "conedeltaangle", 5.0, Range::NonNegative)?;
    let (cos_total, cos_start) = (cone.to_radians().cos(), (cone - delta).to_radians().cos());
    let mut i = emission(p, "I", &ctx.spectra, span)?;
    if let Some(w) = power(p)? {
        let solid = 2.0 * PI * (1.0 - 0.5 * (cos_start + cos_total));
        i = in_range(p, "I", i * (w / solid.max(1e-9)), span)?;
    }
    let position = m.transform_point3(from);
    let smooth_falloff = ctx.syntax == Syntax::V4;
    Ok(LightKind::Spot(Spot { position, direction, i, cos_total, cos_start, smooth_falloff }))
}

impl Spot {
    pub fn mitsuba(&self, notes: &mut Vec<Unsupported>) -> LightOut {
        if self.cos_start > self.cos_total {
            let ours = if self.smooth_falloff { "smoothstep in cos θ (v4)" } else { "quartic in cos θ (v3)" };
            notes.push(Unsupported::new("", "spot light falloff", format!("Mitsuba's is linear in θ, pbrt's {ours}")));
        }
        let frame = frame(self.direction);
        LightOut::Spot {
            position: self.position.as_vec3().to_array(),
            direction: frame[2].to_array(),
            up: frame[1].to_array(),
            intensity: self.i.to_array(),
            cutoff_angle: self.cos_total.clamp(-1.0, 1.0).acos().to_degrees(),
            beam_width: self.cos_start.clamp(-1.0, 1.0).acos().to_degrees(),
        }
    }
}

/// The light's frame: two tangents and the cone's axis.
fn frame(direction: DVec3) -> [Vec3; 3] {
    let dir = direction.as_vec3();
    let (a, b) = coordinate_system(dir);
    [a, b, dir]
}

/// A spot light ready to sample.
#[derive(Clone, Debug)]
pub struct SpotLight {
    pub p: Vec3,
    pub frame: [Vec3; 3],
    pub i: Rgb,
    pub cos_total: f32,
    pub cos_start: f32,
    pub smooth: bool,
}

impl SpotLight {
    pub fn new(d: &Spot) -> SpotLight {
        SpotLight {
            p: d.position.as_vec3(),
            frame: frame(d.direction),
            i: d.i,
            cos_total: d.cos_total,
            cos_start: d.cos_start,
            smooth: d.smooth_falloff,
        }
    }

    /// The intensity leaving along the unit world direction `w`: I times the falloff.
    #[inline]
    pub fn intensity(&self, w: Vec3) -> Rgb {
        self.i * self.falloff(w)
    }

    /// The share of I emitted along the unit direction `w` (away from the light).
    #[inline]
    fn falloff(&self, w: Vec3) -> f32 {
        let c = w.dot(self.frame[2]);
        if c < self.cos_total {
            return 0.0;
        }
        if c >= self.cos_start {
            return 1.0;
        }
        let d = (c - self.cos_total) / (self.cos_start - self.cos_total);
        if self.smooth { d * d * (3.0 - 2.0 * d) } else { d * d * d * d }
    }

    #[inline]
    pub fn power(&self) -> f64 {
        luminance(self.i) as f64 * 2.0 * std::f64::consts::PI * (1.0 - 0.5 * (self.cos_start + self.cos_total)) as f64
    }

    /// Bounds for choosing lights (pbrt-v4's `SpotLight::Bounds`): its intensity over
    /// the sphere, the full cone about its axis, the falloff band past it.
    pub fn bounds(&self) -> LightBounds {
        let band = self.cos_total.clamp(-1.0, 1.0).acos() - self.cos_start.clamp(-1.0, 1.0).acos();
        let mut cos_theta_e = band.cos();
        // pbrt-v4's slop: round-off in the importance must not shut a thin band.
        if cos_theta_e == 1.0 && self.cos_total != self.cos_start {
            cos_theta_e = 0.999;
        }
        let phi = 4.0 * std::f32::consts::PI * luminance(self.i);
        let point = LightBounds::isotropic(self.p, phi);
        LightBounds { w: self.frame[2], cos_theta_o: self.cos_start, cos_theta_e, ..point }
    }

    #[inline]
    pub fn sample_li(&self, p: Vec3) -> Option<LightSample> {
        let d = self.p - p;
        let d2 = d.length_squared();
        let wi = d / d2.sqrt();
        let f = self.falloff(-wi);
        (d2 > 0.0 && f > 0.0).then(|| LightSample::delta(wi, self.i * f / d2, Some(self.p)))
    }

    #[inline]
    pub fn sample_le(&self, u: [f32; 2]) -> Emission {
        let l = uniform_cone(u, self.cos_total);
        let [a, b, c] = self.frame;
        let d = a * l.x + b * l.y + c * l.z;
        let le = self.i * self.falloff(d);
        let pdf_dir = self.pdf_dir();
        Emission { ray: Ray::new(Point3(self.p), Vector3(d)), n: d, pdf_pos: 1.0, pdf_dir, le, surface: None }
    }

    /// The density of `sample_le`'s directions: uniform within the cone.
    pub fn pdf_dir(&self) -> f32 {
        1.0 / (2.0 * PI * (1.0 - self.cos_total))
    }

    /// (position, direction) densities of an emission along the unit direction `d`:
    /// the position is a delta (0), the direction uniform within the cone.
    #[inline]
    pub fn pdf_le(&self, d: Vec3) -> (f32, f32) {
        (0.0, if d.dot(self.frame[2]) >= self.cos_total { self.pdf_dir() } else { 0.0 })
    }
}
