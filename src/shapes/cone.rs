//! `Shape "cone" "float height" 1 "float radius" 1 "float phimax" 360` (pbrt-v3 only)
//!
//! p(u, v) = (r(1 − v) cosφ, r(1 − v) sinφ, v·h): base circle at z = 0, apex at z = h.

use super::Quadric;
use super::params::{f, positive};
use super::phi_max_radians;
use super::quadric::{Local, QuadricSurface, newton};
use crate::math::bounded::Interval;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::DVec3;

#[derive(Clone, Debug, PartialEq)]
pub struct Cone {
    pub height: f32,
    pub radius: f32,
    pub phi_max: f32,
}

impl Cone {
    pub fn new(height: f32, radius: f32, phi_max_deg: f32) -> Cone {
        Cone { height, radius, phi_max: phi_max_radians(phi_max_deg) }
    }

    pub fn object_bounds(&self) -> [DVec3; 2] {
        let r = self.radius as f64;
        [DVec3::new(-r, -r, 0.0), DVec3::new(r, r, self.height as f64)]
    }

    /// (φmax / 2) · r · sqrt(h² + r²).
    pub fn area(&self) -> f64 {
        let (r, h) = (self.radius as f64, self.height as f64);
        r * (h * h + r * r).sqrt() * self.phi_max as f64 / 2.0
    }

    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        let (phi, rho) = (u * self.phi_max as f64, self.radius as f64 * (1.0 - v));
        DVec3::new(rho * phi.cos(), rho * phi.sin(), v * self.height as f64)
    }

    pub fn dpdv(&self, u: f64, _v: f64) -> DVec3 {
        let (phi, r) = (u * self.phi_max as f64, self.radius as f64);
        DVec3::new(-r * phi.cos(), -r * phi.sin(), self.height as f64)
    }
}

impl QuadricSurface for Cone {
    /// F = x² + y² − k(z − h)², k = (r/h)².
    fn coefficients<N: Interval>(&self, [ox, oy, oz]: [N; 3], [dx, dy, dz]: [N; 3]) -> (N, N, N) {
        let k = N::from(self.radius as f64 / self.height as f64);
        let k = k * k;
        let oz_h = oz - N::from(self.height as f64);
        (
            dx * dx + dy * dy - k * dz * dz,
            (dx * ox + dy * oy - k * dz * oz_h) * 2.0,
            ox * ox + oy * oy - k * oz_h * oz_h,
        )
    }

    fn implicit(&self, p: DVec3) -> (f64, DVec3) {
        let k = (self.radius as f64 / self.height as f64).powi(2);
        let zh = p.z - self.height as f64;
        (p.x * p.x + p.y * p.y - k * zh * zh, DVec3::new(2.0 * p.x, 2.0 * p.y, -2.0 * k * zh))
    }

    fn ranges(&self) -> (f64, f64, f64) {
        let h = self.height as f64;
        (h.min(0.0), h.max(0.0), self.phi_max as f64)
    }

    /// Newton steps, then a point that landed on the other nappe within 2^-20 of the
    /// cone's size from the apex is the apex: a ray through the tip crosses both nappes
    /// there, and the steps may settle on the wrong one.
    fn refine(&self, p: DVec3) -> DVec3 {
        let p = newton(self, p);
        let (h, r) = (self.height as f64, self.radius as f64);
        let apex = DVec3::new(0.0, 0.0, h);
        let beyond = if h > 0.0 { p.z > h } else { p.z < h };
        if beyond && (p - apex).length() <= (h.abs().max(r)) * 2f64.powi(-20) { apex } else { p }
    }

    fn local(&self, p: DVec3, phi: f64) -> Local {
        let (pm, h) = (self.phi_max as f64, self.height as f64);
        let v = p.z / h;
        Local {
            uv: [phi / pm, v],
            dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
            dpdv: DVec3::new(-p.x / (1.0 - v), -p.y / (1.0 - v), h),
            d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
            d2_uv: pm / (1.0 - v) * DVec3::new(p.y, -p.x, 0.0),
            d2_vv: DVec3::ZERO,
        }
    }
}

impl Cone {
    /// Its parameters after defaults and clamps, for `check --shapes`.
    pub fn params(&self) -> Vec<(&'static str, super::ShapeParam)> {
        use super::ShapeParam::*;
        vec![("height", Float(self.height)), ("radius", Float(self.radius)), ("phimax", Angle(self.phi_max))]
    }
}

pub const NAME: &str = "cone";

/// `Shape "cone"` (v3): `height` 1 (not 0), `radius` 1, `phimax` 360.
pub fn read(p: &ParamList, span: Span) -> Res<Quadric> {
    let r = positive(p, "radius", 1.0, span)?;
    let h = f(p, "height", 1.0)?;
    if h == 0.0 {
        return Err(Diagnostic::error(span, "cone: height must be nonzero"));
    }
    Ok(Quadric::Cone(Cone::new(h, r, f(p, "phimax", 360.0)?)))
}
