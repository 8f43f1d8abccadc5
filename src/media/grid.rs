//! Media whose density varies over a grid: pbrt-v3's `heterogeneous` and pbrt-v4's
//! `uniformgrid`, tracked against a majorant grid ([`super::tracking`]).
//!
//! ```text
//! MakeNamedMedium "smoke" "string type" "heterogeneous"        # v3 (v4: "uniformgrid")
//!     "integer nx" 2 "integer ny" 1 "integer nz" 1 "float density" [0.5 2]
//!     "point p0" [-1 0 -1] "point p1" [1 2 1] "rgb sigma_s" [1 1 1] "rgb sigma_a" [.1 .1 .1]
//! MakeNamedMedium "fire" "string type" "uniformgrid" ...       # v4 emission, one of:
//!     "rgb Le" [4 2 1] "float Lescale" [...nx·ny·nz values]      #   Le scaled per sample
//!     "float temperature" [...] "float temperatureoffset" 0 "float temperaturescale" 1
//! ```
//!
//! The density at a point is the trilinear interpolation of the samples
//! ([`super::sampled`]) over the box `p0`–`p1` in the medium's space (the CTM at its
//! statement). σa and σs (with each version's defaults, `scale`, and v3's presets)
//! multiply it; `g` is the phase function's; `nx·ny·nz` must match the number of
//! densities. pbrt-v3 tracks one σt and requires σa + σs equal in every channel,
//! otherwise using the first (so do we, with a warning); pbrt-v4 tracks every channel
//! (so do we, by spectral tracking).
//!
//! pbrt-v4's emission is σa·Le per unit length, Le being `Le` (normalised to luminance
//! 1 as lights are, times the `Lescale` grid) or a blackbody at the interpolated
//! `temperature` (minus `temperatureoffset` — pbrt reads `temperaturecutoff` as its
//! old name — times `temperaturescale`; none below 100 K), peak-normalised, times the
//! `Lescale` grid. pbrt-v4 does not normalise that blackbody as it does lights: its
//! film integrates the matching functions over wavelength in nanometres, so a spectrum
//! of 1 records as 106.86 (∫ȳ), and so do we (`--fix medium-emission`: as 1).

use super::MediumContext;
use super::lanes::{Emitted, Lanes, Sigma, sigma_t_bound};
use super::sampled::SampledGrid;
use super::tracking::{Field, Props, Tracked};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::values::{self, Range, Res};
use glam::{DMat4, DVec3, Vec3};
use std::sync::Arc;

pub const NAMES: [&str; 2] = ["heterogeneous", "uniformgrid"];

/// The density grid and its coefficients.
#[derive(Debug)]
pub struct DensityGrid {
    sigma_a: Sigma,
    sigma_s: Sigma,
    /// pbrt-v3's σt: the first channel of σa + σs in every channel (`None`: σa + σs).
    first_channel: Option<f32>,
    density: SampledGrid<f32>,
    emission: Option<Emission>,
}

/// Where pbrt-v4's grid emits.
#[derive(Debug)]
enum Emission {
    /// `Le` (normalised), times the `Lescale` grid.
    Le { le: Emitted, scale: SampledGrid<f32> },
    /// A blackbody at the temperature grid's value, times the `Lescale` grid.
    Temperature { kelvin: SampledGrid<f32>, offset: f32, scale: f32, le_scale: SampledGrid<f32>, table: Blackbody },
}

impl DensityGrid {
    /// σt per unit density at its largest (over wavelengths, or the tracked channel).
    fn sigma_t_bound(&self) -> f32 {
        self.first_channel.unwrap_or_else(|| sigma_t_bound(&self.sigma_a, &self.sigma_s))
    }
}

