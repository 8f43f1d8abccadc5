//! `PixelFilter "sinc" "float tau" 3` (radius 4): sinc windowed by a wider sinc, the
//! Lanczos filter (pbrt-v4's `LanczosSincFilter`).

use crate::parser::params::ParamList;
use crate::values::{self, Range, Res};

/// f(x) along an axis of radius r.
pub fn profile(p: &ParamList) -> Res<impl Fn(f32, f32) -> f32 + use<>> {
    let tau = values::float(p, "tau", 3.0, Range::Positive)?;
    Ok(move |x: f32, r: f32| if x.abs() > r { 0.0 } else { sinc(x) * sinc(x / tau) })
}

fn sinc(x: f32) -> f32 {
    let px = std::f32::consts::PI * x;
    if 1.0 - px * px == 1.0 { 1.0 } else { px.sin() / px }
}
