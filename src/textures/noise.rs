//! Perlin noise, fractional Brownian motion and turbulence, as pbrt computes them (the
//! same permutation, gradients and quintic weights, so noise textures match pbrt's
//! images feature for feature).
//!
//! As in pbrt, octaves finer than the footprint the ray differentials give (in texture
//! space, `dpdx`, `dpdy`) are left out, the last one faded in; without differentials
//! every octave is summed.

use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::values::{self, Range, Res};
use glam::Vec3;

/// The noise textures' parameters: `octaves` and `roughness` (ω, each octave's weight
/// relative to the one before).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Octaves {
    pub octaves: u32,
    pub omega: f32,
}

impl Octaves {
    /// `octaves` (default 8, at most 32) and `roughness` (default .5).
    pub fn read(p: &ParamList) -> Res<Octaves> {
        let n = p.int("octaves")?.unwrap_or(8);
        if !(0..=32).contains(&n) {
            let at = values::span_of(p, "octaves").unwrap_or_default();
            return Err(Diagnostic::error(at, format!("\"octaves\" must be between 0 and 32, not {n}")));
        }
        Ok(Octaves { octaves: n as u32, omega: values::float(p, "roughness", 0.5, Range::Any)? })
    }
}

/// Ken Perlin's permutation of 0..=255 (the table pbrt uses).
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37, 240,
    21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88,
    237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83,
    111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216,
    80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173, 186,
    3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17,
    182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129,
    22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238,
    210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184,
    84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195,
    78, 66, 215, 61, 156, 180,
];

fn perm(i: i32) -> i32 {
    PERM[(i & 255) as usize] as i32
}

