//! `Texture "name" "float|spectrum" "mix"`: `tex1` × (1 − amount) + `tex2` × amount.
//!
//! ```text
//! Texture "m" "spectrum" "mix" "rgb tex1" [1 1 1] "texture tex2" "checks" "float amount" 0.3
//! ```

use super::{Input, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::Range;
use crate::values::{Res, TexValue};
use glam::Vec3;

pub const NAME: &str = "mix";

pub fn read(i: &mut Input, p: &ParamList, _at: Span, _site: &TextureSite) -> Res<Option<TextureKind>> {
    Ok(Some(TextureKind::Mix {
        tex1: i.input(p, "tex1", 0.0)?,
        tex2: i.input(p, "tex2", 1.0)?,
        amount: i.float(p, "amount", 0.5, Range::Any)?,
    }))
}

#[inline]
pub fn eval([tex1, tex2, amount]: [TexValue; 3], get: impl Fn(TexValue) -> Rgb) -> Rgb {
    let t = get(amount);
    get(tex1) * (Vec3::ONE - t) + get(tex2) * t
}
