//! `Shape "cone" "float height" 1 "float radius" 1 "float phimax" 360` (pbrt-v3 only)
//!
//! p(u, v) = (r(1 − v) cosφ, r(1 − v) sinφ, v·h): base circle at z = 0, apex at z = h.

use super::phi_max_radians;
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
