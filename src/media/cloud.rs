//! pbrt-v4's `cloud`: a procedural cloud of noise in a box, thinning with height.
//!
//! ```text
//! MakeNamedMedium "sky" "string type" "cloud" "float density" 1 "float wispiness" 1
//!     "float frequency" 5 "rgb sigma_a" [1 1 1] "rgb sigma_s" [1 1 1] "float g" 0
//!     "point3 p0" [0 0 0] "point3 p1" [1 1 1]
//! ```
//!
//! The density at a point p of the medium's space (not of the box: the cloud is the
//! same wherever its box is placed) is pbrt-v4's: five octaves of Perlin noise at
//! `frequency`·p, first displaced by two octaves of the noise's gradient scaled by
//! `wispiness`, times 4.5·`density`·(1 − y), clamped to [0, 1], plus 2·max(0, ½ − y),
//! clamped to [0, 1]. It multiplies σa and σs (no `scale`); σt is their sum at most.

use super::MediumContext;
use super::lanes::{Lanes, Sigma, sigma_t_bound};
use super::phase::HenyeyGreenstein;
use super::tracking::{Field, Props, Tracked};
use crate::parser::params::ParamList;
use crate::textures::noise::noise;
use crate::values::{self, Range, Res};
use glam::{DMat4, Vec3};
use std::sync::Arc;

pub const NAME: &str = "cloud";

#[derive(Debug)]
pub struct Cloud {
    sigma_a: Sigma,
    sigma_s: Sigma,
    density: f32,
    wispiness: f32,
    frequency: f32,
    /// The unit cube to the box, in the medium's space.
    unit_to_box: DMat4,
}

impl Cloud {
    fn density_at(&self, p: Vec3) -> f32 {
        let mut pp = self.frequency * p;
        if self.wispiness > 0.0 {
            let (mut omega, mut lambda) = (0.05 * self.wispiness, 10.0);
            for _ in 0..2 {
                pp += omega * gradient(lambda * pp);
                omega *= 0.5;
                lambda *= 1.99;
            }
        }
        let (mut d, mut omega, mut lambda) = (0.0, 0.5, 1.0);
        for _ in 0..5 {
            d += omega * noise(lambda * pp);
            omega *= 0.5;
            lambda *= 1.99;
        }
        let d = ((1.0 - p.y) * 4.5 * self.density * d).clamp(0.0, 1.0);
        // DEVIATION(pbrt): robustness. A `frequency` or point so large that the noise
        // overflows gives NaN in pbrt (NaN pixels); here no medium there.
        let d = (d + 2.0 * (0.5 - p.y).max(0.0)).clamp(0.0, 1.0);
        if d.is_nan() { 0.0 } else { d }
    }
}

/// pbrt-v4's `DNoise`: the noise's gradient by forward differences of 0.01.
fn gradient(p: Vec3) -> Vec3 {
    let n = noise(p);
    let delta = 0.01;
    (Vec3::new(noise(p + Vec3::X * delta), noise(p + Vec3::Y * delta), noise(p + Vec3::Z * delta)) - n) / delta
}

impl Field for Cloud {
    fn at(&self, u: Vec3, _emission: bool, lanes: Lanes) -> Props {
        let p = self.unit_to_box.transform_point3(u.as_dvec3()).as_vec3();
        let d = self.density_at(p);
        let (sigma_a, sigma_s) = (self.sigma_a.at(lanes), self.sigma_s.at(lanes));
        Props { sigma_t: (sigma_a + sigma_s) * d, sigma_s: sigma_s * d, emitted: Vec3::ZERO }
    }

    fn majorant(&self, _lo: Vec3, _hi: Vec3) -> f32 {
        sigma_t_bound(&self.sigma_a, &self.sigma_s)
    }

    fn emissive(&self) -> bool {
        false
    }

    /// The density is at most 1 everywhere: one bound for the whole box, as pbrt-v4.
    fn majorant_res(&self) -> usize {
        1
    }
}

/// Reads a `cloud`, placed by the CTM at its statement.
pub fn read(p: &ParamList, ctx: &mut MediumContext) -> Res<Tracked> {
    let unit_to_box = super::grid::unit_to_box(p, ctx.at)?;
    let rgb = |name| {
        let c = values::rgb(p, name, &ctx.spectra, Range::NonNegative)?.unwrap_or(Vec3::ONE);
        Ok(Sigma::new(c, ctx.spectral))
    };
    let field = Cloud {
        sigma_a: rgb("sigma_a")?,
        sigma_s: rgb("sigma_s")?,
        density: values::float(p, "density", 1.0, Range::Any)?,
        wispiness: values::float(p, "wispiness", 1.0, Range::Any)?,
        frequency: values::float(p, "frequency", 5.0, Range::Any)?,
        unit_to_box,
    };
    let phase = HenyeyGreenstein::new(super::asymmetry(p)?);
    super::finite(Tracked::new(ctx.medium_to_world * unit_to_box, phase, Arc::new(field)), ctx.at)
}
