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
//! weight is 1 and their noise is that of the pixel's coverage, one ray a pass.
//!
//! Before the first pass every pixel sends a probe ray along its prefix; those within
//! [`REACH`] of one that met an emitter or a perfect specular surface send [`PROBES`]
//! in all. A pixel whose probes' emitters disagree by more than [`SPREAD`] of the
//! brightest, and the pixels within [`REACH`] of it, trace [`RAYS`] rays a pass for
//! their prefix light (their own camera subpath's prefix among them) and average them,
//! where the rest of the subpath stays one. A prefix costs one ray a vertex, against a
//! whole subpath with next-event estimation, connections and a merge lookup at every
//! vertex.
//! A scene without area lights sends no probes. Light at infinity seen through glass
//! does not mark a pixel: there (a glass ring or ball under a sky, `caustic-ring`,
//! `v3-caustic`) the rays cost a quarter to a half more time and left the error where
//! it was, as the sky is smooth and the rest of those pixels' paths hold their noise.
//! The marks depend on the scene and the seed alone, so every shard and every resumed
//! render draws the same ones.

use super::{Cameras, Next, PixelSample, Vertex, Work, scatter};
use crate::integrators::sppm::camera_ray;
use crate::integrators::vcm::mis::Partial;
use crate::integrators::vcm::{Technique, Techniques};
use crate::lights::Light;
use crate::sampling::{Rng, Sampler, SamplerKind, SobolSample, hash};
use crate::spectrum::{Rgb, luminance};
use glam::Vec3;
use rayon::prelude::*;

/// Rays a marked pixel traces a pass for its prefix light, its camera subpath's own
/// among them.
pub const RAYS: u8 = 8;

/// Rays a pixel near an emitter or a perfect specular surface sends once to decide
/// whether it is marked, one in each quarter of it. Each costs a camera ray and the
/// material at its first hit: four in every pixel took 0.6 s on killeroo-simple at
/// 700 × 700 (a fifth of its first pass; one everywhere and four near what matters:
/// the time of six passes within noise, 0.99). Two random ones, with the same marking
/// of neighbours, marked 87 pixels of `cornell-glass` rather than 108 and kept a third
/// of the gain.
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
                self.prefix_light(pixel, &mut s, work, true).0
            }
            SamplerKind::Random => {
                let mut rng = Rng::new(hash(&[self.seed, x, y, self.iteration as u64, STREAM, stream]));
                self.prefix_light(pixel, &mut rng, work, true).0
            }
        }
    }

    /// Which pixels of the rendered window (`width` wide, `count` pixels) trace
    /// [`RAYS`] for their prefix light; `None` where no pixel does, or the techniques
    /// leave emitters found by camera subpaths out.
    pub fn prefix_marks(&self, width: usize, count: usize) -> Option<Vec<bool>> {
        let t = self.pass.techniques;
        let area_lights = self.pass.scene.lights.iter().any(|l| matches!(l, Light::Area(_)));
        if !area_lights || !matches!(t, Techniques::All | Techniques::Bdpt) || !t.uses(Technique::EmitterHit) {
            return None;
        }
        let origin = self.pass.origin;
        let pixel = |i: usize| [(origin.0 as usize + i % width) as f32, (origin.1 as usize + i / width) as f32];
        // Probe k of a pixel: the first points of a scrambled Sobol' sequence, one in
        // each quarter of it.
        let probe = |i: usize, k: u32| {
            let p = pixel(i);
            let mut s = SobolSample::new(hash(&[self.seed, p[0] as u64, p[1] as u64, STREAM, 0]), k);
            self.prefix_light(p, &mut s, &mut Work::default(), false)
        };
        // One probe everywhere finds where an emitter or a perfect specular surface is
        // in view; only the pixels within reach of those send the rest.
        let seen: Vec<bool> = (0..count)
            .into_par_iter()
            .map(|i| matches!(probe(i, 0), (l, specular) if specular || l != Vec3::ZERO))
            .collect();
        let near = dilate(&seen, width);
        let probed: Vec<bool> = (0..count)
            .into_par_iter()
            .map(|i| {
                if !near[i] {
                    return false;
                }
                let lum = (0..PROBES as u32).map(|k| luminance(probe(i, k).0));
                let (lo, hi) = lum.fold((f32::INFINITY, 0f32), |(lo, hi), l| (lo.min(l), hi.max(l)));
                hi > 0.0 && hi - lo > SPREAD * hi
            })
            .collect();
        probed.iter().any(|&m| m).then(|| dilate(&probed, width))
    }

    /// The light a camera ray finds before its first vertex that is not perfectly
    /// specular, in vacuum (the module's docs); weighted as the camera subpath weighs it
    /// (1, as nothing else finds it), and whether it met a perfectly specular surface.
    /// Without `escapes`, only emitters hit count (the probes').
    fn prefix_light(&self, pixel: [f32; 2], s: &mut impl Sampler, work: &mut Work, escapes: bool) -> (Rgb, bool) {
        let (pass, scene) = (self.pass, self.pass.scene);
        let (mut ray, mut diff, weight) = camera_ray(scene, pixel, s, self.differential_scale, pass.time);
        let (mut found, mut specular) = (Vec3::ZERO, false);
        if weight == 0.0 || scene.camera_medium.is_some() {
            return (found, specular);
        }
        let camera_pdf = scene.camera.pdf_we(&ray).1 as f64 * pass.film_pixels;
        let mut partial = Partial::camera(camera_pdf, pass.lt_count());
        let (mut beta, mut prev, mut origin, mut eta_scale) = (Vec3::splat(weight), ray.o.0, ray.o.0, 1.0f32);
        let (mut len, mut passes, mut medium) = (0u32, 0u32, None);
        let (mut out, mut terminated) = (PixelSample::default(), false);
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
            let v = Vertex { first_diffuse: true, terminated, ..Vertex::plain(place, &at, wo, partial, len) };
            if let Some((hit, si)) = &surf {
                found += beta * self.emitted(hit, si, &v, origin, dist2);
                scene.terminate_if_dispersed(hit, &mut beta, &mut terminated);
            }
            if len >= pass.max_len || !at.is_delta() || (surf.is_some() && wo.dot(place.ng) == 0.0) {
                break;
            }
            specular = true;
            let Some(sc) = scatter(pass, &v, (beta, &mut eta_scale), s) else { break };
            let (b, dir, p) = (sc.beta, sc.wi, sc.partial);
            // Light through a BSSRDF leaves at a diffuse vertex: the prefix ends.
            if self.bssrdf_below(&v, surf.as_ref(), dir).is_some() {
                break;
            }
            (beta, partial, prev) = (b, p, place.p);
            ray = place.spawn(dir);
            (medium, origin) = (place.toward(dir), ray.o.0);
        }
        *work = *work + out.work;
        (found, specular)
    }
}

