//! The progressive renderers the render loop drives, behind one interface: SPPM, or
//! vertex connection and merging (and bidirectional path tracing, its part without
//! merging). Both add one pass per iteration and save the same checkpoint state.

use super::adaptive::Chain;
use super::error::RenderError;
use super::plan::{Algorithm, Plan};
use super::preview::Preview;
use super::sppm::{PixelState, Sppm, Stats};
use super::vcm::{Vcm, VcmSettings};
use crate::render::RenderScene;
use glam::DVec3;

/// A render's progressive state.
pub enum Engine<'a> {
    Sppm(Box<Sppm<'a>>),
    Vcm(Box<Vcm<'a>>),
}

impl<'a> Engine<'a> {
    pub fn new(scene: &'a RenderScene, p: &Plan) -> Result<Engine<'a>, RenderError> {
        Ok(match p.algorithm {
            Algorithm::Sppm => Engine::Sppm(Box::new(
                Sppm::new(scene, p.iterations, p.photons, p.radius, p.seed, (p.sampler, p.photon_sampling))?
                    .with_passes(p.passes, p.range.start)?
                    .with_volume_gather(p.volume_gather),
            )),
            Algorithm::Vcm(techniques) => {
                let settings = VcmSettings {
                    light_paths: p.photons,
                    radius: p.radius as f64,
                    alpha: p.alpha(),
                    seed: p.seed,
                    sampler: p.sampler,
                    techniques,
                    balance: p.balances(),
                    prefix_rays: true,
                    emission: p.emission,
                    guiding: p.guiding,
                    connections: p.connections,
                };
                Engine::Vcm(Box::new(Vcm::new(scene, p.iterations, p.range.start, settings)?))
            }
        })
    }

    /// Photons (light subpaths) the last iteration traced: the plan's, unless vcm
    /// chose its own ([`super::vcm::balance`]).
    pub fn photons(&self, planned: u64) -> u64 {
        match self {
            Engine::Sppm(_) => planned,
            Engine::Vcm(v) => v.light_paths(v.iteration.saturating_sub(1)),
        }
    }

    /// Camera paths per iteration: the rendered window's pixels.
    pub fn pixel_count(&self) -> usize {
        match self {
            Engine::Sppm(s) => s.pixels.len(),
            Engine::Vcm(v) => v.pixel_count(),
        }
    }

    /// The rendered window's width and height.
    pub fn size(&self) -> (usize, usize) {
        let [x0, x1, y0, y1] = self.scene().film.pixel_bounds;
        ((x1 - x0) as usize, (y1 - y0) as usize)
    }

    /// The counts of the iteration under way.
    pub fn live(&self) -> std::sync::Arc<super::report::Live> {
        match self {
            Engine::Sppm(s) => s.live.clone(),
            Engine::Vcm(v) => v.live.clone(),
        }
    }

    /// One iteration; with a `preview`, provisional images part way through it.
    pub fn iterate(&mut self, preview: Option<&mut Preview>) {
        match self {
            Engine::Sppm(s) => s.iterate_showing(preview),
            Engine::Vcm(v) => v.iterate_showing(preview),
        }
    }

    /// Passes done, counting those before the first of this run.
    pub fn iteration(&self) -> u32 {
        match self {
            Engine::Sppm(s) => s.iteration,
            Engine::Vcm(v) => v.iteration,
        }
    }

    pub fn passes_done(&self) -> u32 {
        match self {
            Engine::Sppm(s) => s.passes_done(),
            Engine::Vcm(v) => v.passes_done(),
        }
    }

    pub fn first_pass(&self) -> u32 {
        match self {
            Engine::Sppm(s) => s.first_pass(),
            Engine::Vcm(v) => v.first_pass(),
        }
    }

    pub fn scene(&self) -> &'a RenderScene {
        match self {
            Engine::Sppm(s) => s.scene,
            Engine::Vcm(v) => v.scene,
        }
    }

    pub fn stats(&self) -> &Stats {
        match self {
            Engine::Sppm(s) => &s.stats,
            Engine::Vcm(v) => &v.stats,
        }
    }

    pub fn image(&self) -> Vec<[f32; 3]> {
        match self {
            Engine::Sppm(s) => s.image(),
            Engine::Vcm(v) => v.image(),
        }
    }

    /// A spectral film's buckets after the passes so far (vcm and bdpt; pbrt-v4's
    /// SPPM writes R, G, B only).
    pub fn bands(&self) -> Option<crate::imageio::Bands> {
        self.bucket_totals().map(|t| t.bands(self.first_pass()..self.iteration()))
    }

    /// The sum of the passes' estimates (independent passes and every VCM render).
    pub fn pass_sums(&self) -> Vec<DVec3> {
        match self {
            Engine::Sppm(s) => s.pass_sums(),
            Engine::Vcm(v) => v.pass_sums(),
        }
    }

    pub fn save(&self) -> (Vec<PixelState>, Option<Vec<Chain>>) {
        match self {
            Engine::Sppm(s) => s.save(),
            Engine::Vcm(v) => (v.save(), None),
        }
    }

    /// A spectral film's bucket sums, as a checkpoint saves them.
    pub fn save_buckets(&self) -> Vec<f64> {
        self.bucket_totals().map_or_else(Vec::new, |t| t.sums)
    }

    /// A spectral film's bucket sums and layout (vcm and bdpt).
    pub fn bucket_totals(&self) -> Option<super::buckets::BucketTotals> {
        match self {
            Engine::Sppm(_) => None,
            Engine::Vcm(v) => v.bucket_totals(),
        }
    }

    /// What vcm's passes so far decided (a checkpoint saves it).
    pub fn decided(&self) -> super::vcm::Decided {
        match self {
            Engine::Sppm(_) => Default::default(),
            Engine::Vcm(v) => v.decided(),
        }
    }

    /// What a checkpoint saved of the passes' decisions (after [`Self::restore`]).
    pub fn restore_decided(&mut self, saved: super::vcm::Decided) {
        if let Engine::Vcm(v) = self {
            v.restore_decided(saved);
        }
    }

    pub fn restore_buckets(&mut self, saved: &[f64]) -> Result<(), RenderError> {
        match self {
            Engine::Sppm(_) if saved.is_empty() => Ok(()),
            Engine::Sppm(_) => Err(RenderError::CheckpointBuckets { saved: saved.len(), film: 0 }),
            Engine::Vcm(v) => v.restore_buckets(saved),
        }
    }

    pub fn restore(
        &mut self,
        iteration: u32,
        pixels: &[PixelState],
        chains: Option<Vec<Chain>>,
        stats: Stats,
    ) -> Result<(), RenderError> {
        match self {
            Engine::Sppm(s) => s.restore(iteration, pixels, chains, stats),
            Engine::Vcm(_) if chains.is_some() => Err(RenderError::CheckpointSampling),
            Engine::Vcm(v) => v.restore(iteration, pixels, stats),
        }
    }
}
