//! Materials and textures (RGB) and the BSDFs they produce at a hit.
//!
//! ```text
//! Material "matte" "rgb Kd" [.5 .5 .5]        Material "diffuse" "texture reflectance" "checks"
//! Material "glass" "float index" 1.5          Material "metal" "spectrum eta" "metal-Au-eta"
//! Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "rgb tex1" [1 0 0]
//! ```
//! Every parameter is settled by the scene description (`scene::materials`); this module
//! turns typed materials into BSDFs. Textures live in one array and refer to each other
//! by index, so shared definitions are stored once. `imagemap` lookups are bilinear with
//! t = 0 at the image's bottom row (as pbrt), `wrap` repeat/clamp/black, `scale`,
//! `invert`.

mod bsdf;

pub use bsdf::{Bsdf, BsdfSample, BxDF, TransportMode};

use crate::imageio::RgbImage;
use crate::scene::{MaterialDesc, MaterialKind, RoughnessRemap, TexValue, TextureDesc, TextureKind, UvMapping, Wrap};
use crate::spectrum::Rgb;
use glam::Vec3;
use std::sync::Arc;

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

/// An RGB texture over (u, v); inputs refer to other textures by index.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Const(Rgb),
    Checker { tex1: TexValue, tex2: TexValue, map: UvMapping },
    Scale(TexValue, TexValue),
    Mix(TexValue, TexValue, TexValue),
    Image { img: Arc<RgbImage>, map: UvMapping, wrap: Wrap, scale: f32, invert: bool },
}

/// Every texture of a scene, by the indices [`TexValue::Texture`] names.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Textures(pub Vec<Texture>);

impl Textures {
    pub fn new(descs: &[TextureDesc]) -> Textures {
        Textures(descs.iter().map(|t| Texture::from_kind(&t.kind)).collect())
    }

    pub fn eval(&self, v: TexValue, uv: [f32; 2]) -> Rgb {
        match v {
            TexValue::Const(c) => c,
            TexValue::Texture(t) => self.0.get(t as usize).map_or(Vec3::ZERO, |t| t.eval(self, uv)),
        }
    }
}

impl Texture {
    fn from_kind(k: &TextureKind) -> Texture {
        match k {
            TextureKind::Constant(TexValue::Const(c)) => Texture::Const(*c),
            TextureKind::Constant(v) => Texture::Scale(*v, TexValue::Const(Vec3::ONE)),
            TextureKind::Checkerboard { tex1, tex2, map } => Texture::Checker { tex1: *tex1, tex2: *tex2, map: *map },
            TextureKind::Scale { tex, scale } => Texture::Scale(*tex, *scale),
            TextureKind::Mix { tex1, tex2, amount } => Texture::Mix(*tex1, *tex2, *amount),
            TextureKind::Image { image, map, wrap, scale, invert } => {
                Texture::Image { img: image.clone(), map: *map, wrap: *wrap, scale: *scale, invert: *invert }
            }
        }
    }

    pub fn eval(&self, all: &Textures, uv: [f32; 2]) -> Rgb {
        let st = |m: &UvMapping| (uv[0] * m.su + m.du, uv[1] * m.sv + m.dv);
        match self {
            Texture::Const(c) => *c,
            Texture::Checker { tex1, tex2, map } => {
                let (s, t) = st(map);
                if (s.floor() as i64 + t.floor() as i64) % 2 == 0 { all.eval(*tex1, uv) } else { all.eval(*tex2, uv) }
            }
            Texture::Scale(a, b) => all.eval(*a, uv) * all.eval(*b, uv),
            Texture::Mix(a, b, t) => {
                let t = all.eval(*t, uv);
                all.eval(*a, uv) * (Vec3::ONE - t) + all.eval(*b, uv) * t
            }
            Texture::Image { img, map, wrap, scale, invert } => {
                let (s, t) = st(map);
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
        kd: TexValue,
    },
    /// A perfect mirror tinted by `kr`.
    Mirror {
        kr: TexValue,
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
    /// No surface: rays continue straight through.
    Interface,
}

/// The (u, v) where inputs that can only be constant take a texture's value.
const CENTRE: [f32; 2] = [0.5, 0.5];

impl Material {
    pub fn from_desc(m: &MaterialDesc, textures: &Textures) -> Material {
        let at_centre = |v: TexValue| textures.eval(v, CENTRE);
        match &m.kind {
            MaterialKind::Diffuse { reflectance } => Material::Diffuse { kd: *reflectance },
            MaterialKind::Mirror { reflectance } => Material::Mirror { kr: *reflectance },
            MaterialKind::Dielectric { eta, kr, kt } => {
                Material::Dielectric { eta: at_centre(*eta).x, kr: at_centre(*kr), kt: at_centre(*kt) }
            }
            MaterialKind::Conductor { eta, k, roughness, remap } => {
                let to_alpha = |r: f32| match remap {
                    RoughnessRemap::None => r,
                    RoughnessRemap::V3 => bsdf::roughness_to_alpha_v3(r),
                    RoughnessRemap::V4 => r.max(0.0).sqrt(),
                };
                let alpha = roughness.map(|r| to_alpha(at_centre(r).x));
                if alpha[0] < 1e-3 && alpha[1] < 1e-3 {
                    Material::Conductor { eta: *eta, k: *k }
                } else {
                    Material::RoughConductor { eta: *eta, k: *k, alpha: alpha.map(|a| a.max(1e-3)) }
                }
            }
            MaterialKind::Interface => Material::Interface,
        }
    }

    /// The BSDF at a hit (`None` for interfaces).
    pub fn bsdf(&self, textures: &Textures, uv: [f32; 2], frame: [Vec3; 3], ng: Vec3) -> Option<Bsdf> {
        let bxdf = match self {
            Material::Diffuse { kd } => BxDF::Lambert(textures.eval(*kd, uv).clamp(Vec3::ZERO, Vec3::ONE)),
            Material::Mirror { kr } => BxDF::Specular(textures.eval(*kr, uv)),
            Material::Dielectric { eta, kr, kt } => BxDF::Dielectric { eta: *eta, kr: *kr, kt: *kt },
            Material::Conductor { eta, k } => BxDF::Conductor { eta: *eta, k: *k },
            Material::RoughConductor { eta, k, alpha } => BxDF::RoughConductor { eta: *eta, k: *k, alpha: *alpha },
            Material::Interface => return None,
        };
        Some(Bsdf::new(frame, ng, bxdf))
    }
}
