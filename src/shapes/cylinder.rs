//! `Shape "cylinder" "float radius" 1 "float zmin" -1 "float zmax" 1 "float phimax" 360`
//!
//! p(u, v) = (r cosφ, r sinφ, zmin + v·(zmax − zmin)).

use super::Quadric;
use super::params::{f, positive};
use super::phi_max_radians;
use super::quadric::{Local, QuadricSurface};
use crate::math::bounded::Interval;
use crate::math::transform::row_major;
use crate::mitsuba::GeometryOut;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::{DMat3, DMat4, DVec3};

#[derive(Clone, Debug, PartialEq)]
pub struct Cylinder {
    pub radius: f32,
    pub z_min: f32,
    pub z_max: f32,
    pub phi_max: f32,
}

impl Cylinder {
    /// pbrt sorts zmin/zmax (they are not radius-relative) and clamps φmax.
    pub fn new(radius: f32, z_min: f32, z_max: f32, phi_max_deg: f32) -> Cylinder {
        Cylinder { radius, z_min: z_min.min(z_max), z_max: z_min.max(z_max), phi_max: phi_max_radians(phi_max_deg) }
    }

    pub fn object_bounds(&self) -> [DVec3; 2] {
        let r = self.radius as f64;
        [DVec3::new(-r, -r, self.z_min as f64), DVec3::new(r, r, self.z_max as f64)]
    }

    pub fn area(&self) -> f64 {
        (self.z_max as f64 - self.z_min as f64) * self.radius as f64 * self.phi_max as f64
    }

    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        let (phi, r) = (u * self.phi_max as f64, self.radius as f64);
        let z = self.z_min as f64 + v * (self.z_max as f64 - self.z_min as f64);
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    pub fn dpdv(&self, _u: f64, _v: f64) -> DVec3 {
        DVec3::new(0.0, 0.0, self.z_max as f64 - self.z_min as f64)
    }
}

impl QuadricSurface for Cylinder {
    fn coefficients<N: Interval>(&self, [ox, oy, _]: [N; 3], [dx, dy, _]: [N; 3]) -> (N, N, N) {
        let r = self.radius as f64;
        (dx * dx + dy * dy, (dx * ox + dy * oy) * 2.0, ox * ox + oy * oy - N::from(r * r))
    }

    fn implicit(&self, p: DVec3) -> (f64, DVec3) {
        let r = self.radius as f64;
        (p.x * p.x + p.y * p.y - r * r, DVec3::new(2.0 * p.x, 2.0 * p.y, 0.0))
    }

    fn ranges(&self) -> (f64, f64, f64) {
        (self.z_min as f64, self.z_max as f64, self.phi_max as f64)
    }

    /// Radial re-projection.
    fn refine(&self, p: DVec3) -> DVec3 {
        let k = self.radius as f64 / (p.x * p.x + p.y * p.y).sqrt();
        DVec3::new(p.x * k, p.y * k, p.z)
    }

    fn residual(&self, p: DVec3) -> f64 {
        ((p.x * p.x + p.y * p.y).sqrt() - self.radius as f64).abs()
    }

    fn local(&self, p: DVec3, phi: f64) -> Local {
        let pm = self.phi_max as f64;
        let dz = self.z_max as f64 - self.z_min as f64;
        Local {
            uv: [phi / pm, (p.z - self.z_min as f64) / dz],
            dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
            dpdv: DVec3::new(0.0, 0.0, dz),
            d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
            d2_uv: DVec3::ZERO,
            d2_vv: DVec3::ZERO,
        }
    }
}

impl Cylinder {
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

    /// Mitsuba's `cylinder` (unit radius and height, placed by `to_world`), for a full
    /// cylinder under a similarity transform that keeps handedness.
    pub fn mitsuba(&self, m: &DMat4, reverse: bool) -> Option<GeometryOut> {
        let full = self.phi_max as f64 >= std::f64::consts::TAU - 1e-6;
        if !(super::native_in_mitsuba(DMat3::from_mat4(*m)) && full) {
            return None;
        }
        let (r, z0, z1) = (self.radius as f64, self.z_min as f64, self.z_max as f64);
        let local = DMat4::from_translation(DVec3::new(0.0, 0.0, z0)) * DMat4::from_scale(DVec3::new(r, r, z1 - z0));
        let to_world = row_major(&(*m * local));
        Some(GeometryOut::Cylinder { to_world, flip_normals: reverse })
    }
}

pub const NAME: &str = "cylinder";

/// `Shape "cylinder"`: `radius` 1, `zmin` −1, `zmax` 1, `phimax` 360.
pub fn read(p: &ParamList, span: Span) -> Res<Quadric> {
    let r = positive(p, "radius", 1.0, span)?;
    Ok(Quadric::Cylinder(Cylinder::new(r, f(p, "zmin", -1.0)?, f(p, "zmax", 1.0)?, f(p, "phimax", 360.0)?)))
}
