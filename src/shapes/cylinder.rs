//! `Shape "cylinder" "float radius" 1 "float zmin" -1 "float zmax" 1 "float phimax" 360`
//!
//! p(u, v) = (r cosφ, r sinφ, zmin + v·(zmax − zmin)).

use super::phi_max_radians;
use glam::DVec3;

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
