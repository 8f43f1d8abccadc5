//! Materials, one module per type, each owning its parameters (names, defaults per
//! version, located errors), the lobes it makes at a hit, and its Mitsuba export;
//! [`REGISTRY`] is the one list of `Material` types. Textures ([`Textures`]) are
//! evaluated at each hit; [`Bsdf`] combines the lobes as pbrt's `BSDF` does.
//!
//! ```text
//! Material "matte" "rgb Kd" [.5 .5 .5]        Material "diffuse" "texture reflectance" "checks"
//! Material "glass" "float index" 1.5          Material "dielectric" "float eta" 1.5
//! Material "metal" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k" "float roughness" .1
//! Material "plastic" "rgb Kd" [.4 .1 .1]      Material "coateddiffuse" "float roughness" .05
//! Material "mix" "string materials" ["a" "b"] "float amount" .3
//! ```
//! pbrt-v3's material types build their BSDFs by pbrt-v3's rules (reflectances clamped
//! only below 0, the geometric normal deciding reflection or transmission), pbrt-v4's
//! by pbrt-v4's. A type we do not render is drawn as grey diffuse, noted as an
//! approximation at its statement.
//!
//! Adding a material type: a module here with its name(s), `read`, `lobes` and
//! `mitsuba`; a variant in [`MaterialKind`]; a line in [`REGISTRY`]; then the compiler
//! lists the `match`es to extend ([`Material`]'s lobes, [`MaterialDesc::mitsuba`]).

mod bsdf;
pub mod bssrdf;
pub mod coated;
pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod diffusetransmission;
pub mod disney;
pub mod disneybsdf;
pub mod disneybssrdf;
pub mod fibre;
pub mod fourier;
pub mod fourierbsdf;
pub mod hair;
pub mod inputs;
pub mod interface;
pub mod layered;
pub mod lobes;
pub mod matte;
pub mod measured;
pub mod measuredbsdf;
pub mod microfacet;
pub mod mirror;
pub mod mix;
pub mod params;
pub mod plastic;
pub mod shared;
pub mod substrate;
pub mod subsurface;
pub mod thindielectric;
pub mod translucent;
mod transport;
pub mod uber;

pub use crate::textures::{TexCtx, Textures};
pub use bsdf::{Bsdf, BsdfEval, BsdfSample, Convention, KeptBsdf};
pub use coated::{CoatBase, Coated};
pub use inputs::LobeList;
pub use mix::MixRule;
pub use params::{Metal, Resolver, RoughnessRemap, TexValue};
pub use transport::TransportMode;

use crate::fixes::Fixes;
use crate::imageio::Texels;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::Syntax;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::spectrum::transport::PassSpectrum;
use crate::values::Res;
use glam::Vec3;
use inputs::{Inputs, Lobes, MATERIAL_LOBES, lambert};
use std::sync::Arc;

/// A `Material` type: the name scenes use, the pbrt version it belongs to (`None`:
/// both), and its reader.
pub struct MaterialType {
    pub name: &'static str,
    pub syntax: Option<Syntax>,
    pub read: fn(&str, &ParamList, Span, &mut dyn Resolver) -> Res<MaterialKind>,
}

const fn ty(
    name: &'static str,
    syntax: Option<Syntax>,
    read: fn(&str, &ParamList, Span, &mut dyn Resolver) -> Res<MaterialKind>,
) -> MaterialType {
    MaterialType { name, syntax, read }
}

const V3: Option<Syntax> = Some(Syntax::V3);
const V4: Option<Syntax> = Some(Syntax::V4);

/// Every `Material` type we render.
pub const REGISTRY: [MaterialType; 25] = [
    ty(matte::NAME, V3, matte::read),
    ty(diffuse::NAME, V4, diffuse::read),
    ty(mirror::NAME, V3, mirror::read),
    ty(dielectric::NAMES[0], V3, dielectric::read),
    ty(dielectric::NAMES[1], V4, dielectric::read),
    ty(thindielectric::NAME, V4, thindielectric::read),
    ty(conductor::NAMES[0], V3, conductor::read),
    ty(conductor::NAMES[1], V4, conductor::read),
    ty(plastic::NAME, V3, plastic::read),
    ty(uber::NAME, V3, uber::read),
    ty(translucent::NAME, V3, translucent::read),
    ty(substrate::NAME, V3, substrate::read),
    ty(disney::NAME, V3, disney::read),
    ty(coated::NAMES[0], V4, coated::read),
    ty(coated::NAMES[1], V4, coated::read),
    ty(diffusetransmission::NAME, V4, diffusetransmission::read),
    ty(interface::NAMES[0], V4, interface::read),
    ty(interface::NAMES[1], V3, interface::read),
    ty(interface::NAMES[2], V3, interface::read),
    ty(mix::NAME, None, mix::read),
    ty(hair::NAME, None, hair::read),
    ty(fourier::NAME, V3, fourier::read),
    ty(measured::NAME, V4, measured::read),
    ty(subsurface::NAMES[0], None, subsurface::read),
    ty(subsurface::NAMES[1], V3, subsurface::read),
];

