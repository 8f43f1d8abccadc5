//! `AreaLightSource "diffuse"` (v3 also `"area"`): the shapes that follow emit L
//! evenly over their surface, from one side or both.
//!
//! ```text
//! AreaLightSource "diffuse" "rgb L" [4 4 4] "bool twosided" true
//! AreaLightSource "diffuse" "blackbody L" [6500] "float power" 100     # v4
//! AreaLightSource "diffuse" "string filename" "screen.exr" "float scale" 2   # v4
//! ```
//! An emitting shape is one light per quadric, triangle or patch, as in pbrt. v4's
//! `power` (watts) scales the emission as read so that the shape emits that much.
//! v4's `filename` makes the emission an image over the surface's (u, v): bilinear,
//! (0, 0) at the image's bottom left, clamped at its edges, negative channels emitting
//! nothing, times `scale` (pbrt-v4's `DiffuseAreaLight::L`); points are still drawn by
//! area, as pbrt-v4 draws them. An image with `L` as well, or one that cannot be read, is
//! an error, as in pbrt-v4.

use super::bounds::LightBounds;
use super::params::{emission, finite_image, power};
use super::{Emission, LightSample};
use crate::imageio::RgbImage;
use crate::imageio::lookup::{Wrap, lookup};
use crate::interaction::offset_ray_origin;
use crate::math::frame::coordinate_system;
use crate::math::{Normal3, Point3, Ray, Vector3};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::shapes::{Piece, ShapeSet};
use crate::spectrum::{Rgb, luminance};
use crate::values::{self, Res, SpectrumContext};
use glam::Vec3;
use std::f32::consts::PI;
use std::sync::Arc;

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
    /// `L` as a spectrum, where the file gives one (a blackbody, samples, a named
    /// illuminant): what spectral paths read exactly.
    pub spectrum: Option<Arc<crate::spectrum::EmissionSpectrum>>,
    pub two_sided: bool,
    /// v4 `power` (watts): the emission is scaled so the whole shape emits this much.
    pub power: Option<f32>,
    /// v4 `filename`: the emission over (u, v), scaled by `l`.
    pub image: Option<EmissionImage>,
}

/// An image an area light emits, with its mean luminance (negative channels as 0),
/// which its power counts, found once.
#[derive(Clone, Debug, PartialEq)]
pub struct EmissionImage {
    pub image: Arc<RgbImage>,
    pub mean_luminance: f64,
}

impl EmissionImage {
    pub fn new(image: Arc<RgbImage>) -> EmissionImage {
        let sum: f64 = image.pixels.iter().map(|p| luminance(Vec3::from(*p).max(Vec3::ZERO)) as f64).sum();
        let mean_luminance = sum / image.pixels.len().max(1) as f64;
        EmissionImage { image, mean_luminance }
    }
}

/// Reads an image by the scene-relative name a file gives.
pub type ImageReader<'a> = dyn FnMut(&str) -> Result<Arc<RgbImage>, String> + 'a;

/// A `diffuse` (v3 also `area`) area light, or `None` for other types.
pub fn read(
    ty: &str,
    p: &ParamList,
    (syntax, spectra): (Syntax, &SpectrumContext),
    images: &mut ImageReader,
    warnings: &mut Vec<Diagnostic>,
    span: Span,
) -> Res<Option<AreaLightDesc>> {
    if !NAMES.contains(&ty) {
        return Ok(None);
    }
    values::no_effect(p, &["samples", "nsamples"]);
    let image = match syntax {
        Syntax::V4 => image(p, images)?,
        Syntax::V3 => {
            values::ignored(p, &["filename"], "pbrt-v3's area lights take no image", warnings);
            None
        }
    };
    Ok(Some(AreaLightDesc {
        l: emission(p, "L", spectra, span)?,
        spectrum: values::emission_spectrum(p, "L", spectra)?.map(Arc::new),
        two_sided: p.bool("twosided")?.unwrap_or(false),
        power: power(p)?,
        image,
    }))
}

/// v4's emission image, `filename`.
fn image(p: &ParamList, images: &mut ImageReader) -> Res<Option<EmissionImage>> {
    let Some(name) = p.string("filename")?.filter(|n| !n.is_empty()) else { return Ok(None) };
    let at = p.named("filename").map_or(Span::default(), |q| q.value_span);
    if let Some(l) = p.named("L") {
        return Err(Diagnostic::error(l.span, "an area light takes \"L\" or \"filename\", not both (as in pbrt-v4)"));
    }
    let img = images(&name).map_err(|e| Diagnostic::error(at, format!("area light image: {e}")))?;
    finite_image(&img, &name, at)?;
    Ok(Some(EmissionImage::new(img)))
}

/// What an image adds to an area light's power: its mean luminance (1 for none).
fn mean_luminance(image: Option<&EmissionImage>) -> f64 {
    image.map_or(1.0, |i| i.mean_luminance)
}

