//! Environment maps for infinite lights, in the mapping of the file's pbrt.
//!
//! ```text
//! AttributeBegin Rotate -90 1 0 0
//!   LightSource "infinite" "string mapname" "sky.exr" "rgb scale" [1 1 1]   # v3
//! AttributeEnd
//! LightSource "infinite" "string filename" "sky-equalarea.exr"               # v4
//! ```
//! - pbrt-v3 (latitude-longitude): in light space, direction (θ, φ) looks up
//!   (s, t) = (φ/2π, θ/π), bilinearly, with t = 0 at the image's top row (θ = 0 is
//!   light-space +z). Directions are importance sampled from a 2D piecewise-constant
//!   distribution of luminance × sin θ.
//! - pbrt-v4 (equal-area): the square image is Clarberg's equal-area map of the
//!   sphere ([`crate::math::equal_area`]), light-space +z at its centre; a direction
//!   reads the texel it falls in (no filtering, as pbrt-v4's `LookupNearest`), and
//!   directions are sampled from the texels' channel means, every texel covering the
//!   same solid angle 4π/(w·h).

use crate::imageio::{RgbImage, Wrap, lookup};
use crate::math::equal_area;
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

/// How a map's texels cover the sphere of directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapping {
    /// pbrt-v3's latitude-longitude map, filtered bilinearly.
    Equirect,
    /// pbrt-v4's equal-area square, nearest texel.
    EqualArea,
}

/// An environment map with its orientation and sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvMap {
    img: Arc<RgbImage>,
    scale: Rgb,
    light_from_world: DMat3,
    world_from_light: DMat3,
    mapping: Mapping,
    distribution: Distribution2D,
    pub average_luminance: f32,
}

impl EnvMap {
    pub fn new(img: Arc<RgbImage>, scale: Rgb, world_from_light: DMat3, mapping: Mapping) -> EnvMap {
        let (w, h) = (img.width, img.height);
        let f: Vec<f64> = match mapping {
            Mapping::Equirect => (0..w * h)
                .map(|i| {
                    let theta = ((i / w) as f32 + 0.5) / h as f32 * PI;
                    luminance(Vec3::from(img.pixels[i])) as f64 * theta.sin() as f64
                })
                .collect(),
            // Every texel spans the same solid angle; pbrt-v4 weighs them by the mean
            // of their channels (here of what they emit, below).
            Mapping::EqualArea => {
                img.pixels.iter().map(|p| p.iter().map(|c| c.max(0.0)).sum::<f32>() as f64 / 3.0).collect()
            }
        };
        let average_luminance =
            img.pixels.iter().map(|p| luminance(Vec3::from(*p))).sum::<f32>() / (w * h).max(1) as f32;
        EnvMap {
            distribution: Distribution2D::new(&f, w.max(1), h.max(1)),
            light_from_world: world_from_light.inverse(),
            world_from_light,
            mapping,
            scale,
            img,
            average_luminance: average_luminance * luminance(scale),
        }
    }

    /// The map's coordinates of a world direction, and the solid angle per unit of
    /// their area there, which divides their density into a solid-angle one (0 where
    /// the map has no area: the equirectangular poles).
    fn st_of(&self, w: Vec3) -> ([f32; 2], f32) {
        let l = (self.light_from_world * w.as_dvec3()).normalize();
        match self.mapping {
            Mapping::Equirect => {
                let theta = l.z.clamp(-1.0, 1.0).acos();
                let phi = l.y.atan2(l.x).rem_euclid(std::f64::consts::TAU);
                let st = [(phi / std::f64::consts::TAU) as f32, (theta / std::f64::consts::PI) as f32];
                (st, (2.0 * PI * PI * theta.sin() as f32).max(0.0))
            }
            Mapping::EqualArea => (equal_area::sphere_to_square(l).map(|x| x as f32), 4.0 * PI),
        }
    }

    /// Radiance arriving from world direction `w`.
    #[inline]
    pub fn le(&self, w: Vec3) -> Rgb {
        let (st, _) = self.st_of(w);
        let texel = match self.mapping {
            Mapping::Equirect => lookup(&self.img, st[0], st[1], Wrap::Repeat, true),
            Mapping::EqualArea => {
                let (wd, ht) = (self.img.width, self.img.height);
                let x = ((st[0] * wd as f32) as usize).min(wd - 1);
                let y = ((st[1] * ht as f32) as usize).min(ht - 1);
                // Negative channels emit nothing (pbrt-v4's `ClampZero`).
                Vec3::from(self.img.pixels[y * wd + x]).max(Vec3::ZERO)
            }
        };
        texel * self.scale
    }