impl Field for DensityGrid {
    fn at(&self, u: Vec3, emission: bool, lanes: Lanes) -> Props {
        let d = self.density.lookup(u);
        let (sigma_a, sigma_s) = (self.sigma_a.at(lanes), self.sigma_s.at(lanes));
        let emitted = match (&self.emission, emission) {
            (Some(e), true) if d > 0.0 => sigma_a * d * e.le(u, lanes),
            _ => Vec3::ZERO,
        };
        let sigma_t = self.first_channel.map_or(sigma_a + sigma_s, Vec3::splat);
        Props { sigma_t: sigma_t * d, sigma_s: sigma_s * d, emitted }
    }

    fn majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
        self.density.max_over(lo, hi, |d| d) * self.sigma_t_bound()
    }

    fn fine_majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
        self.density.max_within(lo, hi, |d| d.max(0.0)) * self.sigma_t_bound()
    }

    fn emissive(&self) -> bool {
        self.emission.is_some()
    }

    fn emission_bound(&self) -> f32 {
        let Some(e) = &self.emission else { return 0.0 };
        let all = |g: &SampledGrid<f32>| g.max_over(Vec3::ZERO, Vec3::ONE, |v| v);
        let le = match e {
            Emission::Le { le, scale } => le.rgb.max_element() * all(scale),
            Emission::Temperature { le_scale, table, .. } => table.max() * all(le_scale),
        };
        self.sigma_a.rgb.max_element() * all(&self.density) * le
    }
}

impl Emission {
    fn le(&self, u: Vec3, lanes: Lanes) -> Vec3 {
        match self {
            Emission::Le { le, scale } => le.at(lanes) * scale.lookup(u).max(0.0),
            Emission::Temperature { kelvin, offset, scale, le_scale, table } => {
                let s = le_scale.lookup(u);
                if s <= 0.0 {
                    return Vec3::ZERO;
                }
                let kelvin = (kelvin.lookup(u) - offset) * scale;
                match lanes {
                    Some(p) => s * table.at_lanes(kelvin, p),
                    None => s * table.at(kelvin),
                }
            }
        }
    }
}

/// Reads a grid medium, placed by the CTM at its statement (`ctx.medium_to_world`).
pub fn read(p: &ParamList, ctx: &mut MediumContext) -> Res<Tracked> {
    let homogeneous = super::Homogeneous::coefficients(p, ctx, ctx.syntax == Syntax::V3)?;
    let (at, values) = grid_values(p, "density", ParamType::Float)?
        .ok_or_else(|| Diagnostic::error(ctx.at, "a grid medium needs \"float density\" values"))?;
    let n = resolution(p, values.len(), at)?;
    let box_to_world = ctx.medium_to_world * unit_to_box(p, at)?;
    let st = homogeneous.sigma_a.rgb + homogeneous.sigma_s.rgb;
    let emission = if ctx.syntax == Syntax::V4 { emission(p, ctx, n)? } else { None };
    let grid = DensityGrid {
        sigma_a: homogeneous.sigma_a,
        sigma_s: homogeneous.sigma_s,
        first_channel: first_channel(p, st, ctx, at),
        density: SampledGrid::new(n, values),
        emission,
    };
    super::finite(Tracked::new(box_to_world, homogeneous.phase, Arc::new(grid)), at)
}

/// `nx`, `ny`, `nz`, checked against the number of samples given (`count`, written at `at`).
pub fn resolution(p: &ParamList, count: usize, at: Span) -> Res<[usize; 3]> {
    let n = [p.int("nx")?.unwrap_or(1), p.int("ny")?.unwrap_or(1), p.int("nz")?.unwrap_or(1)];
    let want = n.iter().map(|&k| k.max(0) as i128).product::<i128>();
    if n.iter().any(|&k| k < 1) || want != count as i128 {
        let msg = format!("the grid has {count} values; nx·ny·nz = {}·{}·{} = {want} are needed", n[0], n[1], n[2]);
        return Err(Diagnostic::error(at, msg));
    }
    Ok(n.map(|k| k as usize))
}

