//! Equirectangular environment maps for infinite lights (pbrt-v3's mapping).
//!
//! ```text
//! AttributeBegin Rotate -90 1 0 0
//!   LightSource "infinite" "string mapname" "sky.exr" "rgb scale" [1 1 1]   # v3 (v4: filename)
//! AttributeEnd
//! ```
//! In light space, direction (θ, φ) looks up (s, t) = (φ/2π, θ/π) with t = 0 at the
//! image's top row (θ = 0 is light-space +z). Directions are importance sampled from a
//! 2D piecewise-constant distribution of luminance × sin θ, with the matching pdf.

use crate::imageio::{RgbImage, Wrap, lookup};
use crate::spectrum::{Rgb, luminance};
use glam::{DMat3, DVec3, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// A 2D piecewise-constant distribution over [0,1]² on an `nu × nv` grid.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    nu: usize,
    nv: usize,
    /// Per row: cumulative weights of its cells.
    rows: Vec<Vec<f64>>,
    /// Cumulative row totals.
    marginal: Vec<f64>,
}

impl Distribution2D {
    pub fn new(f: &[f64], nu: usize, nv: usize) -> Distribution2D {
        let mut rows = Vec::with_capacity(nv);
        let mut marginal = Vec::with_capacity(nv);
        let mut total = 0.0;
        for v in 0..nv {
            let mut acc = 0.0;
            let row: Vec<f64> = (0..nu)
                .map(|u| {
                    acc += f[v * nu + u].max(0.0);
                    acc
                })
                .collect();
            total += acc;
            marginal.push(total);
            rows.push(row);
        }
        Distribution2D { nu, nv, rows, marginal }
    }

    fn total(&self) -> f64 {
        self.marginal.last().copied().unwrap_or(0.0)
    }

    /// A continuous point in [0,1]² and its density.
    pub fn sample(&self, u: [f32; 2]) -> Option<([f32; 2], f32)> {
        let total = self.total();
        if total <= 0.0 {
            return None;
        }
        let pick = |cdf: &[f64], x: f64| -> (usize, f64) {
            let sum = *cdf.last().unwrap_or(&0.0);
            let target = x * sum;
            let i = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1);
            let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
            let w = cdf[i] - lo;
            (i, if w > 0.0 { ((target - lo) / w).clamp(0.0, 1.0 - 1e-7) } else { 0.5 })
        };
        let (v, dv) = pick(&self.marginal, u[1] as f64);
        let (iu, du) = pick(&self.rows[v], u[0] as f64);
        let st = [((iu as f64 + du) / self.nu as f64) as f32, ((v as f64 + dv) / self.nv as f64) as f32];
        Some((st, self.pdf(st)))
    }

    /// The density at a point of [0,1]².
    pub fn pdf(&self, st: [f32; 2]) -> f32 {
        let total = self.total();
        if total <= 0.0 {
            return 0.0;
        }
        let iu = ((st[0] * self.nu as f32) as usize).min(self.nu - 1);
        let v = ((st[1] * self.nv as f32) as usize).min(self.nv - 1);
        let row = &self.rows[v];
        let cell = row[iu] - if iu == 0 { 0.0 } else { row[iu - 1] };
        (cell / total * (self.nu * self.nv) as f64) as f32
    }
}

/// An environment map with its orientation and sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvMap {
    img: Arc<RgbImage>,
    scale: Rgb,
    light_from_world: DMat3,
    world_from_light: DMat3,
    distribution: Distribution2D,
    pub average_luminance: f32,
}

impl EnvMap {
    pub fn new(img: Arc<RgbImage>, scale: Rgb, world_from_light: DMat3) -> EnvMap {
        let (w, h) = (img.width, img.height);
        let f: Vec<f64> = (0..w * h)
            .map(|i| {
                let theta = ((i / w) as f32 + 0.5) / h as f32 * PI;
                luminance(Vec3::from(img.pixels[i])) as f64 * theta.sin() as f64
            })
            .collect();
        let average_luminance =
            img.pixels.iter().map(|p| luminance(Vec3::from(*p))).sum::<f32>() / (w * h).max(1) as f32;
        EnvMap {
            distribution: Distribution2D::new(&f, w.max(1), h.max(1)),
            light_from_world: world_from_light.inverse(),
            world_from_light,
            scale,
            img,
            average_luminance: average_luminance * luminance(scale),
        }
    }

    fn st_of(&self, w: Vec3) -> ([f32; 2], f32) {
        let l = (self.light_from_world * w.as_dvec3()).normalize();
        let theta = l.z.clamp(-1.0, 1.0).acos();
        let mut phi = l.y.atan2(l.x);
        if phi < 0.0 {
            phi += std::f64::consts::TAU;
        }
        ([(phi / std::f64::consts::TAU) as f32, (theta / std::f64::consts::PI) as f32], theta.sin() as f32)
    }

    /// Radiance arriving from world direction `w`.
    #[inline]
    pub fn le(&self, w: Vec3) -> Rgb {
        let (st, _) = self.st_of(w);
        lookup(&self.img, st[0], st[1], Wrap::Repeat, true) * self.scale
    }

    /// A world direction toward the environment, importance sampled; solid-angle pdf.
    pub fn sample(&self, u: [f32; 2]) -> Option<(Vec3, f32)> {
        let (st, pdf_uv) = self.distribution.sample(u)?;
        let (theta, phi) = (st[1] as f64 * std::f64::consts::PI, st[0] as f64 * std::f64::consts::TAU);
        let sin_t = theta.sin();
        if sin_t <= 0.0 {
            return None;
        }
        let l = DVec3::new(sin_t * phi.cos(), sin_t * phi.sin(), theta.cos());
        let w = (self.world_from_light * l).normalize().as_vec3();
        Some((w, pdf_uv / (2.0 * PI * PI * sin_t as f32)))
    }

    pub fn pdf(&self, w: Vec3) -> f32 {
        let (st, sin_t) = self.st_of(w);
        if sin_t <= 0.0 { 0.0 } else { self.distribution.pdf(st) / (2.0 * PI * PI * sin_t) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn importance_sampled_directions_integrate_to_one_and_match_the_pdf() {
        let mut img = RgbImage::new(16, 8);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [1.0 + (i % 5) as f32, 0.5, (i % 3) as f32];
        }
        let env = EnvMap::new(Arc::new(img), Vec3::ONE, DMat3::from_rotation_x(0.4));
        let mut rng = crate::sampling::Rng::new(3);
        // E[1/pdf] over sampled directions is the sphere's 4π.
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let (w, pdf) = env.sample(rng.uniform2()).unwrap();
            assert!((env.pdf(w) - pdf).abs() <= 2e-3 * pdf, "{} vs {pdf}", env.pdf(w));
            sum += 1.0 / pdf as f64;
        }
        assert!((sum / n as f64 - 4.0 * std::f64::consts::PI).abs() < 0.05, "{}", sum / n as f64);
    }
}
