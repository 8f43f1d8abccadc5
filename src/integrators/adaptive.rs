//! Visibility-driven adaptive photon tracing (Hachisuka and Jensen, "Robust adaptive
//! photon tracing using photon path visibility", ACM TOG 30(5), 2011), chosen with
//! `pbrt-sppm render --photon-sampling adaptive`.
//!
//! A photon path is a function of its random numbers u ∈ [0, 1)^d. Where the camera
//! sees a small part of what the lights reach, most uniform photons land nowhere near
//! a visible point and are wasted. Here photons are drawn in proportion to the
//! visibility V(u) by a Markov chain, and the flux is rescaled by the visible fraction
//! ∫V, which uniform photons estimate. V(u) is 1 when the path meets a grid cell that
//! holds a visible point, a superset of the paths that deposit: the paper's "deposits
//! somewhere" is, once radii are below the pixel spacing, a scatter of tiny disks that
//! moves every iteration, which chains cannot follow (we measured a 5–10% dark bias).
//!
//! ```text
//! Φ(pixel) ≈ (V_uniform / N) · Σ_steps f(u_step),    each of the N steps:
//!   draw a uniform u (the "large step"); visible?  → the chain jumps to it (replica exchange)
//!   otherwise propose u' = u_chain + δ·(2ξ − 1) per coordinate (wrapped); visible? → accept
//!   record the chain's path; δ += (accepted − 0.234) / mutations
//! ```
//!
//! The step then records the chain's current path, and the image's usual 1/N applies.
//! The mutation size δ adapts toward the acceptance rate 0.234 with a step that shrinks
//! as 1/n, so the adaptation fades and the chain keeps its target.
//!
//! There is a fixed number of chains, not one per thread, each with its own generator
//! and state kept across iterations, so the image is the same for any thread count.
//! At the start of an iteration each chain re-traces its path against the new visible
//! points, since which paths are visible changes with them.

use crate::sampling::{Rng, Sampler, hash};
use glam::Vec3;
use rayon::prelude::*;

/// Chains: enough to keep every core busy, few enough that each runs long.
pub const CHAINS: usize = 64;
/// The acceptance rate δ is steered toward (optimal for random-walk proposals).
const TARGET_ACCEPTANCE: f32 = 0.234;
const MIN_DELTA: f32 = 1e-5;

/// How photon paths are drawn (`--photon-sampling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PhotonSampling {
    /// Independent uniform photons, as pbrt traces them.
    #[default]
    Uniform,
    /// Markov chains over paths that reach a visible point.
    Adaptive,
}

/// A photon deposit: pixel and flux.
pub type Deposit = (u32, Vec3);

/// A photon path's numbers: replayed from a stored vector, which grows with fresh
/// uniform numbers when the path asks for more than it holds.
pub struct PrimarySample<'a> {
    u: &'a mut Vec<f32>,
    next: usize,
    rng: &'a mut Rng,
}

impl Sampler for PrimarySample<'_> {
    fn get1d(&mut self) -> f32 {
        if self.next == self.u.len() {
            self.u.push(self.rng.uniform());
        }
        self.next += 1;
        self.u[self.next - 1]
    }

    fn get2d(&mut self) -> [f32; 2] {
        [self.get1d(), self.get1d()]
    }
}

/// One Markov chain over visible photon paths. A checkpoint saves what carries over
/// from one iteration to the next; the deposits and visibility are re-traced at the
/// start of every iteration, so they are not saved.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Chain {
    rng: Rng,
    /// The current path's numbers; empty until a visible path is found.
    state: Vec<f32>,
    /// The current path's deposits against this iteration's visible points, and
    /// whether it is visible now.
    #[serde(skip)]
    deposits: Vec<Deposit>,
    #[serde(skip)]
    visible: bool,
    delta: f32,
    mutations: u64,
}

