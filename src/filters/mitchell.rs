//! `PixelFilter "mitchell" "float B" 0.3333 "float C" 0.3333` (radius 2): Mitchell and
//! Netravali's cubic, negative near its edge (pbrt-v4's `MitchellFilter`).

use crate::parser::params::ParamList;
use crate::values::{self, Range, Res};

/// f(x) along an axis of radius r.
pub fn profile(p: &ParamList) -> Res<impl Fn(f32, f32) -> f32 + use<>> {
    let b = values::float(p, "B", 1.0 / 3.0, Range::Any)?;
    let c = values::float(p, "C", 1.0 / 3.0, Range::Any)?;
    Ok(move |x: f32, r: f32| cubic(2.0 * x / r, b, c))
}

fn cubic(x: f32, b: f32, c: f32) -> f32 {
    let x = x.abs();
    let v = if x <= 1.0 {
        (12.0 - 9.0 * b - 6.0 * c) * x.powi(3) + (-18.0 + 12.0 * b + 6.0 * c) * x * x + (6.0 - 2.0 * b)
    } else if x <= 2.0 {
        (-b - 6.0 * c) * x.powi(3) + (6.0 * b + 30.0 * c) * x * x + (-12.0 * b - 48.0 * c) * x + (8.0 * b + 24.0 * c)
    } else {
        0.0
    };
    v / 6.0
}
