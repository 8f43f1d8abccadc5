//! `Material "coateddiffuse"` and `Material "coatedconductor"` (v4): a dielectric coat
//! over a diffuse or conductor base, with an optional scattering layer between,
//! evaluated by pbrt-v4's stochastic layered BSDF ([`super::layered`]).
//!
//! ```text
//! Material "coateddiffuse" "rgb reflectance" [.4 .1 .1] "float roughness" .05 "float thickness" .01
//! Material "coatedconductor" "float interface.roughness" .1 "spectrum conductor.eta" "metal-Au-eta"
//!          "spectrum conductor.k" "metal-Au-k" "float conductor.roughness" .2
//! ```
//! Also `albedo` (0), `g` (0), `maxdepth` (10), `nsamples` (1); the coat is
//! `roughness`/`eta` for `coateddiffuse`, `interface.roughness`/`interface.eta` for
//! `coatedconductor`, whose base is `conductor.eta`/`conductor.k` (copper) or a
//! `reflectance`, never both (pbrt-v4's error).

use super::MaterialKind;
use super::dielectric::Dispersion;
use super::inputs::{Inputs, Lobes};
use super::layered::{Base, Coat, Layered};
use super::lobes::Lobe;
use super::microfacet::{Fresnel, TrowbridgeReitz};
use super::params::{Metal, Resolver, RoughnessRemap, TexValue, float, metal, prefixed_roughness, remap_v4, spectrum};
use crate::fixes::Fix;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::textures::TexCtx;
use crate::values::{self, Range, Res};
use glam::Vec3;

pub const NAMES: [&str; 2] = ["coateddiffuse", "coatedconductor"];

/// The inputs of a pbrt-v4 coated material (`thickness`, `albedo`, `g`, `maxdepth`,
/// `nsamples` as pbrt-v4 names them).
#[derive(Clone, Debug, PartialEq)]
pub struct Coated {
    pub coat_eta: f32,
    /// The coat's index by wavelength where a spectrum gives it: spectral paths
    /// disperse through the coat, as through a `dielectric`.
    pub coat_dispersion: Option<Dispersion>,
    pub coat_roughness: [TexValue; 2],
    pub base: CoatBase,
    pub thickness: TexValue,
    pub albedo: TexValue,
    pub g: TexValue,
    pub max_depth: u32,
    pub n_samples: u32,
    pub remap: RoughnessRemap,
}

/// What lies under a coat.
#[derive(Clone, Debug, PartialEq)]
pub enum CoatBase {
    Diffuse {
        reflectance: TexValue,
    },
    /// A conductor (relative to air; pbrt-v4 divides η and k by the coat's index).
    Conductor {
        metal: Metal,
        roughness: [TexValue; 2],
    },
}

pub fn read(ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    if ty == NAMES[0] {
        let base = CoatBase::Diffuse { reflectance: spectrum(p, "reflectance", 0.5, r)? };
        return coated(p, "", base, r);
    }
    let roughness = prefixed_roughness(p, "conductor.", r)?;
    let base = CoatBase::Conductor { metal: metal(p, "conductor.", Some(NAMES[1]), r)?, roughness };
    coated(p, "interface.", base, r)
}

/// A coated material's coat and layer; `prefix` is where the coat's own parameters
/// live (`interface.` for `coatedconductor`).
fn coated(p: &ParamList, prefix: &str, base: CoatBase, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let coat_eta = coat_eta(p, &format!("{prefix}eta"), r)?;
    let coat_dispersion = super::dielectric::dispersion(p, &format!("{prefix}eta"), r)?;
    let coat_roughness = prefixed_roughness(p, prefix, r)?;
    let thickness = float(p, "thickness", 0.01, Range::Any, r)?;
    let albedo = spectrum(p, "albedo", 0.0, r)?;
    let g = float(p, "g", 0.0, Range::Any, r)?;
    let (max_depth, n_samples) = (count(p, "maxdepth", 10)?, count(p, "nsamples", 1)?);
    let remap = remap_v4(p)?;
    let c =
        Coated { coat_eta, coat_dispersion, coat_roughness, base, thickness, albedo, g, max_depth, n_samples, remap };
    Ok(MaterialKind::Coated(Box::new(c)))
}

