//! What both kinds of subpath vertex share: where the vertex is ([`Place`]: a surface
//! point or a point in a medium, and the media on its sides) and what scatters there
//! ([`Scatterer`]: a BSDF or a medium's phase function), and what reaches one point
//! from another ([`visible`]: a visibility test in vacuum, the transmittance with media).
//!
//! ```text
//! MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_s" [0.2 0.2 0.2]
//! Integrator "bdpt"                 # vcm and bdpt scatter in the fog too
//! ```
//!
//! A medium vertex is to the weights what a surface vertex is, with σt (the mean over
//! channels) where a surface has the cosine that turns a solid-angle density into an
//! area density: a distance sampled by free flight has density σt·Tr per unit length,
//! so σt/d² per unit volume over solid angle, and the transmittance is left out of every
//! density, as pbrt's bdpt leaves it out (see [`super::mis`]).

use super::mis::{Factors, PassFactors};
use crate::accel::Hit;
use crate::guiding::Mix;
use crate::integrators::volume;
use crate::interaction::{SHADOW_EPSILON, SurfaceInteraction, offset_ray_origin};
use crate::materials::{Bsdf, BsdfEval, TransportMode};
use crate::math::{Normal3, Point3, Ray, Vector3};
use crate::media::{HenyeyGreenstein, MediumInterface};
use crate::render::RenderScene;
use crate::sampling::Sampler;
use crate::spectrum::Rgb;
use glam::Vec3;

/// Where a vertex is: its point, the error bounds and geometric normal of a surface
/// point (zero in a medium: rays leave a medium point from the point itself), and the
/// media a ray leaving it enters on each side.
#[derive(Clone, Copy, Debug)]
pub struct Place {
    pub p: Vec3,
    pub p_error: Vec3,
    pub ng: Vec3,
    pub sides: MediumInterface,
    /// The path's time (motion blur): rays leaving here carry it.
    pub time: f32,
    /// A BSSRDF lies under the surface here ([`RenderScene::subsurface`]): a subpath
    /// that crosses it goes through the BSSRDF, never straight through its transmission
    /// lobes, so connections and merges across it carry nothing
    /// ([`Place::crosses_into_bssrdf`]); only next-event estimates do, as in pbrt.
    pub over_bssrdf: bool,
}

impl Place {
    /// A surface point a ray in `medium` arrived at (`hit`, `si`): a medium transition's
    /// sides, or that medium on both.
    pub fn on_surface(scene: &RenderScene, hit: &Hit, si: &SurfaceInteraction, medium: Option<u32>) -> Place {
        let sides = match scene.media.is_empty() {
            true => MediumInterface::default(),
            false => match scene.media_of(hit) {
                mi if mi.is_transition() => mi,
                _ => MediumInterface { inside: medium, outside: medium },
            },
        };
        // Per hit: a `disney` material's BSSRDF depends on its textures there.
        let over_bssrdf = scene.has_bssrdf(hit) && scene.bssrdf(hit, si).is_some();
        Place { p: si.p.0, p_error: si.p_error, ng: si.n.0, sides, time: si.time, over_bssrdf }
    }

    /// Whether going from `wo` to `wi` here would cross into a BSSRDF. pbrt's path
    /// tracers send what their BSDF samples across such a boundary into the BSSRDF,
    /// yet their next-event estimate still takes light from the far side through the
    /// transmission lobes: a light behind an open surface, or light seen from inside
    /// by a path that got in where there was no BSSRDF (a `disney` `scatterdistance`
    /// black in places, with `spectrans`). So the camera's next-event estimate alone
    /// counts such pairs (`Cameras::direct_from`); no other technique can.
    pub fn crosses_into_bssrdf(&self, wo: Vec3, wi: Vec3) -> bool {
        self.over_bssrdf && wo.dot(self.ng) * wi.dot(self.ng) < 0.0
    }

    /// A point in medium `m`.
    pub fn in_medium(p: Vec3, m: u32, time: f32) -> Place {
        let sides = MediumInterface { inside: Some(m), outside: Some(m) };
        Place { p, p_error: Vec3::ZERO, ng: Vec3::ZERO, sides, time, over_bssrdf: false }
    }

    /// The medium a ray leaving in direction `d` travels in.
    #[inline]
    pub fn toward(&self, d: Vec3) -> Option<u32> {
        self.sides.toward(d, self.ng)
    }

    /// A ray leaving in direction `d`, offset off the surface.
    pub fn spawn(&self, d: Vec3) -> Ray {
        Ray::new(self.origin_toward(d), Vector3(d)).at_time(self.time)
    }