    /// A world direction toward the environment, importance sampled; solid-angle pdf.
    pub fn sample(&self, u: [f32; 2]) -> Option<(Vec3, f32)> {
        let (st, pdf_uv) = self.distribution.sample(u)?;
        let (l, area) = match self.mapping {
            Mapping::Equirect => {
                let (theta, phi) = (st[1] as f64 * std::f64::consts::PI, st[0] as f64 * std::f64::consts::TAU);
                let sin_t = theta.sin();
                if sin_t <= 0.0 {
                    return None;
                }
                (DVec3::new(sin_t * phi.cos(), sin_t * phi.sin(), theta.cos()), 2.0 * PI * PI * sin_t as f32)
            }
            Mapping::EqualArea => (equal_area::square_to_sphere(st.map(f64::from)), 4.0 * PI),
        };
        let w = (self.world_from_light * l).normalize().as_vec3();
        Some((w, pdf_uv / area))
    }

    pub fn pdf(&self, w: Vec3) -> f32 {
        let (st, area) = self.st_of(w);
        if area <= 0.0 { 0.0 } else { self.distribution.pdf(st) / area }
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
        let env = EnvMap::new(Arc::new(img), Vec3::ONE, DMat3::from_rotation_x(0.4), Mapping::Equirect);
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

    fn equal_area_map(n: usize, rotation: DMat3) -> EnvMap {
        let mut img = RgbImage::new(n, n);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [(i % 7) as f32 + 0.5, (i % 3) as f32, (i / n) as f32 * 0.1];
        }
        EnvMap::new(Arc::new(img), Vec3::ONE, rotation, Mapping::EqualArea)
    }

    #[test]
    fn an_equal_area_map_gives_each_direction_the_texel_it_falls_in() {
        // The texel whose centre maps to a direction is the one that direction reads,
        // through the light's rotation: no filtering, no flip.
        let rotation = DMat3::from_rotation_y(0.5) * DMat3::from_rotation_x(-std::f64::consts::FRAC_PI_2);
        let (n, env) = (16, equal_area_map(16, rotation));
        for (i, texel) in env.img.pixels.iter().enumerate() {
            let uv = [((i % n) as f64 + 0.5) / n as f64, ((i / n) as f64 + 0.5) / n as f64];
            let w = (rotation * equal_area::square_to_sphere(uv)).as_vec3();
            assert_eq!(env.le(w), Vec3::from(*texel), "texel {i}");
        }
        // Light-space +z is the square's centre.
        assert_eq!(env.st_of((rotation * DVec3::Z).as_vec3()).0.map(|x| (x * 1e4).round() / 1e4), [0.5, 0.5]);
    }

    #[test]
    fn negative_channels_of_an_equal_area_map_emit_nothing() {
        // pbrt-v4 clamps each channel at zero; the texel's positive channel is still
        // sampled (its density is not zero).
        let mut img = RgbImage::new(2, 2);
        img.pixels = vec![[-4.0, 1.0, 1.0], [0.0; 3], [0.0; 3], [0.0; 3]];
        let env = EnvMap::new(Arc::new(img), Vec3::ONE, DMat3::IDENTITY, Mapping::EqualArea);
        let (w, pdf) = env.sample([0.3, 0.6]).unwrap();
        assert_eq!(env.le(w), Vec3::new(0.0, 1.0, 1.0));
        assert!((pdf - 1.0 / PI).abs() < 1e-5, "one texel of four: {pdf}");
    }

    #[test]
    fn equal_area_sampling_integrates_to_the_sphere_and_matches_its_pdf() {
        let env = equal_area_map(32, DMat3::from_rotation_z(0.3));
        let mut rng = crate::sampling::Rng::new(5);
        let n = 200_000;
        let (mut sum, mut radiance, mut off) = (0.0, 0.0, 0);
        for _ in 0..n {
            let (w, pdf) = env.sample(rng.uniform2()).unwrap();
            // pbrt-v4's inverse map uses a polynomial arctangent: a direction sampled
            // right at a texel's edge may read back from its neighbour.
            off += usize::from((env.pdf(w) - pdf).abs() > 1e-3 * pdf);
            sum += 1.0 / pdf as f64;
            radiance += (env.le(w).element_sum() / 3.0) as f64 / pdf as f64;
        }
        assert!(off < n / 1000, "{off} of {n} samples read another texel's density");
        assert!((sum / n as f64 - 4.0 * std::f64::consts::PI).abs() < 0.05, "{}", sum / n as f64);
        // ∫ L dω = 4π × the texels' mean, each texel covering 4π/N².
        let mean = env.img.pixels.iter().map(|p| p.iter().sum::<f32>() as f64 / 3.0).sum::<f64>() / 1024.0;
        let estimate = radiance / n as f64;
        assert!((estimate / (4.0 * std::f64::consts::PI * mean) - 1.0).abs() < 1e-3, "{estimate}");
    }
}