/// The most random-walk steps (`maxdepth`) or walks (`nsamples`) a coated material may
/// ask for: each BSDF evaluation costs up to their product.
const MAX_LAYER_COUNT: i32 = 1000;

/// `maxdepth` or `nsamples`, within 1..=[`MAX_LAYER_COUNT`].
fn count(p: &ParamList, name: &str, default: i32) -> Res<u32> {
    match p.int(name)? {
        None => Ok(default as u32),
        Some(v) if (1..=MAX_LAYER_COUNT).contains(&v) => Ok(v as u32),
        Some(v) => {
            let at = p.named(name).map_or_else(Span::default, |x| x.value_span);
            Err(Diagnostic::error(at, format!("\"{name}\" must be in 1..={MAX_LAYER_COUNT}, not {v}")))
        }
    }
}

/// A coat's index: a float, or a spectrum taken as one index (its luminance-weighted
/// mean, as for `dielectric`); 0 means 1 (pbrt-v4).
fn coat_eta(p: &ParamList, name: &str, r: &mut dyn Resolver) -> Res<f32> {
    let eta = if values::given(p, name, &[ParamType::Float]) {
        p.float(name)?.unwrap_or(1.5)
    } else {
        values::rgb(p, name, &r.spectra(), Range::NonNegative)?.map_or(1.5, crate::spectrum::luminance)
    };
    Ok(if eta == 0.0 { 1.0 } else { eta.abs() })
}

/// The layers at a hit (pbrt-v4's `CoatedDiffuseMaterial::GetBxDF` and
/// `CoatedConductorMaterial::GetBxDF`).
#[inline]
pub fn layers(c: &Coated, i: &Inputs<impl Fn() -> TexCtx>) -> Layered {
    let alpha = |r: &[TexValue; 2]| i.alpha(r, c.remap);
    let smooth = |a: [f32; 2]| a[0].max(a[1]) < 1e-3;
    let a = alpha(&c.coat_roughness);
    let coat_eta = match (&c.coat_dispersion, &i.spectral) {
        (Some(d), Some(pass)) => d.eta(pass.lambda[0]),
        _ => c.coat_eta,
    };
    let top = Coat { eta: coat_eta, dist: TrowbridgeReitz::new(a), smooth: smooth(a) };
    let conductor = |eta: Rgb, k: Rgb, r: &[TexValue; 2]| {
        let a = alpha(r);
        Base::Conductor { eta: eta / coat_eta, k: k / coat_eta, dist: TrowbridgeReitz::new(a), smooth: smooth(a) }
    };
    let bottom = match &c.base {
        CoatBase::Diffuse { reflectance } => Base::Diffuse(i.refl(*reflectance)),
        CoatBase::Conductor { metal, roughness } => {
            let (eta, k) = i.eta_k(metal);
            conductor(eta, k, roughness)
        }
    };
    Layered {
        top,
        bottom,
        thickness: i.float(c.thickness).max(f32::MIN_POSITIVE),
        albedo: i.albedo(c.albedo),
        g: i.float(c.g).clamp(-1.0, 1.0),
        max_depth: c.max_depth,
        n_samples: c.n_samples,
        fixed_weights: i.fixes.has(Fix::LayeredWeights),
    }
}

/// Only inside a pbrt-v3 mix, which holds lobes: the base alone (noted when read).
#[inline]
pub fn base_lobes<const N: usize>(c: &Coated, i: &Inputs<impl Fn() -> TexCtx>, out: &mut Lobes<N>) {
    match layers(c, i).bottom {
        Base::Diffuse(r) => out.push_nonzero(r, Lobe::Lambert),
        Base::Conductor { eta, k, dist, smooth } => {
            let fresnel = Fresnel::Conductor { eta, k };
            out.push(match smooth {
                true => Lobe::SpecularReflection { r: Vec3::ONE, fresnel },
                false => Lobe::MicrofacetReflection { r: Vec3::ONE, dist, fresnel },
            })
        }
    }
}

pub fn mitsuba(c: &Coated, e: &mut dyn MaterialExport) -> MaterialOut {
    e.note("coated: no Mitsuba equivalent is exported yet; exported as its diffuse base (grey over a conductor)");
    let reflectance = match c.base {
        CoatBase::Diffuse { reflectance } => e.rgb(reflectance),
        _ => [0.5; 3],
    };
    MaterialOut::Diffuse { reflectance }
}
