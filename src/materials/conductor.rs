//! `Material "metal"` (v3) and `Material "conductor"` (v4): smooth or rough metal.
//!
//! ```text
//! Material "metal" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k" "float roughness" .1
//! Material "conductor" "rgb reflectance" [.9 .6 .3] "float uroughness" .05 "float vroughness" .2
//! ```
//! v3's metal is copper with roughness .01 through v3's remapping by default; v4's
//! conductor is smooth copper, √-remapped, or given by `reflectance` (never with
//! `eta`/`k`: pbrt-v4's error).

use super::MaterialKind;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::{Fresnel, TrowbridgeReitz};
use super::params::{Metal, Resolver, RoughnessRemap, TexValue, metal, remap_v3, remap_v4, roughness};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::Res;
use glam::Vec3;

pub const NAMES: [&str; 2] = ["metal", "conductor"];

pub fn read(ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let v3 = ty == NAMES[0];
    let metal = if v3 { metal(p, "", None, r)? } else { metal(p, "", Some(ty), r)? };
    let roughness = roughness(p, if v3 { 0.01 } else { 0.0 }, r)?;
    let remap = if v3 { remap_v3(p)? } else { remap_v4(p)? };
    Ok(MaterialKind::Conductor { metal, roughness, remap })
}

/// A conductor is smooth when both roughnesses give α below 10⁻³.
#[inline]
pub fn lobes<const N: usize>(
    metal: &Metal,
    roughness: &[TexValue; 2],
    remap: RoughnessRemap,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let (eta, k) = i.eta_k(metal);
    let fresnel = Fresnel::Conductor { eta, k };
    let alpha = i.alpha(roughness, remap);
    if alpha[0] < 1e-3 && alpha[1] < 1e-3 {
        out.push(Lobe::SpecularReflection { r: Vec3::ONE, fresnel });
    } else {
        out.push(Lobe::MicrofacetReflection { r: Vec3::ONE, dist: TrowbridgeReitz::new(alpha), fresnel });
    }
}

pub fn mitsuba(
    metal: &Metal,
    roughness: &[TexValue; 2],
    remap: RoughnessRemap,
    e: &mut dyn MaterialExport,
) -> MaterialOut {
    let (eta, k) = match metal {
        Metal::EtaK { eta, k } => (eta.rgb, k.rgb),
        Metal::Reflectance(r) => Metal::eta_k_of_reflectance(Vec3::from(e.rgb(*r))),
    };
    let alpha = roughness.map(|r| remap.alpha(e.rgb(r)[0]));
    if alpha[0] < 1e-3 && alpha[1] < 1e-3 {
        return MaterialOut::Conductor { eta: eta.to_array(), k: k.to_array() };
    }
    if alpha[0] != alpha[1] {
        e.note("anisotropic roughness: Mitsuba's tangent frame differs from pbrt's");
    }
    MaterialOut::RoughConductor { eta: eta.to_array(), k: k.to_array(), alpha: alpha.map(|a| a.max(1e-3)) }
}
