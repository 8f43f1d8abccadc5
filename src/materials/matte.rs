//! `Material "matte"` (v3): Lambertian, or Oren–Nayar when `sigma` (degrees) is not 0.
//!
//! ```text
//! Material "matte" "rgb Kd" [.5 .5 .5]
//! Material "matte" "rgb Kd" [.5 .5 .5] "float sigma" 20        # Oren–Nayar, pbrt's A and B
//! ```

use super::MaterialKind;
use super::inputs::{Inputs, Lobes};
use super::lobes::{Lobe, oren_nayar_ab};
use super::params::{Resolver, TexValue, float, spectrum};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::{Range, Res};
use glam::Vec3;

pub const NAME: &str = "matte";

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let sigma = float(p, "sigma", 0.0, Range::NonNegative, r)?;
    let reflectance = spectrum(p, "Kd", 0.5, r)?;
    if sigma == TexValue::Const(Vec3::ZERO) {
        Ok(MaterialKind::Diffuse { reflectance })
    } else {
        Ok(MaterialKind::OrenNayar { reflectance, sigma })
    }
}

/// Oren–Nayar with pbrt's A and B (Lambertian where σ is 0 at this hit).
#[inline]
pub fn lobes<const N: usize>(
    reflectance: TexValue,
    sigma: TexValue,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let r = i.refl(reflectance);
    match oren_nayar_ab(i.float(sigma)) {
        (_, 0.0) => out.push_nonzero(r, Lobe::Lambert),
        (a, b) => out.push_nonzero(r, |r| Lobe::OrenNayar { r, a, b }),
    }
}

pub fn mitsuba(reflectance: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    e.diffuse_part(reflectance)
}
