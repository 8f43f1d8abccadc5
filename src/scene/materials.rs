//! `Material` and `MakeNamedMaterial` statements to typed descriptions (textures:
//! [`super::textures`]).
//!
//! ```text
//! Material "matte" "rgb Kd" [.5 .5 .5]        Material "diffuse" "texture reflectance" "checks"
//! Material "mirror" "rgb Kr" [.9 .9 .9]
//! Material "glass" "float index" 1.5          Material "dielectric" "float eta" 1.5
//! Material "metal" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k" "float roughness" .1
//! Material "conductor" "rgb reflectance" [.9 .6 .3]
//! Material "plastic" "rgb Kd" [.4 .1 .1] "rgb Ks" [.3 .3 .3] "float roughness" .05
//! Material "uber" "rgb Kr" [.2 .2 .2] "float index" 1.5 "rgb opacity" [1 1 1]
//! Material "translucent" "rgb reflect" [.5 .5 .5] "rgb transmit" [.5 .5 .5]
//! Material "substrate" "float uroughness" .05 "float vroughness" .2
//! Material "matte" "float sigma" 20                   # Oren–Nayar
//! Material "mix" "string namedmaterial1" "a" "string namedmaterial2" "b" "color amount" [.3 .3 .3]  # v3
//! Material "mix" "string materials" ["a" "b"] "float amount" .3                                  # v4
//! Material "coateddiffuse" "rgb reflectance" [.4 .1 .1] "float roughness" .05      # v4
//! Material "coatedconductor" "spectrum conductor.eta" "metal-Au-eta" "spectrum conductor.k" "metal-Au-k"
//! Material "diffusetransmission" "rgb reflectance" [.3 .3 .3] "rgb transmittance" [.5 .5 .5]
//! Material "" / "none" / "interface"                # no surface: paths pass through
//! ```
//! What we render differently from the file (a material drawn as its diffuse part, rough
//! glass as smooth, a textured roughness taken at the texture's centre, ...) is recorded
//! as an [`Approx`] at the statement, so `check` and the renderer report it.

use super::approx::Approx;
use super::values::{self, Range, Res, SpectrumContext, SpectrumOrTexture};
use crate::imageio::RgbImage;
use crate::parser::error::Diagnostic;
use crate::parser::params::{FloatValue, ParamList, ParamType};
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use glam::Vec3;
use std::sync::Arc;

/// A spectrum- or float-valued input: a constant (floats as grey) or a texture, by its
/// index in [`super::SceneDescription::textures`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TexValue {
    Const(Rgb),
    Texture(u32),
}

/// How a roughness becomes a microfacet α.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RoughnessRemap {
    /// `remaproughness false`: α = roughness.
    None,
    /// pbrt-v3's polynomial in log(roughness) (`metal`, `glass`, `plastic`, `uber`).
    V3,
    /// pbrt-v4's √roughness (`conductor`, `dielectric`, `coated*`).
    V4,
}

