//! Stochastic progressive photon mapping (pbrt-v3 `SPPMIntegrator`), one function per
//! phase: camera pass (visible points and direct light), grid build ([`super::grid`]),
//! photon pass (parallel, deterministic), per-pixel update (γ = 2/3, f64
//! accumulators), image.
//!
//! ```text
//! Integrator "sppm" "integer numiterations" 64 "integer maxdepth" 5
//!            "integer photonsperiteration" -1 "float radius" 1 "integer seed" 0
//! ```
//! Camera paths draw from a pixel's scrambled Sobol' sequences (index: the iteration),
//! or with `--sampler random` from a generator seeded by (seed, pixel, iteration);
//! photons from a generator seeded by (seed, iteration, photon), or with
//! `--photon-sampling adaptive` from [`super::adaptive`]'s Markov chains. Photon
//! contributions are summed in a fixed order, so any thread count gives a bit-identical
//! image.

use super::adaptive::{self, Chain, Deposit, PhotonCounts, PhotonSampling};
use super::beams::{self, Beam, VolumeGather, VolumePhoton};
use super::error::RenderError;
use super::grid::{Binning, Grid, Grouped, Site};
use super::passes::{self, PassMode};
use super::preview::{self, Preview};
use super::volume::{self, MediumPoint};
use crate::fixes::Fix;
use crate::interaction::Footprint;
use crate::lights::Light;
use crate::materials::{Bsdf, KeptBsdf, TransportMode};
use crate::math::{Point3, Vector3};
use crate::media::HenyeyGreenstein;
use crate::memory::{DEPOSITS_HELD, prefetch};
use crate::parser::Syntax;
use crate::render::RenderScene;
use crate::sampling::power_heuristic;
use crate::sampling::{Rng, Sampler, SamplerKind, SobolSample, hash, hash_more};
use crate::spectrum::{Rgb, luminance, transport};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::ops::Range;
use std::time::Instant;

const GAMMA: f64 = 2.0 / 3.0;
const PHOTON_CHUNK: usize = 1024;
/// The most photon chunks traced before their deposits are summed: a bound on the
/// memory deposits hold (f16-11b at 10⁶ photons held 440 MB of them at once).
const DEPOSIT_BAND: usize = 256;
/// The most photon chunks traced at a time with beams: a bound on the memory of the
/// photons in media they keep before [`beams::Gather`] takes them.
const BEAM_BAND: usize = 32;
/// Pixel ranges photon deposits are grouped into for the parallel reduction.
const DEPOSIT_RANGES: usize = 64;
/// Interfaces crossed by one path before it is abandoned (guards against loops).
const MAX_PASSES: u32 = 64;

/// A point where a camera path met a diffuse surface, or scattered in a medium.
#[derive(Clone, Debug)]
pub struct VisiblePoint {
    pub p: Vec3,
    pub wo: Vec3,
    pub ng: Vec3,
    pub at: Scatterer,
    pub beta: Rgb,
    /// The camera path kept only its first wavelength (dispersion).
    pub terminated: bool,
}

/// What scatters light at a visible point.
// Visible points live in one array per render, not per hit: the size is fine.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Scatterer {
    Surface(KeptBsdf),
    /// A point in a medium: photons that scatter in a medium within the radius count,
    /// by volume (Jensen and Christensen 1998), weighted by the phase function.
    Medium(HenyeyGreenstein),
}

/// Per-pixel SPPM state.
#[derive(Clone, Debug)]
pub struct Pixel {
    pub radius: f64,
    pub ld: DVec3,
    pub tau: DVec3,
    pub n: f64,
    pub vp: Option<VisiblePoint>,
}

/// One pixel's progressive state as a checkpoint saves it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelState {
    pub radius: f64,
    pub n: f64,
    pub ld: [f64; 3],
    pub tau: [f64; 3],
}

/// Timings and counts, for `--stats`.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Stats {
    pub camera_seconds: f64,
    pub grid_seconds: f64,
    pub photon_seconds: f64,
    pub update_seconds: f64,
    /// With beams, the part of `photon_seconds` spent gathering photons along them.
    #[serde(default)]
    pub beam_seconds: f64,
    pub camera_rays: u64,
    /// Photon paths traced, surfaces hit, uniform photons that deposited nothing
    /// (wasted), adaptive mutations.
    pub photons: PhotonCounts,
    /// Visible points stored, over all iterations (with VCM: light vertices).
    pub visible_points: u64,
    pub iterations: u32,
    /// Kept by VCM: the phases are light subpaths, the grid of their vertices, camera
    /// subpaths and light tracing's splats, and `photons` counts light subpaths.
    #[serde(default)]
    pub bidirectional: bool,
    /// With VCM: pixels that trace more rays for what they see through perfect
    /// specular chains (`vcm/camera/prefix.rs`).
    #[serde(default)]
    pub prefix_pixels: u64,
    /// With vcm's cached connections, once learnt: the draws a camera vertex makes
    /// (`vcm/links.rs`); 0 otherwise.
    #[serde(default)]
    pub connection_draws: u32,
    /// With vcm: connections that traced a shadow ray, and those it found clear.
    #[serde(default)]
    pub connections: u64,
    #[serde(default)]
    pub connections_clear: u64,
    /// With vcm's `--connections auto`, once the pilot is done: what chose between
    /// cached and paired connections.
    #[serde(default)]
    pub connections_auto: Option<super::vcm::links::Unblocking>,
}

/// The progressive state of a render.
pub struct Sppm<'a> {
    pub(super) scene: &'a RenderScene,
    pub pixels: Vec<Pixel>,
    /// Where each pixel gathers photons this iteration: written by the camera pass
    /// while the pixel is in cache (a pass over the pixels after it read 216 bytes a
    /// pixel to keep 20).
    sites: Vec<Option<Site>>,
    width: usize,
    origin: (u32, u32),
    pub iteration: u32,
    pub photons_per_iteration: u64,
    max_depth: u32,
    seed: u64,
    sampler: SamplerKind,
    /// Adaptive photon tracing's chains (`None`: uniform photons).
    chains: Option<Vec<Chain>>,
    /// How much camera rays' differentials are scaled (pbrt scales them down as the
    /// iterations that share a pixel grow; see [`crate::scene::Integrator`]).
    differential_scale: f32,
    /// Classic SPPM or independent passes ([`super::passes`]).
    passes: PassMode,
    /// The first pass rendered (independent passes may start anywhere).
    first: u32,
    /// The first pass's radius.
    r1: f64,
    /// How camera paths gather photons in media.
    volume: VolumeGather,
    /// With beams, each pixel's medium segments of this iteration's camera path (empty
    /// otherwise: nothing per pixel where no medium is).
    beams: Vec<Vec<Beam>>,
    pub stats: Stats,
    /// The iteration under way's counts, for progress.
    pub live: std::sync::Arc<super::report::Live>,
}

/// max(floor, 1/√iterations).
fn differential_scale(iterations: u32, floor: f32) -> f32 {
    (1.0 / (iterations.max(1) as f32).sqrt()).max(floor)
}

