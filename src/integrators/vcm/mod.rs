//! Vertex connection and merging (Georgiev et al. 2012; Hachisuka et al. 2012), and
//! bidirectional path tracing as the same code with merging left out.
//!
//! ```text
//! pbrt-sppm render scene.pbrt --integrator vcm [--alpha 0.6667] [--radius R]
//! pbrt-sppm render scene.pbrt --integrator bdpt
//! Integrator "bdpt" "integer maxdepth" 5      # rendered with bdpt
//! Integrator "path"                           # rendered with vcm
//! ```
//! Each iteration (one pass) traces `photons` light subpaths ([`light`]), keeps their
//! non-specular vertices in the photon grid, then one camera subpath per pixel
//! ([`camera`]). Every technique counts, weighted by the power heuristic over all of
//! them ([`mis`]): camera paths finding emitters, next-event estimation, connections
//! of a camera vertex with the vertices of one light subpath, light vertices seen
//! through the lens (light tracing) and merging light vertices within the pass's
//! radius. The radius of pass i is that of independent SPPM passes
//! ([`super::passes::radius`]), so passes stand alone: any range of them can be
//! rendered apart and merged, and the image is their mean.
//!
//! Determinism: seeds derive from (seed, pixel, pass) and (seed, pass, light path);
//! light vertices keep their subpaths' order; splats are summed per pixel in light-path
//! order; so the thread count never changes the image.

pub mod aim;
pub mod balance;
pub mod camera;
pub use camera::PREFIX_RAYS;
pub mod emission_map;
pub mod light;
pub mod links;
pub mod mis;
pub mod vertex;

use super::buckets::{BucketSums, PassLanes};
use super::error::RenderError;
use super::grid::{Binning, Grid, Grouped, Site};
use super::passes;
use super::sppm::{PixelState, Stats};
use crate::filters::PixelFilter;
use crate::guiding::{Guide, Guided, Guiding, Mix, Records, STree};
use crate::render::RenderScene;
use crate::sampling::SamplerKind;
use crate::scene::Film;
use crate::spectrum::Rgb;
use glam::DVec3;
use mis::PassFactors;
use rayon::prelude::*;
use std::time::Instant;

/// Next-event estimation samples every light when there are at most this many, and
/// one chosen by power when there are more. Choosing one adds the choice's noise to
/// every estimate: on `sppm-bench` (a point light and a disk) sampling both left an
/// eighth of the error at equal passes for a fifth more time a pass, and four other
/// scenes of the suite (two lights each, counting a quad's two triangles) 0.74–0.95 of
/// the error × time (`docs/vcm.md`, "Every light, when there are few"). Past a few
/// lights the shadow rays cost more than the choice: a mesh emitter has a light per
/// triangle.
pub const NEE_ALL_LIGHTS_MAX: usize = 8;

/// What a band of camera subpaths gives besides the image: work, guide records,
/// connections for the table of cached connections.
type Out = (camera::Work, Records, Vec<links::Sample>);

/// Two neighbouring bands' [`Out`]: work sums in any order; records and connections
/// join in pixel order (the guide's and the table's sums then do not depend on the
/// thread count).
fn join((wa, mut ra, mut la): Out, (wb, rb, mut lb): Out) -> Out {
    ra.append(rb);
    la.append(&mut lb);
    (wa + wb, ra, la)
}

/// Whether a vertex may be guided: on a surface whose BSDF can be
/// ([`crate::materials::Bsdf::guidable`]).
fn guidable(at: &vertex::Scatterer) -> bool {
    matches!(at, vertex::Scatterer::Surface(b) if b.guidable())
}

/// Where a vertex stands in `tree`, if it is guided there: on a guidable surface, in a
/// leaf that has learnt something; folded toward `wo`'s side where the BSDF only
/// reflects.
fn guided_in(tree: &STree, p: glam::Vec3, wo: glam::Vec3, at: &vertex::Scatterer) -> Option<Guided> {
    let vertex::Scatterer::Surface(b) = at else { return None };
    if !b.guidable() {
        return None;
    }
    let leaf = tree.leaf(p);
    if tree.sampling_of(leaf).total() <= 0.0 {
        return None;
    }
    let fold = b.reflecting_normal().map(|n| if wo.dot(n) < 0.0 { -n } else { n });
    Some(Guided { leaf, fold })
}

/// The mixture of a vertex guided by `tree` ([`guided_in`]).
fn mix(tree: &STree, g: Guided) -> Mix<'_> {
    Mix { tree: tree.sampling_of(g.leaf), bsdf_share: crate::guiding::BSDF_SHARE, fold: g.fold }
}

/// Pixel ranges splats are grouped into for the parallel reduction.
const SPLAT_RANGES: usize = 64;

/// Pixels a band of a pass the table of cached connections learns from: its
/// connections (12 bytes each) are held until the band ends. 64 work items: a few
/// connections a pixel make a few megabytes.
const LEARNING_BAND: usize = 64 * crate::integrators::PIXELS_PER_TASK;

