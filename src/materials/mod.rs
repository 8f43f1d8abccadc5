//! Materials and textures (RGB) and the BSDFs they produce at a hit.
//!
//! ```text
//! Material "matte" "rgb Kd" [.5 .5 .5]        Material "diffuse" "texture reflectance" "checks"
//! Material "mirror" "rgb Kr" [.9 .9 .9]
//! Material "glass" "float index" 1.5          Material "dielectric" "float eta" 1.5
//! Material "metal" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
//! Material "conductor" "rgb reflectance" [.9 .6 .3]
//! Material "plastic" / "coateddiffuse" / "uber"     # their diffuse part (see below)
//! Material "" / "none" / "interface"                # no surface: paths pass through
//! Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "rgb tex1" [1 0 0]
//! Texture "s" "spectrum" "scale" "texture tex" "checks" "float scale" 0.5
//! Texture "m" "spectrum" "mix" "rgb tex1" [1 1 1] "texture tex2" "checks" "float amount" 0.3
//! ```
//! Approximations, listed in the README: plastic, coated diffuse and uber render as their
//! diffuse part (`Kd`/`reflectance`); rough dielectrics and metals render as smooth ones;
//! matte's `sigma` (Oren–Nayar) is ignored; image textures are not read yet (they use
//! their average, 0.5).

mod bsdf;

pub use bsdf::{Bsdf, BsdfSample, BxDF, TransportMode};

use crate::parser::params::{FloatValue, ParamList, ParamType, SpectrumValue};
use crate::scene::{MaterialDesc, TextureDesc};
use crate::spectrum::{Rgb, named_metal, to_rgb};
use glam::Vec3;

/// An RGB texture over (u, v).
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Const(Rgb),
    Checker { tex1: Box<Texture>, tex2: Box<Texture>, uscale: f32, vscale: f32, udelta: f32, vdelta: f32 },
    Scale(Box<Texture>, Box<Texture>),
    Mix(Box<Texture>, Box<Texture>, Box<Texture>),
}

impl Texture {
    pub fn eval(&self, uv: [f32; 2]) -> Rgb {
        match self {
            Texture::Const(c) => *c,
            Texture::Checker { tex1, tex2, uscale, vscale, udelta, vdelta } => {
                let (s, t) = (uv[0] * uscale + udelta, uv[1] * vscale + vdelta);
                if (s.floor() as i64 + t.floor() as i64) % 2 == 0 { tex1.eval(uv) } else { tex2.eval(uv) }
            }
            Texture::Scale(a, b) => a.eval(uv) * b.eval(uv),
            Texture::Mix(a, b, t) => {
                let t = t.eval(uv);
                a.eval(uv) * (Vec3::ONE - t) + b.eval(uv) * t
            }
        }
    }
}

/// A material ready to shade.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    Diffuse {
        kd: Texture,
    },
    Mirror {
        kr: Texture,
    },
    Dielectric {
        eta: f32,
        kr: Rgb,
        kt: Rgb,
    },
    Conductor {
        eta: Rgb,
        k: Rgb,
    },
    /// A reflectance given directly (`conductor "reflectance"`): a tinted mirror.
    ConductorReflectance {
        r: Texture,
    },
    /// No surface: rays continue straight through.
    Interface,
}

/// Looks up spectrum- or float-valued parameters, following texture references.
struct Lookup<'a> {
    params: &'a ParamList,
    textures: &'a [(String, u32)],
    all: &'a [TextureDesc],
}

impl Lookup<'_> {
    fn texture(&self, name: &str, default: Rgb) -> Texture {
        if let Some((_, t)) = self.textures.iter().find(|(n, _)| n == name) {
            return build_texture(&self.all[*t as usize], self.all);
        }
        match self.params.spectrum(name).ok().flatten() {
            Some(v) => Texture::Const(to_rgb(&v).unwrap_or(default)),
            None => match self.params.float(name).ok().flatten() {
                Some(f) => Texture::Const(Vec3::splat(f)),
                None => Texture::Const(default),
            },
        }
    }

    fn rgb(&self, name: &str, default: Rgb) -> Rgb {
        match self.texture(name, default) {
            Texture::Const(c) => c,
            t => t.eval([0.5, 0.5]),
        }
    }

    fn float(&self, name: &str, default: f32) -> f32 {
        match self.params.float_or_texture(name).ok().flatten() {
            Some(FloatValue::Const(v)) => v,
            _ => match self.params.spectrum(name).ok().flatten().and_then(|s| to_rgb(&s)) {
                Some(c) => c.x.max(c.y).max(c.z),
                None => default,
            },
        }
    }
}

