//! `Texture "name" "float|spectrum" "imagemap"`: an image of a format the file's pbrt
//! reads ([`crate::imageio::formats`]), looked up bilinearly with t = 0 at the bottom
//! row (as pbrt).
//!
//! ```text
//! Texture "img" "spectrum" "imagemap" "string filename" "wood.png" "string wrap" "clamp"
//! Texture "raw" "spectrum" "imagemap" "string filename" "n.png" "bool gamma" false   # v3
//! Texture "raw" "spectrum" "imagemap" "string filename" "n.png" "string encoding" "linear"   # v4
//! Texture "g" "spectrum" "imagemap" "string filename" "n.png" "string encoding" "gamma 2.2"   # v4
//! ```
//! 8-bit images are sRGB-decoded unless `gamma false` (v3) or another `encoding` (v4:
//! `linear`, `gamma g`; it reaches PNG values only, as pbrt-v4 reads TGA, JPEG and BMP
//! as sRGB); a v3 `gamma true` decodes EXR, PFM and HDR texels too, as pbrt-v3 does. A
//! float texture takes one value a texel as its pbrt does ([`crate::imageio::grey`]:
//! pbrt-v3's luminance, pbrt-v4's alpha or mean). `wrap` is repeat, clamp or black;
//! `scale` and `invert` apply after the lookup. An image that cannot be read is, as in
//! pbrt-v3, one grey texel of 0.5 times `scale` (noted); pbrt-v4 aborts. Filtering
//! hints have no effect: SPPM's many samples per pixel filter.

use super::mapping::{self, Mapping2D, map_2d};
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::approx::Approx;
use crate::imageio::{Format, Grey, Texels, Wrap, lookup};
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::{self, ColorEncoding, Range, Res, Resolver, TexValue};
use glam::Vec3;
use std::path::Path;
use std::sync::Arc;

pub const NAME: &str = "imagemap";

/// pbrt-v4's `filter` names (`ParseFilter`).
const FILTERS: [&str; 5] = ["ewa", "EWA", "trilinear", "bilinear", "point"];

/// `wrap`: repeat, clamp or black (pbrt-v4's octahedralsphere is read as repeat).
/// pbrt-v3 takes any other name as repeat without a word, and pbrt-v4 stops: in a v3
/// file it is repeat, with a warning.
fn wrap_mode(r: &mut dyn Resolver, p: &ParamList) -> Res<Wrap> {
    const MODES: [&str; 4] = ["repeat", "clamp", "black", "octahedralsphere"];
    let v3 = r.syntax() == crate::parser::Syntax::V3;
    if let Some(w) = p.string("wrap")?.filter(|w| v3 && !MODES.contains(&w.as_str())) {
        let at = values::span_of(p, "wrap").unwrap_or_default();
        r.warn(at, format!("imagemap: unknown wrap mode \"{w}\"; repeat, as pbrt-v3 takes it"));
        return Ok(Wrap::Repeat);
    }
    Ok(match values::choice(p, "wrap", "repeat", &MODES)? {
        "clamp" => Wrap::Clamp,
        "black" => Wrap::Black,
        _ => Wrap::Repeat,
    })
}

pub fn read(i: &mut Input, p: &ParamList, at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    let name = p
        .string("filename")?
        .ok_or_else(|| p.wrong_type().unwrap_or_else(|| Diagnostic::error(at, "imagemap needs \"string filename\"")))?;
    let name_at = p.named("filename").map_or(at, |f| f.value_span);
    let map = mapping::read(p, site, i.r)?;
    let wrap = wrap_mode(i.r, p)?;
    let scale = values::float(p, "scale", 1.0, Range::Any)?;
    let invert = p.bool("invert")?.unwrap_or(false);
    let v3 = i.r.syntax() == crate::parser::Syntax::V3;
    // pbrt-v3 reads `gamma`, pbrt-v4 `encoding` (which reaches PNG values only).
    let (gamma, encoding) = match v3 {
        true => (p.bool("gamma")?, ColorEncoding::Srgb),
        false => (None, values::encoding(p, ColorEncoding::Srgb, at)?),
    };
    values::no_effect(p, &["maxanisotropy", "trilinear", "filter"]);
    if let Some(f) = p.string("filter")?.filter(|f| !v3 && !FILTERS.contains(&f.as_str())) {
        let at = values::span_of(p, "filter").unwrap_or(at);
        i.r.warn(at, format!("imagemap: unknown filter \"{f}\"; the default one, as pbrt-v4 takes it"));
    }
    let eight_bit = Format::of(Path::new(&name)).is_some_and(Format::eight_bit);
    let read = match i.is_float {
        true if v3 => i.r.grey_image(&name, Grey::V3 { decode: gamma.unwrap_or(eight_bit) }),
        true => i.r.grey_image(&name, Grey::V4 { png: encoding }),
        false => i.r.image(&name),
    };
    let image = match read {
        Ok(img) if i.is_float => img,
        Ok(img) => encoded(&name, img, v3, gamma, encoding),
        Err(e) => {
            i.r.approximate(name_at, format!("imagemap ({e})"), Approx::MissingImage);
            let lower = name.to_ascii_lowercase();
            let gamma = gamma.unwrap_or(lower.ends_with(".png") || lower.ends_with(".tga"));
            let grey = if gamma { crate::imageio::from_srgb(0.5) } else { 0.5 };
            return Ok(Some(TextureKind::Constant(TexValue::Const(Vec3::splat(scale * grey)))));
        }
    };
    Ok(Some(TextureKind::Image { image, map, wrap, scale, invert }))
}

/// A colour texture's texels (read sRGB-decoded) as `gamma` (v3) or `encoding` (v4)
/// asks.
fn encoded(name: &str, image: Arc<Texels>, v3: bool, gamma: Option<bool>, encoding: ColorEncoding) -> Arc<Texels> {
    let float_format = Format::of(Path::new(name)).is_some_and(|f| !f.eight_bit());
    match encoding {
        _ if gamma == Some(false) => crate::imageio::stored_values(name, image, v3),
        ColorEncoding::Linear => crate::imageio::stored_values(name, image, v3),
        ColorEncoding::Gamma(_) => {
            // Only where the file's encoding reaches the values (a PNG) are they
            // stored ones to raise to the power.
            let stored = crate::imageio::stored_values(name, image.clone(), v3);
            match Arc::ptr_eq(&stored, &image) {
                true => image,
                false => Arc::new(stored.map_values(|v| encoding.to_linear(v))),
            }
        }
        // pbrt-v3 decodes every texel of a texture that asks for `gamma`, floats too.
        ColorEncoding::Srgb if v3 && gamma == Some(true) && float_format => {
            Arc::new(image.map_values(crate::imageio::from_srgb))
        }
        ColorEncoding::Srgb => image,
    }
}

#[inline]
pub fn eval(image: &Arc<Texels>, map: &Mapping2D, (wrap, scale, invert): (Wrap, f32, bool), ctx: &TexCtx) -> Rgb {
    let [s, t] = map_2d(map, ctx);
    let v = lookup(image, s, t, wrap, false) * scale;
    if invert { (Vec3::ONE - v).max(Vec3::ZERO) } else { v }
}
