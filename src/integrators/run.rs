//! The render loop: iterations of SPPM or VCM ([`super::engine`]) until the count or the time limit, with the
//! error against a reference after each (`ERRORS.csv`), a progress bar, partial images,
//! checkpoints, and a clean stop when interrupted.

use super::checkpoint::{Checkpoint, Every, Fingerprint};
use super::completed::{Completed, Snapshot};
use super::engine::Engine;
use super::error::RenderError;
use super::passes::PassSet;
pub use super::plan::{Algorithm, MIN_RADIUS, Plan, RenderSettings};
use super::preview::Preview;
use super::report::{ErrorRow, Pace, progress_bar, progress_inside};
use crate::imageio::{ImageMeta, RgbImage, metrics, write_image};
use crate::render::RenderScene;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// What a render reports and saves while it runs, and what stops it early.
#[derive(Clone, Debug, Default)]
pub struct Monitor {
    /// Compare against this image after every iteration (`--mse-reference-image`).
    pub reference: Option<RgbImage>,
    /// Print a progress bar with ETA on stderr.
    pub progress: bool,
    /// Print no warnings (a checkpoint or partial image that could not be written).
    pub quiet: bool,
    /// Save the state as it goes (`--checkpoint`).
    pub checkpoint: Option<CheckpointTarget>,
    /// Write the image here after iterations 1, 2, 4, 8, … (`--write-partial-images`).
    pub partial_images: Option<PathBuf>,
    /// Raised (by a signal handler) to stop after the iteration under way.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// Keeps the image of the completed iterations for an abort that will not wait for
    /// the one under way (a second Ctrl-C).
    pub completed: Option<Arc<Completed>>,
    /// Show the image in tev as it converges (`--display-server`).
    pub display: Option<Arc<std::sync::Mutex<crate::imageio::tev::Tev>>>,
    /// Told after every iteration (the Python package's `progress` callback).
    pub observer: Option<Observer>,
}

/// What an [`Observer`] is told after an iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IterationDone {
    /// Iterations (passes) rendered so far in this run, and planned.
    pub done: u32,
    pub planned: u32,
    /// Seconds since the render started (a resumed render's earlier runs included).
    pub seconds: f64,
}

/// A function called on the rendering thread after each iteration.
#[derive(Clone)]
pub struct Observer(pub Arc<dyn Fn(IterationDone) + Send + Sync>);

impl std::fmt::Debug for Observer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Observer")
    }
}

/// Where and how often a render saves its state, and what it was made from.
#[derive(Clone, Debug)]
pub struct CheckpointTarget {
    pub path: PathBuf,
    pub every: Every,
    pub fingerprint: Fingerprint,
}

pub struct RenderOutput {
    pub image: RgbImage,
    pub stats: super::sppm::Stats,
    pub errors: Vec<ErrorRow>,
    pub seconds: f64,
    /// Stopped early by [`Monitor::interrupt`].
    pub interrupted: bool,
    /// The passes rendered (fewer than planned after a time limit or an interrupt).
    pub passes: PassSet,
    /// With independent passes, the sum of the passes' estimates per pixel (see
    /// [`super::sppm::Sppm::pass_sums`]).
    pub pass_sums: Option<Vec<[f64; 3]>>,
    /// A spectral film's bucket sums over the passes.
    pub buckets: Option<super::buckets::BucketTotals>,
}

/// The loop's bookkeeping beside the SPPM state.
struct Progress {
    start: Instant,
    /// Seconds spent by the runs a checkpoint continues.
    prior: f64,
    errors: Vec<ErrorRow>,
    saved: (u32, Instant),
    /// The last checkpoint write failed (warned about once until one succeeds).
    save_failed: bool,
    /// What the last snapshot for an abort took.
    snapshot_cost: Duration,
}

impl Progress {
    fn seconds(&self) -> f64 {
        self.prior + self.start.elapsed().as_secs_f64()
    }
}

/// Plans and renders with no monitor and no checkpoint (tests and tools; the command
/// line goes through [`crate::job::Job`]).
pub fn render(scene: &RenderScene, settings: &RenderSettings) -> Result<RenderOutput, RenderError> {
    run(scene, &Plan::new(&scene.integrator, || scene.world.radius, settings)?, &Monitor::default(), None)
}

