//! `Shape "sphere" "float radius" 1 "float zmin" -r "float zmax" r "float phimax" 360`
//!
//! p(u, v) = r(sinθ cosφ, sinθ sinφ, cosθ), φ = u·φmax, θ = θ(zmin) + v·(θ(zmax) − θ(zmin)),
//! so v = 0 at zmin and v = 1 at zmax.

use super::phi_max_radians;
use glam::DVec3;

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