/// What a photon pass did (uniform photons, or the chains), summed over a render in
/// [`super::sppm::Stats`].
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct PhotonCounts {
    /// Uniform photons traced, those that were visible (V = 1) and those that
    /// deposited.
    pub uniform: u64,
    pub uniform_visible: u64,
    pub uniform_deposited: u64,
    /// Mutations proposed and accepted.
    pub mutations: u64,
    pub accepted: u64,
    /// Steps that recorded a visible path (a chain records nothing until it has one).
    /// A visible path may deposit nothing.
    pub recorded: u64,
    /// Every path traced (uniform, mutated and re-traced) and their surface hits.
    pub traced: u64,
    pub hits: u64,
}

impl PhotonCounts {
    pub fn plus(mut self, o: PhotonCounts) -> PhotonCounts {
        self.uniform += o.uniform;
        self.uniform_visible += o.uniform_visible;
        self.uniform_deposited += o.uniform_deposited;
        self.mutations += o.mutations;
        self.accepted += o.accepted;
        self.recorded += o.recorded;
        self.traced += o.traced;
        self.hits += o.hits;
        self
    }
}

impl Chain {
    /// The chains of a render, each seeded from the render's seed and its index.
    pub fn new_set(seed: u64) -> Vec<Chain> {
        (0..CHAINS as u64)
            .map(|c| Chain {
                rng: Rng::new(hash(&[seed, c, 2])),
                state: Vec::new(),
                deposits: Vec::new(),
                visible: false,
                delta: 0.1,
                mutations: 0,
            })
            .collect()
    }

    /// `steps` steps; returns the recorded deposits (in step order) and the counts.
    /// `trace` follows one path, appending its deposits; it returns the surfaces hit
    /// and whether the path is visible.
    fn run<F>(&mut self, steps: u64, trace: &F) -> (Vec<Deposit>, PhotonCounts)
    where
        F: Fn(&mut PrimarySample, &mut Vec<Deposit>) -> (u64, bool),
    {
        let mut n = PhotonCounts::default();
        let mut path = |u: &mut Vec<f32>, rng: &mut Rng, out: &mut Vec<Deposit>| {
            out.clear();
            n.traced += 1;
            let (hits, visible) = trace(&mut PrimarySample { u, next: 0, rng }, out);
            n.hits += hits;
            visible
        };
        if !self.state.is_empty() {
            self.visible = path(&mut self.state, &mut self.rng, &mut self.deposits);
        }
        let (mut u, mut d, mut records) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..steps {
            u.clear();
            n.uniform += 1;
            if path(&mut u, &mut self.rng, &mut d) {
                n.uniform_visible += 1;
                n.uniform_deposited += !d.is_empty() as u64;
                std::mem::swap(&mut self.state, &mut u);
                std::mem::swap(&mut self.deposits, &mut d);
                self.visible = true;
            } else if !self.state.is_empty() {
                self.propose(&mut u);
                let accepted = path(&mut u, &mut self.rng, &mut d);
                if accepted {
                    std::mem::swap(&mut self.state, &mut u);
                    std::mem::swap(&mut self.deposits, &mut d);
                    self.visible = true;
                }
                self.mutations += 1;
                let a = if accepted { 1.0 } else { 0.0 };
                self.delta = (self.delta + (a - TARGET_ACCEPTANCE) / self.mutations as f32).clamp(MIN_DELTA, 0.5);
                n.mutations += 1;
                n.accepted += accepted as u64;
            }
            if self.visible {
                records.extend_from_slice(&self.deposits);
                n.recorded += 1;
            }
        }
        (records, n)
    }

    /// `u` := the current state moved by up to ±δ per coordinate, wrapped into [0, 1).
    fn propose(&mut self, u: &mut Vec<f32>) {
        u.clear();
        for &x in &self.state {
            let mut y = x + self.delta * (2.0 * self.rng.uniform() - 1.0);
            if y < 0.0 {
                y += 1.0;
            } else if y >= 1.0 {
                y -= 1.0;
            }
            u.push(y.min(1.0 - f32::EPSILON / 2.0));
        }
    }
}

