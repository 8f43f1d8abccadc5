//! Typed parameter values: the checks every value of a light, material, texture or
//! shape gets as its type's module reads it. Inputs that may be textures
//! ([`TexValue`]) are resolved through the builder ([`Resolver`]).
//!
//! ```text
//! "float eta" 1.5              # exactly one finite number; eta must be positive
//! "rgb Kd" [.8 .2 .2]          # exactly three finite, non-negative numbers
//! "blackbody L" [6500]         # v4; v3 writes [6500 1] (temperature, scale)
//! "spectrum k" "metal-Au-k"    # a named spectrum, or an SPD file of (λ, value) pairs
//! "texture Kd" "checks"        # a texture of the right kind, defined somewhere
//! ```
//! Each lookup marks the parameter used, so what no lookup asked for is reported as
//! unused at its own span; a wrong type, arity or value is a located error.

use crate::parser::error::Diagnostic;
use crate::parser::params::{FloatValue, Param, ParamList, ParamType, SpectrumValue};
use crate::parser::source::Span;
use crate::spectrum::colorspace::ColorSpaceName;
use crate::spectrum::{EmissionSpectrum, Rgb, blackbody, named_spectrum, sampled_to_rgb, xyz_to_rgb};
use glam::Vec3;
use std::path::Path;
use std::sync::Arc;

pub use crate::imageio::ColorEncoding;

pub type Res<T> = Result<T, Diagnostic>;

/// What range a number must lie in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Range {
    Any,
    NonNegative,
    Positive,
}

impl Range {
    fn check(self, v: f32) -> Option<&'static str> {
        if !v.is_finite() {
            return Some("finite");
        }
        match self {
            Range::Any => None,
            Range::NonNegative => (v < 0.0).then_some("at least 0"),
            Range::Positive => (v <= 0.0).then_some("greater than 0"),
        }
    }
}

fn bad_value(p: &Param, what: &str, v: impl std::fmt::Display) -> Diagnostic {
    Diagnostic::error(p.value_span, format!("\"{} {}\" must be {what}, not {v}", p.type_name, p.name))
}

/// A float, checked against `range`; `default` when absent.
pub fn float(p: &ParamList, name: &str, default: f32, range: Range) -> Res<f32> {
    let Some(v) = p.float(name)? else { return Ok(default) };
    match range.check(v) {
        Some(what) => Err(bad_value(last(p, name), what, v)),
        None => Ok(v),
    }
}

/// The parameter a successful lookup of `name` just found.
fn last<'a>(p: &'a ParamList, name: &str) -> &'a Param {
    p.named(name).unwrap_or_else(|| unreachable!("\"{name}\" was just found"))
}

/// A float constant or a float texture's name.
pub fn float_or_texture(p: &ParamList, name: &str, range: Range) -> Res<Option<(FloatValue, Span)>> {
    let Some(v) = p.float_or_texture(name)? else { return Ok(None) };
    let param = last(p, name);
    if let FloatValue::Const(x) = v
        && let Some(what) = range.check(x)
    {
        return Err(bad_value(param, what, x));
    }
    Ok(Some((v, param.value_span)))
}

/// A spectrum parameter reduced to RGB, or a texture name.
pub enum SpectrumOrTexture {
    Rgb(Rgb),
    Texture(String),
}

/// What a spectrum lookup needs besides the parameter list.
pub struct SpectrumContext<'a> {
    /// Directory that SPD file names are relative to.
    pub base_dir: &'a Path,
    /// pbrt-v4 divides a light's or medium's emission spectrum by its luminance
    /// (`SpectrumToPhotometric`): blackbody, sampled, named and SPD spectra (not RGB,
    /// whose white already has luminance 1).
    pub normalize_emission: bool,
    pub files: &'a crate::limits::Files,
    /// The scene's colour space (pbrt-v4's `ColorSpace`): RGB given in the file is in
    /// it, and spectra reduce to it.
    pub space: ColorSpaceName,
}

