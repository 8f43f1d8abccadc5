//! A medium's colours at the wavelengths a path carries. In RGB (pbrt-v3's files) they
//! are the RGB the file gives; when the scene renders spectrally (pbrt-v4's files) they
//! are pbrt-v4's spectra of that RGB at the pass's wavelengths: σa and σs as
//! `RGBUnboundedSpectrum`, the emission `Le` as `RGBIlluminantSpectrum`. Each spectrum
//! is fitted once, when the medium is read, so a lookup costs three sigmoid
//! evaluations.
//!
//! ```text
//! MakeNamedMedium "dye" "string type" "homogeneous"
//!     "rgb sigma_a" [0.9 0.1 0.02] "rgb sigma_s" [0.2 0.2 0.2]   # σa: a spectrum; σs: grey, flat
//! ```
//!
//! The transmittance of a spectral medium is the exponential of each wavelength's
//! σt, which is not the exponential of an RGB σt: a dye's colour through a thick
//! layer differs, as it does in pbrt-v4.

use crate::spectrum::colorspace::ColorSpaceName;
use crate::spectrum::sigmoid::{RgbIlluminantSpectrum, RgbUnboundedSpectrum};
use crate::spectrum::transport::PassSpectrum;
use glam::Vec3;

/// The wavelengths of the pass under way, `None` for a scene rendered in RGB.
pub type Lanes<'a> = Option<&'a PassSpectrum>;

/// An attenuation coefficient (σa, σs): its RGB and, where the scene renders
/// spectrally and the RGB is not grey (a grey's spectrum is flat), its spectrum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sigma {
    pub rgb: Vec3,
    spectrum: Option<RgbUnboundedSpectrum>,
}

impl Sigma {
    /// `space`: the colour space of a spectral scene, `None` in RGB.
    pub fn new(rgb: Vec3, space: Option<ColorSpaceName>) -> Sigma {
        let grey = rgb.x == rgb.y && rgb.y == rgb.z;
        // DEVIATION(pbrt): robustness. A value past half the float range has a spectrum
        // of scale Inf (NaN pixels in pbrt); it keeps its RGB, which the readers' range
        // checks then judge.
        let spectrum =
            space.filter(|_| !grey && fits(rgb)).map(|s| RgbUnboundedSpectrum::new(s, rgb.max(Vec3::ZERO).to_array()));
        Sigma { rgb, spectrum }
    }

    #[inline]
    pub fn at(&self, lanes: Lanes) -> Vec3 {
        match (lanes, &self.spectrum) {
            (Some(p), Some(s)) => p.values(|l| s.eval(l)),
            _ => self.rgb,
        }
    }

    /// The largest value at any wavelength (spectral) or in any channel (RGB).
    pub fn bound(&self) -> f32 {
        match &self.spectrum {
            Some(s) => spectrum_max(s),
            None => self.rgb.max_element(),
        }
    }
}

/// Whether an RGB's pbrt-v4 spectrum has a finite scale (2·max).
pub fn fits(rgb: Vec3) -> bool {
    (2.0 * rgb.max_element()).is_finite()
}

/// The largest value of an unbounded spectrum over the visible range (Inf where its
/// scale is).
pub fn spectrum_max(s: &RgbUnboundedSpectrum) -> f32 {
    if s.scale.is_finite() { s.scale * s.rsp.max_value() } else { f32::INFINITY }
}

/// A bound of σa + σs at every wavelength or channel; in RGB the largest channel of
/// the sum, as before spectra.
pub fn sigma_t_bound(a: &Sigma, s: &Sigma) -> f32 {
    if a.spectrum.is_none() && s.spectrum.is_none() {
        return (a.rgb + s.rgb).max_element();
    }
    a.bound() + s.bound()
}

/// An emission `Le`: its RGB and, where the scene renders spectrally, its illuminant
/// spectrum (a grey one too: it is the colour space's white, not flat).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitted {
    pub rgb: Vec3,
    spectrum: Option<RgbIlluminantSpectrum>,
}

impl Emitted {
    pub fn new(rgb: Vec3, space: Option<ColorSpaceName>) -> Emitted {
        let spectrum = space
            .filter(|_| rgb != Vec3::ZERO && fits(rgb))
            .map(|s| RgbIlluminantSpectrum::new(s, rgb.max(Vec3::ZERO).to_array()));
        Emitted { rgb, spectrum }
    }

    pub const NONE: Emitted = Emitted { rgb: Vec3::ZERO, spectrum: None };

    #[inline]
    pub fn at(&self, lanes: Lanes) -> Vec3 {
        match (lanes, &self.spectrum) {
            (Some(p), Some(s)) => p.values(|l| s.eval(l)),
            _ => self.rgb,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::transport::PassSpectrum;

    #[test]
    fn rgb_scenes_read_the_rgb_and_greys_stay_flat() {
        let space = Some(ColorSpaceName::Srgb);
        let p = PassSpectrum::for_pass(ColorSpaceName::Srgb, None, 5);
        let red = Vec3::new(0.9, 0.1, 0.02);
        assert_eq!(Sigma::new(red, None).at(Some(&p)), red);
        assert_eq!(Sigma::new(red, space).at(None), red);
        assert_eq!(Sigma::new(Vec3::splat(0.4), space).at(Some(&p)), Vec3::splat(0.4));
        let lanes = Sigma::new(red, space).at(Some(&p));
        assert_ne!(lanes, red);
        assert!(lanes.min_element() >= 0.0);
    }

    /// The bound holds at every wavelength, and at 2·max(RGB) at most (the unbounded
    /// spectrum's scale).
    #[test]
    fn the_bound_holds_over_the_visible_range() {
        for rgb in [Vec3::new(0.9, 0.1, 0.02), Vec3::new(0.0, 3.0, 1.0), Vec3::new(0.2, 0.25, 0.3)] {
            let s = Sigma::new(rgb, Some(ColorSpaceName::Srgb));
            let b = s.bound();
            assert!(b <= 2.0 * rgb.max_element() + 1e-6);
            for k in 0..=470 {
                let p = PassSpectrum::of(
                    ColorSpaceName::Srgb,
                    None,
                    crate::spectrum::sampled::SampledWavelengths::sample_uniform(k as f32 / 471.0, 360.0, 830.0),
                );
                let v = s.at(Some(&p));
                assert!(v.max_element() <= b * (1.0 + 1e-5), "{rgb}: {v} above {b}");
            }
        }
    }
}
