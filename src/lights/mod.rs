//! Light sources, one module per type, each owning its parameters (defaults per
//! version, located errors), its sampling and evaluation, and its Mitsuba export:
//! [`point`], [`spot`], [`goniometric`], [`projection`], [`distant`], [`infinite`] (with
//! [`envmap`] and [`portal`]) and the area light
//! [`diffuse`]. [`REGISTRY`] is the one list of `LightSource` types.
//!
//! ```text
//! LightSource "point" "rgb I" [10 10 10] "point from" [0 4 0]    # v3: from is a world offset
//! LightSource "spot" "blackbody I" [5500 125] "point from" [0 5 9] "point to" [-5 2.75 0]
//! LightSource "distant" "point3 from" [0 0 0] "point3 to" [0 0 1] "rgb L" [3 3 3] "float illuminance" 2
//! LightSource "infinite" "rgb L" [.1 .1 .1]      # or "string mapname" (v3) / "filename" (v4)
//! LightSource "goniometric" "rgb I" [1 1 1] "string mapname" "profile.exr"   # v4: filename
//! LightSource "projection" "rgb I" [1 1 1] "string mapname" "slide.exr" "float fov" 45
//! AreaLightSource "diffuse" "rgb L" [4 4 4] "bool twosided" true "float power" 100   # v4 power
//! ```
//! Every light, through one dispatch ([`Light`]), can be sampled for direct lighting
//! (`sample_li`, with `pdf_li` for MIS), can emit (`sample_le`: a ray with its position
//! and direction densities), gives the densities of an emission it did not sample
//! (`pdf_le`, for bidirectional methods), and reports its `power` for choosing photon
//! sources. v4 normalises blackbody spectra to luminance 1 and honours `power`; v3
//! blackbody is peak-normalised × scale. Emission must be finite and non-negative.
//!
//! Adding a light type: a module here with `NAME`, `read`, a description (with its
//! `mitsuba`) and a light ready to sample; a variant in [`LightKind`] and [`Light`]; a
//! line in [`REGISTRY`].

pub mod bounds;
pub mod choice;
pub mod diffuse;
pub mod distant;
pub mod envmap;
pub mod goniometric;
pub mod infinite;
pub mod params;
pub mod point;
pub mod portal;
pub mod projection;
pub mod spot;

pub use diffuse::{AreaLight, AreaLightDesc};
pub use infinite::EnvMapDesc;
pub use params::LightContext;

use crate::math::Ray;
use crate::mitsuba::{LightOut, Unsupported};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::shapes::{ShapeSample, ShapeSet};
use crate::spectrum::{EmissionSpectrum, Rgb};
use crate::values::{self, Res};
use glam::{DMat4, Vec3};

/// A `LightSource` type: the name scenes use, its reader, and the parameter whose
/// spectrum it emits (times a scalar: a scale, a profile), where there is one.
pub struct LightType {
    pub name: &'static str,
    pub read: fn(&ParamList, &DMat4, Span, &mut LightContext) -> Res<LightKind>,
    pub emits: Option<&'static str>,
}

/// Every `LightSource` type we render; any other is skipped with a warning.
pub const REGISTRY: [LightType; 6] = [
    LightType { name: point::NAME, read: point::read, emits: Some("I") },
    LightType { name: spot::NAME, read: spot::read, emits: Some("I") },
    LightType { name: distant::NAME, read: distant::read, emits: Some("L") },
    LightType { name: infinite::NAME, read: infinite::read, emits: Some("L") },
    LightType { name: goniometric::NAME, read: goniometric::read, emits: Some("I") },
    // Its image's colours are the emission (pbrt-v4: RGB illuminant spectra).
    LightType { name: projection::NAME, read: projection::read, emits: None },
];

/// The spectrum a `LightSource` of type `ty` emits where the file gives it as one (a
/// blackbody, a named illuminant, samples): what spectral paths read exactly.
pub fn emission_spectrum(
    ty: &str,
    p: &ParamList,
    ctx: &values::SpectrumContext,
) -> Res<Option<std::sync::Arc<EmissionSpectrum>>> {
    let Some(name) = REGISTRY.iter().find(|t| t.name == ty).and_then(|t| t.emits) else { return Ok(None) };
    if ty == infinite::NAME && infinite::map_replaces_l(p) {
        return Ok(None);
    }
    Ok(values::emission_spectrum(p, name, ctx)?.map(std::sync::Arc::new))
}

/// A `LightSource` of type `ty`, or `None` for a type we do not render.
pub fn read(ty: &str, p: &ParamList, m: &DMat4, span: Span, ctx: &mut LightContext) -> Res<Option<LightKind>> {
    let Some(t) = REGISTRY.iter().find(|t| t.name == ty) else { return Ok(None) };
    values::no_effect(p, &["samples", "nsamples"]);
    (t.read)(p, m, span, ctx).map(Some)
}

