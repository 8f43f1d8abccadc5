//! pbrt-v3's `whitted` and `directlighting` ([`crate::integrators::vcm::Techniques::Direct`]):
//! the image they render, which leaves out indirect light.
//!
//! ```text
//! Integrator "directlighting" "integer maxdepth" 5   # rendered with direct
//! Integrator "whitted"                               # the same image
//! ```
//!
//! Every vertex takes light straight from the lights: next-event estimation and one
//! BSDF sample finding an emitter, weighted against each other by the power heuristic
//! (the two strategies directlighting combines; whitted samples the lights alone, for
//! the same mean). From there the path follows every perfectly specular direction (a
//! dielectric's reflection and its refraction both, with their Fresnel shares), as
//! pbrt's recursion does, while the depth stays below maxdepth; the depth bounds only
//! that recursion, so maxdepth 0 still lights the first hit. Past [`MAX_SPLITS`]
//! two-way splits one branch is chosen at random instead, which keeps the mean and
//! bounds the work. No light subpaths are traced. Media are left out as pbrt-v3 leaves
//! them there: camera rays cross them untouched and shadow rays stop at any shape, a
//! medium's boundary too.

use super::{Cameras, Next, PixelSample, Vertex, scatter};
use crate::accel::Hit;
use crate::integrators::vcm::mis::Partial;
use crate::integrators::vcm::vertex::{Place, Scatterer};
use crate::interaction::SurfaceInteraction;
use crate::materials::TransportMode;
use crate::math::Ray;
use crate::math::ray::RayDifferential;
use crate::sampling::{Distribution1D, Sampler};
use crate::spectrum::{Rgb, luminance};
use glam::Vec3;

/// A camera path's two-way specular splits followed in full; past them one branch of
/// each is chosen at random (a glass ball with a large maxdepth would otherwise take
/// 2^maxdepth rays, as it does in pbrt).
// DEVIATION(pbrt): robustness. pbrt follows every branch at any depth.
pub const MAX_SPLITS: u32 = 6;

/// A ray still to follow: its throughput, partial sums, where it left (for the
/// distance to the next vertex), edges so far and splits taken.
struct Branch {
    ray: Ray,
    diff: Option<RayDifferential>,
    beta: Rgb,
    partial: Partial,
    prev: Vec3,
    len: u32,
    splits: u32,
    /// It kept only its first wavelength (dispersion).
    terminated: bool,
}

/// What a ray found: its vertex (the place, what scatters there, the direction back,
/// the surface hit).
type Found = (Place, Scatterer, Vec3, Option<(Hit, SurfaceInteraction)>);

