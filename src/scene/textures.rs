//! `Texture` statements to typed descriptions.
//!
//! ```text
//! Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "rgb tex1" [1 0 0]
//! Texture "c3" "float" "checkerboard" "integer dimension" 3        # in texture space
//! Texture "s" "spectrum" "scale" "texture tex" "checks" "float scale" 0.5      # v3: tex1 × tex2
//! Texture "m" "spectrum" "mix" "rgb tex1" [1 1 1] "texture tex2" "checks" "float amount" 0.3
//! Texture "d" "spectrum" "directionmix" "vector3 dir" [0 0 1] "texture tex1" "checks"
//! Texture "b" "float" "bilerp" "float v00" 0 "float v01" 1 "float v10" 0 "float v11" 1
//! Texture "img" "spectrum" "imagemap" "string filename" "wood.png" "string wrap" "clamp"
//! Texture "a" "float" "dots" "float inside" 1 "float outside" 0 "float uscale" 10  # dots 0, as pbrt
//! Texture "n" "float" "fbm" "integer octaves" 8 "float roughness" .5   # also wrinkled, windy
//! Texture "m" "spectrum" "marble" "float scale" 4 "float variation" .2
//! Texture "u" "spectrum" "uv" "string mapping" "spherical"
//! ```
//! 2D textures map the hit through `"string mapping"`: `uv` (`uscale`, `vscale`,
//! `udelta`, `vdelta`), `spherical`, `cylindrical` or `planar` (`vector v1`, `v2`,
//! `udelta`, `vdelta`), the last three in the space the CTM at the `Texture` statement
//! defines. 3D textures (`fbm`, `wrinkled`, `windy`, `marble`, 3D `checkerboard`) take
//! the hit point to texture space as each version does:
//! - pbrt-v4: by the inverse of the CTM;
//! - pbrt-v3: by the CTM itself (pbrt-v3 hands the texture-to-world transform to a
//!   mapping that expects world-to-texture). v3 files were made to look right under
//!   that rule, so v3 files keep it. v3's `planar` mapping likewise takes world-space
//!   points, without the CTM.
//!
//! `ptex` is left out (noted; a constant 0.5 stands in).

use super::approx::Approx;
use super::values::{self, Range, Res};
use crate::imageio::RgbImage;
use crate::materials::params::{Resolver, TexValue, float, spectrum};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use glam::{DMat4, DVec3, Mat4, Vec3};
use std::sync::Arc;

pub use crate::imageio::Wrap;

/// (s, t) = (su·u + du, sv·v + dv).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMapping {
    pub su: f32,
    pub sv: f32,
    pub du: f32,
    pub dv: f32,
}

/// How a 2D texture finds (s, t) at a hit. `texture_from_world` takes world-space
/// points to texture space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mapping2D {
    Uv(UvMapping),
    /// s = θ/π, t = φ/2π of the direction from the texture-space origin.
    Spherical {
        texture_from_world: Mat4,
    },
    /// s = (π + atan2(y, x))/2π, t = z.
    Cylindrical {
        texture_from_world: Mat4,
    },
    /// s = ds + p·vs, t = dt + p·vt.
    Planar {
        texture_from_world: Mat4,
        vs: Vec3,
        vt: Vec3,
        ds: f32,
        dt: f32,
    },
}

/// Where a `Texture` statement stands: its CTM and the file's syntax version.
#[derive(Clone, Copy, Debug)]
pub struct TextureSite {
    pub world_from_texture: DMat4,
    pub syntax: Syntax,
}

impl TextureSite {
    /// World to texture space for 3D textures (see the module notes on v3).
    fn map3d(&self) -> Mat4 {
        match self.syntax {
            Syntax::V3 => self.world_from_texture.as_mat4(),
            Syntax::V4 => self.world_from_texture.inverse().as_mat4(),
        }
    }
}

/// The noise textures' parameters: `octaves` and `roughness` (ω, each octave's weight
/// relative to the one before).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Octaves {
    pub octaves: u32,
    pub omega: f32,
}

