//! `Texture "name" "float" "windy"`: pbrt's waves, a low-frequency fBm scaling a
//! higher one.
//!
//! ```text
//! Texture "sea" "float" "windy"
//! ```

use super::mapping::map_3d;
use super::noise::fbm;
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::Res;
use glam::{Mat4, Vec3};

pub const NAME: &str = "windy";

pub fn read(_i: &mut Input, _p: &ParamList, _at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    Ok(Some(TextureKind::Windy { map: site.map3d() }))
}

#[inline]
pub fn eval(map: &Mat4, ctx: &TexCtx) -> Rgb {
    let (p, dx, dy) = map_3d(map, ctx);
    Vec3::splat(fbm(0.1 * p, 0.1 * dx, 0.1 * dy, 0.5, 3).abs() * fbm(p, dx, dy, 0.5, 6))
}
