//! The Henyey–Greenstein phase function, pbrt's only one (`"float g"` of every medium).
//!
//! ```text
//! MakeNamedMedium "fog" "string type" "homogeneous" "float g" 0.7   # forward scattering
//! ```
//!
//! Directions follow pbrt: `wo` points back along the arriving path, `wi` toward where
//! light comes from, both away from the scattering point. With g > 0 light keeps going
//! forward, so `wi` lies near `-wo`.

use crate::math::frame::coordinate_system;
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein {
    pub g: f32,
}

/// A sampled direction; the density is the phase function's value, so the weight
/// p/pdf is 1.
#[derive(Clone, Copy, Debug)]
pub struct PhaseSample {
    pub wi: Vec3,
    pub p: f32,
}

impl HenyeyGreenstein {
    /// pbrt clamps g to the open interval, where the function is finite.
    pub fn new(g: f32) -> HenyeyGreenstein {
        HenyeyGreenstein { g: g.clamp(-0.99, 0.99) }
    }

    /// p(wo, wi) with pbrt's sign convention: cos θ = wo·wi, the density peaking at
    /// wi = -wo for g > 0.
    pub fn p(&self, wo: Vec3, wi: Vec3) -> f32 {
        hg(wo.dot(wi), self.g)
    }

    /// wi drawn with density p(wo, ·) from two uniform numbers.
    pub fn sample(&self, wo: Vec3, u: [f32; 2]) -> PhaseSample {
        let g = self.g;
        // cos of the angle to the forward direction -wo, by inverting HG's CDF.
        let cos_fwd = if g.abs() < 1e-3 {
            1.0 - 2.0 * u[0]
        } else {
            let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u[0]);
            ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
        };
        let sin = (1.0 - cos_fwd * cos_fwd).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1];
        let fwd = -wo.normalize();
        let (t1, t2) = coordinate_system(fwd);
        let wi = (t1 * (sin * phi.cos()) + t2 * (sin * phi.sin()) + fwd * cos_fwd).normalize();
        PhaseSample { wi, p: hg(-cos_fwd, g) }
    }
}

/// HG as a function of cos θ between `wo` and `wi` (pbrt's `HenyeyGreenstein`).
pub fn hg(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g + 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.max(1e-12).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ p dω = 1 and sampling has density p, for several g.
    #[test]
    fn integrates_to_one_and_samples_its_own_density() {
        let wo = Vec3::new(0.3, -0.5, 0.8).normalize();
        for g in [-0.8, -0.3, 0.0, 0.5, 0.9] {
            let hg = HenyeyGreenstein::new(g);
            // Uniform sphere quadrature.
            let n = 400;
            let mut sum = 0.0f64;
            for i in 0..n {
                for j in 0..2 * n {
                    let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                    let phi = PI * (j as f32 + 0.5) / n as f32;
                    let r = (1.0 - z * z).sqrt();
                    let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                    sum += hg.p(wo, wi) as f64;
                }
            }
            let integral = sum * 4.0 * std::f64::consts::PI / (2 * n * n) as f64;
            assert!((integral - 1.0).abs() < 0.01, "g {g}: ∫p = {integral}");
            // The mean cosine with the forward direction is g.
            let mut mean = 0.0f64;
            let m = 20000;
            for k in 0..m {
                let u = [(k as f32 + 0.5) / m as f32, ((k * 7919) % m) as f32 / m as f32];
                let s = hg.sample(wo, u);
                assert!((s.p - hg.p(wo, s.wi)).abs() <= 1e-3 * s.p.max(1.0), "g {g}");
                mean += s.wi.dot(-wo) as f64;
            }
            mean /= m as f64;
            assert!((mean - g as f64).abs() < 0.01, "g {g}: mean cosine {mean}");
        }
    }
}
