//! `Texture "name" "float|spectrum" "constant" "value" v`: the same value everywhere.
//!
//! ```text
//! Texture "grey" "spectrum" "constant" "rgb value" [.5 .5 .5]
//! ```

use super::{Input, TextureKind, TextureSite};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::{Res, TexValue};

pub const NAME: &str = "constant";

pub fn read(i: &mut Input, p: &ParamList, _at: Span, _site: &TextureSite) -> Res<Option<TextureKind>> {
    Ok(Some(TextureKind::Constant(i.input(p, "value", 1.0)?)))
}

#[inline]
pub fn eval(v: TexValue, get: impl Fn(TexValue) -> Rgb) -> Rgb {
    get(v)
}