impl AreaLightDesc {
    /// The radiance on a shape of total area `area`, after v4's `power`. As in pbrt-v4,
    /// `power` scales the emission as read (the RGB's own brightness and `scale` stay;
    /// spectra were already normalised to luminance 1), so an `rgb L` of luminance y
    /// emits y·power watts (photometric).
    pub fn emission(&self, area: f64) -> Rgb {
        match self.power {
            Some(w) if area > 0.0 => {
                // An image's own brightness counts toward the watts (its mean luminance).
                let sides = if self.two_sided { 2.0 } else { 1.0 };
                let k = std::f64::consts::PI * sides * area * mean_luminance(self.image.as_ref());
                self.l * (w as f64 / k) as f32
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
    /// The emission over (u, v), times `l` (v4 `filename`).
    pub image: Option<EmissionImage>,
    /// `L` as a spectrum, where the file gives one.
    pub spectrum: Option<Arc<crate::spectrum::EmissionSpectrum>>,
}

impl AreaLight {
    #[inline]
    pub fn power(&self) -> f64 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        let mean = mean_luminance(self.image.as_ref());
        luminance(self.l) as f64 * mean * self.area as f64 * std::f64::consts::PI * sides
    }

    /// Bounds for choosing lights: the emitter's box, shining every way.
    // DEVIATION(pbrt): noise only. pbrt-v4 bounds the emitter's normals (a triangle's
    // one normal); every direction is a looser bound, never a wrong one.
    pub fn bounds(&self, shapes: &ShapeSet) -> LightBounds {
        let b = shapes.piece_bounds(&self.emitter);
        LightBounds { bounds: b, two_sided: self.two_sided, ..LightBounds::isotropic(b.min, self.power() as f32) }
    }

    /// The radiance the surface emits at (u, v).
    #[inline]
    pub fn radiance(&self, uv: [f32; 2]) -> Rgb {
        match &self.image {
            None => self.l,
            Some(e) => self.l * lookup(&e.image, uv[0], uv[1], Wrap::Clamp, false).max(Vec3::ZERO),
        }
    }

    #[inline]
    pub fn sample_li(&self, shapes: &ShapeSet, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let s = shapes.sample_piece(&self.emitter, Some(Point3(p)), u)?;
        let d = s.p.0 - p;
        let wi = d.normalize_or_zero();
        let facing = self.two_sided || s.n.0.dot(-wi) > 0.0;
        (s.pdf > 0.0 && facing && wi != Vec3::ZERO).then_some(LightSample {
            wi,
            li: self.radiance(s.uv),
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
        let le = self.radiance(s.uv);
        Some(Emission { ray: Ray::new(o, Vector3(d)), n, pdf_pos: s.pdf, pdf_dir, le, surface: Some(s) })
    }

    /// The point of the unit square `sample_le` lifts to the unit direction `d` leaving
    /// a point whose oriented normal is `n`: one-sided lights, in front of the surface.
    pub fn direction_square(&self, n: Vec3, d: Vec3) -> Option<[f32; 2]> {
        if self.two_sided || n.dot(d) <= 0.0 {
            return None;
        }
        let (a, b) = coordinate_system(n);
        Some(crate::sampling::invert_concentric_disk(glam::Vec2::new(d.dot(a), d.dot(b))))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn piece() -> Piece {
        Piece::Triangle { mesh: 0, tri: 0, flags: Default::default() }
    }

    fn screen() -> Arc<RgbImage> {
        // 2 × 2: top row red, green; bottom row blue, white (row 0 is the top).
        let mut img = RgbImage::new(2, 2);
        img.pixels = vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
        Arc::new(img)
    }

    #[test]
    fn an_image_light_puts_the_images_bottom_left_at_uv_zero() {
        let light = AreaLight {
            emitter: piece(),
            shape: 0,
            l: Vec3::splat(2.0),
            two_sided: false,
            area: 1.0,
            image: Some(EmissionImage::new(screen())),
            spectrum: None,
        };
        // pbrt-v4 flips v: (u, v) = (0, 1) is the image's top left.
        assert_eq!(light.radiance([0.0, 1.0]), Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(light.radiance([1.0, 1.0]), Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(light.radiance([0.0, 0.0]), Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(light.radiance([1.0, 0.0]), Vec3::splat(2.0));
        // Bilinear between texel centres.
        assert_eq!(light.radiance([0.5, 1.0]), Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn power_counts_the_images_mean_luminance() {
        let desc = AreaLightDesc {
            l: Vec3::ONE,
            spectrum: None,
            two_sided: false,
            power: Some(10.0),
            image: Some(EmissionImage::new(screen())),
        };
        let light = AreaLight {
            emitter: piece(),
            shape: 0,
            l: desc.emission(2.0),
            two_sided: false,
            area: 2.0,
            image: desc.image.clone(),
            spectrum: None,
        };
        assert!((light.power() - 10.0).abs() < 1e-4, "{}", light.power());
    }
}