/// Renders a plan (scene loading excluded from the timings), continuing a
/// checkpoint's state when given one (whose fingerprint the caller has checked).
pub fn run(
    scene: &RenderScene,
    plan: &Plan,
    monitor: &Monitor,
    resume: Option<Checkpoint>,
) -> Result<RenderOutput, RenderError> {
    check_reference(scene, monitor)?;
    check_area_lights(scene)?;
    let mut engine = Engine::new(scene, plan)?;
    let now = Instant::now();
    let mut progress = Progress {
        start: now,
        prior: 0.0,
        errors: Vec::new(),
        saved: (0, now),
        save_failed: false,
        snapshot_cost: Duration::ZERO,
    };
    if let Some(c) = resume {
        if !(plan.range.start..=plan.range.end).contains(&c.iteration) {
            return Err(RenderError::CheckpointOutside { at: c.iteration, range: plan.range.clone() });
        }
        engine.restore(c.iteration, &c.pixels, c.chains, c.stats)?;
        engine.restore_buckets(&c.buckets)?;
        let pairs_kept = c.pairs_kept;
        engine.restore_decided(super::vcm::Decided { light_paths: c.light_paths, guide: c.guide, pairs_kept });
        (progress.prior, progress.errors, progress.saved.0) = (c.seconds, c.errors, c.iteration);
    }
    let mut took = None;
    let interrupted = loop {
        if monitor.interrupt.as_ref().is_some_and(|f| f.load(Ordering::SeqCst)) {
            break true;
        }
        let over_time = plan.time_limit.is_some_and(|t| progress.seconds() >= t);
        if engine.iteration() >= plan.range.end || (engine.passes_done() > 0 && over_time) {
            break false;
        }
        let start = Instant::now();
        iterate(&mut engine, monitor, plan, &progress, took.is_none_or(|t: f64| t >= LONG_ITERATION));
        let iteration = start.elapsed();
        took = Some(iteration.as_secs_f64());
        after_iteration(&engine, monitor, plan, &mut progress);
        keep_completed(&engine, monitor, plan, &mut progress, iteration);
    };
    if monitor.progress {
        eprintln!();
    }
    if monitor.completed.as_ref().is_some_and(|c| !c.finishing()) {
        return Err(RenderError::Aborted);
    }
    show(monitor, engine.size(), &|| engine.image(), true);
    if let Some(t) = &monitor.checkpoint
        && progress.saved.0 != engine.iteration()
    {
        save(&engine, t, &mut progress, monitor.quiet);
    }
    let seconds = progress.seconds();
    let image = image(&engine, engine.photons(plan.photons), seconds);
    check_finite(&image)?;
    let passes = PassSet::from_range(engine.first_pass()..engine.iteration());
    let independent = plan.passes.is_independent() || plan.algorithm != Algorithm::Sppm;
    let pass_sums = independent.then(|| engine.pass_sums().iter().map(|s| s.to_array()).collect());
    let stats = engine.stats().clone();
    let buckets = engine.bucket_totals();
    Ok(RenderOutput { image, stats, errors: progress.errors, seconds, interrupted, passes, pass_sums, buckets })
}

/// An iteration at least this long (seconds) is shown in tev while it runs.
const LONG_ITERATION: f64 = 1.0;

/// One iteration; with a progress bar, a thread redraws it every half second while the
/// iteration runs longer than one (camera paths and photons done so far). With
/// `--display-server` and a `long` iteration expected (the run's first, or after one
/// that took [`LONG_ITERATION`]), tev is shown provisional images as it goes.
fn iterate(engine: &mut Engine, monitor: &Monitor, plan: &Plan, progress: &Progress, long: bool) {
    let size = engine.size();
    let mut preview = |image: &dyn Fn() -> Vec<[f32; 3]>| show(monitor, size, image, false);
    let preview = (monitor.display.is_some() && long).then_some(&mut preview as &mut Preview);
    if !monitor.progress {
        return engine.iterate(preview);
    }
    let (live, done) = (engine.live(), std::sync::atomic::AtomicBool::new(false));
    let totals = (engine.pixel_count() as u64, plan.photons);
    let passes = engine.passes_done();
    std::thread::scope(|s| {
        s.spawn(|| {
            let start = Instant::now();
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(std::time::Duration::from_millis(100));
                let t = start.elapsed().as_secs_f64();
                if t >= 1.0 && (t * 2.0).fract() < 0.2 && !done.load(Ordering::Relaxed) {
                    progress_inside(pace(plan, passes, progress.seconds()), &live, totals);
                }
            }
        });
        engine.iterate(preview);
        done.store(true, Ordering::Relaxed);
    });
}

