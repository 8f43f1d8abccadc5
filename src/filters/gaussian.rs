//! `PixelFilter "gaussian" "float sigma" 0.5` (radius 1.5): a Gaussian less its value
//! at the radius, so that it falls to zero there (pbrt-v4's `GaussianFilter`).

use crate::parser::params::ParamList;
use crate::values::{self, Range, Res};

/// f(x) along an axis of radius r.
pub fn profile(p: &ParamList) -> Res<impl Fn(f32, f32) -> f32 + use<>> {
    let sigma = values::float(p, "sigma", 0.5, Range::Positive)?;
    let g = move |x: f32| (-x * x / (2.0 * sigma * sigma)).exp() / (2.0 * std::f32::consts::PI * sigma * sigma).sqrt();
    Ok(move |x: f32, r: f32| (g(x) - g(r)).max(0.0))
}
