//! Participating media: what `MakeNamedMedium` creates and `MediumInterface` places.
//!
//! ```text
//! MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_s" [0.2 0.2 0.2]
//! MediumInterface "" "fog"          # the camera sits in fog: Camera takes the outside
//! Camera "perspective"
//! WorldBegin
//! AttributeBegin
//!   MediumInterface "fog" ""        # inside fog, outside vacuum
//!   Material "interface"            # v4 (v3: Material "") — a boundary that does not scatter
//!   Shape "sphere" "float radius" 2
//! AttributeEnd
//! ```
//!
//! One module per medium type ([`homogeneous`], [`grid`], [`rgbgrid`], [`cloud`],
//! [`nanovdb`], which reads NanoVDB files with its own reader); the ones that vary in
//! space share [`tracking`] and [`sampled`]; the phase function is in [`phase`], the
//! measured presets in [`presets`]. The types registered are [`TYPES`].

pub mod cloud;
pub mod emitters;
pub mod grid;
pub mod homogeneous;
pub mod lanes;
pub mod nanovdb;
pub mod phase;
pub mod presets;
pub mod rgbgrid;
pub mod sampled;
pub mod tracking;

use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::sampling::Sampler;
use crate::values::{self, Range, Res, SpectrumContext};
use glam::{DMat4, Vec3};
pub use homogeneous::{Coefficients, Flight, Homogeneous};
pub use lanes::Lanes;
pub use phase::HenyeyGreenstein;
use std::sync::Arc;
pub use tracking::Tracked;

/// The medium types rendered.
pub const TYPES: &[&str] =
    &[homogeneous::NAME, grid::NAMES[0], grid::NAMES[1], rgbgrid::NAME, cloud::NAME, nanovdb::NAME];

/// A named medium as the scene built it.
#[derive(Clone, Debug, PartialEq)]
pub struct MediumDesc {
    pub name: String,
    pub kind: Medium,
}

/// A medium, ready to render.
#[derive(Clone, Debug, PartialEq)]
pub enum Medium {
    Homogeneous(Homogeneous),
    /// Varying over a box: the grids and the cloud.
    Tracked(Arc<Tracked>),
}

impl Medium {
    pub fn phase(&self) -> HenyeyGreenstein {
        match self {
            Medium::Homogeneous(h) => h.phase,
            Medium::Tracked(g) => g.phase,
        }
    }

    /// Whether it emits light (pbrt-v4's `Le` and `temperature`).
    pub fn emissive(&self) -> bool {
        match self {
            Medium::Homogeneous(h) => h.le.rgb != Vec3::ZERO,
            Medium::Tracked(g) => g.emissive(),
        }
    }

    /// σa·Le at a world point (where the medium is).
    pub fn emitted_at(&self, p: Vec3, lanes: Lanes) -> Vec3 {
        match self {
            Medium::Homogeneous(h) => {
                let c = h.at(lanes);
                c.sigma_a * c.le
            }
            Medium::Tracked(g) => g.emitted_at(p, lanes),
        }
    }

    /// The light the medium emits toward `o` along the segment `o + t·d`, t in [0,
    /// `t_max`), attenuated on the way: ∫ Tr·σa·Le (exact for homogeneous media, an
    /// unbiased estimate for the others).
    pub fn emission(&self, o: Vec3, d: Vec3, t_max: f32, sampler: &mut impl Sampler, lanes: Lanes) -> Vec3 {
        let dlen = d.length();
        match self {
            Medium::Homogeneous(h) => h.at(lanes).emission(t_max * dlen),
            Medium::Tracked(g) => g.emission(o, d / dlen, t_max * dlen, sampler, lanes),
        }
    }

    /// Free-flight sampling along the segment `o + t·d`, t in [0, `t_max`).
    pub fn sample(&self, o: Vec3, d: Vec3, t_max: f32, sampler: &mut impl Sampler, lanes: Lanes) -> Flight {
        match self {
            Medium::Homogeneous(h) => {
                let u = sampler.get2d();
                h.at(lanes).sample(t_max, d.length(), u[0], u[1])
            }
            Medium::Tracked(g) => g.sample_flight(o, d, t_max, sampler, lanes),
        }
    }

    /// The transmittance profile over `dist` world units from `o` along unit
    /// direction `d` (see [`Profile`]).
    pub fn profile(&self, o: Vec3, d: Vec3, dist: f32, sampler: &mut impl Sampler, lanes: Lanes) -> Profile {
        match self {
            Medium::Homogeneous(h) => Profile::Exact(h.at(lanes)),
            Medium::Tracked(g) => Profile::Steps(g.transmittance_steps(o, d, dist, sampler, lanes)),
        }
    }

    /// Transmittance along the segment `o + t·d`, t in [0, `t_max`] (an unbiased
    /// estimate for grids, exact for homogeneous media).
    pub fn transmittance(&self, o: Vec3, d: Vec3, t_max: f32, sampler: &mut impl Sampler, lanes: Lanes) -> Vec3 {
        let dlen = d.length();
        match self {
            Medium::Homogeneous(h) => h.at(lanes).transmittance(t_max * dlen),
            Medium::Tracked(g) => g.transmittance(o, d / dlen, t_max * dlen, sampler, lanes),
        }
    }
}

