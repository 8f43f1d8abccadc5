//! Emission drawn toward what the camera sees: light subpaths from a one-sided area
//! light or a distant light draw one of their two sample points from a mixture of
//! the light's own density and a map learnt before the first pass.
//!
//! ```text
//! LightSource "distant" "point from" [8 6.5 4.5] "point to" [0 0 3]  # a sun outside a room
//! pbrt-sppm render window.pbrt --integrator vcm                 # mapped: few subpaths get in
//! pbrt-sppm render window.pbrt --integrator vcm --emission own  # the light's own sampling
//! ```
//!
//! Both lights map a point of the unit square onto a disk through the concentric map
//! (`sampling::concentric_disk`): an area light its direction (the disk then lifted to
//! the cosine-weighted hemisphere), a distant light its ray's start (on the disk
//! across the world's sphere). Uniform points of the square give the light's own
//! density, so a piecewise-constant density `h` over a grid of [`SIDE`]² cells of the
//! square gives `h` times it. The mixture draws a cell by the map with probability
//! [`GUIDED`] and uniformly otherwise, so its density is the light's own times
//! `q = (1 − GUIDED) + GUIDED·SIDE²·h(cell)`, and never under half of it: the weights
//! read `q` wherever they read the light's emission density (a light subpath's start,
//! a camera subpath that finds the light, next-event estimation), finding the cell
//! through the light's own inverse (`AreaLight::direction_square`,
//! `DistantLight::start_square`).
//!
//! The map is learnt from probe paths traced before the first pass, the same for any
//! thread count, shard or resumed render: a cell's weight is the share of its probes
//! that meet, within the scene's depth, a surface the camera sees from the side the
//! probe arrived on. Under `auto`, the default, a light is mapped only where a survey
//! of [`SURVEY`] probes found it less than [`SPARSE`] of the time; `seen` maps a light
//! below [`PLENTY`]. Sunlight falling on the outside of a room seen from inside is what
//! this is for: such light subpaths end with nothing, and cost as much as the few
//! through the window. Where most of a light's subpaths reach the view, the ones that
//! do not (into a room the camera sees only through a doorway) carry light the camera
//! subpaths connect to, and a map sending them elsewhere loses (`docs/vcm.md`).

use crate::interaction::SurfaceInteraction;
use crate::lights::{Light, WorldSphere};
use crate::materials::TransportMode;
use crate::math::{Point3, Ray, Vector3};
use crate::render::RenderScene;
use crate::sampling::{Distribution1D, Rng, hash};
use glam::Vec3;
use rayon::prelude::*;

/// Cells per side of the square: fine enough for a window a tenth of the world's
/// width (64² cells of 16 probes: `window`'s relMSE 4.61e-2, against 5.26e-2 for 16²
/// cells of 8 and 6.07e-2 unmapped).
pub const SIDE: usize = 64;
/// The mixture's probability of drawing from the map.
pub const GUIDED: f32 = 0.5;
/// Probe paths per cell.
const PROBES: usize = 16;
/// Probe paths that measure, before any map is learnt, how often a light's subpaths
/// reach what the camera sees.
const SURVEY: usize = 1024;
/// The most bounces a probe path takes (at most the scene's depth).
const PROBE_DEPTH: u32 = 8;
/// Lights past this many are left to their own sampling (a mesh emitter is a light
/// per triangle; probing each would cost more than it saves).
pub const MAX_LIGHTS: usize = 64;

/// One light's learnt map: where on the square its subpaths were seen to go.
#[derive(Clone, Debug)]
pub struct EmissionMap {
    cells: Distribution1D,
    /// Per cell, the mixture's density over the light's own: `q` above.
    factor: Vec<f32>,
}

impl EmissionMap {
    /// From each cell's weight (row by row from the square's v = 0); `None` where
    /// every weight is zero.
    pub fn new(weights: &[f64]) -> Option<EmissionMap> {
        let total: f64 = weights.iter().sum();
        if total.is_nan() || total <= 0.0 || weights.len() != SIDE * SIDE {
            return None;
        }
        let n = weights.len() as f64;
        let factor = weights.iter().map(|w| ((1.0 - GUIDED as f64) + GUIDED as f64 * n * w / total) as f32).collect();
        Some(EmissionMap { cells: Distribution1D::new(weights), factor })
    }