/// One iteration's photons: `total` steps shared among the chains, in parallel.
/// Returns each chain's deposits, the weight every deposit takes and the counts.
///
/// The records are visible paths, so their mean estimates the flux per visible path;
/// times ∫V (the visible fraction of the uniform photons) it is the flux per photon,
/// and the image divides by `total`: hence weight = (visible / uniform) · total /
/// records. Dividing by the records made rather than by the steps keeps a chain that
/// has no visible path yet (at the start, or when the visible points move) from
/// darkening the image.
pub fn pass<F>(chains: &mut [Chain], total: u64, trace: &F) -> (Vec<Vec<Deposit>>, f32, PhotonCounts)
where
    F: Fn(&mut PrimarySample, &mut Vec<Deposit>) -> (u64, bool) + Sync,
{
    let k = chains.len() as u64;
    let results: Vec<(Vec<Deposit>, PhotonCounts)> = chains
        .par_iter_mut()
        .enumerate()
        .map(|(c, chain)| chain.run(total / k + ((c as u64) < total % k) as u64, trace))
        .collect();
    let counts = results.iter().fold(PhotonCounts::default(), |a, r| a.plus(r.1));
    let weight = match counts.recorded {
        0 => 0.0,
        r => (counts.uniform_visible as f64 / counts.uniform as f64 * total as f64 / r as f64) as f32,
    };
    (results.into_iter().map(|r| r.0).collect(), weight, counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stand-in photon path: deposits at "pixel" ⌊1000·u₀⌋ with flux u₁ when u₀ lies in
    /// a small window (the visible region), else nothing.
    fn toy(s: &mut PrimarySample, out: &mut Vec<Deposit>) -> (u64, bool) {
        let (a, b) = (s.get1d(), s.get1d());
        if (0.50..0.52).contains(&a) {
            out.push(((a * 1000.0) as u32, Vec3::splat(b)));
        }
        (1, (0.49..0.53).contains(&a))
    }

    #[test]
    fn the_weighted_chain_estimates_the_uniform_integral() {
        // ∫ f over the window = 0.02 · E[u₁] = 0.01 per unit of flux.
        let mut chains = Chain::new_set(3);
        let (mut sum, mut steps) = (0.0f64, 0u64);
        for _ in 0..20 {
            let (records, w, n) = pass(&mut chains, 20_000, &toy);
            sum += w as f64 * records.iter().flatten().map(|d| d.1.x as f64).sum::<f64>();
            steps += n.uniform;
        }
        let estimate = sum / steps as f64;
        assert!((estimate - 0.01).abs() < 0.0005, "{estimate}");
    }

    #[test]
    fn nearly_every_step_records_a_visible_path_and_acceptance_nears_the_target() {
        let mut chains = Chain::new_set(1);
        pass(&mut chains, 50_000, &toy);
        let (records, _, n) = pass(&mut chains, 50_000, &toy);
        // Uniform photons would be visible 4% of the time and deposit 2%.
        assert!(n.recorded as f64 > 0.95 * 50_000.0, "{}", n.recorded);
        let deposits: usize = records.iter().map(Vec::len).sum();
        assert!((0.4..0.6).contains(&(deposits as f64 / n.recorded as f64)), "{deposits}");
        let rate = n.accepted as f64 / n.mutations as f64;
        assert!((rate - TARGET_ACCEPTANCE as f64).abs() < 0.05, "acceptance {rate}");
        assert!(n.uniform_visible > 0 && n.uniform_visible < n.uniform / 10);
    }

    #[test]
    fn the_chains_do_not_depend_on_the_thread_count() {
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
            let mut chains = Chain::new_set(7);
            Ok::<_, String>(pool.install(|| {
                (0..3).map(|_| pass(&mut chains, 10_001, &toy)).map(|(r, w, _)| (r, w.to_bits())).collect::<Vec<_>>()
            }))
        };
        let (Ok(a), Ok(b)) = (run(1), run(2)) else { panic!("no thread pool") };
        assert_eq!(a, b);
    }
}
