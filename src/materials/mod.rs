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
//! diffuse part (`Kd`/`reflectance`); rough dielectrics render as smooth ones;
//! matte's `sigma` (Oren–Nayar) is ignored.
//!
//! `imagemap` reads EXR or PNG (sRGB-decoded unless `"bool gamma" false` / `"string
//! encoding" "linear"`), looked up bilinearly with t = 0 at the image's bottom row (as
//! pbrt), `wrap` repeat/clamp/black, `scale`, `invert`. An unreadable file is warned
//! about and replaced by 0.5.

mod bsdf;

pub use bsdf::{Bsdf, BsdfSample, BxDF, TransportMode};

use crate::imageio::RgbImage;
use crate::parser::params::{FloatValue, ParamList, ParamType, SpectrumValue};
use crate::scene::{MaterialDesc, TextureDesc};
use crate::spectrum::{Rgb, named_metal, to_rgb};
use glam::Vec3;
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How image lookups treat coordinates outside [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Clamp,
    Black,
}

/// Bilinear lookup at (s, t) with t = 0 at the bottom row unless `top_down`.
pub fn lookup(img: &RgbImage, s: f32, t: f32, wrap: Wrap, top_down: bool) -> Rgb {
    let (w, h) = (img.width as i64, img.height as i64);
    if w == 0 || h == 0 {
        return Vec3::ZERO;
    }
    let y = if top_down { t } else { 1.0 - t };
    let (x, y) = (s * w as f32 - 0.5, y * h as f32 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |xi: i64, yi: i64| -> Rgb {
        let (xi, yi) = match wrap {
            Wrap::Repeat => (xi.rem_euclid(w), yi.rem_euclid(h)),
            Wrap::Clamp => (xi.clamp(0, w - 1), yi.clamp(0, h - 1)),
            Wrap::Black if xi < 0 || yi < 0 || xi >= w || yi >= h => return Vec3::ZERO,
            Wrap::Black => (xi, yi),
        };
        Vec3::from(img.pixels[(yi * w + xi) as usize])
    };
    let (x0, y0) = (x0 as i64, y0 as i64);
    (1.0 - fx) * (1.0 - fy) * texel(x0, y0)
        + fx * (1.0 - fy) * texel(x0 + 1, y0)
        + (1.0 - fx) * fy * texel(x0, y0 + 1)
        + fx * fy * texel(x0 + 1, y0 + 1)
}

/// What building textures needs: where files are, a cache, and warnings to report.
pub struct TextureContext {
    pub base_dir: PathBuf,
    cache: RefCell<HashMap<PathBuf, Option<Arc<RgbImage>>>>,
    pub warnings: RefCell<Vec<String>>,
}

impl TextureContext {
    pub fn new(base_dir: &Path) -> TextureContext {
        TextureContext { base_dir: base_dir.to_path_buf(), cache: RefCell::default(), warnings: RefCell::default() }
    }

    /// An image by scene-relative name, read once; `None` (warned) when unreadable.
    pub fn image(&self, name: &str) -> Option<Arc<RgbImage>> {
        let path = crate::parser::stmt::resolve_relative(&self.base_dir, name);
        self.cache
            .borrow_mut()
            .entry(path.clone())
            .or_insert_with(|| match crate::imageio::read_image(&path) {
                Ok(img) => Some(Arc::new(img)),
                Err(e) => {
                    self.warnings.borrow_mut().push(format!("{e}; using 0.5 instead"));
                    None
                }
            })
            .clone()
    }
}

/// An RGB texture over (u, v).
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Const(Rgb),
    Checker { tex1: Box<Texture>, tex2: Box<Texture>, uscale: f32, vscale: f32, udelta: f32, vdelta: f32 },
    Scale(Box<Texture>, Box<Texture>),
    Mix(Box<Texture>, Box<Texture>, Box<Texture>),
    Image { img: Arc<RgbImage>, map: [f32; 4], wrap: Wrap, scale: f32, invert: bool },
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
            Texture::Image { img, map, wrap, scale, invert } => {
                let (s, t) = (uv[0] * map[0] + map[2], uv[1] * map[1] + map[3]);
                let v = lookup(img, s, t, *wrap, false) * *scale;
                if *invert { (Vec3::ONE - v).max(Vec3::ZERO) } else { v }
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
    /// Microfacet conductor (α along the shading tangents).
    RoughConductor {
        eta: Rgb,
        k: Rgb,
        alpha: [f32; 2],
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
    ctx: &'a TextureContext,
}

impl Lookup<'_> {
    fn texture(&self, name: &str, default: Rgb) -> Texture {
        if let Some((_, t)) = self.textures.iter().find(|(n, _)| n == name) {
            return build_texture(&self.all[*t as usize], self.all, self.ctx);
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
pub fn build_texture(t: &TextureDesc, all: &[TextureDesc], ctx: &TextureContext) -> Texture {
    let l = Lookup { params: &t.params, textures: &t.textures, all, ctx };
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
        "imagemap" => image_texture(p, ctx).unwrap_or(Texture::Const(Vec3::splat(0.5))),
        _ => Texture::Const(Vec3::splat(0.5)),
    }
}

fn image_texture(p: &ParamList, ctx: &TextureContext) -> Option<Texture> {
    let name = p.string("filename").ok().flatten()?;
    let mut img = ctx.image(&name)?;
    let is_png = name.to_ascii_lowercase().ends_with(".png");
    let linear = p.bool("gamma").ok().flatten() == Some(false)
        || p.string("encoding").ok().flatten().is_some_and(|e| e == "linear");
    if is_png && linear {
        // read_png decodes sRGB; this texture wants the stored values as they are.
        let mut raw = (*img).clone();
        raw.pixels.iter_mut().for_each(|px| *px = px.map(crate::imageio::to_srgb));
        img = Arc::new(raw);
    }
    let f = |name: &str, d: f32| p.float(name).ok().flatten().unwrap_or(d);
    let wrap = match p.string("wrap").ok().flatten().as_deref() {
        Some("clamp") => Wrap::Clamp,
        Some("black") => Wrap::Black,
        _ => Wrap::Repeat,
    };
    Some(Texture::Image {
        img,
        map: [f("uscale", 1.0), f("vscale", 1.0), f("udelta", 0.0), f("vdelta", 0.0)],
        wrap,
        scale: f("scale", 1.0),
        invert: p.bool("invert").ok().flatten().unwrap_or(false),
    })
}

impl Material {
    pub fn from_desc(m: &MaterialDesc, textures: &[TextureDesc], ctx: &TextureContext) -> Material {
        let l = Lookup { params: &m.params, textures: &m.textures, all: textures, ctx };
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
                let (eta, k) = (spec("eta", "metal-Cu-eta"), spec("k", "metal-Cu-k"));
                // v3 metal: roughness 0.01, remapped by pbrt-v3's polynomial; v4
                // conductor: roughness 0, remapped by √r.
                let v3 = m.ty == "metal";
                let r = l.float("roughness", if v3 { 0.01 } else { 0.0 });
                let (ur, vr) = (l.float("uroughness", r), l.float("vroughness", r));
                let remap = m.params.bool("remaproughness").ok().flatten().unwrap_or(true);
                let to_alpha = |r: f32| match (remap, v3) {
                    (false, _) => r,
                    (true, true) => bsdf::roughness_to_alpha_v3(r),
                    (true, false) => r.max(0.0).sqrt(),
                };
                let alpha = [to_alpha(ur), to_alpha(vr)];
                if alpha[0] < 1e-3 && alpha[1] < 1e-3 {
                    Material::Conductor { eta, k }
                } else {
                    Material::RoughConductor { eta, k, alpha: alpha.map(|a| a.max(1e-3)) }
                }
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
            Material::RoughConductor { eta, k, alpha } => BxDF::RoughConductor { eta: *eta, k: *k, alpha: *alpha },
            Material::ConductorReflectance { r } => BxDF::Specular(r.eval(uv)),
            Material::Interface => return None,
        };
        Some(Bsdf::new(frame, ng, bxdf))
    }
}