/// The map from the unit cube to the box `p0`–`p1` (defaults 0 and 1) of the medium's
/// space; `at` locates the statement for errors without a parameter to point at.
pub fn unit_to_box(p: &ParamList, at: Span) -> Res<DMat4> {
    let p0 = p.point3("p0")?.unwrap_or([0.0; 3]);
    let p1 = p.point3("p1")?.unwrap_or([1.0; 3]);
    let (lo, hi) = (DVec3::from(p0.map(f64::from)), DVec3::from(p1.map(f64::from)));
    if (hi - lo).min_element() <= 0.0 {
        let at = values::span_of(p, "p1").or(values::span_of(p, "p0")).unwrap_or(at);
        return Err(Diagnostic::error(at, "\"p1\" must exceed \"p0\" in x, y and z"));
    }
    Ok(DMat4::from_translation(lo) * DMat4::from_scale(hi - lo))
}

/// pbrt-v3's σt where its channels differ: the first channel's (with an error
/// message, and it goes on). pbrt-v4 tracks each channel (`None`), and so does a
/// scene rendered spectrally.
fn first_channel(p: &ParamList, st: Vec3, ctx: &mut MediumContext, fallback: Span) -> Option<f32> {
    let grey = st.max_element() - st.min_element() <= 1e-6 * st.max_element();
    if ctx.syntax == Syntax::V4 || ctx.spectral.is_some() || grey {
        return None;
    }
    let at = values::span_of(p, "sigma_a").or(values::span_of(p, "sigma_s")).unwrap_or(fallback);
    let msg = "a grid medium needs the same σa + σs in every channel; as pbrt-v3, the first channel's is used";
    ctx.warnings.push(Diagnostic::warning(at, msg));
    Some(st.x)
}

/// The values of array `name` of type `ty` (every number finite and at least 0) and
/// where they are written.
pub fn grid_values(p: &ParamList, name: &str, ty: ParamType) -> Res<Option<(Span, Vec<f32>)>> {
    let Some(param) = p.array(name, ty)? else { return Ok(None) };
    param.mark_used();
    if let Some(v) = param.floats().iter().find(|v| !v.is_finite() || **v < 0.0) {
        return Err(Diagnostic::error(
            param.value_span,
            format!("\"{name}\" values must be finite and at least 0, not {v}"),
        ));
    }
    Ok(Some((param.value_span, param.floats().to_vec())))
}

/// A grid of `name` with `n` samples, or `None` where the parameter is not given.
fn optional_grid(p: &ParamList, name: &str, n: [usize; 3]) -> Res<Option<SampledGrid<f32>>> {
    let Some((span, values)) = grid_values(p, name, ParamType::Float)? else { return Ok(None) };
    let want: usize = n.iter().product();
    if values.len() != want {
        let msg = format!("\"{name}\" needs nx·ny·nz = {want} values, as \"density\" has; found {}", values.len());
        return Err(Diagnostic::error(span, msg));
    }
    Ok(Some(SampledGrid::new(n, values)))
}

/// pbrt-v4's emission: `Le` or `temperature` (not both), either times `Lescale`.
fn emission(p: &ParamList, ctx: &mut MediumContext, n: [usize; 3]) -> Res<Option<Emission>> {
    let le = super::read_le(p, ctx)?;
    let kelvin = optional_grid(p, "temperature", n)?;
    if let (Some(_), Some(_)) = (le, &kelvin) {
        let at = values::span_of(p, "temperature").unwrap_or(ctx.at);
        return Err(Diagnostic::error(at, "give \"Le\" or \"temperature\", not both"));
    }
    let le_scale = optional_grid(p, "Lescale", n)?.unwrap_or(SampledGrid::constant(1.0));
    let (offset, scale) = temperature_mapping(p)?;
    Ok(match (le, kelvin) {
        (Some(le), _) if le.max_element() > 0.0 => {
            Some(Emission::Le { le: Emitted::new(le, ctx.spectral), scale: le_scale })
        }
        (_, Some(kelvin)) => {
            let hottest = kelvin.max_over(Vec3::ZERO, Vec3::ONE, |t| ((t - offset) * scale).abs());
            let table = Blackbody::up_to(hottest, ctx.raw_emission);
            Some(Emission::Temperature { kelvin, offset, scale, le_scale, table })
        }
        _ => None,
    })
}

