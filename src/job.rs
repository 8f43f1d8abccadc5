//! A render job: what `pbrt-sppm render` does between loading a scene and printing its
//! summary, as a library.
//!
//! ```text
//! pbrt-sppm render scene.pbrt --outfile a.exr --checkpoint a.ckpt --mse-reference-image ref.exr \
//!     --mse-reference-out ERRORS.csv --passes independent --pass-range 0..8 --partial a.part.exr
//! ```
//! [`Job::plan`] checks every output path and option before any work, builds the
//! render-ready scene and fixes the pass plan and the fingerprint; [`Job::resume`] reads
//! a checkpoint and refuses one made from other files or settings; [`Job::run`]
//! renders; [`Job::write`] writes the image, the part and `ERRORS.csv`, each through a
//! temporary file renamed into place.

use crate::imageio::{ImageError, RgbImage, check_writable, read_image, write_image, write_text};
use crate::integrators::checkpoint::{Checkpoint, CheckpointError, Every, Fingerprint, Mismatch};
use crate::integrators::completed::{Completed, Snapshot};
use crate::integrators::part::{Part, PartError};
use crate::integrators::run;
use crate::integrators::{
    CheckpointTarget, ErrorRow, Monitor, Plan, RenderError, RenderOutput, RenderSettings, errors_csv,
};
use crate::limits::Limits;
use crate::render::RenderScene;
use crate::scene::SceneDescription;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// What a run was asked for: the settings and every output, by the names the user gave.
#[derive(Clone, Debug, Default)]
pub struct Request {
    /// The scene file as named (its absolute path goes into the fingerprint).
    pub scene: PathBuf,
    pub settings: RenderSettings,
    /// `--outfile`; otherwise the Film's `filename`, unless the run writes a part.
    pub outfile: Option<PathBuf>,
    /// `--partial`: the sum of the passes rendered, for `merge`.
    pub part: Option<PathBuf>,
    /// `--mse-reference-image` and `--mse-reference-out` (`ERRORS.csv`).
    pub reference: Option<PathBuf>,
    pub errors_csv: Option<PathBuf>,
    /// `--checkpoint`, `--checkpoint-every`, `--resume`.
    pub checkpoint: Option<PathBuf>,
    pub checkpoint_every: Option<Every>,
    pub resume: Option<PathBuf>,
    /// `--write-partial-images`.
    pub partial_images: bool,
    /// Print a progress bar; print no warnings.
    pub progress: bool,
    pub quiet: bool,
    /// Raised to stop after the iteration under way.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// Keeps the completed iterations' image for an abort ([`Job::write_snapshot`]).
    pub completed: Option<Arc<Completed>>,
    /// `--display-server HOST:PORT`: tev, shown the image as it converges.
    pub display_server: Option<String>,
}

/// Why a job cannot start or finish, located at the flag, parameter or file to change.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// A flag's value, or a combination of flags, that cannot be used.
    #[error("{flag}: error: {message}")]
    Option { flag: &'static str, message: String },
    /// An output named by `at` (a flag, or the Film's `filename` at its location) that
    /// cannot be written.
    #[error("{at}: error: {source}")]
    Output { at: String, source: OutputError },
    #[error("--mse-reference-image: error: {0}")]
    Reference(ImageError),
    #[error("--partial: error: {0}")]
    Part(PartError),
    #[error("{}: error: {source}", path.display())]
    Checkpoint { path: PathBuf, source: CheckpointError },
    #[error("{}: error: cannot resume: {source}", path.display())]
    Resume { path: PathBuf, source: Mismatch },
    /// `at`: the scene file, or the statement the error is about.
    #[error("{at}: error: {source}")]
    Render { at: String, source: RenderError },
}

/// Why an output cannot be written where it was asked for.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("\"{}\": the image must end in .exr or .png", .0.display())]
    ImageName(PathBuf),
    #[error("\"{}\": a part is an EXR file and must end in .exr", .0.display())]
    PartName(PathBuf),
    #[error(transparent)]
    File(#[from] ImageError),
}

impl JobError {
    fn output(at: impl std::fmt::Display, source: impl Into<OutputError>) -> JobError {
        JobError::Output { at: at.to_string(), source: source.into() }
    }
}

/// A planned render: the scene ready to render, its plan and where everything goes.
pub struct Job {
    pub request: Request,
    pub scene: RenderScene,
    pub plan: Plan,
    /// What the render is made from, for checkpoints and parts.
    pub fingerprint: Fingerprint,
    /// The image to write and what to blame when it cannot be (`--outfile`, or the
    /// Film's `filename` at its location); none for a shard writing only its part.
    pub image: Option<(PathBuf, String)>,
    monitor: Monitor,
}

