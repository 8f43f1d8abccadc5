//! `LightSource` and `AreaLightSource` statements to typed light descriptions, with
//! each version's meaning settled here: positions in world space, emission in RGB with
//! `scale`, `power` and `illuminance` applied.
//!
//! ```text
//! LightSource "point" "rgb I" [10 10 10] "point from" [0 4 0]    # v3: from is a world offset
//! LightSource "spot" "blackbody I" [5500 125] "point from" [0 5 9] "point to" [-5 2.75 0]
//!             "float coneangle" 30 "float conedeltaangle" 5        # v3 quartic / v4 smoothstep falloff
//! LightSource "distant" "point3 from" [0 0 0] "point3 to" [0 0 1] "rgb L" [3 3 3] "float illuminance" 2
//! LightSource "infinite" "rgb L" [.1 .1 .1]      # or "string mapname" (v3) / "filename" (v4)
//! AreaLightSource "diffuse" "rgb L" [4 4 4] "bool twosided" true "float power" 100   # v4 power
//! ```
//! v4 normalises blackbody emission to luminance 1 (v3 multiplies the peak-normalised
//! spectrum by its second number). Emission must be finite and non-negative.

use super::values::{self, Range, Res, SpectrumContext};
use crate::imageio::RgbImage;
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::spectrum::{Rgb, luminance};
use glam::{DMat3, DMat4, DVec3, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;

/// An equirectangular environment map and its orientation.
#[derive(Clone, Debug)]
pub struct EnvMapDesc {
    /// The file name as the scene wrote it, and where it was read from.
    pub filename: String,
    pub path: std::path::PathBuf,
    pub image: Arc<RgbImage>,
    pub world_from_light: DMat3,
}

/// A light source, in world space.
#[derive(Clone, Debug)]
pub enum LightKind {
    Point {
        position: DVec3,
        i: Rgb,
    },
    Spot {
        position: DVec3,
        direction: DVec3,
        i: Rgb,
        cos_total: f32,
        cos_start: f32,
        smooth_falloff: bool,
    },
    /// `toward_light` is the unit direction light comes from.
    Distant {
        toward_light: DVec3,
        l: Rgb,
    },
    /// `l` scales the map when there is one.
    Infinite {
        l: Rgb,
        map: Option<EnvMapDesc>,
    },
}

/// A `LightSource` of a supported type.
#[derive(Clone, Debug)]
pub struct LightDesc {
    pub kind: LightKind,
    /// The CTM at the statement.
    pub world_from_light: DMat4,
}

/// A diffuse `AreaLightSource` some shape uses.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLightDesc {
    pub l: Rgb,
    pub two_sided: bool,
    /// v4 `power` (watts): the emission is scaled so the whole shape emits this much.
    pub power: Option<f32>,
}

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
fn emission(p: &ParamList, name: &str, spectra: &SpectrumContext) -> Res<Rgb> {
    let l = values::rgb(p, name, spectra, Range::NonNegative)?.unwrap_or(Vec3::ONE);
    let scale = if values::given(p, "scale", &[ParamType::Float]) {
        Vec3::splat(values::float(p, "scale", 1.0, Range::NonNegative)?)
    } else {
        values::rgb(p, "scale", spectra, Range::NonNegative)?.unwrap_or(Vec3::ONE)
    };
    Ok(l * scale)
}

fn point3(p: &ParamList, name: &str, default: [f32; 3]) -> Res<DVec3> {
    let v = p.point3(name)?.unwrap_or(default);
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        let param = p.named(name).map_or(Span::default(), |q| q.value_span);
        return Err(Diagnostic::error(param, format!("\"{name}\" must be finite, not {x}")));
    }
    Ok(DVec3::from(v.map(f64::from)))
}

/// v4's `power` in watts, when given and positive (≤ 0 means "not given", as in pbrt).
fn power(p: &ParamList) -> Res<Option<f32>> {
    Ok(Some(values::float(p, "power", -1.0, Range::Any)?).filter(|&w| w > 0.0))
}

/// The unit direction from `from` to `to` in world space.
fn direction(p: &ParamList, m: &DMat4, span: Span) -> Res<(DVec3, DVec3)> {
    let (from, to) = (point3(p, "from", [0.0; 3])?, point3(p, "to", [0.0, 0.0, 1.0])?);
    let d = m.transform_vector3(to - from).try_normalize().ok_or_else(|| {
        Diagnostic::error(span, "\"from\" and \"to\" must be different points (they give the light's direction)")
    })?;
    Ok((from, d))
}

