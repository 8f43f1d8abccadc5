//! A render's plan: the overrides a run was asked for ([`RenderSettings`]) and the
//! settings it runs with once combined with the scene's ([`Plan`]).

use super::adaptive::PhotonSampling;
use super::beams::VolumeGather;
use super::error::RenderError;
use super::passes::{DEFAULT_ALPHA, PassMode};
use super::vcm::Techniques;
use super::vcm::emission_map::EmissionSampling;
use super::vcm::links::Connections;
use crate::guiding::Guiding;
use crate::sampling::SamplerKind;
use crate::scene::Integrator;
use std::ops::Range;

/// Which renderer a run uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Algorithm {
    #[default]
    Sppm,
    /// Vertex connection and merging with these techniques ([`Techniques::Bdpt`]: bdpt).
    Vcm(Techniques),
}

impl Algorithm {
    /// What renders a file that asks for integrator `requested`: SPPM for `sppm`,
    /// bdpt for `bdpt` (the same techniques), vcm for the rest (`path`, `volpath`, …:
    /// the same converged image, and the caustics they leave noisy converge).
    /// A scene whose media emit light gets SPPM whatever it asks for: SPPM's photons
    /// start in them, while vcm finds their light by camera paths alone (2× volpath's
    /// error at equal time on `v4-glow`, where SPPM has 1/20 of it: docs/media-benchmark.md).
    /// pbrt-v3's `whitted` and `directlighting` leave out indirect light, so their
    /// image is not vcm's: they get their own ([`Techniques::Direct`]).
    pub fn for_file(requested: &str, emitting_media: bool) -> Algorithm {
        match requested {
            "sppm" => Algorithm::Sppm,
            "whitted" | "directlighting" => Algorithm::Vcm(Techniques::Direct),
            _ if emitting_media => Algorithm::Sppm,
            "bdpt" => Algorithm::Vcm(Techniques::Bdpt),
            _ => Algorithm::Vcm(Techniques::All),
        }
    }

    /// What renders a scene with these Integrator settings when `--integrator` does
    /// not say.
    pub fn by_default(integrator: &Integrator) -> Algorithm {
        Algorithm::for_file(&integrator.requested, integrator.emitting_media)
    }

    /// The name `--integrator` takes.
    pub fn name(self) -> String {
        match self {
            Algorithm::Sppm => "sppm".into(),
            Algorithm::Vcm(Techniques::All) => "vcm".into(),
            Algorithm::Vcm(Techniques::Bdpt) => "bdpt".into(),
            Algorithm::Vcm(Techniques::Only(t)) => format!("vcm-only-{t:?}").to_lowercase(),
            Algorithm::Vcm(Techniques::Direct) => "direct".into(),
        }
    }
}

impl std::str::FromStr for Algorithm {
    type Err = String;

    /// `sppm`, `vcm`, `bdpt`, `direct`, or `vcm-only-T` for technique T alone (weight 1).
    fn from_str(s: &str) -> Result<Algorithm, String> {
        match s {
            "sppm" => Ok(Algorithm::Sppm),
            "vcm" => Ok(Algorithm::Vcm(Techniques::All)),
            "bdpt" => Ok(Algorithm::Vcm(Techniques::Bdpt)),
            "direct" => Ok(Algorithm::Vcm(Techniques::Direct)),
            _ => super::vcm::Technique::ALL
                .into_iter()
                .map(|t| Algorithm::Vcm(Techniques::Only(t)))
                .find(|a| a.name() == s)
                .ok_or_else(|| format!("\"{s}\" is not an integrator: sppm, vcm, bdpt or direct")),
        }
    }
}

/// The smallest initial radius: its square is a normal f32.
pub use crate::scene::options::MIN_RADIUS;

/// The iterations a render with a time limit and no iteration count plans: the
/// `iterations` limit's default, more than any render reaches in its time. Ray
/// differentials are then scaled as for any long render (their floor).
pub const OPEN_ENDED: u32 = 1 << 24;

