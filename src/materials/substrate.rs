//! `Material "substrate"` (v3): pbrt's Ashikhmin–Shirley `FresnelBlend`.
//!
//! ```text
//! Material "substrate" "rgb Kd" [.5 .5 .5] "rgb Ks" [.5 .5 .5] "float uroughness" .05 "float vroughness" .2
//! ```

use super::MaterialKind;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::TrowbridgeReitz;
use super::params::{Resolver, RoughnessRemap, TexValue, float, remap_v3, spectrum};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::{Range, Res};
use glam::Vec3;

pub const NAME: &str = "substrate";

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let rough = |name: &str, r: &mut dyn Resolver| float(p, name, 0.1, Range::NonNegative, r);
    Ok(MaterialKind::Substrate {
        kd: spectrum(p, "Kd", 0.5, r)?,
        ks: spectrum(p, "Ks", 0.5, r)?,
        roughness: [rough("uroughness", r)?, rough("vroughness", r)?],
        remap: remap_v3(p)?,
    })
}

#[inline]
pub fn lobes<const N: usize>(
    [kd, ks]: [TexValue; 2],
    roughness: &[TexValue; 2],
    remap: RoughnessRemap,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let (rd, rs) = (i.refl(kd), i.refl(ks));
    if rd != Vec3::ZERO || rs != Vec3::ZERO {
        let dist = TrowbridgeReitz::new(i.alpha(roughness, remap));
        out.push(Lobe::FresnelBlend { rd, rs, dist, scale: Vec3::ONE });
    }
}

pub fn mitsuba(kd: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    e.diffuse_part(kd)
}
