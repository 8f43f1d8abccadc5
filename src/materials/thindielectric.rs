//! `Material "thindielectric"` (pbrt-v4): a sheet of glass too thin to bend light, such
//! as a window pane. Light either mirrors off it or passes straight through, undeviated.
//!
//! ```text
//! Material "thindielectric" "float eta" 1.5
//! Material "thindielectric" "spectrum eta" "glass-BK7"   # keeps one wavelength, as pbrt-v4
//! ```
//! The reflected share is the Fresnel reflectance R of one face plus the light bounced
//! back and forth between the two faces, R + T²R/(1 − R²) with T = 1 − R (pbrt-v4's
//! `ThinDielectricBxDF`); the rest passes through. There is no roughness and no tint.
//! An index given as a spectrum is read at a spectral path's first wavelength, and the
//! path keeps only that one, as pbrt-v4 does for any index that is not a constant.

use super::MaterialKind;
use super::dielectric::{Dispersion, Eta, v4_eta};
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::params::{Resolver, TexValue};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::Res;
use glam::Vec3;

pub const NAME: &str = "thindielectric";

/// `eta` (a float or a spectrum, default 1.5); `displacement` and `normalmap` are read
/// for every material by the scene.
pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let (eta, dispersion) = v4_eta(p, r)?;
    Ok(MaterialKind::ThinDielectric { eta, dispersion })
}

#[inline]
pub fn lobes<const N: usize>(
    eta: TexValue,
    dispersion: Option<&Dispersion>,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let eta = Eta { mean: eta, dispersion }.at(i);
    out.push(Lobe::ThinDielectric { eta, scale: Vec3::ONE })
}

pub fn mitsuba(eta: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    MaterialOut::ThinDielectric { eta: e.rgb(eta)[0] }
}
