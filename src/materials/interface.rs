//! `Material "interface"` (v4), `"none"` and `""` (v3): no surface; paths pass straight
//! through (the boundary of a medium).
//!
//! ```text
//! Material "interface"
//! Material ""
//! ```

use super::MaterialKind;
use super::params::Resolver;
use crate::mitsuba::MaterialOut;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;

pub const NAMES: [&str; 3] = ["interface", "none", ""];

pub fn read(_ty: &str, _p: &ParamList, _at: Span, _r: &mut dyn Resolver) -> Res<MaterialKind> {
    Ok(MaterialKind::Interface)
}

pub fn mitsuba() -> MaterialOut {
    MaterialOut::None
}