impl Job {
    /// Checks every output and option, then builds the render scene and the plan.
    pub fn plan(scene: SceneDescription, request: Request) -> Result<Job, JobError> {
        let image = image_output(&scene, &request);
        check_outputs(&request, image.as_ref())?;
        check_overrides(&scene.limits, &request.settings)?;
        let reference = match &request.reference {
            Some(p) => Some(read_image(p).map_err(JobError::Reference)?),
            None => None,
        };
        let render_error = |source| JobError::Render { at: request.scene.display().to_string(), source };
        let plan = Plan::new(&scene.integrator, || crate::render::world_sphere(&scene).radius, &request.settings)
            .map_err(render_error)?;
        let fingerprint = fingerprint(&scene, &request.scene, &plan);
        let display = match request.display_server.as_deref() {
            Some(a) => {
                let title = request.scene.file_name().map_or("pbrt-sppm".into(), |n| n.to_string_lossy().into_owned());
                let tev = crate::imageio::tev::Tev::new(a, &title, request.quiet)
                    .map_err(|message| JobError::Option { flag: "--display-server", message })?;
                Some(Arc::new(std::sync::Mutex::new(tev)))
            }
            None => None,
        };
        let monitor = Monitor {
            reference,
            progress: request.progress,
            quiet: request.quiet,
            checkpoint: checkpoint_target(&request, &fingerprint),
            partial_images: request.partial_images.then(|| image.as_ref().map(|i| i.0.clone())).flatten(),
            interrupt: request.interrupt.clone(),
            completed: request.completed.clone(),
            display,
            observer: None,
        };
        let scene = RenderScene::from_description(scene, plan.algorithm != crate::integrators::Algorithm::Sppm);
        Ok(Job { request, scene, plan, fingerprint, image, monitor })
    }

    /// The checkpoint `--resume` names, if any, refused when made from other scene
    /// files or settings, or for another pass range.
    pub fn resume(&self) -> Result<Option<Checkpoint>, JobError> {
        let (Some(path), Some(target)) = (&self.request.resume, &self.monitor.checkpoint) else { return Ok(None) };
        let c = Checkpoint::read(path).map_err(|source| JobError::Checkpoint { path: path.clone(), source })?;
        c.fingerprint.check(&target.fingerprint).map_err(|source| JobError::Resume { path: path.clone(), source })?;
        Ok(Some(c))
    }

    /// Renders (on the caller's thread pool), continuing `resume` when given.
    pub fn run(&self, resume: Option<Checkpoint>) -> Result<RenderOutput, JobError> {
        run::run(&self.scene, &self.plan, &self.monitor, resume).map_err(|source| {
            let film = self.scene.film.location.clone().filter(|_| matches!(source, RenderError::NotFinite { .. }));
            JobError::Render { at: film.unwrap_or_else(|| self.request.scene.display().to_string()), source }
        })
    }

    /// Writes the image, the part and `ERRORS.csv` that were asked for.
    pub fn write(&self, out: &RenderOutput) -> Result<(), JobError> {
        self.write_image_and_errors(&out.image, &out.errors)?;
        if let Some(path) = &self.request.part {
            self.write_part(out, path).map_err(JobError::Part)?;
        }
        Ok(())
    }

    /// The image (unless this run writes only a part) and `ERRORS.csv`, if asked for.
    fn write_image_and_errors(&self, image: &RgbImage, errors: &[ErrorRow]) -> Result<(), JobError> {
        if let Some((path, blame)) = &self.image {
            write_image(path, image).map_err(|e| JobError::output(blame, e))?;
        }
        if let Some(csv) = &self.request.errors_csv {
            write_text(csv, &errors_csv(errors)).map_err(|e| JobError::output(csv.display(), e))?;
        }
        Ok(())
    }

    /// Writes what an abort keeps of a render stopped mid-iteration: the image and
    /// `ERRORS.csv` of the completed iterations. A part is not written (it needs the
    /// passes' sums, which only a finished iteration hands over): the shard's passes
    /// are rendered again.
    pub fn write_snapshot(&self, snapshot: &Snapshot) -> Result<(), JobError> {
        self.write_image_and_errors(&snapshot.image, &snapshot.errors)
    }

    /// The part a shard writes: its passes' sums and what they belong to.
    pub fn write_part(&self, out: &RenderOutput, path: &Path) -> Result<(), PartError> {
        let Some(sums) = out.pass_sums.clone() else { return Err(PartError::NotIndependent) };
        let img = &out.image;
        let part = Part {
            fingerprint: self.fingerprint.clone(),
            passes: out.passes.clone(),
            seed: self.plan.seed,
            photons: out.stats.photons.traced,
            photons_per_pass: self.plan.photons,
            seconds: out.seconds,
            width: img.width,
            height: img.height,
            origin: img.origin,
            full: img.full,
            world_to_camera: img.meta.world_to_camera,
            sums,
            buckets: out.buckets.clone(),
        };
        part.write(path)
    }