/// Where the render stands, in the words its summary uses: iterations of classic
/// SPPM, passes otherwise.
fn pace(plan: &Plan, done: u32, seconds: f64) -> Pace {
    let sppm = plan.algorithm == Algorithm::Sppm;
    Pace {
        done,
        total: plan.range.len() as u32,
        seconds,
        limit: plan.time_limit,
        word: if sppm && !plan.passes.is_independent() { "iterations" } else { "passes" },
        light: if sppm { "photons" } else { "light subpaths" },
    }
}

/// An image in tev (`--display-server`): at most four times a second, and `last` (the
/// final image) always.
fn show(monitor: &Monitor, size: (usize, usize), image: &dyn Fn() -> Vec<[f32; 3]>, last: bool) {
    if let Some(d) = &monitor.display
        && let Ok(mut tev) = d.lock()
    {
        tev.show_now_and_then(image, size, last);
    }
}

/// Keeps the completed iterations' image for an abort ([`Completed`]) when the
/// iteration took at least a hundred times what the last snapshot cost.
fn keep_completed(engine: &Engine, monitor: &Monitor, plan: &Plan, progress: &mut Progress, took: Duration) {
    let Some(c) = &monitor.completed else { return };
    if took < progress.snapshot_cost * 100 {
        return c.passed();
    }
    let start = Instant::now();
    let image = image(engine, engine.photons(plan.photons), progress.seconds());
    let errors = progress.errors.clone();
    c.keep(Snapshot { image, errors, iterations: engine.passes_done() });
    progress.snapshot_cost = start.elapsed();
}

/// The error row, progress bar, partial image and checkpoint due after an iteration.
fn after_iteration(engine: &Engine, monitor: &Monitor, plan: &Plan, progress: &mut Progress) {
    let seconds = progress.seconds();
    if let Some(r) = &monitor.reference {
        let img = engine.image();
        let refpx = crop_reference(r, engine.scene().film.pixel_bounds);
        let mse = metrics::mse(&img, &refpx);
        progress.errors.push(ErrorRow {
            iteration: engine.iteration(),
            seconds,
            photons: engine.stats().photons.traced,
            mse,
            rmse: mse.sqrt(),
            relmse: metrics::relmse(&img, &refpx),
        });
    }
    if monitor.progress {
        progress_bar(pace(plan, engine.passes_done(), seconds));
    }
    if let Some(Observer(tell)) = &monitor.observer {
        tell(IterationDone { done: engine.passes_done(), planned: plan.range.len() as u32, seconds });
    }
    show(monitor, engine.size(), &|| engine.image(), false);
    if let Some(path) = &monitor.partial_images
        && engine.passes_done().is_power_of_two()
        && let image = image(engine, engine.photons(plan.photons), seconds)
        && let Err(e) = check_finite(&image)
            .map_err(|e| e.to_string())
            .and_then(|()| write_image(path, &image).map_err(|e| e.to_string()))
        && !monitor.quiet
    {
        eprintln!("\n{}: warning: cannot write the partial image ({e}); rendering goes on", path.display());
    }
    if let Some(t) = &monitor.checkpoint {
        let due = match t.every {
            Every::Iterations(n) => engine.iteration().is_multiple_of(n),
            Every::Seconds(s) => progress.saved.1.elapsed().as_secs_f64() >= s,
        };
        if due {
            save(engine, t, progress, monitor.quiet);
        }
    }
}