impl<'a> Sppm<'a> {
    /// Fails (rather than aborting) when the pixels' state does not fit in memory.
    /// `iterations`: how many the run plans, which sets the camera rays' differential
    /// scale as pbrt sets it.
    pub fn new(
        scene: &'a RenderScene,
        iterations: u32,
        photons_per_iteration: u64,
        radius: f32,
        seed: u64,
        (sampler, photon_sampling): (SamplerKind, PhotonSampling),
    ) -> Result<Sppm<'a>, RenderError> {
        let [x0, x1, y0, y1] = scene.film.pixel_bounds;
        let (w, h) = ((x1 - x0) as usize, (y1 - y0) as usize);
        let pixel = Pixel { radius: radius as f64, ld: DVec3::ZERO, tau: DVec3::ZERO, n: 0.0, vp: None };
        // Per pixel: its state and where it gathers photons.
        let bytes = (w * h).saturating_mul(std::mem::size_of::<Pixel>() + std::mem::size_of::<Option<Site>>());
        let out_of_memory = |_| RenderError::OutOfMemory { width: w, height: h, bytes };
        let (mut pixels, mut sites) = (Vec::new(), Vec::new());
        pixels.try_reserve_exact(w * h).map_err(out_of_memory)?;
        sites.try_reserve_exact(w * h).map_err(out_of_memory)?;
        pixels.resize(w * h, pixel);
        sites.resize(w * h, None);
        Ok(Sppm {
            scene,
            pixels,
            sites,
            width: w,
            origin: (x0, y0),
            iteration: 0,
            photons_per_iteration,
            max_depth: scene.integrator.max_depth,
            seed,
            sampler,
            chains: (photon_sampling == PhotonSampling::Adaptive).then(|| Chain::new_set(seed)),
            differential_scale: differential_scale(iterations, scene.integrator.differential_floor),
            passes: PassMode::Classic,
            first: 0,
            r1: radius as f64,
            volume: VolumeGather::Points,
            beams: Vec::new(),
            stats: Stats::default(),
            live: Default::default(),
        })
    }

    /// Renders independent passes from `first` on, or classic SPPM (`first` 0; the
    /// run's plan refuses a pass range for it).
    pub fn with_passes(mut self, mode: PassMode, first: u32) -> Result<Sppm<'a>, RenderError> {
        if mode.is_independent() && self.chains.is_some() {
            return Err(RenderError::AdaptiveIndependent);
        }
        (self.passes, self.first, self.iteration) = (mode, first, first);
        Ok(self)
    }

    /// Gathers photons in media at points or along beams ([`super::beams`]); a scene
    /// without media has nothing to gather there, and renders as it always has.
    /// Adaptive photons gather at points (their chains deposit as they go; the plan
    /// refuses beams with them).
    pub fn with_volume_gather(mut self, volume: VolumeGather) -> Sppm<'a> {
        if !self.scene.media.is_empty() && self.chains.is_none() {
            self.volume = volume;
            let n = if volume == VolumeGather::Beams { self.pixels.len() } else { 0 };
            self.beams = vec![Vec::new(); n];
        }
        self
    }

    /// Passes rendered by this run (a resumed run counts those before it).
    pub fn passes_done(&self) -> u32 {
        self.iteration.saturating_sub(self.first)
    }

    /// The first pass this run renders.
    pub fn first_pass(&self) -> u32 {
        self.first
    }

    /// The state a checkpoint saves (see [`super::checkpoint`]).
    pub fn save(&self) -> (Vec<PixelState>, Option<Vec<Chain>>) {
        let px = |p: &Pixel| PixelState { radius: p.radius, n: p.n, ld: p.ld.to_array(), tau: p.tau.to_array() };
        (self.pixels.iter().map(px).collect(), self.chains.clone())
    }

    /// Continues from a checkpoint's state after `iteration` iterations.
    pub fn restore(
        &mut self,
        iteration: u32,
        pixels: &[PixelState],
        chains: Option<Vec<Chain>>,
        stats: Stats,
    ) -> Result<(), RenderError> {
        if pixels.len() != self.pixels.len() {
            return Err(RenderError::CheckpointPixels { saved: pixels.len(), film: self.pixels.len() });
        }
        if chains.is_some() != self.chains.is_some() {
            return Err(RenderError::CheckpointSampling);
        }
        for (p, s) in self.pixels.iter_mut().zip(pixels) {
            (p.radius, p.n, p.ld, p.tau) = (s.radius, s.n, DVec3::from(s.ld), DVec3::from(s.tau));
        }
        if chains.is_some() {
            self.chains = chains;
        }
        (self.iteration, self.stats) = (iteration, stats);
        Ok(())
    }

    /// One full iteration: camera pass, grid, photons, update.
    pub fn iterate(&mut self) {
        self.iterate_showing(None)
    }

    /// One iteration, offering `preview` provisional images as it goes (see
    /// [`super::preview`]); the image it ends with is the same either way.
    pub fn iterate_showing(&mut self, mut preview: Option<&mut Preview>) {
        let t = Instant::now();
        self.live.reset();
        self.scene.begin_pass(self.iteration);
        if let PassMode::Independent { alpha } = self.passes {
            let r = passes::radius(self.r1, alpha, self.iteration);
            self.pixels.par_iter_mut().for_each(|p| p.radius = r);
        }
        let n = self.pixels.len();
        for band in preview::bands(n, 4 * super::PIXELS_PER_TASK, usize::MAX, preview.is_some()) {
            self.stats.visible_points += self.camera_pass(band.clone());
            if let Some(show) = preview.as_mut() {
                show(&|| self.provisional(band.end, None));
            }
        }
        let t1 = Instant::now();
        // Adaptive chains' visibility is the cell a photon lands in holding a visible
        // point (`adaptive`), which overlap binning gives.
        let binning = if self.chains.is_some() { Binning::Overlap } else { Binning::Centre };
        let grid = Grid::build(&self.sites, binning);
        let t2 = Instant::now();
        let (phi, m, beam_sums) = self.photon_pass(grid.as_ref(), preview);
        let t3 = Instant::now();
        self.update(&phi, &m);
        if let Some(sums) = beam_sums {
            // Averaged over iterations as the direct light is; summed in the pass's
            // lanes, turned into output RGB here.
            let scene = &self.scene;
            self.pixels.par_iter_mut().zip(sums).for_each(|(p, s)| p.ld += scene.film_rgb_f64(s));
        }
        let t4 = Instant::now();
        self.iteration += 1;
        let s = &mut self.stats;
        s.camera_seconds += (t1 - t).as_secs_f64();
        s.grid_seconds += (t2 - t1).as_secs_f64();
        s.photon_seconds += (t3 - t2).as_secs_f64();
        s.update_seconds += (t4 - t3).as_secs_f64();
        s.camera_rays += n as u64;
        s.iterations = self.iteration;
    }

    /// Phase 1, for the pixels in `band`: trace one camera path per pixel to its first
    /// diffuse vertex, adding emitted and directly reflected light on the way. Returns
    /// how many pixels found a visible point (counted here, where each pixel's memory
    /// is in cache: a pass over all of them after took ~1.5% of f16-9a's time).
    fn camera_pass(&mut self, band: Range<usize>) -> u64 {
        let (scene, width, origin, iter, seed, max_depth) =
            (self.scene, self.width, self.origin, self.iteration, self.seed, self.max_depth);
        let (diff_scale, kind, live) = (self.differential_scale, self.sampler, &self.live);
        let time = scene.pass_time(iter, false);
        let first = band.start;
        let trace = |i: usize, (px, site): (&mut Pixel, &mut Option<Site>), beams: Option<&mut Vec<Beam>>| -> u64 {
            let i = first + i;
            if i.is_multiple_of(256) {
                live.add_camera(256);
            }
            let (x, y) = (origin.0 as usize + i % width, origin.1 as usize + i / width);
            let pixel = [x as f32, y as f32];
            // Low discrepancy: the pixel's iterations are the points of one sequence.
            let (ld, vp) = match kind {
                SamplerKind::Sobol => {
                    let mut s = SobolSample::new(hash(&[seed, x as u64, y as u64, 0]), iter);
                    camera_path(scene, pixel, &mut s, max_depth, (diff_scale, time), beams)
                }
                SamplerKind::Random => {
                    let mut rng = Rng::new(hash(&[seed, x as u64, y as u64, iter as u64, 0]));
                    camera_path(scene, pixel, &mut rng, max_depth, (diff_scale, time), beams)
                }
            };
            px.ld += scene.film_rgb(ld);
            // Photons are gathered at each visible point that can reflect.
            *site = vp.as_ref().filter(|vp| vp.beta != Vec3::ZERO).map(|vp| Site { p: vp.p, radius: px.radius as f32 });
            px.vp = vp;
            px.vp.is_some() as u64
        };
        let pixels = self.pixels[band.clone()].par_iter_mut().zip(self.sites[band.clone()].par_iter_mut());
        if self.volume == VolumeGather::Beams {
            let beams = self.beams[band].par_iter_mut();
            pixels
                .zip(beams)
                .enumerate()
                .with_max_len(super::PIXELS_PER_TASK)
                .map(|(i, (p, b))| {
                    b.clear();
                    trace(i, p, Some(b))
                })
                .sum()
        } else {
            pixels.enumerate().with_max_len(super::PIXELS_PER_TASK).map(|(i, p)| trace(i, p, None)).sum()
        }
    }

    /// Phase 3: trace photons; returns per-pixel flux Φ and photon counts M, and with
    /// beams each pixel's beam estimate. Uniform photons run in bands of chunks when a
    /// preview is wanted; the deposits are summed band after band, which is the order
    /// one sum of them all takes.
    fn photon_pass(&mut self, grid: Option<&Grid>, mut preview: Option<&mut Preview>) -> PhotonPass {
        let n = self.pixels.len();
        let (mut phi, mut m) = (vec![DVec3::ZERO; n], vec![0u64; n]);
        let beams = self.volume == VolumeGather::Beams;
        if (grid.is_none() && !beams) || self.scene.photon_sources.is_empty() {
            return (phi, m, beams.then(|| vec![DVec3::ZERO; n]));
        }
        let w = self.scene.photon_scale;
        if let (Some(chains), Some(grid)) = (&mut self.chains, grid) {
            let (scene, pixels, max_depth) = (self.scene, &self.pixels, self.max_depth);
            let time = scene.pass_time(self.iteration, false);
            let trace = |s: &mut adaptive::PrimarySample, out: &mut Vec<Deposit>| {
                let path = trace_photon(scene, (Some(grid), pixels), s, max_depth, (out, None), time);
                (path.hits, path.near)
            };
            let (deposits, weight, counts) = adaptive::pass(chains, self.photons_per_iteration, &trace);
            self.stats.photons = self.stats.photons.plus(counts);
            let (phi, m) = sum_deposits(deposits, weight as f64 * w, phi, m);
            return (phi, m, None);
        }
        let chunks = self.photons_per_iteration.div_ceil(PHOTON_CHUNK as u64) as usize;
        let scale = w / self.photons_per_iteration.max(1) as f64;
        let r = self.beam_radius();
        let mut gather = beams.then(|| beams::Gather::new(self.beams.iter().map(Vec::as_slice).collect(), r, scale));
        let most = if beams { BEAM_BAND } else { DEPOSIT_BAND };
        let mut runs = DepositRuns::default();
        for band in preview::bands(chunks, 8, most, preview.is_some()) {
            let mut rest = band.clone();
            while !rest.is_empty() {
                let run = runs.next(&rest);
                rest.start = run.end;
                let (deposits, more, counts) = self.uniform_photons(grid, run.start as u64..run.end as u64);
                runs.saw(run.len(), deposits.iter().map(Vec::len).sum());
                self.stats.photons = self.stats.photons.plus(counts);
                (phi, m) = sum_deposits(deposits, w, phi, m);
                if let Some(g) = gather.as_mut() {
                    more.into_iter().for_each(|chunk| g.add(chunk));
                }
            }
            if let Some(show) = preview.as_mut() {
                let done = band.end as f64 / chunks as f64;
                show(&|| self.provisional(n, Some((&phi, done))));
            }
        }
        let sums = gather.map(|g| {
            let (sums, seconds) = g.finish();
            self.stats.beam_seconds += seconds;
            sums
        });
        (phi, m, sums)
    }

    /// Independent photons of the chunks in `chunks` (of a fixed size); each chunk's
    /// deposits and (with beams) photons in media, in photon order.
    fn uniform_photons(&self, grid: Option<&Grid>, chunks: Range<u64>) -> UniformPhotons {
        let (scene, pixels, iter, seed, max_depth) =
            (self.scene, &self.pixels, self.iteration as u64, self.seed, self.max_depth);
        let total = self.photons_per_iteration;
        let time = scene.pass_time(self.iteration, false);
        let beams = self.volume == VolumeGather::Beams;
        let pass_hash = hash(&[seed, iter]);
        let results: Vec<(Vec<Deposit>, Vec<VolumePhoton>, PhotonCounts)> = chunks
            .into_par_iter()
            .map(|c| {
                let (mut out, mut volume, mut n) = (Vec::new(), Vec::new(), PhotonCounts::default());
                for k in c * PHOTON_CHUNK as u64..((c + 1) * PHOTON_CHUNK as u64).min(total) {
                    // Independent numbers for photons under either sampler: Sobol'
                    // points, padded per iteration or as one five-dimensional sequence
                    // over the whole render, gained nothing measurable (docs/sampling.md).
                    let mut rng = Rng::new(hash_more(pass_hash, &[k, 1]));
                    let before = out.len() + volume.len();
                    let sink = (&mut out, beams.then_some(&mut volume));
                    let path = trace_photon(scene, (grid, pixels), &mut rng, max_depth, sink, time);
                    n.hits += path.hits;
                    n.uniform_visible += path.near as u64;
                    n.uniform_deposited += (out.len() + volume.len() > before) as u64;
                }
                n.uniform = (total - c * PHOTON_CHUNK as u64).min(PHOTON_CHUNK as u64);
                n.traced = n.uniform;
                self.live.add_photons(n.uniform);
                (out, volume, n)
            })
            .collect();
        let counts = results.iter().fold(PhotonCounts::default(), |a, r| a.plus(r.2));
        let (deposits, volume): (Vec<_>, Vec<_>) = results.into_iter().map(|r| (r.0, r.1)).unzip();
        (deposits, volume, counts)
    }

    /// This iteration's beam radius: one for all pixels, shrinking from the first
    /// radius as independent passes' does (α = 2/3 in classic SPPM, as its γ).
    fn beam_radius(&self) -> f32 {
        let alpha = match self.passes {
            PassMode::Independent { alpha } => alpha,
            PassMode::Classic => GAMMA,
        };
        passes::radius(self.r1, alpha, self.iteration) as f32
    }

    /// Phase 4: the progressive radius and flux update; with independent passes, the
    /// pass's density estimate β·Φ/(π r²) is added to τ instead. Visible points stay
    /// until the next camera pass replaces them: clearing them touched every pixel's
    /// memory and took three times as long as the update itself (f16-9a).
    fn update(&mut self, phi: &[DVec3], m: &[u64]) {
        let scene = self.scene;
        if self.passes.is_independent() {
            self.pixels.par_iter_mut().enumerate().for_each(|(i, p)| {
                if m[i] > 0
                    && let Some(vp) = &p.vp
                {
                    p.tau +=
                        scene.film_rgb_f64(vp.beta.as_dvec3() * phi[i]) / (std::f64::consts::PI * p.radius * p.radius);
                    p.n += m[i] as f64;
                }
            });
            return;
        }
        self.pixels.par_iter_mut().enumerate().for_each(|(i, p)| {
            if m[i] > 0
                && let Some(vp) = &p.vp
            {
                let mf = m[i] as f64;
                let n_new = p.n + GAMMA * mf;
                let r_new = p.radius * (n_new / (p.n + mf)).sqrt();
                p.tau =
                    (p.tau + scene.film_rgb_f64(vp.beta.as_dvec3() * phi[i])) * (r_new * r_new) / (p.radius * p.radius);
                p.n = n_new;
                p.radius = r_new;
            }
        });
    }

    /// The current estimate: L = Ld/k + τ/(k·P·π·r²), as the film records it; with
    /// independent passes, the sum of the passes' estimates over k.
    pub fn image(&self) -> Vec<[f32; 3]> {
        if self.passes.is_independent() {
            let k = self.passes_done().max(1) as f64;
            return self.pass_sums().into_iter().map(|s| (s / k).as_vec3().to_array()).collect();
        }
        let k = self.iteration.max(1) as f64;
        let np = self.photons_per_iteration.max(1) as f64;
        let film = &self.scene.film;
        // On all threads: one thread took 45 ms of f16-9a's 700,000 pixels.
        self.pixels
            .par_iter()
            .map(|p| {
                let l = p.ld / k + p.tau / (k * np * std::f64::consts::PI * p.radius * p.radius);
                film.respond(l).as_vec3().to_array()
            })
            .collect()
    }

    /// The image part way through an iteration: the first `camera_done` pixels with this
    /// iteration's direct light, the rest as they were; indirect light as it was, or,
    /// once `photons` (Φ so far and the share of the iteration's photons traced) are
    /// given, blended with this iteration's estimate from them, scaled up to the whole.
    fn provisional(&self, camera_done: usize, photons: Option<(&[DVec3], f64)>) -> Vec<[f32; 3]> {
        let independent = self.passes.is_independent();
        let k = if independent { self.passes_done() } else { self.iteration } as f64;
        let np = self.photons_per_iteration.max(1) as f64;
        let film = &self.scene.film;
        let area = |p: &Pixel| std::f64::consts::PI * p.radius * p.radius;
        let pixel = |(i, p): (usize, &Pixel)| {
            let old = match (k > 0.0, independent) {
                (false, _) => DVec3::ZERO,
                (true, true) => p.tau / (np * k),
                (true, false) => p.tau / (k * np * area(p)),
            };
            let indirect = match photons {
                Some((phi, share)) => {
                    let beta = p.vp.as_ref().map_or(DVec3::ZERO, |vp| vp.beta.as_dvec3());
                    (old * k + self.scene.film_rgb_f64(beta * phi[i]) / (share * np * area(p))) / (k + 1.0)
                }
                None => old,
            };
            let ld = p.ld / if i < camera_done { k + 1.0 } else { k.max(1.0) };
            film.respond(ld + indirect).as_vec3().to_array()
        };
        self.pixels.par_iter().enumerate().map(pixel).collect()
    }

    /// With independent passes, the sum of the passes' estimates Ld + τ/P per pixel,
    /// as the film records it: what a shard writes and a merge adds up.
    pub fn pass_sums(&self) -> Vec<DVec3> {
        let np = self.photons_per_iteration.max(1) as f64;
        let film = &self.scene.film;
        self.pixels.iter().map(|p| film.respond(p.ld + p.tau / np)).collect()
    }
}