/// How to render: overrides of the scene's SPPM parameters and the pass plan. Nothing
/// here is about reporting or output (see [`super::Monitor`]).
#[derive(Clone, Debug, Default)]
pub struct RenderSettings {
    /// `--integrator` (default: what the file asks for, [`Algorithm::for_file`]).
    pub algorithm: Option<Algorithm>,
    /// SPPM iterations (`--spp`/`--iterations`).
    pub iterations: Option<u32>,
    pub photons: Option<u64>,
    pub radius: Option<f32>,
    pub seed: Option<u64>,
    pub sampler: SamplerKind,
    /// How photon paths are drawn (`--photon-sampling`).
    pub photon_sampling: PhotonSampling,
    /// How SPPM gathers photons in media (`--volume-gather`; default beams, points
    /// with adaptive photons).
    pub volume_gather: Option<VolumeGather>,
    /// Divide the iteration count by 16 (pbrt-v3's `--quick`).
    pub quick: bool,
    /// Stop once this many seconds have passed (the iteration under way is finished).
    /// Without `iterations` (and a pass range), the render runs until then: up to
    /// [`OPEN_ENDED`] iterations rather than the file's count.
    pub time_limit: Option<f64>,
    /// Classic SPPM or independent passes (`--passes`, `--alpha`).
    pub passes: PassMode,
    /// Render only these passes of the planned ones (`--pass-range A..B`; independent
    /// passes only).
    pub pass_range: Option<Range<u32>>,
    /// Which of vcm's and bdpt's subpaths draw from a path guide (`--guiding`).
    pub guiding: Guiding,
    /// How vcm's and bdpt's light subpaths draw their start (`--emission`; default
    /// `auto`).
    pub emission: Option<EmissionSampling>,
    /// What vcm's and bdpt's camera vertices connect to (`--connections`; default
    /// `auto`).
    pub connections: Option<Connections>,
}

/// The settings a render runs with, the scene's defaults and the overrides combined.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub algorithm: Algorithm,
    pub iterations: u32,
    pub photons: u64,
    /// vcm chooses its light subpaths per pass from `photons` ([`super::vcm::balance`]):
    /// no `--photons` was given.
    pub balance_light_paths: bool,
    pub radius: f32,
    pub seed: u64,
    pub sampler: SamplerKind,
    pub photon_sampling: PhotonSampling,
    pub volume_gather: VolumeGather,
    pub passes: PassMode,
    /// The passes this run renders, within `0..iterations`.
    pub range: Range<u32>,
    /// Stop after the iteration that passes this many seconds.
    pub time_limit: Option<f64>,
    /// Which subpaths draw from a path guide ([`crate::guiding`]).
    pub guiding: Guiding,
    /// How light subpaths draw their start ([`super::vcm::emission_map`]).
    pub emission: EmissionSampling,
    /// What camera vertices connect to ([`super::vcm::links`]).
    pub connections: Connections,
}

impl Plan {
    /// Every setting that changes the image, by name, for a checkpoint's fingerprint.
    /// The iteration count is one: it sets the camera rays' differential scale.
    pub fn fingerprint_settings(&self) -> Vec<(String, String)> {
        [
            ("pbrt-sppm", env!("CARGO_PKG_VERSION").to_string()),
            ("iterations", self.iterations.to_string()),
            ("photons", self.photons.to_string()),
            ("radius", format!("{:?}", self.radius)),
            ("seed", self.seed.to_string()),
            ("sampler", format!("{:?}", self.sampler).to_lowercase()),
            ("photon-sampling", format!("{:?}", self.photon_sampling).to_lowercase()),
            ("passes", self.passes.to_string()),
        ]
        .into_iter()
        // SPPM's fingerprint stays as it was before other integrators existed.
        .chain((self.algorithm != Algorithm::Sppm).then(|| ("integrator", self.algorithm.name())))
        .chain(self.balances().then(|| ("light-subpaths", "balanced".to_string())))
        .chain((self.guiding != Guiding::Off).then(|| ("guiding", self.guiding.name().to_string())))
        // Checkpoints made before it existed (without it) still resume.
        .chain((self.emission != EmissionSampling::Auto).then(|| ("emission", self.emission.name().to_string())))
        // Checkpoints made before it existed (without it) were paired's: they do not
        // resume under `auto`, which may draw from the cache past the pilot.
        .chain((self.connections != Connections::Paired).then(|| ("connections", self.connections.name().into())))
        // Checkpoints made before it existed (without it) still resume.
        .chain((self.algorithm == Algorithm::Sppm).then(|| ("volume-gather", self.volume_gather.name().into())))
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }

    /// Whether a vcm render chooses its light subpaths per pass (not when `--photons`
    /// fixed them, nor for a technique alone, whose tests count on the file's count).
    pub fn balances(&self) -> bool {
        matches!(self.algorithm, Algorithm::Vcm(Techniques::All | Techniques::Bdpt)) && self.balance_light_paths
    }

    /// How fast a VCM render's merging radius shrinks: the independent passes' α.
    pub fn alpha(&self) -> f64 {
        match self.passes {
            PassMode::Independent { alpha } => alpha,
            PassMode::Classic => DEFAULT_ALPHA,
        }
    }
}