    /// The point of the square a light draws from in place of `u` (an area light's
    /// direction, a distant light's start), and the mixture's density there over the
    /// light's own.
    pub fn draw(&self, u: [f32; 2]) -> ([f32; 2], f32) {
        let v = if u[0] < GUIDED {
            match self.cells.pick(u[0] / GUIDED) {
                Some(p) => {
                    let (i, j) = (p.index % SIDE, p.index / SIDE);
                    [(i as f32 + p.rest) / SIDE as f32, (j as f32 + u[1]) / SIDE as f32]
                }
                None => u,
            }
        } else {
            [(u[0] - GUIDED) / (1.0 - GUIDED), u[1]]
        };
        let v = v.map(|x| x.clamp(0.0, 1.0 - f32::EPSILON / 2.0));
        (v, self.factor[cell(v)])
    }

    /// The mixture's density over `light`'s own for its emission that reaches `p`
    /// along the unit direction `d`, leaving a point whose emitting normal is `n`: an
    /// area light's reads its direction, a distant light's its start (1 where the
    /// light's own density is 0).
    pub fn factor(&self, light: &Light, world: WorldSphere, p: Vec3, (n, d): (Vec3, Vec3)) -> f32 {
        match light {
            Light::Area(a) => a.direction_square(n, d).map_or(1.0, |u| self.factor_at(u)),
            Light::Distant(l) => self.factor_at(l.start_square(world, p)),
            _ => 1.0,
        }
    }

    /// The mixture's density over the light's own at point `u` of the square.
    pub fn factor_at(&self, u: [f32; 2]) -> f32 {
        self.factor[cell(u)]
    }
}

fn cell(u: [f32; 2]) -> usize {
    let at = |x: f32| ((x * SIDE as f32) as usize).min(SIDE - 1);
    at(u[0]) + SIDE * at(u[1])
}

/// Which of a light's two sample points a map stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapped {
    /// An area light's direction (`sample_le`'s second point).
    Direction,
    /// A distant light's ray start (its only point).
    Start,
}

/// The lights a map is learnt for, and which of their points it maps.
pub fn mapped(light: &Light) -> Option<Mapped> {
    match light {
        Light::Area(a) if !a.two_sided => Some(Mapped::Direction),
        Light::Distant(_) => Some(Mapped::Start),
        _ => None,
    }
}

/// How light subpaths draw their start (`--emission`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EmissionSampling {
    /// From a map where a light's subpaths rarely reach what the camera sees
    /// ([`SPARSE`]), else the light's own sampling.
    #[default]
    Auto,
    /// The light's own sampling, always (pbrt's).
    Own,
    /// From a map wherever the probes find enough the camera does not see ([`PLENTY`]).
    Seen,
}

impl EmissionSampling {
    /// The option's value that asks for it.
    pub fn name(self) -> &'static str {
        match self {
            EmissionSampling::Auto => "auto",
            EmissionSampling::Own => "own",
            EmissionSampling::Seen => "seen",
        }
    }
}

impl std::str::FromStr for EmissionSampling {
    type Err = String;
    fn from_str(s: &str) -> Result<EmissionSampling, String> {
        [EmissionSampling::Auto, EmissionSampling::Own, EmissionSampling::Seen]
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| format!("expected auto, own or seen, not \"{s}\""))
    }
}

/// `auto` maps a light whose survey reached what the camera sees less often than
/// this: sunlight through a small window (`window`: 0.007). Lights in the suite's other
/// scenes reach it 0.17–0.78 of the time, and a map there left the error within the
/// seeds' spread for more time (`doorway`, 0.61: error × time 1.09; `docs/vcm.md`).
pub const SPARSE: f64 = 0.05;

/// `seen` keeps a light's own sampling above this share: a map that sends little
/// elsewhere is not worth its lookups.
pub const PLENTY: f64 = 0.75;

