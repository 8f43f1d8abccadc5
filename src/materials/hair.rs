//! `Material "hair"` (pbrt-v3 and v4): the hair scattering model of pbrt (Chiang et
//! al. 2016 after d'Eon and Marschner): a rough dielectric cylinder with tilted
//! cuticle scales, whose absorption gives the colour. Meant for `curve` shapes, whose
//! v coordinate says where across the fibre a ray hit.
//!
//! ```text
//! Material "hair" "rgb sigma_a" [.2 .4 1]           # absorption per unit diameter, or
//! Material "hair" "rgb reflectance" [.6 .4 .2]      # the colour wanted (v3: "color"), or
//! Material "hair" "float eumelanin" 1.3 "float pheomelanin" 0   # pigment concentrations
//!     "float eta" 1.55 "float beta_m" .3 "float beta_n" .3 "float alpha" 2
//! ```
//! With none of the three, the hair is brown (eumelanin 1.3), as in pbrt. The first of
//! them given wins (`sigma_a`, then the colour, then the melanins); the others are
//! reported as unused parameters, as pbrt-v4 warns of them. The scattering itself is
//! [`super::fibre`]. The colour is turned into σa per RGB channel (pbrt-v4 does it per
//! wavelength).

use super::MaterialKind;
use super::fibre::HairBxdf;
use super::inputs::Inputs;
use super::params::{Resolver, TexValue, float, spectrum};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::textures::TexCtx;
use crate::values::{Range, Res};
use glam::Vec3;

pub const NAME: &str = "hair";

/// Where the absorption comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Absorption {
    SigmaA(TexValue),
    Color(TexValue),
    Melanin { eumelanin: TexValue, pheomelanin: TexValue },
}

/// A hair material's inputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hair {
    pub absorption: Absorption,
    pub eta: TexValue,
    pub beta_m: TexValue,
    pub beta_n: TexValue,
    pub alpha: TexValue,
}

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let given = |n: &str| p.named(n).is_some();
    let color = if given("reflectance") { "reflectance" } else { "color" };
    let melanin = given("eumelanin") || given("pheomelanin");
    let absorption = if given("sigma_a") {
        Absorption::SigmaA(spectrum(p, "sigma_a", 0.0, r)?)
    } else if given(color) {
        Absorption::Color(spectrum(p, color, 0.0, r)?)
    } else {
        let eumelanin = float(p, "eumelanin", if melanin { 0.0 } else { 1.3 }, Range::NonNegative, r)?;
        Absorption::Melanin { eumelanin, pheomelanin: float(p, "pheomelanin", 0.0, Range::NonNegative, r)? }
    };
    let beta = |name, r: &mut dyn Resolver| float(p, name, 0.3, Range::NonNegative, r);
    Ok(MaterialKind::Hair(Box::new(Hair {
        absorption,
        eta: float(p, "eta", 1.55, Range::Positive, r)?,
        beta_m: beta("beta_m", r)?,
        beta_n: beta("beta_n", r)?,
        alpha: float(p, "alpha", 2.0, Range::Any, r)?,
    })))
}

/// Mitsuba 3 has hair only as a plugin of its own: exported as a brown diffuse, noted.
pub fn mitsuba(e: &mut dyn MaterialExport) -> MaterialOut {
    e.note("hair: no Mitsuba equivalent is exported; exported as a brown diffuse");
    MaterialOut::Diffuse { reflectance: [0.25, 0.15, 0.08] }
}

/// σa of the pigment concentrations (pbrt's `SigmaAFromConcentration`).
fn sigma_a_of_melanin(eumelanin: f32, pheomelanin: f32) -> Rgb {
    eumelanin.max(0.0) * Vec3::new(0.419, 0.697, 1.37) + pheomelanin.max(0.0) * Vec3::new(0.187, 0.4, 1.05)
}

/// σa giving roughly the colour `c` (pbrt's `SigmaAFromReflectance`).
fn sigma_a_of_color(c: Rgb, beta_n: f32) -> Rgb {
    let b = beta_n;
    let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3) + 5.574 * b.powi(4) + 0.245 * b.powi(5);
    c.clamp(Vec3::ZERO, Vec3::ONE).map(|c| (c.ln() / d).powi(2))
}

/// The BSDF at a hit whose curve v coordinate is `v`.
pub fn bxdf(hair: &Hair, i: &Inputs<impl Fn() -> TexCtx>, v: f32) -> HairBxdf {
    let beta_m = i.float(hair.beta_m).clamp(0.0, 1.0);
    let beta_n = i.float(hair.beta_n).clamp(0.0, 1.0);
    let sigma_a = match hair.absorption {
        Absorption::SigmaA(s) => i.unbounded(s),
        // pbrt-v4 takes σa per wavelength from the reflectance's spectrum.
        Absorption::Color(c) => sigma_a_of_color(i.albedo(c), beta_n),
        Absorption::Melanin { eumelanin, pheomelanin } => {
            i.lanes_unbounded(sigma_a_of_melanin(i.float(eumelanin), i.float(pheomelanin)))
        }
    };
    let h = (-1.0 + 2.0 * v).clamp(-1.0, 1.0);
    HairBxdf::new(h, i.float(hair.eta), sigma_a, [beta_m, beta_n], i.float(hair.alpha))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_and_melanin_give_pbrts_absorption() {
        // pbrt's brown default; a colour of 1 absorbs nothing.
        assert!((sigma_a_of_melanin(1.3, 0.0) - Vec3::new(0.5447, 0.9061, 1.781)).abs().max_element() < 1e-3);
        assert_eq!(sigma_a_of_color(Vec3::ONE, 0.3), Vec3::ZERO);
        let dark = sigma_a_of_color(Vec3::splat(0.1), 0.3);
        assert!(dark.x > sigma_a_of_color(Vec3::splat(0.5), 0.3).x);
    }
}