impl Plan {
    /// The settings a render of a scene with these integrator parameters, and a
    /// bounding sphere of this radius, runs with.
    /// `world_radius` gives the scene's bounding radius, asked for only when a vcm
    /// radius must be chosen.
    pub fn new(
        integrator: &Integrator,
        world_radius: impl FnOnce() -> f32,
        settings: &RenderSettings,
    ) -> Result<Plan, RenderError> {
        let algorithm = settings.algorithm.unwrap_or_else(|| Algorithm::by_default(integrator));
        let open_ended =
            settings.time_limit.is_some() && settings.pass_range.is_none() && settings.iterations.is_none();
        let mut iterations = if open_ended { OPEN_ENDED } else { settings.iterations.unwrap_or(integrator.iterations) };
        if settings.quick && !open_ended {
            iterations = (iterations / 16).max(1);
        }
        let radius = settings.radius.unwrap_or_else(|| default_radius(integrator, world_radius, algorithm));
        // The gather compares squared distances in f32: below 1e-18 the square leaves
        // f32's normal range and no photon is ever found.
        if !(radius >= MIN_RADIUS && radius.is_finite()) {
            return Err(RenderError::Radius { radius, min: MIN_RADIUS });
        }
        let range = settings.pass_range.clone().unwrap_or(0..iterations);
        if range.end > iterations || range.start >= range.end {
            return Err(RenderError::PassRange { range, iterations });
        }
        let sppm = algorithm == Algorithm::Sppm;
        if range != (0..iterations) && !settings.passes.is_independent() && sppm {
            return Err(RenderError::RangeNeedsIndependentPasses);
        }
        if !sppm && settings.photon_sampling == PhotonSampling::Adaptive {
            return Err(RenderError::AdaptiveVcm);
        }
        if sppm && settings.guiding != Guiding::Off {
            return Err(RenderError::GuidingSppm);
        }
        if sppm && settings.emission.is_some() {
            return Err(RenderError::EmissionSppm);
        }
        if sppm && settings.connections.is_some() {
            return Err(RenderError::ConnectionsSppm);
        }
        if !sppm && settings.volume_gather.is_some() {
            return Err(RenderError::VolumeGatherVcm);
        }
        let adaptive = settings.photon_sampling == PhotonSampling::Adaptive;
        if settings.volume_gather == Some(VolumeGather::Beams) && adaptive {
            return Err(RenderError::AdaptiveBeams);
        }
        // Beams need every photon in a medium kept; adaptive chains deposit as they go.
        let volume_gather =
            settings.volume_gather.unwrap_or(if adaptive { VolumeGather::Points } else { VolumeGather::Beams });
        Ok(Plan {
            algorithm,
            passes: settings.passes,
            range,
            iterations,
            photons: settings.photons.unwrap_or(integrator.photons_per_iteration).max(1),
            balance_light_paths: settings.photons.is_none(),
            radius,
            seed: settings.seed.unwrap_or(integrator.seed),
            sampler: settings.sampler,
            photon_sampling: settings.photon_sampling,
            volume_gather,
            time_limit: settings.time_limit,
            guiding: settings.guiding,
            emission: settings.emission.unwrap_or_default(),
            connections: settings.connections.unwrap_or_default(),
        })
    }
}

// VCM's light subpaths per pass start from the photon count, as SPPM's photons: the
// file's `photonsperiteration` (default one per pixel, as SmallVCM) unless `--photons`
// fixes them; without it vcm chooses the count after a pilot (`vcm::balance`): one per
// pixel suits connections (`doorway`), more suit merging (`pool`'s caustic).

/// The first radius when none is given: SPPM's is the Integrator's `radius`; VCM takes
/// it when the file gives one, else 0.003 of the scene's bounding radius (SmallVCM's
/// default), since a merge radius must suit the scene's scale.
fn default_radius(i: &Integrator, world_radius: impl FnOnce() -> f32, algorithm: Algorithm) -> f32 {
    match algorithm {
        Algorithm::Vcm(_) if !i.radius_given => (0.003 * world_radius()).max(MIN_RADIUS),
        // A file that asked for another integrator (one with emitting media, rendered by SPPM)
        // has no radius meant for photons: pbrt's default of 1 may span the scene.
        Algorithm::Sppm if !i.radius_given && i.requested != "sppm" => (0.01 * world_radius()).max(MIN_RADIUS),
        _ => i.radius,
    }
}
