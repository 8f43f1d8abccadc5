//! More camera rays for the pixels whose noise is their own coverage of something bright
//! seen directly or through perfect mirrors and glass: a light's edge, or a light seen
//! through a glass ball as a small bright image.
//!
//! ```text
//! pbrt-sppm render scene.pbrt --integrator vcm    # on by itself, pixel by pixel
//! pbrt-sppm render scene.pbrt --integrator bdpt   # the same
//! ```
//!
//! A camera subpath's *prefix light* is what it finds before its first vertex that is
//! not perfectly specular, in vacuum: emitters hit and light at infinity escaped to.
//! Only a camera subpath finds such paths (no light subpath can reach the lens through
//! a perfectly specular chain, and no vertex on it can connect or merge), so their
//! weight is 1 and their noise is that of the pixel's coverage, one ray a pass. Before
//! the first pass every pixel sends [`PROBES`] rays after the emitters its prefix hits;
//! a pixel whose probes disagree by more than [`SPREAD`] of the brightest, and the
//! pixels around it, trace [`RAYS`] rays a pass for their prefix light (their own
//! camera subpath's prefix among them) and average them, where the rest of the subpath
//! stays one. A prefix costs one ray a vertex, against a whole subpath with next-event
//! estimation, connections and a merge lookup at every vertex. Light at infinity
//! seen through glass does not mark a pixel: there (a glass ring or ball under a sky,
//! `caustic-ring`, `v3-caustic`) the rays cost a quarter to a half more time and left
//! the error where it was, as the sky is smooth and the rest of those pixels' paths
//! hold their noise. The marks depend on the scene and
//! the seed alone, so every shard and every resumed render draws the same ones.

use super::{Cameras, Next, PixelSample, Vertex, Work, scatter};
use crate::integrators::sppm::camera_ray;
use crate::integrators::vcm::mis::Partial;
use crate::integrators::vcm::{Technique, Techniques};
use crate::sampling::{Rng, Sampler, SamplerKind, SobolSample, hash};
use crate::spectrum::{Rgb, luminance};
use glam::Vec3;
use rayon::prelude::*;

/// Rays a marked pixel traces a pass for its prefix light, its camera subpath's own
/// among them.
pub const RAYS: u8 = 8;

/// Rays each pixel sends once to decide whether it is marked.
const PROBES: u64 = 4;

/// A pixel is marked when its probes' luminances spread by more than this share of the
/// brightest.
const SPREAD: f32 = 0.2;

/// A stream of the pixel's samples apart from its camera subpath's (`stream` > 0).
const STREAM: u64 = 7;