/// A material some shape uses. Inputs are taken at each hit's (u, v); roughnesses are
/// as written, turned into α by `remap` when shading.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    Diffuse {
        reflectance: TexValue,
    },
    /// v3 `matte` with `sigma` (degrees) not zero.
    OrenNayar {
        reflectance: TexValue,
        sigma: TexValue,
    },
    /// v3 `plastic`: Lambertian plus a microfacet coat of index 1.5.
    Plastic {
        kd: TexValue,
        ks: TexValue,
        roughness: TexValue,
        remap: RoughnessRemap,
    },
    /// v3 `uber`: plastic-like layers plus specular reflection, transmission and opacity.
    Uber {
        kd: TexValue,
        ks: TexValue,
        kr: TexValue,
        kt: TexValue,
        roughness: [TexValue; 2],
        eta: TexValue,
        opacity: TexValue,
        remap: RoughnessRemap,
    },
    /// v3 `translucent`: diffuse and glossy reflection and transmission.
    Translucent {
        kd: TexValue,
        ks: TexValue,
        reflect: TexValue,
        transmit: TexValue,
        roughness: TexValue,
        remap: RoughnessRemap,
    },
    /// v3 `substrate` (Ashikhmin–Shirley).
    Substrate {
        kd: TexValue,
        ks: TexValue,
        roughness: [TexValue; 2],
        remap: RoughnessRemap,
    },
    /// pbrt-v4 `diffusetransmission`: Lambertian reflection and transmission, both
    /// multiplied by `scale` and clamped to [0, 1].
    DiffuseTransmission {
        reflectance: TexValue,
        transmittance: TexValue,
        scale: TexValue,
    },
    /// A perfect mirror tinted by `reflectance` (`mirror`).
    Mirror {
        reflectance: TexValue,
    },
    /// A dielectric; smooth when both roughnesses are 0.
    Dielectric {
        eta: TexValue,
        kr: TexValue,
        kt: TexValue,
        roughness: [TexValue; 2],
        remap: RoughnessRemap,
    },
    /// A conductor; smooth when both roughnesses give α below 10⁻³.
    Conductor {
        metal: Metal,
        roughness: [TexValue; 2],
        remap: RoughnessRemap,
    },
    /// pbrt-v4 `coateddiffuse` / `coatedconductor`: a dielectric coat over a base.
    Coated(Box<Coated>),
    /// No surface: rays continue straight through.
    Interface,
    /// Two materials (built indices) mixed by `amount`.
    Mix {
        materials: [u32; 2],
        amount: TexValue,
        rule: MixRule,
    },
}

/// The inputs of a pbrt-v4 coated material (`thickness`, `albedo`, `g`, `maxdepth`,
/// `nsamples` as pbrt-v4 names them; the coat is `roughness`/`eta` for
/// `coateddiffuse`, `interface.roughness`/`interface.eta` for `coatedconductor`).
#[derive(Clone, Debug, PartialEq)]
pub struct Coated {
    pub coat_eta: f32,
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

/// A conductor's optical constants.
#[derive(Clone, Debug, PartialEq)]
pub enum Metal {
    /// Index η + ik.
    EtaK { eta: Rgb, k: Rgb },
    /// pbrt-v4's `reflectance`: the reflectance at normal incidence, turned into η = 1,
    /// k = 2√r / √(1 − r) where it is evaluated.
    Reflectance(TexValue),
}

impl Metal {
    /// pbrt-v4's η and k for a reflectance r at normal incidence (r kept below 1,
    /// where k would be infinite).
    pub fn eta_k_of_reflectance(r: Rgb) -> (Rgb, Rgb) {
        let r = r.clamp(Vec3::ZERO, Vec3::splat(0.9999));
        (Vec3::ONE, 2.0 * r.powf(0.5) / (Vec3::ONE - r).powf(0.5))
    }
}

/// How `mix` combines its two materials.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MixRule {
    /// pbrt-v3 (`namedmaterial1`, `namedmaterial2`, spectrum `amount`): the BSDF holds
    /// both materials' lobes, the first's scaled by amount and the second's by
    /// 1 − amount.
    Blend,
    /// pbrt-v4 (`string materials [a b]`, float `amount`): each hit takes the second
    /// material with probability amount, else the first.
    Choose,
}

#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    /// The type as written (`matte`, `diffuse`, `interface`, ...).
    pub ty: String,
    /// The `MakeNamedMaterial` name, if any.
    pub name: Option<String>,
    pub kind: MaterialKind,
    /// A float texture displacing the surface along its shading normal (v3 `bumpmap`,
    /// v4 `displacement`): it tilts the shading normal, as pbrt's bump mapping does.
    pub bump: Option<TexValue>,
    /// A v4 `normalmap` image, which replaces the bump map when both are given (as in
    /// pbrt-v4).
    pub normal_map: Option<Arc<RgbImage>>,
}