#[derive(Clone, Debug, PartialEq)]
pub enum TextureKind {
    Constant(TexValue),
    Checkerboard {
        tex1: TexValue,
        tex2: TexValue,
        map: Mapping2D,
    },
    Checkerboard3D {
        tex1: TexValue,
        tex2: TexValue,
        map: Mat4,
    },
    Scale {
        tex: TexValue,
        scale: TexValue,
    },
    Mix {
        tex1: TexValue,
        tex2: TexValue,
        amount: TexValue,
    },
    /// `tex1` where the geometric normal is along `dir` (world space), `tex2` across it.
    DirectionMix {
        tex1: TexValue,
        tex2: TexValue,
        dir: Vec3,
    },
    /// Corner values at (s, t) = (0,0), (1,0), (0,1), (1,1).
    Bilerp {
        v: [Rgb; 4],
        map: Mapping2D,
    },
    Image {
        image: Arc<RgbImage>,
        map: Mapping2D,
        wrap: Wrap,
        scale: f32,
        invert: bool,
    },
    /// Polka dots: `dot` inside them, `background` around them.
    Dots {
        dot: TexValue,
        background: TexValue,
        map: Mapping2D,
    },
    Fbm {
        map: Mat4,
        octaves: Octaves,
    },
    Wrinkled {
        map: Mat4,
        octaves: Octaves,
    },
    Windy {
        map: Mat4,
    },
    Marble {
        map: Mat4,
        octaves: Octaves,
        scale: f32,
        variation: f32,
        /// pbrt-v3's colour spline segments (see `materials::textures::marble`).
        v3_segments: bool,
    },
    /// (s, t) modulo 1 as red and green.
    Uv {
        map: Mapping2D,
    },
}

/// A texture some used material (or texture) refers to.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureDesc {
    pub name: String,
    pub kind: TextureKind,
}

impl TextureKind {
    /// The textures this one reads.
    pub fn inputs(&self) -> Vec<TexValue> {
        use TextureKind as K;
        match self {
            K::Constant(v) => vec![*v],
            K::Checkerboard { tex1, tex2, .. } | K::Checkerboard3D { tex1, tex2, .. } => vec![*tex1, *tex2],
            K::DirectionMix { tex1, tex2, .. } => vec![*tex1, *tex2],
            K::Scale { tex, scale } => vec![*tex, *scale],
            K::Mix { tex1, tex2, amount } => vec![*tex1, *tex2, *amount],
            K::Dots { dot, background, .. } => vec![*dot, *background],
            K::Bilerp { .. } | K::Image { .. } | K::Fbm { .. } | K::Wrinkled { .. } => vec![],
            K::Windy { .. } | K::Marble { .. } | K::Uv { .. } => vec![],
        }
    }
}

/// One texture input of a texture of kind `float` or `spectrum`.
fn input(p: &ParamList, name: &str, default: f32, is_float: bool, r: &mut dyn Resolver) -> Res<TexValue> {
    if is_float { float(p, name, default, Range::Any, r) } else { spectrum(p, name, default, r) }
}

/// A constant input (`bilerp`'s corners): a float, or a spectrum as RGB.
fn constant(p: &ParamList, name: &str, default: f32, is_float: bool, r: &mut dyn Resolver) -> Res<Rgb> {
    Ok(if is_float {
        Vec3::splat(values::float(p, name, default, Range::Any)?)
    } else {
        values::rgb(p, name, &r.spectra(), Range::Any)?.unwrap_or(Vec3::splat(default))
    })
}