/// A `LightSource` of type `ty`, or `None` for a type we do not render.
pub fn light(ty: &str, p: &ParamList, m: &DMat4, span: Span, ctx: &mut LightContext) -> Res<Option<LightKind>> {
    values::no_effect(p, &["samples", "nsamples"]);
    Ok(Some(match ty {
        "point" => {
            let from = point3(p, "from", [0.0; 3])?;
            // v3 adds `from` in world space after the CTM; v4 transforms it.
            let position = match ctx.syntax {
                Syntax::V3 => m.transform_point3(DVec3::ZERO) + from,
                Syntax::V4 => m.transform_point3(from),
            };
            let mut i = emission(p, "I", &ctx.spectra)?;
            if let Some(w) = power(p)? {
                i *= w / (4.0 * std::f32::consts::PI);
            }
            LightKind::Point { position, i }
        }
        "spot" => {
            let (from, direction) = direction(p, m, span)?;
            let cone = values::float(p, "coneangle", 30.0, Range::NonNegative)?;
            let delta = values::float(p, "conedeltaangle", 5.0, Range::NonNegative)?;
            let (cos_total, cos_start) = (cone.to_radians().cos(), (cone - delta).to_radians().cos());
            let mut i = emission(p, "I", &ctx.spectra)?;
            if let Some(w) = power(p)? {
                let solid = 2.0 * std::f32::consts::PI * (1.0 - 0.5 * (cos_start + cos_total));
                i *= w / solid.max(1e-9);
            }
            let position = m.transform_point3(from);
            LightKind::Spot { position, direction, i, cos_total, cos_start, smooth_falloff: ctx.syntax == Syntax::V4 }
        }
        "distant" => {
            let (_, d) = direction(p, m, span)?;
            let mut l = emission(p, "L", &ctx.spectra)?;
            if let Some(e) = Some(values::float(p, "illuminance", -1.0, Range::Any)?).filter(|&e| e > 0.0) {
                l *= e / luminance(l).max(1e-9);
            }
            LightKind::Distant { toward_light: -d, l }
        }
        "infinite" => infinite(p, m, ctx)?,
        _ => return Ok(None),
    }))
}

fn infinite(p: &ParamList, m: &DMat4, ctx: &mut LightContext) -> Res<LightKind> {
    values::ignored(p, &["portal"], "portals are not supported; the whole map is sampled", ctx.warnings);
    let mut l = emission(p, "L", &ctx.spectra)?;
    let name = match p.string("mapname")? {
        Some(n) => Some((n, "mapname")),
        None => p.string("filename")?.map(|n| (n, "filename")),
    };
    let map = match name.filter(|(n, _)| !n.is_empty()) {
        None => None,
        Some((filename, param)) => {
            let at = p.named(param).map_or(Span::default(), |q| q.value_span);
            match (ctx.image)(&filename) {
                Ok(image) => {
                    let path = crate::parser::stmt::resolve_relative(ctx.spectra.base_dir, &filename);
                    Some(EnvMapDesc { filename, path, image, world_from_light: DMat3::from_mat4(*m) })
                }
                Err(e) => {
                    (ctx.missing)(at, format!("environment map ({e})"));
                    None
                }
            }
        }
    };
    if let Some(e) = Some(values::float(p, "illuminance", -1.0, Range::Any)?).filter(|&e| e > 0.0) {
        // Scale so that an upward-facing surface (light-space +z) receives e.
        let up = match &map {
            None => std::f32::consts::PI * luminance(l),
            Some(env) => upper_hemisphere_illuminance(&env.image) * luminance(l),
        };
        l *= e / up.max(1e-9);
    }
    Ok(LightKind::Infinite { l, map })
}

/// ∫ over the map's upper hemisphere (θ < π/2) of luminance · cos θ dω, for the
/// equirectangular mapping (row = θ).
fn upper_hemisphere_illuminance(img: &RgbImage) -> f32 {
    let (w, h) = (img.width, img.height);
    let cell = (PI / h as f64) * (2.0 * PI / w as f64);
    let mut sum = 0.0;
    for y in 0..h {
        let theta = (y as f64 + 0.5) / h as f64 * PI;
        if theta >= PI / 2.0 {
            break;
        }
        let row: f64 = img.pixels[y * w..(y + 1) * w].iter().map(|px| luminance(Vec3::from(*px)) as f64).sum();
        sum += row * theta.cos() * theta.sin() * cell;
    }
    sum as f32
}

/// A `diffuse` (v3 also `area`) area light, or `None` for other types.
pub fn area_light(
    ty: &str,
    p: &ParamList,
    spectra: &SpectrumContext,
    warnings: &mut Vec<Diagnostic>,
) -> Res<Option<AreaLightDesc>> {
    if !matches!(ty, "diffuse" | "area") {
        return Ok(None);
    }
    values::no_effect(p, &["samples", "nsamples"]);
    let why = "image area lights are not supported; the light emits L uniformly";
    values::ignored(p, &["filename"], why, warnings);
    Ok(Some(AreaLightDesc {
        l: emission(p, "L", spectra)?,
        two_sided: p.bool("twosided")?.unwrap_or(false),
        power: power(p)?,
    }))
}