/// Φ and M per pixel, and with beams each pixel's beam estimate.
type PhotonPass = (Vec<DVec3>, Vec<u64>, Option<Vec<DVec3>>);
/// Per chunk of photons: deposits, photons in media (with beams); the counts.
type UniformPhotons = (Vec<Vec<Deposit>>, Vec<Vec<VolumePhoton>>, PhotonCounts);

/// Cuts a band of photon chunks into runs whose deposits stay near [`DEPOSITS_HELD`]
/// (16 bytes each, and as many again while grouped by pixel): a short first run, then
/// runs as long as the deposits per chunk of the run before allow, growing at most
/// eightfold a run (chunks are alike, but a rare photon may meet thousands of visible
/// points). Every run's deposits are summed before the next is traced, in chunk
/// order, so where the runs are cut changes no bit of the image. A wide radius meets
/// thousands of visible points per photon: in fixed bands of 256 chunks a 1024² film
/// held 1.1 GB of deposits.
#[derive(Default)]
struct DepositRuns {
    /// The last run's length and deposits per chunk; `None` before the first.
    last: Option<(usize, f64)>,
}

impl DepositRuns {
    /// The next run: the start of `rest`, at least one chunk unless `rest` is empty.
    fn next(&self, rest: &Range<usize>) -> Range<usize> {
        let len = match self.last {
            None => 2 * rayon::current_num_threads(),
            Some((len, d)) => ((DEPOSITS_HELD as f64 / d.max(1.0)) as usize).min(8 * len),
        };
        rest.start..rest.start + len.max(1).min(rest.len())
    }

