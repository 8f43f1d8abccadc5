//! `Texture "name" "float|spectrum" "directionmix"` (v4): `tex1` where the geometric
//! normal is along `dir` (world space), `tex2` across it.
//!
//! ```text
//! Texture "d" "spectrum" "directionmix" "vector3 dir" [0 0 1] "texture tex1" "checks"
//! ```

use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::params::ParamType;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::{Res, TexValue};
use glam::{DVec3, Vec3};

pub const NAME: &str = "directionmix";

pub fn read(i: &mut Input, p: &ParamList, _at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    let dir = p.fixed::<3>("dir", &[ParamType::Vector3])?.map_or(DVec3::Y, |d| DVec3::from(d.map(f64::from)));
    let dir = site.world_from_texture.transform_vector3(dir).try_normalize().unwrap_or(DVec3::Y).as_vec3();
    let (tex1, tex2) = (i.input(p, "tex1", 0.0)?, i.input(p, "tex2", 1.0)?);
    Ok(Some(TextureKind::DirectionMix { tex1, tex2, dir }))
}

#[inline]
pub fn eval([tex1, tex2]: [TexValue; 2], dir: Vec3, ctx: &TexCtx, get: impl Fn(TexValue) -> Rgb) -> Rgb {
    let a = ctx.n.dot(dir).abs();
    a * get(tex1) + (1.0 - a) * get(tex2)
}
