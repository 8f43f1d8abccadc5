//! `LightSource "goniometric"`: a point light whose intensity in each direction is read
//! from an image, at the origin of the light's own space.
//!
//! ```text
//! LightSource "goniometric" "rgb I" [1 1 1] "string mapname" "profile.exr"     # v3
//! LightSource "goniometric" "rgb I" [1 1 1] "string filename" "profile.exr"    # v4
//!     "float scale" 1 "float power" 100                                        # v4 power
//! ```
//! Light space has its y axis as the image's pole. pbrt-v3 reads the image by latitude
//! (rows, from +y down) and longitude (columns), in colour and bilinearly; pbrt-v4 by
//! its equal-area square (it must be square), as the mean of the channels, nearest
//! texel, and `power` scales I by the image's mean. Without an image (none named, or
//! unreadable, which is noted) the light is the same every way, as pbrt-v3's.

use super::bounds::LightBounds;
use super::params::{LightContext, emission, finite_image, in_range, power};
use super::{Emission, LightKind, LightSample};
use crate::imageio::RgbImage;
use crate::imageio::lookup::{Wrap, lookup};
use crate::math::equal_area;
use crate::math::{Point3, Ray, Vector3};
use crate::mitsuba::{LightOut, Unsupported};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::sampling::uniform_sphere;
use crate::spectrum::{Rgb, luminance};
use crate::values::Res;
use glam::{DMat3, DMat4, DVec3, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

pub const NAME: &str = "goniometric";

/// How the image is laid on the sphere of directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Profile {
    /// pbrt-v3: latitude and longitude, colour, bilinear.
    LatLong,
    /// pbrt-v4: the equal-area square, the channels' mean, nearest texel.
    EqualArea,
}

/// A goniometric light as read.
#[derive(Clone, Debug)]
pub struct Goniometric {
    pub position: DVec3,
    pub light_from_world: DMat3,
    pub i: Rgb,
    pub image: Option<Arc<RgbImage>>,
    pub profile: Profile,
}

pub fn read(p: &ParamList, m: &DMat4, span: Span, ctx: &mut LightContext) -> Res<LightKind> {
    let profile = if ctx.syntax == Syntax::V4 { Profile::EqualArea } else { Profile::LatLong };
    let param = if profile == Profile::EqualArea { "filename" } else { "mapname" };
    let image = match p.string(param)?.filter(|n| !n.is_empty()) {
        None => None,
        Some(name) => {
            let at = p.named(param).map_or(Span::default(), |q| q.value_span);
            match (ctx.image)(&name) {
                Ok(img) if profile == Profile::EqualArea && img.width != img.height => {
                    let msg = format!(
                        "goniometric: \"{name}\" is {}x{}; pbrt-v4 needs a square image",
                        img.width, img.height
                    );
                    return Err(Diagnostic::error(at, msg));
                }
                Ok(img) => {
                    finite_image(&img, &name, at)?;
                    Some(img)
                }
                Err(e) => {
                    (ctx.missing)(at, format!("goniometric light ({e})"));
                    None
                }
            }
        }
    };
    let mut i = emission(p, "I", &ctx.spectra, span)?;
    if profile == Profile::EqualArea
        && let Some(w) = power(p)?
    {
        let mean = image.as_ref().map_or(1.0, |img| mean_of(img, profile));
        i = in_range(p, "I", i * (w / (4.0 * PI * mean).max(1e-30)), span)?;
    }
    let light_from_world = DMat3::from_mat4(*m).inverse();
    Ok(LightKind::Goniometric(Goniometric {
        position: m.transform_point3(DVec3::ZERO),
        light_from_world,
        i,
        image,
        profile,
    }))
}

/// The image's mean value as the light reads it (luminance for pbrt-v3's colours).
fn mean_of(img: &RgbImage, profile: Profile) -> f32 {
    let n = img.pixels.len().max(1) as f32;
    let value = |p: &[f32; 3]| match profile {
        Profile::LatLong => luminance(Vec3::from(*p)),
        Profile::EqualArea => (p[0] + p[1] + p[2]) / 3.0,
    };
    img.pixels.iter().map(value).sum::<f32>() / n
}

impl Goniometric {
    /// Mitsuba 3 has no goniometric light: a point light of the mean intensity, noted.
    pub fn mitsuba(&self, notes: &mut Vec<Unsupported>) -> LightOut {
        notes.push(Unsupported::new("", "goniometric light", "exported as a point light of its mean intensity"));
        let mean = self.image.as_ref().map_or(1.0, |img| mean_of(img, self.profile));
        LightOut::Point { position: self.position.as_vec3().to_array(), intensity: (self.i * mean).to_array() }
    }
}

