//! How many light subpaths a pass traces, when the user has not said (`--photons`).
//!
//! ```text
//! pbrt-sppm render scene.pbrt --integrator vcm                 # balanced from the file's count
//! pbrt-sppm render scene.pbrt --integrator vcm --photons 50000 # fixed
//! ```
//!
//! The noise of merging and light tracing falls with the pass's light subpaths; that
//! of the techniques traced from the camera (emitters found, next-event estimation,
//! connections) does not. With a pass's relative variance `V_l·n₀/n + V_c` at `n`
//! light subpaths, and its cost `c_l·n + C_c`, the error at equal time is least at
//! `n = n₀·sqrt(V_l·C_c / (V_c·c_l·n₀))`; below `n₀` the light side's variance grows
//! more slowly, as `(n₀/n)^a` with a between ½ and 1 (its paths go to connections as
//! its weights fall, where connections can make them), see `growth` and `fewer`.
//!
//! The first [`PILOT_PASSES`] passes trace the starting count (the file's
//! `photonsperiteration`) and measure: each pixel's variance between passes (all of
//! it), the part of it the light subpaths cause (each pass's two halves of subpaths,
//! merged and light-traced apart, differ by it: for halves of n/2,
//! E[(X₁ − X₂)²] = 4·Var(X | camera subpaths)), the rest being the camera's; and both
//! parts of the cost in work counted (rays, vertices, merge candidates: whole numbers,
//! so the choice is the same for any thread count and on any machine). Every later
//! pass traces the count chosen. A render that starts past the pilot (a shard, a
//! resumed checkpoint) renders the pilot passes again to make the same choice.
//!
//! The same scene wants opposite things by what carries its light: a room lit
//! through a keyhole (merging) wanted ten times the file's photons, a room lit
//! through a doorway (connections) a fifth (`docs/vcm.md`).

use super::camera::{PixelSample, Work};
use super::light::Counts;
use crate::spectrum::Rgb;

/// Passes whose spread the choice is measured from.
pub const PILOT_PASSES: u32 = 4;

/// The choice stays within this factor of the starting count either way. The model
/// leaves out merging's bias, which more light subpaths do not reduce and fewer passes
/// in the same time leave larger: on `pool` it asked for 10× the file's count and left
/// 1.48× the error × time of the file's count (`docs/vcm.md`).
pub const MAX_FACTOR: f64 = 4.0;

/// Light vertices of one pass may take at most this many bytes.
const MEMORY_BUDGET: f64 = 2.0 * (1u64 << 30) as f64;

/// Costs, in units of a light vertex (its ray, BSDF, light-tracing shadow ray and
/// storage): a light subpath emitted; a camera subpath's ray (closest hit or shadow),
/// vertex (a BSDF built and sampled) and merge candidate looked at. Fitted by least
/// squares to the phase times of six scenes of the README's suite, 4 passes each, on
/// the 2-core Intel Xeon (within 15% of every phase time but one, 24%; `docs/vcm.md`,
/// "Light subpaths per pass").
const LIGHT_PATH: f64 = 0.11;
const CAMERA_RAY: f64 = 0.107;
const CAMERA_VERTEX: f64 = 0.354;
const CANDIDATE: f64 = 0.041;

/// What the pilot passes measured: per pixel the sum and sum of squares of each
/// pass's value and the sum of its estimates of the light subpaths' variance (channel
/// means), and the work of both sides.
pub struct Pilot {
    pixels: Vec<[f64; 3]>,
    passes: u32,
    light: Counts,
    camera: Work,
    /// Light vertices stored over the pilot passes.
    stored: u64,
}

impl Pilot {
    pub fn new(pixels: usize) -> Pilot {
        Pilot {
            pixels: vec![[0.0; 3]; pixels],
            passes: 0,
            light: Counts::default(),
            camera: Work::default(),
            stored: 0,
        }
    }

