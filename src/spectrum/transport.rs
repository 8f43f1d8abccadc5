//! What a path carries when a file renders spectrally (pbrt-v4's files): the values of
//! its throughput at three wavelengths, held in the lanes of the same vector type that
//! holds RGB for pbrt-v3's files. So BSDFs, lights and integrators are written once:
//! they multiply lanes, and only where a colour enters (a material's reflectance, a
//! light's emission) or leaves (the film) does the mode matter.
//!
//! ```text
//! Material "diffuse" "rgb reflectance" [.8 .2 .1]   # lanes: the sigmoid spectrum at λ₁..λ₃
//! LightSource "point" "rgb I" [1 1 1]               # lanes: the colour space's white at λ₁..λ₃
//! ```
//! pbrt-v4's SPPM draws one set of wavelengths per iteration (`passLambda`); so do we,
//! per SPPM iteration and per vcm pass ([`PassSpectrum::for_pass`]), so that camera
//! paths and photons of one iteration carry the same wavelengths and the pixels' sums,
//! checkpoints, shards and merges stay RGB.

use super::cie;
use super::colorspace::{ColorSpaceName, mul, mul_vec};
use super::sampled::{Draw, N_SAMPLES, SampledWavelengths};
use super::sensor::CameraSensor;
use super::sigmoid::{RgbAlbedoSpectrum, RgbIlluminantSpectrum, RgbUnboundedSpectrum};
use glam::{DVec3, Vec3};
use std::sync::atomic::{AtomicU32, Ordering};

// A path's lanes are a `Vec3`'s: three wavelengths.
const _: () = assert!(N_SAMPLES == 3);

/// What paths carry: RGB (as pbrt-v3) or sampled wavelengths (as pbrt-v4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colour {
    Rgb,
    Spectral,
}

impl Colour {
    /// `asked`, or what the file's pbrt does.
    pub fn chosen(asked: Option<Colour>, syntax: crate::parser::Syntax) -> Colour {
        match (asked, syntax) {
            (Some(c), _) => c,
            (None, crate::parser::Syntax::V4) => Colour::Spectral,
            (None, crate::parser::Syntax::V3) => Colour::Rgb,
        }
    }

    pub fn from_name(name: &str) -> Option<Colour> {
        match name {
            "rgb" => Some(Colour::Rgb),
            "spectral" => Some(Colour::Spectral),
            _ => None,
        }
    }
}

/// What a path's weight is multiplied by when it keeps only its first wavelength:
/// the others end, and the first now stands for all (pbrt-v4 divides its density by
/// the lanes' count instead; the film's conversion is linear, so this is the same).
pub const TERMINATE: Vec3 = Vec3::new(N_SAMPLES as f32, 0.0, 0.0);

/// What a connection of two paths that both ended their other wavelengths is
/// multiplied by, so that the first lane's growth counts once.
pub const ONCE: f32 = 1.0 / N_SAMPLES as f32;

/// The wavelengths of one pass and how its lanes become output RGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassSpectrum {
    pub space: ColorSpaceName,
    pub lambda: [f32; N_SAMPLES],
    /// Column `i`: the output RGB of lane `i` at value 1 (x̄ȳz̄(λᵢ) / (p(λᵢ)·n·Σȳ),
    /// then the colour space's RGB from XYZ).
    to_rgb: [[f32; 3]; N_SAMPLES],
}

impl PassSpectrum {
    /// The wavelengths of pass `pass`: u = the base-2 radical inverse of the pass and
    /// the lanes at u + i/3 (mod 1), so that after 2ᵐ passes the lanes have taken three
    /// interleaved sets of 2ᵐ evenly spaced quantiles of the visible density, and the
    /// first lane, the one dispersion keeps, ranges over all of it.
    // DEVIATION(pbrt): noise only. pbrt-v4 takes u in base 3 with its four lanes at
    // u + i/4. With three lanes at u + i/3, base 3 repeats one set for three passes
    // (0, ⅓ and ⅔ are each other's lanes); base 3 scaled to [0, ⅓) left white light a
    // colour cast of 3% at 16 passes and 1.6% at 64, against 0.25% at both by this
    // sequence (unit test below).
    pub fn for_pass(space: ColorSpaceName, sensor: Option<&CameraSensor>, pass: u32) -> PassSpectrum {
        PassSpectrum::of(space, sensor, pass_wavelengths(Draw::Visible, pass))
    }

