//! `Material "glass"` (v3) and `Material "dielectric"` (v4): smooth or rough glass.
//!
//! ```text
//! Material "glass" "float index" 1.5 "rgb Kr" [1 1 1] "rgb Kt" [1 1 1] "float uroughness" .1
//! Material "dielectric" "float eta" 1.5 "float roughness" .2
//! Material "dielectric" "spectrum eta" "glass-BK7"        # disperses (spectral paths)
//! Material "dielectric" "spectrum eta" [400 1.53  700 1.51] # so does a (λ, η) list
//! ```
//! An index given as a spectrum (a named glass, a (λ, η) list, an SPD file) depends on
//! the wavelength. A spectral path (pbrt-v4's files) refracts by the index at its first
//! wavelength and keeps only that one, as pbrt-v4's dielectric does; an RGB path takes
//! one index, the luminance-weighted mean.
//! Smooth glass is one Fresnel-weighted lobe; rough glass is pbrt-v3's pair of
//! microfacet reflection and transmission lobes, or pbrt-v4's single lobe. pbrt-v3's
//! glass reads only `uroughness`/`vroughness` (its `roughness` is unused).

use super::MaterialKind;
use super::bsdf::Convention;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::{Fresnel, TrowbridgeReitz};
use super::params::{Resolver, RoughnessRemap, TexValue, float, remap_v3, remap_v4, roughness, spectrum, uv_roughness};
use crate::fixes::Fix;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::spectrum::named::Sellmeier;
use crate::textures::TexCtx;
use crate::values::{self, Range, Res};
use glam::Vec3;
use std::sync::Arc;

pub const NAMES: [&str; 2] = ["glass", "dielectric"];

/// v3 `glass` (`eta`, else `index`; `Kr`, `Kt`) and v4 `dielectric` (`eta` a float or a
/// spectrum).
pub fn read(ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let v3 = ty == NAMES[0];
    let eta_name = if v3 && p.named("eta").is_none() { "index" } else { "eta" };
    // v3 glass takes a float (texture); v4 dielectric also a spectrum.
    let (eta, dispersion) = if v3 { (float(p, eta_name, 1.5, Range::Positive, r)?, None) } else { v4_eta(p, r)? };
    let one = TexValue::Const(Vec3::ONE);
    let (kr, kt) = if v3 { (spectrum(p, "Kr", 1.0, r)?, spectrum(p, "Kt", 1.0, r)?) } else { (one, one) };
    let roughness = if v3 { uv_roughness(p, r)? } else { roughness(p, 0.0, r)? };
    let remap = if v3 { remap_v3(p)? } else { remap_v4(p)? };
    Ok(MaterialKind::Dielectric { eta, dispersion, kr, kt, roughness, remap })
}

/// pbrt-v4's `"float eta"` or `"spectrum eta"` (default 1.5): one index (for a
/// spectrum, its luminance-weighted mean, which RGB paths take), and how it varies with
/// the wavelength where it is given as a spectrum.
pub fn v4_eta(p: &ParamList, r: &mut dyn Resolver) -> Res<(TexValue, Option<Dispersion>)> {
    let dispersion = dispersion(p, "eta", r)?;
    let eta = if values::given(p, "eta", &[ParamType::Float, ParamType::Texture]) {
        float(p, "eta", 1.5, Range::Positive, r)?
    } else {
        match values::rgb(p, "eta", &r.spectra(), Range::Positive)? {
            Some(c) => TexValue::Const(Vec3::splat(crate::spectrum::luminance(c))),
            None => TexValue::Const(Vec3::splat(1.5)),
        }
    };
    Ok((eta, dispersion))
}

/// How a `"spectrum eta"` varies with the wavelength, if it is given as a spectrum.
pub fn dispersion(p: &ParamList, name: &str, r: &mut dyn Resolver) -> Res<Option<Dispersion>> {
    let Some(param) = p.named(name).filter(|q| q.ty == ParamType::Spectrum) else { return Ok(None) };
    if let Some(glass) = param.strings().first().and_then(|n| crate::spectrum::named::glass_named(n)) {
        return Ok(Some(Dispersion::Glass(glass)));
    }
    Ok(values::sampled_pairs(p, name, &r.spectra())?.map(|pairs| Dispersion::Table(pairs.into())))
}

/// A dielectric's index by wavelength (nm).
#[derive(Clone, Debug, PartialEq)]
pub enum Dispersion {
    /// A named glass's Sellmeier formula.
    Glass(Sellmeier),
    /// (λ, η) pairs, linear between them and 0 outside, as pbrt-v4's
    /// `PiecewiseLinearSpectrum` (whose 0 its dielectric reads as 1).
    Table(Arc<[(f32, f32)]>),
}

