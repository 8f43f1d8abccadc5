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

/// The shares reflected and passed through at `cos_o` (|cos θ| of the direction the
/// light leaves by): each face's Fresnel reflectance R, then the geometric series of
/// bounces between the two faces, R + T²R/(1 − R²).
pub fn shares(cos_o: f32, eta: f32) -> (f32, f32) {
    let r = super::microfacet::fr_dielectric(cos_o.abs(), 1.0, eta);
    if r >= 1.0 {
        return (1.0, 0.0);
    }
    let t = 1.0 - r;
    let r = r + t * t * r / (1.0 - r * r);
    (r, 1.0 - r)
}

pub fn mitsuba(eta: TexValue, e: &mut dyn MaterialExport) -> MaterialOut {
    MaterialOut::ThinDielectric { eta: e.rgb(eta)[0] }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pane_reflects_both_faces_and_passes_the_rest_straight() {
        // Head-on through glass of 1.5: 4% a face, 2R/(1 + R) ≈ 7.7% for the pane.
        let (r, t) = shares(1.0, 1.5);
        assert!((r - 0.08 / 1.04).abs() < 1e-6, "{r}");
        assert!((r + t - 1.0).abs() < 1e-6);
        // Either side, the same shares; at grazing, all reflected.
        assert_eq!(shares(-0.3, 1.5), shares(0.3, 1.5));
        assert!(shares(1e-6, 1.5).0 > 0.999);
        // An index of 1 is no surface at all; below 1, light from outside can be
        // reflected whole.
        assert_eq!(shares(0.7, 1.0), (0.0, 1.0));
        assert_eq!(shares(0.1, 0.5), (1.0, 0.0));
    }
}
