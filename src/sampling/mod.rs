//! Random numbers and sampling helpers.
//!
//! Every sample is drawn from a sequence or generator seeded by a hash of what it is for
//! (pixel and iteration, or iteration and photon index, plus the scene seed), so the
//! thread count never changes which samples are drawn.

use glam::{Vec2, Vec3};

mod piecewise2d;
mod sobol;
#[cfg(test)]
pub(crate) mod testing;
pub use piecewise2d::{PiecewiseLinear2D, PlSample};
pub use sobol::SobolSample;

/// Which numbers drive camera paths (`--sampler`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol' points ([`SobolSample`]), a pixel's iterations being
    /// successive points: less noise per iteration.
    #[default]
    Sobol,
    /// Independent random numbers, one generator per path.
    Random,
}

impl std::str::FromStr for SamplerKind {
    type Err = String;

    /// `--sampler`'s names: `sobol` or `random`.
    fn from_str(s: &str) -> Result<SamplerKind, String> {
        match s {
            "sobol" => Ok(SamplerKind::Sobol),
            "random" => Ok(SamplerKind::Random),
            _ => Err(format!("expected sobol or random, not \"{s}\"")),
        }
    }
}

/// A small, fast generator (PCG-XSH-RR 64/32).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Rng {
    state: u64,
}

/// A 64-bit mix of several words (splitmix64 finaliser chained).
pub fn hash(words: &[u64]) -> u64 {
    hash_more(0x9e37_79b9_7f4a_7c15, words)
}

/// [`hash`] of a list's first words, then `words`: `hash_more(hash(a), b)` is
/// `hash(a ++ b)`. A loop whose words share a start hashes that start once (two of a
/// photon's four rounds).
#[inline]
pub fn hash_more(mut h: u64, words: &[u64]) -> u64 {
    for &w in words {
        h ^= w.wrapping_add(0x9e37_79b9_7f4a_7c15).wrapping_add(h << 6).wrapping_add(h >> 2);
        h = mix64(h);
    }
    h
}

/// The splitmix64 finaliser: every output bit depends on every input bit.
pub(crate) fn mix64(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Where a path's random numbers come from: a generator ([`Rng`]) or a point of a
/// low-discrepancy sequence ([`SobolSample`]).
pub trait Sampler {
    /// Uniform in [0, 1).
    fn get1d(&mut self) -> f32;
    /// Uniform in [0, 1)².
    fn get2d(&mut self) -> [f32; 2];
    /// Moves past a 2D sample the caller does not need, as [`Sampler::get2d`] would,
    /// so that the samples after it are the same either way.
    fn skip2d(&mut self) {
        self.get2d();
    }
}

impl Sampler for Rng {
    fn get1d(&mut self) -> f32 {
        self.uniform()
    }

    fn get2d(&mut self) -> [f32; 2] {
        self.uniform2()
    }
}

impl Rng {
    pub fn new(seed: u64) -> Rng {
        let mut r = Rng { state: seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407) };
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    pub fn uniform2(&mut self) -> [f32; 2] {
        [self.uniform(), self.uniform()]
    }
}

/// The radical inverse of `i` in `base` (pbrt's `RadicalInverse`): `i`'s digits
/// mirrored about the point, in [0, 1). Computed as pbrt computes it, the reversed
/// digits as an integer and then one product (in base 2 the reversed bits, exactly):
/// a sum digit by digit needs a chain of divisions, a fifth of the realistic camera's
/// exit-pupil search.
pub fn radical_inverse(base: u64, mut i: u64) -> f64 {
    let value = if base == 2 {
        i.reverse_bits() as f64 * 2f64.powi(-64)
    } else {
        let (mut reversed, mut scale) = (0u64, 1.0);
        let inv_base = 1.0 / base as f64;
        while i > 0 {
            let next = i / base;
            reversed = reversed * base + (i - next * base);
            scale *= inv_base;
            i = next;
        }
        reversed as f64 * scale
    };
    value.min(1.0 - f64::EPSILON / 2.0)
}

/// The base-5 radical inverse of `i` (pbrt's `RadicalInverse(2, i)`) in f32, in [0, 1).
pub fn radical_inverse_5(i: u64) -> f32 {
    (radical_inverse(5, i) as f32).min(1.0 - f32::EPSILON / 2.0)
}

/// Veach's power heuristic (β = 2): the MIS weight of a sample drawn with density `f`
/// against another strategy's density `g`.
pub fn power_heuristic(f: f32, g: f32) -> f32 {
    let (f2, g2) = (f * f, g * g);
    if f2.is_infinite() { 1.0 } else { f2 / (f2 + g2) }
}

/// Cosine-weighted direction about +z.
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = concentric_disk(u);
    Vec3::new(d.x, d.y, (1.0 - d.length_squared()).max(0.0).sqrt())
}