    /// The lanes at wavelengths `w`, recorded by the CIE observer or by a camera's
    /// curves and matrix (pbrt-v4's `PixelSensor::ToSensorRGB`, then its
    /// `XYZFromSensorRGB`).
    pub fn of(space: ColorSpaceName, sensor: Option<&CameraSensor>, w: SampledWavelengths) -> PassSpectrum {
        let m = match sensor {
            None => space.rgb_from_xyz(),
            Some(s) => mul(&space.rgb_from_xyz(), &s.xyz_from_sensor),
        };
        let norm = N_SAMPLES as f64 * cie::y_integral();
        let to_rgb = std::array::from_fn(|i| {
            if w.pdf[i] <= 0.0 {
                return [0.0; 3];
            }
            let lambda = w.lambda[i] as f64;
            let seen = sensor.map_or_else(|| cie::cmf_at(lambda), |s| s.response(lambda));
            mul_vec(&m, seen.map(|c| c / (w.pdf[i] as f64 * norm))).map(|c| c as f32)
        });
        PassSpectrum { space, lambda: w.lambda, to_rgb }
    }

    /// A spectrum's values at the pass's wavelengths, in the lanes.
    #[inline]
    pub fn values(&self, spectrum: impl Fn(f32) -> f32) -> Vec3 {
        Vec3::from(self.lambda.map(spectrum))
    }

    /// A reflectance: `rgb` clamped to [0, 1], upsampled as pbrt-v4's
    /// `RGBAlbedoSpectrum`.
    #[inline]
    pub fn albedo(&self, rgb: Vec3) -> Vec3 {
        let rgb = rgb.clamp(Vec3::ZERO, Vec3::ONE);
        if rgb.x == rgb.y && rgb.y == rgb.z {
            return rgb; // a grey is flat
        }
        let s = RgbAlbedoSpectrum::new(self.space, rgb.to_array());
        self.values(|l| s.eval(l))
    }

    /// A value without bound (η, k, σ), as pbrt-v4's `RGBUnboundedSpectrum`.
    #[inline]
    pub fn unbounded(&self, rgb: Vec3) -> Vec3 {
        let rgb = rgb.max(Vec3::ZERO);
        if rgb.x == rgb.y && rgb.y == rgb.z {
            return rgb;
        }
        let s = RgbUnboundedSpectrum::new(self.space, rgb.to_array());
        self.values(|l| s.eval(l))
    }

    /// An emitted colour, as pbrt-v4's `RGBIlluminantSpectrum` normalised by its
    /// lights (the space's white at luminance 1, times the unbounded shape).
    #[inline]
    pub fn illuminant(&self, rgb: Vec3) -> Vec3 {
        if rgb == Vec3::ZERO {
            return rgb;
        }
        let s = RgbIlluminantSpectrum::new(self.space, rgb.max(Vec3::ZERO).to_array());
        self.values(|l| s.eval(l))
    }

    /// Output RGB of lanes `v` (what pbrt-v4's `Film::ToOutputRGB` gives for the
    /// `cie1931` sensor before white balance and exposure), in f64 as pixels sum.
    #[inline]
    pub fn to_rgb(&self, v: DVec3) -> DVec3 {
        let (c, v) = (self.to_rgb, v.to_array());
        let ch = |k: usize| (0..N_SAMPLES).map(|i| c[i][k] as f64 * v[i]).sum::<f64>();
        DVec3::new(ch(0), ch(1), ch(2))
    }
}

/// The wavelengths of pass `pass` drawn as `draw` says (see [`PassSpectrum::for_pass`]).
pub fn pass_wavelengths(draw: Draw, pass: u32) -> SampledWavelengths {
    draw.sample(radical_inverse_2(pass))
}

/// The van der Corput sequence: `i`'s bits mirrored about the binary point.
pub fn radical_inverse_2(i: u32) -> f32 {
    crate::sampling::radical_inverse(2, i as u64) as f32
}

