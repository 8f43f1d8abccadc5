//! Lights: point, spot, distant, infinite (constant) and diffuse area lights on every
//! shape, with each pbrt version's semantics.
//!
//! ```text
//! LightSource "point" "rgb I" [10 10 10] "point from" [0 4 0]    # v3: from is a world offset
//! LightSource "spot" "blackbody I" [5500 125] "point from" [0 5 9] "point to" [-5 2.75 0]
//!             "float coneangle" 30 "float conedeltaangle" 5        # v3 quartic / v4 smoothstep falloff
//! LightSource "distant" "point from" [0 0 0] "point to" [0 0 1] "rgb L" [3 3 3]
//! LightSource "infinite" "rgb L" [.1 .1 .1]      # or "string mapname"/"filename" (equirectangular)
//! AreaLightSource "diffuse" "rgb L" [4 4 4] "bool twosided" true "float power" 100   # v4 power
//! ```
//! The scene description settles every parameter (`scene::lights`); this module turns
//! the typed lights into what the integrator samples. Every light can be sampled for direct lighting (`sample_li`, with the solid-angle pdf
//! `pdf_li` for MIS), can emit photons (`sample_le`: ray, light normal, position and
//! direction pdfs) and reports its `power` for choosing photon sources. Area lights are
//! one light per quadric and one per triangle, as in pbrt. v4 normalises blackbody
//! spectra to luminance 1 and honours `power`; v3 blackbody is peak-normalised × scale.

pub mod envmap;

