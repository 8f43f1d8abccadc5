//! Materials and textures (RGB) and the BSDFs they produce at a hit.
//!
//! ```text
//! Material "matte" "rgb Kd" [.5 .5 .5]        Material "diffuse" "texture reflectance" "checks"
//! Material "glass" "float index" 1.5          Material "metal" "spectrum eta" "metal-Au-eta"
//! Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "rgb tex1" [1 0 0]
//! ```
//! Every parameter is settled by the scene description (`scene::materials`); this module
//! turns typed materials into BSDFs, their inputs evaluated at each hit. Textures live
//! in one array and refer to each other by index, so shared definitions are stored once
//! (`textures`).

mod bsdf;
pub mod layered;
pub mod lobes;
pub mod microfacet;
pub mod noise;
mod textures;
mod transport;

pub use bsdf::{Bsdf, BsdfEval, BsdfSample, Convention};
use lobes::{Lobe, MAX_LOBES, oren_nayar_ab};
use microfacet::{Fresnel, TrowbridgeReitz};
pub use textures::{TexCtx, Textures};
pub use transport::TransportMode;

use crate::fixes::{Fix, Fixes};
use crate::scene::{CoatBase, Coated, MaterialDesc, MaterialKind, Metal, RoughnessRemap, TexValue};
use crate::spectrum::Rgb;
use glam::Vec3;
use layered::{Base, Coat, Layered};

/// A material ready to shade: the scene's description, its inputs evaluated at each hit.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    kind: MaterialKind,
    /// Reflectances are clamped to [0, this]: pbrt-v3's materials clamp only below
    /// (`Spectrum::Clamp()`), so a v3 `Kd` above 1 reflects more than it receives, as
    /// in pbrt-v3; pbrt-v4's clamp to [0, 1].
    max_reflectance: f32,
    /// The version whose rules its BSDF follows where shading normals bend.
    convention: Convention,
    /// The bump map (a float texture), if any.
    pub bump: Option<TexValue>,
    /// The normal map (tangent-space normals as stored), if any; it wins over `bump`.
    pub normal_map: Option<std::sync::Arc<crate::imageio::RgbImage>>,
    /// The pbrt bugs fixed (`--fix`).
    fixes: Fixes,
}

/// pbrt-v3's material types (the rest are pbrt-v4's): their BSDFs follow pbrt-v3.
const V3_TYPES: [&str; 8] = ["matte", "plastic", "uber", "translucent", "substrate", "glass", "metal", "mirror"];

impl Material {
    pub fn from_desc(m: &MaterialDesc, fixes: Fixes) -> Material {
        let v3 = V3_TYPES.contains(&m.ty.as_str());
        let (max_reflectance, convention) =
            if v3 { (f32::INFINITY, Convention::PbrtV3) } else { (1.0, Convention::PbrtV4) };
        let normal_map = m.normal_map.clone();
        Material { kind: m.kind.clone(), max_reflectance, convention, bump: m.bump, normal_map, fixes }
    }

    pub fn kind(&self) -> &MaterialKind {
        &self.kind
    }

    /// The BSDF at a hit (`None` for interfaces); `ctx` says where textured inputs are
    /// looked up (made only when one is).
    #[inline]
    pub fn bsdf(&self, textures: &Textures, ctx: impl Fn() -> TexCtx, frame: [Vec3; 3], ng: Vec3) -> Option<Bsdf> {
        let inputs = Inputs { textures, ctx, max_reflectance: self.max_reflectance, fixes: self.fixes };
        if let MaterialKind::Diffuse { reflectance } = &self.kind {
            // The common case, without the lobe list's set-up.
            let lambert = lambert(inputs.refl(*reflectance));
            return Some(Bsdf::new(frame, ng, lambert.as_slice(), self.convention));
        }
        self.layered_bsdf(&inputs, frame, ng)
    }

    #[inline(never)]
    fn layered_bsdf(&self, inputs: &Inputs<impl Fn() -> TexCtx>, frame: [Vec3; 3], ng: Vec3) -> Option<Bsdf> {
        if let MaterialKind::Coated(c) = &self.kind {
            return Some(Bsdf::layered(frame, coated(c, inputs)));
        }
        let mut lobes = Lobes::<MATERIAL_LOBES>::default();
        self.lobes(inputs, &mut lobes)?;
        Some(Bsdf::new(frame, ng, &lobes.list[..lobes.n], self.convention))
    }