impl Cameras<'_> {
    /// How many rays pixel `i` traces for its prefix light this pass.
    pub(super) fn prefix_rays(&self, i: usize) -> u8 {
        self.prefix.map_or(1, |marks| if marks[i] { RAYS } else { 1 })
    }

    /// The prefix light of ray `stream` (> 0) of the pixel at `pixel` this pass.
    pub(super) fn extra_prefix(&self, pixel: [f32; 2], stream: u64, work: &mut Work) -> Rgb {
        let (x, y) = (pixel[0] as u64, pixel[1] as u64);
        match self.sampler {
            SamplerKind::Sobol => {
                let mut s = SobolSample::new(hash(&[self.seed, x, y, STREAM, stream]), self.iteration);
                self.prefix_light(pixel, &mut s, work, true)
            }
            SamplerKind::Random => {
                let mut rng = Rng::new(hash(&[self.seed, x, y, self.iteration as u64, STREAM, stream]));
                self.prefix_light(pixel, &mut rng, work, true)
            }
        }
    }

    /// Which pixels of the rendered window (`width` wide, `count` pixels) trace
    /// [`RAYS`] for their prefix light; `None` where no pixel does, or the techniques
    /// leave emitters found by camera subpaths out.
    pub fn prefix_marks(&self, width: usize, count: usize) -> Option<Vec<bool>> {
        let t = self.pass.techniques;
        if !matches!(t, Techniques::All | Techniques::Bdpt) || !t.uses(Technique::EmitterHit) {
            return None;
        }
        let origin = self.pass.origin;
        let probed: Vec<bool> = (0..count)
            .into_par_iter()
            .map(|i| {
                let pixel = [(origin.0 as usize + i % width) as f32, (origin.1 as usize + i / width) as f32];
                let (x, y) = (pixel[0] as u64, pixel[1] as u64);
                let mut work = Work::default();
                let lum = (0..PROBES).map(|k| {
                    let mut rng = Rng::new(hash(&[self.seed, x, y, STREAM, 0, k]));
                    luminance(self.prefix_light(pixel, &mut rng, &mut work, false))
                });
                let (lo, hi) = lum.fold((f32::INFINITY, 0f32), |(lo, hi), l| (lo.min(l), hi.max(l)));
                hi > 0.0 && hi - lo > SPREAD * hi
            })
            .collect();
        probed.iter().any(|&m| m).then(|| dilate(&probed, width))
    }

    /// The light a camera ray finds before its first vertex that is not perfectly
    /// specular, in vacuum (the module's docs); weighted as the camera subpath weighs it
    /// (1, as nothing else finds it). Without `escapes`, only emitters hit count (the
    /// probes').
    fn prefix_light(&self, pixel: [f32; 2], s: &mut impl Sampler, work: &mut Work, escapes: bool) -> Rgb {
        let (pass, scene) = (self.pass, self.pass.scene);
        let (mut ray, mut diff, weight) = camera_ray(scene, pixel, s, self.differential_scale, pass.time);
        let mut found = Vec3::ZERO;
        if weight == 0.0 || scene.camera_medium.is_some() {
            return found;
        }
        let camera_pdf = scene.camera.pdf_we(&ray).1 as f64 * pass.film_pixels;
        let mut partial = Partial::camera(camera_pdf, pass.lt_count());
        let (mut beta, mut prev, mut origin, mut eta_scale) = (Vec3::splat(weight), ray.o.0, ray.o.0, 1.0f32);
        let (mut len, mut passes, mut medium) = (0u32, 0u32, None);
        let mut out = PixelSample::default();
        while medium.is_none() {
            let (place, at, wo, surf) =
                match self.next(&mut ray, &mut diff, (&mut passes, &mut medium), &mut beta, &mut out, s) {
                    Next::Vertex(place, at, wo, surf) => (place, at, wo, surf),
                    Next::Through => continue,
                    Next::Escaped if escapes && len < pass.max_len => {
                        found += beta * self.escaped(ray.d.0.normalize(), origin, len, partial);
                        break;
                    }
                    Next::Escaped | Next::Abandon => break,
                };
            len += 1;
            let dist2 = (place.p - prev).length_squared() as f64;
            partial.arrive(Some(dist2), at.measure(wo, place.ng));
            let v = Vertex { place, at: &at, wo, partial, len, merges: false, first_diffuse: true };
            if let Some((hit, si)) = &surf {
                found += beta * self.emitted(hit, si, &v, origin, dist2);
            }
            if len >= pass.max_len || !at.is_delta() || (surf.is_some() && wo.dot(place.ng) == 0.0) {
                break;
            }
            let Some(((b, dir), p, _)) = scatter(pass, &v, (beta, &mut eta_scale), s) else { break };
            (beta, partial, prev) = (b, p, place.p);
            ray = place.spawn(dir);
            (medium, origin) = (place.toward(dir), ray.o.0);
        }
        *work = *work + out.work;
        found
    }
}

/// The marks and every pixel next to one: a probe that missed a thin bright edge
/// usually has a neighbour that did not.
fn dilate(marks: &[bool], width: usize) -> Vec<bool> {
    let height = marks.len() / width.max(1);
    let at = |x: usize, y: usize| marks[y * width + x];
    (0..marks.len())
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let (x0, x1, y0, y1) =
                (x.saturating_sub(1), (x + 1).min(width - 1), y.saturating_sub(1), (y + 1).min(height - 1));
            (y0..=y1).any(|yy| (x0..=x1).any(|xx| at(xx, yy)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::dilate;

    #[test]
    fn dilation_marks_the_neighbours_and_stays_in_the_image() {
        let mut marks = vec![false; 12];
        marks[0] = true; // (0, 0) of a 4 × 3 image
        marks[7] = true; // (3, 1)
        let d = dilate(&marks, 4);
        let expect = [1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 1, 1];
        assert_eq!(d, expect.iter().map(|&e| e == 1).collect::<Vec<_>>());
    }
}
