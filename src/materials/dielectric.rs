//! `Material "glass"` (v3) and `Material "dielectric"` (v4): smooth or rough glass.
//!
//! ```text
//! Material "glass" "float index" 1.5 "rgb Kr" [1 1 1] "rgb Kt" [1 1 1] "float uroughness" .1
//! Material "dielectric" "float eta" 1.5 "float roughness" .2
//! Material "dielectric" "spectrum eta" "glass-BK7"        # disperses (spectral paths)
//! ```
//! A named glass's index depends on the wavelength. A spectral path (pbrt-v4's files)
//! refracts by the index at its first wavelength and keeps only that one, as pbrt-v4's
//! dielectric does; an RGB path takes one index, the luminance-weighted mean.
//! Smooth glass is one Fresnel-weighted lobe; rough glass is pbrt-v3's pair of
//! microfacet reflection and transmission lobes, or pbrt-v4's single lobe. pbrt-v3's
//! glass reads only `uroughness`/`vroughness` (its `roughness` is unused).

use super::MaterialKind;
use super::bsdf::Convention;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::{Fresnel, TrowbridgeReitz};
use super::params::{Resolver, RoughnessRemap, TexValue, float, remap_v3, remap_v4, roughness, spectrum, uv_roughness};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::scene::values::{self, Range, Res};
use crate::spectrum::Rgb;
use crate::spectrum::named::Sellmeier;
use crate::textures::TexCtx;
use glam::Vec3;

pub const NAMES: [&str; 2] = ["glass", "dielectric"];

/// v3 `glass` (`eta`, else `index`; `Kr`, `Kt`) and v4 `dielectric` (`eta` a float or a
/// spectrum).
pub fn read(ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let v3 = ty == NAMES[0];
    let eta_name = if v3 && p.named("eta").is_none() { "index" } else { "eta" };
    // v3 glass takes a float (texture); v4 dielectric also a spectrum.
    let dispersion = if v3 { None } else { named_glass(p, eta_name) };
    let eta = if v3 || values::given(p, eta_name, &[ParamType::Float, ParamType::Texture]) {
        float(p, eta_name, 1.5, Range::Positive, r)?
    } else {
        // A spectral index (v4): RGB has one index, its luminance-weighted mean.
        match values::rgb(p, eta_name, &r.spectra(), Range::Positive)? {
            Some(c) => TexValue::Const(Vec3::splat(crate::spectrum::luminance(c))),
            None => TexValue::Const(Vec3::splat(1.5)),
        }
    };
    let one = TexValue::Const(Vec3::ONE);
    let (kr, kt) = if v3 { (spectrum(p, "Kr", 1.0, r)?, spectrum(p, "Kt", 1.0, r)?) } else { (one, one) };
    let roughness = if v3 { uv_roughness(p, r)? } else { roughness(p, 0.0, r)? };
    let remap = if v3 { remap_v3(p)? } else { remap_v4(p)? };
    Ok(MaterialKind::Dielectric { eta, dispersion, kr, kt, roughness, remap })
}

/// The glass a `"spectrum eta"` names, if it names one.
fn named_glass(p: &ParamList, name: &str) -> Option<Sellmeier> {
    let param = p.named(name).filter(|q| q.ty == ParamType::Spectrum)?;
    crate::spectrum::named::glass_named(param.strings().first()?)
}

/// A dielectric's index: one value, and a glass's formula where it has one.
#[derive(Clone, Copy, Debug)]
pub struct Eta {
    pub mean: TexValue,
    pub dispersion: Option<Sellmeier>,
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
    let eta = match (eta.dispersion, &i.spectral) {
        (Some(glass), Some(pass)) => glass.eta(pass.lambda[0] as f64) as f32,
        _ => i.float(eta.mean),
    };
    glass(eta, i.refl(kr), i.refl(kt), alpha, convention, out)
}

/// Smooth glass is one Fresnel-weighted lobe; rough glass is pbrt-v3's pair of
/// microfacet reflection and transmission lobes, or pbrt-v4's single lobe.
fn glass<const N: usize>(eta: f32, r: Rgb, t: Rgb, alpha: [f32; 2], c: Convention, out: &mut Lobes<N>) {
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
    out.push_nonzero(t, |t| Lobe::MicrofacetTransmission { t, dist, eta });
}

pub fn mitsuba([eta, kr, kt]: [TexValue; 3], roughness: &[TexValue; 2], e: &mut dyn MaterialExport) -> MaterialOut {
    if roughness.iter().any(|r| *r != TexValue::Const(Vec3::ZERO)) {
        e.note("rough dielectric: exported smooth");
    }
    MaterialOut::Dielectric { eta: e.rgb(eta)[0], reflectance: e.rgb(kr), transmittance: e.rgb(kt) }
}
