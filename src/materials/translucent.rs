//! `Material "translucent"` (v3): diffuse and glossy (index 1.5) reflection and
//! transmission, split by `reflect` and `transmit`.
//!
//! ```text
//! Material "translucent" "rgb Kd" [.25 .25 .25] "rgb Ks" [.25 .25 .25] "rgb reflect" [.5 .5 .5] "rgb transmit" [.5 .5 .5]
//! ```

use super::MaterialKind;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::{Fresnel, TrowbridgeReitz};
use super::params::{Resolver, RoughnessRemap, TexValue, float, remap_v3, spectrum};
use crate::fixes::Fix;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::{Range, Res};

pub const NAME: &str = "translucent";

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    Ok(MaterialKind::Translucent {
        kd: spectrum(p, "Kd", 0.25, r)?,
        ks: spectrum(p, "Ks", 0.25, r)?,
        reflect: spectrum(p, "reflect", 0.5, r)?,
        transmit: spectrum(p, "transmit", 0.5, r)?,
        roughness: float(p, "roughness", 0.1, Range::NonNegative, r)?,
        remap: remap_v3(p)?,
    })
}

#[inline]
pub fn lobes<const N: usize>(
    [kd, ks, reflect, transmit]: [TexValue; 4],
    roughness: TexValue,
    remap: RoughnessRemap,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let (r, t) = (i.refl(reflect), i.refl(transmit));
    let (kd, ks) = (i.refl(kd), i.refl(ks));
    out.push_nonzero(r * kd, Lobe::Lambert);
    out.push_nonzero(t * kd, Lobe::LambertTransmission);
    let a = remap.alpha(i.float(roughness));
    let (dist, eta) = (TrowbridgeReitz::new([a, a]), 1.5);
    let fresnel = Fresnel::Dielectric { eta };
    out.push_nonzero(r * ks, |r| Lobe::MicrofacetReflection { r, dist, fresnel });
    let facing_only = i.fixes.has(Fix::RoughTransmission);
    out.push_nonzero(t * ks, |t| Lobe::MicrofacetTransmission { t, dist, eta, facing_only });
}

pub fn mitsuba(kd: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    e.diffuse_part(kd)
}