    /// Notes the deposits a run of `chunks` made.
    fn saw(&mut self, chunks: usize, deposits: usize) {
        self.last = Some((chunks, deposits as f64 / chunks.max(1) as f64));
    }
}

/// Φ and M per pixel from lists of deposits, each deposit's flux times `w`. Each
/// pixel sums its contributions in a fixed order (list by list, deposit by deposit),
/// whatever the thread count; the lists are grouped by pixel range first, so that
/// pixel ranges are summed in parallel and each deposit is read once.
fn sum_deposits(lists: Vec<Vec<Deposit>>, w: f64, mut phi: Vec<DVec3>, mut m: Vec<u64>) -> (Vec<DVec3>, Vec<u64>) {
    let (grouped, span) = Grouped::by_pixel_range(lists, phi.len(), DEPOSIT_RANGES);
    phi.par_chunks_mut(span).zip(m.par_chunks_mut(span)).enumerate().for_each(|(r, (phi, m))| {
        let lo = r * span;
        for &(pixel, f) in grouped.iter().flat_map(|g| g.group(r)) {
            phi[pixel as usize - lo] += w * f.as_dvec3();
            m[pixel as usize - lo] += 1;
        }
    });
    (phi, m)
}

/// What a path finds at a hit.
// A stack temporary per hit: boxing the BSDF would allocate on every bounce.
#[allow(clippy::large_enum_variant)]
pub(super) enum Surface {
    Bsdf(Bsdf),
    /// An interface (no surface): the ray now continues past it, depth unchanged.
    PassedThrough,
    /// Too many interfaces in a row: the path ends.
    Abandon,
}

/// The BSDF at a hit, or for an interface the ray moved past it (at most
/// [`MAX_PASSES`] in a row), into the medium on its other side if it is a transition.
pub(super) fn surface(
    scene: &RenderScene,
    (hit, si): (&crate::accel::Hit, &crate::interaction::SurfaceInteraction),
    fp: &Footprint,
    ray: &mut crate::math::Ray,
    passes: &mut u32,
    medium: &mut Option<u32>,
) -> Surface {
    if let Some(b) = scene.bsdf(hit, si, fp) {
        return Surface::Bsdf(b);
    }
    *passes += 1;
    if *passes > MAX_PASSES {
        return Surface::Abandon;
    }
    *medium = scene.medium_after(hit, si.n.0, ray.d.0, *medium);
    *ray = si.spawn_ray(ray.d);
    Surface::PassedThrough
}

