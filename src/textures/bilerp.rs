//! `Texture "name" "float|spectrum" "bilerp"`: corner values at (s, t) = (0,0), (1,0),
//! (0,1), (1,1), interpolated.
//!
//! ```text
//! Texture "b" "float" "bilerp" "float v00" 0 "float v01" 1 "float v10" 0 "float v11" 1
//! ```

use super::mapping::{self, Mapping2D, map_2d};
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::Res;

pub const NAME: &str = "bilerp";

pub fn read(i: &mut Input, p: &ParamList, _at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    let mut corner = |n: &str, d: f32| i.constant(p, n, d);
    let v = [corner("v00", 0.0)?, corner("v10", 0.0)?, corner("v01", 1.0)?, corner("v11", 1.0)?];
    Ok(Some(TextureKind::Bilerp { v, map: mapping::read(p, site, i.r)? }))
}

#[inline]
pub fn eval(v: &[Rgb; 4], map: &Mapping2D, ctx: &TexCtx) -> Rgb {
    let [s, t] = map_2d(map, ctx);
    (1.0 - s) * (1.0 - t) * v[0] + s * (1.0 - t) * v[1] + (1.0 - s) * t * v[2] + s * t * v[3]
}
