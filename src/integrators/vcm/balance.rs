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
//! `n = n₀·sqrt(V_l·C_c / (V_c·c_l·n₀))`. Below `n₀` the light side's variance grows
//! by what it carries: caustics (light only light subpaths find) faster than `n₀/n`,
//! the rest more slowly, as its paths go to connections and next-event estimation as
//! its weights fall; so the two are measured apart, see `fewer`.
//!
//! The first [`PILOT_PASSES`] passes trace the starting count (the file's
//! `photonsperiteration`) and measure: each pixel's variance between passes (all of
//! it), the part of it the light subpaths cause (each pass's two halves of subpaths,
//! merged and light-traced apart, differ by it: for halves of n/2,
//! E[(X₁ − X₂)²] = 4·Var(X | camera subpaths); caustics and the rest apart), the rest
//! being the camera's; and both parts of the cost in work counted (rays, vertices,
//! merge candidates: whole numbers, so the choice is the same for any thread count and
//! on any machine). Every later pass traces the count chosen. A render that starts
//! past the pilot (a shard, a resumed checkpoint) renders the pilot passes again to
//! make the same choice.
//!
//! The same scene wants opposite things by what carries its light: a room lit
//! through a keyhole (merging) wanted ten times the file's photons, a room lit
//! through a doorway (connections) a fifth (`docs/vcm.md`).

use super::camera::{PixelSample, Work};
use super::light::Counts;
use crate::spectrum::Rgb;

/// Passes whose spread the choice is measured from.
pub const PILOT_PASSES: u32 = 4;

/// The choice stays below this factor of the starting count. The model
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

/// A pilot pass's values at one pixel (channel means): the whole, and the
/// differences between the two halves' light-side estimates ([`Halves`]) of caustics
/// and of the rest.
pub type Part = [f32; 3];

/// What the pilot passes measured: per pixel the sum and sum of squares of each
/// pass's value and the sums of its estimates of the light subpaths' variance, of
/// caustics and of the rest (channel means); and the work of both sides.
pub struct Pilot {
    pixels: Vec<[f64; 4]>,
    passes: u32,
    light: Counts,
    camera: Work,
    /// Light vertices stored over the pilot passes.
    stored: u64,
}

/// The pilot's variances, relative as [`Pilot::variances`] sums them: of what the
/// camera subpaths trace and of the light side's caustics and the rest of it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Variances {
    pub traced: f64,
    pub caustic: f64,
    pub rest: f64,
}

impl Variances {
    fn light(&self) -> f64 {
        self.caustic + self.rest
    }
}

impl Pilot {
    pub fn new(pixels: usize) -> Pilot {
        Pilot {
            pixels: vec![[0.0; 4]; pixels],
            passes: 0,
            light: Counts::default(),
            camera: Work::default(),
            stored: 0,
        }
    }

    /// Adds one pass of `n` light subpaths: each pixel's value and the differences of
    /// its two halves' light-side estimates (each scaled to stand for the pass), and
    /// the work.
    pub fn add(&mut self, parts: &[Part], n: u64, light: Counts, camera: Work, stored: u64) {
        let [a, b] = super::light::halves(n).map(|h| h as f64);
        // Var(X₁ − X₂ | camera) = Var(X | camera)·(n/a + n/b), and 4 for equal halves.
        let k = if b > 0.0 { 1.0 / (n as f64 / a + n as f64 / b) } else { 0.0 };
        for (acc, &[x, c, r]) in self.pixels.iter_mut().zip(parts) {
            let (x, c, r) = (x as f64, c as f64, r as f64);
            *acc = [acc[0] + x, acc[1] + x * x, acc[2] + c * c * k, acc[3] + r * r * k];
        }
        (self.light, self.camera, self.stored) = (self.light + light, self.camera + camera, self.stored + stored);
        self.passes += 1;
    }

    pub fn complete(&self) -> bool {
        self.passes >= PILOT_PASSES
    }

    /// The count later passes trace, from `start` (the count the pilot traced).
    pub fn choose(&self, start: u64) -> u64 {
        let k = self.passes.max(1) as f64;
        let light_work = (self.light.paths as f64 * LIGHT_PATH + self.light.vertices as f64) / k;
        let camera = &self.camera;
        let camera_work = (camera.rays as f64 * CAMERA_RAY
            + camera.vertices as f64 * CAMERA_VERTEX
            + camera.candidates as f64 * CANDIDATE)
            / k;
        let per_path = self.stored as f64 / self.light.paths.max(1) as f64;
        let size =
            (std::mem::size_of::<super::light::LightVertex>() + std::mem::size_of::<super::light::Spot>()) as f64;
        let cap = MEMORY_BUDGET / (per_path * size).max(1e-9);
        choose(start, self.variances(), Parts { traced: camera_work, light: light_work }, cap)
    }