pub fn uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A direction in the cone of half-angle acos(cos_max) about +z, uniformly.
pub fn uniform_cone(u: [f32; 2], cos_max: f32) -> Vec3 {
    let cos_t = (1.0 - u[0]) + u[0] * cos_max;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u[1];
    Vec3::new(phi.cos() * sin_t, phi.sin() * sin_t, cos_t)
}

/// A discrete choice made from one uniform number, and what is left of that number.
///
/// `rest` is where the number fell within the chosen entry's share, rescaled to
/// [0, 1): uniform again, and stratified as the number was. A light chosen from the
/// first coordinate of its own 2D sample takes `rest` as that coordinate, so the points
/// drawn on each light stay as well spread as the 2D samples (a padded sampler's
/// separate choice number would pick a random half of them for each of two lights).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pick {
    pub index: usize,
    /// The probability of `index`.
    pub pmf: f32,
    pub rest: f32,
}

impl Pick {
    /// One of `n` equally likely entries, picked by `u` in [0, 1), with probability
    /// 1/`n`.
    pub fn uniform(u: f64, n: usize) -> Pick {
        let x = u * n as f64;
        let index = (x as usize).min(n - 1);
        Pick { index, pmf: 1.0 / n as f32, rest: rest_of(x - index as f64, 1.0) }
    }
}

/// `offset` over `width`, as a number in [0, 1) (0 for an empty width).
pub fn rest_of(offset: f64, width: f64) -> f32 {
    if width > 0.0 { ((offset / width) as f32).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 }
}

/// The largest f32 below 1.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A discrete distribution proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    total: f64,
}

impl Distribution1D {
    pub fn new(weights: &[f64]) -> Distribution1D {
        let mut cdf = Vec::with_capacity(weights.len());
        let mut total = 0.0;
        for w in weights {
            total += w.max(0.0);
            cdf.push(total);
        }
        Distribution1D { cdf, total }
    }

    pub fn is_empty(&self) -> bool {
        self.total <= 0.0
    }

    /// An index and its probability ([`Self::pick`] without the rest: a division less,
    /// once per photon).
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        let (index, _) = self.find(u)?;
        Some((index, self.pmf(index)))
    }

    /// An index, its probability and where `u` fell within the index's share.
    #[inline]
    pub fn pick(&self, u: f32) -> Option<Pick> {
        let (index, target) = self.find(u)?;
        let lo = if index == 0 { 0.0 } else { self.cdf[index - 1] };
        Some(Pick { index, pmf: self.pmf(index), rest: rest_of(target - lo, self.cdf[index] - lo) })
    }

    /// The index whose share holds `u`, and `u` scaled to the total.
    #[inline]
    fn find(&self, u: f32) -> Option<(usize, f64)> {
        if self.is_empty() {
            return None;
        }
        let target = u as f64 * self.total;
        let index = self.cdf.partition_point(|&c| c <= target);
        Some((index.min(self.cdf.len() - 1), target))
    }

    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        ((self.cdf[i] - lo) / self.total) as f32
    }
}