/// One of the ways a path is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Technique {
    /// A camera subpath finds an emitter (or escapes to a light at infinity).
    EmitterHit,
    /// Next-event estimation: a camera vertex connected to a point drawn on a light.
    Direct,
    /// A camera vertex connected to a light subpath's vertex.
    Connect,
    /// A light vertex connected to the lens.
    LightTrace,
    /// A light vertex merged at a camera vertex within the radius.
    Merge,
}

impl Technique {
    pub const ALL: [Technique; 5] =
        [Technique::EmitterHit, Technique::Direct, Technique::Connect, Technique::LightTrace, Technique::Merge];
}

/// Which techniques a render uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Techniques {
    /// Vertex connection and merging: all of them.
    All,
    /// Bidirectional path tracing: all but merging.
    Bdpt,
    /// One alone with weight 1, to check each converges to the same image. Connections
    /// and merging then keep one strategy each (see [`camera`]), so each path counts once.
    Only(Technique),
    /// pbrt-v3's `whitted` and `directlighting`: light straight from the lights (next-
    /// event estimation and emitters found by sampling the BSDF, weighted against each
    /// other) at every vertex of a camera path that goes on only through perfectly
    /// specular bounces, no light subpaths (`camera/direct.rs`).
    Direct,
}

impl Techniques {
    pub fn uses(self, t: Technique) -> bool {
        match self {
            Techniques::All => true,
            Techniques::Bdpt => t != Technique::Merge,
            Techniques::Only(o) => o == t,
            Techniques::Direct => matches!(t, Technique::EmitterHit | Technique::Direct),
        }
    }

    /// Whether light subpaths take part in the estimator at all (not in pbrt-v3's
    /// whitted and directlighting): its MIS constants and its guide count on them.
    pub fn bidirectional(self) -> bool {
        self != Techniques::Direct
    }

    /// Whether passes trace light subpaths: not where they take no part, nor for a
    /// technique of the camera subpaths alone (a camera subpath's own numbers never
    /// depend on them, so they were traced and thrown away).
    pub fn traces_lights(self) -> bool {
        self.bidirectional() && !matches!(self, Techniques::Only(Technique::EmitterHit | Technique::Direct))
    }

    /// The weight to apply: the MIS weight, or 1 for a technique alone.
    #[inline]
    pub fn weight(self, w: f64) -> f32 {
        match self {
            Techniques::Only(_) => 1.0,
            _ => w as f32,
        }
    }

    /// The pass's constants: merging counts only where it is used (a technique alone
    /// takes weight 1 and reads none).
    fn factors(self, radius: f64, light_paths: f64) -> PassFactors {
        PassFactors::new(radius, light_paths.max(1.0), self.bidirectional(), self.uses(Technique::Merge))
    }
}

/// What one pass shares between its light and camera subpaths.
pub struct Pass<'a> {
    pub scene: &'a RenderScene,
    pub factors: PassFactors,
    pub techniques: Techniques,
    /// The most edges a path may have (pbrt's `maxdepth` + 1).
    pub max_len: u32,
    /// Light subpaths in the pass.
    pub light_paths: u64,
    /// The full film's pixel count: a camera density per unit raster area is pbrt's
    /// per film area times this.
    pub film_pixels: f64,
    pub radius: f32,
    /// The rendered window: its first pixel and its width and height.
    pub origin: (u32, u32),
    pub size: (usize, usize),
    /// What drives the light subpaths (`--sampler`).
    pub sampler: crate::sampling::SamplerKind,
    /// The time of every ray of the pass (see [`RenderScene::pass_time`]).
    pub time: Option<f32>,
    /// Next-event estimation samples every light, not one chosen by power.
    pub nee_all: bool,
    /// Per light, the cone its subpaths are aimed in ([`aim`]).
    pub cones: std::sync::Arc<[Option<aim::Cone>]>,
    /// Per light, the map its subpaths' emissions are drawn from too ([`emission_map`]).
    pub maps: std::sync::Arc<[Option<emission_map::EmissionMap>]>,
    /// Light subpaths take the shading-normal correction on specular bounces too (as
    /// pbrt's bdpt; not for files asking for SPPM, whose photons cross them without it:
    /// [`light::LightVertex::leaving_cos`]).
    pub correct_specular: bool,
    /// The path guide camera subpaths draw from ([`crate::guiding`]), if any.
    pub guide: Option<std::sync::Arc<STree>>,
    /// The importance light subpaths draw from, if any.
    pub light_guide: Option<std::sync::Arc<STree>>,
    /// Camera subpaths record what they find for the guides' training.
    pub training: bool,
    /// Camera vertices draw the light vertices they connect to from the whole pass
    /// by this table ([`links`]), rather than take their pair's.
    pub links: Option<std::sync::Arc<links::Links>>,
    /// Camera subpaths record their connections for the table's learning, by these
    /// cells (a pilot pass's).
    pub link_cells: Option<std::sync::Arc<links::Cells>>,
}