/// What building materials and textures needs from the scene builder.
pub trait Resolver {
    /// The float or spectrum texture `name`, built on first use; `at` is the span of
    /// the parameter naming it.
    fn texture(&mut self, name: &str, float: bool, at: Span) -> Res<u32>;
    fn approximate(&mut self, at: Span, what: String, how: Approx);
    /// The named material `name`, built on first use (for `mix`); its built index.
    fn named_material(&mut self, name: &str, at: Span) -> Res<u32>;
    /// What a built material (a [`Resolver::named_material`] index) is.
    fn material_kind(&self, built: u32) -> Option<&MaterialKind>;
    fn spectra(&self) -> SpectrumContext<'_>;
    /// An image for `imagemap` (cached); errors are plain messages.
    fn image(&mut self, name: &str) -> Result<Arc<RgbImage>, String>;
}

/// A spectrum input: constant (non-negative) or a spectrum texture.
pub(super) fn spectrum(p: &ParamList, name: &str, default: f32, r: &mut dyn Resolver) -> Res<TexValue> {
    let found = values::spectrum(p, name, &r.spectra(), Range::NonNegative)?;
    Ok(match found {
        None => TexValue::Const(Vec3::splat(default)),
        Some((SpectrumOrTexture::Rgb(c), _)) => TexValue::Const(c),
        Some((SpectrumOrTexture::Texture(t), at)) => TexValue::Texture(r.texture(&t, false, at)?),
    })
}

/// A float input: constant (in `range`) or a float texture.
pub(super) fn float(p: &ParamList, name: &str, default: f32, range: Range, r: &mut dyn Resolver) -> Res<TexValue> {
    Ok(match values::float_or_texture(p, name, range)? {
        None => TexValue::Const(Vec3::splat(default)),
        Some((FloatValue::Const(v), _)) => TexValue::Const(Vec3::splat(v)),
        Some((FloatValue::Texture(t), at)) => TexValue::Texture(r.texture(&t, true, at)?),
    })
}

/// The material of type `ty`; unsupported types become grey diffuse (noted).
pub fn material(ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    Ok(match ty {
        "matte" => {
            let sigma = float(p, "sigma", 0.0, Range::NonNegative, r)?;
            let reflectance = spectrum(p, "Kd", 0.5, r)?;
            if sigma == TexValue::Const(Vec3::ZERO) {
                MaterialKind::Diffuse { reflectance }
            } else {
                MaterialKind::OrenNayar { reflectance, sigma }
            }
        }
        "diffuse" => MaterialKind::Diffuse { reflectance: spectrum(p, "reflectance", 0.5, r)? },
        "mirror" => MaterialKind::Mirror { reflectance: spectrum(p, "Kr", 0.9, r)? },
        "glass" | "dielectric" => dielectric(ty, p, r)?,
        "metal" | "conductor" => conductor(ty, p, r)?,
        "plastic" => MaterialKind::Plastic {
            kd: spectrum(p, "Kd", 0.25, r)?,
            ks: spectrum(p, "Ks", 0.25, r)?,
            roughness: float(p, "roughness", 0.1, Range::NonNegative, r)?,
            remap: remap_v3(p)?,
        },
        "uber" => uber(p, r)?,
        "translucent" => MaterialKind::Translucent {
            kd: spectrum(p, "Kd", 0.25, r)?,
            ks: spectrum(p, "Ks", 0.25, r)?,
            reflect: spectrum(p, "reflect", 0.5, r)?,
            transmit: spectrum(p, "transmit", 0.5, r)?,
            roughness: float(p, "roughness", 0.1, Range::NonNegative, r)?,
            remap: remap_v3(p)?,
        },
        "substrate" => {
            let rough = |name: &str, r: &mut dyn Resolver| float(p, name, 0.1, Range::NonNegative, r);
            MaterialKind::Substrate {
                kd: spectrum(p, "Kd", 0.5, r)?,
                ks: spectrum(p, "Ks", 0.5, r)?,
                roughness: [rough("uroughness", r)?, rough("vroughness", r)?],
                remap: remap_v3(p)?,
            }
        }
        "coateddiffuse" => {
            let base = CoatBase::Diffuse { reflectance: spectrum(p, "reflectance", 0.5, r)? };
            coated(p, "", base, r)?
        }
        "coatedconductor" => {
            let base = coat_base(p, r)?;
            coated(p, "interface.", base, r)?
        }
        "diffusetransmission" => {
            let scale = float(p, "scale", 1.0, Range::Any, r)?;
            MaterialKind::DiffuseTransmission {
                reflectance: spectrum(p, "reflectance", 0.25, r)?,
                transmittance: spectrum(p, "transmittance", 0.25, r)?,
                scale,
            }
        }
        "" | "none" | "interface" => MaterialKind::Interface,
        "mix" => mix(p, at, r)?,
        _ => {
            p.mark_all_used();
            r.approximate(at, format!("material \"{ty}\""), Approx::UnsupportedMaterial);
            MaterialKind::Diffuse { reflectance: TexValue::Const(Vec3::splat(0.5)) }
        }
    })
}

