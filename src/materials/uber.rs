//! `Material "uber"` (v3): plastic-like layers plus specular reflection and
//! transmission, all scaled by `opacity`, and a straight pass-through of 1 − opacity.
//!
//! ```text
//! Material "uber" "rgb Kd" [.3 .3 .3] "rgb Ks" [.2 .2 .2] "rgb Kr" [.2 .2 .2] "float index" 1.5 "rgb opacity" [1 1 1]
//! ```
//! `roughness` (.1) is overridden per direction by `uroughness`/`vroughness`; `eta`,
//! else `index`.

use super::MaterialKind;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::{Fresnel, TrowbridgeReitz};
use super::params::{Resolver, RoughnessRemap, TexValue, float, remap_v3, roughness, spectrum};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::{Range, Res};
use glam::Vec3;

pub const NAME: &str = "uber";

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let eta_name = if p.named("eta").is_some() { "eta" } else { "index" };
    Ok(MaterialKind::Uber {
        kd: spectrum(p, "Kd", 0.25, r)?,
        ks: spectrum(p, "Ks", 0.25, r)?,
        kr: spectrum(p, "Kr", 0.0, r)?,
        kt: spectrum(p, "Kt", 0.0, r)?,
        roughness: roughness(p, 0.1, r)?,
        eta: float(p, eta_name, 1.5, Range::Positive, r)?,
        opacity: spectrum(p, "opacity", 1.0, r)?,
        remap: remap_v3(p)?,
    })
}

/// pbrt-v3's uber: a pass-through of 1 − opacity, then each layer scaled by the opacity.
#[inline]
pub fn lobes<const N: usize>(
    [kd, ks, kr, kt, eta, opacity]: [TexValue; 6],
    roughness: &[TexValue; 2],
    remap: RoughnessRemap,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let op = i.refl(opacity);
    out.push_nonzero((Vec3::ONE - op).max(Vec3::ZERO), |t| Lobe::SpecularTransmission { t, eta: 1.0 });
    let eta = i.float(eta);
    out.push_nonzero(op * i.refl(kd), Lobe::Lambert);
    let (dist, fresnel) = (TrowbridgeReitz::new(i.alpha(roughness, remap)), Fresnel::Dielectric { eta });
    out.push_nonzero(op * i.refl(ks), |r| Lobe::MicrofacetReflection { r, dist, fresnel });
    out.push_nonzero(op * i.refl(kr), |r| Lobe::SpecularReflection { r, fresnel });
    out.push_nonzero(op * i.refl(kt), |t| Lobe::SpecularTransmission { t, eta });
}

pub fn mitsuba(kd: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    e.diffuse_part(kd)
}
