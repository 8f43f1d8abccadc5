//! Parameters the quadrics read alike: finite floats, positive radii.

use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;

/// A finite float, `default` when not given.
pub fn f(p: &ParamList, name: &str, default: f32) -> Res<f32> {
    let v = p.float(name)?.unwrap_or(default);
    if !v.is_finite() {
        let span = p.named(name).map(|p| p.value_span).unwrap_or_default();
        return Err(Diagnostic::error(span, format!("\"{name}\" must be finite, not {v}")));
    }
    Ok(v)
}

/// A finite positive float.
pub fn positive(p: &ParamList, name: &str, default: f32, span: Span) -> Res<f32> {
    let v = f(p, name, default)?;
    if v <= 0.0 {
        let at = p.named(name).map_or(span, |p| p.value_span);
        return Err(Diagnostic::error(at, format!("\"{name}\" must be positive, not {v}")));
    }
    Ok(v)
}
