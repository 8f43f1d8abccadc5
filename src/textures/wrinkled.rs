//! `Texture "name" "float" "wrinkled"`: pbrt's turbulence (fBm of |noise|) in texture
//! space.
//!
//! ```text
//! Texture "w" "float" "wrinkled" "integer octaves" 8 "float roughness" .5
//! ```

use super::mapping::map_3d;
use super::noise::{Octaves, turbulence};
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::Res;
use glam::{Mat4, Vec3};

pub const NAME: &str = "wrinkled";

pub fn read(_i: &mut Input, p: &ParamList, _at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    Ok(Some(TextureKind::Wrinkled { map: site.map3d(), octaves: Octaves::read(p)? }))
}

#[inline]
pub fn eval(map: &Mat4, o: &Octaves, ctx: &TexCtx) -> Rgb {
    let (p, dx, dy) = map_3d(map, ctx);
    Vec3::splat(turbulence(p, dx, dy, o.omega, o.octaves))
}