/// The camera ray through a point drawn in `pixel` (two 2D samples: film, lens), about
/// it by the film's pixel filter when it has one (pbrt-v4's), with its differentials
/// scaled by `diff_scale` when the scene's shading reads them.
pub(super) fn camera_ray(
    scene: &RenderScene,
    pixel: [f32; 2],
    sampler: &mut impl Sampler,
    diff_scale: f32,
    time: Option<f32>,
) -> (crate::math::Ray, Option<crate::math::ray::RayDifferential>, f32) {
    let u = sampler.get2d();
    let p_film = match &scene.film.filter {
        Some(f) => {
            let d = f.sample(u);
            [pixel[0] + 0.5 + d[0], pixel[1] + 0.5 + d[1]]
        }
        _ => [pixel[0] + u[0], pixel[1] + u[1]],
    };
    // A pinhole's lens sample is drawn past, not computed (1–2% of a camera pass).
    let u_lens = match scene.camera.reads_lens_sample() {
        true => sampler.get2d(),
        false => {
            sampler.skip2d();
            [0.5; 2]
        }
    };
    let p_raster = p_film;
    // The pass's time (see `RenderScene::pass_time`), or one of the ray's own.
    let time = time.unwrap_or_else(|| scene.camera.time(sampler.get1d()));
    // As in pbrt, only the camera ray has differentials: rays spawned later have none.
    // Scenes whose shading never reads a footprint skip them.
    // A realistic camera's lens may stop the ray (weight 0) or weight it.
    let Some((ray, weight)) = scene.camera.generate_ray_weighted(p_raster, u_lens, time) else {
        return (crate::math::Ray::new(crate::math::Point3(Vec3::ZERO), Vector3(Vec3::Z)), None, 0.0);
    };
    let diff = scene.needs_differentials.then(|| scene.camera.differentials(&ray, p_raster, u_lens, diff_scale));
    (ray, diff, weight)
}

/// A camera path: (direct and emitted light gathered, the visible point).
fn camera_path(
    scene: &RenderScene,
    pixel: [f32; 2],
    sampler: &mut impl Sampler,
    max_depth: u32,
    (diff_scale, time): (f32, Option<f32>),
    mut beams: Option<&mut Vec<Beam>>,
) -> (Rgb, Option<VisiblePoint>) {
    let (mut ray, mut diff, weight) = camera_ray(scene, pixel, sampler, diff_scale, time);
    if weight == 0.0 {
        return (Vec3::ZERO, None);
    }
    let (mut beta, mut ld, mut terminated) = (Vec3::splat(weight), Vec3::ZERO, false);
    let (mut specular_bounce, mut depth, mut passes, mut medium) = (false, 0, 0, scene.camera_medium);
    // DEVIATION(pbrt): appearance, `--fix sky-after-glossy`. pbrt-v3 adds infinite
    // lights to every camera ray that escapes; after a glossy bounce `direct_light` has
    // already counted them (its BSDF-sampled MIS half), so pbrt-v3 counts them twice.
    // pbrt-v4, and the fix, count them once.
    let sky_always = scene.syntax == Syntax::V3 && !scene.fixes.has(Fix::SkyAfterGlossy);
    while depth < max_depth {
        let hit = scene.intersect(&ray);
        if let Some(m) = medium {
            let (light, vp) = in_medium(scene, &ray, (hit.as_ref(), m), &mut beta, beams.as_deref_mut(), sampler);
            ld += light;
            if vp.is_some() {
                return (ld, vp);
            }
        }
        let Some(hit) = hit else {
            if depth == 0 || specular_bounce || sky_always {
                for (k, l) in scene.lights.iter().enumerate() {
                    ld += beta * scene.emission_of(k, l.le_escaped(ray.o.0, ray.d.0));
                }
            }
            break;
        };
        let si = scene.geometry.interaction(&hit);
        let fp = diff.take().map(|d| Footprint::new(&si, &d)).unwrap_or_default();
        let bsdf = match surface(scene, (&hit, &si), &fp, &mut ray, &mut passes, &mut medium) {
            Surface::Bsdf(b) => b,
            Surface::PassedThrough => continue,
            Surface::Abandon => break,
        };
        let wo = -ray.d.0.normalize();
        let here = Here { hit: &hit, medium };
        if depth == 0 || specular_bounce {
            ld += beta * scene.emitted(&hit, &si, wo);
        }
        scene.terminate_if_dispersed(&hit, &mut beta, &mut terminated);
        // pbrt: a visible point at diffuse surfaces, or glossy ones at the last depth.
        let visible_point = bsdf.is_diffuse() || (bsdf.is_glossy() && depth + 1 == max_depth);
        // pbrt-v4 follows the path one bounce past its visible point, so a light seen
        // in a specular lobe there (a smooth coat) is reflected; pbrt-v3 stops.
        let specular_too = visible_point && scene.syntax == Syntax::V4 && bsdf.is_specular();
        ld += beta * direct_light(scene, &si, &bsdf, wo, sampler, specular_too, here);
        if visible_point {
            return (
                ld,
                Some(VisiblePoint { p: si.p.0, wo, ng: si.n.0, at: Scatterer::Surface(bsdf.into()), beta, terminated }),
            );
        }
        if depth + 1 >= max_depth {
            break;
        }
        let Some(s) = bsdf.sample_f(wo, sampler.get2d(), sampler.get1d(), TransportMode::Radiance) else { break };
        beta *= s.f * s.wi.dot(bsdf.shading_normal()).abs() / s.pdf;
        specular_bounce = s.specular;
        let weight = if scene.spectral() { lanes_weight(beta, terminated) } else { luminance(beta) };
        if !camera_roulette(&mut beta, weight, sampler) {
            break;
        }
        ray = si.spawn_ray(Vector3(s.wi));
        medium = scene.medium_after(&hit, si.n.0, s.wi, medium);
        depth += 1;
    }
    (ld, None)
}

/// pbrt-v3's Russian roulette on a camera path, below a weight (luminance) of 0.25:
/// whether it goes on, its weight raised if so; a black path ends.
// DEVIATION(pbrt): noise only. pbrt-v4 roulettes below a largest component of one
// (after undoing refraction's scaling), at least one path in twenty at every bounce:
// on `v4-bilinear` and `v4-rough-glass` that raised the worst tile at the tests'
// budgets from 0.9% to 4.1% and from 2.1% to 4.9%. pbrt-v3's rule serves both.
fn camera_roulette(beta: &mut Rgb, weight: f32, sampler: &mut impl Sampler) -> bool {
    if weight < 0.25 {
        let q = (1.0 - weight).max(0.0);
        if sampler.get1d() < q {
            return false;
        }
        *beta /= 1.0 - q;
    }
    *beta != Vec3::ZERO
}

/// What a spectral weight stands for in roulette: the mean of its wavelengths' values,
/// or, once a path has ended its other wavelengths, its first one's own value (the
/// lane holds it times their count). An RGB luminance of wavelengths means nothing:
/// it took 0.21 of an ended path's first lane, so paths through a prism were cut four
/// times in five and the rest came out as coloured fireflies.
fn lanes_weight(beta: Rgb, terminated: bool) -> f32 {
    if terminated { beta.x * crate::spectrum::transport::ONCE } else { beta.element_sum() / 3.0 }
}

/// A camera path's segment in medium `m` up to `hit`: the light it adds there (the
/// medium's emission, the direct light where it scatters) and, gathering at points,
/// the visible point where it stops; along `beams`, the segment is one more beam.
fn in_medium(
    scene: &RenderScene,
    ray: &crate::math::Ray,
    (hit, m): (Option<&crate::accel::Hit>, u32),
    beta: &mut Rgb,
    beams: Option<&mut Vec<Beam>>,
    sampler: &mut impl Sampler,
) -> (Rgb, Option<VisiblePoint>) {
    let t_max = hit.map_or(f32::INFINITY, |h| h.t);
    let lanes = scene.pass_spectrum();
    let emitted = *beta * scene.media[m as usize].emission(ray.o.0, ray.d.0, t_max, sampler, lanes.as_ref());
    match beams {
        Some(list) => (emitted + beam_on_camera_path(scene, ray, (hit, m), beta, list, sampler), None),
        None => match scatter_on_camera_path(scene, ray, (hit, m), beta, sampler) {
            Some((direct, vp)) => (emitted + direct, Some(vp)),
            None => (emitted, None),
        },
    }
}