    /// Where a ray leaving in direction `d` starts.
    pub fn origin_toward(&self, d: Vec3) -> Point3 {
        offset_ray_origin(Point3(self.p), self.p_error, Normal3(self.ng), Vector3(d))
    }
}

/// What scatters at a vertex.
#[derive(Clone, Debug)]
pub enum Scatterer {
    Surface(Bsdf),
    Medium(Phase),
}

/// A medium's scattering at a point: f = σs·p(ωo, ωi), the phase function's density p.
#[derive(Clone, Copy, Debug)]
pub struct Phase {
    pub hg: HenyeyGreenstein,
    pub sigma_s: Rgb,
    /// σt's mean over channels: the weights' density of stopping here (per unit length,
    /// transmittance aside).
    pub density: f64,
}

impl Phase {
    pub fn new(hg: HenyeyGreenstein, sigma_s: Rgb, sigma_t: Rgb) -> Phase {
        // Free flight only stops where σt > 0; the floor keeps a denormal from
        // dividing the weights by zero.
        Phase { hg, sigma_s, density: (sigma_t.element_sum() as f64 / 3.0).max(1e-30) }
    }
}

/// A direction sampled at a vertex.
pub struct Sampled {
    pub wi: Vec3,
    /// The throughput takes f(ωo, ωi) times `scale`: the cosine it takes over the
    /// sampling density (for a medium, f = σs and the scale 1).
    pub f: Rgb,
    pub scale: f32,
    /// The density of ωi (for the weights), of ωo from ωi (the reverse walk's).
    pub pdf: f32,
    pub pdf_rev: f32,
    pub specular: bool,
}

impl Scatterer {
    /// Whether it only scatters specularly (no connection or merge can use it).
    pub fn is_delta(&self) -> bool {
        match self {
            Scatterer::Surface(b) => !b.is_diffuse() && !b.is_glossy(),
            Scatterer::Medium(_) => false,
        }
    }

    pub fn in_medium(&self) -> bool {
        matches!(self, Scatterer::Medium(_))
    }

    /// The pass's merging constants here.
    #[inline]
    pub fn factors(&self, f: &PassFactors) -> Factors {
        f.at(match self {
            Scatterer::Surface(_) => None,
            Scatterer::Medium(m) => Some(m.density),
        })
    }

    /// What the throughput of radiance was divided by going from ωo to ωi
    /// ([`crate::materials::bsdf::Bsdf::eta_scale`]; 1 in a medium).
    pub fn eta_scale(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Scatterer::Surface(b) => b.eta_scale(wo, wi),
            Scatterer::Medium(_) => 1.0,
        }
    }

    /// f and both densities for a pair of directions.
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> BsdfEval {
        match self {
            Scatterer::Surface(b) => b.eval(wo, wi, mode),
            Scatterer::Medium(m) => {
                let p = m.hg.p(wo, wi);
                BsdfEval { f: m.sigma_s * p, pdf: p, pdf_rev: p }
            }
        }
    }

    /// What turns a solid-angle density toward this vertex along `w` into the weights'
    /// density of the vertex: |w·ng| on a surface, σt in a medium.
    #[inline]
    pub fn measure(&self, w: Vec3, ng: Vec3) -> f64 {
        match self {
            Scatterer::Surface(_) => w.dot(ng).abs() as f64,
            Scatterer::Medium(m) => m.density,
        }
    }

    /// The cosine the radiance carried along `w` takes: |w·ns| on a surface, none in a
    /// medium.
    #[inline]
    pub fn cos(&self, w: Vec3) -> f32 {
        match self {
            Scatterer::Surface(b) => w.dot(b.shading_normal()).abs(),
            Scatterer::Medium(_) => 1.0,
        }
    }

    /// Samples a direction for the quantity `mode` carries; `cos(wi, specular)` gives the
    /// cosine the carried quantity takes along the sampled direction (a light vertex's
    /// adjoint one).
    pub fn sample(
        &self,
        wo: Vec3,
        s: &mut impl Sampler,
        mode: TransportMode,
        cos: impl Fn(Vec3, bool) -> f32,
    ) -> Option<Sampled> {
        let b = match self {
            Scatterer::Surface(b) => b,
            Scatterer::Medium(m) => {
                let ps = m.hg.sample(wo, s.get2d());
                return Some(Sampled {
                    wi: ps.wi,
                    f: m.sigma_s,
                    scale: 1.0,
                    pdf: ps.p,
                    pdf_rev: ps.p,
                    specular: false,
                });
            }
        };
        let smp = b.sample_f(wo, s.get2d(), s.get1d(), mode)?;
        let pdf = if smp.proportional { b.pdf_mode(wo, smp.wi, mode) } else { smp.pdf };
        let pdf_rev = if smp.specular { pdf } else { b.pdf_mode(smp.wi, wo, mode.adjoint()) };
        if !(pdf > 0.0 && smp.pdf > 0.0) {
            return None;
        }
        let scale = cos(smp.wi, smp.specular) / smp.pdf;
        Some(Sampled { wi: smp.wi, f: smp.f, scale, pdf, pdf_rev, specular: smp.specular })
    }

    /// Samples a direction for the quantity `mode` carries from the guided mixture
    /// `mix`: the BSDF with its share, the guide otherwise (four numbers either way, so
    /// that the sampler's dimensions stay in step). f and the densities are the BSDF's
    /// for the pair, the forward one the mixture's; `cos` as [`Self::sample`]'s for a
    /// bounce that is not specular. A medium is not guided.
    pub fn sample_guided(
        &self,
        wo: Vec3,
        s: &mut impl Sampler,
        (mix, mode): (&Mix, TransportMode),
        cos: impl Fn(Vec3) -> f32,
    ) -> Option<Sampled> {
        let Scatterer::Surface(b) = self else {
            return self.sample(wo, s, mode, |wi, _| cos(wi));
        };
        let (choice, u, u_lobe) = (s.get1d(), s.get2d(), s.get1d());
        let wi = match choice < mix.bsdf_share {
            true => b.sample_f(wo, u, u_lobe, mode)?.wi,
            false => mix.sample_guide(u),
        };
        let e = b.eval(wo, wi, mode);
        let pdf = mix.pdf(e.pdf, wi);
        if pdf.is_nan() || pdf <= 0.0 || e.f == Vec3::ZERO {
            return None;
        }
        Some(Sampled { wi, f: e.f, scale: cos(wi) / pdf, pdf, pdf_rev: e.pdf_rev, specular: false })
    }
}