/// A texture of class `class`, or `None` for classes we do not support.
pub fn texture(
    class: &str,
    is_float: bool,
    p: &ParamList,
    at: Span,
    site: &TextureSite,
    r: &mut dyn Resolver,
) -> Res<Option<TextureKind>> {
    Ok(Some(match class {
        "constant" => TextureKind::Constant(input(p, "value", 1.0, is_float, r)?),
        "checkerboard" => checkerboard(p, at, is_float, site, r)?,
        // v3: tex1 × tex2; v4: tex × scale (a float texture).
        "scale" if p.named("tex1").is_some() || p.named("tex2").is_some() => {
            TextureKind::Scale { tex: input(p, "tex1", 1.0, is_float, r)?, scale: input(p, "tex2", 1.0, is_float, r)? }
        }
        "scale" => TextureKind::Scale {
            tex: input(p, "tex", 1.0, is_float, r)?,
            scale: float(p, "scale", 1.0, Range::Any, r)?,
        },
        "mix" => TextureKind::Mix {
            tex1: input(p, "tex1", 0.0, is_float, r)?,
            tex2: input(p, "tex2", 1.0, is_float, r)?,
            amount: float(p, "amount", 0.5, Range::Any, r)?,
        },
        "directionmix" => {
            let dir = p.fixed::<3>("dir", &[ParamType::Vector3])?.map_or(DVec3::Y, |d| DVec3::from(d.map(f64::from)));
            let dir = site.world_from_texture.transform_vector3(dir).try_normalize().unwrap_or(DVec3::Y).as_vec3();
            let (tex1, tex2) = (input(p, "tex1", 0.0, is_float, r)?, input(p, "tex2", 1.0, is_float, r)?);
            TextureKind::DirectionMix { tex1, tex2, dir }
        }
        "bilerp" => {
            let mut corner = |n: &str, d: f32| constant(p, n, d, is_float, r);
            let v = [corner("v00", 0.0)?, corner("v10", 0.0)?, corner("v01", 1.0)?, corner("v11", 1.0)?];
            TextureKind::Bilerp { v, map: mapping(p, site)? }
        }
        "imagemap" => image_texture(p, at, site, r)?,
        // pbrt (v3 and v4) passes "inside" where its constructor takes the texture
        // outside the dots and "outside" where it takes the one inside: the dots show
        // "outside". Files are made to look right in pbrt, so we draw them the same.
        "dots" => TextureKind::Dots {
            map: mapping(p, site)?,
            background: input(p, "inside", 1.0, is_float, r)?,
            dot: input(p, "outside", 0.0, is_float, r)?,
        },
        "fbm" => TextureKind::Fbm { map: site.map3d(), octaves: octaves(p)? },
        "wrinkled" => TextureKind::Wrinkled { map: site.map3d(), octaves: octaves(p)? },
        "windy" => TextureKind::Windy { map: site.map3d() },
        // pbrt has marble as a spectrum texture only.
        "marble" if !is_float => TextureKind::Marble {
            map: site.map3d(),
            octaves: octaves(p)?,
            scale: values::float(p, "scale", 1.0, Range::Any)?,
            variation: values::float(p, "variation", 0.2, Range::Any)?,
            v3_segments: site.syntax == Syntax::V3,
        },
        "uv" if !is_float => TextureKind::Uv { map: mapping(p, site)? },
        _ => return Ok(None),
    }))
}

/// `octaves` (default 8, at most 32) and `roughness` (default .5).
fn octaves(p: &ParamList) -> Res<Octaves> {
    let n = p.int("octaves")?.unwrap_or(8);
    if !(0..=32).contains(&n) {
        let at = values::span_of(p, "octaves").unwrap_or_default();
        return Err(Diagnostic::error(at, format!("\"octaves\" must be between 0 and 32, not {n}")));
    }
    Ok(Octaves { octaves: n as u32, omega: values::float(p, "roughness", 0.5, Range::Any)? })
}