/// Builds a texture description (and the textures it refers to).
pub fn build_texture(t: &TextureDesc, all: &[TextureDesc]) -> Texture {
    let l = Lookup { params: &t.params, textures: &t.textures, all };
    let p = &t.params;
    let f = |name: &str, d: f32| p.float(name).ok().flatten().unwrap_or(d);
    match t.class.as_str() {
        "constant" => l.texture("value", Vec3::ONE),
        "checkerboard" => Texture::Checker {
            tex1: Box::new(l.texture("tex1", Vec3::ONE)),
            tex2: Box::new(l.texture("tex2", Vec3::ZERO)),
            uscale: f("uscale", 1.0),
            vscale: f("vscale", 1.0),
            udelta: f("udelta", 0.0),
            vdelta: f("vdelta", 0.0),
        },
        // v3: tex1 × tex2; v4: tex × scale.
        "scale" => {
            let a = if p.named("tex").is_some() { l.texture("tex", Vec3::ONE) } else { l.texture("tex1", Vec3::ONE) };
            let b =
                if p.named("scale").is_some() { l.texture("scale", Vec3::ONE) } else { l.texture("tex2", Vec3::ONE) };
            Texture::Scale(Box::new(a), Box::new(b))
        }
        "mix" => Texture::Mix(
            Box::new(l.texture("tex1", Vec3::ZERO)),
            Box::new(l.texture("tex2", Vec3::ONE)),
            Box::new(l.texture("amount", Vec3::splat(0.5))),
        ),
        _ => Texture::Const(Vec3::splat(0.5)), // imagemap: not read yet
    }
}

impl Material {
    pub fn from_desc(m: &MaterialDesc, textures: &[TextureDesc]) -> Material {
        let l = Lookup { params: &m.params, textures: &m.textures, all: textures };
        let half = Vec3::splat(0.5);
        match m.ty.as_str() {
            "matte" => Material::Diffuse { kd: l.texture("Kd", half) },
            "diffuse" | "coateddiffuse" => Material::Diffuse { kd: l.texture("reflectance", half) },
            "plastic" | "uber" => Material::Diffuse { kd: l.texture("Kd", Vec3::splat(0.25)) },
            "mirror" => Material::Mirror { kr: l.texture("Kr", Vec3::splat(0.9)) },
            "glass" => {
                let eta = if m.params.named("eta").is_some() { l.float("eta", 1.5) } else { l.float("index", 1.5) };
                Material::Dielectric { eta, kr: l.rgb("Kr", Vec3::ONE), kt: l.rgb("Kt", Vec3::ONE) }
            }
            "dielectric" => Material::Dielectric { eta: l.float("eta", 1.5), kr: Vec3::ONE, kt: Vec3::ONE },
            "metal" | "conductor"
                if m.params
                    .find("reflectance", &[ParamType::Rgb, ParamType::Spectrum, ParamType::Texture])
                    .is_some() =>
            {
                Material::ConductorReflectance { r: l.texture("reflectance", Vec3::ONE) }
            }
            "metal" | "conductor" => {
                let named = |n: &str| named_metal(n).unwrap_or(Vec3::ONE);
                let spec = |name: &str, d: &str| match m.params.spectrum(name).ok().flatten() {
                    Some(SpectrumValue::Named(n)) => named(&n),
                    Some(v) => to_rgb(&v).unwrap_or_else(|| named(d)),
                    None => named(d),
                };
                Material::Conductor { eta: spec("eta", "metal-Cu-eta"), k: spec("k", "metal-Cu-k") }
            }
            "" | "none" | "interface" => Material::Interface,
            _ => Material::Diffuse { kd: Texture::Const(half) },
        }
    }

    /// The BSDF at a hit (`None` for interfaces).
    pub fn bsdf(&self, uv: [f32; 2], frame: [Vec3; 3], ng: Vec3) -> Option<Bsdf> {
        let bxdf = match self {
            Material::Diffuse { kd } => BxDF::Lambert(kd.eval(uv).clamp(Vec3::ZERO, Vec3::ONE)),
            Material::Mirror { kr } => BxDF::Specular(kr.eval(uv)),
            Material::Dielectric { eta, kr, kt } => BxDF::Dielectric { eta: *eta, kr: *kr, kt: *kt },
            Material::Conductor { eta, k } => BxDF::Conductor { eta: *eta, k: *k },
            Material::ConductorReflectance { r } => BxDF::Specular(r.eval(uv)),
            Material::Interface => return None,
        };
        Some(Bsdf::new(frame, ng, bxdf))
    }
}