/// Free flight along `ray` through `medium` (if any) up to `hit`: the medium point
/// where it scatters, as a place, what scatters there and the unit direction back along
/// the ray; β takes the flight's weight (Tr/pdf) whether it scatters or not.
pub fn flight(
    scene: &RenderScene,
    ray: &Ray,
    (hit, medium): (Option<&Hit>, Option<u32>),
    beta: &mut Rgb,
    s: &mut impl Sampler,
) -> Option<(Place, Scatterer, Vec3)> {
    match volume::fly(scene, ray, hit, medium?, s) {
        Ok(weight) => {
            *beta *= weight;
            None
        }
        Err((mp, weight)) => {
            *beta *= weight;
            let phase = Phase::new(mp.phase, mp.sigma_s, mp.sigma_t);
            Some((Place::in_medium(mp.p, mp.medium, mp.time), Scatterer::Medium(phase), mp.wo))
        }
    }
}

/// What reaches point `to` from a place: 1 or 0 in a scene without media (a visibility
/// test), the transmittance through media and interface surfaces otherwise (numbers
/// from `s` for grids).
pub fn visible(scene: &RenderScene, from: &Place, to: Vec3, s: &mut impl Sampler) -> Rgb {
    let ray = toward_point(from, to);
    if scene.media.is_empty() {
        return unoccluded(scene, &ray);
    }
    volume::transmittance(scene, &ray, from.toward(to - from.p), s)
}

/// What reaches a place from infinitely far along direction `d`.
pub fn visible_along(scene: &RenderScene, from: &Place, d: Vec3, s: &mut impl Sampler) -> Rgb {
    let ray = from.spawn(d);
    if scene.media.is_empty() {
        return unoccluded(scene, &ray);
    }
    volume::transmittance(scene, &ray, from.toward(d), s)
}

/// The shadow ray from a place to a point, stopping short of it.
pub fn toward_point(from: &Place, to: Vec3) -> Ray {
    let o = from.origin_toward(to - from.p);
    Ray { o, d: Vector3(to - o.0), t_max: 1.0 - SHADOW_EPSILON, time: from.time }
}

/// 1 where a shadow ray hits nothing, media left out and every shape opaque (a
/// medium's boundary too, as pbrt-v3's `VisibilityTester::Unoccluded`).
pub fn unoccluded(scene: &RenderScene, ray: &Ray) -> Rgb {
    if scene.intersect_p(ray) { Vec3::ZERO } else { Vec3::ONE }
}