/// A spectrum (`rgb`, `xyz`, `blackbody`, `spectrum`) or texture; every component must
/// be finite and, with `NonNegative`, at least 0.
pub fn spectrum(
    p: &ParamList,
    name: &str,
    ctx: &SpectrumContext,
    range: Range,
) -> Res<Option<(SpectrumOrTexture, Span)>> {
    let Some(v) = p.spectrum(name)? else { return Ok(None) };
    let param = last(p, name);
    let rgb = match v {
        SpectrumValue::Rgb(c) => {
            check3(param, c, range)?;
            Vec3::from(c)
        }
        SpectrumValue::Xyz(c) => {
            check3(param, c, Range::Any)?;
            in_space(xyz_to_rgb(c.map(f64::from)), ctx)
        }
        SpectrumValue::Blackbody { kelvin, scale } => in_space(blackbody_rgb(param, kelvin, scale, ctx)?, ctx),
        SpectrumValue::Sampled(pairs) => in_space(photometric(sampled(param, &pairs)?, ctx), ctx),
        SpectrumValue::Named(n) => in_space(photometric(named_or_file(param, &n, ctx)?, ctx), ctx),
        SpectrumValue::Texture(t) => return Ok(Some((SpectrumOrTexture::Texture(t), param.value_span))),
    };
    if let Some(what) = [rgb.x, rgb.y, rgb.z].into_iter().find_map(|c| range.check(c)) {
        return Err(bad_value(param, what, rgb));
    }
    Ok(Some((SpectrumOrTexture::Rgb(rgb), param.value_span)))
}

/// A spectrum that may not be a texture (light emission, `eta`/`k` of metals).
pub fn rgb(p: &ParamList, name: &str, ctx: &SpectrumContext, range: Range) -> Res<Option<Rgb>> {
    match spectrum(p, name, ctx, range)? {
        None => Ok(None),
        Some((SpectrumOrTexture::Rgb(c), _)) => Ok(Some(c)),
        Some((SpectrumOrTexture::Texture(_), span)) => {
            Err(Diagnostic::error(span, format!("\"{name}\" cannot be a texture here; give a spectrum")))
        }
    }
}

/// [`rgb`] with the spectrum's samples where it is given by them (a named metal, an SPD
/// file, (λ, value) pairs), for paths that carry wavelengths to read exactly.
pub fn rgb_and_samples(p: &ParamList, name: &str, ctx: &SpectrumContext, range: Range) -> Res<Option<Sampled>> {
    let Some(rgb) = self::rgb(p, name, ctx, range)? else { return Ok(None) };
    let metal = match p.spectrum(name)? {
        Some(SpectrumValue::Named(n)) => crate::spectrum::named_samples(&n),
        _ => None,
    };
    let samples = match metal {
        Some(t) => Some(t),
        None => sampled_pairs(p, name, ctx)?,
    };
    Ok(Some(Sampled { rgb, samples: samples.map(Into::into) }))
}

/// The spectrum of emission parameter `name` where it is given as one (a blackbody, a
/// named illuminant, (λ, value) pairs, an SPD file), for paths that carry wavelengths;
/// `None` for RGB and XYZ (which pbrt-v4 makes `RGBIlluminantSpectrum`s) and where the
/// parameter is absent. Call after [`rgb`] has checked the parameter.
pub fn emission_spectrum(p: &ParamList, name: &str, ctx: &SpectrumContext) -> Res<Option<EmissionSpectrum>> {
    use crate::spectrum::{daylight::blackbody_normalized, named::illuminant_named, piecewise_linear};
    let Some(v) = p.spectrum(name)? else { return Ok(None) };
    let param = last(p, name);
    let samples = match v {
        SpectrumValue::Blackbody { kelvin, .. } => {
            return Ok(EmissionSpectrum::new(|l| blackbody_normalized(l, kelvin as f64)));
        }
        SpectrumValue::Named(n) => match illuminant_named(&n) {
            Some(s) => return Ok(EmissionSpectrum::new(s)),
            None if named_spectrum(&n).is_some() => return Ok(None),
            None => spd_file(param, &n, ctx)?,
        },
        SpectrumValue::Sampled(pairs) => pairs,
        _ => return Ok(None),
    };
    Ok(EmissionSpectrum::new(|l| piecewise_linear(&samples, l as f32) as f64))
}

/// A constant spectrum: its RGB reduction, and its (λ, value) samples where it was
/// given by them.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampled {
    pub rgb: Rgb,
    pub samples: Option<Arc<[(f32, f32)]>>,
}

