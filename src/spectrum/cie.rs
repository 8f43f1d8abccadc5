//! The CIE 1931 observer: spectra to XYZ, as pbrt-v4 integrates them (1 nm sums from
//! 360 to 830 nm, divided by the sum of ȳ so that a spectrum of 1 has Y = 1).

use super::data::{CIE_X, CIE_Y, CIE_Z};

/// The first and last wavelengths of the tables (nm).
pub const LAMBDA_MIN: f64 = 360.0;
pub const LAMBDA_MAX: f64 = 830.0;

/// Σ ȳ(λ) over the 1 nm table: pbrt-v4's `CIE_Y_integral`.
pub fn y_integral() -> f64 {
    CIE_Y.iter().sum()
}

/// (x̄, ȳ, z̄) at `lambda`, as pbrt-v4's densely sampled spectra answer: the value at
/// the nearest whole nanometre, zero outside 360–830 nm.
pub fn cmf_at(lambda: f64) -> [f64; 3] {
    nearest_nm(lambda).map_or([0.0; 3], |i| [CIE_X[i], CIE_Y[i], CIE_Z[i]])
}

/// The index of the whole nanometre nearest `lambda` in a 1 nm table from 360 to
/// 830 nm; `None` outside it.
pub fn nearest_nm(lambda: f64) -> Option<usize> {
    let i = lambda.round() - LAMBDA_MIN;
    (0.0..=(LAMBDA_MAX - LAMBDA_MIN)).contains(&i).then_some(i as usize)
}

/// A table of 5 nm steps from `first` nm at `lambda`, interpolated linearly; zero
/// outside it (as pbrt-v4's piecewise-linear spectra).
pub fn five_nm(table: &[f64], first: f64, lambda: f64) -> f64 {
    let x = (lambda - first) / 5.0;
    if x < 0.0 || x > (table.len() - 1) as f64 {
        return 0.0;
    }
    let i = (x as usize).min(table.len() - 2);
    let t = x - i as f64;
    table[i] * (1.0 - t) + table[i + 1] * t
}

/// XYZ of a spectrum given as a function of λ (nm).
pub fn spectrum_to_xyz(s: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for (i, ((x, y), z)) in CIE_X.iter().zip(&CIE_Y).zip(&CIE_Z).enumerate() {
        let v = s(LAMBDA_MIN + i as f64);
        xyz[0] += x * v;
        xyz[1] += y * v;
        xyz[2] += z * v;
    }
    let norm = y_integral();
    xyz.map(|c| c / norm)
}

/// The luminance (Y) of a spectrum.
pub fn luminance_of(s: impl Fn(f64) -> f64) -> f64 {
    spectrum_to_xyz(s)[1]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_y_integral_is_pbrt_v4s() {
        // pbrt-v4's CIE_Y_integral, from the same CIE table.
        assert!((y_integral() - 106.856895).abs() < 1e-4, "{}", y_integral());
    }

    #[test]
    fn lookups_round_to_the_nearest_nanometre() {
        assert_eq!(cmf_at(555.4), cmf_at(555.0));
        assert_eq!(cmf_at(359.0), [0.0; 3]);
        assert_eq!(cmf_at(830.4)[1], CIE_Y[470]);
    }
}