/// The transmittance along one segment of a ray at every distance from its start, as
/// the beam radiance estimate reads it: exact in homogeneous media, one ratio-tracking
/// walk's records in the others.
#[derive(Clone, Debug)]
pub enum Profile {
    /// A homogeneous medium.
    Exact(Coefficients),
    /// (distance, transmittance from there on) in increasing distance.
    Steps(Vec<(f32, Vec3)>),
}

impl Profile {
    /// The transmittance over the first `t` world units.
    pub fn at(&self, t: f32) -> Vec3 {
        match self {
            Profile::Exact(h) => h.transmittance(t),
            Profile::Steps(steps) => match steps.partition_point(|s| s.0 <= t) {
                0 => Vec3::ONE,
                k => steps[k - 1].1,
            },
        }
    }
}

/// The media on either side of a surface (`None`: vacuum). `inside` is on the side
/// the surface normal points away from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumInterface {
    pub inside: Option<u32>,
    pub outside: Option<u32>,
}

impl MediumInterface {
    /// Whether crossing the surface changes the medium; where not, rays keep the one
    /// they travel in (as in pbrt).
    pub fn is_transition(&self) -> bool {
        self.inside != self.outside
    }

    /// The medium a ray leaving in direction `d` enters, given the surface normal.
    pub fn toward(&self, d: glam::Vec3, n: glam::Vec3) -> Option<u32> {
        if d.dot(n) > 0.0 { self.outside } else { self.inside }
    }
}

/// What reading a medium needs besides its parameters.
pub struct MediumContext<'a> {
    pub syntax: Syntax,
    pub spectra: SpectrumContext<'a>,
    pub warnings: &'a mut Vec<Diagnostic>,
    /// The CTM at the statement: the medium's own space (grids are placed in it).
    pub medium_to_world: DMat4,
    /// The statement's name, for errors about the whole statement.
    pub at: Span,
    /// What the film records for an emission spectrum of 1 that pbrt-v4 leaves
    /// unnormalised (a temperature grid's, an rgbgrid's): ∫ȳ dλ = 106.86 as pbrt-v4, 1
    /// under `--fix medium-emission`.
    pub raw_emission: f32,
    /// The colour space of a scene rendered spectrally (its media's colours become
    /// spectra), `None` in RGB.
    pub spectral: Option<crate::spectrum::colorspace::ColorSpaceName>,
}

/// pbrt-v4's `Le` (an illuminant: a blackbody is normalised to luminance 1, as for
/// lights), `None` where not given.
pub fn read_le(p: &ParamList, ctx: &MediumContext) -> Res<Option<Vec3>> {
    let spectra = SpectrumContext { normalize_emission: true, ..ctx.spectra };
    values::rgb(p, "Le", &spectra, Range::NonNegative)
}

/// The Henyey–Greenstein asymmetry `g`, in [−1, 1].
pub fn asymmetry(p: &ParamList) -> Res<f32> {
    let g = values::float(p, "g", 0.0, Range::Any)?;
    if !(-1.0..=1.0).contains(&g) {
        let at = values::span_of(p, "g").unwrap_or_default();
        return Err(Diagnostic::error(at, format!("\"float g\" must lie in [-1, 1], not {g}")));
    }
    Ok(g)
}

/// A tracked medium whose bounds of σt and of its emission are finite: no overflow in
/// `scale`, σa + σs, the densities, `Le` or `Lescale` (written at `at`).
// DEVIATION(pbrt): robustness. pbrt lets the coefficients overflow to Inf, and then
// distances of 0 times Inf make NaN pixels.
fn finite(t: Tracked, at: Span) -> Res<Tracked> {
    if !t.max_majorant().is_finite() {
        let msg = "σa + σs times the scale and the densities is beyond the range of 32-bit floats";
        return Err(Diagnostic::error(at, msg));
    }
    if !t.emission_bound().is_finite() {
        return Err(Diagnostic::error(at, "σa times the emission is beyond the range of 32-bit floats"));
    }
    Ok(t)
}

/// Builds a medium of type `ty` (one that [`known`] names).
pub fn read(ty: &str, p: &ParamList, ctx: &mut MediumContext) -> Res<Medium> {
    Ok(match ty {
        homogeneous::NAME => Medium::Homogeneous(Homogeneous::read(p, ctx)?),
        "heterogeneous" | "uniformgrid" => Medium::Tracked(Arc::new(grid::read(p, ctx)?)),
        rgbgrid::NAME => Medium::Tracked(Arc::new(rgbgrid::read(p, ctx)?)),
        cloud::NAME => Medium::Tracked(Arc::new(cloud::read(p, ctx)?)),
        nanovdb::NAME => Medium::Tracked(Arc::new(nanovdb::read(p, ctx)?)),
        _ => return Err(Diagnostic::error(ctx.at, format!("medium type \"{ty}\" is not rendered"))),
    })
}

/// Whether pbrt knows the type (in some version): unknown names are errors.
pub fn known(ty: &str) -> bool {
    matches!(ty, "homogeneous" | "heterogeneous" | "uniformgrid" | "rgbgrid" | "cloud" | "nanovdb")
}