/// How far from a probe's mark pixels are marked too, in pixels (across and down).
/// A light's image through a glass ball can spread over a few pixels that each see it
/// for a few hundredths of their area, which four probes mostly miss: on
/// `cornell-glass` one such pixel held a third of a render's error. Reaching one pixel
/// marked 109 pixels there, two 185, and left 0.88 and 0.80 of the error without the
/// extra rays at equal passes.
const REACH: usize = 2;

/// The marks and every pixel within [`REACH`] of one: a probe that missed a thin or
/// faint bright image usually has a neighbour that did not.
fn dilate(marks: &[bool], width: usize) -> Vec<bool> {
    let height = marks.len() / width.max(1);
    let at = |x: usize, y: usize| marks[y * width + x];
    (0..marks.len())
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let (x0, x1) = (x.saturating_sub(REACH), (x + REACH).min(width - 1));
            let (y0, y1) = (y.saturating_sub(REACH), (y + REACH).min(height - 1));
            (y0..=y1).any(|yy| (x0..=x1).any(|xx| at(xx, yy)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::dilate;

    #[test]
    fn dilation_marks_the_pixels_within_reach_and_stays_in_the_image() {
        assert_eq!(super::REACH, 2);
        let mut marks = vec![false; 7 * 4];
        marks[0] = true; // (0, 0) of a 7 × 4 image
        marks[6 + 3 * 7] = true; // (6, 3)
        let d = dilate(&marks, 7);
        let expect = ["1110000", "1110111", "1110111", "0000111"];
        let expect: Vec<bool> = expect.iter().flat_map(|row| row.chars().map(|c| c == '1')).collect();
        assert_eq!(d, expect);
    }
}