/// The pbrt version a material type name proves, for syntax detection.
pub fn evidence(ty: &str) -> Option<Syntax> {
    REGISTRY.iter().find(|t| t.name == ty).and_then(|t| t.syntax)
}

/// The material of type `ty`, which the scene has checked is one pbrt knows (every one
/// of them is registered: a test holds the two lists together).
pub fn read(ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    match REGISTRY.iter().find(|t| t.name == ty) {
        Some(t) => (t.read)(ty, p, at, r),
        None => Err(crate::parser::error::Diagnostic::error(at, format!("material type \"{ty}\" is not supported"))),
    }
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
    /// `subsurface`, v3 `kdsubsurface`: a dielectric boundary over a BSSRDF.
    Subsurface(Box<subsurface::Subsurface>),
    /// v3 `fourier`: a tabulated BSDF file.
    Fourier {
        table: fourierbsdf::Table,
    },
    /// pbrt-v4 `measured`: an RGL tensor file's BRDF.
    Measured {
        table: measuredbsdf::Table,
    },
    /// A perfect mirror tinted by `reflectance` (`mirror`).
    Mirror {
        reflectance: TexValue,
    },
    /// A dielectric; smooth when both roughnesses are 0.
    Dielectric {
        eta: TexValue,
        /// The index by wavelength where pbrt-v4's `"spectrum eta"` gives it: spectral
        /// paths disperse through it; RGB ones take `eta`, its luminance-weighted mean.
        dispersion: Option<dielectric::Dispersion>,
        kr: TexValue,
        kt: TexValue,
        roughness: [TexValue; 2],
        remap: RoughnessRemap,
    },
    /// pbrt-v4 `thindielectric`: a pane that reflects or passes light straight on.
    ThinDielectric {
        eta: TexValue,
        dispersion: Option<dielectric::Dispersion>,
    },
    /// A conductor; smooth when both roughnesses give α below 10⁻³.
    Conductor {
        metal: Metal,
        roughness: [TexValue; 2],
        remap: RoughnessRemap,
    },
    /// pbrt-v4 `coateddiffuse` / `coatedconductor`: a dielectric coat over a base.
    Coated(Box<Coated>),
    /// pbrt-v3's Disney BSDF (`disney`).
    Disney(Box<disney::Disney>),
    /// pbrt's hair fibre (`hair`).
    Hair(Box<hair::Hair>),
    /// No surface: rays continue straight through.
    Interface,
    /// Two materials (built indices) mixed by `amount`.
    Mix {
        materials: [u32; 2],
        amount: TexValue,
        rule: MixRule,
    },
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
    pub normal_map: Option<Arc<Texels>>,
}

impl MaterialKind {
    /// Whether light that crosses this material's boundary may enter a BSSRDF: always
    /// for `subsurface`, for `disney` where a `scatterdistance` is given.
    pub fn may_have_bssrdf(&self) -> bool {
        match self {
            MaterialKind::Subsurface(_) => true,
            MaterialKind::Disney(d) => d.may_scatter_below(),
            _ => false,
        }
    }

    /// Whether its index varies with the wavelength (a glass or coat whose `eta` is a
    /// spectrum).
    pub fn disperses(&self) -> bool {
        match self {
            MaterialKind::Dielectric { dispersion, .. } | MaterialKind::ThinDielectric { dispersion, .. } => {
                dispersion.is_some()
            }
            MaterialKind::Coated(c) => c.coat_dispersion.is_some(),
            _ => false,
        }
    }
}

