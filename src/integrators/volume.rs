//! Light through participating media, for the integrators: free flight along a ray
//! segment, transmittance of shadow rays through interface surfaces, and direct light
//! at a point inside a medium.
//!
//! ```text
//! MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_s" [0.2 0.2 0.2]
//! AttributeBegin
//!   MediumInterface "fog" ""  Material "interface"  Shape "sphere" "float radius" 3
//! AttributeEnd
//! ```
//!
//! Nothing here runs for a scene without media: the integrators test
//! `RenderScene::media` first, so such scenes render exactly as before.

use crate::accel::Hit;
use crate::interaction::Footprint;
use crate::math::{Point3, Ray};
use crate::media::{Flight, HenyeyGreenstein};
use crate::render::RenderScene;
use crate::sampling::{Sampler, power_heuristic};
use crate::spectrum::Rgb;
use glam::Vec3;

/// Interface surfaces a shadow ray may cross before it counts as blocked.
const MAX_CROSSINGS: u32 = 256;

/// A scattering point inside a medium.
#[derive(Clone, Copy, Debug)]
pub struct MediumPoint {
    pub p: Vec3,
    /// Back along the arriving ray, unit length.
    pub wo: Vec3,
    pub phase: HenyeyGreenstein,
    /// The scattering and attenuation coefficients here.
    pub sigma_s: Rgb,
    pub sigma_t: Rgb,
    pub medium: u32,
    /// The arriving ray's time.
    pub time: f32,
}

/// Free flight along `ray` in `medium` up to `hit`: `Ok(weight)` when the ray gets
/// there (Tr/pdf), `Err((point, weight))` when it scatters first (Tr/pdf, without σs).
pub fn fly(
    scene: &RenderScene,
    ray: &Ray,
    hit: Option<&Hit>,
    medium: u32,
    sampler: &mut impl Sampler,
) -> Result<Rgb, (MediumPoint, Rgb)> {
    let m = &scene.media[medium as usize];
    let t_max = hit.map_or(f32::INFINITY, |h| h.t);
    match m.sample(ray.o.0, ray.d.0, t_max, sampler, scene.pass_spectrum().as_ref()) {
        Flight::Through { weight } => Ok(weight),
        Flight::Scatter { t, weight, sigma_s, sigma_t } => {
            let p = MediumPoint {
                p: ray.at(t).0,
                wo: -ray.d.0.normalize(),
                phase: m.phase(),
                sigma_s,
                sigma_t,
                medium,
                time: ray.time,
            };
            Err((p, weight))
        }
    }
}

/// The first surface along `ray` that is not an interface, and the transmittance up
/// to it (or to `ray.t_max`, or to infinity where nothing is hit), starting in
/// `medium`; `hit` is in the ray's own parameter. The transmittance is 0 where the ray
/// crosses too many interfaces. Grids estimate it with numbers from `sampler`.
pub fn trace(
    scene: &RenderScene,
    ray: &Ray,
    mut medium: Option<u32>,
    sampler: &mut impl Sampler,
) -> (Option<Hit>, Rgb) {
    let (mut r, mut t0, mut tr) = (*ray, 0.0, Vec3::ONE);
    for _ in 0..MAX_CROSSINGS {
        let hit = scene.intersect(&r);
        if let Some(m) = medium {
            let t = hit.map_or(r.t_max, |h| h.t);
            tr *= scene.media[m as usize].transmittance(r.o.0, r.d.0, t, sampler, scene.pass_spectrum().as_ref());
        }
        let Some(hit) = hit else { return (None, tr) };
        let si = scene.geometry.interaction(&hit);
        if tr == Vec3::ZERO || scene.bsdf(&hit, &si, &Footprint::default()).is_some() {
            return (Some(Hit { t: t0 + hit.t, ..hit }), tr);
        }
        medium = scene.medium_after(&hit, si.n.0, r.d.0, medium);
        t0 += hit.t;
        r = Ray { t_max: r.t_max - hit.t, ..si.spawn_ray(r.d) };
    }
    (None, Vec3::ZERO)
}

/// Transmittance of a shadow ray to its `t_max`: 0 when a surface that is not an
/// interface blocks it.
pub fn transmittance(scene: &RenderScene, ray: &Ray, medium: Option<u32>, sampler: &mut impl Sampler) -> Rgb {
    match trace(scene, ray, medium, sampler) {
        (None, tr) => tr,
        (Some(_), _) => Vec3::ZERO,
    }
}

/// Direct light at a medium point from one light chosen by power: light sampling and
/// phase sampling, combined by the power heuristic. Transmittance along both.
pub fn direct_light(scene: &RenderScene, mp: &MediumPoint, sampler: &mut impl Sampler) -> Rgb {
    if scene.lights.is_empty() {
        return Vec3::ZERO;
    }
    let (mut u_light, u_phase) = (sampler.get2d(), sampler.get2d());
    // The light is picked from the light sample's first number, as at surfaces.
    let Some(pick) = scene.direct_light_choice(u_light[0], None) else { return Vec3::ZERO };
    u_light[0] = pick.rest;
    let (idx, weight) = (pick.index, 1.0 / pick.pmf);
    let light = &scene.lights[idx];
    let mut ld = Vec3::ZERO;
    if let Some(ls) = light.sample_li(&scene.geometry.shapes, mp.p, u_light)
        && !scene.emission_masked(light, ls.surface.as_ref())
        && ls.li != Vec3::ZERO
    {
        let f = mp.phase.p(mp.wo, ls.wi);
        let ray = match ls.p_light {
            Some(p) => Ray {
                o: Point3(mp.p),
                d: crate::math::Vector3(p - mp.p),
                t_max: 1.0 - crate::interaction::SHADOW_EPSILON,
                time: mp.time,
            },
            None => Ray::new(Point3(mp.p), crate::math::Vector3(ls.wi)).at_time(mp.time),
        };
        let tr = transmittance(scene, &ray, Some(mp.medium), sampler);
        let w = if ls.delta { 1.0 } else { power_heuristic(ls.pdf, f) };
        ld += f * tr * scene.emission_of(idx, ls.li) * w / ls.pdf;
    }
    if !light.is_delta() {
        let s = mp.phase.sample(mp.wo, u_phase);
        let ray = Ray::new(Point3(mp.p), crate::math::Vector3(s.wi)).at_time(mp.time);
        let (hit, tr) = trace(scene, &ray, Some(mp.medium), sampler);
        let li = scene.chosen_light_along(hit.as_ref(), idx, &ray);
        if li != Vec3::ZERO {
            let light_pdf = light.pdf_li(&scene.geometry.shapes, mp.p, s.wi);
            if light_pdf > 0.0 {
                ld += tr * li * power_heuristic(s.p, light_pdf);
            }
        }
    }
    ld * weight
}
