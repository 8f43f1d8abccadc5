//! `Texture "name" "spectrum" "uv"` (v3): (s, t) modulo 1 as red and green.
//!
//! ```text
//! Texture "u" "spectrum" "uv" "string mapping" "spherical"
//! ```

use super::mapping::{self, Mapping2D, map_2d};
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::Res;
use glam::Vec3;

pub const NAME: &str = "uv";

/// A spectrum texture only, as in pbrt.
pub fn read(i: &mut Input, p: &ParamList, _at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    if i.is_float {
        return Ok(None);
    }
    Ok(Some(TextureKind::Uv { map: mapping::read(p, site, i.r)? }))
}

#[inline]
pub fn eval(map: &Mapping2D, ctx: &TexCtx) -> Rgb {
    let [s, t] = map_2d(map, ctx);
    Vec3::new(s - s.floor(), t - t.floor(), 0.0)
}
