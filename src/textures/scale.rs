//! `Texture "name" "float|spectrum" "scale"`: pbrt-v3's `tex1` × `tex2`, or pbrt-v4's
//! `tex` × `scale` (a float texture).
//!
//! ```text
//! Texture "s" "spectrum" "scale" "texture tex1" "checks" "float tex2" 0.5     # v3
//! Texture "s" "spectrum" "scale" "texture tex" "checks" "float scale" 0.5     # v4
//! ```

use super::{Input, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::Range;
use crate::values::{Res, TexValue};

pub const NAME: &str = "scale";

pub fn read(i: &mut Input, p: &ParamList, _at: Span, _site: &TextureSite) -> Res<Option<TextureKind>> {
    if p.named("tex1").is_some() || p.named("tex2").is_some() {
        return Ok(Some(TextureKind::Scale { tex: i.input(p, "tex1", 1.0)?, scale: i.input(p, "tex2", 1.0)? }));
    }
    let tex = i.input(p, "tex", 1.0)?;
    Ok(Some(TextureKind::Scale { tex, scale: i.float(p, "scale", 1.0, Range::Any)? }))
}

#[inline]
pub fn eval(tex: TexValue, scale: TexValue, get: impl Fn(TexValue) -> Rgb) -> Rgb {
    get(tex) * get(scale)
}
