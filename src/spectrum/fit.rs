//! Fitting the sigmoid-polynomial tables (used by `pbrt-rgb2spec`, `tools/rgb2spec.rs`).
//!
//! For a target RGB, find (c0, c1, c2) whose spectrum S(c0 t² + c1 t + c2), t = λ
//! mapped to [0, 1] over 360–830 nm, lit by the colour space's white and seen by the
//! CIE 1931 observer, has that RGB: Gauss–Newton on the CIELAB difference, with a
//! central-difference Jacobian. The integrals use the CIE tables at 5 nm, linearly
//! interpolated, by the composite Simpson 3/8 rule on a grid three times finer (the
//! quadrature of Jakob and Hanika's reference optimiser, so the tables agree with
//! those fitted there). Each table cell starts from its neighbour's solution, walking
//! the max component up from a fifth of the range and then down, as they do.

use super::colorspace::{ColorSpaceName, Matrix3, mul_vec};
use super::data::{CIE_X, CIE_Y, CIE_Z};
use super::sigmoid::RgbToSpectrumTable;
use rayon::prelude::*;

const COARSE: usize = 95;
const FINE: usize = (COARSE - 1) * 3 + 1;

/// The quadrature of one colour space, ready to fit RGB values in it.
pub struct Fitter {
    /// Quadrature nodes, mapped to [0, 1].
    t: Vec<f64>,
    /// RGB matching functions × white × quadrature weight at each node.
    rgb_weights: [Vec<f64>; 3],
    xyz_from_rgb: Matrix3,
    white: [f64; 3],
}

impl Fitter {
    pub fn new(space: ColorSpaceName) -> Self {
        let rgb_from_xyz = space.rgb_from_xyz();
        let coarse = |table: &[f64], lambda: f64| {
            let x = ((lambda - 360.0) / 5.0).clamp(0.0, (COARSE - 1) as f64);
            let i = (x as usize).min(COARSE - 2);
            let w = x - i as f64;
            (1.0 - w) * table[5 * i] + w * table[5 * (i + 1)]
        };
        let h = 470.0 / (FINE - 1) as f64;
        let mut rgb_weights = [vec![0.0; FINE], vec![0.0; FINE], vec![0.0; FINE]];
        let mut white = [0.0; 3];
        for i in 0..FINE {
            let lambda = 360.0 + i as f64 * h;
            let simpson = if i == 0 || i == FINE - 1 {
                1.0
            } else if i % 3 == 0 {
                2.0
            } else {
                3.0
            };
            let weight = 3.0 / 8.0 * h * simpson * space.illuminant_at(lambda);
            let xyz = [coarse(&CIE_X, lambda), coarse(&CIE_Y, lambda), coarse(&CIE_Z, lambda)];
            let rgb = mul_vec(&rgb_from_xyz, xyz);
            for ((w, c), (sum, x)) in rgb_weights.iter_mut().zip(rgb).zip(white.iter_mut().zip(xyz)) {
                w[i] = c * weight;
                *sum += x * weight;
            }
        }
        // The white's luminance is 1 by the illuminant's scale, up to the quadrature;
        // normalise by it, so that a spectrum of 1 has luminance 1 here exactly (and an
        // RGB of (1, 1, 1) up to the 5 nm quadrature's error in chromaticity).
        let y = white[1];
        rgb_weights.iter_mut().for_each(|w| w.iter_mut().for_each(|v| *v /= y));
        let white = white.map(|c| c / y);
        let t = (0..FINE).map(|i| i as f64 / (FINE - 1) as f64).collect();
        Self { t, rgb_weights, xyz_from_rgb: space.xyz_from_rgb(), white }
    }

