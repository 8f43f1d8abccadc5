//! pbrt-v4's standard illuminants by temperature (`Spectra::D`): CIE daylight from
//! 4000 K, a blackbody below, as its film's `whitebalance` uses them.
//!
//! ```text
//! Film "rgb" "float whitebalance" 5000      # the scene is lit by 5000 K daylight
//! ```

use super::cie::five_nm;
use super::data::{CIE_S0, CIE_S1, CIE_S2};

/// Planck's law (W·sr⁻¹·m⁻³) at `lambda` nm; 0 for a temperature ≤ 0.
pub fn planck(lambda: f64, kelvin: f64) -> f64 {
    if kelvin <= 0.0 {
        return 0.0;
    }
    let (c, h, kb) = (299_792_458.0, 6.626_070_15e-34, 1.380_649e-23);
    let l = lambda * 1e-9;
    2.0 * h * c * c / (l.powi(5) * ((h * c / (l * kb * kelvin)).exp() - 1.0))
}

/// A blackbody normalised to 1 at its peak (pbrt-v4's `BlackbodySpectrum`), λ in nm.
pub fn blackbody_normalized(lambda: f64, kelvin: f64) -> f64 {
    let peak = 2.897_771_955e-3 / kelvin * 1e9;
    planck(lambda, kelvin) / planck(peak, kelvin)
}

/// The illuminant of colour temperature `kelvin`, as a function of λ (nm): CIE
/// daylight at the correlated temperature (the temperature × 1.4388/1.4380, the
/// revision of the radiation constant), or a blackbody below 4000 K.
pub fn std_illuminant(kelvin: f64) -> impl Fn(f64) -> f64 {
    let cct = kelvin * 1.4388 / 1.4380;
    let x = if cct <= 7000.0 {
        -4.607e9 / cct.powi(3) + 2.9678e6 / (cct * cct) + 0.09911e3 / cct + 0.244063
    } else {
        -2.0064e9 / cct.powi(3) + 1.9018e6 / (cct * cct) + 0.24748e3 / cct + 0.23704
    };
    let y = -3.0 * x * x + 2.870 * x - 0.275;
    let m = 0.0241 + 0.2562 * x - 0.7341 * y;
    let m1 = (-1.3515 - 1.7703 * x + 5.9114 * y) / m;
    let m2 = (0.0300 - 31.4424 * x + 30.0717 * y) / m;
    move |lambda: f64| {
        if cct < 4000.0 {
            return blackbody_normalized(lambda, cct);
        }
        // pbrt-v4 samples its illuminants at whole nanometres.
        let l = lambda.round();
        (five_nm(&CIE_S0, 300.0, l) + m1 * five_nm(&CIE_S1, 300.0, l) + m2 * five_nm(&CIE_S2, 300.0, l)) * 0.01
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::cie;

    fn xy(s: impl Fn(f64) -> f64) -> [f64; 2] {
        crate::spectrum::colorspace::chromaticity(cie::spectrum_to_xyz(s))
    }

    #[test]
    fn daylight_at_6504_kelvin_is_d65s_white() {
        // D65 is daylight at 6504 K (6500 K before the radiation constant's revision):
        // chromaticity (0.3127, 0.3290).
        let [x, y] = xy(std_illuminant(6500.0));
        assert!((x - 0.3127).abs() < 5e-4 && (y - 0.3290).abs() < 5e-4, "{x} {y}");
    }

    #[test]
    fn below_4000_kelvin_the_illuminant_is_a_blackbody() {
        // The Planckian locus at 3000 K: (0.4369, 0.4041).
        let [x, y] = xy(std_illuminant(3000.0 * 1.4380 / 1.4388));
        assert!((x - 0.4369).abs() < 1e-3 && (y - 0.4041).abs() < 1e-3, "{x} {y}");
        assert!((blackbody_normalized(2.897_771_955e-3 / 5500.0 * 1e9, 5500.0) - 1.0).abs() < 1e-12);
        assert!(blackbody_normalized(400.0, 5500.0) < 1.0 && blackbody_normalized(700.0, 5500.0) < 1.0);
    }
}
