//! Values sampled on a regular 3D grid, as pbrt's `SampledGrid`: samples sit at voxel
//! centres of the unit cube, a lookup interpolates trilinearly, and beyond the outer
//! samples the value falls toward zero.
//!
//! ```text
//! "integer nx" 2 "integer ny" 1 "integer nz" 1 "float density" [0.5 2]   # x fastest
//! ```

use glam::Vec3;
use std::ops::{Add, Mul};

/// A grid of `n[0]·n[1]·n[2]` values, x varying fastest.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledGrid<T> {
    n: [usize; 3],
    values: Vec<T>,
}

impl<T: Copy + Default + Add<Output = T> + Mul<f32, Output = T>> SampledGrid<T> {
    /// A grid of one value (pbrt's stand-in where a grid parameter is not given).
    pub fn constant(v: T) -> SampledGrid<T> {
        SampledGrid { n: [1, 1, 1], values: vec![v] }
    }

    /// The trilinear interpolation at a point of the unit cube.
    pub fn lookup(&self, u: Vec3) -> T {
        self.lookup_by(u, |v| *v)
    }
}

impl<T: Copy> SampledGrid<T> {
    /// `values.len()` must be `n[0]·n[1]·n[2]` (the readers check it first).
    pub fn new(n: [usize; 3], values: Vec<T>) -> SampledGrid<T> {
        debug_assert_eq!(n.iter().product::<usize>(), values.len());
        SampledGrid { n, values }
    }

    fn sample(&self, x: i64, y: i64, z: i64) -> Option<&T> {
        let [nx, ny, nz] = self.n.map(|k| k as i64);
        if x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz {
            return None;
        }
        Some(&self.values[((z * ny + y) * nx + x) as usize])
    }

    /// The grid of `f` of each sample.
    pub fn map<U: Copy>(&self, f: impl Fn(T) -> U) -> SampledGrid<U> {
        SampledGrid { n: self.n, values: self.values.iter().map(|&v| f(v)).collect() }
    }

    /// The trilinear interpolation at a point of the unit cube of the samples as
    /// `convert` makes them (pbrt-v4 interpolates a grid of spectra at the sampled
    /// wavelengths this way); 0 beyond the outer samples.
    #[inline]
    pub fn lookup_by<U>(&self, u: Vec3, convert: impl Fn(&T) -> U) -> U
    where
        U: Copy + Default + Add<Output = U> + Mul<f32, Output = U>,
    {
        let s = Vec3::new(u.x * self.n[0] as f32 - 0.5, u.y * self.n[1] as f32 - 0.5, u.z * self.n[2] as f32 - 0.5);
        let i = s.floor();
        let d = s - i;
        let (x, y, z) = (i.x as i64, i.y as i64, i.z as i64);
        let at = |dx: i64, dy: i64, dz: i64| self.sample(x + dx, y + dy, z + dz).map_or(U::default(), &convert);
        let lerp = |t: f32, a: U, b: U| a * (1.0 - t) + b * t;
        let d00 = lerp(d.x, at(0, 0, 0), at(1, 0, 0));
        let d10 = lerp(d.x, at(0, 1, 0), at(1, 1, 0));
        let d01 = lerp(d.x, at(0, 0, 1), at(1, 0, 1));
        let d11 = lerp(d.x, at(0, 1, 1), at(1, 1, 1));
        lerp(d.z, lerp(d.y, d00, d10), lerp(d.y, d01, d11))
    }

    /// A bound of `size(lookup(u))` over the box `lo`–`hi`, tighter than
    /// [`Self::max_over`] for a box of a few cells of the samples: within a cell the
    /// interpolation is multilinear, so its value anywhere in the part of the box there
    /// is a convex combination of its values at that part's corners, and a convex
    /// `size` is at most their largest (raised a little for rounding). The corners are
    /// the box's own and where it meets the planes of samples.
    pub fn max_within(&self, lo: Vec3, hi: Vec3, size: impl Fn(T) -> f32) -> f32
    where
        T: Default + Add<Output = T> + Mul<f32, Output = T>,
    {
        // Per axis: the box's ends and the sample planes between them, at most 4.
        let mut stops = [[0f32; 4]; 3];
        let mut count = [0usize; 3];
        for a in 0..3 {
            let n = self.n[a] as f32;
            let (first, last) = ((lo[a] * n - 0.5).floor(), (hi[a] * n - 0.5).floor());
            if last - first > 2.0 || (last - first).is_nan() {
                return self.max_over(lo, hi, size);
            }
            stops[a][0] = lo[a];
            count[a] = 1;
            let mut k = first + 1.0;
            while k <= last {
                stops[a][count[a]] = (k + 0.5) / n;
                count[a] += 1;
                k += 1.0;
            }
            stops[a][count[a]] = hi[a];
            count[a] += 1;
        }
        let mut m = 0f32;
        for &z in &stops[2][..count[2]] {
            for &y in &stops[1][..count[1]] {
                for &x in &stops[0][..count[0]] {
                    m = m.max(size(self.lookup_by(Vec3::new(x, y, z), |v| *v)));
                }
            }
        }
        m * (1.0 + 1e-5)
    }

