//! `Shape "sphere" "float radius" 1 "float zmin" -r "float zmax" r "float phimax" 360`
//!
//! p(u, v) = r(sinθ cosφ, sinθ sinφ, cosθ), φ = u·φmax, θ = θ(zmin) + v·(θ(zmax) − θ(zmin)),
//! so v = 0 at zmin and v = 1 at zmax.

use super::Quadric;
use super::params::{f, positive};
use super::phi_max_radians;
use super::quadric::{Local, QuadricSurface};
use crate::math::bounded::Interval;
use crate::mitsuba::GeometryOut;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::{DMat3, DMat4, DVec3};

#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    pub radius: f32,
    pub z_min: f32,
    pub z_max: f32,
    /// θ at zmin (pbrt-v4 `thetaZMin`; the larger angle).
    pub theta_z_min: f32,
    pub theta_z_max: f32,
    pub phi_max: f32,
}

impl Sphere {
    /// pbrt's clamps: z range sorted and clamped to [−r, r], φmax to [0°, 360°].
    pub fn new(radius: f32, z_min: f32, z_max: f32, phi_max_deg: f32) -> Sphere {
        let (lo, hi) = (z_min.min(z_max), z_min.max(z_max));
        Sphere {
            radius,
            z_min: lo.clamp(-radius, radius),
            z_max: hi.clamp(-radius, radius),
            theta_z_min: (lo / radius).clamp(-1.0, 1.0).acos(),
            theta_z_max: (hi / radius).clamp(-1.0, 1.0).acos(),
            phi_max: phi_max_radians(phi_max_deg),
        }
    }

    pub fn object_bounds(&self) -> [DVec3; 2] {
        let r = self.radius as f64;
        [DVec3::new(-r, -r, self.z_min as f64), DVec3::new(r, r, self.z_max as f64)]
    }

    /// φmax · r · (zmax − zmin) (Archimedes).
    pub fn area(&self) -> f64 {
        self.phi_max as f64 * self.radius as f64 * (self.z_max as f64 - self.z_min as f64)
    }

    /// θ at zmin and at zmax, in f64 from the stored z values.
    fn theta_range(&self) -> (f64, f64) {
        let r = self.radius as f64;
        let t = |z: f32| (z as f64 / r).clamp(-1.0, 1.0).acos();
        (t(self.z_min), t(self.z_max))
    }

    fn theta(&self, v: f64) -> f64 {
        let (a, b) = self.theta_range();
        a + v * (b - a)
    }

    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        let (phi, theta, r) = (u * self.phi_max as f64, self.theta(v), self.radius as f64);
        r * DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
    }

    pub fn dpdv(&self, u: f64, v: f64) -> DVec3 {
        let (phi, theta, r) = (u * self.phi_max as f64, self.theta(v), self.radius as f64);
        let z = r * theta.cos();
        let (a, b) = self.theta_range();
        (b - a) * DVec3::new(z * phi.cos(), z * phi.sin(), -r * theta.sin())
    }
}

impl QuadricSurface for Sphere {
    fn coefficients<N: Interval>(&self, [ox, oy, oz]: [N; 3], [dx, dy, dz]: [N; 3]) -> (N, N, N) {
        let r = self.radius as f64;
        (dx * dx + dy * dy + dz * dz, (dx * ox + dy * oy + dz * oz) * 2.0, ox * ox + oy * oy + oz * oz - N::from(r * r))
    }

    fn implicit(&self, p: DVec3) -> (f64, DVec3) {
        let r = self.radius as f64;
        (p.length_squared() - r * r, 2.0 * p)
    }

    fn ranges(&self) -> (f64, f64, f64) {
        (self.z_min as f64, self.z_max as f64, self.phi_max as f64)
    }

    /// Radial re-projection; a point on the axis is nudged off it, as pbrt does, so φ
    /// is defined.
    fn refine(&self, p: DVec3) -> DVec3 {
        let mut p = p * (self.radius as f64 / p.length());
        if p.x == 0.0 && p.y == 0.0 {
            p.x = 1e-5 * self.radius as f64;
        }
        p
    }

    fn residual(&self, p: DVec3) -> f64 {
        (p.length() - self.radius as f64).abs()
    }

    fn local(&self, p: DVec3, phi: f64) -> Local {
        let (r, pm) = (self.radius as f64, self.phi_max as f64);
        let (ta, tb) = self.theta_range();
        let theta = (p.z / r).clamp(-1.0, 1.0).acos();
        let zr = (p.x * p.x + p.y * p.y).sqrt();
        let (cos_phi, sin_phi) = (p.x / zr, p.y / zr);
        let dt = tb - ta;
        Local {
            uv: [phi / pm, (theta - ta) / dt],
            dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
            dpdv: dt * DVec3::new(p.z * cos_phi, p.z * sin_phi, -r * theta.sin()),
            d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
            d2_uv: dt * p.z * pm * DVec3::new(-sin_phi, cos_phi, 0.0),
            d2_vv: -dt * dt * p,
        }
    }
}

impl Sphere {
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

    /// Mitsuba's `sphere`, for a full sphere under a similarity transform that keeps
    /// handedness; `None` otherwise (the exporter tessellates).
    pub fn mitsuba(&self, m: &DMat4, reverse: bool) -> Option<GeometryOut> {
        let m3 = DMat3::from_mat4(*m);
        let full = self.phi_max as f64 >= std::f64::consts::TAU - 1e-6
            && self.z_min <= -self.radius
            && self.z_max >= self.radius;
        (super::native_in_mitsuba(m3) && full).then(|| GeometryOut::Sphere {
            center: m.transform_point3(DVec3::ZERO).to_array(),
            radius: m3.x_axis.length() * self.radius as f64,
            flip_normals: reverse,
        })
    }
}

pub const NAME: &str = "sphere";

/// `Shape "sphere"`: `radius` 1, `zmin` −radius, `zmax` radius, `phimax` 360.
pub fn read(p: &ParamList, span: Span) -> Res<Quadric> {
    let r = positive(p, "radius", 1.0, span)?;
    Ok(Quadric::Sphere(Sphere::new(r, f(p, "zmin", -r)?, f(p, "zmax", r)?, f(p, "phimax", 360.0)?)))
}