/// A goniometric light ready to sample.
#[derive(Clone, Debug)]
pub struct GoniometricLight {
    pub p: Vec3,
    light_from_world: DMat3,
    i: Rgb,
    image: Option<Arc<RgbImage>>,
    profile: Profile,
    mean: f32,
}

impl GoniometricLight {
    pub fn new(d: &Goniometric) -> GoniometricLight {
        let mean = d.image.as_ref().map_or(1.0, |img| mean_of(img, d.profile));
        GoniometricLight {
            p: d.position.as_vec3(),
            light_from_world: d.light_from_world,
            i: d.i,
            image: d.image.clone(),
            profile: d.profile,
            mean,
        }
    }

    /// The intensity leaving along the world direction `w` (pbrt's `Scale` times I).
    pub fn intensity(&self, w: Vec3) -> Rgb {
        let Some(img) = &self.image else { return self.i };
        let wl = (self.light_from_world * w.as_dvec3()).normalize();
        // The image's pole is light space's y axis.
        let wp = DVec3::new(wl.x, wl.z, wl.y);
        match self.profile {
            Profile::LatLong => {
                let theta = wp.z.clamp(-1.0, 1.0).acos();
                let phi = wp.y.atan2(wp.x).rem_euclid(2.0 * std::f64::consts::PI);
                let (s, t) = (phi / (2.0 * std::f64::consts::PI), theta / std::f64::consts::PI);
                self.i * lookup(img, s as f32, t as f32, Wrap::Repeat, true)
            }
            Profile::EqualArea => {
                let [u, v] = equal_area::sphere_to_square(wp);
                let x = ((u * img.width as f64) as usize).min(img.width - 1);
                let y = ((v * img.height as f64) as usize).min(img.height - 1);
                let p = img.pixels[y * img.width + x];
                self.i * ((p[0] + p[1] + p[2]) / 3.0)
            }
        }
    }

    #[inline]
    pub fn power(&self) -> f64 {
        4.0 * std::f64::consts::PI * (luminance(self.i) * self.mean) as f64
    }

    /// Bounds for choosing lights: an isotropic point light, as pbrt-v4 bounds it.
    pub fn bounds(&self) -> LightBounds {
        LightBounds::isotropic(self.p, self.power() as f32)
    }

    #[inline]
    pub fn sample_li(&self, p: Vec3) -> Option<LightSample> {
        let d = self.p - p;
        let d2 = d.length_squared();
        let wi = d / d2.sqrt();
        (d2 > 0.0).then(|| LightSample::delta(wi, self.intensity(-wi) / d2, Some(self.p)))
    }

    #[inline]
    pub fn sample_le(&self, u: [f32; 2]) -> Emission {
        let d = uniform_sphere(u);
        let ray = Ray::new(Point3(self.p), Vector3(d));
        Emission { ray, n: d, pdf_pos: 1.0, pdf_dir: 1.0 / (4.0 * PI), le: self.intensity(d), surface: None }
    }

    /// (position, direction) densities: a delta position (0), uniform directions.
    #[inline]
    pub fn pdf_le(&self) -> (f32, f32) {
        (0.0, 1.0 / (4.0 * PI))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light(profile: Profile, pixels: Vec<[f32; 3]>, size: usize) -> GoniometricLight {
        let img = RgbImage { pixels, ..RgbImage::new(size, size) };
        GoniometricLight::new(&Goniometric {
            position: DVec3::ZERO,
            light_from_world: DMat3::IDENTITY,
            i: Vec3::ONE,
            image: Some(Arc::new(img)),
            profile,
        })
    }

    #[test]
    fn pbrt_v3_reads_rows_from_the_y_pole_down() {
        // Four rows of four: the top two light the +y hemisphere. Row k's centre is at
        // θ = (k + ½)π/4 from +y (pbrt's lookup wraps at the poles, as here).
        let rows = [4.0, 4.0, 1.0, 1.0];
        let l = light(Profile::LatLong, rows.iter().flat_map(|&r| [[r; 3]; 4]).collect(), 4);
        let at = |theta: f32| Vec3::new(theta.sin(), theta.cos(), 0.0);
        assert!((l.intensity(at(PI / 8.0)).x - 4.0).abs() < 1e-4);
        assert!((l.intensity(at(7.0 * PI / 8.0)).x - 1.0).abs() < 1e-4);
    }

    #[test]
    fn pbrt_v4_reads_the_equal_area_square_as_a_mean_of_channels() {
        // The square's centre is the +y pole after pbrt-v4's swap of y and z.
        let mut pixels = vec![[0.0; 3]; 9];
        pixels[4] = [3.0, 6.0, 0.0];
        let l = light(Profile::EqualArea, pixels, 3);
        assert!((l.intensity(Vec3::Y).x - 3.0).abs() < 1e-5);
        assert_eq!(l.intensity(-Vec3::Y).x, 0.0);
    }
}