impl Pass<'_> {
    /// The guided mixture camera subpaths sample from at a vertex, where there is one:
    /// on a surface whose BSDF can be guided ([`crate::materials::Bsdf::guidable`]),
    /// in a leaf of the guide that has learnt something. Light subpaths ask it too, for
    /// the density a camera subpath would have drawn their way back with.
    /// `wo`: the direction the camera subpath arrives from (the side a reflecting
    /// BSDF's guide folds to).
    pub fn guide_at(&self, p: glam::Vec3, wo: glam::Vec3, at: &vertex::Scatterer) -> Option<Mix<'_>> {
        let tree = self.guide.as_deref()?;
        guided_in(tree, p, wo, at).map(|g| mix(tree, g))
    }

    /// Where a light subpath's vertex stands in the importance guide, if it is guided
    /// there (as [`Self::guide_at`], `wo` the direction the light arrived from). Camera
    /// subpaths ask it too, for the density a light subpath would have drawn their way
    /// back with.
    pub fn light_guided(&self, p: glam::Vec3, wo: glam::Vec3, at: &vertex::Scatterer) -> Option<Guided> {
        guided_in(self.light_guide.as_deref()?, p, wo, at)
    }

    /// The mixture a light subpath draws from where [`Self::light_guided`] put it.
    pub fn light_mix(&self, g: Guided) -> Option<Mix<'_>> {
        self.light_guide.as_deref().map(|tree| mix(tree, g))
    }

    /// Whether a camera subpath records what it finds past a vertex for the guide.
    pub fn records_at(&self, at: &vertex::Scatterer) -> bool {
        self.training && self.guide.is_some() && guidable(at)
    }

    /// Whether a camera subpath records the importance arriving at a vertex `len` edges
    /// from the camera for the light subpaths' guide: the importance from the vertex
    /// before, which light leaving here that way would meet. Not at the first vertex,
    /// where it arrives from the lens: light tracing connects there, and a light
    /// subpath sent that way lands behind the camera.
    pub fn records_importance_at(&self, at: &vertex::Scatterer, len: u32) -> bool {
        self.training && self.light_guide.is_some() && len > 1 && guidable(at)
    }

    /// Next-event estimation's probability of choosing light `k`.
    pub fn nee_pick(&self, k: usize) -> f64 {
        match self.nee_all {
            true => 1.0,
            false => self.scene.light_power.pmf(k) as f64,
        }
    }

    /// How many samples light tracing counts as in the weights: one per light subpath.
    /// (Counting fewer, to favour the camera's low-discrepancy techniques, halved a
    /// diffuse scene's error but raised the caustic scenes' by half: left at 1.)
    pub fn lt_count(&self) -> f64 {
        self.light_paths as f64
    }

    /// The pixels of the window whose filtered rays reach `raster`, each with the
    /// density its rays are drawn there with (see [`crate::filters`]).
    pub fn footprint<'f>(&self, raster: [f32; 2], f: &'f PixelFilter) -> impl Iterator<Item = (u32, f32)> + 'f {
        let [rx, ry] = f.radius();
        let span = |c: f32, r: f32, lo: u32, n: usize| {
            let first = ((c - 0.5 - r).floor() as i64).max(lo as i64);
            let last = ((c - 0.5 + r).ceil() as i64).min(lo as i64 + n as i64 - 1);
            first..=last
        };
        let (xs, ys) =
            (span(raster[0], rx, self.origin.0, self.size.0), span(raster[1], ry, self.origin.1, self.size.1));
        let (origin, width) = (self.origin, self.size.0);
        ys.flat_map(move |y| xs.clone().map(move |x| (x, y)))
            .map(move |(x, y)| {
                let w = f.density([raster[0] - (x as f32 + 0.5), raster[1] - (y as f32 + 0.5)]);
                let i = (y - origin.1 as i64) as usize * width + (x - origin.0 as i64) as usize;
                (i as u32, w)
            })
            .filter(|&(_, w)| w > 0.0)
    }

    /// The index in the rendered window of the pixel holding a raster point, if any.
    pub fn pixel_index(&self, raster: [f32; 2]) -> Option<u32> {
        let (x, y) = (raster[0].floor(), raster[1].floor());
        let (x, y) = (x as i64 - self.origin.0 as i64, y as i64 - self.origin.1 as i64);
        let inside = (0..self.size.0 as i64).contains(&x) && (0..self.size.1 as i64).contains(&y);
        inside.then(|| (y as usize * self.size.0 + x as usize) as u32)
    }
}

/// The settings of a render with [`Vcm`].
#[derive(Clone, Copy, Debug)]
pub struct VcmSettings {
    pub light_paths: u64,
    /// The first pass's merging radius.
    pub radius: f64,
    /// How fast the radius shrinks (as independent SPPM passes').
    pub alpha: f64,
    pub seed: u64,
    pub sampler: SamplerKind,
    pub techniques: Techniques,
    /// Choose the light subpaths of the passes after the pilot ([`balance`]), starting
    /// from `light_paths`.
    pub balance: bool,
    /// Let the pixels that need it trace more rays for their prefix light
    /// (`camera/prefix.rs`).
    pub prefix_rays: bool,
    /// Which subpaths draw directions from a path guide too (`--guiding`,
    /// [`crate::guiding`]).
    pub guiding: Guiding,
    /// How light subpaths draw their start (`--emission`, [`emission_map`]).
    pub emission: emission_map::EmissionSampling,
    /// What camera vertices connect to (`--connections`, [`links`]).
    pub connections: links::Connections,
}