    /// The RGB of the spectrum with coefficients `c` (over t in [0, 1]).
    fn rgb_of(&self, c: [f64; 3]) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (i, t) in self.t.iter().enumerate() {
            let x = (c[0] * t + c[1]) * t + c[2];
            let s = 0.5 * x / (1.0 + x * x).sqrt() + 0.5;
            for (k, o) in out.iter_mut().enumerate() {
                *o += self.rgb_weights[k][i] * s;
            }
        }
        out
    }

    fn lab(&self, rgb: [f64; 3]) -> [f64; 3] {
        let xyz = mul_vec(&self.xyz_from_rgb, rgb);
        let f = |t: f64| {
            let d = 6.0 / 29.0;
            if t > d * d * d { t.cbrt() } else { t / (3.0 * d * d) + 4.0 / 29.0 }
        };
        let [fx, fy, fz] = [0, 1, 2].map(|k| f(xyz[k] / self.white[k]));
        [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
    }

    fn residual(&self, c: [f64; 3], target: [f64; 3]) -> [f64; 3] {
        let got = self.lab(self.rgb_of(c));
        std::array::from_fn(|k| target[k] - got[k])
    }

    /// Improves `c` (over t in [0, 1]) toward `rgb`: at most 15 Gauss–Newton steps.
    pub fn gauss_newton(&self, rgb: [f64; 3], c: &mut [f64; 3]) {
        const EPS: f64 = 1e-4;
        let target = self.lab(rgb);
        for _ in 0..15 {
            let r = self.residual(*c, target);
            let mut jac = [[0.0; 3]; 3];
            for i in 0..3 {
                let (mut lo, mut hi) = (*c, *c);
                lo[i] -= EPS;
                hi[i] += EPS;
                let (r0, r1) = (self.residual(lo, target), self.residual(hi, target));
                for j in 0..3 {
                    jac[j][i] = (r1[j] - r0[j]) / (2.0 * EPS);
                }
            }
            let Some(step) = solve(jac, r) else { return };
            for j in 0..3 {
                c[j] -= step[j];
            }
            let max = c[0].max(c[1]).max(c[2]);
            if max > 200.0 {
                c.iter_mut().for_each(|v| *v *= 200.0 / max);
            }
            if r.iter().map(|v| v * v).sum::<f64>() < 1e-6 {
                break;
            }
        }
    }

    /// The whole table at resolution `res`.
    pub fn table(&self, res: usize) -> RgbToSpectrumTable {
        let smoothstep = |x: f64| x * x * (3.0 - 2.0 * x);
        let scale: Vec<f64> = (0..res).map(|k| smoothstep(smoothstep(k as f64 / (res - 1) as f64))).collect();
        let mut coeffs = vec![0.0f32; 9 * res * res * res];
        // One chunk per (max component, y): its res × res cells of (z, x) are filled
        // in the loop below, into their places in the [l][z][y][x] layout afterwards.
        let rows: Vec<(usize, usize, Vec<[f32; 3]>)> = (0..3 * res)
            .into_par_iter()
            .map(|ly| (ly / res, ly % res, self.row(ly / res, ly % res, res, &scale)))
            .collect();
        for (l, j, cells) in rows {
            for (k, row) in cells.chunks(res).enumerate() {
                for (i, c) in row.iter().enumerate() {
                    let at = (((l * res + k) * res + j) * res + i) * 3;
                    coeffs[at..at + 3].copy_from_slice(c);
                }
            }
        }
        RgbToSpectrumTable { res, scale: scale.iter().map(|&s| s as f32).collect(), coeffs }
    }

    /// The cells of max component `l` and minor `y` index `j`: [z][x], in nm.
    fn row(&self, l: usize, j: usize, res: usize, scale: &[f64]) -> Vec<[f32; 3]> {
        let mut out = vec![[0.0f32; 3]; res * res];
        let y = j as f64 / (res - 1) as f64;
        for i in 0..res {
            let x = i as f64 / (res - 1) as f64;
            let start = res / 5;
            let mut fit = |k: usize, c: &mut [f64; 3]| {
                let b = scale[k];
                let mut rgb = [0.0; 3];
                rgb[l] = b;
                rgb[(l + 1) % 3] = x * b;
                rgb[(l + 2) % 3] = y * b;
                self.gauss_newton(rgb, c);
                out[k * res + i] = to_nanometres(*c);
            };
            // Up from a fifth, then down from there again, each from zero.
            let mut c = [0.0; 3];
            (start..res).for_each(|k| fit(k, &mut c));
            let mut c = [0.0; 3];
            (0..=start).rev().for_each(|k| fit(k, &mut c));
        }
        out
    }
}

/// Coefficients over t = (λ − 360) / 470 rewritten over λ in nm.
fn to_nanometres([a, b, c]: [f64; 3]) -> [f32; 3] {
    let (c0, c1) = (360.0, 1.0 / 470.0);
    [(a * c1 * c1) as f32, (b * c1 - 2.0 * a * c0 * c1 * c1) as f32, (c - b * c0 * c1 + a * (c0 * c1).powi(2)) as f32]
}

/// Solves `a · x = b` by Gaussian elimination with partial pivoting; `None` when `a`
/// is (nearly) singular.
fn solve(mut a: Matrix3, mut b: [f64; 3]) -> Option<[f64; 3]> {
    for col in 0..3 {
        let pivot = (col..3).max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs()))?;
        if a[pivot][col].abs() < 1e-15 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..3 {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col];
            for (v, p) in a[row].iter_mut().zip(pivot_row).skip(col) {
                *v -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..3).rev() {
        let rest: f64 = (row + 1..3).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - rest) / a[row][row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fit_reproduces_its_rgb() {
        let fitter = Fitter::new(ColorSpaceName::Srgb);
        for rgb in [[0.8, 0.2, 0.1], [0.1, 0.5, 0.3], [0.05, 0.05, 0.6]] {
            let mut c = [0.0; 3];
            fitter.gauss_newton(rgb, &mut c);
            let got = fitter.rgb_of(c);
            assert!((0..3).all(|k| (got[k] - rgb[k]).abs() < 1e-3), "{rgb:?} → {got:?}");
        }
    }
}