    /// The largest `size(v)` over the samples whose interpolation reaches the box
    /// `lo`–`hi` of the unit cube (0 where none does): a bound of `size(lookup(u))` in
    /// the box for any `size` that is convex and 0 at the default value.
    pub fn max_over(&self, lo: Vec3, hi: Vec3, size: impl Fn(T) -> f32) -> f32 {
        let range = |a: usize| {
            let n = self.n[a] as f32;
            let first = ((lo[a] * n - 0.5).floor() as i64).max(0);
            let last = ((hi[a] * n - 0.5).floor() as i64 + 1).min(self.n[a] as i64 - 1);
            first..=last
        };
        let mut m = 0f32;
        for z in range(2) {
            for y in range(1) {
                for x in range(0) {
                    m = m.max(self.sample(x, y, z).map_or(0.0, |v| size(*v)));
                }
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_between_voxel_centres_and_falls_to_zero_outside() {
        let g = SampledGrid::new([3, 1, 1], vec![0.0f32, 1.0, 4.0]);
        assert_eq!(g.lookup(Vec3::splat(0.5)), 1.0);
        assert!((g.lookup(Vec3::new(2.0 / 3.0, 0.5, 0.5)) - 2.5).abs() < 1e-5);
        // Past the last sample (x = 5/6) the value falls toward the zero beyond.
        assert!((g.lookup(Vec3::new(1.0, 0.5, 0.5)) - 2.0).abs() < 1e-5);
        assert!((g.lookup(Vec3::new(0.5, 1.0, 0.5)) - 0.5).abs() < 1e-5);
    }

    /// The bound holds at every point of every box of an 8³ split of the cube.
    #[test]
    fn max_over_bounds_every_lookup_in_the_box() {
        let values: Vec<f32> = (0..4 * 3 * 5).map(|i| ((i * 37) % 11) as f32).collect();
        let g = SampledGrid::new([4, 3, 5], values);
        let mut rng = crate::sampling::Rng::new(3);
        use crate::sampling::Sampler;
        for b in 0..512 {
            let lo = Vec3::new((b % 8) as f32, ((b / 8) % 8) as f32, (b / 64) as f32) / 8.0;
            let hi = lo + 0.125;
            let bound = g.max_over(lo, hi, |v| v);
            for _ in 0..20 {
                let u = lo + Vec3::new(rng.get1d(), rng.get1d(), rng.get1d()) * 0.125;
                assert!(g.lookup(u) <= bound + 1e-4, "box {b}: {} > {bound}", g.lookup(u));
            }
        }
    }

    /// The corner bound holds at every point of small boxes anywhere (within a cell,
    /// across cell planes, past the outer samples), is no looser than the sample
    /// maximum, and is tight where the values vary little over the box.
    #[test]
    fn max_within_bounds_every_lookup_and_is_tighter() {
        let values: Vec<f32> = (0..4 * 3 * 5).map(|i| ((i * 37) % 11) as f32).collect();
        let g = SampledGrid::new([4, 3, 5], values);
        let mut rng = crate::sampling::Rng::new(5);
        use crate::sampling::Sampler;
        let mut tighter = 0;
        for _ in 0..2000 {
            let size = 0.4 * rng.get1d().powi(3);
            let lo = Vec3::new(rng.get1d(), rng.get1d(), rng.get1d()) * (1.0 - size);
            let hi = lo + size;
            let (within, over) = (g.max_within(lo, hi, |v| v), g.max_over(lo, hi, |v| v));
            assert!(within <= over * (1.0 + 1e-5), "{within} looser than {over}");
            tighter += (within < 0.9 * over) as u32;
            for _ in 0..20 {
                let u = lo + Vec3::new(rng.get1d(), rng.get1d(), rng.get1d()) * size;
                assert!(g.lookup(u) <= within + 1e-4, "{} > {within} in {lo}..{hi}", g.lookup(u));
            }
        }
        assert!(tighter > 1000, "tighter in only {tighter} boxes of 2000");
    }
}