    /// Where the state is saved (`--checkpoint`, or the `--resume` file), if anywhere.
    pub fn checkpoint_path(&self) -> Option<&Path> {
        self.monitor.checkpoint.as_ref().map(|c| c.path.as_path())
    }
}

/// Where the image goes and what to blame when it cannot: `--outfile`, or the Film's
/// `filename` at its location. A shard writes its part, and an image only when named.
fn image_output(scene: &SceneDescription, request: &Request) -> Option<(PathBuf, String)> {
    match &request.outfile {
        Some(p) => Some((p.clone(), "--outfile".to_string())),
        None if request.part.is_some() => None,
        None => {
            let at = scene.film.filename_location.clone().unwrap_or_else(|| "Film \"filename\"".into());
            Some((PathBuf::from(&scene.film.filename), at))
        }
    }
}

/// Checks an output path before any work: a known extension, and a folder we can write
/// a file in (the temporary file is made and removed).
pub fn check_output(path: &Path, image: bool) -> Result<(), OutputError> {
    if image {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("exr" | "png")) {
            return Err(OutputError::ImageName(path.to_path_buf()));
        }
    }
    Ok(check_writable(path)?)
}

/// A part must be an EXR (it holds 32-bit floats and its metadata).
pub fn check_part_path(p: &Path) -> Result<(), OutputError> {
    if !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
        return Err(OutputError::PartName(p.to_path_buf()));
    }
    Ok(check_writable(p)?)
}

/// Every output path and the flags that need one another.
fn check_outputs(r: &Request, image: Option<&(PathBuf, String)>) -> Result<(), JobError> {
    if let Some((path, blame)) = image {
        check_output(path, true).map_err(|e| JobError::output(blame, e))?;
    }
    if let Some(p) = &r.part {
        check_part_path(p).map_err(|e| JobError::output("--partial", e))?;
    }
    for (flag, path) in [("--mse-reference-out", &r.errors_csv), ("--checkpoint", &r.checkpoint)] {
        if let Some(p) = path {
            check_output(p, false).map_err(|e| JobError::output(flag, e))?;
        }
    }
    if r.checkpoint_every.is_some() && r.checkpoint.is_none() && r.resume.is_none() {
        let message = "it needs --checkpoint FILE (or --resume FILE)".into();
        return Err(JobError::Option { flag: "--checkpoint-every", message });
    }
    Ok(())
}

/// Command-line values the scene's limits also bound.
pub fn check_overrides(l: &Limits, s: &RenderSettings) -> Result<(), JobError> {
    if let Some(n) = s.iterations.filter(|&n| n as u64 > l.iterations) {
        let message = Limits::over(format!("{n} iterations"), "iterations", l.iterations);
        return Err(JobError::Option { flag: "--spp", message });
    }
    if let Some(n) = s.photons.filter(|&n| n > l.photons) {
        let message = Limits::over(format!("{n} photons"), "photons", l.photons);
        return Err(JobError::Option { flag: "--photons", message });
    }
    Ok(())
}

/// What the render is made from: every file read and every setting that changes the
/// image (the pass range excepted: the parts of one render differ in it).
fn fingerprint(scene: &SceneDescription, path: &Path, plan: &Plan) -> Fingerprint {
    let mut settings = plan.fingerprint_settings();
    settings.push(("syntax".into(), scene.syntax.name().into()));
    settings.push(("fix".into(), scene.fixes.names()));
    // Passes in RGB and passes in wavelengths do not add up to either's image.
    settings.push(("colour".into(), if scene.spectral { "spectral" } else { "rgb" }.into()));
    Fingerprint {
        scene: std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()).display().to_string(),
        inputs: scene.inputs.iter().map(|f| (f.path.display().to_string(), f.hash)).collect(),
        settings,
    }
}

/// `--checkpoint` (or the `--resume` file, which the run goes on saving to): its
/// fingerprint names the pass range too, as a checkpoint continues only its own.
fn checkpoint_target(r: &Request, fingerprint: &Fingerprint) -> Option<CheckpointTarget> {
    let path = r.checkpoint.as_ref().or(r.resume.as_ref())?;
    let mut fingerprint = fingerprint.clone();
    if let Some(range) = &r.settings.pass_range {
        fingerprint.settings.push(("pass-range".into(), format!("{}..{}", range.start, range.end)));
    }
    let every = r.checkpoint_every.unwrap_or_default();
    Some(CheckpointTarget { path: path.clone(), every, fingerprint })
}