/// The material's normal map (v4 `normalmap`, an RGB image of tangent-space normals,
/// its values as stored: no sRGB decoding). An image that cannot be read leaves the
/// surface smooth (noted).
pub fn normal_map(ty: &str, p: &ParamList, r: &mut dyn Resolver) -> Res<Option<Arc<RgbImage>>> {
    let Some(file) = p.string("normalmap")? else { return Ok(None) };
    let at = p.named("normalmap").map_or_else(Span::default, |x| x.value_span);
    match r.image(&file) {
        Ok(img) => Ok(Some(crate::imageio::stored_values(&file, img))),
        Err(e) => {
            r.approximate(at, format!("\"normalmap\" of material \"{ty}\" ({e})"), Approx::MissingImage);
            Ok(None)
        }
    }
}

/// The material's bump map (`bumpmap` in v3, `displacement` in v4; either is read in
/// either version).
pub fn bump_map(p: &ParamList, r: &mut dyn Resolver) -> Res<Option<TexValue>> {
    let name = if p.named("bumpmap").is_some() { "bumpmap" } else { "displacement" };
    Ok(match values::float_or_texture(p, name, Range::Any)? {
        None => None,
        // A constant displacement moves the whole surface and tilts nothing.
        Some((FloatValue::Const(_), _)) => None,
        Some((FloatValue::Texture(t), at)) => Some(TexValue::Texture(r.texture(&t, true, at)?)),
    })
}

/// v3 `glass` (`eta`, else `index`; `Kr`, `Kt`) and v4 `dielectric` (`eta` a float or
/// a spectrum). Rough ones render smooth (noted).
fn dielectric(ty: &str, p: &ParamList, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let eta_name = if ty == "glass" && p.named("eta").is_none() { "index" } else { "eta" };
    // v3 glass takes a float (texture); v4 dielectric also a spectrum.
    let eta = if ty == "glass" || values::given(p, eta_name, &[ParamType::Float, ParamType::Texture]) {
        float(p, eta_name, 1.5, Range::Positive, r)?
    } else {
        // A spectral index (v4): RGB has one index, its luminance-weighted mean.
        match values::rgb(p, eta_name, &r.spectra(), Range::Positive)? {
            Some(c) => TexValue::Const(Vec3::splat(crate::spectrum::luminance(c))),
            None => TexValue::Const(Vec3::splat(1.5)),
        }
    };
    let (kr, kt) = if ty == "glass" { (spectrum(p, "Kr", 1.0, r)?, spectrum(p, "Kt", 1.0, r)?) } else { one_one() };
    // pbrt-v3's glass reads only `uroughness`/`vroughness`: its `roughness` is unused.
    let roughness = if ty == "glass" { uv_roughness(p, r)? } else { roughness(p, 0.0, r)? };
    let remap = if ty == "glass" { remap_v3(p)? } else { remap_v4(p)? };
    Ok(MaterialKind::Dielectric { eta, kr, kt, roughness, remap })
}

/// v3 `remaproughness` (default true): pbrt-v3's polynomial.
fn remap_v3(p: &ParamList) -> Res<RoughnessRemap> {
    Ok(if p.bool("remaproughness")?.unwrap_or(true) { RoughnessRemap::V3 } else { RoughnessRemap::None })
}

/// v4 `remaproughness` (default true): α = √roughness.
fn remap_v4(p: &ParamList) -> Res<RoughnessRemap> {
    Ok(if p.bool("remaproughness")?.unwrap_or(true) { RoughnessRemap::V4 } else { RoughnessRemap::None })
}