/// The choice of light subpaths per pass under way: the pilot's measurements while it
/// runs, then the count chosen.
enum Balance {
    Measuring(Box<balance::Pilot>),
    Chosen(u64),
    /// The pilot is to be rendered again before the first pass past it (a render that
    /// did not start at pass 0).
    Unknown,
}

/// The progressive state of a render: each pixel's sum over the passes so far.
pub struct Vcm<'a> {
    pub(super) scene: &'a RenderScene,
    sums: Vec<DVec3>,
    origin: (u32, u32),
    size: (usize, usize),
    pub iteration: u32,
    first: u32,
    settings: VcmSettings,
    /// Camera rays' differential scale (as SPPM's).
    differential_scale: f32,
    pub stats: Stats,
    /// The pass under way's counts, for progress.
    pub live: std::sync::Arc<super::report::Live>,
    balance: Option<Balance>,
    cones: std::sync::Arc<[Option<aim::Cone>]>,
    maps: std::sync::Arc<[Option<emission_map::EmissionMap>]>,
    /// The pixels that trace more rays for what they see through perfect specular
    /// chains (`camera/prefix.rs`), drawn once before the first pass.
    prefix: Option<Vec<bool>>,
    /// A spectral film's bucket sums.
    buckets: Option<BucketSums>,
    /// The path guide, trained over the first passes ([`crate::guiding::training`]).
    guide: Option<Guide>,
    /// The table cached connections draw by, learnt over the pilot ([`links`]).
    links: Option<links::State>,
}

/// What the passes so far decided that a resumed render would otherwise replay them
/// for (a checkpoint saves it).
#[derive(Clone, Debug, Default)]
pub struct Decided {
    /// The pilot's light subpaths per pass.
    pub light_paths: Option<u64>,
    /// The path guide.
    pub guide: Option<Guide>,
    /// `--connections auto`'s choice to keep the pairs. A table it draws by is not
    /// saved (up to 2 MB): the pilot is played again to learn it.
    pub pairs_kept: Option<links::Unblocking>,
}

/// What a pass did besides adding to the sums.
struct Done {
    counts: light::Counts,
    stored: usize,
    camera: camera::Work,
    /// The camera subpaths' records for the guide, in pixel order (a training pass's).
    records: Records,
    /// In a pass the table learns from, the table's sums with the pass's connections
    /// added, and where the stored light vertices stand.
    links: Option<(links::Tally, Vec<glam::Vec3>)>,
    times: [Instant; 5],
}