impl Dispersion {
    pub fn eta(&self, lambda: f32) -> f32 {
        let eta = match self {
            Dispersion::Glass(g) => g.eta(lambda as f64) as f32,
            Dispersion::Table(t) => crate::spectrum::piecewise_linear(t, lambda),
        };
        if eta == 0.0 { 1.0 } else { eta }
    }
}

/// A dielectric's index: one value, and how it varies with the wavelength where it does.
#[derive(Clone, Copy, Debug)]
pub struct Eta<'a> {
    pub mean: TexValue,
    pub dispersion: Option<&'a Dispersion>,
}

impl Eta<'_> {
    /// The index at a hit: at a spectral path's first wavelength where it disperses.
    pub fn at(&self, i: &Inputs<impl Fn() -> TexCtx>) -> f32 {
        match (self.dispersion, &i.spectral) {
            (Some(d), Some(pass)) => d.eta(pass.lambda[0]),
            _ => i.float(self.mean),
        }
    }
}

/// The glass's lobes at a hit.
#[inline]
pub fn lobes<const N: usize>(
    eta: Eta,
    [kr, kt]: [TexValue; 2],
    roughness: &[TexValue; 2],
    remap: RoughnessRemap,
    convention: Convention,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    // Smooth when the roughness as written is 0 (pbrt-v3: v3's remapping takes 0 to
    // α ≈ 0.047) or α is below 10⁻³ (pbrt-v4's test).
    let raw = roughness.map(|r| i.float(r));
    let alpha = if raw == [0.0; 2] { raw } else { raw.map(|r| remap.alpha(r)) };
    let alpha = if alpha.iter().all(|a| *a < 1e-3) { [0.0; 2] } else { alpha };
    let facing_only = i.fixes.has(Fix::RoughTransmission);
    glass(eta.at(i), i.refl(kr), i.refl(kt), alpha, convention, facing_only, out)
}

/// Smooth glass is one Fresnel-weighted lobe; rough glass is pbrt-v3's pair of
/// microfacet reflection and transmission lobes (`facing_only`: see
/// [`Lobe::MicrofacetTransmission`]), or pbrt-v4's single lobe.
fn glass<const N: usize>(
    eta: f32,
    r: Rgb,
    t: Rgb,
    alpha: [f32; 2],
    c: Convention,
    facing_only: bool,
    out: &mut Lobes<N>,
) {
    if r == Vec3::ZERO && t == Vec3::ZERO {
        return;
    }
    if alpha == [0.0, 0.0] {
        out.push(Lobe::FresnelSpecular { r, t, eta });
        return;
    }
    let dist = TrowbridgeReitz::new(alpha);
    if c == Convention::PbrtV4 {
        out.push(Lobe::RoughDielectric { r, t, dist, eta });
        return;
    }
    out.push_nonzero(r, |r| Lobe::MicrofacetReflection { r, dist, fresnel: Fresnel::Dielectric { eta } });
    out.push_nonzero(t, |t| Lobe::MicrofacetTransmission { t, dist, eta, facing_only });
}

pub fn mitsuba([eta, kr, kt]: [TexValue; 3], roughness: &[TexValue; 2], e: &mut dyn MaterialExport) -> MaterialOut {
    if roughness.iter().any(|r| *r != TexValue::Const(Vec3::ZERO)) {
        e.note("rough dielectric: exported smooth");
    }
    MaterialOut::Dielectric { eta: e.rgb(eta)[0], reflectance: e.rgb(kr), transmittance: e.rgb(kt) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_listed_index_is_linear_between_its_points_and_air_outside_them() {
        let d = Dispersion::Table(vec![(400.0, 1.6), (500.0, 1.5), (700.0, 1.5)].into());
        assert!((d.eta(450.0) - 1.55).abs() < 1e-6);
        assert_eq!(d.eta(400.0), 1.6);
        assert_eq!(d.eta(700.0), 1.5);
        // pbrt-v4's spectrum is 0 outside its points, which its dielectric reads as 1.
        assert_eq!(d.eta(390.0), 1.0);
        assert_eq!(d.eta(701.0), 1.0);
        assert_eq!(Dispersion::Table(vec![(500.0, 1.4)].into()).eta(500.0), 1.4);
        let bk7 = Dispersion::Glass(crate::spectrum::named::glass_named("glass-BK7").unwrap());
        assert!(bk7.eta(450.0) > bk7.eta(650.0), "blue bends more");
    }
}
