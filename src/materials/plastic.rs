//! `Material "plastic"` (v3): Lambertian `Kd` under a microfacet coat `Ks` of index 1.5.
//!
//! ```text
//! Material "plastic" "rgb Kd" [.4 .1 .1] "rgb Ks" [.3 .3 .3] "float roughness" .05
//! ```
//! pbrt-v3 builds the coat's Fresnel term with the indices swapped (pbrt-v3 #210);
//! we do too unless `--fix plastic-fresnel`.

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

pub const NAME: &str = "plastic";

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    Ok(MaterialKind::Plastic {
        kd: spectrum(p, "Kd", 0.25, r)?,
        ks: spectrum(p, "Ks", 0.25, r)?,
        roughness: float(p, "roughness", 0.1, Range::NonNegative, r)?,
        remap: remap_v3(p)?,
    })
}

#[inline]
pub fn lobes<const N: usize>(
    [kd, ks]: [TexValue; 2],
    roughness: TexValue,
    remap: RoughnessRemap,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    out.push_nonzero(i.refl(kd), Lobe::Lambert);
    let a = remap.alpha(i.float(roughness));
    let fresnel = match i.fixes.has(Fix::PlasticFresnel) {
        true => Fresnel::Coat { eta: 1.5 },
        false => Fresnel::SwappedCoat { eta: 1.5 },
    };
    let dist = TrowbridgeReitz::new([a, a]);
    out.push_nonzero(i.refl(ks), |r| Lobe::MicrofacetReflection { r, dist, fresnel });
}

pub fn mitsuba(kd: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    e.diffuse_part(kd)
}
