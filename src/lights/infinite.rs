//! `LightSource "infinite"`: light from every direction, constant or from an
//! environment map ([`super::envmap`]): latitude-longitude in v3 files, pbrt-v4's
//! equal-area square in v4 ones.
//!
//! ```text
//! LightSource "infinite" "rgb L" [.1 .1 .1]
//! LightSource "infinite" "string mapname" "sky.exr"            # v3: latitude-longitude
//! LightSource "infinite" "string filename" "sky.exr" "float illuminance" 1000   # v4: equal-area
//! LightSource "infinite" "string filename" "sky.exr" "point3 portal" [...]      # v4: a window
//! ```
//! A v4 `portal` (four world-space corners) lets the sky in through that rectangle
//! alone ([`super::portal`]); without a map, the portal's sky is a 1×1 map of `L`.
//! As in pbrt-v4, a v4 map and `L` together are an error, except with a portal, where
//! `L` is ignored with a warning (pbrt-v3 multiplies its `mapname` by `L`).
//! (`mapname` in a v4 file, which pbrt-v4 does not know, is read as pbrt-v3 reads it.)
//! v4's `illuminance` scales the light so that an upward-facing surface (light-space
//! +z) receives that many lux, computed as pbrt-v4 computes it (for a map, with half
//! the solid angle its texels cover, so pbrt-v4 and we render twice the lux asked for;
//! `--fix map-illuminance` gives the lux asked for).
//! A v4 map must be square, as pbrt-v4 requires (a located error). A map that cannot be
//! read leaves the constant `L`, with a located warning. Photons start on a disk of the
//! scene's bounding sphere.

