//! Points inside emitting media, drawn for photons: pbrt-v4's `Le` and `temperature`
//! media send photons as lights do, so their light reaches what the camera sees after
//! any number of bounces.
//!
//! ```text
//! MakeNamedMedium "haze" "string type" "homogeneous" "rgb sigma_a" [1 1 1] "rgb Le" [2 1 .5]
//! ```
//!
//! A tracked medium (a grid) draws a voxel of its majorant grid in proportion to an
//! estimate of the emission in it (eight lookups; every voxel that may hold medium
//! keeps a small share, so no emitting point is left out), then a uniform point in the
//! voxel. A homogeneous medium fills no box of its own: its points are uniform in a box
//! the renderer gives (the scene's bounds). Either way the estimate stays unbiased: a
//! photon carries the emission at its point over the density of drawing it.

use super::Medium;
use super::tracking::Tracked;
use crate::sampling::Distribution1D;
use crate::spectrum::luminance;
use glam::{DMat4, DVec3, Vec3};

/// Where an emitting medium's photons start.
#[derive(Clone, Debug)]
pub struct EmissionPoints {
    box_to_world: DMat4,
    res: usize,
    voxels: Distribution1D,
    /// A voxel's volume in the world.
    voxel_volume: f64,
    /// ∫ luminance(σa·Le) dV·4π, roughly: the medium's share among the photon sources.
    pub power: f64,
}

/// A drawn point and the density of drawing it per unit of world volume.
pub struct EmissionPoint {
    pub p: Vec3,
    pub pdf: f64,
}

impl EmissionPoints {
    /// For a medium that emits: its own box (tracked media) or `bounds` (homogeneous).
    pub fn new(m: &Medium, bounds: [DVec3; 2]) -> Option<EmissionPoints> {
        if !m.emissive() {
            return None;
        }
        match m {
            Medium::Homogeneous(h) => {
                let box_to_world = DMat4::from_translation(bounds[0]) * DMat4::from_scale(bounds[1] - bounds[0]);
                let volume = (bounds[1] - bounds[0]).element_product();
                let power = luminance(h.sigma_a.rgb * h.le.rgb) as f64 * volume * 4.0 * std::f64::consts::PI;
                let voxels = Distribution1D::new(&[1.0]);
                Some(EmissionPoints { box_to_world, res: 1, voxels, voxel_volume: volume, power })
            }
            Medium::Tracked(t) => Some(tracked(t)),
        }
    }

    /// A point: `u_voxel` picks the voxel, `u` places the point in it.
    pub fn sample(&self, u_voxel: f32, u: Vec3) -> Option<EmissionPoint> {
        let (i, pmf) = self.voxels.sample(u_voxel)?;
        let n = self.res;
        let voxel = Vec3::new((i % n) as f32, ((i / n) % n) as f32, (i / (n * n)) as f32);
        let p = self.box_to_world.transform_point3(((voxel + u) / n as f32).as_dvec3()).as_vec3();
        Some(EmissionPoint { p, pdf: pmf as f64 / self.voxel_volume })
    }
}

fn tracked(t: &Tracked) -> EmissionPoints {
    let (res, box_to_world) = (t.res(), t.box_to_world());
    let mut estimates = Vec::with_capacity(res * res * res);
    for i in 0..res * res * res {
        let (x, y, z) = (i % res, (i / res) % res, i / (res * res));
        let lo = Vec3::new(x as f32, y as f32, z as f32);
        let mean = (0..8)
            .map(|k| {
                let o = Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, (k >> 2) as f32) * 0.5 + 0.25;
                luminance(t.emitted_at_unit((lo + o) / res as f32, None)).max(0.0) as f64
            })
            .sum::<f64>()
            / 8.0;
        estimates.push((mean, t.majorant_at(i) > 0.0));
    }
    let top = estimates.iter().fold(0f64, |m, e| m.max(e.0));
    let weights: Vec<f64> = estimates.iter().map(|&(e, any)| if any { e + 1e-3 * top } else { 0.0 }).collect();
    let voxel_volume = box_to_world.determinant().abs() / (res * res * res) as f64;
    let power = estimates.iter().map(|e| e.0).sum::<f64>() * voxel_volume * 4.0 * std::f64::consts::PI;
    EmissionPoints { box_to_world, res, voxels: Distribution1D::new(&weights), voxel_volume, power }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::phase::HenyeyGreenstein;
    use crate::media::sampled::SampledGrid;
    use crate::media::tracking::{Field, Props};
    use crate::sampling::{Rng, Sampler};
    use std::sync::Arc;

    /// Emission only in a ball about (0.3, 0.5, 0.5) of the unit cube, rising toward
    /// its centre; σt bounds that include empty voxels.
    #[derive(Debug)]
    struct Ember(SampledGrid<f32>);

    impl Field for Ember {
        fn at(&self, u: Vec3, _emission: bool, _lanes: crate::media::Lanes) -> Props {
            let e = (0.25 - u.distance(Vec3::new(0.3, 0.5, 0.5))).max(0.0);
            Props { sigma_t: Vec3::ONE, sigma_s: Vec3::ZERO, emitted: Vec3::new(e, 2.0 * e, 0.5 * e) }
        }
        fn majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
            self.0.max_over(lo, hi, |v| v)
        }
        fn emissive(&self) -> bool {
            true
        }
    }

    /// The mean of emission over density at the drawn points is the integral of the
    /// emission over the box (2 × 3 × 1 in the world): the points leave no emitting
    /// part out and their densities are right.
    #[test]
    fn drawn_points_integrate_the_emission() {
        let box_to_world = DMat4::from_scale(DVec3::new(2.0, 3.0, 1.0));
        let field = Ember(SampledGrid::constant(1.0));
        let t = Tracked::new(box_to_world, HenyeyGreenstein::new(0.0), Arc::new(field));
        let points = EmissionPoints::new(&Medium::Tracked(Arc::new(t.clone())), [DVec3::ZERO; 2]).unwrap();
        let n = 400_000;
        let mut rng = Rng::new(5);
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = Vec3::new(rng.get1d(), rng.get1d(), rng.get1d());
            let at = points.sample(rng.get1d(), u).unwrap();
            sum += t.emitted_at(at.p, None).y as f64 / at.pdf;
        }
        // ∫ 2·(0.25 − r) over the ball of radius 0.25 in the unit cube: 2·π·0.25⁴/3,
        // times the box's volume 6.
        let want = 2.0 * std::f64::consts::PI * 0.25f64.powi(4) / 3.0 * 6.0;
        assert!((sum / n as f64 - want).abs() < 0.01 * want, "{} against {want}", sum / n as f64);
    }
}