fn check3(p: &Param, c: [f32; 3], range: Range) -> Res<()> {
    match c.iter().find_map(|&x| range.check(x)) {
        Some(what) => Err(bad_value(p, what, format!("[{} {} {}]", c[0], c[1], c[2]))),
        None => Ok(()),
    }
}

fn blackbody_rgb(p: &Param, kelvin: f32, scale: Option<f32>, ctx: &SpectrumContext) -> Res<Rgb> {
    if !(kelvin.is_finite() && kelvin > 0.0) {
        return Err(bad_value(p, "a positive temperature in kelvin", kelvin));
    }
    if let Some(s) = scale.filter(|s| !s.is_finite()) {
        return Err(bad_value(p, "finite", s));
    }
    let b = blackbody(kelvin);
    Ok(match scale {
        Some(s) => b * s,
        None => photometric(b, ctx),
    })
}

/// A spectrum's linear sRGB reduction in the scene's colour space.
fn in_space(srgb: Rgb, ctx: &SpectrumContext) -> Rgb {
    Vec3::from(ctx.space.from_srgb(srgb.to_array()))
}

/// A spectrum's colour at luminance 1 where `ctx` asks for pbrt-v4's normalisation of
/// emission (a spectrum all but invisible is scaled by at most 10⁶; black stays black).
fn photometric(c: Rgb, ctx: &SpectrumContext) -> Rgb {
    if ctx.normalize_emission { c / crate::spectrum::luminance(c).max(1e-6) } else { c }
}

fn sampled(p: &Param, pairs: &[(f32, f32)]) -> Res<Rgb> {
    if let Some(&(l, v)) = pairs.iter().find(|(l, v)| !(l.is_finite() && v.is_finite())) {
        return Err(bad_value(p, "finite (wavelength, value) pairs", format!("({l}, {v})")));
    }
    if pairs.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err(Diagnostic::error(p.value_span, "sampled spectrum wavelengths must increase"));
    }
    Ok(sampled_to_rgb(pairs))
}

/// A named spectrum pbrt knows, or an SPD file: whitespace-separated (λ, value) pairs,
/// `#` comments (pbrt-v3's format).
fn named_or_file(p: &Param, name: &str, ctx: &SpectrumContext) -> Res<Rgb> {
    if let Some(c) = named_spectrum(name) {
        return Ok(c);
    }
    sampled(p, &spd_file(p, name, ctx)?)
}

/// The (λ, value) pairs of spectrum `name` when it is given by them, inline or as an
/// SPD file (not a named spectrum, RGB or blackbody), checked as [`spectrum`] checks
/// them.
pub fn sampled_pairs(p: &ParamList, name: &str, ctx: &SpectrumContext) -> Res<Option<Vec<(f32, f32)>>> {
    let Some(v) = p.spectrum(name)? else { return Ok(None) };
    let param = last(p, name);
    let pairs = match v {
        SpectrumValue::Sampled(pairs) => pairs,
        SpectrumValue::Named(n) if named_spectrum(&n).is_none() => spd_file(param, &n, ctx)?,
        _ => return Ok(None),
    };
    sampled(param, &pairs)?;
    Ok(Some(pairs))
}

/// The (λ, value) pairs of SPD file `name`.
fn spd_file(p: &Param, name: &str, ctx: &SpectrumContext) -> Res<Vec<(f32, f32)>> {
    let path = crate::parser::stmt::resolve_relative(ctx.base_dir, name);
    let at = |m: String| Diagnostic::error(p.value_span, m);
    let bytes = ctx
        .files
        .read(&path)
        .map_err(|e| at(format!("\"{name}\" is neither a named spectrum nor a readable SPD file: {e}")))?;
    let values = spd_numbers(&bytes, name).map_err(at)?;
    if values.is_empty() || values.len() % 2 != 0 {
        return Err(at(format!("{name}: an SPD file needs (wavelength, value) pairs, found {} numbers", values.len())));
    }
    Ok(values.chunks_exact(2).map(|c| (c[0], c[1])).collect())
}

/// The numbers of SPD file `name` (its bytes): whitespace-separated, `#` comments.
pub fn spd_numbers(bytes: &[u8], name: &str) -> Result<Vec<f32>, String> {
    let text = String::from_utf8_lossy(bytes);
    let mut values = Vec::new();
    for line in text.lines() {
        for word in line.split('#').next().unwrap_or("").split_whitespace() {
            values.push(word.parse().map_err(|_| format!("{name}: \"{word}\" is not a number"))?);
        }
    }
    Ok(values)
}