    /// The variance a pass's value has for reasons of the camera subpaths (all of it
    /// but the light subpaths' part) and of the light subpaths (caustics and the rest),
    /// relative to the pixel's squared mean (as relMSE weighs errors; dark pixels count
    /// against a tenth of the image's mean), summed over pixels in order (the same sum
    /// for any thread count).
    fn variances(&self) -> Variances {
        let k = self.passes as f64;
        if k < 2.0 {
            return Variances::default();
        }
        let mean = |a: &[f64; 4]| a[0] / k;
        let image = self.pixels.iter().map(mean).sum::<f64>() / self.pixels.len().max(1) as f64;
        let floor = (0.1 * image).powi(2);
        let (mut all, mut caustic, mut rest) = (0.0, 0.0, 0.0);
        for a in &self.pixels {
            let norm = mean(a).powi(2) + floor;
            if norm > 0.0 {
                all += ((a[1] - a[0] * a[0] / k) / (k - 1.0)).max(0.0) / norm;
                caustic += a[2] / k / norm;
                rest += a[3] / k / norm;
            }
        }
        Variances { traced: (all - caustic - rest).max(0.0), caustic, rest }
    }
}

/// A pilot pass's values per pixel ([`Part`]): the whole, and the differences of the
/// light-side estimates of the pass's two halves of light subpaths
/// ([`super::light::half`]), each scaled to stand for the pass, caustics apart from
/// the rest ([`super::light::ByKind`]).
pub struct Halves {
    scale: [f32; 2],
}

impl Halves {
    pub fn new(light_paths: u64) -> Halves {
        Halves { scale: super::light::halves(light_paths).map(|h| light_paths as f32 / h.max(1) as f32) }
    }

    /// A camera subpath's part.
    pub fn part(&self, p: &PixelSample) -> Part {
        let m = p.merged.map(mean);
        let [s0, s1] = self.scale;
        [mean(p.total()), m[2] * s0 - m[3] * s1, m[0] * s0 - m[1] * s1]
    }

    /// Adds the light-tracing splats (list j of kind j mod 4, [`super::light::kind`])
    /// times `scale`.
    pub fn add_splats(&self, parts: &mut [Part], lists: &[Vec<(u32, Rgb)>], scale: f64) {
        for (j, list) in lists.iter().enumerate() {
            let (half, caustic) = (j % 2, j % 4 >= 2);
            let sign = if half == 0 { 1.0 } else { -1.0 };
            let slot = if caustic { 1 } else { 2 };
            for &(pixel, c) in list {
                let c = (mean(c) as f64 * scale) as f32;
                let part = &mut parts[pixel as usize];
                part[0] += c;
                part[slot] += sign * c * self.scale[half];
            }
        }
    }
}

fn mean(c: Rgb) -> f32 {
    c.element_sum() / 3.0
}

/// How the light side's variance grows below the pilot's count, (n₀/n)^a, by what it
/// carries. Caustics ([`super::light::ByKind`]): nothing else samples them, and the
/// error grew faster than n₀/n (fitted a = 1.29 on `caustic-ring`, 1.32 on
/// `v3-caustic`, from the error at two counts and the pilot's share; with a = 1 both
/// chose about half the count best for them). The rest goes to connections and
/// next-event estimation as the light side's weights fall, the more readily the less
/// of the variance it holds: see [`rest_growth`].
const CAUSTIC_GROWTH: f64 = 1.3;

/// The rest's exponent: its share of the variance but the caustics',
/// V_rest/(V_rest + V_c). Measured: ≤ 0 on `sppm-bench` (share 0.29), about 0.4 on
/// `doorway` (0.46), where 0.2 for both chose an eighth of the file's count and left
/// `doorway` 1.2 times the error at equal time in the suite (`docs/vcm.md`, "Caustics
/// apart"); where the light side holds nearly all of it (`keyhole`, `pool`) nothing
/// takes its paths over, and the law tends to n₀/n.
fn rest_growth(v: Variances) -> f64 {
    let share = v.rest / (v.rest + v.traced);
    if share.is_finite() { share.clamp(0.0, 1.0) } else { 0.0 }
}

/// The choice stays above the starting count over this: `sppm-bench` and `doorway`,
/// whose light side carries no caustics, were best at an eighth of the file's count or
/// fewer in the count sweep of `docs/vcm.md` (equal passes, the pilot left out).
pub const FEWEST_FACTOR: f64 = 8.0;

