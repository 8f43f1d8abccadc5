//! `Texture "name" "float|spectrum" "checkerboard"`: `tex1` and `tex2` in alternating
//! cells of (s, t), or of texture space with `"integer dimension" 3`.
//!
//! ```text
//! Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "rgb tex1" [1 0 0]
//! Texture "c3" "float" "checkerboard" "integer dimension" 3        # in texture space
//! ```
//! `aamode` has no effect: SPPM's many samples per pixel filter the point-sampled checks.

use super::mapping::{self, Mapping2D, map_2d};
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values;
use crate::values::{Res, TexValue};
use glam::Mat4;

pub const NAME: &str = "checkerboard";

pub fn read(i: &mut Input, p: &ParamList, at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    let dimension = p.int("dimension")?.unwrap_or(2);
    values::no_effect(p, &["aamode"]);
    let (tex1, tex2) = (i.input(p, "tex1", 1.0)?, i.input(p, "tex2", 0.0)?);
    match dimension {
        2 => Ok(Some(TextureKind::Checkerboard { tex1, tex2, map: mapping::read(p, site, i.r)? })),
        3 => Ok(Some(TextureKind::Checkerboard3D { tex1, tex2, map: site.map3d() })),
        d => {
            let at = values::span_of(p, "dimension").unwrap_or(at);
            Err(Diagnostic::error(at, format!("checkerboard \"dimension\" must be 2 or 3, not {d}")))
        }
    }
}

#[inline]
pub fn eval_2d([tex1, tex2]: [TexValue; 2], map: &Mapping2D, ctx: &TexCtx, get: impl Fn(TexValue) -> Rgb) -> Rgb {
    let [s, t] = map_2d(map, ctx);
    get(if (s.floor() as i64 + t.floor() as i64) % 2 == 0 { tex1 } else { tex2 })
}

#[inline]
pub fn eval_3d([tex1, tex2]: [TexValue; 2], map: &Mat4, ctx: &TexCtx, get: impl Fn(TexValue) -> Rgb) -> Rgb {
    let p = map.transform_point3(ctx.p).floor();
    get(if (p.x as i64 + p.y as i64 + p.z as i64) % 2 == 0 { tex1 } else { tex2 })
}
