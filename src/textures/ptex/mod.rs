//! `Texture "name" "float|spectrum" "ptex"`: per-face textures from a Ptex file, looked
//! up by the hit's face index (`faceIndices` of a mesh, `face_indices` of a PLY) and
//! its (u, v), through the Ptex library's filters: B-spline on quad meshes
//! ([`filter`]), Gaussian on triangle meshes ([`triangle`]).
//!
//! ```text
//! Texture "skin" "spectrum" "ptex" "string filename" "head.ptx" "float gamma" 2.2        # v3
//! Texture "skin" "spectrum" "ptex" "string filename" "head.ptx" "string encoding" "sRGB"
//!     "float scale" 1                                                                   # v4
//! ```
//! pbrt-v3 raises each channel in [0, 1] to `gamma` (default 2.2). pbrt-v4 rounds each
//! channel to 8 bits and decodes it by `encoding` ("linear", "sRGB" or "gamma g";
//! default "gamma 2.2"), then multiplies by `scale`. A float texture is the mean of
//! three channels. The filter's footprint is the camera ray's, where the first hit has
//! ray differentials; elsewhere it is one texel, as in pbrt-v3 without differentials.
//! A file that cannot be read, or whose channel count is not 1 or 3, is black, as in
//! both pbrts (noted).

pub mod file;
pub mod filter;
pub mod triangle;

use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::approx::Approx;
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::{self, ColorEncoding, Range, Res, TexValue};
use file::PtexFile;
use glam::Vec3;
use std::sync::Arc;

pub const NAME: &str = "ptex";

/// How filtered values become linear ones.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Decode {
    /// pbrt-v3: x^gamma for x in [0, 1], other values as they are.
    Power(f32),
    /// pbrt-v4's `encoding "linear"`.
    Linear,
    /// pbrt-v4: rounded to 8 bits, then the sRGB curve.
    Srgb8,
    /// pbrt-v4: rounded to 8 bits, then (x / 255)^gamma.
    Gamma8(f32),
}

impl Decode {
    fn apply(self, x: f32) -> f32 {
        let byte = || (x * 255.0 + 0.5).clamp(0.0, 255.0) as u8 as f32 / 255.0;
        match self {
            Decode::Power(g) if (0.0..=1.0).contains(&x) && g != 1.0 => x.powf(g),
            Decode::Power(_) | Decode::Linear => x,
            Decode::Srgb8 => crate::imageio::from_srgb(byte()),
            Decode::Gamma8(g) => byte().powf(g),
        }
    }
}

/// A `ptex` texture: the file and how its values are decoded.
#[derive(Debug)]
pub struct PtexTexture {
    pub file: Arc<PtexFile>,
    pub decode: Decode,
    pub scale: f32,
    /// A float texture: the mean of the channels.
    pub float: bool,
}

impl PartialEq for PtexTexture {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.file, &o.file) && (self.decode, self.scale, self.float) == (o.decode, o.scale, o.float)
    }
}

pub fn read(i: &mut Input, p: &ParamList, at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    let name = p
        .string("filename")?
        .ok_or_else(|| p.wrong_type().unwrap_or_else(|| Diagnostic::error(at, "ptex needs \"string filename\"")))?;
    let name_at = values::span_of(p, "filename").unwrap_or(at);
    let (decode, scale) = match site.syntax {
        Syntax::V3 => (Decode::Power(values::float(p, "gamma", 2.2, Range::Any)?), 1.0),
        Syntax::V4 => (encoding(p, at)?, values::float(p, "scale", 1.0, Range::Any)?),
    };
    let spectra = i.r.spectra();
    let path = spectra.base_dir.join(&name);
    let read = spectra
        .files
        .read(&path)
        .and_then(|bytes| PtexFile::read(&bytes, spectra.files.limits.file_bytes).map_err(|e| e.to_string()));
    let file = match read {
        Ok(f) if f.channels == 1 || f.channels == 3 => f,
        Ok(f) => return Ok(Some(black(i, name_at, &name, format!("{} channels; pbrt reads 1 or 3", f.channels)))),
        Err(e) => return Ok(Some(black(i, name_at, &name, e))),
    };
    let tex = PtexTexture { file: Arc::new(file), decode, scale, float: i.is_float };
    Ok(Some(TextureKind::Ptex(Arc::new(tex))))
}

/// pbrt-v4's `encoding` (default "gamma 2.2"; a located error where it names none).
fn encoding(p: &ParamList, at: Span) -> Res<Decode> {
    Ok(match values::encoding(p, ColorEncoding::Gamma(2.2f32.to_bits()), at)? {
        ColorEncoding::Linear => Decode::Linear,
        ColorEncoding::Srgb => Decode::Srgb8,
        ColorEncoding::Gamma(g) => Decode::Gamma8(f32::from_bits(g)),
    })
}

/// What pbrt renders for a Ptex file it cannot use: black, with the reason noted.
fn black(i: &mut Input, at: Span, name: &str, why: String) -> TextureKind {
    i.r.approximate(at, format!("ptex \"{name}\" ({why})"), Approx::UnreadablePtex);
    TextureKind::Constant(TexValue::Const(Vec3::ZERO))
}

/// The texture at a hit: filtered at the hit's face and (u, v), over its footprint.
pub fn eval(t: &PtexTexture, ctx: &TexCtx) -> Rgb {
    let raw = t.file.eval(ctx.face, ctx.uv[0], ctx.uv[1], ctx.duv);
    let v: Vec<f32> = raw.iter().map(|&x| t.decode.apply(x) * t.scale).collect();
    match v[..] {
        [g] => Vec3::splat(g),
        [r, g, b] if t.float => Vec3::splat((r + g + b) / 3.0),
        [r, g, b] => Vec3::new(r, g, b),
        _ => Vec3::ZERO,
    }
}
