//! `pbrt_sppm._native`: the Rust side of the Python package. It speaks in bytes and
//! plain values; `python/pbrt_sppm/__init__.py` turns them into NumPy arrays and
//! documents the API users call:
//!
//! ```python
//! import pbrt_sppm
//! scene = pbrt_sppm.load("cornell.pbrt")
//! image = scene.render(spp=16, integrator="vcm", seed=1)   # float32, H×W×3
//! ```

mod render;
mod tools;

use pbrt_sppm::cli::check;
use pbrt_sppm::cli::trace::{self, Tracer};
use pbrt_sppm::fixes::Fixes;
use pbrt_sppm::limits::Limits;
use pbrt_sppm::math::Ray;
use pbrt_sppm::parser::Syntax;
use pbrt_sppm::parser::error::LoadError;
use pbrt_sppm::scene::{LoadOptions, SceneDescription, load_scene, load_scene_from_bytes};
use pbrt_sppm::spectrum::transport::Colour;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use rayon::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// A loaded scene: its description, and the ray tracer `trace` builds on first use.
#[pyclass(frozen, module = "pbrt_sppm._native")]
struct Scene {
    desc: SceneDescription,
    tracer: OnceLock<Tracer>,
}

/// Reads a scene from a file (`text` false) or from scene text (relative names then
/// resolve against the current folder), with the command line's `--syntax`, `--fix`
/// and `--limit`. A scene that does not load raises `pbrt_sppm.SceneError`.
#[pyfunction]
#[pyo3(signature = (source, text, syntax=None, fix=None, limits=Vec::new(), colour=None))]
fn load(
    py: Python<'_>,
    source: &str,
    text: bool,
    syntax: Option<&str>,
    fix: Option<&str>,
    limits: Vec<String>,
    colour: Option<&str>,
) -> PyResult<Scene> {
    let colour = match colour.map(|c| Colour::from_name(c).ok_or(c)) {
        None => None,
        Some(Ok(c)) => Some(c),
        Some(Err(c)) => {
            return Err(PyValueError::new_err(format!("colour: expected \"spectral\" or \"rgb\", not \"{c}\"")));
        }
    };
    let syntax = match syntax {
        None => None,
        Some("v3") => Some(Syntax::V3),
        Some("v4") => Some(Syntax::V4),
        Some(s) => return Err(PyValueError::new_err(format!("syntax: expected \"v3\" or \"v4\", not \"{s}\""))),
    };
    let mut lim = Limits::default();
    for spec in &limits {
        lim.set(spec).map_err(|e| PyValueError::new_err(format!("limits: {e}")))?;
    }
    let fixes = fix.map(Fixes::parse).transpose().map_err(|e| PyValueError::new_err(format!("fix: {e}")))?;
    let opts = LoadOptions { syntax, limits: lim, fixes: fixes.unwrap_or_default(), colour, ..Default::default() };
    let loaded = py.detach(|| match text {
        true => load_scene_from_bytes(Path::new("<string>"), source.as_bytes().to_vec(), &opts),
        false => load_scene(Path::new(source), &opts),
    });
    match loaded {
        Ok(desc) => Ok(Scene { desc, tracer: OnceLock::new() }),
        Err(e) => Err(scene_error(py, &e)),
    }
}

/// `pbrt_sppm.SceneError(message, file, line, column)`: the error `pbrt-sppm` prints as
/// `file:line:col: error: message`.
fn scene_error(py: Python<'_>, e: &LoadError) -> PyErr {
    let (file, line, column) = match &e.location {
        Some(l) => (l.file.clone(), Some(l.line), Some(l.column)),
        None => (e.file.clone(), None, None),
    };
    let made = py
        .import("pbrt_sppm")
        .and_then(|m| m.getattr("SceneError"))
        .and_then(|class| class.call1((e.message.clone(), file, line, column)));
    match made {
        Ok(instance) => PyErr::from_value(instance),
        Err(err) => err,
    }
}