    /// Adds one pass of `n` light subpaths: each pixel's value and the difference of
    /// its two halves' light-side estimates (each scaled to stand for the pass), and
    /// the work.
    pub fn add(&mut self, parts: &[[f32; 2]], n: u64, light: Counts, camera: Work, stored: u64) {
        let [a, b] = super::light::halves(n).map(|h| h as f64);
        // Var(X₁ − X₂ | camera) = Var(X | camera)·(n/a + n/b), and 4 for equal halves.
        let k = if b > 0.0 { 1.0 / (n as f64 / a + n as f64 / b) } else { 0.0 };
        for (acc, &[x, d]) in self.pixels.iter_mut().zip(parts) {
            let (x, d) = (x as f64, d as f64);
            *acc = [acc[0] + x, acc[1] + x * x, acc[2] + d * d * k];
        }
        (self.light, self.camera, self.stored) = (self.light + light, self.camera + camera, self.stored + stored);
        self.passes += 1;
    }

    pub fn complete(&self) -> bool {
        self.passes >= PILOT_PASSES
    }

    /// The count later passes trace, from `start` (the count the pilot traced).
    pub fn choose(&self, start: u64) -> u64 {
        let (traced, light) = self.variances();
        let k = self.passes.max(1) as f64;
        let light_work = (self.light.paths as f64 * LIGHT_PATH + self.light.vertices as f64) / k;
        let camera = &self.camera;
        let camera_work = (camera.rays as f64 * CAMERA_RAY
            + camera.vertices as f64 * CAMERA_VERTEX
            + camera.candidates as f64 * CANDIDATE)
            / k;
        let per_path = self.stored as f64 / self.light.paths.max(1) as f64;
        let size = std::mem::size_of::<super::light::LightVertex>() as f64;
        let cap = MEMORY_BUDGET / (per_path * size).max(1e-9);
        choose(start, Parts { traced, light }, Parts { traced: camera_work, light: light_work }, cap)
    }

    /// The variance a pass's value has for reasons of the camera subpaths (all of it
    /// but the light subpaths' part) and of the light subpaths, relative to the
    /// pixel's squared mean (as relMSE weighs errors; dark pixels count against a tenth
    /// of the image's mean), summed over pixels in order (the same sum for any thread
    /// count).
    fn variances(&self) -> (f64, f64) {
        let k = self.passes as f64;
        if k < 2.0 {
            return (0.0, 0.0);
        }
        let mean = |a: &[f64; 3]| a[0] / k;
        let image = self.pixels.iter().map(mean).sum::<f64>() / self.pixels.len().max(1) as f64;
        let floor = (0.1 * image).powi(2);
        let (mut all, mut light) = (0.0, 0.0);
        for a in &self.pixels {
            let norm = mean(a).powi(2) + floor;
            if norm > 0.0 {
                all += ((a[1] - a[0] * a[0] / k) / (k - 1.0)).max(0.0) / norm;
                light += a[2] / k / norm;
            }
        }
        ((all - light).max(0.0), light)
    }
}

/// A pilot pass's values per pixel: the whole, and the difference of the light-side
/// estimates of the pass's two halves of light subpaths ([`super::light::half`]), each
/// scaled to stand for the pass (channel means).
pub struct Halves {
    scale: [f32; 2],
}

impl Halves {
    pub fn new(light_paths: u64) -> Halves {
        Halves { scale: super::light::halves(light_paths).map(|h| light_paths as f32 / h.max(1) as f32) }
    }

    /// A camera subpath's (whole, halves' difference).
    pub fn part(&self, p: &PixelSample) -> [f32; 2] {
        [mean(p.total()), mean(p.merged[0]) * self.scale[0] - mean(p.merged[1]) * self.scale[1]]
    }

    /// Adds the light-tracing splats (list j from half j mod 2) times `scale`.
    pub fn add_splats(&self, parts: &mut [[f32; 2]], lists: &[Vec<(u32, Rgb)>], scale: f64) {
        for (j, list) in lists.iter().enumerate() {
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            for &(pixel, c) in list {
                let c = (mean(c) as f64 * scale) as f32;
                parts[pixel as usize][0] += c;
                parts[pixel as usize][1] += sign * c * self.scale[j % 2];
            }
        }
    }
}