fn checkerboard(p: &ParamList, at: Span, is_float: bool, site: &TextureSite, r: &mut dyn Resolver) -> Res<TextureKind> {
    let dimension = p.int("dimension")?.unwrap_or(2);
    // Filtering: SPPM's many samples per pixel filter the point-sampled checks.
    values::no_effect(p, &["aamode"]);
    let (tex1, tex2) = (input(p, "tex1", 1.0, is_float, r)?, input(p, "tex2", 0.0, is_float, r)?);
    match dimension {
        2 => Ok(TextureKind::Checkerboard { tex1, tex2, map: mapping(p, site)? }),
        3 => Ok(TextureKind::Checkerboard3D { tex1, tex2, map: site.map3d() }),
        d => {
            let at = values::span_of(p, "dimension").unwrap_or(at);
            Err(Diagnostic::error(at, format!("checkerboard \"dimension\" must be 2 or 3, not {d}")))
        }
    }
}

/// `"string mapping"` and its parameters.
fn mapping(p: &ParamList, site: &TextureSite) -> Res<Mapping2D> {
    let kind = values::choice(p, "mapping", "uv", &["uv", "spherical", "cylindrical", "planar"])?;
    let f = |name: &str, d: f32| values::float(p, name, d, Range::Any);
    let texture_from_world = site.world_from_texture.inverse().as_mat4();
    Ok(match kind {
        "spherical" => Mapping2D::Spherical { texture_from_world },
        "cylindrical" => Mapping2D::Cylindrical { texture_from_world },
        "planar" => {
            let v = |name: &str, d: Vec3| -> Res<Vec3> {
                Ok(p.fixed::<3>(name, &[ParamType::Vector3])?.map_or(d, Vec3::from))
            };
            Mapping2D::Planar {
                // pbrt-v3 maps world-space points (see the module notes).
                texture_from_world: if site.syntax == Syntax::V3 { Mat4::IDENTITY } else { texture_from_world },
                vs: v("v1", Vec3::X)?,
                vt: v("v2", Vec3::Y)?,
                ds: f("udelta", 0.0)?,
                dt: f("vdelta", 0.0)?,
            }
        }
        _ => Mapping2D::Uv(UvMapping {
            su: f("uscale", 1.0)?,
            sv: f("vscale", 1.0)?,
            du: f("udelta", 0.0)?,
            dv: f("vdelta", 0.0)?,
        }),
    })
}

fn image_texture(p: &ParamList, at: Span, site: &TextureSite, r: &mut dyn Resolver) -> Res<TextureKind> {
    let name = p
        .string("filename")?
        .ok_or_else(|| p.wrong_type().unwrap_or_else(|| Diagnostic::error(at, "imagemap needs \"string filename\"")))?;
    let name_at = p.named("filename").map_or(at, |f| f.value_span);
    let map = mapping(p, site)?;
    let wrap = match values::choice(p, "wrap", "repeat", &["repeat", "clamp", "black", "octahedralsphere"])? {
        "clamp" => Wrap::Clamp,
        "black" => Wrap::Black,
        _ => Wrap::Repeat,
    };
    let scale = values::float(p, "scale", 1.0, Range::Any)?;
    let invert = p.bool("invert")?.unwrap_or(false);
    let gamma = p.bool("gamma")?;
    let encoding = p.string("encoding")?;
    // Filtering hints: lookups are bilinear, and SPPM's many samples per pixel filter.
    values::no_effect(p, &["maxanisotropy", "trilinear", "filter"]);
    let mut image = match r.image(&name) {
        Ok(img) => img,
        Err(e) => {
            // pbrt-v3 stands in one grey texel, converted as the file's texels would be
            // (pbrt-v4 aborts).
            r.approximate(name_at, format!("imagemap ({e})"), Approx::MissingImage);
            let lower = name.to_ascii_lowercase();
            let gamma = gamma.unwrap_or(lower.ends_with(".png") || lower.ends_with(".tga"));
            let grey = if gamma { crate::imageio::from_srgb(0.5) } else { 0.5 };
            return Ok(TextureKind::Constant(TexValue::Const(Vec3::splat(scale * grey))));
        }
    };
    let linear = gamma == Some(false) || encoding.as_deref() == Some("linear");
    if linear {
        image = crate::imageio::stored_values(&name, image);
    }
    Ok(TextureKind::Image { image, map, wrap, scale, invert })
}