    /// Appends this material's lobes at a hit, each scaled by `weight` (a v3 `mix`
    /// part); interfaces and mixes add none.
    pub fn add_lobes(&self, textures: &Textures, ctx: impl Fn() -> TexCtx, weight: Rgb, out: &mut LobeList) {
        let inputs = Inputs { textures, ctx, max_reflectance: self.max_reflectance, fixes: self.fixes };
        let start = out.0.n;
        if self.lobes(&inputs, &mut out.0).is_some() {
            out.0.list[start..out.0.n].iter_mut().for_each(|l| *l = l.scaled(weight));
        }
    }

    fn lobes<const N: usize>(&self, i: &Inputs<impl Fn() -> TexCtx>, out: &mut Lobes<N>) -> Option<()> {
        match &self.kind {
            MaterialKind::Diffuse { reflectance } => {
                lambert(i.refl(*reflectance)).into_iter().for_each(|l| out.push(l))
            }
            MaterialKind::OrenNayar { reflectance, sigma } => {
                let r = i.refl(*reflectance);
                match oren_nayar_ab(i.float(*sigma)) {
                    (_, 0.0) => out.push_nonzero(r, Lobe::Lambert),
                    (a, b) => out.push_nonzero(r, |r| Lobe::OrenNayar { r, a, b }),
                }
            }
            MaterialKind::DiffuseTransmission { reflectance, transmittance, scale } => {
                let s = i.float(*scale);
                out.push_nonzero(i.refl_scaled(*reflectance, s), Lobe::Lambert);
                out.push_nonzero(i.refl_scaled(*transmittance, s), Lobe::LambertTransmission);
            }
            // Only inside a pbrt-v3 mix, which holds lobes: the base alone (noted).
            MaterialKind::Coated(c) => match coated(c, i).bottom {
                Base::Diffuse(r) => out.push_nonzero(r, Lobe::Lambert),
                Base::Conductor { eta, k, dist, smooth } => {
                    let fresnel = Fresnel::Conductor { eta, k };
                    out.push(match smooth {
                        true => Lobe::SpecularReflection { r: Vec3::ONE, fresnel },
                        false => Lobe::MicrofacetReflection { r: Vec3::ONE, dist, fresnel },
                    })
                }
            },
            MaterialKind::Mirror { reflectance } => {
                out.push(Lobe::SpecularReflection { r: i.rgb(*reflectance), fresnel: Fresnel::One })
            }
            MaterialKind::Dielectric { eta, kr, kt, roughness, remap } => {
                // Smooth when the roughness as written is 0 (pbrt-v3: v3's remapping
                // takes 0 to α ≈ 0.047) or α is below 10⁻³ (pbrt-v4's test).
                let raw = roughness.map(|r| i.float(r));
                let alpha = if raw == [0.0; 2] { raw } else { raw.map(|r| remap.alpha(r)) };
                let alpha = if alpha.iter().all(|a| *a < 1e-3) { [0.0; 2] } else { alpha };
                dielectric(i.float(*eta), i.refl(*kr), i.refl(*kt), alpha, self.convention, out)
            }
            MaterialKind::Conductor { metal, roughness, remap } => {
                let (eta, k) = i.eta_k(metal);
                let fresnel = Fresnel::Conductor { eta, k };
                let alpha = i.alpha(roughness, *remap);
                if alpha[0] < 1e-3 && alpha[1] < 1e-3 {
                    out.push(Lobe::SpecularReflection { r: Vec3::ONE, fresnel });
                } else {
                    out.push(Lobe::MicrofacetReflection { r: Vec3::ONE, dist: TrowbridgeReitz::new(alpha), fresnel });
                }
            }
            MaterialKind::Plastic { kd, ks, roughness, remap } => plastic(i, [*kd, *ks], *roughness, *remap, out),
            MaterialKind::Uber { kd, ks, kr, kt, roughness, eta, opacity, remap } => {
                uber(i, [*kd, *ks, *kr, *kt, *eta, *opacity], roughness, *remap, out)
            }
            MaterialKind::Translucent { kd, ks, reflect, transmit, roughness, remap } => {
                translucent(i, [*kd, *ks, *reflect, *transmit], *roughness, *remap, out)
            }
            MaterialKind::Substrate { kd, ks, roughness, remap } => {
                let (rd, rs) = (i.refl(*kd), i.refl(*ks));
                if rd != Vec3::ZERO || rs != Vec3::ZERO {
                    let dist = TrowbridgeReitz::new(i.alpha(roughness, *remap));
                    out.push(Lobe::FresnelBlend { rd, rs, dist, scale: Vec3::ONE });
                }
            }
            // Mixes are resolved by the scene, which holds their materials.
            MaterialKind::Interface | MaterialKind::Mix { .. } => return None,
        }
        Some(())
    }
}

