//! `Material "mirror"`: a perfect mirror tinted by `Kr`.
//!
//! ```text
//! Material "mirror" "rgb Kr" [.9 .9 .9]
//! ```

use super::MaterialKind;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::Fresnel;
use super::params::{Resolver, TexValue, spectrum};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::Res;

pub const NAME: &str = "mirror";

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    Ok(MaterialKind::Mirror { reflectance: spectrum(p, "Kr", 0.9, r)? })
}

#[inline]
pub fn lobes<const N: usize>(reflectance: TexValue, i: &Inputs<impl Fn() -> TexCtx>, out: &mut Lobes<N>) {
    out.push(Lobe::SpecularReflection { r: i.refl(reflectance), fresnel: Fresnel::One })
}

pub fn mitsuba(reflectance: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    MaterialOut::Mirror { reflectance: e.rgb(reflectance) }
}
