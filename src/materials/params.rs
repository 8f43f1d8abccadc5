//! What materials read: inputs that may be textures ([`TexValue`]), roughness and its
//! remapping, conductors' constants, coats, and the builder services a reader needs
//! ([`Resolver`]). Also the parameters every material takes: `bumpmap`/`displacement`
//! and `normalmap`.
//!
//! ```text
//! Material "plastic" "texture Kd" "wood" "float roughness" .05 "bool remaproughness" false
//! Material "conductor" "float uroughness" .1 "float vroughness" .3 "texture displacement" "bumps"
//! Material "diffuse" "string normalmap" "normals.png"     # v4
//! ```

use crate::approx::Approx;
use crate::imageio::Texels;
use crate::parser::error::Diagnostic;
use crate::parser::params::{FloatValue, ParamList};
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::{self, Range, Res, Sampled};
pub use crate::values::{Resolver, TexValue, float_input as float, spectrum_input as spectrum};
use glam::Vec3;
use std::sync::Arc;

/// How a roughness becomes a microfacet α.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RoughnessRemap {
    /// `remaproughness false`: α = roughness.
    None,
    /// pbrt-v3's polynomial in log(roughness) (`metal`, `glass`, `plastic`, `uber`).
    V3,
    /// pbrt-v4's √roughness (`conductor`, `dielectric`, `coated*`).
    V4,
}

impl RoughnessRemap {
    /// The microfacet α of a roughness as written.
    pub fn alpha(self, r: f32) -> f32 {
        match self {
            RoughnessRemap::None => r.max(0.0),
            RoughnessRemap::V3 => super::microfacet::roughness_to_alpha_v3(r),
            RoughnessRemap::V4 => r.max(0.0).sqrt(),
        }
    }
}

/// A conductor's optical constants.
#[derive(Clone, Debug, PartialEq)]
pub enum Metal {
    /// Index η + ik (as RGB, and as samples where the file gives them: named metals,
    /// SPD files).
    EtaK { eta: Sampled, k: Sampled },
    /// pbrt-v4's `reflectance`: the reflectance at normal incidence, turned into η = 1,
    /// k = 2√r / √(1 − r) where it is evaluated.
    Reflectance(TexValue),
}

impl Metal {
    /// pbrt-v4's η and k for a reflectance r at normal incidence (r kept below 1,
    /// where k would be infinite).
    pub fn eta_k_of_reflectance(r: Rgb) -> (Rgb, Rgb) {
        let r = r.clamp(Vec3::ZERO, Vec3::splat(0.9999));
        (Vec3::ONE, 2.0 * r.powf(0.5) / (Vec3::ONE - r).powf(0.5))
    }
}

/// v3 `remaproughness` (default true): pbrt-v3's polynomial.
pub fn remap_v3(p: &ParamList) -> Res<RoughnessRemap> {
    Ok(if p.bool("remaproughness")?.unwrap_or(true) { RoughnessRemap::V3 } else { RoughnessRemap::None })
}

/// v4 `remaproughness` (default true): α = √roughness.
pub fn remap_v4(p: &ParamList) -> Res<RoughnessRemap> {
    Ok(if p.bool("remaproughness")?.unwrap_or(true) { RoughnessRemap::V4 } else { RoughnessRemap::None })
}

/// `roughness` (both directions), overridden per direction by `uroughness`/`vroughness`.
pub fn roughness(p: &ParamList, default: f32, r: &mut dyn Resolver) -> Res<[TexValue; 2]> {
    let both = float(p, "roughness", default, Range::NonNegative, r)?;
    let one = |name: &str, r: &mut dyn Resolver| -> Res<TexValue> {
        Ok(if p.named(name).is_some() { float(p, name, default, Range::NonNegative, r)? } else { both })
    };
    Ok([one("uroughness", r)?, one("vroughness", r)?])
}