/// A light source as read, in world space.
#[derive(Clone, Debug)]
pub enum LightKind {
    Point(point::Point),
    Spot(spot::Spot),
    Distant(distant::Distant),
    Infinite(infinite::Infinite),
    Goniometric(goniometric::Goniometric),
    Projection(projection::Projection),
}

/// A `LightSource` of a supported type.
#[derive(Clone, Debug)]
pub struct LightDesc {
    pub kind: LightKind,
    /// Its emission as a spectrum, where the file gives one.
    pub spectrum: Option<std::sync::Arc<EmissionSpectrum>>,
    /// The CTM at the statement.
    pub world_from_light: DMat4,
    /// The medium it sits in (the outside one current at the statement).
    pub medium: Option<u32>,
}

impl LightDesc {
    /// The type's name as scenes write it.
    pub fn name(&self) -> &'static str {
        match &self.kind {
            LightKind::Point(_) => point::NAME,
            LightKind::Spot(_) => spot::NAME,
            LightKind::Distant(_) => distant::NAME,
            LightKind::Infinite(_) => infinite::NAME,
            LightKind::Goniometric(_) => goniometric::NAME,
            LightKind::Projection(_) => projection::NAME,
        }
    }

    /// The light for Mitsuba 3; what cannot go over alike is noted.
    pub fn mitsuba(&self, notes: &mut Vec<Unsupported>) -> LightOut {
        match &self.kind {
            LightKind::Point(l) => l.mitsuba(),
            LightKind::Spot(l) => l.mitsuba(notes),
            LightKind::Distant(l) => l.mitsuba(),
            LightKind::Infinite(l) => l.mitsuba(&self.world_from_light, notes),
            LightKind::Goniometric(l) => l.mitsuba(notes),
            LightKind::Projection(l) => l.mitsuba(notes),
        }
    }
}

/// A light ready to sample.
#[derive(Clone, Debug)]
pub enum Light {
    Point(point::PointLight),
    Spot(spot::SpotLight),
    Distant(distant::DistantLight),
    Infinite(infinite::InfiniteLight),
    Goniometric(goniometric::GoniometricLight),
    Projection(projection::ProjectionLight),
    Area(AreaLight),
}

/// A light sample for direct lighting.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub wi: Vec3,
    pub li: Rgb,
    /// Solid-angle density (1 for delta lights).
    pub pdf: f32,
    /// The point to test visibility against; `None` for directions to infinity.
    pub p_light: Option<Vec3>,
    pub delta: bool,
    /// The point drawn on an area light (its alpha mask may cut it away).
    pub surface: Option<ShapeSample>,
}

impl LightSample {
    /// Light from a delta light (a point or a direction) along `wi`.
    fn delta(wi: Vec3, li: Rgb, p_light: Option<Vec3>) -> LightSample {
        LightSample { wi, li, pdf: 1.0, p_light, delta: true, surface: None }
    }
}

/// A photon leaving a light.
#[derive(Clone, Copy, Debug)]
pub struct Emission {
    pub ray: Ray,
    pub n: Vec3,
    pub pdf_pos: f32,
    pub pdf_dir: f32,
    pub le: Rgb,
    /// The point drawn on an area light (its alpha mask may cut it away).
    pub surface: Option<ShapeSample>,
}