fn mean(c: Rgb) -> f32 {
    c.element_sum() / 3.0
}

/// How fast the light side's variance grows below the pilot's count, (n₀/n)^a, by its
/// share f = V_l/(V_l + V_c) of the pass's variance: a = ½ up to f = ½, rising to 1 at
/// f = 1. Where connections and next-event estimation carry much of the light, the
/// weights hand the light side's paths to them as light subpaths fall, and the growth
/// was measured as (n₀/n)^½ (`doorway`, `cornell-glass`, `sppm-bench`, f ≤ 0.46);
/// where merging carries nearly all of it (`pool`, f = 0.83, where no connection makes
/// a path) there is no one to hand them to, and the ½ law asked for the ¼ bound, which
/// left 2.3 times the error of the file's count at equal passes (`docs/vcm.md`).
fn growth(vl: f64, vc: f64) -> f64 {
    0.5 + (vl / (vl + vc) - 0.5).max(0.0)
}

/// The fraction x < 1 of the pilot's count that makes (V_l·x^-a + V_c)(c_l·x + C_c)
/// least, with a = [`growth`]. Where the derivative vanishes:
/// c_l·V_c·x^(a+1) + (1 − a)·c_l·V_l·x − a·V_l·C_c = 0, increasing in x: bisection.
fn fewer(vl: f64, vc: f64, cl: f64, cc: f64) -> f64 {
    let a = growth(vl, vc);
    let g = |x: f64| cl * vc * x.powf(a + 1.0) + (1.0 - a) * cl * vl * x - a * vl * cc;
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let m = 0.5 * (lo + hi);
        if g(m) < 0.0 { lo = m } else { hi = m }
    }
    0.5 * (lo + hi)
}

/// A pair of figures for the camera-traced part and the light side.
#[derive(Clone, Copy, Debug)]
pub struct Parts {
    pub traced: f64,
    pub light: f64,
}

