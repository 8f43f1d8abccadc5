//! `Material "diffusetransmission"` (v4): Lambertian reflection and transmission, both
//! multiplied by `scale` and clamped to [0, 1].
//!
//! ```text
//! Material "diffusetransmission" "rgb reflectance" [.3 .3 .3] "rgb transmittance" [.5 .5 .5] "float scale" 1
//! ```

use super::MaterialKind;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::params::{Resolver, TexValue, float, spectrum};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::{Range, Res};

pub const NAME: &str = "diffusetransmission";

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let scale = float(p, "scale", 1.0, Range::Any, r)?;
    Ok(MaterialKind::DiffuseTransmission {
        reflectance: spectrum(p, "reflectance", 0.25, r)?,
        transmittance: spectrum(p, "transmittance", 0.25, r)?,
        scale,
    })
}

#[inline]
pub fn lobes<const N: usize>(
    [reflectance, transmittance, scale]: [TexValue; 3],
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let s = i.float(scale);
    out.push_nonzero(i.refl_scaled(reflectance, s), Lobe::Lambert);
    out.push_nonzero(i.refl_scaled(transmittance, s), Lobe::LambertTransmission);
}

pub fn mitsuba(reflectance: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    e.diffuse_part(reflectance)
}
