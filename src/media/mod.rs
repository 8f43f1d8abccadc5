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
//! One module per medium type ([`homogeneous`], [`grid`]), the phase function in
//! [`phase`], the measured presets in [`presets`]. The types registered are [`TYPES`];
//! the others pbrt knows are skipped with a located warning and rendered as vacuum.

pub mod grid;
pub mod homogeneous;
pub mod phase;
pub mod presets;

use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::sampling::Sampler;
use crate::scene::approx::Approx;
use crate::scene::values::{self, Range, Res, SpectrumContext};
use glam::{DMat4, Vec3};
pub use grid::GridMedium;
pub use homogeneous::{Flight, Homogeneous};
pub use phase::HenyeyGreenstein;
use std::sync::Arc;

/// The medium types rendered.
pub const TYPES: &[&str] = &[homogeneous::NAME, grid::NAMES[0], grid::NAMES[1]];

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
    Grid(Arc<GridMedium>),
}

impl Medium {
    pub fn phase(&self) -> HenyeyGreenstein {
        match self {
            Medium::Homogeneous(h) => h.phase,
            Medium::Grid(g) => g.phase,
        }
    }

    /// Free-flight sampling along the segment `o + t·d`, t in [0, `t_max`).
    pub fn sample(&self, o: Vec3, d: Vec3, t_max: f32, sampler: &mut impl Sampler) -> Flight {
        match self {
            Medium::Homogeneous(h) => {
                let u = sampler.get2d();
                h.sample(t_max, d.length(), u[0], u[1])
            }
            Medium::Grid(g) => g.sample_flight(o, d, t_max, sampler),
        }
    }

    /// Transmittance along the segment `o + t·d`, t in [0, `t_max`] (an unbiased
    /// estimate for grids, exact for homogeneous media).
    pub fn transmittance(&self, o: Vec3, d: Vec3, t_max: f32, sampler: &mut impl Sampler) -> Vec3 {
        let dlen = d.length();
        match self {
            Medium::Homogeneous(h) => h.transmittance(t_max * dlen),
            Medium::Grid(g) => g.transmittance(o, d / dlen, t_max * dlen, sampler),
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
    /// Notes something rendered other than as written.
    pub approximate: &'a mut dyn FnMut(Span, String, Approx),
    /// The CTM at the statement: the medium's own space (grids are placed in it).
    pub medium_to_world: DMat4,
    /// The statement's name, for errors about the whole statement.
    pub at: Span,
}

/// pbrt-v4's medium emission, noted as approximated (it is not rendered yet) where it
/// would emit: a nonzero `Le` (checked) under a positive scale, or what else the type
/// found (`other`: a grid's `temperature`). `what` names it in the note.
pub fn note_emission(p: &ParamList, ctx: &mut MediumContext, what: &str, scale_positive: bool, other: bool) -> Res<()> {
    let le = values::rgb(p, "Le", &ctx.spectra, Range::NonNegative)?;
    if (le.is_some_and(|c| c.max_element() > 0.0) && scale_positive) || other {
        let at = values::span_of(p, "Le").or(values::span_of(p, "temperature")).unwrap_or_default();
        (ctx.approximate)(at, what.into(), Approx::MediumEmission);
    }
    Ok(())
}

/// Builds a medium of type `ty`; `Ok(None)` for a type that is not rendered.
pub fn read(ty: &str, p: &ParamList, ctx: &mut MediumContext) -> Res<Option<Medium>> {
    Ok(match ty {
        homogeneous::NAME => Some(Medium::Homogeneous(Homogeneous::read(p, ctx)?)),
        "heterogeneous" | "uniformgrid" => Some(Medium::Grid(Arc::new(GridMedium::read(p, ctx)?))),
        _ => None,
    })
}

/// Whether pbrt knows the type (in some version): unknown names are errors.
pub fn known(ty: &str) -> bool {
    matches!(ty, "homogeneous" | "heterogeneous" | "uniformgrid" | "rgbgrid" | "cloud" | "nanovdb")
}