impl Cameras<'_> {
    /// What a camera ray gives its pixel: the tree of specular branches from it, each
    /// vertex lit straight from the lights.
    pub(super) fn direct_path(
        &self,
        ray: Ray,
        diff: Option<RayDifferential>,
        beta: Rgb,
        partial: Partial,
        s: &mut impl Sampler,
    ) -> PixelSample {
        let mut out = PixelSample::default();
        let mut todo = vec![Branch { ray, diff, beta, partial, prev: ray.o.0, len: 0, splits: 0, terminated: false }];
        while let Some(b) = todo.pop() {
            self.direct_branch(b, &mut todo, s, &mut out);
        }
        out
    }

    /// One branch: the emitter its ray finds, the direct light at its vertex, and the
    /// specular branches from there pushed onto `todo`.
    fn direct_branch(&self, b: Branch, todo: &mut Vec<Branch>, s: &mut impl Sampler, out: &mut PixelSample) {
        let pass = self.pass;
        let (origin, mut partial, mut beta) = (b.ray.o.0, b.partial, b.beta);
        let Some((place, at, wo, surf)) = self.find(b.ray, b.diff, (b.len, partial), &mut beta, s, out) else {
            return;
        };
        let len = b.len + 1;
        let dist2 = (place.p - b.prev).length_squared() as f64;
        partial.arrive(Some(dist2), at.measure(wo, place.ng));
        let mut terminated = b.terminated;
        let v = Vertex { terminated, ..Vertex::plain(place, &at, wo, partial, len) };
        if let Some((hit, si)) = &surf {
            out.traced += beta * self.emitted(hit, si, &v, origin, dist2);
            pass.scene.terminate_if_dispersed(hit, &mut beta, &mut terminated);
        }
        let v = Vertex { terminated, ..v };
        if len >= pass.max_len || (surf.is_some() && wo.dot(v.place.ng) == 0.0) {
            return;
        }
        out.work.vertices += 1;
        if !at.is_delta() {
            // Next-event estimation alone: the mode uses no other technique there.
            let (nee, _) = self.at_vertex(&v, &[], s, (&mut out.work, &mut Vec::new()));
            out.traced += beta * nee;
            let found = self.bsdf_emitter(&v, s, out);
            out.traced += beta * found;
        }
        let Scatterer::Surface(bsdf) = &at else { return };
        if len + 1 >= pass.max_len {
            return;
        }
        let branches: Vec<(Vec3, Rgb)> = bsdf.specular_branches(wo, TransportMode::Radiance).collect();
        let split = branches.len() > 1;
        let pick = (split && b.splits >= MAX_SPLITS).then(|| choose(&branches, s.get1d()));
        for (k, &(wi, w)) in branches.iter().enumerate() {
            let w = match pick {
                Some((chosen, p)) if chosen == k => w / p,
                Some(_) => continue,
                None => w,
            };
            let mut p = partial;
            p.scatter(at.measure(wi, v.place.ng), 1.0, 1.0, true, false, at.factors(&pass.factors));
            let ray = v.place.spawn(wi);
            let splits = b.splits + split as u32;
            let (prev, beta) = (v.place.p, beta * w);
            todo.push(Branch { ray, diff: None, beta, partial: p, prev, len, splits, terminated });
        }
    }

    /// Where a ray next scatters, crossing surfaces without a material; counts the
    /// light at infinity it escapes to (`len` edges before it, `partial` its sums).
    fn find(
        &self,
        mut ray: Ray,
        mut diff: Option<RayDifferential>,
        (len, partial): (u32, Partial),
        beta: &mut Rgb,
        s: &mut impl Sampler,
        out: &mut PixelSample,
    ) -> Option<Found> {
        let origin = ray.o.0;
        let (mut passes, mut medium) = (0u32, None);
        loop {
            match self.next(&mut ray, &mut diff, (&mut passes, &mut medium), beta, out, s) {
                Next::Vertex(place, at, wo, surf) => return Some((place, at, wo, surf)),
                // pbrt-v3 leaves media out: a boundary crossed leads into none.
                Next::Through => medium = None,
                Next::Escaped => {
                    if len < self.pass.max_len {
                        out.traced += *beta * self.escaped(ray.d.0.normalize(), origin, len, partial);
                    }
                    return None;
                }
                Next::Abandon => return None,
            }
        }
    }

    /// The BSDF's own sample at a vertex, counting only the emitter it finds (weighted
    /// against next-event estimation); a specular sample counts nothing, its branches
    /// carry it.
    fn bsdf_emitter(&self, v: &Vertex, s: &mut impl Sampler, out: &mut PixelSample) -> Rgb {
        let Some(sc) = scatter(self.pass, v, (Vec3::ONE, &mut 1.0), s).filter(|sc| !sc.specular) else {
            return Vec3::ZERO;
        };
        let (mut beta, wi, partial) = (sc.beta, sc.wi, sc.partial);
        let ray = v.place.spawn(wi);
        let origin = ray.o.0;
        // Light at infinity it escapes to lands in `found`, already times `beta`.
        let mut found = PixelSample::default();
        let next = self.find(ray, None, (v.len, partial), &mut beta, s, &mut found);
        out.work = out.work + found.work;
        let Some((place, at, wo, Some((hit, si)))) = next else { return found.traced };
        let dist2 = (place.p - v.place.p).length_squared() as f64;
        let mut p = partial;
        p.arrive(Some(dist2), at.measure(wo, place.ng));
        let emitter = Vertex { place, at: &at, wo, partial: p, len: v.len + 1, ..*v };
        found.traced + beta * self.emitted(&hit, &si, &emitter, origin, dist2)
    }
}

/// One of several branches, by the luminance of its weight (uniformly if all are
/// black, or the sum is not finite): its index and probability.
fn choose(branches: &[(Vec3, Rgb)], u: f32) -> (usize, f32) {
    let lum: Vec<f64> = branches.iter().map(|b| luminance(b.1) as f64).collect();
    let by_lum = Distribution1D::new(&lum);
    match by_lum.sample(u) {
        Some(pick) if lum.iter().sum::<f64>().is_finite() => pick,
        _ => {
            let n = branches.len();
            (((u * n as f32) as usize).min(n - 1), 1.0 / n as f32)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_branch_is_chosen_by_the_luminance_it_carries() {
        let b = [(Vec3::Z, Vec3::splat(1.0)), (Vec3::X, Vec3::splat(3.0))];
        assert_eq!(choose(&b, 0.1), (0, 0.25));
        assert_eq!(choose(&b, 0.3), (1, 0.75));
        assert_eq!(choose(&b, 0.999_999), (1, 0.75));
        // Black branches: uniformly, so the weight over the probability keeps the mean.
        let black = [(Vec3::Z, Vec3::ZERO), (Vec3::X, Vec3::ZERO)];
        assert_eq!(choose(&black, 0.7), (1, 0.5));
        // A black branch is never chosen beside a bright one.
        let one = [(Vec3::Z, Vec3::ZERO), (Vec3::X, Vec3::ONE)];
        assert_eq!(choose(&one, 0.0), (1, 1.0));
    }
}
