//! What every `Shape` statement may carry besides its geometry: `alpha` and `shadowalpha`.
//! The geometry is each shape type's own (`shapes::REGISTRY`).
//!
//! ```text
//! Shape "trianglemesh" "float alpha" 0.5 ...           # v4: passes half the rays
//! Shape "trianglemesh" "texture alpha" "leaf" "texture shadowalpha" "leaf" ...   # v3
//! ```

use crate::parser::error::Diagnostic;
use crate::parser::params::FloatValue;
use crate::parser::params::ParamList;
use crate::parser::source::Span;

type Res<T> = Result<T, Diagnostic>;

/// A shape's `alpha` and (v3) `shadowalpha` as written: a constant or a float texture's
/// name, each with its span. Resolved once the file is read (`builder::typed`).
#[derive(Clone, Debug, Default)]
pub struct AlphaParams {
    pub alpha: Option<(FloatValue, Span)>,
    pub shadow: Option<(FloatValue, Span)>,
}

/// The shape's alpha parameters, `None` when neither is given.
pub fn alpha_params(p: &ParamList) -> Res<Option<AlphaParams>> {
    let get = |name: &str| -> Res<Option<(FloatValue, Span)>> {
        Ok(p.float_or_texture(name)?.map(|v| (v, p.named(name).map(|x| x.value_span).unwrap_or_default())))
    };
    let a = AlphaParams { alpha: get("alpha")?, shadow: get("shadowalpha")? };
    Ok((a.alpha.is_some() || a.shadow.is_some()).then_some(a))
}
