//! `Shape "paraboloid" "float radius" 1 "float zmin" 0 "float zmax" 1 "float phimax" 360`
//! (pbrt-v3 only)
//!
//! z = zmin + v·(zmax − zmin), ρ = r·sqrt(z / zmax): the radius is r at z = zmax.

use super::Quadric;
use super::params::{f, positive};
use super::phi_max_radians;
use super::quadric::{Local, QuadricSurface};
use crate::math::bounded::Interval;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::DVec3;

#[derive(Clone, Debug, PartialEq)]
pub struct Paraboloid {
    pub radius: f32,
    pub z_min: f32,
    pub z_max: f32,
    pub phi_max: f32,
}

impl Paraboloid {
    pub fn new(radius: f32, z_min: f32, z_max: f32, phi_max_deg: f32) -> Paraboloid {
        Paraboloid { radius, z_min: z_min.min(z_max), z_max: z_min.max(z_max), phi_max: phi_max_radians(phi_max_deg) }
    }

    pub fn object_bounds(&self) -> [DVec3; 2] {
        let r = self.radius as f64;
        [DVec3::new(-r, -r, self.z_min as f64), DVec3::new(r, r, self.z_max as f64)]
    }

    /// φmax·r⁴/(12 zmax²) · [(1 + 4 zmax²/r²)^{3/2} − (1 + 4 zmax·zmin/r²)^{3/2}].
    pub fn area(&self) -> f64 {
        let (r, z0, z1) = (self.radius as f64, self.z_min as f64, self.z_max as f64);
        let (r2, k) = (r * r, 4.0 * z1 / (r * r));
        self.phi_max as f64 * r2 * r2 / (12.0 * z1 * z1) * ((k * z1 + 1.0).powf(1.5) - (k * z0 + 1.0).powf(1.5))
    }

    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        let (z0, z1) = (self.z_min as f64, self.z_max as f64);
        let z = z0 + v * (z1 - z0);
        let (phi, rho) = (u * self.phi_max as f64, self.radius as f64 * (z / z1).max(0.0).sqrt());
        DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
    }

    /// (zmax − zmin)·(x/(2z), y/(2z), 1), written as ρ/(2z) = r/(2·sqrt(z·zmax)).
    pub fn dpdv(&self, u: f64, v: f64) -> DVec3 {
        let (z0, z1) = (self.z_min as f64, self.z_max as f64);
        let z = z0 + v * (z1 - z0);
        let phi = u * self.phi_max as f64;
        let k = self.radius as f64 / (2.0 * (z * z1).sqrt());
        (z1 - z0) * DVec3::new(k * phi.cos(), k * phi.sin(), 1.0)
    }
}

impl QuadricSurface for Paraboloid {
    /// F = k(x² + y²) − z, k = zmax/r².
    fn coefficients<N: Interval>(&self, [ox, oy, oz]: [N; 3], [dx, dy, dz]: [N; 3]) -> (N, N, N) {
        let r = self.radius as f64;
        let k = N::from(self.z_max as f64) / N::from(r * r);
        (k * (dx * dx + dy * dy), k * (dx * ox + dy * oy) * 2.0 - dz, k * (ox * ox + oy * oy) - oz)
    }

    fn implicit(&self, p: DVec3) -> (f64, DVec3) {
        let k = self.z_max as f64 / (self.radius as f64).powi(2);
        (k * (p.x * p.x + p.y * p.y) - p.z, DVec3::new(2.0 * k * p.x, 2.0 * k * p.y, -1.0))
    }

    fn ranges(&self) -> (f64, f64, f64) {
        (self.z_min as f64, self.z_max as f64, self.phi_max as f64)
    }

    fn local(&self, p: DVec3, phi: f64) -> Local {
        let (pm, z0, z1) = (self.phi_max as f64, self.z_min as f64, self.z_max as f64);
        let dz = z1 - z0;
        Local {
            uv: [phi / pm, (p.z - z0) / dz],
            dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
            dpdv: dz * DVec3::new(p.x / (2.0 * p.z), p.y / (2.0 * p.z), 1.0),
            d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
            d2_uv: dz * pm * DVec3::new(-p.y / (2.0 * p.z), p.x / (2.0 * p.z), 0.0),
            d2_vv: -dz * dz * DVec3::new(p.x / (4.0 * p.z * p.z), p.y / (4.0 * p.z * p.z), 0.0),
        }
    }
}

impl Paraboloid {
    /// Its parameters after defaults and clamps, for `check --shapes`.
    pub fn params(&self) -> Vec<(&'static str, super::ShapeParam)> {
        use super::ShapeParam::*;
        vec![
            ("radius", Float(self.radius)),
            ("zmin", Float(self.z_min)),
            ("zmax", Float(self.z_max)),
            ("phimax", Angle(self.phi_max)),
        ]
    }
}

pub const NAME: &str = "paraboloid";

/// `Shape "paraboloid"` (v3): `radius` 1, `zmin` 0, `zmax` 1 (not both 0), `phimax` 360.
pub fn read(p: &ParamList, span: Span) -> Res<Quadric> {
    let r = positive(p, "radius", 1.0, span)?;
    let (z0, z1) = (f(p, "zmin", 0.0)?, f(p, "zmax", 1.0)?);
    if z0.max(z1) == 0.0 {
        return Err(Diagnostic::error(span, "paraboloid: zmax must be nonzero"));
    }
    Ok(Quadric::Paraboloid(Paraboloid::new(r, z0, z1, f(p, "phimax", 360.0)?)))
}
