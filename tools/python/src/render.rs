//! `Scene.render`: the render runs on its own thread with the GIL released, while the
//! calling thread wakes ten times a second to pass progress to the Python callback and
//! to let Python see Ctrl-C. An interrupt or an exception in the callback stops the
//! render after the iteration under way, and is raised once it has stopped.

use crate::tools;
use pbrt_sppm::integrators::beams::VolumeGather;
use pbrt_sppm::integrators::passes::PassMode;
use pbrt_sppm::integrators::run::{IterationDone, Observer, run};
use pbrt_sppm::integrators::{Algorithm, Monitor, Plan, RenderOutput, RenderSettings};
use pbrt_sppm::render::{RenderScene, world_sphere};
use pbrt_sppm::sampling::SamplerKind;
use pbrt_sppm::scene::SceneDescription;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// The render's options, by the command line's names (None: the scene's value).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Settings {
    spp: Option<u32>,
    integrator: Option<String>,
    seed: Option<u64>,
    photons: Option<u64>,
    radius: Option<f32>,
    time_limit: Option<f64>,
    sampler: Option<String>,
    passes: Option<String>,
    alpha: Option<f64>,
    volume_gather: Option<String>,
}

impl Settings {
    /// The library's settings, each value checked as the command line checks it.
    fn checked(self) -> Result<RenderSettings, String> {
        let algorithm = self.integrator.as_deref().map(str::parse::<Algorithm>).transpose()?;
        let sampler = self.sampler.as_deref().map(str::parse::<SamplerKind>).transpose();
        let sampler = sampler.map_err(|e| format!("sampler: {e}"))?.unwrap_or_default();
        let independent = match self.passes.as_deref() {
            None => None,
            Some("classic") => Some(false),
            Some("independent") => Some(true),
            Some(s) => return Err(format!("passes: expected \"classic\" or \"independent\", not \"{s}\"")),
        };
        if self.spp == Some(0) || self.photons == Some(0) {
            return Err("spp and photons must be at least 1".into());
        }
        let positive = |v: Option<f64>| v.is_none_or(|v| v > 0.0 && v.is_finite());
        if !positive(self.radius.map(f64::from)) || !positive(self.time_limit) {
            return Err("radius and time_limit must be positive numbers".into());
        }
        if self.alpha.is_some_and(|a| !(a > 0.0 && a < 1.0)) {
            return Err("alpha must be between 0 and 1 (exclusive)".into());
        }
        let volume_gather = self.volume_gather.as_deref().map(str::parse::<VolumeGather>).transpose();
        let volume_gather = volume_gather.map_err(|e| format!("volume_gather: {e}"))?;
        let bidirectional = algorithm.is_some_and(|a| a != Algorithm::Sppm);
        Ok(RenderSettings {
            algorithm,
            iterations: self.spp,
            photons: self.photons,
            radius: self.radius,
            seed: self.seed,
            sampler,
            time_limit: self.time_limit,
            volume_gather,
            passes: PassMode::asked(independent, self.alpha, false, bidirectional)?,
            ..Default::default()
        })
    }
}

/// Renders `desc`; returns a dict: `image` (float32 bytes, row-major RGB), `width`,
/// `height`, `seconds`, `iterations`, `photons`, `integrator`, `interrupted`, and
/// `errors` (ERRORS.csv's rows as tuples) when a reference image is given.
pub fn render<'py>(
    py: Python<'py>,
    desc: &SceneDescription,
    settings: Settings,
    progress: Option<Py<PyAny>>,
    reference: Option<(Vec<u8>, usize, usize)>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let settings = settings.checked().map_err(PyValueError::new_err)?;
    pbrt_sppm::job::check_overrides(&desc.limits, &settings).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let plan = Plan::new(&desc.integrator, || world_sphere(desc).radius, &settings)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let reference = reference.map(|(bytes, w, h)| tools::image(&bytes, w, h)).transpose()?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| PyValueError::new_err(format!("threads: {e}")))?;
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = mpsc::channel();
    // With a callback the render waits for it after each iteration, so returning False
    // stops the render exactly there.
    let (ack, acked) = mpsc::channel::<()>();
    let (wait, acked) = (progress.is_some(), std::sync::Mutex::new(acked));
    let monitor = Monitor {
        reference,
        interrupt: Some(stop.clone()),
        observer: Some(Observer(Arc::new(move |d: IterationDone| {
            if tx.send(d).is_ok() && wait {
                let _ = acked.lock().map(|r| r.recv());
            }
        }))),
        ..Default::default()
    };
    let name = plan.algorithm.name();
    let (out, raised) = py.detach(move || {
        std::thread::scope(|s| {
            let worker = s.spawn(|| {
                pool.install(|| {
                    let scene = RenderScene::for_integrator(desc, plan.algorithm != Algorithm::Sppm);
                    run(&scene, &plan, &monitor, None)
                })
            });
            let raised = watch((&rx, &ack), &stop, progress.as_ref(), || worker.is_finished());
            (worker.join(), raised)
        })
    });
    if let Some(e) = raised {
        return Err(e);
    }
    let out = out
        .map_err(|_| PyRuntimeError::new_err("the render panicked"))?
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    result(py, &out, &name)
}

/// Until the render has finished: progress to the callback (each answered on `ack`)
/// and Ctrl-C to Python. The first exception (KeyboardInterrupt, or one raised by the
/// callback) raises `stop` and is returned; a callback returning `False` raises `stop`
/// alone.
fn watch(
    (rx, ack): (&mpsc::Receiver<IterationDone>, &mpsc::Sender<()>),
    stop: &AtomicBool,
    progress: Option<&Py<PyAny>>,
    finished: impl Fn() -> bool,
) -> Option<PyErr> {
    let mut raised: Option<PyErr> = None;
    loop {
        let done = finished();
        let news = match rx.recv_timeout(Duration::from_millis(100)) {
            Ok(d) => Some(d),
            Err(_) if done => break,
            Err(_) => None,
        };
        Python::attach(|py| {
            let answer = match (news, progress) {
                (Some(d), Some(f)) if raised.is_none() => {
                    f.call1(py, (d.done, d.planned, d.seconds)).map(|v| !v.bind(py).is(PyBool::new(py, false)))
                }
                _ => py.check_signals().map(|()| true),
            };
            match answer {
                Ok(true) => {}
                Ok(false) => stop.store(true, Ordering::SeqCst),
                Err(e) => {
                    stop.store(true, Ordering::SeqCst);
                    raised.get_or_insert(e);
                }
            }
            // The stop flag is set before the render is let go, or it could start
            // another iteration before it sees the flag.
            if news.is_some() {
                let _ = ack.send(());
            }
        });
    }
    raised
}

fn result<'py>(py: Python<'py>, out: &RenderOutput, integrator: &str) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let floats: Vec<f32> = out.image.pixels.iter().flatten().copied().collect();
    d.set_item("image", PyBytes::new(py, &tools::float_bytes(&floats)))?;
    d.set_item("width", out.image.width)?;
    d.set_item("height", out.image.height)?;
    d.set_item("seconds", out.seconds)?;
    d.set_item("iterations", out.passes.count())?;
    d.set_item("photons", out.stats.photons.traced)?;
    d.set_item("integrator", integrator)?;
    d.set_item("interrupted", out.interrupted)?;
    let rows: Vec<_> =
        out.errors.iter().map(|r| (r.iteration, r.seconds, r.photons, r.mse, r.rmse, r.relmse)).collect();
    d.set_item("errors", rows)?;
    Ok(d)
}