use crate::accel::Geometry;
use crate::interaction::offset_ray_origin;
use crate::math::frame::coordinate_system;
use crate::math::{Normal3, Point3, Ray, Vector3};
use crate::sampling::{uniform_cone, uniform_sphere};
use crate::scene::{LightDesc, LightKind};
use crate::shapes::{Piece, ShapeSample};
use crate::spectrum::{Rgb, luminance};
use envmap::EnvMap;
use glam::Vec3;
use std::f32::consts::PI;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub enum Light {
    Point {
        p: Vec3,
        i: Rgb,
    },
    Spot {
        p: Vec3,
        frame: [Vec3; 3],
        i: Rgb,
        cos_total: f32,
        cos_start: f32,
        smooth: bool,
    },
    /// `w` points toward the light.
    Distant {
        w: Vec3,
        l: Rgb,
    },
    Infinite {
        l: Rgb,
        map: Option<Arc<EnvMap>>,
    },
    Area {
        /// The primitive that emits (one light per triangle or patch, as in pbrt).
        emitter: Piece,
        /// The world shape it belongs to (whose alpha mask applies).
        shape: u32,
        l: Rgb,
        two_sided: bool,
        area: f32,
    },
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
    /// The render form of a typed light.
    pub fn from_desc(d: &LightDesc) -> Light {
        match &d.kind {
            LightKind::Point { position, i } => Light::Point { p: position.as_vec3(), i: *i },
            LightKind::Spot { position, direction, i, cos_total, cos_start, smooth_falloff } => {
                let dir = direction.as_vec3();
                let (a, b) = coordinate_system(dir);
                Light::Spot {
                    p: position.as_vec3(),
                    frame: [a, b, dir],
                    i: *i,
                    cos_total: *cos_total,
                    cos_start: *cos_start,
                    smooth: *smooth_falloff,
                }
            }
            LightKind::Distant { toward_light, l } => Light::Distant { w: toward_light.as_vec3(), l: *l },
            LightKind::Infinite { l, map } => Light::Infinite {
                l: *l,
                map: map.as_ref().map(|m| Arc::new(EnvMap::new(m.image.clone(), *l, m.world_from_light))),
            },
        }
    }

    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point { .. } | Light::Spot { .. } | Light::Distant { .. })
    }

    fn spot_falloff(frame: &[Vec3; 3], w: Vec3, cos_total: f32, cos_start: f32, smooth: bool) -> f32 {
        let c = w.dot(frame[2]);
        if c < cos_total {
            return 0.0;
        }
        if c >= cos_start {
            return 1.0;
        }
        let d = (c - cos_total) / (cos_start - cos_total);
        if smooth { d * d * (3.0 - 2.0 * d) } else { d * d * d * d }
    }

    /// Total emitted power, for choosing photon sources (luminance).
    pub fn power(&self, world: WorldSphere) -> f64 {
        // In f64: a light bright enough for 4π·I to pass f32's range still has a power.
        let r2 = (world.radius as f64).powi(2);
        let lum = |c: Vec3| luminance(c) as f64;
        match self {
            Light::Point { i, .. } => 4.0 * std::f64::consts::PI * lum(*i),
            Light::Spot { i, cos_total, cos_start, .. } => {
                lum(*i) * 2.0 * std::f64::consts::PI * (1.0 - 0.5 * (cos_start + cos_total)) as f64
            }
            Light::Distant { l, .. } | Light::Infinite { l, map: None } => lum(*l) * std::f64::consts::PI * r2,
            Light::Infinite { map: Some(env), .. } => env.average_luminance as f64 * std::f64::consts::PI * r2,
            Light::Area { l, two_sided, area, .. } => {
                lum(*l) * *area as f64 * std::f64::consts::PI * if *two_sided { 2.0 } else { 1.0 }
            }
        }
    }

    /// Incident light at `p` from this light.
    pub fn sample_li(&self, g: &Geometry, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        match self {
            Light::Point { p: lp, i } => {
                let d = *lp - p;
                let d2 = d.length_squared();
                (d2 > 0.0).then(|| LightSample {
                    wi: d / d2.sqrt(),
                    li: *i / d2,
                    pdf: 1.0,
                    p_light: Some(*lp),
                    delta: true,
                    surface: None,
                })
            }
            Light::Spot { p: lp, frame, i, cos_total, cos_start, smooth } => {
                let d = *lp - p;
                let d2 = d.length_squared();
                let wi = d / d2.sqrt();
                let f = Self::spot_falloff(frame, -wi, *cos_total, *cos_start, *smooth);
                (d2 > 0.0 && f > 0.0).then(|| LightSample {
                    wi,
                    li: *i * f / d2,
                    pdf: 1.0,
                    p_light: Some(*lp),
                    delta: true,
                    surface: None,
                })
            }
            Light::Distant { w, l } => {
                Some(LightSample { wi: *w, li: *l, pdf: 1.0, p_light: None, delta: true, surface: None })
            }
            Light::Infinite { l, map: None } => {
                let (wi, pdf) = (uniform_sphere(u), 1.0 / (4.0 * PI));
                Some(LightSample { wi, li: *l, pdf, p_light: None, delta: false, surface: None })
            }
            Light::Infinite { map: Some(env), .. } => {
                let (wi, pdf) = env.sample(u)?;
                (pdf > 0.0).then(|| LightSample { wi, li: env.le(wi), pdf, p_light: None, delta: false, surface: None })
            }
            Light::Area { emitter, l, two_sided, .. } => {
                let s = g.shapes.sample_piece(emitter, Some(Point3(p)), u)?;
                let d = s.p.0 - p;
                let wi = d.normalize_or_zero();
                let facing = *two_sided || s.n.0.dot(-wi) > 0.0;
                (s.pdf > 0.0 && facing && wi != Vec3::ZERO).then_some(LightSample {
                    wi,
                    li: *l,
                    pdf: s.pdf,
                    p_light: Some(s.p.0),
                    delta: false,
                    surface: Some(s),
                })
            }
        }
    }

    /// The solid-angle density `sample_li` gives direction `wi` from `p`.
    pub fn pdf_li(&self, g: &Geometry, p: Vec3, wi: Vec3) -> f32 {
        match self {
            Light::Infinite { map: None, .. } => 1.0 / (4.0 * PI),
            Light::Infinite { map: Some(env), .. } => env.pdf(wi),
            Light::Area { emitter, .. } => g.shapes.pdf_piece(emitter, Point3(p), Vector3(wi)),
            _ => 0.0,
        }
    }

    /// A photon: ray, light normal, pdfs and emitted radiance (pbrt's `Sample_Le`).
    pub fn sample_le(&self, g: &Geometry, world: WorldSphere, u1: [f32; 2], u2: [f32; 2]) -> Option<Emission> {
        let r = world.radius;
        match self {
            Light::Point { p, i } => {
                let d = uniform_sphere(u1);
                Some(Emission {
                    ray: Ray::new(Point3(*p), Vector3(d)),
                    n: d,
                    pdf_pos: 1.0,
                    pdf_dir: 1.0 / (4.0 * PI),
                    le: *i,
                    surface: None,
                })
            }
            Light::Spot { p, frame, i, cos_total, cos_start, smooth } => {
                let l = uniform_cone(u1, *cos_total);
                let d = frame[0] * l.x + frame[1] * l.y + frame[2] * l.z;
                let le = *i * Self::spot_falloff(frame, d, *cos_total, *cos_start, *smooth);
                let pdf_dir = 1.0 / (2.0 * PI * (1.0 - cos_total));
                Some(Emission { ray: Ray::new(Point3(*p), Vector3(d)), n: d, pdf_pos: 1.0, pdf_dir, le, surface: None })
            }
            Light::Distant { w, l } => {
                let (a, b) = coordinate_system(*w);
                let cd = crate::camera::concentric_disk(u1);
                let o = world.center + r * (cd.x * a + cd.y * b) + r * *w;
                let ray = Ray::new(Point3(o), Vector3(-*w));
                Some(Emission { ray, n: -*w, pdf_pos: 1.0 / (PI * r * r), pdf_dir: 1.0, le: *l, surface: None })
            }
            Light::Infinite { l, map } => {
                // w points toward the environment; photons travel along d = −w.
                let (w, pdf_dir, le) = match map {
                    None => (uniform_sphere(u1), 1.0 / (4.0 * PI), *l),
                    Some(env) => {
                        let (w, pdf) = env.sample(u1)?;
                        (w, pdf, env.le(w))
                    }
                };
                let d = -w;
                let (a, b) = coordinate_system(w);
                let cd = crate::camera::concentric_disk(u2);
                let o = world.center + r * (cd.x * a + cd.y * b) + r * w;
                let ray = Ray::new(Point3(o), Vector3(d));
                Some(Emission { ray, n: d, pdf_pos: 1.0 / (PI * r * r), pdf_dir, le, surface: None })
            }
            Light::Area { emitter, l, two_sided, .. } => {
                let s = g.shapes.sample_piece(emitter, None, u1)?;
                let n = s.n.0;
                // Cosine-weighted about n; two-sided lights pick a side with probability ½.
                let (mut u2, mut side) = (u2, 1.0);
                if *two_sided {
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
                if *two_sided {
                    pdf_dir *= 0.5;
                }
                let p_error = crate::math::float::gamma(8) * s.p.0.abs() + Vec3::splat(1e-30);
                let o = offset_ray_origin(s.p, p_error, Normal3(n), Vector3(d));
                Some(Emission { ray: Ray::new(o, Vector3(d)), n, pdf_pos: s.pdf, pdf_dir, le: *l, surface: Some(s) })
            }
        }
    }

    /// Radiance from an infinite light along a ray that escapes.
    pub fn le_escaped(&self, d: Vec3) -> Rgb {
        match self {
            Light::Infinite { l, map: None } => *l,
            Light::Infinite { map: Some(env), .. } => env.le(d.normalize()),
            _ => Vec3::ZERO,
        }
    }
}