/// The count that makes variance × cost least, from a pass at `start` light subpaths
/// with these variances and costs, within [`MAX_FACTOR`] of `start` and at most `cap`.
pub fn choose(start: u64, variance: Parts, cost: Parts, cap: f64) -> u64 {
    let n0 = start as f64;
    let (lo, hi) = ((n0 / MAX_FACTOR).max(1.0), (n0 * MAX_FACTOR).min(cap).max(1.0));
    // NaN counts as nothing measured.
    let positive = |x: f64| x > 0.0;
    let ideal = if !positive(variance.light) && !positive(variance.traced) {
        // Nothing measured (a black pilot): no reason to move.
        n0
    } else if !positive(variance.light) {
        lo
    } else if !positive(variance.traced) || !positive(cost.light) {
        hi
    } else {
        let (vl, vc, cl, cc) = (variance.light, variance.traced, cost.light, cost.traced);
        let up = n0 * (vl * cc / (vc * cl)).sqrt();
        if up >= n0 { up } else { n0 * fewer(vl, vc, cl, cc) }
    };
    if !ideal.is_finite() {
        return start;
    }
    ideal.clamp(lo.min(hi), hi).round() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(v: (f64, f64), c: (f64, f64)) -> u64 {
        choose(1000, Parts { traced: v.0, light: v.1 }, Parts { traced: c.0, light: c.1 }, f64::INFINITY)
    }

    #[test]
    fn the_count_minimises_variance_times_cost() {
        // Balanced already: V_l/n0 = V_c and c_l·n0 = C_c.
        assert_eq!(at((1.0, 1.0), (1.0, 1.0)), 1000);
        // Light-side noise 4× the camera's: twice the subpaths; cost 4× cheaper: twice too.
        assert_eq!(at((1.0, 4.0), (1.0, 1.0)), 2000);
        assert_eq!(at((1.0, 1.0), (4.0, 1.0)), 2000);
        // Brute force over n agrees with the formulas: above the pilot's count (light
        // variance as n0/n; the first case) and below it, as (n0/n)^a, a = ½ while the
        // light side holds at most half the variance (the second and third) and 0.8
        // where it holds 80% (the fourth).
        let cases = [(0.3, 1.0, 2.0, 0.7), (4.0, 1.0, 1.0, 1.0), (1.0, 0.84, 0.81, 1.0), (1.0, 4.0, 1.0, 5.0)];
        for (vt, vl, ct, cl) in cases {
            let a = growth(vl, vt);
            let f = |n: f64| {
                let r = 1000.0 / n;
                (vl * if r <= 1.0 { r } else { r.powf(a) } + vt) * (cl * n / 1000.0 + ct)
            };
            let best = (250..4000).map(|n| n as f64).min_by(|a, b| f(*a).total_cmp(&f(*b))).unwrap();
            let got = at((vt, vl), (ct, cl));
            assert!((got as f64 - best).abs() <= 1.0, "{got} against {best}");
        }
        // Camera-side noise twice the light's: n0/n growth would give 1000/√2 = 707;
        // the slower growth below n0 moves further, to about 0.3 of it.
        let fewer = at((2.0, 1.0), (1.0, 1.0));
        assert!((251..500).contains(&fewer), "{fewer}");
        // A light side holding 82% of the variance, just below balance (n0/n growth
        // would give 949): about half the count, where the ½ law gave the ¼ bound.
        let merged = at((1.0, 4.5), (1.0, 5.0));
        assert!((400..700).contains(&merged), "{merged}");
    }

    #[test]
    fn the_count_stays_within_its_bounds() {
        assert_eq!(at((1.0, 1e6), (1.0, 1.0)), 4_000);
        assert_eq!(at((1e6, 1.0), (1.0, 1.0)), 250);
        // No light-side noise at all: the fewest; no camera-side noise: the most.
        assert_eq!(at((1.0, 0.0), (1.0, 1.0)), 250);
        assert_eq!(at((0.0, 1.0), (1.0, 1.0)), 4_000);
        // A black pilot keeps the count; NaN figures never escape.
        assert_eq!(at((0.0, 0.0), (1.0, 1.0)), 1000);
        assert_eq!(at((f64::NAN, f64::NAN), (1.0, 1.0)), 1000);
        assert_eq!(choose(1000, Parts { traced: 1.0, light: 1e6 }, Parts { traced: 1.0, light: 1.0 }, 3000.0), 3000);
        assert_eq!(choose(1, Parts { traced: 1.0, light: 0.0 }, Parts { traced: 1.0, light: 1.0 }, 1e9), 1);
    }

    #[test]
    fn the_pilot_splits_the_spread_between_the_parts() {
        let counts = Counts { paths: 1000, hits: 0, vertices: 0 };
        let work = Work { rays: 1000, vertices: 0, candidates: 0 };
        let pilot = |values: [f32; 4], halves_differ: f32| {
            let mut p = Pilot::new(1);
            for x in values {
                p.add(&[[x, halves_differ]], 1000, counts, work, 10);
            }
            assert!(p.complete());
            p
        };
        // Values 1 ± 0.5 between passes (variance 1/3), and halves 2·0.5 apart in every
        // pass: the light subpaths' variance is (2·0.5)²/4 = 1/4, the camera's the rest.
        let (camera, light) = pilot([0.5, 1.5, 0.5, 1.5], 1.0).variances();
        let norm = 1.0 + 0.01;
        assert!((light - 0.25 / norm).abs() < 1e-6, "{light}");
        assert!((camera - (1.0 / 3.0 - 0.25) / norm).abs() < 1e-6, "{camera}");
        // Halves that agree: all the spread is the camera's, and the fewest subpaths.
        let p = pilot([0.5, 1.5, 0.5, 1.5], 0.0);
        assert_eq!(p.variances().1, 0.0);
        assert_eq!(p.choose(1000), 250);
        // Halves that differ more than passes do: all the light's, and the most.
        assert_eq!(pilot([1.0, 1.0, 1.0, 1.0], 1.0).choose(1000), 4_000);
    }
}