use super::envmap::{EnvMap, Mapping};
use super::params::{LightContext, emission, finite_image, illuminance, in_range, scale};
use super::portal::{Portal, PortalMap};
use super::{Emission, LightKind, LightSample, WorldSphere};
use crate::fixes::{Fix, Fixes};
use crate::imageio::RgbImage;
use crate::math::equal_area;
use crate::math::frame::coordinate_system;
use crate::math::transform::row_major;
use crate::math::{Point3, Ray, Vector3};
use crate::mitsuba::{LightOut, Unsupported};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::sampling::{concentric_disk, uniform_sphere};
use crate::spectrum::{Rgb, luminance};
use crate::values::{self, Res};
use glam::{DMat3, DMat4, DVec3, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

pub const NAME: &str = "infinite";

/// An environment map, its mapping and its orientation.
#[derive(Clone, Debug)]
pub struct EnvMapDesc {
    /// The file name as the scene wrote it, and where it was read from.
    pub filename: String,
    pub path: std::path::PathBuf,
    pub image: Arc<RgbImage>,
    pub mapping: Mapping,
    pub world_from_light: DMat3,
}

/// An infinite light as read; `l` scales the map when there is one.
#[derive(Clone, Debug)]
pub struct Infinite {
    pub l: Rgb,
    pub map: Option<EnvMapDesc>,
    /// `l` was scaled to an `illuminance` by pbrt-v4's measure of an equal-area map,
    /// which `--fix map-illuminance` corrects.
    pub pbrt_map_illuminance: bool,
    /// A v4 portal, with the light's orientation (its map's, or the CTM's without one).
    pub portal: Option<Box<(Portal, DMat3)>>,
}

pub fn read(p: &ParamList, m: &DMat4, span: Span, ctx: &mut LightContext) -> Res<LightKind> {
    let portal = match ctx.syntax {
        Syntax::V4 => portal(p, ctx.warnings)?,
        Syntax::V3 => {
            values::ignored(p, &["portal"], "pbrt-v3 has no portals", ctx.warnings);
            None
        }
    };
    let mut l = emission(p, "L", &ctx.spectra, span)?;
    let map = map(p, m, ctx)?;
    // A latitude-longitude map (v3's `mapname` in a v4 file) has no portal in pbrt-v4.
    let portal = match &map {
        Some(env) if env.mapping == Mapping::Equirect && portal.is_some() => {
            let at = p.named("portal").map_or(span, |q| q.span);
            let msg = "infinite: a portal needs pbrt-v4's equal-area map (\"filename\"); it is ignored";
            ctx.warnings.push(Diagnostic::warning(at, msg));
            None
        }
        _ => portal.map(|portal| Box::new((portal, DMat3::from_mat4(*m)))),
    };
    if let Some(scale_only) = l_beside_map(p, &map, ctx)? {
        l = scale_only;
    }
    let mut pbrt_map_illuminance = false;
    if let Some(e) = illuminance(p)? {
        // A portal without a map has pbrt-v4's 1×1 map of L.
        let one_texel = || RgbImage::from_pixels(1, 1, vec![[1.0; 3]]);
        pbrt_map_illuminance = portal.is_some() || map.as_ref().is_some_and(|env| env.mapping == Mapping::EqualArea);
        let up = match &map {
            None if portal.is_some() => upper_hemisphere_illuminance(&one_texel(), Mapping::EqualArea) * luminance(l),
            None => PI * luminance(l),
            Some(env) => upper_hemisphere_illuminance(&env.image, env.mapping) * luminance(l),
        };
        l = in_range(p, "L", l * (e / up.max(1e-9)), span)?;
    }
    Ok(LightKind::Infinite(Infinite { l, map, pbrt_map_illuminance, portal }))
}

/// Whether a v4 file's equal-area map takes the place of its `L` (with a portal); the
/// one test both the light's colour and its emission spectrum go by.
pub fn map_replaces_l(p: &ParamList) -> bool {
    p.named("portal").is_some() && p.named("filename").is_some() && p.named("mapname").is_none()
}

/// pbrt-v4 refuses `L` beside an equal-area map, and with a portal reads the map and
/// leaves `L` out: then the emission is `scale` alone (`Some`). pbrt-v3 multiplies
/// its `mapname` by `L`, as we do in v3 files.
fn l_beside_map(p: &ParamList, map: &Option<EnvMapDesc>, ctx: &mut LightContext) -> Res<Option<Rgb>> {
    let equal_area = map.as_ref().is_some_and(|env| env.mapping == Mapping::EqualArea);
    let Some(l) = p.named("L").filter(|_| equal_area && ctx.syntax == Syntax::V4) else { return Ok(None) };
    if !map_replaces_l(p) {
        let msg = "infinite: pbrt-v4 takes either \"L\" or \"filename\", not both";
        return Err(Diagnostic::error(l.span, msg));
    }
    l.mark_used();
    let msg = "infinite: \"L\" is ignored beside a portal's map, as pbrt-v4 ignores it";
    ctx.warnings.push(Diagnostic::warning(l.span, msg));
    Ok(Some(scale(p, &ctx.spectra)?))
}

/// A v4 `point3 portal`: four corners making a rectangle, as pbrt-v4 requires (it
/// warns where they do not, and renders).
fn portal(p: &ParamList, warnings: &mut Vec<Diagnostic>) -> Res<Option<Portal>> {
    let Some(param) = p.array("portal", crate::parser::params::ParamType::Point3)? else { return Ok(None) };
    let v = param.floats();
    if v.len() != 12 {
        let msg = format!("infinite: a portal needs 4 corners, found {}", v.len() / 3);
        return Err(Diagnostic::error(param.value_span, msg));
    }
    let corner = |i: usize| DVec3::new(v[3 * i] as f64, v[3 * i + 1] as f64, v[3 * i + 2] as f64);
    let Some(portal) =
        Portal::new([corner(0), corner(1), corner(2), corner(3)]).filter(|_| v.iter().all(|x| x.is_finite()))
    else {
        return Err(Diagnostic::error(param.value_span, "infinite: the portal's corners make no rectangle"));
    };
    if !portal.is_rectangle() {
        let msg = "infinite: the portal is not a planar rectangle (pbrt-v4 warns too, and renders)";
        warnings.push(Diagnostic::warning(param.value_span, msg));
    }
    Ok(Some(portal))
}

/// The map `mapname` (v3) or `filename` (v4) names, if it can be read.
fn map(p: &ParamList, m: &DMat4, ctx: &mut LightContext) -> Res<Option<EnvMapDesc>> {
    let name = match p.string("mapname")? {
        Some(n) => Some((n, "mapname")),
        None => p.string("filename")?.map(|n| (n, "filename")),
    };
    let Some((filename, param)) = name.filter(|(n, _)| !n.is_empty()) else { return Ok(None) };
    let at = p.named(param).map_or(Span::default(), |q| q.value_span);
    // pbrt-v4 names its equal-area map `filename`; pbrt-v3's `mapname` keeps its own
    // latitude-longitude meaning wherever it is written.
    let mapping = match (ctx.syntax, param) {
        (Syntax::V4, "filename") => Mapping::EqualArea,
        _ => Mapping::Equirect,
    };
    match (ctx.image)(&filename) {
        Ok(image) if mapping == Mapping::EqualArea && image.width != image.height => {
            let (w, h) = (image.width, image.height);
            let msg = format!(
                "infinite: \"{filename}\" is {w}x{h}; pbrt-v4 reads environment maps as equal-area squares and refuses others"
            );
            Err(Diagnostic::error(at, msg))
        }
        Ok(image) => {
            finite_image(&image, &filename, at)?;
            let path = crate::parser::stmt::resolve_relative(ctx.spectra.base_dir, &filename);
            Ok(Some(EnvMapDesc { filename, path, image, mapping, world_from_light: DMat3::from_mat4(*m) }))
        }
        Err(e) => {
            (ctx.missing)(at, format!("environment map ({e})"));
            Ok(None)
        }
    }
}

/// ∫ over the map's upper hemisphere (θ < π/2) of luminance · cos θ dω, as the file's
/// pbrt computes it.
fn upper_hemisphere_illuminance(img: &RgbImage, mapping: Mapping) -> f32 {
    use std::f64::consts::PI;
    let (w, h) = (img.width, img.height);
    if mapping == Mapping::EqualArea {
        // pbrt-v4 weighs each texel by 2π/(w·h), half the solid angle it covers; we
        // scale as it does, so that a file's `illuminance` gives pbrt-v4's image
        // (`--fix map-illuminance` halves the light, [`InfiniteLight::new`]).
        let mut sum = 0.0;
        for (i, px) in img.pixels.iter().enumerate() {
            let uv = [((i % w) as f64 + 0.5) / w as f64, ((i / w) as f64 + 0.5) / h as f64];
            let z = equal_area::square_to_sphere(uv).z;
            if z > 0.0 {
                sum += luminance(Vec3::from(*px)) as f64 * z;
            }
        }
        return (sum * 2.0 * PI / (w * h).max(1) as f64) as f32;
    }
    let cell = (PI / h as f64) * (2.0 * PI / w as f64);
    let mut sum = 0.0;
    for y in 0..h {
        let theta = (y as f64 + 0.5) / h as f64 * PI;
        if theta >= PI / 2.0 {
            break;
        }
        let row: f64 = img.pixels[y * w..(y + 1) * w].iter().map(|px| luminance(Vec3::from(*px)) as f64).sum();
        sum += row * theta.cos() * theta.sin() * cell;
    }
    sum as f32
}

impl Infinite {
    /// Mitsuba's `constant`, or its `envmap`, which reads directions as
    /// (atan2(x, −z)/2π, acos(y)/π) where pbrt reads (atan2(y, x)/2π, acos(z)/π): its
    /// axes are ours through a reflection, (x, y, z)_mitsuba = (y, z, −x)_pbrt.
    pub fn mitsuba(&self, world_from_light: &DMat4, notes: &mut Vec<Unsupported>) -> LightOut {
        if self.portal.is_some() {
            let why = "Mitsuba has no portals: the whole sky lights the scene there";
            notes.push(Unsupported::new("", "infinite light portal", why));
        }
        let (l, Some(map)) = (self.l, &self.map) else { return LightOut::Constant { radiance: self.l.to_array() } };
        let path = std::path::absolute(&map.path).unwrap_or_else(|_| map.path.clone());
        if map.mapping == Mapping::EqualArea {
            let why = "Mitsuba's envmap is latitude-longitude: pbrt-v4's equal-area map is written as is and reads wrongly there";
            notes.push(Unsupported::new("", "equal-area environment map", why));
        }
        if l.max_element() - l.min_element() > 1e-6 * l.max_element() {
            let why = "a coloured scale has no Mitsuba equivalent; its mean is used";
            notes.push(Unsupported::new("", "environment map scale", why));
        }
        let rotation = DMat3::from_mat4(*world_from_light);
        let pbrt_from_mitsuba = DMat3::from_cols(DVec3::Y, DVec3::Z, -DVec3::X);
        let to_world = DMat4::from_mat3(rotation * pbrt_from_mitsuba);
        LightOut::EnvMap {
            filename: path.display().to_string(),
            to_world: row_major(&to_world),
            scale: (l.x + l.y + l.z) / 3.0,
        }
    }
}

/// What an infinite light shows in each direction.
#[derive(Clone, Debug)]
pub enum Sky {
    /// Its `L` everywhere.
    Uniform,
    /// An environment map (scaled by `L`).
    Map(Arc<EnvMap>),
    /// A v4 map (or `L`) seen only through a portal.
    Portal(Arc<PortalMap>),
}

/// An infinite light ready to sample.
#[derive(Clone, Debug)]
pub struct InfiniteLight {
    pub l: Rgb,
    pub sky: Sky,
}

impl InfiniteLight {
    pub fn new(d: &Infinite, fixes: Fixes) -> InfiniteLight {
        // DEVIATION(pbrt): appearance, `--fix map-illuminance`: the texels' true solid
        // angle, 4π/(w·h), where pbrt-v4 counts 2π/(w·h) and so doubles the light.
        let l = if d.pbrt_map_illuminance && fixes.has(Fix::MapIlluminance) { d.l * 0.5 } else { d.l };
        let sky = match (d.portal.as_deref(), &d.map) {
            (Some(&(portal, _)), Some(m)) => {
                Sky::Portal(Arc::new(PortalMap::new(&m.image.pixels, m.image.width, l, m.world_from_light, portal)))
            }
            (Some(&(portal, world_from_light)), None) => {
                Sky::Portal(Arc::new(PortalMap::new(&[[1.0; 3]], 1, l, world_from_light, portal)))
            }
            (None, Some(m)) => Sky::Map(Arc::new(EnvMap::new(m.image.clone(), l, m.world_from_light, m.mapping))),
            (None, None) => Sky::Uniform,
        };
        InfiniteLight { l, sky }
    }

    #[inline]
    pub fn power(&self, world: WorldSphere) -> f64 {
        let lum = match &self.sky {
            Sky::Portal(portal) => return portal.power,
            Sky::Uniform => luminance(self.l),
            Sky::Map(env) => env.average_luminance,
        };
        lum as f64 * std::f64::consts::PI * (world.radius as f64).powi(2)
    }

    /// Incident light at `p` (only a portal's depends on `p`).
    #[inline]
    pub fn sample_li(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let (wi, li, pdf) = match &self.sky {
            Sky::Portal(portal) => portal.sample_li(p, u)?,
            Sky::Uniform => (uniform_sphere(u), self.l, 1.0 / (4.0 * PI)),
            Sky::Map(env) => {
                let (wi, pdf) = env.sample(u)?;
                (wi, env.le(wi), pdf)
            }
        };
        (pdf > 0.0).then_some(LightSample { wi, li, pdf, p_light: None, delta: false, surface: None })
    }

    /// The solid-angle density `sample_li` gives direction `wi` at `p`.
    #[inline]
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        match &self.sky {
            Sky::Portal(portal) => portal.pdf_li(p, wi),
            Sky::Uniform => 1.0 / (4.0 * PI),
            Sky::Map(env) => env.pdf(wi),
        }
    }

    /// A photon: a direction toward the environment, then a start on the disk of the
    /// world's radius facing it.
    #[inline]
    pub fn sample_le(&self, world: WorldSphere, u1: [f32; 2], u2: [f32; 2]) -> Option<Emission> {
        // w points toward the environment; photons travel along d = −w.
        let (w, le, pdf_dir) = match &self.sky {
            Sky::Portal(portal) => portal.sample_direction(u1)?,
            Sky::Uniform => (uniform_sphere(u1), self.l, 1.0 / (4.0 * PI)),
            Sky::Map(env) => {
                let (w, pdf) = env.sample(u1)?;
                (w, env.le(w), pdf)
            }
        };
        let (d, r) = (-w, world.radius);
        let (a, b) = coordinate_system(w);
        let cd = concentric_disk(u2);
        let o = world.center + r * (cd.x * a + cd.y * b) + r * w;
        let ray = Ray::new(Point3(o), Vector3(d));
        Some(Emission { ray, n: d, pdf_pos: 1.0 / (PI * r * r), pdf_dir, le, surface: None })
    }

    /// An emission for bidirectional methods: through the portal where there is one
    /// ([`PortalMap::sample_through`]), else as [`Self::sample_le`].
    pub fn sample_le_through_portal(&self, world: WorldSphere, u1: [f32; 2], u2: [f32; 2]) -> Option<Emission> {
        let Sky::Portal(portal) = &self.sky else { return self.sample_le(world, u1, u2) };
        let reach = 2.0 * world.radius as f64 + world.center.as_dvec3().length();
        let (o, d, le, pdf_pos, pdf_dir) = portal.sample_through(u1, u2, reach)?;
        Some(Emission { ray: Ray::new(Point3(o), Vector3(d)), n: d, pdf_pos, pdf_dir, le, surface: None })
    }

    /// (position, direction) densities of an emission travelling along `d`: as
    /// [`Self::sample_le_through_portal`] draws it, which vcm and bdpt use.
    #[inline]
    pub fn pdf_le(&self, world: WorldSphere, d: Vec3) -> (f32, f32) {
        let pdf_dir = match &self.sky {
            Sky::Portal(portal) => return (portal.pdf_position(d), portal.pdf_direction(-d)),
            Sky::Uniform => 1.0 / (4.0 * PI),
            Sky::Map(env) => env.pdf(-d),
        };
        (1.0 / (PI * world.radius * world.radius), pdf_dir)
    }

    /// Radiance along a ray from `o` that escapes in direction `d` (only a portal's
    /// depends on `o`).
    #[inline]
    pub fn le(&self, o: Vec3, d: Vec3) -> Rgb {
        match &self.sky {
            Sky::Portal(portal) => portal.le(o, d.normalize()),
            Sky::Uniform => self.l,
            Sky::Map(env) => env.le(d.normalize()),
        }
    }
}