/// The gradient of lattice point (x, y, z) dotted with the offset (dx, dy, dz).
fn grad(x: i32, y: i32, z: i32, dx: f32, dy: f32, dz: f32) -> f32 {
    let h = perm(perm(perm(x) + y) + z) & 15;
    let u = if h < 8 || h == 12 || h == 13 { dx } else { dy };
    let v = if h < 4 || h == 12 || h == 13 { dy } else { dz };
    (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
}

fn weight(t: f32) -> f32 {
    let t3 = t * t * t;
    let t4 = t3 * t;
    6.0 * t4 * t - 15.0 * t4 + 10.0 * t3
}

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// Gradient noise in [-1, 1], zero at lattice points.
pub fn noise(p: Vec3) -> f32 {
    // As pbrt-v4: far-away coordinates wrap before they overflow an i32.
    let p = p.map(|c| c % (1u32 << 30) as f32);
    let (fx, fy, fz) = (p.x.floor(), p.y.floor(), p.z.floor());
    let (dx, dy, dz) = (p.x - fx, p.y - fy, p.z - fz);
    let (ix, iy, iz) = ((fx as i32) & 255, (fy as i32) & 255, (fz as i32) & 255);
    let w = |i: i32, j: i32, k: i32| grad(ix + i, iy + j, iz + k, dx - i as f32, dy - j as f32, dz - k as f32);
    let (wx, wy, wz) = (weight(dx), weight(dy), weight(dz));
    let x00 = lerp(wx, w(0, 0, 0), w(1, 0, 0));
    let x10 = lerp(wx, w(0, 1, 0), w(1, 1, 0));
    let x01 = lerp(wx, w(0, 0, 1), w(1, 0, 1));
    let x11 = lerp(wx, w(0, 1, 1), w(1, 1, 1));
    lerp(wz, lerp(wy, x00, x10), lerp(wy, x01, x11))
}

/// pbrt's two-argument noise: z = 0.5.
pub fn noise2(x: f32, y: f32) -> f32 {
    noise(Vec3::new(x, y, 0.5))
}

/// How many octaves the footprint leaves, as a real number in [0, `max`]: pbrt's
/// −1 − ½·log₂ max(|dpdx|², |dpdy|²) (a zero footprint keeps them all).
fn octave_count(dpdx: Vec3, dpdy: Vec3, max: u32) -> f32 {
    let len2 = dpdx.length_squared().max(dpdy.length_squared());
    (-1.0 - 0.5 * len2.log2()).clamp(0.0, max as f32)
}

fn smooth_step(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Σ ωⁱ·noise(λⁱ·p), λ = 1.99, over the octaves the footprint leaves (at most
/// `octaves`), the last partial one faded in (pbrt's `FBm`).
pub fn fbm(p: Vec3, dpdx: Vec3, dpdy: Vec3, omega: f32, octaves: u32) -> f32 {
    let n = octave_count(dpdx, dpdy, octaves);
    let whole = n.floor() as u32;
    let (mut sum, mut lambda, mut o) = (0.0, 1.0, 1.0);
    for _ in 0..whole {
        sum += o * noise(lambda * p);
        lambda *= 1.99;
        o *= omega;
    }
    sum + o * smooth_step(0.3, 0.7, n - whole as f32) * noise(lambda * p)
}

/// Σ ωⁱ·|noise(λⁱ·p)| as [`fbm`] counts octaves, the partial one blended from 0.2
/// and each octave left out counted as 0.2 (pbrt's `Turbulence`, its constants kept).
pub fn turbulence(p: Vec3, dpdx: Vec3, dpdy: Vec3, omega: f32, octaves: u32) -> f32 {
    let n = octave_count(dpdx, dpdy, octaves);
    let whole = n.floor() as u32;
    let (mut sum, mut lambda, mut o) = (0.0, 1.0, 1.0);
    for _ in 0..whole {
        sum += o * noise(lambda * p).abs();
        lambda *= 1.99;
        o *= omega;
    }
    let t = smooth_step(0.3, 0.7, n - whole as f32);
    sum += o * ((1.0 - t) * 0.2 + t * noise(lambda * p).abs());
    for _ in whole..octaves {
        sum += o * 0.2;
        o *= omega;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_vanishes_on_the_lattice_and_stays_bounded() {
        for p in [Vec3::ZERO, Vec3::new(3.0, -7.0, 12.0), Vec3::new(255.0, 256.0, -1.0)] {
            assert_eq!(noise(p), 0.0);
        }
        let mut max = 0.0f32;
        for i in 0..20_000 {
            let p = Vec3::new(i as f32 * 0.0137, (i as f32 * 0.731).sin() * 9.0, (i % 97) as f32 * 0.11);
            max = max.max(noise(p).abs());
        }
        assert!(max > 0.5 && max <= 1.0, "{max}");
    }

    #[test]
    fn noise_is_continuous_across_cells() {
        let a = noise(Vec3::new(0.999_999, 0.3, 0.6));
        let b = noise(Vec3::new(1.000_001, 0.3, 0.6));
        assert!((a - b).abs() < 1e-4, "{a} {b}");
    }

    #[test]
    fn matches_a_value_worked_by_hand() {
        // At (0.5, 0.5, 0.5) every weight is 1/2: the mean of the eight corner terms.
        let p = Vec3::splat(0.5);
        let mut sum = 0.0;
        for (i, j, k) in (0..8).map(|c| (c & 1, (c >> 1) & 1, c >> 2)) {
            sum += grad(i, j, k, 0.5 - i as f32, 0.5 - j as f32, 0.5 - k as f32);
        }
        assert!((noise(p) - sum / 8.0).abs() < 1e-6);
    }

    #[test]
    fn octaves_add_up() {
        let (p, z) = (Vec3::new(0.3, 1.7, -2.2), Vec3::ZERO);
        assert_eq!(fbm(p, z, z, 0.5, 1), noise(p));
        assert!((fbm(p, z, z, 0.5, 2) - (noise(p) + 0.5 * noise(1.99 * p))).abs() < 1e-6);
        assert!((turbulence(p, z, z, 0.5, 1) - (noise(p).abs() + 0.1)).abs() < 1e-6);
    }

    #[test]
    fn a_wide_footprint_drops_octaves() {
        let p = Vec3::new(0.3, 1.7, -2.2);
        // |dpdx|² = 2⁻⁶: −1 + 3 = 2 octaves exactly, nothing partial.
        let d = Vec3::new(0.125, 0.0, 0.0);
        assert_eq!(fbm(p, d, Vec3::ZERO, 0.5, 8), fbm(p, Vec3::ZERO, Vec3::ZERO, 0.5, 2));
        // A footprint wider than the coarsest octave leaves none; turbulence then counts
        // 0.2 for the (empty) partial octave and 0.2·ωⁱ for each left out, as pbrt does.
        let wide = Vec3::splat(10.0);
        assert_eq!(fbm(p, wide, wide, 0.5, 8), 0.0);
        let t: f32 = 0.2 + (0..3).map(|i| 0.2 * 0.5f32.powi(i)).sum::<f32>();
        assert!((turbulence(p, wide, wide, 0.5, 3) - t).abs() < 1e-6);
    }
}
