//! `Material "diffuse"` (v4): Lambertian reflection.
//!
//! ```text
//! Material "diffuse" "rgb reflectance" [.5 .5 .5]
//! Material "diffuse" "texture reflectance" "checks"
//! ```

use super::MaterialKind;
use super::inputs::{Inputs, Lobes, lambert};
use super::params::{Resolver, TexValue, spectrum};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::Res;

pub const NAME: &str = "diffuse";

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    Ok(MaterialKind::Diffuse { reflectance: spectrum(p, "reflectance", 0.5, r)? })
}

/// A Lambertian lobe (also pbrt-v3's `matte` without `sigma`).
#[inline]
pub fn lobes<const N: usize>(reflectance: TexValue, i: &Inputs<impl Fn() -> TexCtx>, out: &mut Lobes<N>) {
    lambert(i.refl(reflectance)).into_iter().for_each(|l| out.push(l))
}

pub fn mitsuba(reflectance: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    MaterialOut::Diffuse { reflectance: e.rgb(reflectance) }
}