/// A camera path's flight through medium `m` up to `hit`: β takes the flight's weight;
/// where the path scatters, the direct light there and the medium visible point.
// DEVIATION(pbrt): pbrt's SPPM ignores media; here a camera path that scatters in one
// makes its visible point there (see `volume`).
fn scatter_on_camera_path(
    scene: &RenderScene,
    ray: &crate::math::Ray,
    (hit, m): (Option<&crate::accel::Hit>, u32),
    beta: &mut Rgb,
    sampler: &mut impl Sampler,
) -> Option<(Rgb, VisiblePoint)> {
    match volume::fly(scene, ray, hit, m, sampler) {
        Ok(weight) => {
            *beta *= weight;
            None
        }
        Err((mp, weight)) => {
            *beta *= weight * mp.sigma_s;
            let direct = *beta * volume::direct_light(scene, &mp, sampler);
            let vp = VisiblePoint {
                p: mp.p,
                wo: mp.wo,
                ng: Vec3::ZERO,
                at: Scatterer::Medium(mp.phase),
                beta: *beta,
                terminated: false,
            };
            Some((direct, vp))
        }
    }
}

/// A camera path's segment in medium `m` up to `hit`, with beams: the segment becomes a
/// beam, the direct light is taken at one point drawn by free flight (the photons
/// leave it out, as on surfaces), and β takes the transmittance over the segment, as
/// the path goes on to the surface behind. Returns the direct light.
// DEVIATION(pbrt): pbrt's SPPM ignores media (see `beams`).
fn beam_on_camera_path(
    scene: &RenderScene,
    ray: &crate::math::Ray,
    (hit, m): (Option<&crate::accel::Hit>, u32),
    beta: &mut Rgb,
    beams: &mut Vec<Beam>,
    sampler: &mut impl Sampler,
) -> Rgb {
    let direct = match volume::fly(scene, ray, hit, m, sampler) {
        Err((mp, weight)) => *beta * weight * mp.sigma_s * volume::direct_light(scene, &mp, sampler),
        Ok(_) => Vec3::ZERO,
    };
    let (beam, tr) = Beam::along(scene, ray, (m, hit.map_or(f32::INFINITY, |h| h.t)), *beta, sampler);
    beams.push(beam);
    *beta *= tr;
    direct
}

/// The surface a path is at and the medium it arrived in: which medium a ray leaving
/// it enters.
#[derive(Clone, Copy)]
struct Here<'a> {
    hit: &'a crate::accel::Hit,
    medium: Option<u32>,
}

impl Here<'_> {
    fn medium_toward(&self, scene: &RenderScene, si: &crate::interaction::SurfaceInteraction, d: Vec3) -> Option<u32> {
        scene.medium_after(self.hit, si.n.0, d, self.medium)
    }
}

/// Direct light from one light (chosen uniformly as pbrt-v3's `UniformSampleOneLight`,
/// by power in scenes with media: `RenderScene::direct_light_choice`), MIS of light
/// and BSDF sampling. `specular_too`: a specular BSDF sample counts
/// too, alone (light sampling cannot find it), where the path ends here.
fn direct_light(
    scene: &RenderScene,
    si: &crate::interaction::SurfaceInteraction,
    bsdf: &Bsdf,
    wo: Vec3,
    sampler: &mut impl Sampler,
    specular_too: bool,
    here: Here,
) -> Rgb {
    if scene.lights.is_empty() {
        return Vec3::ZERO;
    }
    let (mut u_light, u_bsdf, u_lobe) = (sampler.get2d(), sampler.get2d(), sampler.get1d());
    let Some(pick) = scene.direct_light_choice(u_light[0], Some((si.p.0, si.n.0))) else {
        return Vec3::ZERO;
    };
    // DEVIATION(pbrt): noise only. pbrt-v3 picks the light with a number of its own;
    // under a padded sampler that leaves each light a random subset of the light
    // samples. The pick's rest keeps them stratified (docs/sampling.md).
    u_light[0] = pick.rest;
    let (idx, weight) = (pick.index, 1.0 / pick.pmf);
    let light = &scene.lights[idx];
    // At glass and mirrors the estimate is 0 (pbrt computes it, and finds so): the
    // numbers above are drawn all the same, so the path's sequence goes on unchanged.
    if bsdf.only_specular() && !specular_too {
        return Vec3::ZERO;
    }
    let ns = bsdf.shading_normal();
    let mut ld = Vec3::ZERO;
    let v4 = scene.syntax == crate::parser::Syntax::V4;
    let from = crate::interaction::light_sample_point(v4, si.p, si.p_error, si.n, bsdf.sides(), wo);
    if let Some(ls) = light.sample_li(&scene.geometry.shapes, from.0, u_light)
        && !scene.emission_masked(light, ls.surface.as_ref())
    {
        let f = bsdf.f(wo, ls.wi) * ls.wi.dot(ns).abs();
        let tr =
            if f != Vec3::ZERO && ls.li != Vec3::ZERO { shadow(scene, si, &ls, here, sampler) } else { Vec3::ZERO };
        if tr != Vec3::ZERO {
            let w = if ls.delta { 1.0 } else { power_heuristic(ls.pdf, bsdf.pdf(wo, ls.wi)) };
            ld += tr * f * scene.emission_of(idx, ls.li) * w / ls.pdf;
        }
    }
    let mut specular = Vec3::ZERO;
    if (specular_too || !light.is_delta())
        && let Some(s) = bsdf.sample_f(wo, u_bsdf, u_lobe, TransportMode::Radiance)
    {
        if !s.specular && !light.is_delta() {
            ld += bsdf_strategy(scene, si, (bsdf, wo, &s), (light, idx), here, sampler);
        } else if s.specular && specular_too {
            // Light sampling cannot find this direction: whatever emits along it counts
            // in full, once (not through the light chosen above).
            specular = s.f * s.wi.dot(ns).abs() * emitted_along(scene, si, s.wi, here, sampler) / s.pdf;
        }
    }
    ld * weight + specular
}

/// The BSDF-sampled half of [`direct_light`] for the chosen light, MIS-weighted.
fn bsdf_strategy(
    scene: &RenderScene,
    si: &crate::interaction::SurfaceInteraction,
    (bsdf, wo, s): (&Bsdf, Vec3, &crate::materials::BsdfSample),
    (light, idx): (&Light, usize),
    here: Here,
    sampler: &mut impl Sampler,
) -> Rgb {
    // Trace first: the sample only counts where it reaches this light, and only then
    // is the light's density needed (measured from the offset origin, so the surface
    // just left is never taken for the light).
    let ray = si.spawn_ray(Vector3(s.wi));
    // In vacuum only the light's own hit counts, so the trace is cut short: a ray
    // that misses an area light's box is not traced (where a few lights are small,
    // that is most of these rays), and for a light without a surface (the sky),
    // which counts only where the ray escapes, any hit will do. (Through media the
    // trace draws numbers, which the path after it must find in their places.)
    let li = if !scene.media.is_empty() {
        let (hit, tr) = trace_lit(scene, &ray, || here.medium_toward(scene, si, s.wi), sampler);
        tr * scene.chosen_light_along(hit.as_ref(), idx, &ray)
    } else if !matches!(light, Light::Area(_)) {
        match scene.hits_anything(&ray) {
            true => Vec3::ZERO,
            false => scene.chosen_light_along(None, idx, &ray),
        }
    } else if scene.may_reach_light(idx, &ray) {
        scene.chosen_light_along(scene.intersect(&ray).as_ref(), idx, &ray)
    } else {
        Vec3::ZERO
    };
    if li == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let light_pdf = light.pdf_li(&scene.geometry.shapes, ray.o.0, s.wi);
    if light_pdf <= 0.0 {
        return Vec3::ZERO;
    }
    let bsdf_pdf = if s.proportional { bsdf.pdf(wo, s.wi) } else { s.pdf };
    s.f * s.wi.dot(bsdf.shading_normal()).abs() * li * power_heuristic(bsdf_pdf, light_pdf) / s.pdf
}

