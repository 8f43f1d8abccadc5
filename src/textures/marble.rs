//! `Texture "name" "spectrum" "marble"`: pbrt's marble, a colour spline at
//! ½ + ½ sin(y + variation · fBm) in texture space.
//!
//! ```text
//! Texture "m" "spectrum" "marble" "float scale" 4 "float variation" .2 "integer octaves" 8
//! ```

use super::mapping::map_3d;
use super::noise::{Octaves, fbm};
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::Res;
use glam::{Mat4, Vec3};

use crate::parser::Syntax;
use crate::values::{self, Range};

pub const NAME: &str = "marble";

/// A spectrum texture only, as in pbrt.
pub fn read(i: &mut Input, p: &ParamList, _at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    if i.is_float {
        return Ok(None);
    }
    Ok(Some(TextureKind::Marble {
        map: site.map3d(),
        octaves: Octaves::read(p)?,
        scale: values::float(p, "scale", 1.0, Range::Any)?,
        variation: values::float(p, "variation", 0.2, Range::Any)?,
        v3_segments: site.syntax == Syntax::V3,
    }))
}

#[inline]
pub fn eval(map: &Mat4, o: &Octaves, [scale, variation]: [f32; 2], v3_segments: bool, ctx: &TexCtx) -> Rgb {
    let (p, dx, dy) = map_3d(map, ctx);
    let m = p.y * scale + variation * fbm(p * scale, dx * scale, dy * scale, o.omega, o.octaves);
    colour(0.5 + 0.5 * m.sin(), v3_segments)
}

/// pbrt's marble colour at `t` = ½ + ½ sin(y + variation · fBm): a cubic Bézier colour
/// spline of six segments.
// DEVIATION(pbrt): appearance, `--fix marble-palette`. pbrt-v3 picks the segment with
// `min(1, ⌊6t⌋)` (`v3_segments`), which evaluates the Bézier far outside [0, 1]
// (colours beyond 10, or negative); the fix, and pbrt-v4, use `min(⌊6t⌋, 5)`.
#[inline]
pub fn colour(t: f32, v3_segments: bool) -> Rgb {
    const C: [[f32; 3]; 9] = [
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.5, 0.5, 0.5],
        [0.6, 0.59, 0.58],
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.2, 0.2, 0.33],
        [0.58, 0.58, 0.6],
    ];
    let segments = C.len() - 3;
    let last = if v3_segments { 1 } else { segments - 1 };
    let first = ((t * segments as f32).floor().max(0.0) as usize).min(last);
    let t = t * segments as f32 - first as f32;
    let c: Vec<Vec3> = C[first..first + 4].iter().map(|c| Vec3::from(*c)).collect();
    let l = |a: Vec3, b: Vec3| (1.0 - t) * a + t * b;
    let (s0, s1, s2) = (l(c[0], c[1]), l(c[1], c[2]), l(c[2], c[3]));
    let (s0, s1) = (l(s0, s1), l(s1, s2));
    1.5 * l(s0, s1)
}