/// An SPD file as pbrt-v3's `ReadFloatFile` scans it.
pub struct FloatFileV3 {
    pub values: Vec<f32>,
    /// Characters outside numbers, comments and whitespace: skipped, each with a
    /// warning.
    pub skipped: usize,
    /// The file ends inside a number, which is then lost.
    pub cut_off: bool,
}

/// Scans `bytes` as pbrt-v3 scans a float file. A number starts at a digit, `.`, `-`
/// or `+` and runs over digits, `.`, `e`, `-` and `+`; the character that ends it is
/// consumed with it; it is read as C's `atof` reads it (its longest numeric prefix,
/// else 0). `#` starts a comment to the line's end.
pub fn pbrt_v3_float_file(bytes: &[u8]) -> FloatFileV3 {
    let mut out = FloatFileV3 { values: Vec::new(), skipped: 0, cut_off: false };
    let (mut number, mut comment) = (None::<usize>, false);
    for (i, &c) in bytes.iter().enumerate() {
        if let Some(start) = number {
            if !(c.is_ascii_digit() || b".e-+".contains(&c)) {
                out.values.push(atof_prefix(&bytes[start..i]) as f32);
                number = None;
            }
        } else if comment {
            comment = c != b'\n';
        } else if c.is_ascii_digit() || b".-+".contains(&c) {
            number = Some(i);
        } else if c == b'#' {
            comment = true;
        } else if !c.is_ascii_whitespace() {
            out.skipped += 1;
        }
    }
    out.cut_off = number.is_some();
    out
}

/// C's `atof` on ASCII text: the longest prefix that is a decimal number, else 0.
fn atof_prefix(text: &[u8]) -> f64 {
    let text = std::str::from_utf8(text).unwrap_or("");
    (1..=text.len()).rev().find_map(|n| text[..n].parse::<f64>().ok()).unwrap_or(0.0)
}

/// A string from a fixed set of choices.
pub fn choice<'a>(p: &ParamList, name: &str, default: &'a str, choices: &[&'a str]) -> Res<&'a str> {
    let Some(v) = p.string(name)? else { return Ok(default) };
    choices.iter().find(|c| **c == v).copied().ok_or_else(|| {
        Diagnostic::error(last(p, name).value_span, format!("\"{name}\" must be one of {choices:?}, not \"{v}\""))
    })
}

/// Warns once per parameter that is read but has no effect yet, at its span.
pub fn ignored(p: &ParamList, names: &[&str], why: &str, warnings: &mut Vec<Diagnostic>) {
    for param in p.params.iter().filter(|x| names.contains(&x.name.as_str())) {
        param.mark_used();
        let msg = format!("\"{} {}\" is ignored: {why}", param.type_name, param.name);
        warnings.push(Diagnostic::warning(param.span, msg));
    }
}

/// Marks parameters that change nothing in an SPPM render (sampling hints) as used.
pub fn no_effect(p: &ParamList, names: &[&str]) {
    p.params.iter().filter(|x| names.contains(&x.name.as_str())).for_each(Param::mark_used);
}

/// The `encoding` parameter, `default` where it is not given; a located error where it
/// names no encoding (pbrt-v4 refuses it too).
pub fn encoding(p: &ParamList, default: ColorEncoding, at: Span) -> Res<ColorEncoding> {
    let Some(e) = p.string("encoding")? else { return Ok(default) };
    let at = span_of(p, "encoding").unwrap_or(at);
    match e.split_whitespace().collect::<Vec<_>>()[..] {
        ["linear"] => Ok(ColorEncoding::Linear),
        ["sRGB"] => Ok(ColorEncoding::Srgb),
        ["gamma", g] => match g.parse::<f32>() {
            Ok(g) if g != 0.0 && g.is_finite() => Ok(ColorEncoding::Gamma(g.to_bits())),
            _ => Err(Diagnostic::error(at, format!("\"{g}\" is not a gamma value for \"encoding\""))),
        },
        _ => Err(Diagnostic::error(
            at,
            format!("\"{e}\" is not a colour encoding (\"linear\", \"sRGB\" or \"gamma <value>\")"),
        )),
    }
}

/// The span of a parameter if present (for notes about it).
pub fn span_of(p: &ParamList, name: &str) -> Option<Span> {
    p.named(name).map(|x| x.span)
}

/// Is `name` given with any of `types`? (Does not mark it used.)
pub fn given(p: &ParamList, name: &str, types: &[ParamType]) -> bool {
    p.named(name).is_some_and(|x| types.contains(&x.ty))
}

/// A spectrum- or float-valued input: a constant (floats as grey) or a texture, by its
/// index in the scene description's `textures`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TexValue {
    Const(Rgb),
    Texture(u32),
}

