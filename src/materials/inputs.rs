//! What a material's lobes are made from at one hit: its inputs evaluated there
//! ([`Inputs`]) and the short list the lobes go into ([`Lobes`]).

use super::bsdf::{Bsdf, Convention};
use super::lobes::{Lobe, MAX_LOBES};
use super::params::{Metal, RoughnessRemap, TexValue};
use crate::fixes::Fixes;
use crate::spectrum::Rgb;
use crate::spectrum::transport::PassSpectrum;
use crate::textures::TexCtx;
use crate::textures::Textures;
use glam::Vec3;

/// Texture inputs at one hit.
pub struct Inputs<'a, C: Fn() -> TexCtx> {
    pub textures: &'a Textures,
    pub ctx: C,
    pub max_reflectance: f32,
    pub fixes: Fixes,
    /// The pass's wavelengths when paths carry them: colours are upsampled here.
    pub spectral: Option<PassSpectrum>,
}

impl<C: Fn() -> TexCtx> Inputs<'_, C> {
    /// A reflectance (or transmittance), clamped as the material's version does.
    pub fn refl(&self, v: TexValue) -> Rgb {
        match &self.spectral {
            Some(s) => s.albedo(self.rgb(v)),
            None => self.rgb(v).clamp(Vec3::ZERO, Vec3::splat(self.max_reflectance)),
        }
    }

    /// `v` times `s`, clamped as a reflectance (pbrt-v4 scales the reflectance's
    /// spectrum, then clamps).
    pub fn refl_scaled(&self, v: TexValue, s: f32) -> Rgb {
        match &self.spectral {
            Some(sp) => (s * sp.albedo(self.rgb(v))).clamp(Vec3::ZERO, Vec3::ONE),
            None => (s * self.rgb(v)).clamp(Vec3::ZERO, Vec3::splat(self.max_reflectance)),
        }
    }

    /// A colour within [0, 1] that is not a surface's reflectance (a layer's albedo).
    pub fn albedo(&self, v: TexValue) -> Rgb {
        match &self.spectral {
            Some(s) => s.albedo(self.rgb(v)),
            None => self.rgb(v).clamp(Vec3::ZERO, Vec3::ONE),
        }
    }

    /// A non-negative value without bound (σa), upsampled as such when spectral.
    pub fn unbounded(&self, v: TexValue) -> Rgb {
        self.lanes_unbounded(self.rgb(v).max(Vec3::ZERO))
    }

    /// A constant spectrum in the path's lanes: its samples (at least `floor`) where it
    /// has them, else its RGB upsampled as an unbounded value.
    pub fn sampled(&self, v: &crate::values::Sampled, floor: f32) -> Rgb {
        match (&self.spectral, &v.samples) {
            (Some(s), Some(t)) => s.values(|l| crate::spectrum::piecewise_linear(t, l).max(floor)),
            _ => self.lanes_unbounded(v.rgb),
        }
    }

    /// `rgb` in the path's lanes as an unbounded value.
    pub fn lanes_unbounded(&self, rgb: Rgb) -> Rgb {
        match &self.spectral {
            Some(s) => s.unbounded(rgb),
            None => rgb,
        }
    }

    pub fn rgb(&self, v: TexValue) -> Rgb {
        match v {
            TexValue::Const(c) => c,
            TexValue::Texture(_) => self.textures.eval(v, &(self.ctx)()),
        }
    }

    pub fn float(&self, v: TexValue) -> f32 {
        self.rgb(v).x
    }

    pub fn alpha(&self, roughness: &[TexValue; 2], remap: RoughnessRemap) -> [f32; 2] {
        roughness.map(|r| remap.alpha(self.float(r)))
    }

    /// A conductor's η and k here.
    pub fn eta_k(&self, metal: &Metal) -> (Rgb, Rgb) {
        match metal {
            // DEVIATION(pbrt): robustness. A sampled η of 0 makes pbrt's Fresnel NaN.
            Metal::EtaK { eta, k } => (self.sampled(eta, 1e-4), self.sampled(k, 0.0)),
            Metal::Reflectance(r) => Metal::eta_k_of_reflectance(match &self.spectral {
                Some(s) => s.albedo(self.rgb(*r)),
                None => self.rgb(*r),
            }),
        }
    }
}

/// Lobes gathered from the parts of a pbrt-v3 `mix` (at most [`MAX_LOBES`], as
/// pbrt-v3's BSDF holds at most 8).
#[derive(Default)]
pub struct LobeList(pub(super) Lobes<MAX_LOBES>);

impl LobeList {
    /// Their BSDF, combined as pbrt-v3 combines them.
    pub fn bsdf(&self, frame: [Vec3; 3], ng: Vec3) -> Bsdf {
        Bsdf::new(frame, ng, &self.0.list[..self.0.n], Convention::PbrtV3)
    }
}

/// The most lobes one material makes (uber's five); a list this long is set up for
/// every hit, so it is no longer than that.
pub const MATERIAL_LOBES: usize = 5;

/// Lobes made at one hit, at most `N`.
pub struct Lobes<const N: usize> {
    pub list: [Lobe; N],
    pub n: usize,
}

impl<const N: usize> Default for Lobes<N> {
    fn default() -> Self {
        Lobes { list: [Lobe::default(); N], n: 0 }
    }
}

impl Default for Lobe {
    fn default() -> Lobe {
        Lobe::Lambert(Vec3::ZERO)
    }
}

impl<const N: usize> Lobes<N> {
    pub fn push(&mut self, l: Lobe) {
        if self.n < N {
            self.list[self.n] = l;
            self.n += 1;
        }
    }

    /// Adds `make(c)` unless `c` is black (pbrt adds no lobe for a black input).
    pub fn push_nonzero(&mut self, c: Rgb, make: impl FnOnce(Rgb) -> Lobe) {
        if c != Vec3::ZERO {
            self.push(make(c));
        }
    }
}

/// A Lambertian lobe, or none for a black reflectance (pbrt adds no lobe then).
pub fn lambert(r: Rgb) -> Option<Lobe> {
    (r != Vec3::ZERO).then_some(Lobe::Lambert(r))
}