/// Per light of the scene, its map where it has one: one-sided area lights and
/// distant lights in a vacuum, in a scene of at most [`MAX_LIGHTS`] lights, whose
/// survey found too little of what the camera sees for `mode`.
pub fn maps(scene: &RenderScene, seed: u64, mode: EmissionSampling) -> Vec<Option<EmissionMap>> {
    let n = scene.lights.len();
    let most = match mode {
        EmissionSampling::Own => return vec![None; n],
        EmissionSampling::Auto => SPARSE,
        EmissionSampling::Seen => PLENTY,
    };
    if n > MAX_LIGHTS || !scene.media.is_empty() {
        return vec![None; n];
    }
    (0..n).into_par_iter().map(|k| learn(scene, k, seed, most)).collect()
}

/// Light `k`'s map, if its survey's share is below `most`.
fn learn(scene: &RenderScene, k: usize, seed: u64, most: f64) -> Option<EmissionMap> {
    let light = &scene.lights[k];
    let what = mapped(light)?;
    let time = scene.camera.time(0.5);
    let mut rng = Rng::new(hash(&[seed, k as u64, 0x656d_6974]));
    let probe = |cell: [f32; 2], rng: &mut Rng| {
        let other = [rng.uniform(), rng.uniform()];
        let (u1, u2) = match what {
            Mapped::Direction => (other, cell),
            Mapped::Start => (cell, other),
        };
        reaches_seen(scene, light, (u1, u2), time, rng)
    };
    let surveyed = (0..SURVEY).filter(|_| probe(rng.uniform2(), &mut rng)).count();
    if surveyed as f64 >= most * SURVEY as f64 {
        return None;
    }
    let weights: Vec<f64> = (0..SIDE * SIDE)
        .map(|c| {
            let (i, j) = ((c % SIDE) as f32, (c / SIDE) as f32);
            let cell = |rng: &mut Rng| [(i + rng.uniform()) / SIDE as f32, (j + rng.uniform()) / SIDE as f32];
            (0..PROBES).filter(|_| probe(cell(&mut rng), &mut rng)).count() as f64
        })
        .collect();
    EmissionMap::new(&weights)
}

/// Whether a probe emission, followed by BSDF sampling up to the scene's depth (at most
/// [`PROBE_DEPTH`] bounces), meets a surface the camera sees from the side the probe
/// arrives on (either side where the surface transmits).
fn reaches_seen(scene: &RenderScene, light: &Light, (u1, u2): ([f32; 2], [f32; 2]), time: f32, rng: &mut Rng) -> bool {
    let Some(e) = light.sample_le(&scene.geometry.shapes, scene.world, u1, u2) else { return false };
    let mut ray = Ray::new(e.ray.o, Vector3(e.ray.d.0.normalize())).at_time(time);
    for _ in 0..scene.integrator.max_depth.clamp(1, PROBE_DEPTH) {
        let Some(hit) = scene.intersect(&ray) else { return false };
        let si = scene.geometry.interaction(&hit);
        let wo = -ray.d.0;
        let Some(bsdf) = scene.bsdf(&hit, &si, &Default::default()) else {
            ray = si.spawn_ray(ray.d);
            continue;
        };
        if camera_sees(scene, &si, wo, bsdf.transmits(), time) {
            return true;
        }
        let Some(s) = bsdf.sample_f(wo, rng.uniform2(), rng.uniform(), TransportMode::Importance) else { return false };
        ray = si.spawn_ray(Vector3(s.wi));
    }
    false
}

