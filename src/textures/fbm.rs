//! `Texture "name" "float" "fbm"`: pbrt's fractional Brownian motion of Perlin noise in
//! texture space; octaves finer than the pixel's footprint are left out.
//!
//! ```text
//! Texture "n" "float" "fbm" "integer octaves" 8 "float roughness" .5
//! ```

use super::mapping::map_3d;
use super::noise::{Octaves, fbm};
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::Res;
use glam::{Mat4, Vec3};

pub const NAME: &str = "fbm";

pub fn read(_i: &mut Input, p: &ParamList, _at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    Ok(Some(TextureKind::Fbm { map: site.map3d(), octaves: Octaves::read(p)? }))
}

#[inline]
pub fn eval(map: &Mat4, o: &Octaves, ctx: &TexCtx) -> Rgb {
    let (p, dx, dy) = map_3d(map, ctx);
    Vec3::splat(fbm(p, dx, dy, o.omega, o.octaves))
}