/// The pass under way, readable by every thread that traces for it. One pass renders
/// at a time; the integrator sets it before the pass's work starts and reads go
/// through relaxed atomics, which cost a plain load (a lock would bounce a cache line
/// between the cores on every hit).
#[derive(Debug)]
pub struct PassCell {
    space: ColorSpaceName,
    sensor: Option<CameraSensor>,
    draw: Draw,
    bits: [AtomicU32; 2 * N_SAMPLES + 3 * N_SAMPLES],
}

impl PassCell {
    pub fn new(space: ColorSpaceName, sensor: Option<CameraSensor>, draw: Draw) -> PassCell {
        let cell = PassCell { space, sensor, draw, bits: std::array::from_fn(|_| AtomicU32::new(0)) };
        cell.begin(0);
        cell
    }

    /// Sets pass `pass`'s wavelengths.
    pub fn begin(&self, pass: u32) {
        let p = PassSpectrum::of(self.space, self.sensor.as_ref(), pass_wavelengths(self.draw, pass));
        let values = p.lambda.iter().chain(p.to_rgb.iter().flatten());
        for (slot, v) in self.bits.iter().zip(values) {
            slot.store(v.to_bits(), Ordering::Relaxed);
        }
    }

    #[inline]
    pub fn get(&self) -> PassSpectrum {
        let f = |k: usize| f32::from_bits(self.bits[k].load(Ordering::Relaxed));
        PassSpectrum {
            space: self.space,
            lambda: std::array::from_fn(f),
            to_rgb: std::array::from_fn(|i| std::array::from_fn(|k| f(N_SAMPLES + 3 * i + k))),
        }
    }

    pub fn space(&self) -> ColorSpaceName {
        self.space
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_light_on_a_grey_comes_out_grey_on_average() {
        // Over many passes, the illuminant (1, 1, 1) returns RGB (1, 1, 1): the
        // conversion's normalisation and the illuminant's agree.
        let n = 3000;
        let mut sum = DVec3::ZERO;
        for k in 0..n {
            let p = PassSpectrum::for_pass(ColorSpaceName::Srgb, None, k);
            sum += p.to_rgb((p.illuminant(Vec3::ONE) * 0.5).as_dvec3());
        }
        let mean = sum / n as f64;
        assert!((mean - DVec3::splat(0.5)).abs().max_element() < 2e-3, "{mean}");
    }

    #[test]
    fn a_coloured_reflectance_under_white_keeps_its_colour_on_average() {
        let n = 3000;
        let rgb = Vec3::new(0.7, 0.3, 0.1);
        let mut sum = DVec3::ZERO;
        for k in 0..n {
            let p = PassSpectrum::for_pass(ColorSpaceName::Srgb, None, k);
            sum += p.to_rgb((p.illuminant(Vec3::ONE) * p.albedo(rgb)).as_dvec3());
        }
        let mean = sum / n as f64;
        assert!((mean - rgb.as_dvec3()).abs().max_element() < 5e-3, "{mean}");
    }

    #[test]
    fn the_cell_returns_what_was_set() {
        let cell = PassCell::new(ColorSpaceName::Srgb, None, Draw::Visible);
        cell.begin(7);
        assert_eq!(cell.get(), PassSpectrum::for_pass(ColorSpaceName::Srgb, None, 7));
        assert_eq!(radical_inverse_2(1), 0.5);
        assert_eq!(radical_inverse_2(6), 0.375);
    }

    #[test]
    fn sixteen_passes_already_give_white_and_a_saturated_red_their_colour() {
        // The passes share their wavelengths over the whole image, so what they miss is
        // a cast on every pixel: it must be small after few passes.
        for k in [16, 64] {
            let (mut white, mut red) = (DVec3::ZERO, DVec3::ZERO);
            let rgb = Vec3::new(0.9, 0.15, 0.1);
            for i in 0..k {
                let p = PassSpectrum::for_pass(ColorSpaceName::Srgb, None, i);
                white += p.to_rgb(p.illuminant(Vec3::ONE).as_dvec3()) / k as f64;
                red += p.to_rgb((p.illuminant(Vec3::ONE) * p.albedo(rgb)).as_dvec3()) / k as f64;
            }
            assert!((white - DVec3::ONE).abs().max_element() < 4e-3, "{k} passes: white {white}");
            let rel = (red - rgb.as_dvec3()).abs() / rgb.as_dvec3();
            assert!(rel.max_element() < 1e-2, "{k} passes: red {red}");
        }
    }
}