impl<'a> Vcm<'a> {
    /// Fails (rather than aborting) when the pixels do not fit in memory. `iterations`
    /// sets the camera rays' differential scale; `first` is the first pass rendered.
    pub fn new(
        scene: &'a RenderScene,
        iterations: u32,
        first: u32,
        settings: VcmSettings,
    ) -> Result<Vcm<'a>, RenderError> {
        let [x0, x1, y0, y1] = scene.film.pixel_bounds;
        let (w, h) = ((x1 - x0) as usize, (y1 - y0) as usize);
        let mut sums = Vec::new();
        sums.try_reserve_exact(w * h).map_err(|_| RenderError::OutOfMemory {
            width: w,
            height: h,
            bytes: (w * h).saturating_mul(std::mem::size_of::<DVec3>()),
        })?;
        sums.resize(w * h, DVec3::ZERO);
        let floor = scene.integrator.differential_floor;
        let balance = settings.balance.then(|| match first {
            0 => Balance::Measuring(Box::new(balance::Pilot::new(w * h))),
            _ => Balance::Unknown,
        });
        let mut vcm = Vcm {
            scene,
            sums,
            origin: (x0, y0),
            size: (w, h),
            iteration: first,
            first,
            settings,
            differential_scale: (1.0 / (iterations.max(1) as f32).sqrt()).max(floor),
            stats: Stats::default(),
            live: Default::default(),
            balance,
            cones: aim::cones(scene).into(),
            // Without light subpaths (`direct`, a camera technique alone) no density of
            // emission is read.
            maps: match [Technique::Connect, Technique::LightTrace, Technique::Merge]
                .into_iter()
                .any(|t| settings.techniques.uses(t))
            {
                true => emission_map::maps(scene, settings.seed, settings.emission).into(),
                false => vec![None; scene.lights.len()].into(),
            },
            prefix: None,
            buckets: bucket_sums(scene, w * h, (w, h))?,
            guide: guide(scene, &settings),
            links: match first {
                0 => learning(scene, &settings),
                _ => learning(scene, &settings).map(|_| links::State::Unknown),
            },
        };
        vcm.prefix = vcm.prefix_marks();
        Ok(vcm)
    }

    /// Which pixels trace more rays for their prefix light (`camera/prefix.rs`): the
    /// same for every pass, shard and resumed render of the scene and seed.
    fn prefix_marks(&self) -> Option<Vec<bool>> {
        if !self.settings.prefix_rays {
            return None;
        }
        let pass = self.pass(0);
        let lights = light::LightPass::default();
        self.cameras(&pass, &lights, None, 0).prefix_marks(self.size.0, self.sums.len())
    }

    fn cameras<'p>(
        &'p self,
        pass: &'p Pass<'a>,
        lights: &'p light::LightPass,
        grid: Option<&'p Grid>,
        iteration: u32,
    ) -> camera::Cameras<'p> {
        camera::Cameras {
            pass,
            lights,
            grid,
            seed: self.settings.seed,
            iteration,
            sampler: self.settings.sampler,
            differential_scale: self.differential_scale,
            prefix: self.prefix.as_deref(),
            pool: None,
        }
    }

    /// The light subpaths pass `iteration` traces: the pilot's count, then the one
    /// chosen ([`balance`]).
    pub fn light_paths(&self, iteration: u32) -> u64 {
        if !self.settings.techniques.traces_lights() {
            return 0;
        }
        match &self.balance {
            Some(Balance::Chosen(n)) if iteration >= balance::PILOT_PASSES => *n,
            _ => self.settings.light_paths.max(1),
        }
    }

    pub fn passes_done(&self) -> u32 {
        self.iteration.saturating_sub(self.first)
    }

    /// Camera subpaths per pass: the rendered window's pixels.
    pub fn pixel_count(&self) -> usize {
        self.sums.len()
    }

    pub fn first_pass(&self) -> u32 {
        self.first
    }

    /// The merging radius of the pass under way.
    pub fn radius(&self) -> f64 {
        passes::radius(self.settings.radius, self.settings.alpha, self.iteration)
    }

    /// The state a checkpoint saves: each pixel's sum (as `ld`) and the radius.
    pub fn save(&self) -> Vec<PixelState> {
        let radius = self.radius();
        self.sums.iter().map(|s| PixelState { radius, n: 0.0, ld: s.to_array(), tau: [0.0; 3] }).collect()
    }

    /// Continues from a checkpoint's state after `iteration` passes.
    pub fn restore(&mut self, iteration: u32, pixels: &[PixelState], stats: Stats) -> Result<(), RenderError> {
        if pixels.len() != self.sums.len() {
            return Err(RenderError::CheckpointPixels { saved: pixels.len(), film: self.sums.len() });
        }
        for (s, p) in self.sums.iter_mut().zip(pixels) {
            *s = DVec3::from(p.ld);
        }
        (self.iteration, self.stats) = (iteration, stats);
        if self.balance.is_some() && iteration > 0 {
            self.balance = Some(Balance::Unknown);
        }
        if self.links.is_some() && iteration > 0 {
            self.links = Some(links::State::Unknown);
        }
        if let Some(g) = &mut self.guide {
            g.reset();
        }
        Ok(())
    }

    /// What the passes so far decided, for a checkpoint to save.
    pub fn decided(&self) -> Decided {
        Decided {
            light_paths: match self.balance {
                Some(Balance::Chosen(n)) => Some(n),
                _ => None,
            },
            guide: self.guide.clone(),
            pairs_kept: match &self.links {
                Some(links::State::Paired(u)) => Some(*u),
                _ => None,
            },
        }
    }

    /// Takes what a checkpoint saved after [`Self::restore`]: the pilot's choices,
    /// where the pilot was done, and then the guide, where it is the one the passes so
    /// far trained (else the passes are replayed before the next, [`Self::rehearse`]).
    pub fn restore_decided(&mut self, saved: Decided) {
        let past_pilot = self.iteration >= balance::PILOT_PASSES;
        if let (Some(n), Some(Balance::Unknown)) = (saved.light_paths, &self.balance)
            && past_pilot
        {
            self.balance = Some(Balance::Chosen(n));
        }
        let settled = !matches!(self.balance, Some(Balance::Unknown));
        if let (Some(u), Some(links::State::Unknown)) = (saved.pairs_kept, &self.links)
            && past_pilot
            && settled
        {
            self.links = Some(links::State::Paired(u));
        }
        let trained = self.iteration.min(crate::guiding::training::TRAINING_PASSES);
        if let (Some(g), Some(mine)) = (saved.guide, &mut self.guide)
            && settled
            && g.recorded() == trained
        {
            *mine = g;
        }
    }

    /// A spectral film's bucket sums and layout.
    pub fn bucket_totals(&self) -> Option<super::buckets::BucketTotals> {
        self.buckets.as_ref().map(BucketSums::totals)
    }

    /// Sets the bucket sums from a checkpoint's (those of [`Self::bucket_totals`]).
    pub fn restore_buckets(&mut self, saved: &[f64]) -> Result<(), RenderError> {
        let film = self.buckets.as_ref().map_or(0, BucketSums::sum_count);
        let restored = match &mut self.buckets {
            None => saved.is_empty(),
            Some(b) => b.restore(saved),
        };
        match restored {
            true => Ok(()),
            false => Err(RenderError::CheckpointBuckets { saved: saved.len(), film }),
        }
    }

    /// One pass: light subpaths, the grid of their vertices, camera subpaths, splats.
    pub fn iterate(&mut self) {
        self.iterate_showing(None)
    }

    /// One pass, offering `preview` provisional images between bands of camera
    /// subpaths (see [`super::preview`]); the image it ends with is the same either way.
    pub fn iterate_showing(&mut self, preview: Option<&mut super::preview::Preview>) {
        self.rehearse();
        let mut parts = self.measuring().then(|| vec![[0f32; 3]; self.sums.len()]);
        let mut sums = std::mem::take(&mut self.sums);
        let buckets = self.buckets.as_ref();
        let mut done = self.render_pass(self.iteration, (&mut sums, buckets), parts.as_deref_mut(), preview);
        self.sums = sums;
        self.learn(self.iteration, parts.as_deref(), &mut done);
        self.iteration += 1;
        (self.stats.connections, self.stats.connections_clear) = (
            self.stats.connections + done.camera.connections,
            self.stats.connections_clear + done.camera.connections_clear,
        );
        self.note(&done.counts, done.stored, done.times);
    }

    /// Whether the pilot is measuring the passes ([`balance`]).
    fn measuring(&self) -> bool {
        matches!(self.balance, Some(Balance::Measuring(_)))
    }

    /// What pass `k` teaches: the pilot its parts (when it measures), the guide its
    /// records (when it trains on the pass).
    fn learn(&mut self, k: u32, parts: Option<&[balance::Part]>, done: &mut Done) {
        if let Some(g) = self.guide.as_mut().filter(|g| g.trains_on(k)) {
            g.add_pass(&done.records);
        }
        let n = self.light_paths(k);
        if let (Some(links::State::Learning(l)), Some((tally, points))) = (&mut self.links, done.links.take()) {
            l.add_pass(tally, points.into_iter(), n);
        }
        if k + 1 >= balance::PILOT_PASSES
            && let Some(links::State::Learning(l)) = self.links.take_if(|s| matches!(s, links::State::Learning(_)))
        {
            self.links = Some(l.finish());
        }
        if let (Some(parts), Some(Balance::Measuring(pilot))) = (parts, &mut self.balance) {
            pilot.add(parts, n, done.counts, done.camera, done.stored as u64);
            if pilot.complete() {
                self.balance = Some(Balance::Chosen(pilot.choose(self.settings.light_paths.max(1))));
            }
        }
    }

    /// Before a pass of a render that did not start at pass 0 (a shard, a resumed
    /// render): renders the passes before it again, apart from the image, as far as
    /// the pilot's choice of light subpaths and the guide's training need them, so
    /// that the pass is the one a render from pass 0 renders.
    fn rehearse(&mut self) {
        let it = self.iteration;
        let links_unknown = matches!(self.links, Some(links::State::Unknown));
        let unknown = matches!(self.balance, Some(Balance::Unknown)) || links_unknown;
        let pilot = unknown && it >= balance::PILOT_PASSES;
        if !pilot && !self.guide.as_ref().is_some_and(|g| g.behind(it)) {
            return;
        }
        if unknown {
            if self.balance.is_some() {
                self.balance = Some(Balance::Measuring(Box::new(balance::Pilot::new(self.sums.len()))));
            }
            if links_unknown {
                self.links = learning(self.scene, &self.settings);
            }
        }
        let mut end = if pilot { balance::PILOT_PASSES } else { 0 };
        if let Some(g) = &mut self.guide {
            g.reset();
            end = end.max(it.min(crate::guiding::training::TRAINING_PASSES));
        }
        let mut scratch = vec![DVec3::ZERO; self.sums.len()];
        for k in 0..end {
            let mut parts = self.measuring().then(|| vec![[0f32; 3]; self.sums.len()]);
            let mut done = self.render_pass(k, (&mut scratch, None), parts.as_deref_mut(), None);
            self.learn(k, parts.as_deref(), &mut done);
        }
    }

    /// Pass `iteration` added to `sums` (and a spectral film's buckets): light subpaths,
    /// the grid of their vertices, camera subpaths, splats; with `parts`, each pixel's
    /// camera-traced and light-side values of the pass (channel means, for the pilot).
    fn render_pass(
        &self,
        iteration: u32,
        (sums, buckets): (&mut [DVec3], Option<&BucketSums>),
        mut parts: Option<&mut [balance::Part]>,
        mut preview: Option<&mut super::preview::Preview>,
    ) -> Done {
        let t0 = Instant::now();
        self.live.reset();
        self.scene.begin_pass(iteration);
        let pass = self.pass(iteration);
        let lights = match pass.techniques.traces_lights() {
            true => light::trace_all(&pass, self.settings.seed, iteration, &self.live),
            false => light::LightPass::default(),
        };
        let t1 = Instant::now();
        let grid = self.settings.techniques.uses(Technique::Merge).then(|| merge_grid(&lights, pass.radius)).flatten();
        let pool = pass.links.as_ref().map(|l| links::Pool::new(l.cells(), lights.spots.iter().map(|s| s.p)));
        let mut tally = match &self.links {
            Some(links::State::Learning(l)) if pass.link_cells.is_some() => Some(l.tally()),
            _ => None,
        };
        let t2 = Instant::now();
        let cams = camera::Cameras { pool: pool.as_ref(), ..self.cameras(&pass, &lights, grid.as_ref(), iteration) };
        let (width, live, scene) = (self.size.0, &self.live, self.scene);
        let tasks = crate::integrators::PIXELS_PER_TASK;
        let (mut work, mut records) = (camera::Work::default(), Records::default());
        let halves = balance::Halves::new(pass.light_paths);
        let lanes = buckets.map(|b| (b, b.lanes(iteration)));
        // A pass the table learns from holds one band's connections at a time.
        let most = if tally.is_some() { LEARNING_BAND } else { usize::MAX };
        for band in super::preview::bands(sums.len(), 4 * tasks, most, preview.is_some()) {
            let first = band.start;
            let pixel = |i: usize, s: &mut DVec3| {
                if (first + i).is_multiple_of(256) {
                    live.add_camera(256);
                }
                let p = cams.pixel(first + i, width);
                let total = p.total();
                *s += scene.film_rgb(total);
                if let Some((b, lanes)) = &lanes {
                    b.add(first + i, lanes, total);
                }
                p
            };
            let band_sums = sums[band.clone()].par_iter_mut().enumerate().with_max_len(tasks);
            let (w, r, l) = match parts.as_deref_mut() {
                Some(parts) => band_sums
                    .zip(parts[band.clone()].par_iter_mut())
                    .map(|((i, s), part)| {
                        let p = pixel(i, s);
                        *part = halves.part(&p);
                        (p.work, p.records, p.links)
                    })
                    .reduce(Default::default, join),
                None => band_sums
                    .map(|(i, s)| pixel(i, s))
                    .map(|p| (p.work, p.records, p.links))
                    .reduce(Default::default, join),
            };
            work = work + w;
            records.append(r);
            if let Some(t) = &mut tally {
                t.add(&l);
            }
            if let Some(show) = preview.as_mut() {
                show(&|| provisional(sums, self.passes_done(), &self.scene.film, band.end));
            }
        }
        let t3 = Instant::now();
        let scale = self.scene.photon_scale;
        if let Some(parts) = parts {
            halves.add_splats(parts, &lights.splats, scale);
        }
        let (counts, stored) = (lights.counts, lights.stored());
        add_splats((sums, lanes.as_ref()), lights.splats, scale, scene);
        let links = tally.map(|t| (t, lights.spots.iter().map(|s| s.p).collect()));
        Done { counts, stored, camera: work, records, links, times: [t0, t1, t2, t3, Instant::now()] }
    }

    fn pass(&self, iteration: u32) -> Pass<'a> {
        let scene = self.scene;
        let radius = passes::radius(self.settings.radius, self.settings.alpha, iteration);
        let n = self.light_paths(iteration);
        Pass {
            scene,
            factors: self.settings.techniques.factors(radius, n as f64),
            techniques: self.settings.techniques,
            max_len: self.max_len(),
            light_paths: n,
            film_pixels: scene.film.x_resolution as f64 * scene.film.y_resolution as f64,
            radius: radius as f32,
            origin: self.origin,
            size: self.size,
            sampler: self.settings.sampler,
            time: scene.pass_time(iteration, true),
            nee_all: scene.lights.len() <= NEE_ALL_LIGHTS_MAX,
            cones: self.cones.clone(),
            maps: self.maps.clone(),
            correct_specular: scene.integrator.requested != "sppm",
            guide: self.guide.as_ref().filter(|_| self.settings.guiding.camera()).map(|g| g.tree()),
            light_guide: self.guide.as_ref().and_then(|g| g.importance()),
            training: self.guide.as_ref().is_some_and(|g| g.trains_on(iteration)),
            links: match &self.links {
                Some(links::State::Learnt(l)) if iteration >= balance::PILOT_PASSES => Some(l.clone()),
                _ => None,
            },
            link_cells: match &self.links {
                Some(links::State::Learning(l)) if iteration < balance::PILOT_PASSES => {
                    Some(std::sync::Arc::new(l.cells().clone()))
                }
                _ => None,
            },
        }
    }

    /// The most edges a path may have: pbrt's `maxdepth` bounces and one more edge to
    /// an emitter. pbrt-v3's whitted and directlighting light their first hit even at
    /// `maxdepth` 0 (their depth only bounds the specular recursion).
    fn max_len(&self) -> u32 {
        let depth = self.scene.integrator.max_depth;
        match self.settings.techniques {
            Techniques::Direct => depth.max(1) + 1,
            _ => depth + 1,
        }
    }

    fn note(&mut self, counts: &light::Counts, vertices: usize, t: [Instant; 5]) {
        let s = &mut self.stats;
        s.photon_seconds += (t[1] - t[0]).as_secs_f64();
        s.grid_seconds += (t[2] - t[1]).as_secs_f64();
        s.camera_seconds += (t[3] - t[2]).as_secs_f64();
        s.update_seconds += (t[4] - t[3]).as_secs_f64();
        s.camera_rays += self.sums.len() as u64;
        s.photons.traced += counts.paths;
        s.photons.hits += counts.hits;
        s.visible_points += vertices as u64;
        s.iterations = self.iteration;
        s.bidirectional = true;
        s.prefix_pixels = self.prefix.as_ref().map_or(0, |m| m.iter().filter(|&&p| p).count() as u64);
        match &self.links {
            Some(links::State::Learnt(l)) => (s.connection_draws, s.connections_auto) = (l.draws, l.auto),
            Some(links::State::Paired(u)) => s.connections_auto = Some(*u),
            _ => {}
        }
    }

    /// The current estimate: the mean of the passes, as the film records it.
    pub fn image(&self) -> Vec<[f32; 3]> {
        let k = self.passes_done().max(1) as f64;
        let film = &self.scene.film;
        self.sums.iter().map(|s| (film.respond(*s) / k).as_vec3().to_array()).collect()
    }

    /// The sum of the passes' estimates per pixel, as the film records it (what a shard
    /// writes and a merge adds up).
    pub fn pass_sums(&self) -> Vec<DVec3> {
        let film = &self.scene.film;
        self.sums.iter().map(|s| film.respond(*s)).collect()
    }
}