/// pbrt-v4's `temperatureoffset` and `temperaturescale` (T = (value − offset) · scale);
/// it reads `temperaturecutoff` as the default of the offset.
pub(super) fn temperature_mapping(p: &ParamList) -> Res<(f32, f32)> {
    let cutoff = values::float(p, "temperaturecutoff", 0.0, Range::Any)?;
    let offset = values::float(p, "temperatureoffset", cutoff, Range::Any)?;
    Ok((offset, values::float(p, "temperaturescale", 1.0, Range::Any)?))
}

/// Peak-normalised blackbody colours from 100 K to the hottest temperature, as
/// pbrt-v4's film records them, linearly interpolated (evaluating Planck's law at
/// every lookup would dominate tracking).
#[derive(Debug)]
pub(super) struct Blackbody {
    top: f32,
    rgb: Vec<Vec3>,
    /// What the film records for a spectrum of 1.
    raw: f32,
}

impl Blackbody {
    const ENTRIES: usize = 512;
    const HOTTEST: f32 = 1e6;

    /// The table to the hottest temperature, each colour times `raw` (what the film
    /// records for a spectrum of 1).
    pub(super) fn up_to(hottest: f32, raw: f32) -> Blackbody {
        // DEVIATION(pbrt): robustness. Planck's law underflows past ~1e30 K (NaN pixels
        // in pbrt); above 1e6 K the peak-normalised visible part is below 1e-9 of the
        // peak, so hotter is drawn as 1e6 K.
        let top = hottest.clamp(200.0, Self::HOTTEST);
        let rgb = (0..Self::ENTRIES)
            .map(|i| {
                let kelvin = 100.0 + (top - 100.0) * i as f32 / (Self::ENTRIES - 1) as f32;
                crate::spectrum::blackbody(kelvin) * raw
            })
            .collect();
        Blackbody { top, rgb, raw }
    }

    /// The peak-normalised blackbody at the lanes' wavelengths, times the same `raw`
    /// (pbrt-v4's `BlackbodySpectrum`, evaluated, as it does, at each lookup).
    pub(super) fn at_lanes(&self, kelvin: f32, p: &crate::spectrum::transport::PassSpectrum) -> Vec3 {
        if kelvin.is_nan() || kelvin <= 100.0 {
            return Vec3::ZERO;
        }
        let t = kelvin.min(self.top) as f64;
        p.values(|l| (crate::spectrum::daylight::blackbody_normalized(l as f64, t) as f32) * self.raw)
    }

    /// The largest channel in the table.
    pub(super) fn max(&self) -> f32 {
        self.rgb.iter().fold(0f32, |m, c| m.max(c.max_element()))
    }

    /// pbrt-v4: no emission at or below 100 K.
    pub(super) fn at(&self, kelvin: f32) -> Vec3 {
        if kelvin.is_nan() || kelvin <= 100.0 {
            return Vec3::ZERO;
        }
        if self.top <= 100.0 {
            return self.rgb[0];
        }
        let x = ((kelvin.min(self.top) - 100.0) / (self.top - 100.0)) * (Self::ENTRIES - 1) as f32;
        let i = (x as usize).min(Self::ENTRIES - 2);
        let f = x - i as f32;
        self.rgb[i] * (1.0 - f) + self.rgb[i + 1] * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_blackbody_table_matches_planck_between_its_entries() {
        let table = Blackbody::up_to(3000.0, crate::spectrum::CIE_Y_INTEGRAL);
        for k in [150.0, 1234.5, 2000.0, 2999.0] {
            let (got, want) = (table.at(k), crate::spectrum::blackbody(k) * crate::spectrum::CIE_Y_INTEGRAL);
            assert!((got - want).abs().max_element() <= 2e-3 * want.max_element().max(1e-3), "{k} K: {got} vs {want}");
        }
        assert_eq!(table.at(100.0), Vec3::ZERO);
    }
}