/// pbrt-v3's plastic: Lambertian `kd` and a microfacet coat `ks` of index 1.5.
fn plastic<const N: usize>(
    i: &Inputs<impl Fn() -> TexCtx>,
    [kd, ks]: [TexValue; 2],
    roughness: TexValue,
    remap: RoughnessRemap,
    out: &mut Lobes<N>,
) {
    out.push_nonzero(i.refl(kd), Lobe::Lambert);
    let a = remap.alpha(i.float(roughness));
    let fresnel = match i.fixes.has(Fix::PlasticFresnel) {
        true => Fresnel::Coat { eta: 1.5 },
        false => Fresnel::SwappedCoat { eta: 1.5 },
    };
    let dist = TrowbridgeReitz::new([a, a]);
    out.push_nonzero(i.refl(ks), |r| Lobe::MicrofacetReflection { r, dist, fresnel });
}

/// pbrt-v3's uber: a pass-through of 1 − opacity, then each layer scaled by the opacity.
fn uber<const N: usize>(
    i: &Inputs<impl Fn() -> TexCtx>,
    [kd, ks, kr, kt, eta, opacity]: [TexValue; 6],
    roughness: &[TexValue; 2],
    remap: RoughnessRemap,
    out: &mut Lobes<N>,
) {
    let op = i.refl(opacity);
    out.push_nonzero((Vec3::ONE - op).max(Vec3::ZERO), |t| Lobe::SpecularTransmission { t, eta: 1.0 });
    let eta = i.float(eta);
    out.push_nonzero(op * i.refl(kd), Lobe::Lambert);
    let (dist, fresnel) = (TrowbridgeReitz::new(i.alpha(roughness, remap)), Fresnel::Dielectric { eta });
    out.push_nonzero(op * i.refl(ks), |r| Lobe::MicrofacetReflection { r, dist, fresnel });
    out.push_nonzero(op * i.refl(kr), |r| Lobe::SpecularReflection { r, fresnel });
    out.push_nonzero(op * i.refl(kt), |t| Lobe::SpecularTransmission { t, eta });
}

/// pbrt-v3's translucent: diffuse and glossy (index 1.5) reflection and transmission.
fn translucent<const N: usize>(
    i: &Inputs<impl Fn() -> TexCtx>,
    [kd, ks, reflect, transmit]: [TexValue; 4],
    roughness: TexValue,
    remap: RoughnessRemap,
    out: &mut Lobes<N>,
) {
    let (r, t) = (i.refl(reflect), i.refl(transmit));
    let (kd, ks) = (i.refl(kd), i.refl(ks));
    out.push_nonzero(r * kd, Lobe::Lambert);
    out.push_nonzero(t * kd, Lobe::LambertTransmission);
    let a = remap.alpha(i.float(roughness));
    let (dist, eta) = (TrowbridgeReitz::new([a, a]), 1.5);
    let fresnel = Fresnel::Dielectric { eta };
    out.push_nonzero(r * ks, |r| Lobe::MicrofacetReflection { r, dist, fresnel });
    out.push_nonzero(t * ks, |t| Lobe::MicrofacetTransmission { t, dist, eta });
}

/// A coated material's layers at a hit (pbrt-v4's `CoatedDiffuseMaterial::GetBxDF`
/// and `CoatedConductorMaterial::GetBxDF`).
fn coated(c: &Coated, i: &Inputs<impl Fn() -> TexCtx>) -> Layered {
    let alpha = |r: &[TexValue; 2]| i.alpha(r, c.remap);
    let smooth = |a: [f32; 2]| a[0].max(a[1]) < 1e-3;
    let a = alpha(&c.coat_roughness);
    let top = Coat { eta: c.coat_eta, dist: TrowbridgeReitz::new(a), smooth: smooth(a) };
    let conductor = |eta: Rgb, k: Rgb, r: &[TexValue; 2]| {
        let a = alpha(r);
        Base::Conductor { eta: eta / c.coat_eta, k: k / c.coat_eta, dist: TrowbridgeReitz::new(a), smooth: smooth(a) }
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
        albedo: i.rgb(c.albedo).clamp(Vec3::ZERO, Vec3::ONE),
        g: i.float(c.g).clamp(-1.0, 1.0),
        max_depth: c.max_depth,
        n_samples: c.n_samples,
        fixed_weights: i.fixes.has(Fix::LayeredWeights),
    }
}

/// A Lambertian lobe, or none for a black reflectance (pbrt adds no lobe then).
fn lambert(r: Rgb) -> Option<Lobe> {
    (r != Vec3::ZERO).then_some(Lobe::Lambert(r))
}