/// The fraction x < 1 of the pilot's count that makes
/// (V_caustic·x^-a_c + V_rest·x^-a_r + V_c)(c_l·x + C_c) least (a_c =
/// [`CAUSTIC_GROWTH`], a_r = [`rest_growth`]), x ≥ `lo`: the least
/// over a fine grid in log x (the sum of two powers leaves no closed form).
fn fewer(v: Variances, cl: f64, cc: f64, lo: f64) -> f64 {
    let a = rest_growth(v);
    let f = |x: f64| (v.caustic * x.powf(-CAUSTIC_GROWTH) + v.rest * x.powf(-a) + v.traced) * (cl * x + cc);
    const STEPS: u32 = 1024;
    (0..=STEPS).map(|i| lo.powf(1.0 - i as f64 / STEPS as f64)).min_by(|x, y| f(*x).total_cmp(&f(*y))).unwrap_or(1.0)
}

/// A pair of figures for the camera-traced part and the light side.
#[derive(Clone, Copy, Debug)]
pub struct Parts {
    pub traced: f64,
    pub light: f64,
}

/// The count that makes variance × cost least, from a pass at `start` light subpaths
/// with these variances and costs, within [`FEWEST_FACTOR`] below `start` and
/// [`MAX_FACTOR`] above it, and at most `cap`.
pub fn choose(start: u64, variance: Variances, cost: Parts, cap: f64) -> u64 {
    let n0 = start as f64;
    let (lo, hi) = ((n0 / FEWEST_FACTOR).max(1.0), (n0 * MAX_FACTOR).min(cap).max(1.0));
    // NaN counts as nothing measured.
    let positive = |x: f64| x > 0.0;
    let vl = variance.light();
    let ideal = if !positive(vl) && !positive(variance.traced) {
        // Nothing measured (a black pilot): no reason to move.
        n0
    } else if !positive(vl) {
        lo
    } else if !positive(variance.traced) || !positive(cost.light) {
        hi
    } else {
        let (vc, cl, cc) = (variance.traced, cost.light, cost.traced);
        let up = n0 * (vl * cc / (vc * cl)).sqrt();
        if up >= n0 { up } else { n0 * fewer(variance, cl, cc, (lo / n0).min(1.0)) }
    };
    if !ideal.is_finite() {
        return start;
    }
    ideal.clamp(lo.min(hi), hi).round() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(traced: f64, caustic: f64, rest: f64) -> Variances {
        Variances { traced, caustic, rest }
    }

    fn at(v: Variances, c: (f64, f64)) -> u64 {
        choose(1000, v, Parts { traced: c.0, light: c.1 }, f64::INFINITY)
    }

    /// The least of variance × cost over whole counts 125..4000, by brute force.
    fn brute(v: Variances, (ct, cl): (f64, f64)) -> f64 {
        let f = |n: f64| {
            let r = 1000.0 / n;
            let light = match r <= 1.0 {
                true => (v.caustic + v.rest) * r,
                false => v.caustic * r.powf(CAUSTIC_GROWTH) + v.rest * r.powf(rest_growth(v)),
            };
            (light + v.traced) * (cl * n / 1000.0 + ct)
        };
        (125..4000).map(|n| n as f64).min_by(|a, b| f(*a).total_cmp(&f(*b))).unwrap()
    }

    #[test]
    fn the_count_minimises_variance_times_cost() {
        // Balanced already: V_l/n0 = V_c and c_l·n0 = C_c.
        assert_eq!(at(v(1.0, 0.5, 0.5), (1.0, 1.0)), 1000);
        // Light-side noise 4× the camera's: twice the subpaths; cost 4× cheaper: twice too.
        assert_eq!(at(v(1.0, 2.0, 2.0), (1.0, 1.0)), 2000);
        assert_eq!(at(v(1.0, 0.0, 1.0), (4.0, 1.0)), 2000);
        // Brute force over n agrees: above the pilot's count (light variance as n0/n;
        // the first case) and below it (caustics as n0/n, the rest as (n0/n)^a).
        let cases = [
            (v(0.3, 0.5, 0.5), (2.0, 0.7)),
            (v(4.0, 1.0, 0.0), (1.0, 1.0)),
            (v(4.0, 0.0, 1.0), (1.0, 1.0)),
            (v(1.0, 0.3, 0.6), (0.81, 1.0)),
            (v(1.0, 2.0, 2.0), (1.0, 5.0)),
        ];
        for (var, cost) in cases {
            let (got, best) = (at(var, cost) as f64, brute(var, cost));
            assert!((got - best).abs() <= 0.005 * best, "{var:?} {cost:?}: {got} against {best}");
        }
    }

    #[test]
    fn caustics_keep_more_light_subpaths_than_the_rest() {
        // The same light-side variance below balance: as caustics it grows faster than
        // n0/n (which would ask for 1000/√4.5 = 471; (n0/n)^1.3 asks for 618), as the
        // rest (a share of 1/5.5 of the variance but the caustics') as (n0/n)^0.18,
        // which asks for fewer.
        let caustic = at(v(4.5, 1.0, 0.0), (1.0, 1.0));
        let rest = at(v(4.5, 0.0, 1.0), (1.0, 1.0));
        assert!((550..700).contains(&caustic), "{caustic}");
        assert!(rest < caustic * 2 / 3, "caustic {caustic}, rest {rest}");
    }

    #[test]
    fn the_rest_grows_with_its_share() {
        assert_eq!(rest_growth(v(3.0, 5.0, 1.0)), 0.25);
        assert_eq!(rest_growth(v(0.0, 0.0, 0.0)), 0.0);
        // Half the variance the light side's (no caustics), its work at n0 twice the
        // camera's: the least of (x^-½ + 1)(2x + 1) is where x + 2x^1.5 = ½, x = ¼ (a
        // constant a = 0.2 would give the lower bound, 125).
        let half = at(v(1.0, 0.0, 1.0), (1.0, 2.0));
        assert!((248..253).contains(&half), "{half}");
    }

    #[test]
    fn the_count_stays_within_its_bounds() {
        assert_eq!(at(v(1.0, 1e6, 0.0), (1.0, 1.0)), 4_000);
        assert_eq!(at(v(1e6, 1.0, 0.0), (1.0, 1.0)), 125);
        // No light-side noise at all: the fewest; no camera-side noise: the most.
        assert_eq!(at(v(1.0, 0.0, 0.0), (1.0, 1.0)), 125);
        assert_eq!(at(v(0.0, 0.0, 1.0), (1.0, 1.0)), 4_000);
        // A black pilot keeps the count; NaN figures never escape.
        assert_eq!(at(v(0.0, 0.0, 0.0), (1.0, 1.0)), 1000);
        assert_eq!(at(v(f64::NAN, f64::NAN, f64::NAN), (1.0, 1.0)), 1000);
        let cost = Parts { traced: 1.0, light: 1.0 };
        assert_eq!(choose(1000, v(1.0, 1e6, 0.0), cost, 3000.0), 3000);
        assert_eq!(choose(1, v(1.0, 0.0, 0.0), cost, 1e9), 1);
    }

    #[test]
    fn the_pilot_splits_the_spread_between_the_parts() {
        let counts = Counts { paths: 1000, hits: 0, vertices: 0 };
        let work = Work { rays: 1000, ..Default::default() };
        let pilot = |values: [f32; 4], caustics_differ: f32, rest_differs: f32| {
            let mut p = Pilot::new(1);
            for x in values {
                p.add(&[[x, caustics_differ, rest_differs]], 1000, counts, work, 10);
            }
            assert!(p.complete());
            p
        };
        // Values 1 ± 0.5 between passes (variance 1/3); caustics' halves 2·0.5 apart in
        // every pass (variance (2·0.5)²/4 = 1/4) and the rest's 0.2 (1/100); the
        // camera's the rest of the spread.
        let got = pilot([0.5, 1.5, 0.5, 1.5], 1.0, 0.2).variances();
        let norm = 1.0 + 0.01;
        assert!((got.caustic - 0.25 / norm).abs() < 1e-6, "{got:?}");
        assert!((got.rest - 0.01 / norm).abs() < 1e-6, "{got:?}");
        assert!((got.traced - (1.0 / 3.0 - 0.26) / norm).abs() < 1e-6, "{got:?}");
        // Halves that agree: all the spread is the camera's, and the fewest subpaths.
        let p = pilot([0.5, 1.5, 0.5, 1.5], 0.0, 0.0);
        assert_eq!(p.variances().caustic + p.variances().rest, 0.0);
        assert_eq!(p.choose(1000), 125);
        // Halves that differ more than passes do: all the light's, and the most.
        assert_eq!(pilot([1.0, 1.0, 1.0, 1.0], 1.0, 0.0).choose(1000), 4_000);
        assert_eq!(pilot([1.0, 1.0, 1.0, 1.0], 0.0, 1.0).choose(1000), 4_000);
    }
}
