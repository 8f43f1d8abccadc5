//! `LightSource "projection"`: a point light that projects an image, like a slide
//! projector, along the +z axis of its own space.
//!
//! ```text
//! LightSource "projection" "rgb I" [1 1 1] "string mapname" "slide.exr" "float fov" 45   # v3
//! LightSource "projection" "string filename" "slide.exr" "float fov" 45 "float power" 10   # v4
//! ```
//! `fov` (default 45 in v3, 90 in v4) spans the image's shorter side. pbrt-v3 reads the
//! image bilinearly and tints it by `I`, its top row toward light-space −y (the slide
//! upside down, as pbrt-v3 has it); pbrt-v4 reads the nearest texel, its top row
//! toward +y, has no `I`, and `power` scales it by the image's luminance integrated
//! over the solid angle it covers. Without a readable image (v3) the light is a
//! uniform rectangle of `I`; pbrt-v4 requires the image.

use super::bounds::LightBounds;
use super::params::{LightContext, emission, finite_image, in_range, power};
use super::{Emission, LightKind, LightSample};
use crate::imageio::RgbImage;
use crate::imageio::lookup::{Wrap, lookup};
use crate::math::frame::coordinate_system;
use crate::math::{Point3, Ray, Vector3};
use crate::mitsuba::{LightOut, Unsupported};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::sampling::uniform_cone;
use crate::spectrum::{Rgb, luminance};
use crate::values::{self, Range, Res};
use glam::{DMat3, DMat4, DVec3, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

pub const NAME: &str = "projection";

/// pbrt's near plane: directions closer to the image plane than this are dark.
const HITHER: f32 = 1e-3;

/// A projection light as read.
#[derive(Clone, Debug)]
pub struct Projection {
    pub position: DVec3,
    /// Light space from world space, y flipped for pbrt-v4.
    pub light_from_world: DMat3,
    pub i: Rgb,
    pub image: Option<Arc<RgbImage>>,
    /// tan(fov/2).
    pub tan_half: f32,
    /// pbrt-v4 reads the nearest texel, pbrt-v3 bilinearly.
    pub nearest: bool,
}

pub fn read(p: &ParamList, m: &DMat4, span: Span, ctx: &mut LightContext) -> Res<LightKind> {
    let v4 = ctx.syntax == Syntax::V4;
    let fov = values::float(p, "fov", if v4 { 90.0 } else { 45.0 }, Range::Positive)?;
    if fov >= 180.0 {
        let at = p.named("fov").map_or(span, |q| q.value_span);
        return Err(Diagnostic::error(at, format!("projection: fov {fov}; it must be below 180 degrees")));
    }
    let param = if v4 { "filename" } else { "mapname" };
    let name = p.string(param)?.filter(|n| !n.is_empty());
    let image = match name {
        None if v4 => return Err(Diagnostic::error(span, "projection needs \"string filename\" (as in pbrt-v4)")),
        None => None,
        Some(name) => match (ctx.image)(&name) {
            Ok(img) => {
                finite_image(&img, &name, p.named(param).map_or(span, |q| q.value_span))?;
                Some(img)
            }
            Err(e) if v4 => return Err(Diagnostic::error(p.named(param).map_or(span, |q| q.value_span), e)),
            Err(e) => {
                (ctx.missing)(p.named(param).map_or(span, |q| q.value_span), format!("projection light ({e})"));
                None
            }
        },
    };
    let tan_half = (fov.to_radians() / 2.0).tan();
    let i = if v4 {
        Vec3::splat(values::float(p, "scale", 1.0, Range::NonNegative)?)
    } else {
        emission(p, "I", &ctx.spectra, span)?
    };
    let flip = if v4 { DMat3::from_diagonal(DVec3::new(1.0, -1.0, 1.0)) } else { DMat3::IDENTITY };
    let light_from_world = flip * DMat3::from_mat4(*m).inverse();
    let mut light =
        Projection { position: m.transform_point3(DVec3::ZERO), light_from_world, i, image, tan_half, nearest: v4 };
    if v4 && let Some(w) = power(p)? {
        light.i = in_range(p, "I", light.i * (w / light.unit_power().max(1e-30)), span)?;
    }
    Ok(LightKind::Projection(light))
}

impl Projection {
    /// The screen window: [−aspect, aspect] × [−1, 1] for a wide image, else the
    /// transpose; and the image's aspect.
    fn window(&self) -> [f32; 4] {
        let aspect = self.image.as_ref().map_or(1.0, |img| img.width as f32 / img.height as f32);
        if aspect > 1.0 { [-aspect, aspect, -1.0, 1.0] } else { [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect] }
    }

    /// pbrt-v4's power for I = 1: the image's luminance over the solid angle it covers.
    fn unit_power(&self) -> f32 {
        let Some(img) = &self.image else { return 0.0 };
        let [x0, x1, y0, y1] = self.window();
        let mut sum = 0.0;
        for y in 0..img.height {
            for x in 0..img.width {
                let sx = x0 + (x as f32 + 0.5) / img.width as f32 * (x1 - x0);
                let sy = y0 + (y as f32 + 0.5) / img.height as f32 * (y1 - y0);
                let cos = Vec3::new(sx * self.tan_half, sy * self.tan_half, 1.0).normalize().z;
                sum += luminance(Vec3::from(img.pixels[y * img.width + x])) * cos.powi(3);
            }
        }
        let area = (x1 - x0) * (y1 - y0) * self.tan_half * self.tan_half;
        area * sum / (img.width * img.height) as f32
    }

    /// Mitsuba 3 has a projector only as a plugin of its own: a spot light of the
    /// cone, noted.
    pub fn mitsuba(&self, notes: &mut Vec<Unsupported>) -> LightOut {
        notes.push(Unsupported::new("", "projection light", "exported as a spot light of its cone, without its image"));
        let world_from_light = self.light_from_world.inverse();
        let light = ProjectionLight::new(self);
        LightOut::Spot {
            position: self.position.as_vec3().to_array(),
            direction: (world_from_light * DVec3::Z).normalize().as_vec3().to_array(),
            up: (world_from_light * DVec3::Y).normalize().as_vec3().to_array(),
            intensity: self.i.to_array(),
            cutoff_angle: light.cos_total.acos().to_degrees(),
            beam_width: light.cos_total.acos().to_degrees(),
        }
    }
}

/// A projection light ready to sample.
#[derive(Clone, Debug)]
pub struct ProjectionLight {
    pub p: Vec3,
    light_from_world: DMat3,
    /// The light's axes in world space (x, y, z), for emission.
    frame: [Vec3; 3],
    d: Projection,
    window: [f32; 4],
    /// The cosine of the cone holding the whole image.
    cos_total: f32,
}

impl ProjectionLight {
    pub fn new(d: &Projection) -> ProjectionLight {
        let window = d.window();
        let corner = Vec3::new(window[1] * d.tan_half, window[3] * d.tan_half, 1.0);
        let world_from_light = d.light_from_world.inverse();
        let z = (world_from_light * DVec3::Z).normalize().as_vec3();
        let (x, y) = coordinate_system(z);
        ProjectionLight {
            p: d.position.as_vec3(),
            light_from_world: d.light_from_world,
            frame: [x, y, z],
            d: d.clone(),
            window,
            cos_total: corner.normalize().z,
        }
    }

    /// The intensity leaving along the world direction `w` (pbrt's `Projection` times I).
    pub fn intensity(&self, w: Vec3) -> Rgb {
        let wl = (self.light_from_world * w.as_dvec3()).normalize().as_vec3();
        if wl.z < HITHER {
            return Vec3::ZERO;
        }
        let (sx, sy) = (wl.x / (wl.z * self.d.tan_half), wl.y / (wl.z * self.d.tan_half));
        let [x0, x1, y0, y1] = self.window;
        if !(x0..=x1).contains(&sx) || !(y0..=y1).contains(&sy) {
            return Vec3::ZERO;
        }
        let Some(img) = &self.d.image else { return self.d.i };
        let (s, t) = ((sx - x0) / (x1 - x0), (sy - y0) / (y1 - y0));
        let texel = if self.d.nearest {
            let x = ((s * img.width as f32) as usize).min(img.width - 1);
            let y = ((t * img.height as f32) as usize).min(img.height - 1);
            Vec3::from(img.pixels[y * img.width + x]).max(Vec3::ZERO)
        } else {
            lookup(img, s, t, Wrap::Repeat, true)
        };
        self.d.i * texel
    }

    #[inline]
    pub fn power(&self) -> f64 {
        let mean = self.d.image.as_ref().map_or(1.0, |img| {
            img.pixels.iter().map(|p| luminance(Vec3::from(*p))).sum::<f32>() / img.pixels.len().max(1) as f32
        });
        (luminance(self.d.i) * mean) as f64 * 2.0 * std::f64::consts::PI * (1.0 - self.cos_total) as f64
    }

    /// Bounds for choosing lights: its axis, with light out to the image's corners.
    pub fn bounds(&self) -> LightBounds {
        let point = LightBounds::isotropic(self.p, self.power() as f32);
        LightBounds { w: self.frame[2], cos_theta_o: 1.0, cos_theta_e: self.cos_total, ..point }
    }

    #[inline]
    pub fn sample_li(&self, p: Vec3) -> Option<LightSample> {
        let d = self.p - p;
        let d2 = d.length_squared();
        let wi = d / d2.sqrt();
        let i = self.intensity(-wi);
        (d2 > 0.0 && i != Vec3::ZERO).then(|| LightSample::delta(wi, i / d2, Some(self.p)))
    }

    /// A photon: a direction uniform in the cone holding the image.
    #[inline]
    pub fn sample_le(&self, u: [f32; 2]) -> Emission {
        let l = uniform_cone(u, self.cos_total);
        let [a, b, c] = self.frame;
        let d = a * l.x + b * l.y + c * l.z;
        let ray = Ray::new(Point3(self.p), Vector3(d));
        Emission { ray, n: d, pdf_pos: 1.0, pdf_dir: self.pdf_dir(), le: self.intensity(d), surface: None }
    }

    /// The density of `sample_le`'s directions: uniform within the frustum's cone.
    pub fn pdf_dir(&self) -> f32 {
        1.0 / (2.0 * PI * (1.0 - self.cos_total))
    }

    /// (position, direction) densities: a delta position (0), uniform in the cone.
    #[inline]
    pub fn pdf_le(&self, d: Vec3) -> (f32, f32) {
        (0.0, if d.dot(self.frame[2]) >= self.cos_total { self.pdf_dir() } else { 0.0 })
    }
}