/// The guide a render trains, if it asks for one: over the box around what rays can
/// hit (none for pbrt-v3's whitted and directlighting, whose estimator has no light
/// subpaths).
fn guide(scene: &RenderScene, settings: &VcmSettings) -> Option<Guide> {
    let b = scene.geometry.bounds()?;
    let g = settings.guiding;
    (g != Guiding::Off && settings.techniques.bidirectional()).then(|| Guide::new(b.min, b.max, g.light()))
}

/// The grid of a pass's light vertices that merging looks up.
fn merge_grid(lights: &light::LightPass, radius: f32) -> Option<Grid> {
    let sites = lights
        .spots
        .par_iter()
        // A first vertex is direct light, never merged (`mis`).
        .map(|s| (s.edges() >= 2).then_some(Site { p: s.p, radius }))
        .collect::<Vec<_>>();
    Grid::build(&sites, Binning::Centre)
}

/// The table of cached connections at its start, where the render asks for one and
/// the pilot runs to learn it ([`links`]).
fn learning(scene: &RenderScene, settings: &VcmSettings) -> Option<links::State> {
    let mode = settings.connections;
    let learns = mode != links::Connections::Paired && settings.techniques.uses(Technique::Connect);
    let b = scene.geometry.bounds().filter(|_| learns)?;
    Some(links::State::Learning(Box::new(links::Learning::new(links::Cells::new(b.min, b.max), mode))))
}

