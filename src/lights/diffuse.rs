//! `AreaLightSource "diffuse"` (v3 also `"area"`): the shapes that follow emit L
//! evenly over their surface, from one side or both.
//!
//! ```text
//! AreaLightSource "diffuse" "rgb L" [4 4 4] "bool twosided" true
//! AreaLightSource "diffuse" "blackbody L" [6500] "float power" 100     # v4
//! ```
//! An emitting shape is one light per quadric, triangle or patch, as in pbrt. v4's
//! `power` (watts) scales the emission as read so that the shape emits that much.

use super::params::{emission, power};
use super::{Emission, LightSample};
use crate::interaction::offset_ray_origin;
use crate::math::frame::coordinate_system;
use crate::math::{Normal3, Point3, Ray, Vector3};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::scene::values::{self, Res, SpectrumContext};
use crate::shapes::{Piece, ShapeSet};
use crate::spectrum::{Rgb, luminance};
use glam::Vec3;
use std::f32::consts::PI;

/// The names this area light type is written as (`area` in v3 only).
pub const NAMES: [&str; 2] = ["diffuse", "area"];

/// The pbrt version a type name proves: `area` is pbrt-v3's.
pub fn evidence(ty: &str) -> Option<Syntax> {
    (ty == NAMES[1]).then_some(Syntax::V3)
}

/// A diffuse area light as read.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLightDesc {
    pub l: Rgb,
    pub two_sided: bool,
    /// v4 `power` (watts): the emission is scaled so the whole shape emits this much.
    pub power: Option<f32>,
}

/// A `diffuse` (v3 also `area`) area light, or `None` for other types.
pub fn read(
    ty: &str,
    p: &ParamList,
    spectra: &SpectrumContext,
    warnings: &mut Vec<Diagnostic>,
) -> Res<Option<AreaLightDesc>> {
    if !NAMES.contains(&ty) {
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

impl AreaLightDesc {
    /// The radiance on a shape of total area `area`, after v4's `power`. As in pbrt-v4,
    /// `power` scales the emission as read (the RGB's own brightness and `scale` stay;
    /// spectra were already normalised to luminance 1), so an `rgb L` of luminance y
    /// emits y·power watts (photometric).
    pub fn emission(&self, area: f64) -> Rgb {
        match self.power {
            Some(w) if area > 0.0 => {
                let sides = if self.two_sided { 2.0 } else { 1.0 };
                self.l * (w as f64 / (std::f64::consts::PI * sides * area)) as f32
            }
            _ => self.l,
        }
    }
}

/// One emitting primitive, ready to sample.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// The primitive that emits (one light per triangle or patch, as in pbrt).
    pub emitter: Piece,
    /// The world shape it belongs to (whose alpha mask applies).
    pub shape: u32,
    pub l: Rgb,
    pub two_sided: bool,
    pub area: f32,
}

impl AreaLight {
    #[inline]
    pub fn power(&self) -> f64 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        luminance(self.l) as f64 * self.area as f64 * std::f64::consts::PI * sides
    }

    #[inline]
    pub fn sample_li(&self, shapes: &ShapeSet, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let s = shapes.sample_piece(&self.emitter, Some(Point3(p)), u)?;
        let d = s.p.0 - p;
        let wi = d.normalize_or_zero();
        let facing = self.two_sided || s.n.0.dot(-wi) > 0.0;
        (s.pdf > 0.0 && facing && wi != Vec3::ZERO).then_some(LightSample {
            wi,
            li: self.l,
            pdf: s.pdf,
            p_light: Some(s.p.0),
            delta: false,
            surface: Some(s),
        })
    }

    /// The solid-angle density `sample_li` gives direction `wi` from `p`.
    #[inline]
    pub fn pdf_li(&self, shapes: &ShapeSet, p: Vec3, wi: Vec3) -> f32 {
        shapes.pdf_piece(&self.emitter, Point3(p), Vector3(wi))
    }

    /// A photon: a point by area, then a cosine-weighted direction about its normal
    /// (two-sided lights pick a side with probability ½).
    #[inline]
    pub fn sample_le(&self, shapes: &ShapeSet, u1: [f32; 2], u2: [f32; 2]) -> Option<Emission> {
        let s = shapes.sample_piece(&self.emitter, None, u1)?;
        let n = s.n.0;
        let (mut u2, mut side) = (u2, 1.0);
        if self.two_sided {
            if u2[0] < 0.5 {
                u2[0] *= 2.0;
            } else {
                u2[0] = 2.0 * (u2[0] - 0.5);
                side = -1.0;
            }
        }
        let local = crate::sampling::cosine_hemisphere(u2);
        let (a, b) = coordinate_system(n * side);
        let d = a * local.x + b * local.y + n * side * local.z;
        let mut pdf_dir = local.z / PI;
        if self.two_sided {
            pdf_dir *= 0.5;
        }
        let p_error = crate::math::float::gamma(8) * s.p.0.abs() + Vec3::splat(1e-30);
        let o = offset_ray_origin(s.p, p_error, Normal3(n), Vector3(d));
        Some(Emission { ray: Ray::new(o, Vector3(d)), n, pdf_pos: s.pdf, pdf_dir, le: self.l, surface: Some(s) })
    }

    /// (position, direction) densities of an emission from the point `p` of this
    /// primitive, whose oriented normal there is `n`, along the unit direction `d`.
    #[inline]
    pub fn pdf_le(&self, shapes: &ShapeSet, p: Vec3, n: Vec3, d: Vec3) -> (f32, f32) {
        let cos = n.dot(d);
        let pdf_dir = match self.two_sided {
            true => 0.5 * cos.abs() / PI,
            false => cos.max(0.0) / PI,
        };
        (shapes.pdf_piece_area(&self.emitter, Point3(p), n), pdf_dir)
    }
}
