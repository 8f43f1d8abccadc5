//! `Texture "name" "float|spectrum" "dots"`: pbrt's polka dots, one of radius .35 in
//! half the unit cells of (s, t), jittered by noise.
//!
//! ```text
//! Texture "a" "float" "dots" "float inside" 1 "float outside" 0 "float uscale" 10   # dots 0, as pbrt
//! ```
//! pbrt (v3 and v4) passes `inside` where its constructor takes the texture outside the
//! dots and `outside` where it takes the one inside: the dots show `outside`. Files are
//! made to look right in pbrt, so we draw them the same.

use super::mapping::{self, Mapping2D, map_2d};
use super::noise::noise2;
use super::{Input, TexCtx, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::{Res, TexValue};

pub const NAME: &str = "dots";

pub fn read(i: &mut Input, p: &ParamList, _at: Span, site: &TextureSite) -> Res<Option<TextureKind>> {
    Ok(Some(TextureKind::Dots {
        map: mapping::read(p, site, i.r)?,
        background: i.input(p, "inside", 1.0)?,
        dot: i.input(p, "outside", 0.0)?,
    }))
}

#[inline]
pub fn eval([dot, background]: [TexValue; 2], map: &Mapping2D, ctx: &TexCtx, get: impl Fn(TexValue) -> Rgb) -> Rgb {
    get(if inside_dot(map_2d(map, ctx)) { dot } else { background })
}

/// Whether (s, t) is inside a dot.
#[inline]
pub fn inside_dot([s, t]: [f32; 2]) -> bool {
    let (sc, tc) = ((s + 0.5).floor(), (t + 0.5).floor());
    if noise2(sc + 0.5, tc + 0.5) <= 0.0 {
        return false;
    }
    const RADIUS: f32 = 0.35;
    let shift = 0.5 - RADIUS;
    let centre = (sc + shift * noise2(sc + 1.5, tc + 2.8), tc + shift * noise2(sc + 4.5, tc + 9.8));
    let (ds, dt) = (s - centre.0, t - centre.1);
    ds * ds + dt * dt < RADIUS * RADIUS
}