/// Concentric mapping of the unit square to the unit disk (Shirley–Chiu).
pub fn concentric_disk(u: [f32; 2]) -> Vec2 {
    let o = Vec2::new(2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if o == Vec2::ZERO {
        return o;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, std::f32::consts::FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// The point of the unit square [`concentric_disk`] maps to `p` (pbrt-v4's
/// `InvertUniformDiskConcentricSample`).
pub fn invert_concentric_disk(p: Vec2) -> [f32; 2] {
    use std::f32::consts::{FRAC_PI_4, PI};
    let r = p.length();
    if r == 0.0 {
        return [0.5, 0.5];
    }
    let mut t = p.y.atan2(p.x);
    if t < -FRAC_PI_4 {
        t += 2.0 * PI;
    }
    let o = if t < FRAC_PI_4 {
        Vec2::new(r, r * t / FRAC_PI_4)
    } else if t < 3.0 * FRAC_PI_4 {
        Vec2::new(r * (PI / 2.0 - t) / FRAC_PI_4, r)
    } else if t < 5.0 * FRAC_PI_4 {
        Vec2::new(-r, r * (PI - t) / FRAC_PI_4)
    } else {
        Vec2::new(r * (t - 1.5 * PI) / FRAC_PI_4, -r)
    };
    [(o.x + 1.0) * 0.5, (o.y + 1.0) * 0.5].map(|x| x.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_concentric_map_inverts() {
        let mut rng = Rng::new(7);
        for _ in 0..20000 {
            let u = [rng.uniform(), rng.uniform()];
            let back = invert_concentric_disk(concentric_disk(u));
            assert!((back[0] - u[0]).abs() < 1e-4 && (back[1] - u[1]).abs() < 1e-4, "{u:?} -> {back:?}");
        }
    }

    #[test]
    fn radical_inverses_are_the_reversed_digits() {
        assert_eq!(radical_inverse(2, 6), 0.375);
        assert_eq!(radical_inverse(2, 0), 0.0);
        // 5 = 12 in base 3, read backwards 21 = 7, over 3²; 7 = 12 in base 5 → 11/25.
        assert!((radical_inverse(3, 5) - 7.0 / 9.0).abs() < 1e-15);
        assert!((radical_inverse(5, 7) - 11.0 / 25.0).abs() < 1e-15);
        assert_eq!(radical_inverse_5(7), 0.44);
        assert!(radical_inverse(2, u64::MAX) < 1.0);
    }

    /// A start hashed once goes on as the whole list would: photon streams depend on it.
    #[test]
    fn a_hash_goes_on_from_its_start() {
        let words = [7u64, 3, 1 << 40, 1];
        for cut in 0..=words.len() {
            assert_eq!(hash_more(hash(&words[..cut]), &words[cut..]), hash(&words));
        }
        assert_ne!(hash(&words[..3]), hash(&words));
    }

    /// `sample` is `pick` without the rest, for few entries and many.
    #[test]
    fn a_sample_is_a_pick_without_its_rest() {
        for n in [1usize, 3, 9, 40] {
            let w: Vec<f64> = (0..n).map(|i| ((i * 7 + 1) % 5) as f64).collect();
            let d = Distribution1D::new(&w);
            for k in 0..1000 {
                let u = (k as f32 + 0.5) / 1000.0;
                let p = d.pick(u).expect("weights");
                assert_eq!(d.sample(u), Some((p.index, p.pmf)));
                assert!(w[p.index] > 0.0, "{n} {u}");
            }
        }
    }

    /// Stratified numbers picked by weight: each index gets its share, and the rests
    /// of its picks are stratified in turn (the j-th smallest of m in [j/m, (j+1)/m)).
    #[test]
    fn a_pick_leaves_each_index_a_stratified_rest() {
        let d = Distribution1D::new(&[1.0, 3.0, 0.0, 4.0]);
        let n = 8_000;
        let mut rests = vec![Vec::new(); 4];
        for k in 0..n {
            let p = d.pick((k as f32 + 0.5) / n as f32).expect("weights");
            assert!((0.0..1.0).contains(&p.rest), "{p:?}");
            assert_eq!(p.pmf, d.pmf(p.index));
            rests[p.index].push(p.rest);
        }
        assert_eq!(rests.iter().map(Vec::len).collect::<Vec<_>>(), [1_000, 3_000, 0, 4_000]);
        for r in &mut rests {
            r.sort_by(f32::total_cmp);
            let m = r.len() as f32;
            for (j, x) in r.iter().enumerate() {
                assert!(*x >= (j as f32 - 0.01) / m && *x < (j as f32 + 1.01) / m, "{j} of {m}: {x}");
            }
        }
    }
}