/// Whether the camera sees `si` (on the film, unoccluded) from the side `wo` leaves
/// on, or from either side where the surface transmits.
fn camera_sees(scene: &RenderScene, si: &SurfaceInteraction, wo: Vec3, transmits: bool, time: f32) -> bool {
    let Some(cs) = scene.camera.sample_wi(si.p.0, [0.5, 0.5], time) else { return false };
    let [x0, x1, y0, y1] = scene.film.pixel_bounds;
    let [x, y] = cs.raster;
    let on_film = x >= x0 as f32 && x < x1 as f32 && y >= y0 as f32 && y < y1 as f32;
    let ng = si.n.0;
    let same_side = wo.dot(ng) * cs.wi.dot(ng) > 0.0;
    on_film && (same_side || transmits) && !scene.intersect_p(&si.spawn_ray_to(Point3(cs.p_lens)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-sided area light of one triangle (only its sidedness is read here).
    fn area_light() -> Light {
        Light::Area(crate::lights::diffuse::AreaLight {
            emitter: crate::shapes::Piece::Triangle { mesh: 0, tri: 0, flags: Default::default() },
            shape: 0,
            l: Vec3::ONE,
            two_sided: false,
            area: 1.0,
            image: None,
            spectrum: None,
        })
    }

    #[test]
    fn a_drawn_direction_reads_back_its_factor() {
        let weights: Vec<f64> = (0..SIDE * SIDE).map(|c| ((c * 7919) % 13) as f64).collect();
        let map = EmissionMap::new(&weights).unwrap();
        let (light, world) = (area_light(), WorldSphere { center: Vec3::ZERO, radius: 1.0 });
        let mut rng = Rng::new(3);
        for _ in 0..20000 {
            let n = crate::sampling::uniform_sphere([rng.uniform(), rng.uniform()]);
            let (v, q) = map.draw([rng.uniform(), rng.uniform()]);
            let local = crate::sampling::cosine_hemisphere(v);
            let (a, b) = crate::math::frame::coordinate_system(n);
            let d = (a * local.x + b * local.y + n * local.z).normalize();
            if local.z < 1e-3 {
                continue;
            }
            // The frame the area light's `sample_le` lifts the disk into.
            let back = map.factor(&light, world, Vec3::ZERO, (n, d));
            // Cell edges may round either way.
            let near = |c: f32| (c * SIDE as f32 - (c * SIDE as f32).round()).abs() < 1e-3;
            assert!(back == q || near(v[0]) || near(v[1]), "{v:?}: drew {q}, read {back}");
        }
    }

    #[test]
    fn a_distant_ray_reads_back_its_factor_anywhere_along_it() {
        let weights: Vec<f64> = (0..SIDE * SIDE).map(|c| ((c * 31) % 7) as f64).collect();
        let map = EmissionMap::new(&weights).unwrap();
        let world = WorldSphere { center: Vec3::new(1.0, -2.0, 0.5), radius: 7.0 };
        let mut rng = Rng::new(5);
        let mut checked = 0;
        for _ in 0..20000 {
            let w = crate::sampling::uniform_sphere([rng.uniform(), rng.uniform()]);
            let light = crate::lights::distant::DistantLight { w, l: Vec3::ONE };
            let (v, q) = map.draw([rng.uniform(), rng.uniform()]);
            let e = light.sample_le(world, v);
            let p = e.ray.o.0 + e.ray.d.0 * (rng.uniform() * 2.0 * world.radius);
            let near = |c: f32| (c * SIDE as f32 - (c * SIDE as f32).round()).abs() < 1e-3;
            if near(v[0]) || near(v[1]) {
                continue;
            }
            checked += 1;
            assert_eq!(map.factor(&Light::Distant(light), world, p, (Vec3::Z, -w)), q, "{v:?}");
        }
        assert!(checked > 19000, "{checked}");
    }

    #[test]
    fn the_mixture_integrates_to_one_and_its_draws_follow_it() {
        let weights: Vec<f64> = (0..SIDE * SIDE).map(|c| if c % 5 == 0 { 3.0 } else { (c % 2) as f64 }).collect();
        let map = EmissionMap::new(&weights).unwrap();
        // Over the square (uniform measure: the light's own density), q integrates to 1.
        let mean: f64 = map.factor.iter().map(|&q| q as f64).sum::<f64>() / (SIDE * SIDE) as f64;
        assert!((mean - 1.0).abs() < 1e-5, "{mean}");
        // χ² of the draws' cells against q / SIDE².
        let (mut counts, draws) = (vec![0u32; SIDE * SIDE], 400_000);
        let mut rng = Rng::new(11);
        for _ in 0..draws {
            counts[cell(map.draw([rng.uniform(), rng.uniform()]).0)] += 1;
        }
        let chi2: f64 = counts
            .iter()
            .zip(&map.factor)
            .map(|(&c, &q)| {
                let e = draws as f64 * q as f64 / (SIDE * SIDE) as f64;
                (c as f64 - e).powi(2) / e
            })
            .sum();
        // Its 99.9th percentile, about the degrees of freedom plus 3.1 of its standard
        // deviations (the normal approximation holds at thousands of them).
        let dof = (SIDE * SIDE - 1) as f64;
        assert!(chi2 < dof + 3.1 * (2.0 * dof).sqrt(), "χ² {chi2} over {dof} degrees of freedom");
    }
}