/// v3 `uber`: `roughness` .1 overridden by `uroughness`/`vroughness`; `eta`, else `index`.
fn uber(p: &ParamList, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let eta_name = if p.named("eta").is_some() { "eta" } else { "index" };
    Ok(MaterialKind::Uber {
        kd: spectrum(p, "Kd", 0.25, r)?,
        ks: spectrum(p, "Ks", 0.25, r)?,
        kr: spectrum(p, "Kr", 0.0, r)?,
        kt: spectrum(p, "Kt", 0.0, r)?,
        roughness: roughness(p, 0.1, r)?,
        eta: float(p, eta_name, 1.5, Range::Positive, r)?,
        opacity: spectrum(p, "opacity", 1.0, r)?,
        remap: remap_v3(p)?,
    })
}

fn one_one() -> (TexValue, TexValue) {
    (TexValue::Const(Vec3::ONE), TexValue::Const(Vec3::ONE))
}

/// `roughness` (both directions), overridden per direction by `uroughness`/`vroughness`.
fn roughness(p: &ParamList, default: f32, r: &mut dyn Resolver) -> Res<[TexValue; 2]> {
    let both = float(p, "roughness", default, Range::NonNegative, r)?;
    let one = |name: &str, r: &mut dyn Resolver| -> Res<TexValue> {
        Ok(if p.named(name).is_some() { float(p, name, default, Range::NonNegative, r)? } else { both })
    };
    Ok([one("uroughness", r)?, one("vroughness", r)?])
}

/// v3 `metal` (copper by default, roughness 0.01 through v3's remapping) and v4
/// `conductor` (roughness 0, √ remapping, or a `reflectance`).
fn conductor(ty: &str, p: &ParamList, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let v3 = ty == "metal";
    let metal = if v3 { metal(p, "", None, r)? } else { metal(p, "", Some(ty), r)? };
    let roughness = roughness(p, if v3 { 0.01 } else { 0.0 }, r)?;
    let remap = if v3 { remap_v3(p)? } else { remap_v4(p)? };
    Ok(MaterialKind::Conductor { metal, roughness, remap })
}

/// `{prefix}eta` / `{prefix}k` (copper by default), or, for the v4 material `v4`, a
/// `reflectance` instead (never both: pbrt-v4's error).
fn metal(p: &ParamList, prefix: &str, v4: Option<&str>, r: &mut dyn Resolver) -> Res<Metal> {
    let (eta_name, k_name) = (format!("{prefix}eta"), format!("{prefix}k"));
    if let (Some(ty), Some(refl)) = (v4, p.named("reflectance")) {
        if p.named(&eta_name).is_some() || p.named(&k_name).is_some() {
            let msg = format!("{ty} takes \"reflectance\" or \"{eta_name}\"/\"{k_name}\", not both");
            return Err(Diagnostic::error(refl.span, msg));
        }
        return Ok(Metal::Reflectance(spectrum(p, "reflectance", 0.0, r)?));
    }
    let spectra = r.spectra();
    let named = |n: &str| crate::spectrum::named_spectrum(n).unwrap_or(Vec3::ONE);
    let eta = values::rgb(p, &eta_name, &spectra, Range::Positive)?.unwrap_or_else(|| named("metal-Cu-eta"));
    let k = values::rgb(p, &k_name, &spectra, Range::NonNegative)?.unwrap_or_else(|| named("metal-Cu-k"));
    Ok(Metal::EtaK { eta, k })
}

