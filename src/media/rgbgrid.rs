//! pbrt-v4's `rgbgrid`: σa, σs and emission each given per sample as RGB.
//!
//! ```text
//! MakeNamedMedium "dye" "string type" "rgbgrid" "integer nx" 2 "integer ny" 1 "integer nz" 1
//!     "rgb sigma_a" [0.5 0.1 0.1  0.1 0.1 0.5] "rgb sigma_s" [1 1 1  1 1 1]
//!     "rgb Le" [0 0 0  2 1 0] "float Lescale" 1 "float scale" 2 "float g" 0
//!     "point3 p0" [-1 0 -1] "point3 p1" [1 1 1]
//! ```
//!
//! Either of `sigma_a` and `sigma_s` may be left out (it is then 1 everywhere), not
//! both; `Le` needs `sigma_a`, since emission is σa·Le per unit length. Every grid has
//! `nx·ny·nz` samples over the box `p0`–`p1`, interpolated trilinearly; `scale`
//! multiplies σa and σs, `Lescale` the emission. No density multiplies them. Unlike a
//! light's or a homogeneous medium's, pbrt-v4 does not normalise this `Le`: its film
//! records an RGB illuminant of 1 as 106.86 (∫ȳ over nanometres), and so do we
//! (`--fix medium-emission`: as 1).

use super::MediumContext;
use super::lanes::{Lanes, spectrum_max};
use super::phase::HenyeyGreenstein;
use super::sampled::SampledGrid;
use super::tracking::{Field, Props, Tracked};
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::spectrum::colorspace::ColorSpaceName;
use crate::spectrum::sigmoid::{RgbIlluminantSpectrum, RgbUnboundedSpectrum};
use crate::values::{self, Range, Res};
use glam::Vec3;
use std::sync::Arc;

pub const NAME: &str = "rgbgrid";

#[derive(Debug)]
pub struct RgbGrid {
    sigma_a: Option<SampledGrid<Vec3>>,
    sigma_s: Option<SampledGrid<Vec3>>,
    scale: f32,
    le: Option<SampledGrid<Vec3>>,
    /// `Lescale` times what the film records for an unnormalised spectrum of 1.
    le_scale: f32,
    /// The samples' spectra, where the scene renders spectrally.
    spectra: Option<Spectra>,
}

impl RgbGrid {
    /// σa, σs and Le interpolated in RGB.
    fn at_rgb(&self, u: Vec3, emission: bool) -> [Vec3; 3] {
        let get = |g: &Option<SampledGrid<Vec3>>| g.as_ref().map_or(Vec3::ONE, |g| g.lookup(u));
        let le = match (&self.le, emission) {
            (Some(le), true) => le.lookup(u),
            _ => Vec3::ZERO,
        };
        [get(&self.sigma_a), get(&self.sigma_s), le]
    }
}

/// Each sample's colours as pbrt-v4's spectra, fitted once.
#[derive(Debug)]
struct Spectra {
    sigma_a: Option<SampledGrid<RgbUnboundedSpectrum>>,
    sigma_s: Option<SampledGrid<RgbUnboundedSpectrum>>,
    le: Option<SampledGrid<RgbIlluminantSpectrum>>,
}

impl Spectra {
    fn new(g: &RgbGrid, space: ColorSpaceName) -> Spectra {
        let sigma = |g: &Option<SampledGrid<Vec3>>| {
            g.as_ref().map(|g| g.map(|v| RgbUnboundedSpectrum::new(space, v.max(Vec3::ZERO).to_array())))
        };
        let le = g.le.as_ref().map(|g| g.map(|v| RgbIlluminantSpectrum::new(space, v.max(Vec3::ZERO).to_array())));
        Spectra { sigma_a: sigma(&g.sigma_a), sigma_s: sigma(&g.sigma_s), le }
    }

    /// σa, σs and Le: each sample's spectrum at the lanes' wavelengths, interpolated
    /// (pbrt-v4's `RGBGridMedium::SamplePoint`).
    fn at(&self, u: Vec3, emission: bool, p: &crate::spectrum::transport::PassSpectrum) -> [Vec3; 3] {
        let get = |g: &Option<SampledGrid<RgbUnboundedSpectrum>>| {
            g.as_ref().map_or(Vec3::ONE, |g| g.lookup_by(u, |s| p.values(|l| s.eval(l))))
        };
        let le = match (&self.le, emission) {
            (Some(le), true) => le.lookup_by(u, |s| p.values(|l| s.eval(l))),
            _ => Vec3::ZERO,
        };
        [get(&self.sigma_a), get(&self.sigma_s), le]
    }

