//! `Shape "disk" "float height" 0 "float radius" 1 "float innerradius" 0 "float phimax" 360`
//!
//! p(u, v) = (ρ cosφ, ρ sinφ, h) with ρ = r − v·(r − ri): v = 0 on the outer rim.

use super::Quadric;
use super::params::{f, positive};
use super::phi_max_radians;
use super::quadric::{E, Local, ObjectRay, QuadricSurface, within};
use crate::math::bounded::Bounded64;
use crate::math::bounded::Interval;
use crate::math::transform::row_major;
use crate::mitsuba::GeometryOut;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::{DMat3, DMat4, DVec3};

#[derive(Clone, Debug, PartialEq)]
pub struct Disk {
    pub height: f32,
    pub radius: f32,
    pub inner_radius: f32,
    pub phi_max: f32,
}

impl Disk {
    pub fn new(height: f32, radius: f32, inner_radius: f32, phi_max_deg: f32) -> Disk {
        Disk { height, radius, inner_radius, phi_max: phi_max_radians(phi_max_deg) }
    }

    pub fn object_bounds(&self) -> [DVec3; 2] {
        let (r, h) = (self.radius as f64, self.height as f64);
        [DVec3::new(-r, -r, h), DVec3::new(r, r, h)]
    }

    /// (φmax / 2) · (r² − ri²).
    pub fn area(&self) -> f64 {
        let (r, ri) = (self.radius as f64, self.inner_radius as f64);
        self.phi_max as f64 * 0.5 * (r * r - ri * ri)
    }

    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        let phi = u * self.phi_max as f64;
        let rho = self.radius as f64 - v * (self.radius as f64 - self.inner_radius as f64);
        DVec3::new(rho * phi.cos(), rho * phi.sin(), self.height as f64)
    }

    pub fn dpdv(&self, u: f64, _v: f64) -> DVec3 {
        let phi = u * self.phi_max as f64;
        (self.inner_radius as f64 - self.radius as f64) * DVec3::new(phi.cos(), phi.sin(), 0.0)
    }
}

impl QuadricSurface for Disk {
    /// F = z − h is linear (a = 0); [`Disk::hit`] solves it directly.
    fn coefficients<N: Interval>(&self, [_, _, oz]: [N; 3], [_, _, dz]: [N; 3]) -> (N, N, N) {
        (N::from(0.0), dz, oz - N::from(self.height as f64))
    }

    fn implicit(&self, p: DVec3) -> (f64, DVec3) {
        (p.z - self.height as f64, DVec3::Z)
    }

    fn ranges(&self) -> (f64, f64, f64) {
        (self.height as f64, self.height as f64, self.phi_max as f64)
    }

    fn residual(&self, p: DVec3) -> f64 {
        (p.z - self.height as f64).abs()
    }

    /// The plane z = h, then the annulus test; the point is put exactly on the plane
    /// before the shared range test. Whether t's interval lies in (0, t_max) is
    /// decided from its value and a bound where that settles it.
    fn hit(&self, ray: &ObjectRay, t_max: f64) -> Option<(f64, DVec3)> {
        let h = self.height as f64;
        if ray.d[2].0 == 0.0 {
            return None;
        }
        let (o, d) = ray.bounded();
        let quick = (Bounded64::from(h) - o[2]) / d[2];
        let inside = match within(quick, t_max) {
            Some(inside) => inside,
            None => {
                let (o, d) = ray.intervals();
                let t = (E::from(h) - o[2]) / d[2];
                !(t.lower() <= 0.0 || t.upper() >= t_max)
            }
        };
        if !inside {
            return None;
        }
        let t = quick.v;
        let mut p = ray.at(t);
        let dist2 = p.x * p.x + p.y * p.y;
        let (r, ri) = (self.radius as f64, self.inner_radius as f64);
        if dist2 > r * r || dist2 < ri * ri {
            return None;
        }
        p.z = h;
        self.accept(p).then_some((t, p))
    }

    fn local(&self, p: DVec3, phi: f64) -> Local {
        let (pm, r, ri) = (self.phi_max as f64, self.radius as f64, self.inner_radius as f64);
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let dpdv = if rho > 0.0 { DVec3::new(p.x, p.y, 0.0) * ((ri - r) / rho) } else { DVec3::new(ri - r, 0.0, 0.0) };
        Local {
            uv: [phi / pm, (r - rho) / (r - ri)],
            dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
            dpdv,
            d2_uu: DVec3::ZERO,
            d2_uv: DVec3::ZERO,
            d2_vv: DVec3::ZERO,
        }
    }
}

impl Disk {
    /// Its parameters after defaults and clamps, for `check --shapes`.
    pub fn params(&self) -> Vec<(&'static str, super::ShapeParam)> {
        use super::ShapeParam::*;
        vec![
            ("height", Float(self.height)),
            ("radius", Float(self.radius)),
            ("innerradius", Float(self.inner_radius)),
            ("phimax", Angle(self.phi_max)),
        ]
    }

    /// Mitsuba's `disk` (unit radius, placed by `to_world`), for a full disk without a
    /// hole under a similarity transform that keeps handedness.
    pub fn mitsuba(&self, m: &DMat4, reverse: bool) -> Option<GeometryOut> {
        let full = self.phi_max as f64 >= std::f64::consts::TAU - 1e-6 && self.inner_radius == 0.0;
        if !(super::native_in_mitsuba(DMat3::from_mat4(*m)) && full) {
            return None;
        }
        let r = self.radius as f64;
        let local = DMat4::from_translation(DVec3::new(0.0, 0.0, self.height as f64))
            * DMat4::from_scale(DVec3::new(r, r, 1.0));
        let to_world = row_major(&(*m * local));
        Some(GeometryOut::Disk { to_world, flip_normals: reverse })
    }
}

pub const NAME: &str = "disk";

/// `Shape "disk"`: `height` 0, `radius` 1, `innerradius` 0 (within [0, radius]), `phimax` 360.
pub fn read(p: &ParamList, span: Span) -> Res<Quadric> {
    let r = positive(p, "radius", 1.0, span)?;
    let ri = f(p, "innerradius", 0.0)?;
    if !(0.0..=r).contains(&ri) {
        return Err(Diagnostic::error(span, format!("disk: innerradius {ri} must lie in [0, radius {r}]")));
    }
    Ok(Quadric::Disk(Disk::new(f(p, "height", 0.0)?, r, ri, f(p, "phimax", 360.0)?)))
}
