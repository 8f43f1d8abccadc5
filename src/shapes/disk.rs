//! `Shape "disk" "float height" 0 "float radius" 1 "float innerradius" 0 "float phimax" 360`
//!
//! p(u, v) = (ρ cosφ, ρ sinφ, h) with ρ = r − v·(r − ri): v = 0 on the outer rim.

use super::phi_max_radians;
use glam::DVec3;

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