#[pymethods]
impl Scene {
    /// The `check --json` object, as JSON text.
    #[pyo3(signature = (shapes=false))]
    fn check_json(&self, shapes: bool) -> PyResult<String> {
        serde_json::to_string(&check::report(&self.desc, shapes)).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The text `pbrt-sppm check` prints.
    fn summary(&self) -> String {
        check::summary(&self.desc)
    }

    /// Every warning the scene gave while loading, located.
    fn warnings(&self) -> Vec<String> {
        self.desc.warnings.iter().map(|w| w.to_string()).collect()
    }

    /// The rendered window's width and height in pixels.
    fn size(&self) -> (u32, u32) {
        let [x0, x1, y0, y1] = self.desc.film.pixel_bounds;
        (x1 - x0, y1 - y0)
    }

    /// Traces `n` rays (float32 bytes, 3 per ray, and optionally one tmax per ray):
    /// a dict of the `trace` contract's fields, each as bytes of `n` rows (misses: NaN,
    /// or −1 for indices), plus `shape` as a list of names (`""` for a miss).
    #[pyo3(signature = (origins, directions, tmax=None))]
    fn trace<'py>(
        &self,
        py: Python<'py>,
        origins: &[u8],
        directions: &[u8],
        tmax: Option<&[u8]>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let rays = rays(origins, directions, tmax)?;
        let tracer = py.detach(|| self.tracer.get_or_init(|| Tracer::new(&self.desc)));
        let hits: Vec<_> = py.detach(|| rays.par_iter().map(|r| tracer.hit(r)).collect());
        trace_columns(py, &hits)
    }

    /// Renders; see `render::render` for the arguments.
    #[pyo3(signature = (settings, progress=None, reference=None, threads=None))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        settings: render::Settings,
        progress: Option<Py<PyAny>>,
        reference: Option<(Vec<u8>, usize, usize)>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyDict>> {
        render::render(py, &self.desc, settings, progress, reference, threads)
    }
}

/// Rays from float32 bytes, each checked as `pbrt-sppm trace` checks its lines.
fn rays(origins: &[u8], directions: &[u8], tmax: Option<&[u8]>) -> PyResult<Vec<Ray>> {
    let (o, d) = (tools::floats(origins)?, tools::floats(directions)?);
    if o.len() != d.len() || o.len() % 3 != 0 {
        return Err(PyValueError::new_err("origins and directions must both be N×3"));
    }
    let n = o.len() / 3;
    let t = match tmax {
        Some(b) => tools::floats(b)?,
        None => vec![f32::INFINITY; n],
    };
    if t.len() != n {
        return Err(PyValueError::new_err(format!("tmax must hold one value per ray ({n}), not {}", t.len())));
    }
    (0..n)
        .map(|i| {
            let (oi, di) = ([o[3 * i], o[3 * i + 1], o[3 * i + 2]], [d[3 * i], d[3 * i + 1], d[3 * i + 2]]);
            trace::query(oi, di, t[i]).map_err(|why| PyValueError::new_err(format!("ray {i}: {why}")))
        })
        .collect()
}

/// The hits as columns: float32 and int64 bytes, and the shape names.
fn trace_columns<'py>(
    py: Python<'py>,
    hits: &[Option<pbrt_sppm::cli::trace::TraceHit>],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let column = |f: &dyn Fn(&pbrt_sppm::cli::trace::TraceHit) -> Vec<f32>, width: usize| {
        let values: Vec<f32> = hits.iter().flat_map(|h| h.as_ref().map_or_else(|| vec![f32::NAN; width], f)).collect();
        PyBytes::new(py, &tools::float_bytes(&values))
    };
    out.set_item("hit", hits.iter().map(|h| h.is_some()).collect::<Vec<bool>>())?;
    out.set_item("t", column(&|h| vec![h.t], 1))?;
    out.set_item("p", column(&|h| h.p.to_vec(), 3))?;
    out.set_item("p_error", column(&|h| h.p_error.to_vec(), 3))?;
    out.set_item("n", column(&|h| h.n.to_vec(), 3))?;
    out.set_item("ns", column(&|h| h.ns.to_vec(), 3))?;
    out.set_item("uv", column(&|h| h.uv.to_vec(), 2))?;
    out.set_item("dpdu", column(&|h| h.dpdu.to_vec(), 3))?;
    out.set_item("dpdv", column(&|h| h.dpdv.to_vec(), 3))?;
    out.set_item("shape", hits.iter().map(|h| h.as_ref().map_or("", |h| h.shape)).collect::<Vec<&str>>())?;
    let index = |f: &dyn Fn(&pbrt_sppm::cli::trace::TraceHit) -> Option<u32>| {
        let values: Vec<i64> = hits.iter().map(|h| h.as_ref().and_then(f).map_or(-1, i64::from)).collect();
        PyBytes::new(py, &values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>())
    };
    out.set_item("shape_index", index(&|h| Some(h.shape_index)))?;
    out.set_item("triangle", index(&|h| h.triangle))?;
    out.set_item("patch", index(&|h| h.patch))?;
    Ok(out)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    tools::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