/// What reaches one place from another (each end offset off its surface).
pub fn visible_between(scene: &RenderScene, a: &Place, b: &Place, s: &mut impl Sampler) -> Rgb {
    visible(scene, a, b.origin_toward(a.p - b.p).0, s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guiding::DTree;
    use crate::guiding::dtree::{from_square, to_square};
    use crate::materials::Convention;
    use crate::materials::lobes::Lobe;
    use crate::sampling::Rng;
    use crate::sampling::testing::{cell_mean, histogram, lcg};

    /// A Lambertian surface facing +z and a guide trained on light from a window at
    /// the side (-x, a little up): the mixture of the two.
    fn guided() -> (Scatterer, DTree) {
        let frame = [Vec3::X, Vec3::Y, Vec3::Z];
        let bsdf = Bsdf::new(frame, Vec3::Z, &[Lobe::Lambert(Vec3::splat(0.7))], Convention::PbrtV4);
        let window = Vec3::new(-1.0, 0.0, 0.4).normalize();
        let (mut tree, mut s) = (DTree::default(), 5);
        for _ in 0..3 {
            let mut next = tree.refined(0.01);
            for _ in 0..20_000 {
                let d = from_square([lcg(&mut s), lcg(&mut s)]);
                next.record(d, if d.dot(window) > 0.95 { 40.0 } else { 0.5 });
            }
            tree = next;
        }
        (Scatterer::Surface(bsdf), tree)
    }

    #[test]
    fn the_guided_mixture_integrates_to_one_and_its_samples_follow_it() {
        let (at, tree) = guided();
        // Unfolded (guide samples behind the surface end the path) and folded about +z,
        // for a camera walk and a light walk (the guide of importance).
        for (fold, mode) in [None, Some(Vec3::Z)].into_iter().zip([TransportMode::Radiance, TransportMode::Importance])
        {
            let mix = Mix { tree: &tree, bsdf_share: 0.5, fold };
            check_mixture(&at, &mix, mode);
        }
    }

    fn check_mixture(at: &Scatterer, mix: &Mix, mode: TransportMode) {
        let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
        let pdf = |p: [f32; 2]| {
            let wi = from_square(p);
            mix.pdf(at.eval(wo, wi, mode).pdf, wi) as f64
        };
        let n = 2048;
        let sum: f64 =
            (0..n * n).map(|k| pdf([((k % n) as f32 + 0.5) / n as f32, ((k / n) as f32 + 0.5) / n as f32])).sum();
        let integral = sum * 4.0 * std::f64::consts::PI / (n * n) as f64;
        assert!((integral - 1.0).abs() < 2e-3, "{:?}: ∫pdf = {integral}", mix.fold);
        // χ² on a 16 × 16 grid of the square: each cell within 5σ of its integral.
        let (samples, bins, mut rng) = (400_000usize, 16usize, Rng::new(11));
        let (mut drawn, cos) = (0usize, |wi: Vec3| wi.z.abs());
        let hist = histogram(samples, bins, || match at.sample_guided(wo, &mut rng, (mix, mode), cos) {
            Some(smp) => {
                drawn += 1;
                let expect = mix.pdf(at.eval(wo, smp.wi, mode).pdf, smp.wi);
                assert!((smp.pdf - expect).abs() <= 1e-4 * expect, "{} vs {expect}", smp.pdf);
                assert!((smp.scale - cos(smp.wi) / smp.pdf).abs() <= 1e-5 * smp.scale);
                to_square(smp.wi)
            }
            // A guide sample behind the surface: f = 0, the path ends (filed in the
            // last cell, which is not checked).
            None => [2.0, 2.0],
        });
        let mut chi2 = 0.0;
        let area = 4.0 * std::f64::consts::PI / (bins * bins) as f64;
        for (k, &count) in hist.iter().enumerate().filter(|&(k, _)| k % bins >= bins / 2 && k != bins * bins - 1) {
            let expected = samples as f64 * cell_mean(bins, k, 8, pdf) * area;
            let sigma = expected.max(1.0).sqrt();
            assert!((count as f64 - expected).abs() < 5.0 * sigma, "{:?}: cell {k}: {count} vs {expected}", mix.fold);
            chi2 += (count as f64 - expected).powi(2) / expected.max(1.0);
        }
        let lost = samples - drawn;
        assert!(chi2 < 300.0, "{:?}: χ² {chi2}", mix.fold);
        // Folded, none is lost behind the surface (a few graze it: f = 0 at z = 0).
        assert!(if mix.fold.is_some() { lost < 10 } else { lost > samples / 20 }, "{:?}: {lost} lost", mix.fold);
    }
}