/// v3 `mix` (`namedmaterial1`/`namedmaterial2`, spectrum `amount`) or v4 `mix`
/// (`string materials` [two names], float `amount`).
fn mix(p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let names_at = |n: &str| p.named(n).map_or(at, |x| x.value_span);
    if let Some(list) = p.array("materials", ParamType::String)? {
        let names = list.strings();
        let [a, b] = names else {
            let msg = format!("mix needs two \"materials\", not {}", names.len());
            return Err(Diagnostic::error(list.value_span, msg));
        };
        let materials = [r.named_material(a, list.value_span)?, r.named_material(b, list.value_span)?];
        let amount = float(p, "amount", 0.5, Range::Any, r)?;
        return Ok(MaterialKind::Mix { materials, amount, rule: MixRule::Choose });
    }
    let named = |n: &str, r: &mut dyn Resolver| -> Res<u32> {
        let name = p.string(n)?.ok_or_else(|| Diagnostic::error(at, format!("mix needs \"string {n}\"")))?;
        r.named_material(&name, names_at(n))
    };
    let materials = [named("namedmaterial1", r)?, named("namedmaterial2", r)?];
    let amount = spectrum(p, "amount", 0.5, r)?;
    if materials.iter().any(|&m| matches!(r.material_kind(m), Some(MaterialKind::Coated(_)))) {
        r.approximate(at, "pbrt-v4 coated material in a pbrt-v3 mix".into(), Approx::CoatInBlend);
    }
    Ok(MaterialKind::Mix { materials, amount, rule: MixRule::Blend })
}

/// A coated material's coat and layer; `prefix` is where the coat's own parameters
/// live (`interface.` for `coatedconductor`).
fn coated(p: &ParamList, prefix: &str, base: CoatBase, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let coat_eta = coat_eta(p, &format!("{prefix}eta"), r)?;
    let coat_roughness = prefixed_roughness(p, prefix, r)?;
    let thickness = float(p, "thickness", 0.01, Range::Any, r)?;
    let albedo = spectrum(p, "albedo", 0.0, r)?;
    let g = float(p, "g", 0.0, Range::Any, r)?;
    let count = |name: &str, default: i32| -> Res<u32> {
        match p.int(name)? {
            None => Ok(default as u32),
            Some(v) if (1..=MAX_LAYER_COUNT).contains(&v) => Ok(v as u32),
            Some(v) => {
                let at = p.named(name).map_or_else(Span::default, |x| x.value_span);
                Err(Diagnostic::error(at, format!("\"{name}\" must be in 1..={MAX_LAYER_COUNT}, not {v}")))
            }
        }
    };
    let (max_depth, n_samples) = (count("maxdepth", 10)?, count("nsamples", 1)?);
    let remap = remap_v4(p)?;
    let c = Coated { coat_eta, coat_roughness, base, thickness, albedo, g, max_depth, n_samples, remap };
    Ok(MaterialKind::Coated(Box::new(c)))
}

/// The most random-walk steps (`maxdepth`) or walks (`nsamples`) a coated material may
/// ask for: each BSDF evaluation costs up to their product.
const MAX_LAYER_COUNT: i32 = 1000;

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

/// `uroughness` and `vroughness` alone (0 by default).
fn uv_roughness(p: &ParamList, r: &mut dyn Resolver) -> Res<[TexValue; 2]> {
    Ok([float(p, "uroughness", 0.0, Range::NonNegative, r)?, float(p, "vroughness", 0.0, Range::NonNegative, r)?])
}

/// `{prefix}roughness`, overridden per direction by `{prefix}uroughness`/`vroughness`.
fn prefixed_roughness(p: &ParamList, prefix: &str, r: &mut dyn Resolver) -> Res<[TexValue; 2]> {
    let both = float(p, &format!("{prefix}roughness"), 0.0, Range::NonNegative, r)?;
    let one = |dir: &str, r: &mut dyn Resolver| -> Res<TexValue> {
        let name = format!("{prefix}{dir}roughness");
        Ok(if p.named(&name).is_some() { float(p, &name, 0.0, Range::NonNegative, r)? } else { both })
    };
    Ok([one("u", r)?, one("v", r)?])
}

/// `coatedconductor`'s base: `conductor.eta`/`conductor.k` (copper by default) or a
/// `reflectance`, never both (pbrt-v4's error).
fn coat_base(p: &ParamList, r: &mut dyn Resolver) -> Res<CoatBase> {
    let roughness = prefixed_roughness(p, "conductor.", r)?;
    Ok(CoatBase::Conductor { metal: metal(p, "conductor.", Some("coatedconductor"), r)?, roughness })
}