/// What reading materials and textures needs from the scene builder.
pub trait Resolver {
    /// The float or spectrum texture `name`, built on first use; `at` is the span of
    /// the parameter naming it. `None`: a v3 file names a texture defined nowhere, and
    /// the parameter takes its default (as in pbrt-v3, with a warning).
    fn texture(&mut self, name: &str, float: bool, at: Span) -> Res<Option<u32>>;
    fn approximate(&mut self, at: Span, what: String, how: super::approx::Approx);
    /// A located warning (what pbrt warns about and renders anyway).
    fn warn(&mut self, at: Span, message: String);
    /// The pbrt version the file is read as (for types both versions have).
    fn syntax(&self) -> crate::parser::Syntax;
    /// The named material `name`, built on first use (for `mix`); its built index.
    fn named_material(&mut self, name: &str, at: Span) -> Res<u32>;
    /// The type (as written) of a built material (a [`Resolver::named_material`] index).
    fn material_type(&self, built: u32) -> Option<&str>;
    fn spectra(&self) -> SpectrumContext<'_>;
    /// An image for `imagemap` (cached); errors are plain messages.
    fn image(&mut self, name: &str) -> Result<Arc<crate::imageio::Texels>, String>;
    /// A grey image for a float `imagemap` (cached by name and `grey`).
    fn grey_image(&mut self, name: &str, grey: crate::imageio::Grey) -> Result<Arc<crate::imageio::Texels>, String>;
}

/// A spectrum input: constant (non-negative) or a spectrum texture.
pub fn spectrum_input(p: &ParamList, name: &str, default: f32, r: &mut dyn Resolver) -> Res<TexValue> {
    let found = spectrum(p, name, &r.spectra(), Range::NonNegative)?;
    Ok(match found {
        None => TexValue::Const(Vec3::splat(default)),
        Some((SpectrumOrTexture::Rgb(c), _)) => TexValue::Const(c),
        Some((SpectrumOrTexture::Texture(t), at)) => match r.texture(&t, false, at)? {
            Some(i) => TexValue::Texture(i),
            None => TexValue::Const(Vec3::splat(default)),
        },
    })
}

/// A float input: constant (in `range`) or a float texture.
pub fn float_input(p: &ParamList, name: &str, default: f32, range: Range, r: &mut dyn Resolver) -> Res<TexValue> {
    Ok(match float_or_texture(p, name, range)? {
        None => TexValue::Const(Vec3::splat(default)),
        Some((FloatValue::Const(v), _)) => TexValue::Const(Vec3::splat(v)),
        Some((FloatValue::Texture(t), at)) => match r.texture(&t, true, at)? {
            Some(i) => TexValue::Texture(i),
            None => TexValue::Const(Vec3::splat(default)),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// pbrt-v3's scanner, case by case: the character that ends a number goes with it
    /// (so a `#` right after a number starts no comment), `atof` reads a prefix, other
    /// characters are skipped one by one, and a number the file ends in is lost.
    #[test]
    fn float_files_scan_as_pbrt_v3_scans_them() {
        let scan = |t: &str| {
            let f = pbrt_v3_float_file(t.as_bytes());
            (f.values, f.skipped, f.cut_off)
        };
        assert_eq!(scan("400 0.5\n# a comment 7\n700 .25\n"), (vec![400.0, 0.5, 700.0, 0.25], 0, false));
        assert_eq!(scan("1e 2.5.1 -+ 3e-1x\n"), (vec![1.0, 2.5, 0.0, 0.3], 0, false));
        assert_eq!(scan("1#x 2 ab\n"), (vec![1.0, 2.0], 3, false));
        assert_eq!(scan("400 0.5\n700 1"), (vec![400.0, 0.5, 700.0], 0, true));
        assert_eq!(scan(""), (vec![], 0, false));
    }
}