/// The image part way through a pass: the first `camera_done` pixels with this pass's
/// camera subpaths (its light tracing is added when the pass ends), the rest as they
/// were after `passes_done` passes.
fn provisional(sums: &[DVec3], passes_done: u32, film: &Film, camera_done: usize) -> Vec<[f32; 3]> {
    let k = passes_done as f64;
    let pixel = |(i, s): (usize, &DVec3)| film.respond(*s) / if i < camera_done { k + 1.0 } else { k.max(1.0) };
    sums.par_iter().enumerate().map(|p| pixel(p).as_vec3().to_array()).collect()
}

/// Adds light tracing's splats to the pixels' sums, each pixel in a fixed order (list by
/// list, splat by splat) whatever the thread count; pixel ranges in parallel.
fn add_splats(
    (sums, buckets): (&mut [DVec3], Option<&(&BucketSums, PassLanes)>),
    lists: Vec<Vec<(u32, Rgb)>>,
    scale: f64,
    scene: &RenderScene,
) {
    let (grouped, span) = Grouped::by_pixel_range(lists, sums.len(), SPLAT_RANGES);
    sums.par_chunks_mut(span).enumerate().for_each(|(r, sums)| {
        let lo = r * span;
        for &(pixel, c) in grouped.iter().flat_map(|g| g.group(r)) {
            sums[pixel as usize - lo] += scene.film_rgb(c) * scale;
            if let Some((b, lanes)) = buckets {
                b.add_splat(pixel as usize, lanes, c, scale);
            }
        }
    });
}

/// A spectral film's bucket sums, when paths carry wavelengths.
fn bucket_sums(scene: &RenderScene, pixels: usize, size: (usize, usize)) -> Result<Option<BucketSums>, RenderError> {
    let Some(layout) = scene.film.buckets.filter(|_| scene.spectral()) else { return Ok(None) };
    let oom = RenderError::OutOfMemory { width: size.0, height: size.1, bytes: BucketSums::bytes(layout, pixels) };
    BucketSums::new(layout, pixels).map(Some).ok_or(oom)
}