    /// The largest σa plus the largest σs at any wavelength over the samples that
    /// reach the box.
    fn majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
        let max = |g: &Option<SampledGrid<RgbUnboundedSpectrum>>| {
            g.as_ref().map_or(1.0, |g| g.max_over(lo, hi, |s| spectrum_max(&s)))
        };
        max(&self.sigma_a) + max(&self.sigma_s)
    }
}

impl Field for RgbGrid {
    fn at(&self, u: Vec3, emission: bool, lanes: Lanes) -> Props {
        let [a, s, le] = match (lanes, &self.spectra) {
            (Some(p), Some(spectra)) => spectra.at(u, emission, p),
            _ => self.at_rgb(u, emission),
        };
        let (sigma_a, sigma_s) = (self.scale * a, self.scale * s);
        let emitted = if le == Vec3::ZERO { Vec3::ZERO } else { sigma_a * self.le_scale * le };
        Props { sigma_t: sigma_a + sigma_s, sigma_s, emitted }
    }

    /// pbrt-v4's bound: the largest σa channel plus the largest σs channel (of the
    /// spectra, at any wavelength, when spectral).
    fn majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
        if let Some(spectra) = &self.spectra {
            return self.scale * spectra.majorant(lo, hi);
        }
        let max = |g: &Option<SampledGrid<Vec3>>| g.as_ref().map_or(1.0, |g| g.max_over(lo, hi, |v| v.max_element()));
        self.scale * (max(&self.sigma_a) + max(&self.sigma_s))
    }

    fn emissive(&self) -> bool {
        self.le.is_some() && self.le_scale > 0.0
    }

    fn emission_bound(&self) -> f32 {
        let max = |g: &Option<SampledGrid<Vec3>>| {
            g.as_ref().map_or(1.0, |g| g.max_over(Vec3::ZERO, Vec3::ONE, |v| v.max_element()))
        };
        match &self.le {
            Some(_) => self.scale * max(&self.sigma_a) * self.le_scale * max(&self.le),
            None => 0.0,
        }
    }
}

/// Reads an `rgbgrid`, placed by the CTM at its statement.
pub fn read(p: &ParamList, ctx: &mut MediumContext) -> Res<Tracked> {
    let sigma_a = rgb_values(p, "sigma_a")?;
    let sigma_s = rgb_values(p, "sigma_s")?;
    let le = rgb_values(p, "Le")?;
    let Some((at, count)) = sigma_a.as_ref().or(sigma_s.as_ref()).map(|(s, v)| (*s, v.len())) else {
        return Err(Diagnostic::error(ctx.at, "an rgbgrid medium needs \"rgb sigma_a\" or \"rgb sigma_s\" values"));
    };
    if let (Some((span, _)), None) = (&le, &sigma_a) {
        return Err(Diagnostic::error(*span, "an rgbgrid medium needs \"sigma_a\" for \"Le\": it emits σa·Le"));
    }
    let n = super::grid::resolution(p, count, at)?;
    let grid = |g: Option<(Span, Vec<Vec3>)>| -> Res<Option<SampledGrid<Vec3>>> {
        match g {
            Some((span, v)) if v.len() != count => Err(Diagnostic::error(
                span,
                format!("every rgbgrid parameter needs nx·ny·nz = {count} colours; found {}", v.len()),
            )),
            Some((_, v)) => Ok(Some(SampledGrid::new(n, v))),
            None => Ok(None),
        }
    };
    let mut field = RgbGrid {
        sigma_a: grid(sigma_a)?,
        sigma_s: grid(sigma_s)?,
        scale: values::float(p, "scale", 1.0, Range::NonNegative)?,
        le: grid(le)?,
        le_scale: values::float(p, "Lescale", 1.0, Range::NonNegative)? * ctx.raw_emission,
        spectra: None,
    };
    field.spectra = ctx.spectral.map(|space| Spectra::new(&field, space));
    let box_to_world = ctx.medium_to_world * super::grid::unit_to_box(p, ctx.at)?;
    super::finite(Tracked::new(box_to_world, HenyeyGreenstein::new(super::asymmetry(p)?), Arc::new(field)), at)
}

/// The colours of `rgb name` (finite, at least 0) and where they are written.
fn rgb_values(p: &ParamList, name: &str) -> Res<Option<(Span, Vec<Vec3>)>> {
    let values = super::grid::grid_values(p, name, ParamType::Rgb)?;
    Ok(values.map(|(at, v)| (at, v.chunks_exact(3).map(Vec3::from_slice).collect())))
}