impl MaterialDesc {
    /// The material for Mitsuba 3 (the nearest BSDF; what differs is noted).
    pub fn mitsuba(&self, e: &mut dyn MaterialExport) -> MaterialOut {
        match &self.kind {
            MaterialKind::Diffuse { reflectance } => diffuse::mitsuba(*reflectance, e),
            MaterialKind::OrenNayar { reflectance, .. } => matte::mitsuba(*reflectance, e),
            MaterialKind::Mirror { reflectance } => mirror::mitsuba(*reflectance, e),
            MaterialKind::Dielectric { eta, kr, kt, roughness, .. } => {
                dielectric::mitsuba([*eta, *kr, *kt], roughness, e)
            }
            MaterialKind::ThinDielectric { eta, .. } => thindielectric::mitsuba(*eta, e),
            MaterialKind::Conductor { metal, roughness, remap } => conductor::mitsuba(metal, roughness, *remap, e),
            MaterialKind::Plastic { kd, .. } => plastic::mitsuba(*kd, e),
            MaterialKind::Uber { kd, .. } => uber::mitsuba(*kd, e),
            MaterialKind::Translucent { kd, .. } => translucent::mitsuba(*kd, e),
            MaterialKind::Substrate { kd, .. } => substrate::mitsuba(*kd, e),
            MaterialKind::DiffuseTransmission { reflectance, .. } => diffusetransmission::mitsuba(*reflectance, e),
            MaterialKind::Coated(c) => coated::mitsuba(c, e),
            MaterialKind::Hair(_) => hair::mitsuba(e),
            MaterialKind::Disney(d) => disney::mitsuba(d, e),
            MaterialKind::Fourier { .. } => fourier::mitsuba(e),
            MaterialKind::Measured { .. } => measured::mitsuba(e),
            MaterialKind::Subsurface(s) => subsurface::mitsuba(s, e),
            MaterialKind::Interface => interface::mitsuba(),
            MaterialKind::Mix { .. } => mix::mitsuba(e),
        }
    }
}

/// Where a material is shaded: the scene's textures, the hit's texture context (made
/// only when a textured input asks) and the pass's wavelengths when spectral.
pub struct Shading<'a, C: Fn() -> TexCtx> {
    pub textures: &'a Textures,
    pub ctx: C,
    pub spectral: Option<PassSpectrum>,
}

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
    pub normal_map: Option<Arc<Texels>>,
    /// The pbrt bugs fixed (`--fix`).
    fixes: Fixes,
    /// Light subpaths meet camera paths (vcm, bdpt): hair takes its adjoint for them.
    bidirectional: bool,
}

impl Material {
    pub fn from_desc(m: &MaterialDesc, fixes: Fixes) -> Material {
        let v3 = REGISTRY.iter().any(|t| t.name == m.ty && t.syntax == V3)
            || matches!(&m.kind, MaterialKind::Subsurface(s) if !s.v4);
        let (max_reflectance, convention) =
            if v3 { (f32::INFINITY, Convention::PbrtV3) } else { (1.0, Convention::PbrtV4) };
        let normal_map = m.normal_map.clone();
        Material {
            kind: m.kind.clone(),
            max_reflectance,
            convention,
            bump: m.bump,
            normal_map,
            fixes,
            bidirectional: false,
        }
    }

    /// The material for vcm and bdpt, whose light and camera paths meet.
    pub fn bidirectional(self) -> Material {
        Material { bidirectional: true, ..self }
    }

    pub fn kind(&self) -> &MaterialKind {
        &self.kind
    }

    /// The BSDF at a hit (`None` for interfaces); `ctx` says where textured inputs are
    /// looked up (made only when one is).
    #[inline]
    pub fn bsdf(&self, at: Shading<'_, impl Fn() -> TexCtx>, frame: [Vec3; 3], ng: Vec3) -> Option<Bsdf> {
        let inputs = self.inputs(at);
        if let MaterialKind::Diffuse { reflectance } = &self.kind {
            // The common case, without the lobe list's set-up.
            let lambert = lambert(inputs.refl(*reflectance));
            return Some(Bsdf::new(frame, ng, lambert.as_slice(), self.convention));
        }
        self.layered_bsdf(&inputs, frame, ng)
    }

    #[inline(never)]
    fn layered_bsdf(&self, inputs: &Inputs<impl Fn() -> TexCtx>, frame: [Vec3; 3], ng: Vec3) -> Option<Bsdf> {
        match &self.kind {
            MaterialKind::Coated(c) => return Some(Bsdf::layered(frame, coated::layers(c, inputs))),
            MaterialKind::Hair(h) => {
                let fibre = hair::bxdf(h, inputs, (inputs.ctx)().uv[1]).with_adjoint(self.bidirectional);
                return Some(Bsdf::hair(frame, fibre));
            }
            MaterialKind::Disney(d) => {
                // Up to eight lobes: more than the list every hit sets up.
                let mut lobes = Lobes::<{ lobes::MAX_LOBES }>::default();
                disney::lobes(d, inputs, &mut lobes);
                return Some(Bsdf::new(frame, ng, &lobes.list[..lobes.n], self.convention));
            }
            _ => {}
        }
        let mut lobes = Lobes::<MATERIAL_LOBES>::default();
        self.lobes(inputs, &mut lobes)?;
        Some(Bsdf::new(frame, ng, &lobes.list[..lobes.n], self.convention))
    }