/// What every light sends back along the ray from `si` in direction `wi`: the area
/// light it hits, or the infinite lights where it escapes.
fn emitted_along(
    scene: &RenderScene,
    si: &crate::interaction::SurfaceInteraction,
    wi: Vec3,
    here: Here,
    sampler: &mut impl Sampler,
) -> Rgb {
    let ray = si.spawn_ray(Vector3(wi));
    let (hit, tr) = trace_lit(scene, &ray, || here.medium_toward(scene, si, wi), sampler);
    tr * match hit {
        Some(hit) => scene.emitted(&hit, &scene.geometry.interaction(&hit), -wi),
        None => scene.lights.iter().enumerate().map(|(k, l)| scene.emission_of(k, l.le_escaped(ray.o.0, wi))).sum(),
    }
}

/// The first hit along a ray toward a light and the transmittance to it: in a scene
/// with media, past interface surfaces and through the media (`medium` says where the
/// ray starts); otherwise the plain first hit, as pbrt.
fn trace_lit(
    scene: &RenderScene,
    ray: &crate::math::Ray,
    medium: impl FnOnce() -> Option<u32>,
    sampler: &mut impl Sampler,
) -> (Option<crate::accel::Hit>, Rgb) {
    if scene.media.is_empty() {
        (scene.intersect(ray), Vec3::ONE)
    } else {
        volume::trace(scene, ray, medium(), sampler)
    }
}

/// How much of a light sample arrives: 0 or 1 in vacuum (an interface blocks it, as
/// in pbrt's SPPM), the transmittance through media and interfaces otherwise.
fn shadow(
    scene: &RenderScene,
    si: &crate::interaction::SurfaceInteraction,
    ls: &crate::lights::LightSample,
    here: Here,
    sampler: &mut impl Sampler,
) -> Rgb {
    let ray = match ls.p_light {
        Some(p) => si.spawn_ray_to(Point3(p)),
        None => si.spawn_ray(Vector3(ls.wi)),
    };
    if scene.media.is_empty() {
        return if scene.intersect_p(&ray) { Vec3::ZERO } else { Vec3::ONE };
    }
    volume::transmittance(scene, &ray, here.medium_toward(scene, si, ls.wi), sampler)
}

/// What tracing a photon path found.
#[derive(Clone, Copy, Debug, Default)]
pub struct PhotonPath {
    /// Surfaces hit.
    pub hits: u64,
    /// Whether the path met a grid cell holding a visible point: under overlap
    /// binning, which adaptive chains use, the cell it landed in (a superset of the
    /// paths that deposit: what adaptive photon tracing calls visible).
    pub near: bool,
}

/// One photon path; appends (pixel, β·f) for each visible point it reaches.
/// Without a grid (no surface visible point, with beams) nothing lands on surfaces;
/// with `volume` (beams) photons that scatter in media are kept there instead of
/// deposited on medium visible points.
fn trace_photon(
    scene: &RenderScene,
    (grid, pixels): (Option<&Grid>, &[Pixel]),
    sampler: &mut impl Sampler,
    max_depth: u32,
    (out, mut volume): (&mut Vec<(u32, Vec3)>, Option<&mut Vec<VolumePhoton>>),
    time: Option<f32>,
) -> PhotonPath {
    let Some(Photon { mut beta, mut ray, mut medium, from_medium }) = emit_photon(scene, sampler, time) else {
        return PhotonPath::default();
    };
    let (mut depth, mut passes, mut hits, mut near, mut terminated) = (0, 0, 0, false, false);
    // Light from lights is the camera side's where it arrives directly; light from
    // media is not (nothing samples media toward a visible point), so it deposits at once.
    let first_deposit = if from_medium { 0 } else { 1 };
    let skip_behind = scene.fixes.has(Fix::PhotonsBehind);
    while depth < max_depth {
        let hit = scene.intersect(&ray);
        if let Some(m) = medium {
            match volume::fly(scene, &ray, hit.as_ref(), m, sampler) {
                Ok(weight) => beta *= weight,
                Err((mp, weight)) => {
                    // Direct light in media is the camera side's, as on surfaces.
                    if depth >= first_deposit {
                        let flux = beta * weight;
                        near |= match (volume.as_deref_mut(), grid) {
                            (Some(v), _) => {
                                v.push(VolumePhoton { p: mp.p, wo: mp.wo, flux: flux * mp.sigma_s });
                                true
                            }
                            (None, Some(grid)) => deposit_in_medium(grid, pixels, &mp, flux, out),
                            (None, None) => false,
                        };
                    }
                    let Some(next) = scatter_in_medium(&mp, beta * weight, beta, sampler) else { break };
                    (beta, ray) = next;
                    depth += 1;
                    continue;
                }
            }
        }
        let Some(hit) = hit else { break };
        hits += 1;
        let si = scene.geometry.interaction(&hit);
        let wi = -ray.d.0;
        let at = surface(scene, (&hit, &si), &Footprint::default(), &mut ray, &mut passes, &mut medium);
        // DEVIATION(pbrt): appearance, in scenes with media only (which pbrt's SPPM does
        // not render). pbrt gathers photons where they cross an interface as well as
        // where they land, counting them twice near a medium's boundary (13% too bright
        // on a floor just under a fog box, against pbrt's volpath); with media we gather
        // at scattering surfaces only. Scenes without media keep pbrt's rule.
        if let Some(grid) = grid
            && depth >= first_deposit
            && (scene.media.is_empty() || matches!(at, Surface::Bsdf(_)))
        {
            let photon = PhotonHere { p: si.p.0, wi, beta, terminated };
            near |= deposit_on_surface(grid, pixels, photon, skip_behind, out);
        }
        let bsdf = match at {
            Surface::Bsdf(b) => b,
            Surface::PassedThrough => continue,
            Surface::Abandon => break,
        };
        scene.terminate_if_dispersed(&hit, &mut beta, &mut terminated);
        let Some(s) = bsdf.sample_f(wi, sampler.get2d(), sampler.get1d(), TransportMode::Importance) else { break };
        let bnew = beta * s.f * s.wi.dot(bsdf.shading_normal()).abs() / s.pdf;
        let q = (1.0 - luminance(bnew) / luminance(beta).max(1e-30)).max(0.0);
        if sampler.get1d() < q {
            break;
        }
        beta = bnew / (1.0 - q);
        if !beta.is_finite() || beta == Vec3::ZERO {
            break;
        }
        ray = si.spawn_ray(Vector3(s.wi));
        medium = scene.medium_after(&hit, si.n.0, s.wi, medium);
        depth += 1;
    }
    PhotonPath { hits, near }
}

/// A photon as it starts.
struct Photon {
    beta: Rgb,
    ray: crate::math::Ray,
    medium: Option<u32>,
    /// Whether an emitting medium sent it.
    from_medium: bool,
}

/// A photon leaving a light or an emitting medium chosen by power.
fn emit_photon(scene: &RenderScene, sampler: &mut impl Sampler, time: Option<f32>) -> Option<Photon> {
    let (li, pick) = scene.photon_sources.sample(sampler.get1d())?;
    // The pass's time (see `RenderScene::pass_time`), or one of the photon's own.
    let time = time.unwrap_or_else(|| scene.camera.time(sampler.get1d()));
    if li >= scene.lights.len() {
        let p = emit_from_medium(scene, li - scene.lights.len(), pick, sampler)?;
        return Some(Photon { ray: p.ray.at_time(time), ..p });
    }
    let light: &Light = &scene.lights[li];
    let (u1, u2) = (sampler.get2d(), sampler.get2d());
    let e = match light {
        // DEVIATION(pbrt): appearance, `--fix portal-photons`: through the portal only.
        Light::Infinite(sky) if scene.fixes.has(Fix::PortalPhotons) => {
            sky.sample_le_through_portal(scene.world, u1, u2)?
        }
        _ => light.sample_le(&scene.geometry.shapes, scene.world, u1, u2)?,
    };
    if scene.emission_masked(light, e.surface.as_ref()) || e.pdf_pos <= 0.0 || e.pdf_dir <= 0.0 || e.le == Vec3::ZERO {
        return None;
    }
    let d = e.ray.d.0.normalize();
    // DEVIATION(pbrt): robustness. The photon's power is formed in f64 and carried divided by a
    // power of two near the lights' total power. pbrt's f32 β overflows for emitters
    // past about 1e37 and silently drops those photons.
    let pdf = pick as f64 * e.pdf_pos as f64 * e.pdf_dir as f64;
    let beta =
        (scene.emission_of(li, e.le).as_dvec3() * (e.n.dot(d).abs() as f64 / pdf / scene.photon_scale)).as_vec3();
    let medium = if scene.media.is_empty() { None } else { scene.light_medium(li, d, e.n) };
    Some(Photon { beta, ray: crate::math::Ray::new(e.ray.o, Vector3(d)).at_time(time), medium, from_medium: false })
}

