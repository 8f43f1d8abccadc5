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
//! One module per medium type ([`homogeneous`]), the phase function in [`phase`], the
//! measured presets in [`presets`]. The types registered are [`TYPES`]; the others pbrt
//! knows are skipped with a located warning and rendered as vacuum.

pub mod homogeneous;
pub mod phase;
pub mod presets;

use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::scene::approx::Approx;
use crate::scene::values::{Res, SpectrumContext};
pub use homogeneous::{Flight, Homogeneous};
pub use phase::HenyeyGreenstein;

/// The medium types rendered.
pub const TYPES: &[&str] = &[homogeneous::NAME];

/// A named medium as the scene built it.
#[derive(Clone, Debug, PartialEq)]
pub struct MediumDesc {
    pub name: String,
    pub kind: Medium,
}

/// A medium, ready to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Medium {
    Homogeneous(Homogeneous),
}

impl Medium {
    pub fn type_name(&self) -> &'static str {
        match self {
            Medium::Homogeneous(_) => homogeneous::NAME,
        }
    }

    pub fn phase(&self) -> HenyeyGreenstein {
        match self {
            Medium::Homogeneous(h) => h.phase,
        }
    }

    /// The scattering coefficient at a point the sampler chose.
    pub fn sigma_s(&self) -> glam::Vec3 {
        match self {
            Medium::Homogeneous(h) => h.sigma_s,
        }
    }

    /// Free-flight sampling along a segment of parameter length `t_max` of a ray
    /// whose direction has length `dlen`.
    pub fn sample(&self, t_max: f32, dlen: f32, u: [f32; 2]) -> Flight {
        match self {
            Medium::Homogeneous(h) => h.sample(t_max, dlen, u[0], u[1]),
        }
    }

    /// Transmittance across `dist` world units of the segment.
    pub fn transmittance(&self, dist: f32) -> glam::Vec3 {
        match self {
            Medium::Homogeneous(h) => h.transmittance(dist),
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
}

/// Builds a medium of type `ty`; `Ok(None)` for a type that is not rendered.
pub fn read(ty: &str, p: &ParamList, ctx: &mut MediumContext) -> Res<Option<Medium>> {
    Ok(match ty {
        homogeneous::NAME => Some(Medium::Homogeneous(Homogeneous::read(p, ctx)?)),
        _ => None,
    })
}

/// Whether pbrt knows the type (in some version): unknown names are errors.
pub fn known(ty: &str) -> bool {
    matches!(ty, "homogeneous" | "heterogeneous" | "uniformgrid" | "rgbgrid" | "cloud" | "nanovdb")
}
