//! Parameters several light types read alike: emission with `scale`, v4's `power`,
//! finite points and the `from`/`to` direction.

use crate::imageio::RgbImage;
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::{self, Range, Res, SpectrumContext};
use glam::{DMat4, DVec3, Vec3};
use std::sync::Arc;

/// What reading a light needs besides its parameters.
pub struct LightContext<'a> {
    pub syntax: Syntax,
    pub spectra: SpectrumContext<'a>,
    /// Reads an image (cached) for environment maps; errors are plain messages.
    pub image: &'a mut dyn FnMut(&str) -> Result<Arc<RgbImage>, String>,
    pub warnings: &'a mut Vec<Diagnostic>,
    /// Notes an image that cannot be read (the light then uses its constant `L`).
    pub missing: &'a mut dyn FnMut(Span, String),
}

/// Light emission: the spectrum `name` (default 1) times `scale` (a float, or in v3 a
/// spectrum).
pub fn emission(p: &ParamList, name: &str, spectra: &SpectrumContext, at: Span) -> Res<Rgb> {
    let l = values::rgb(p, name, spectra, Range::NonNegative)?.unwrap_or(Vec3::ONE);
    in_range(p, name, l * scale(p, spectra)?, at)
}

/// A light's `scale`: a float, or in v3 a spectrum (default 1; finite, as read).
pub fn scale(p: &ParamList, spectra: &SpectrumContext) -> Res<Rgb> {
    Ok(match values::given(p, "scale", &[ParamType::Float]) {
        true => Vec3::splat(values::float(p, "scale", 1.0, Range::NonNegative)?),
        false => values::rgb(p, "scale", spectra, Range::NonNegative)?.unwrap_or(Vec3::ONE),
    })
}

/// A light's emission after its `scale`, `power` or `illuminance`, which must stay
/// within f32's range: an error at the parameter that scaled it (or at `name`, or at
/// the statement, `at`).
// DEVIATION(pbrt): robustness. pbrt-v3 writes Inf pixels for such a light; ours lit
// nothing with it in SPPM and wrote NaN in vcm.
pub fn in_range(p: &ParamList, name: &str, v: Rgb, at: Span) -> Res<Rgb> {
    if v.is_finite() {
        return Ok(v);
    }
    let mut factors = ["scale", "power", "illuminance"].into_iter().filter(|n| p.named(n).is_some());
    let times: String = factors.clone().map(|f| format!(" times \"{f}\"")).collect();
    let at = factors.next_back().or(Some(name)).and_then(|n| p.named(n)).map_or(at, |q| q.value_span);
    let msg = format!("\"{name}\"{times} is beyond the range of 32-bit floats");
    Err(Diagnostic::error(at, msg))
}

pub fn point3(p: &ParamList, name: &str, default: [f32; 3]) -> Res<DVec3> {
    let v = p.point3(name)?.unwrap_or(default);
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        let param = p.named(name).map_or(Span::default(), |q| q.value_span);
        return Err(Diagnostic::error(param, format!("\"{name}\" must be finite, not {x}")));
    }
    Ok(DVec3::from(v.map(f64::from)))
}

/// A light's image must be finite everywhere, as pbrt-v4 requires of every emitting
/// image: a NaN or infinite texel would spread through every pixel it lights (pbrt-v3
/// does not check). `at`: the file name's span.
pub fn finite_image(img: &RgbImage, name: &str, at: Span) -> Res<()> {
    let Some(i) = img.pixels.iter().position(|p| p.iter().any(|c| !c.is_finite())) else { return Ok(()) };
    let (x, y, texel) = (i % img.width.max(1), i / img.width.max(1), img.pixels[i]);
    let msg = format!("\"{name}\": texel ({x}, {y}) is {texel:?}; an image that emits light must be finite");
    Err(Diagnostic::error(at, msg))
}

/// v4's `power` in watts, when given and positive (≤ 0 means "not given", as in pbrt).
#[inline]
pub fn power(p: &ParamList) -> Res<Option<f32>> {
    Ok(Some(values::float(p, "power", -1.0, Range::Any)?).filter(|&w| w > 0.0))
}

/// v4's `illuminance` (distant and infinite lights), when given and positive.
pub fn illuminance(p: &ParamList) -> Res<Option<f32>> {
    Ok(Some(values::float(p, "illuminance", -1.0, Range::Any)?).filter(|&e| e > 0.0))
}

/// `from` and the unit direction from `from` to `to` in world space.
pub fn direction(p: &ParamList, m: &DMat4, span: Span) -> Res<(DVec3, DVec3)> {
    let (from, to) = (point3(p, "from", [0.0; 3])?, point3(p, "to", [0.0, 0.0, 1.0])?);
    let d = m.transform_vector3(to - from).try_normalize().ok_or_else(|| {
        Diagnostic::error(span, "\"from\" and \"to\" must be different points (they give the light's direction)")
    })?;
    Ok((from, d))
}