/// `uroughness` and `vroughness` alone (0 by default).
pub fn uv_roughness(p: &ParamList, r: &mut dyn Resolver) -> Res<[TexValue; 2]> {
    Ok([float(p, "uroughness", 0.0, Range::NonNegative, r)?, float(p, "vroughness", 0.0, Range::NonNegative, r)?])
}

/// `{prefix}roughness`, overridden per direction by `{prefix}uroughness`/`vroughness`.
pub fn prefixed_roughness(p: &ParamList, prefix: &str, r: &mut dyn Resolver) -> Res<[TexValue; 2]> {
    let both = float(p, &format!("{prefix}roughness"), 0.0, Range::NonNegative, r)?;
    let one = |dir: &str, r: &mut dyn Resolver| -> Res<TexValue> {
        let name = format!("{prefix}{dir}roughness");
        Ok(if p.named(&name).is_some() { float(p, &name, 0.0, Range::NonNegative, r)? } else { both })
    };
    Ok([one("u", r)?, one("v", r)?])
}

/// `{prefix}eta` / `{prefix}k` (copper by default), or, for the v4 material `v4`, a
/// `reflectance` instead (never both: pbrt-v4's error).
pub fn metal(p: &ParamList, prefix: &str, v4: Option<&str>, r: &mut dyn Resolver) -> Res<Metal> {
    let (eta_name, k_name) = (format!("{prefix}eta"), format!("{prefix}k"));
    if let (Some(ty), Some(refl)) = (v4, p.named("reflectance")) {
        if p.named(&eta_name).is_some() || p.named(&k_name).is_some() {
            let msg = format!("{ty} takes \"reflectance\" or \"{eta_name}\"/\"{k_name}\", not both");
            return Err(Diagnostic::error(refl.span, msg));
        }
        return Ok(Metal::Reflectance(spectrum(p, "reflectance", 0.0, r)?));
    }
    let spectra = r.spectra();
    let copper = |n: &str| Sampled {
        rgb: Vec3::from(spectra.space.from_srgb(crate::spectrum::named_spectrum(n).unwrap_or(Vec3::ONE).to_array())),
        samples: crate::spectrum::named_samples(n).map(Into::into),
    };
    let eta =
        values::rgb_and_samples(p, &eta_name, &spectra, Range::Positive)?.unwrap_or_else(|| copper("metal-Cu-eta"));
    let k = values::rgb_and_samples(p, &k_name, &spectra, Range::NonNegative)?.unwrap_or_else(|| copper("metal-Cu-k"));
    Ok(Metal::EtaK { eta, k })
}

/// The material's normal map (v4 `normalmap`, an RGB image of tangent-space normals,
/// its values as stored: no sRGB decoding). An image that cannot be read leaves the
/// surface smooth (noted).
pub fn normal_map(ty: &str, p: &ParamList, r: &mut dyn Resolver) -> Res<Option<Arc<Texels>>> {
    let Some(file) = p.string("normalmap")? else { return Ok(None) };
    let at = p.named("normalmap").map_or_else(Span::default, |x| x.value_span);
    match r.image(&file) {
        Ok(img) => Ok(Some(crate::imageio::stored_values(&file, img, r.syntax() == crate::parser::Syntax::V3))),
        Err(e) => {
            r.approximate(at, format!("\"normalmap\" of material \"{ty}\" ({e})"), Approx::MissingImage);
            Ok(None)
        }
    }
}

/// The material's bump map (`bumpmap` in v3, `displacement` in v4; either is read in
/// either version).
pub fn bump_map(p: &ParamList, r: &mut dyn Resolver) -> Res<Option<TexValue>> {
    let name = if p.named("bumpmap").is_some() { "bumpmap" } else { "displacement" };
    Ok(match values::float_or_texture(p, name, Range::Any)? {
        None => None,
        // A constant displacement moves the whole surface and tilts nothing.
        Some((FloatValue::Const(_), _)) => None,
        Some((FloatValue::Texture(t), at)) => r.texture(&t, true, at)?.map(TexValue::Texture),
    })
}