/// An area light's v4 `power` becomes a radiance only over its shape's area, when the
/// render scene is made: a huge power on a tiny shape can overflow there, after the
/// load's own range checks.
fn check_area_lights(scene: &RenderScene) -> Result<(), RenderError> {
    let overflowing = scene.lights.iter().find_map(|l| match l {
        crate::lights::Light::Area(a) if !a.l.is_finite() => Some(a),
        _ => None,
    });
    overflowing.map_or(Ok(()), |a| Err(RenderError::LightOverflow { shape: a.shape, area: a.area }))
}

/// Fails when a reference image's size fits neither the film nor its crop.
fn check_reference(scene: &RenderScene, monitor: &Monitor) -> Result<(), RenderError> {
    let film = &scene.film;
    let [x0, x1, y0, y1] = film.pixel_bounds;
    let render = ((x1 - x0) as usize, (y1 - y0) as usize);
    match &monitor.reference {
        Some(r)
            if (r.width, r.height) != render
                && (r.width, r.height) != (film.x_resolution as usize, film.y_resolution as usize) =>
        {
            Err(RenderError::ReferenceSize { reference: (r.width, r.height), render })
        }
        _ => Ok(()),
    }
}

/// The current estimate as an image with the render's metadata.
fn image(engine: &Engine, photons: u64, seconds: f64) -> RgbImage {
    let scene = engine.scene();
    let [x0, x1, y0, y1] = scene.film.pixel_bounds;
    RgbImage {
        width: (x1 - x0) as usize,
        height: (y1 - y0) as usize,
        pixels: engine.image(),
        bands: engine.bands(),
        origin: (x0 as i32, y0 as i32),
        full: (scene.film.x_resolution as usize, scene.film.y_resolution as usize),
        meta: ImageMeta {
            render_time_seconds: Some(seconds as f32),
            samples_per_pixel: Some(engine.passes_done() as i32),
            photons_per_iteration: Some(photons as i64),
            world_to_camera: Some(scene.world_to_camera),
            software: Some(format!("pbrt-sppm {}", env!("CARGO_PKG_VERSION"))),
        },
    }
}

/// Saves a checkpoint; a failure is a warning (the render goes on, and the previous
/// checkpoint stays as it was).
fn save(engine: &Engine, target: &CheckpointTarget, progress: &mut Progress, quiet: bool) {
    let (pixels, chains) = engine.save();
    let decided = engine.decided();
    let c = Checkpoint {
        fingerprint: target.fingerprint.clone(),
        iteration: engine.iteration(),
        seconds: progress.seconds(),
        stats: engine.stats().clone(),
        errors: progress.errors.clone(),
        pixels,
        chains,
        buckets: engine.save_buckets(),
        light_paths: decided.light_paths,
        guide: decided.guide,
        pairs_kept: decided.pairs_kept,
    };
    match c.write(&target.path) {
        Ok(()) => (progress.saved, progress.save_failed) = ((engine.iteration(), Instant::now()), false),
        Err(e) => {
            if !quiet && !progress.save_failed {
                let at = target.path.display();
                eprintln!("\n{at}: warning: {e}; rendering goes on, the last good checkpoint is kept");
            }
            progress.save_failed = true;
        }
    }
}

/// Refuses to write an image with a value f32 cannot hold (no Inf or NaN is ever
/// written): the scene's radiance times the Film's `scale` passed 3.4e38.
fn check_finite(image: &RgbImage) -> Result<(), RenderError> {
    match image.pixels.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        Some(i) => Err(RenderError::NotFinite {
            pixel: (image.origin.0 + (i % image.width) as i32, image.origin.1 + (i / image.width) as i32),
            value: image.pixels[i],
        }),
        None => Ok(()),
    }
}

/// The reference's pixels under the render's data window (the reference may be the
/// full image or already cropped).
fn crop_reference(r: &RgbImage, bounds: [u32; 4]) -> Vec<[f32; 3]> {
    let [x0, x1, y0, y1] = bounds.map(|v| v as usize);
    if r.width == x1 - x0 && r.height == y1 - y0 {
        return r.pixels.clone();
    }
    (y0..y1).flat_map(|y| (x0..x1).map(move |x| r.pixels[y * r.width + x])).collect()
}