/// A photon from emitting medium `k` of `scene.medium_emitters` (picked with
/// probability `pick`): a point drawn in it, a uniform direction, σa·Le over the
/// densities. A point where another medium is (outside the medium's region) sends none.
// DEVIATION(pbrt): pbrt's SPPM ignores media; their emission here is a photon source.
fn emit_from_medium(scene: &RenderScene, k: usize, pick: f32, sampler: &mut impl Sampler) -> Option<Photon> {
    let (m, points) = &scene.medium_emitters[k];
    let (u_voxel, u_pos, u_dir) = (sampler.get1d(), sampler.get2d(), sampler.get2d());
    let at = points.sample(u_voxel, Vec3::new(u_pos[0], u_pos[1], sampler.get1d()))?;
    let le = scene.media[*m as usize].emitted_at(at.p, scene.pass_spectrum().as_ref());
    if le == Vec3::ZERO || scene.medium_at(at.p) != Some(*m) {
        return None;
    }
    let pdf = pick as f64 * at.pdf / (4.0 * std::f64::consts::PI);
    let beta = (le.as_dvec3() / pdf / scene.photon_scale).as_vec3();
    let ray = crate::math::Ray::new(Point3(at.p), Vector3(crate::sampling::uniform_sphere(u_dir)));
    Some(Photon { beta, ray, medium: Some(*m), from_medium: true })
}

/// Deposits a photon that arrived at surface point `p` from direction `wi` with weight
/// A photon where it lands: arriving along `wi` with weight `beta`; `terminated`: it
/// kept only its first wavelength.
struct PhotonHere {
    p: Vec3,
    wi: Vec3,
    beta: Rgb,
    terminated: bool,
}

/// `beta` on the surface visible points whose ball holds it.
fn deposit_on_surface(
    grid: &Grid,
    pixels: &[Pixel],
    photon: PhotonHere,
    skip_behind: bool,
    out: &mut Vec<Deposit>,
) -> bool {
    let PhotonHere { p, wi, beta, terminated } = photon;
    // The grid's sites are the visible points and radii (`Sppm::sites`).
    grid.gather_within_prefetched(
        p,
        |pixel| prefetch(&pixels[pixel as usize]),
        |pixel| {
            let Some(vp) = &pixels[pixel as usize].vp else { return };
            let Scatterer::Surface(bsdf) = &vp.at else { return };
            // DEVIATION(pbrt): appearance, `--fix photons-behind`. pbrt counts photons
            // that reach an opaque visible point from behind its surface in M (f is
            // 0 there, or nearly), which only shrinks the radius (Mitsuba #145); the
            // fix leaves them out. Transmitting surfaces count them either way.
            let behind = wi.dot(vp.ng) * vp.wo.dot(vp.ng) <= 0.0;
            if behind && skip_behind && !bsdf.transmits() {
                return;
            }
            // Both sides grew their first lane for ending the others: pbrt-v4 ends a
            // wavelength set once.
            let once = if terminated && vp.terminated { transport::ONCE } else { 1.0 };
            out.push((pixel, beta * bsdf.f(vp.wo, wi) * once));
        },
    )
}

/// Deposits a photon that scattered at `mp` (its weight `beta` there, before σs) on the
/// medium visible points whose ball holds it. Each deposit is scaled by 3/(4r): the
/// pixel divides its sum by πr², so a volume estimate comes out over (4/3)πr³, and
/// shrinking r keeps it consistent (the flux in a ball scales with r³, 3/(4r) with
/// 1/r: their product with r², as the pixel's update assumes).
fn deposit_in_medium(grid: &Grid, pixels: &[Pixel], mp: &MediumPoint, beta: Rgb, out: &mut Vec<Deposit>) -> bool {
    grid.gather_within(mp.p, |pixel| {
        let px = &pixels[pixel as usize];
        let Some(vp) = &px.vp else { return };
        let Scatterer::Medium(phase) = &vp.at else { return };
        out.push((pixel, beta * phase.p(vp.wo, mp.wo) * (0.75 / px.radius as f32)));
    })
}

/// The photon's next ray after scattering at `mp` (phase sampling, whose weight is 1),
/// its weight σs·`weight`, with Russian roulette against the weight it had (`before`).
fn scatter_in_medium(
    mp: &MediumPoint,
    weight: Rgb,
    before: Rgb,
    sampler: &mut impl Sampler,
) -> Option<(Rgb, crate::math::Ray)> {
    let bnew = weight * mp.sigma_s;
    let s = mp.phase.sample(mp.wo, sampler.get2d());
    let q = (1.0 - luminance(bnew) / luminance(before).max(1e-30)).max(0.0);
    if sampler.get1d() < q {
        return None;
    }
    let beta = bnew / (1.0 - q);
    if !beta.is_finite() || beta == Vec3::ZERO {
        return None;
    }
    Some((beta, crate::math::Ray::new(Point3(mp.p), Vector3(s.wi)).at_time(mp.time)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deposit_runs_cover_a_band_in_order_and_follow_the_deposits() {
        // Deposits per chunk: few, then a wide radius's flood, then few again.
        let per_chunk = |c: usize| if (1000..2000).contains(&c) { 1 << 20 } else { 10 };
        let (mut runs, mut cut) = (DepositRuns::default(), Vec::<Range<usize>>::new());
        for band in preview::bands(4096, 8, DEPOSIT_BAND, false) {
            let mut rest = band;
            while !rest.is_empty() {
                let run = runs.next(&rest);
                rest.start = run.end;
                runs.saw(run.len(), run.clone().map(per_chunk).sum());
                cut.push(run);
            }
        }
        assert_eq!(cut[0].len(), 2 * rayon::current_num_threads(), "a short first run: {cut:?}");
        assert!(cut[0].start == 0 && cut.last().map(|r| r.end) == Some(4096), "{cut:?}");
        assert!(cut.windows(2).all(|w| w[0].end == w[1].start && w[1].len() <= 8 * w[0].len().max(32)), "{cut:?}");
        // The run that meets the flood measures a mix; from the one after it, runs hold
        // DEPOSITS_HELD (4 chunks of flood, fewer at a band's end); after the flood they
        // grow back.
        let first_flooded = cut.iter().position(|r| r.end > 1000).unwrap_or(0);
        let inside = cut[first_flooded + 2..].iter().filter(|r| r.end <= 2000);
        assert!(inside.clone().count() > 200 && inside.clone().all(|r| r.len() <= 4), "{cut:?}");
        assert!(cut.iter().any(|r| r.start >= 2000 && r.len() > 4), "{cut:?}");
        // A run is never empty, whatever the deposits.
        runs.saw(1, usize::MAX);
        assert_eq!(runs.next(&(5..9)), 5..6);
        assert!(runs.next(&(9..9)).is_empty());
    }
}
