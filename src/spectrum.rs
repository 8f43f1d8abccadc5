//! RGB spectra: scene spectrum parameters reduced to linear sRGB.
//!
//! ```text
//! "rgb L" [1 1 1]   "color Kd" [.5 .5 .5]   "xyz L" [...]
//! "blackbody I" [5500 125]    # v3: peak-normalised spectrum × scale
//! "blackbody I" [5500]        # v4: peak-normalised (lights then normalise to luminance 1)
//! "spectrum eta" "metal-Au-eta"   "spectrum L" [400 1  500 2  600 1]
//! ```
//! Blackbody and sampled spectra are integrated against an analytic fit of the CIE 1931
//! matching functions (Wyman, Sloan and Shirley 2013) and converted XYZ → linear sRGB.
//! Named metal spectra use common RGB reductions.

use glam::Vec3;

/// Linear sRGB.
pub type Rgb = Vec3;

/// CIE 1931 2° matching functions, multi-lobe Gaussian fit.
fn cie_xyz(lambda: f64) -> [f64; 3] {
    let g = |x: f64, mu: f64, s1: f64, s2: f64| {
        let t = (x - mu) / if x < mu { s1 } else { s2 };
        (-0.5 * t * t).exp()
    };
    [
        1.056 * g(lambda, 599.8, 37.9, 31.0) + 0.362 * g(lambda, 442.0, 16.0, 26.7)
            - 0.065 * g(lambda, 501.1, 20.4, 26.2),
        0.821 * g(lambda, 568.8, 46.9, 40.5) + 0.286 * g(lambda, 530.9, 16.3, 31.1),
        1.217 * g(lambda, 437.0, 11.8, 36.0) + 0.681 * g(lambda, 459.0, 26.0, 13.8),
    ]
}

/// XYZ → linear sRGB (D65).
pub fn xyz_to_rgb(xyz: [f64; 3]) -> Rgb {
    let [x, y, z] = xyz;
    Vec3::new(
        (3.240479 * x - 1.537150 * y - 0.498535 * z) as f32,
        (-0.969256 * x + 1.875991 * y + 0.041556 * z) as f32,
        (0.055648 * x - 0.204043 * y + 1.057311 * z) as f32,
    )
}

/// ∫ s(λ) CMF(λ) dλ / ∫ ȳ(λ) dλ over 360–830 nm.
fn integrate(s: impl Fn(f64) -> f64) -> [f64; 3] {
    let (mut xyz, mut y_norm) = ([0.0; 3], 0.0);
    let mut lambda = 360.0;
    while lambda <= 830.0 {
        let c = cie_xyz(lambda);
        let v = s(lambda);
        for i in 0..3 {
            xyz[i] += v * c[i];
        }
        y_norm += c[1];
        lambda += 1.0;
    }
    xyz.map(|c| c / y_norm)
}

/// Planck's law, in arbitrary units (W·sr⁻¹·m⁻³), λ in nm.
fn planck(lambda_nm: f64, t: f64) -> f64 {
    let (c, h, kb) = (299_792_458.0, 6.626_070_15e-34, 1.380_649e-23);
    let l = lambda_nm * 1e-9;
    2.0 * h * c * c / (l.powi(5) * ((h * c / (l * kb * t)).exp() - 1.0))
}

/// ∫ȳ(λ) dλ over nanometres: what pbrt-v4's film records for a spectrum of 1 that no
/// light normalised (the emission of its temperature grids and RGB grids).
pub const CIE_Y_INTEGRAL: f32 = 106.856_895;

/// A blackbody spectrum normalised so its peak is 1, as RGB.
pub fn blackbody(kelvin: f32) -> Rgb {
    let t = kelvin.max(1.0) as f64;
    let peak = planck(2.897_771_955e-3 / t * 1e9, t);
    xyz_to_rgb(integrate(|l| planck(l, t) / peak))
}

/// Luminance (Y) of a linear sRGB colour.
pub fn luminance(c: Rgb) -> f32 {
    0.212_671 * c.x + 0.715_160 * c.y + 0.072_169 * c.z
}

/// RGB reductions of the named spectra pbrt-v4 knows (metal η and k, glass indices).
pub fn named_spectrum(name: &str) -> Option<Rgb> {
    Some(match name {
        "metal-Cu-eta" => Vec3::new(0.200, 0.924, 1.102),
        "metal-Cu-k" => Vec3::new(3.912, 2.452, 2.142),
        "metal-Au-eta" => Vec3::new(0.143, 0.374, 1.442),
        "metal-Au-k" => Vec3::new(3.983, 2.385, 1.603),
        "metal-Ag-eta" => Vec3::new(0.155, 0.116, 0.138),
        "metal-Ag-k" => Vec3::new(4.828, 3.122, 2.147),
        "metal-Al-eta" => Vec3::new(1.657, 0.880, 0.521),
        "metal-Al-k" => Vec3::new(9.224, 6.270, 4.837),
        "glass-BK7" => Vec3::splat(1.5168),
        "glass-BAF10" => Vec3::splat(1.67),
        "glass-F11" => Vec3::splat(1.62),
        _ => return None,
    })
}

/// A piecewise-linear spectrum of (λ nm, value) pairs (increasing λ) as RGB.
pub fn sampled_to_rgb(pairs: &[(f32, f32)]) -> Rgb {
    xyz_to_rgb(integrate(|l| interpolate(pairs, l as f32) as f64))
}

/// Piecewise-linear interpolation of (λ, value) pairs, clamped at the ends.
fn interpolate(pairs: &[(f32, f32)], l: f32) -> f32 {
    match pairs.iter().position(|p| p.0 >= l) {
        None => pairs.last().map_or(0.0, |p| p.1),
        Some(0) => pairs[0].1,
        Some(i) => {
            let (a, b) = (pairs[i - 1], pairs[i]);
            a.1 + (b.1 - a.1) * (l - a.0) / (b.0 - a.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_spectrum_is_illuminant_e() {
        // Equal energy is slightly pink in sRGB (its white point is D65), luminance 1.
        let c = sampled_to_rgb(&[(300.0, 1.0), (900.0, 1.0)]);
        assert!((c - Vec3::new(1.205, 0.948, 0.909)).abs().max_element() < 0.02, "{c}");
        assert!((luminance(c) - 1.0).abs() < 0.01);
    }

    #[test]
    fn blackbodies_warm_to_cool() {
        let (warm, cool) = (blackbody(2700.0), blackbody(9000.0));
        assert!(warm.x > warm.z && cool.z > cool.x, "{warm} {cool}");
        // 5500 K normalised to its peak has luminance ≈ 0.98 (pbrt-reference §1.5).
        assert!((luminance(blackbody(5500.0)) - 0.98).abs() < 0.05, "{}", luminance(blackbody(5500.0)));
    }
}