/// Smooth glass is one Fresnel-weighted lobe; rough glass is pbrt-v3's pair of
/// microfacet reflection and transmission lobes, or pbrt-v4's single lobe.
fn dielectric<const N: usize>(eta: f32, r: Rgb, t: Rgb, alpha: [f32; 2], c: Convention, out: &mut Lobes<N>) {
    if r == Vec3::ZERO && t == Vec3::ZERO {
        return;
    }
    if alpha == [0.0, 0.0] {
        out.push(Lobe::FresnelSpecular { r, t, eta });
        return;
    }
    let dist = TrowbridgeReitz::new(alpha);
    if c == Convention::PbrtV4 {
        out.push(Lobe::RoughDielectric { r, t, dist, eta });
        return;
    }
    out.push_nonzero(r, |r| Lobe::MicrofacetReflection { r, dist, fresnel: Fresnel::Dielectric { eta } });
    out.push_nonzero(t, |t| Lobe::MicrofacetTransmission { t, dist, eta });
}

/// Texture inputs at one hit.
struct Inputs<'a, C: Fn() -> TexCtx> {
    textures: &'a Textures,
    ctx: C,
    max_reflectance: f32,
    fixes: Fixes,
}

impl<C: Fn() -> TexCtx> Inputs<'_, C> {
    /// A reflectance (or transmittance), clamped as the material's version does.
    fn refl(&self, v: TexValue) -> Rgb {
        self.rgb(v).clamp(Vec3::ZERO, Vec3::splat(self.max_reflectance))
    }

    /// `v` times `s`, clamped as a reflectance.
    fn refl_scaled(&self, v: TexValue, s: f32) -> Rgb {
        (s * self.rgb(v)).clamp(Vec3::ZERO, Vec3::splat(self.max_reflectance))
    }

    fn rgb(&self, v: TexValue) -> Rgb {
        match v {
            TexValue::Const(c) => c,
            TexValue::Texture(_) => self.textures.eval(v, &(self.ctx)()),
        }
    }

    fn float(&self, v: TexValue) -> f32 {
        self.rgb(v).x
    }

    fn alpha(&self, roughness: &[TexValue; 2], remap: RoughnessRemap) -> [f32; 2] {
        roughness.map(|r| remap.alpha(self.float(r)))
    }

    /// A conductor's η and k here.
    fn eta_k(&self, metal: &Metal) -> (Rgb, Rgb) {
        match metal {
            Metal::EtaK { eta, k } => (*eta, *k),
            Metal::Reflectance(r) => Metal::eta_k_of_reflectance(self.rgb(*r)),
        }
    }
}

impl RoughnessRemap {
    /// The microfacet α of a roughness as written.
    pub fn alpha(self, r: f32) -> f32 {
        match self {
            RoughnessRemap::None => r.max(0.0),
            RoughnessRemap::V3 => microfacet::roughness_to_alpha_v3(r),
            RoughnessRemap::V4 => r.max(0.0).sqrt(),
        }
    }
}

/// Lobes gathered from the parts of a pbrt-v3 `mix` (at most [`MAX_LOBES`], as
/// pbrt-v3's BSDF holds at most 8).
#[derive(Default)]
pub struct LobeList(Lobes<MAX_LOBES>);

impl LobeList {
    /// Their BSDF, combined as pbrt-v3 combines them.
    pub fn bsdf(&self, frame: [Vec3; 3], ng: Vec3) -> Bsdf {
        Bsdf::new(frame, ng, &self.0.list[..self.0.n], Convention::PbrtV3)
    }
}

/// The most lobes one material makes (uber's five); a list this long is set up for
/// every hit, so it is no longer than that.
const MATERIAL_LOBES: usize = 5;

/// Lobes made at one hit, at most `N`.
struct Lobes<const N: usize> {
    list: [Lobe; N],
    n: usize,
}

impl<const N: usize> Default for Lobes<N> {
    fn default() -> Self {
        Lobes { list: [Lobe::default(); N], n: 0 }
    }
}

impl Default for Lobe {
    fn default() -> Lobe {
        Lobe::Lambert(Vec3::ZERO)
    }
}

impl<const N: usize> Lobes<N> {
    fn push(&mut self, l: Lobe) {
        if self.n < N {
            self.list[self.n] = l;
            self.n += 1;
        }
    }

    /// Adds `make(c)` unless `c` is black (pbrt adds no lobe for a black input).
    fn push_nonzero(&mut self, c: Rgb, make: impl FnOnce(Rgb) -> Lobe) {
        if c != Vec3::ZERO {
            self.push(make(c));
        }
    }
}