/// The scene's bounding sphere (for distant and infinite lights).
#[derive(Clone, Copy, Debug)]
pub struct WorldSphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Light {
    pub fn from_desc(d: &LightDesc, fixes: crate::fixes::Fixes) -> Light {
        match &d.kind {
            LightKind::Point(l) => Light::Point(point::PointLight::new(l)),
            LightKind::Spot(l) => Light::Spot(spot::SpotLight::new(l)),
            LightKind::Distant(l) => Light::Distant(distant::DistantLight::new(l)),
            LightKind::Infinite(l) => Light::Infinite(infinite::InfiniteLight::new(l, fixes)),
            LightKind::Goniometric(l) => Light::Goniometric(goniometric::GoniometricLight::new(l)),
            LightKind::Projection(l) => Light::Projection(projection::ProjectionLight::new(l)),
        }
    }

    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point(_) | Light::Spot(_) | Light::Goniometric(_) | Light::Projection(_) | Light::Distant(_)
        )
    }

    /// Bounds for choosing a light to light a point (pbrt-v4's `Light::Bounds`); `None`
    /// for lights at infinity, which have none.
    pub fn bounds(&self, shapes: &ShapeSet) -> Option<bounds::LightBounds> {
        match self {
            Light::Point(l) => Some(l.bounds()),
            Light::Spot(l) => Some(l.bounds()),
            Light::Goniometric(l) => Some(l.bounds()),
            Light::Projection(l) => Some(l.bounds()),
            Light::Area(l) => Some(l.bounds(shapes)),
            Light::Distant(_) | Light::Infinite(_) => None,
        }
    }

    /// Total emitted power, for choosing photon sources (luminance; in f64, so that a
    /// light bright enough for 4π·I to pass f32's range still has a power).
    #[inline]
    pub fn power(&self, world: WorldSphere) -> f64 {
        match self {
            Light::Point(l) => l.power(),
            Light::Spot(l) => l.power(),
            Light::Goniometric(l) => l.power(),
            Light::Projection(l) => l.power(),
            Light::Distant(l) => l.power(world),
            Light::Infinite(l) => l.power(world),
            Light::Area(l) => l.power(),
        }
    }

    /// Incident light at `p` from this light.
    #[inline]
    pub fn sample_li(&self, shapes: &ShapeSet, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        match self {
            Light::Point(l) => l.sample_li(p),
            Light::Spot(l) => l.sample_li(p),
            Light::Goniometric(l) => l.sample_li(p),
            Light::Projection(l) => l.sample_li(p),
            Light::Distant(l) => Some(l.sample_li()),
            Light::Infinite(l) => l.sample_li(p, u),
            Light::Area(l) => l.sample_li(shapes, p, u),
        }
    }

    /// The solid-angle density `sample_li` gives direction `wi` from `p` (0 for delta
    /// lights, which no direction finds by chance).
    #[inline]
    pub fn pdf_li(&self, shapes: &ShapeSet, p: Vec3, wi: Vec3) -> f32 {
        match self {
            Light::Infinite(l) => l.pdf_li(p, wi),
            Light::Area(l) => l.pdf_li(shapes, p, wi),
            Light::Point(_) | Light::Spot(_) | Light::Goniometric(_) | Light::Projection(_) | Light::Distant(_) => 0.0,
        }
    }

    /// A photon: ray, light normal, position and direction densities and emitted
    /// radiance (pbrt's `Sample_Le`).
    #[inline]
    pub fn sample_le(&self, shapes: &ShapeSet, world: WorldSphere, u1: [f32; 2], u2: [f32; 2]) -> Option<Emission> {
        match self {
            Light::Point(l) => Some(l.sample_le(u1)),
            Light::Spot(l) => Some(l.sample_le(u1)),
            Light::Goniometric(l) => Some(l.sample_le(u1)),
            Light::Projection(l) => Some(l.sample_le(u1)),
            Light::Distant(l) => Some(l.sample_le(world, u1)),
            Light::Infinite(l) => l.sample_le(world, u1, u2),
            Light::Area(l) => l.sample_le(shapes, u1, u2),
        }
    }

    /// A light with a position and no extent (point, spot, goniometric, projection):
    /// where it is and its `sample_le` direction density (`None` for other lights).
    pub fn point_source(&self) -> Option<(Vec3, f32)> {
        match self {
            Light::Point(l) => Some((l.p, l.pdf_le().1)),
            Light::Spot(l) => Some((l.p, l.pdf_dir())),
            Light::Goniometric(l) => Some((l.p, l.pdf_le().1)),
            Light::Projection(l) => Some((l.p, l.pdf_dir())),
            Light::Distant(_) | Light::Infinite(_) | Light::Area(_) => None,
        }
    }

    /// The intensity a [`Light::point_source`] sends along the unit world direction
    /// `w` (zero for other lights).
    pub fn intensity(&self, w: Vec3) -> Rgb {
        match self {
            Light::Point(l) => l.intensity(),
            Light::Spot(l) => l.intensity(w),
            Light::Goniometric(l) => l.intensity(w),
            Light::Projection(l) => l.intensity(w),
            Light::Distant(_) | Light::Infinite(_) | Light::Area(_) => Vec3::ZERO,
        }
    }

    /// The (position, direction) densities `sample_le` has for an emission it did not
    /// necessarily draw: a ray leaving `ray.o` (on an area light, where its oriented
    /// normal is `n`) along the unit direction `ray.d` (pbrt's `PDF_Le`). Delta
    /// positions and directions have density 0 here, as in pbrt. A portal sky's are
    /// those of its emission through the portal, which vcm and bdpt draw
    /// ([`infinite::InfiniteLight::sample_le_through_portal`]), not SPPM's photons'.
    #[inline]
    pub fn pdf_le(&self, shapes: &ShapeSet, world: WorldSphere, ray: &Ray, n: Vec3) -> (f32, f32) {
        match self {
            Light::Point(l) => l.pdf_le(),
            Light::Spot(l) => l.pdf_le(ray.d.0),
            Light::Goniometric(l) => l.pdf_le(),
            Light::Projection(l) => l.pdf_le(ray.d.0),
            Light::Distant(l) => l.pdf_le(world),
            Light::Infinite(l) => l.pdf_le(world, ray.d.0),
            Light::Area(l) => l.pdf_le(shapes, ray.o.0, n, ray.d.0),
        }
    }

    /// Radiance from an infinite light along a ray from `o` that escapes in direction
    /// `d`.
    pub fn le_escaped(&self, o: Vec3, d: Vec3) -> Rgb {
        match self {
            Light::Infinite(l) => l.le(o, d),
            _ => Vec3::ZERO,
        }
    }
}