    /// Appends this material's lobes at a hit, each scaled by `weight` (a v3 `mix`
    /// part); interfaces and mixes add none.
    pub fn add_lobes(&self, at: Shading<'_, impl Fn() -> TexCtx>, weight: Rgb, out: &mut LobeList) {
        let inputs = self.inputs(at);
        let start = out.0.n;
        if self.lobes(&inputs, &mut out.0).is_some() {
            out.0.list[start..out.0.n].iter_mut().for_each(|l| *l = l.scaled(weight));
        }
    }

    /// The BSSRDF profile at a hit and the boundary's index, for a `subsurface`
    /// material, or a `disney` one with a `scatterdistance` (`None` elsewhere).
    pub fn bssrdf(&self, at: Shading<'_, impl Fn() -> TexCtx>) -> Option<(bssrdf::Profile, f32)> {
        match &self.kind {
            MaterialKind::Subsurface(s) => Some((subsurface::profile(s, &self.inputs(at)), s.eta)),
            MaterialKind::Disney(d) => disney::bssrdf(d, &self.inputs(at)),
            _ => None,
        }
    }

    fn inputs<'t, C: Fn() -> TexCtx>(&self, at: Shading<'t, C>) -> Inputs<'t, C> {
        let (max_reflectance, fixes) = (self.max_reflectance, self.fixes);
        Inputs { textures: at.textures, ctx: at.ctx, max_reflectance, fixes, spectral: at.spectral }
    }

    /// Whether the BSDF here bends each wavelength its own way, so that a spectral path
    /// keeps only its first (a `mix` counts if either part does).
    pub fn disperses(&self, all: &[Material]) -> bool {
        match &self.kind {
            MaterialKind::Mix { materials, .. } => {
                materials.iter().any(|&m| all.get(m as usize).is_some_and(|m| m.kind.disperses()))
            }
            kind => kind.disperses(),
        }
    }

    /// The lobes of this material at a hit, by its type's module.
    fn lobes<const N: usize>(&self, i: &Inputs<impl Fn() -> TexCtx>, out: &mut Lobes<N>) -> Option<()> {
        match &self.kind {
            MaterialKind::Diffuse { reflectance } => diffuse::lobes(*reflectance, i, out),
            MaterialKind::OrenNayar { reflectance, sigma } => matte::lobes(*reflectance, *sigma, i, out),
            MaterialKind::DiffuseTransmission { reflectance, transmittance, scale } => {
                diffusetransmission::lobes([*reflectance, *transmittance, *scale], i, out)
            }
            MaterialKind::Coated(c) => coated::base_lobes(c, i, out),
            MaterialKind::Fourier { table } => out.push(fourier::lobe(*table)),
            MaterialKind::Disney(d) => disney::lobes(d, i, out),
            MaterialKind::Measured { table } => out.push(measured::lobe(*table, i)),
            MaterialKind::Subsurface(s) => subsurface::lobes(s, self.convention, i, out),
            MaterialKind::Mirror { reflectance } => mirror::lobes(*reflectance, i, out),
            MaterialKind::Dielectric { eta, dispersion, kr, kt, roughness, remap } => {
                let eta = dielectric::Eta { mean: *eta, dispersion: dispersion.as_ref() };
                dielectric::lobes(eta, [*kr, *kt], roughness, *remap, self.convention, i, out)
            }
            MaterialKind::ThinDielectric { eta, dispersion } => {
                thindielectric::lobes(*eta, dispersion.as_ref(), i, out)
            }
            MaterialKind::Conductor { metal, roughness, remap } => conductor::lobes(metal, roughness, *remap, i, out),
            MaterialKind::Plastic { kd, ks, roughness, remap } => {
                plastic::lobes([*kd, *ks], *roughness, *remap, i, out)
            }
            MaterialKind::Uber { kd, ks, kr, kt, roughness, eta, opacity, remap } => {
                uber::lobes([*kd, *ks, *kr, *kt, *eta, *opacity], roughness, *remap, i, out)
            }
            MaterialKind::Translucent { kd, ks, reflect, transmit, roughness, remap } => {
                translucent::lobes([*kd, *ks, *reflect, *transmit], *roughness, *remap, i, out)
            }
            MaterialKind::Substrate { kd, ks, roughness, remap } => {
                substrate::lobes([*kd, *ks], roughness, *remap, i, out)
            }
            // Mixes are resolved by the scene, which holds their materials; a fibre is
            // not a sum of lobes.
            MaterialKind::Interface | MaterialKind::Mix { .. } | MaterialKind::Hair(_) => return None,
        }
        Some(())
    }
}
