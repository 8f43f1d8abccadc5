//! Helpers shared by the integration tests.

use pbrt_sppm::parser::error::LoadError;
use pbrt_sppm::scene::{LoadOptions, SceneDescription, load_scene, load_scene_from_bytes};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository root (tests run there, but be explicit).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A test's own empty folder, `pbrt-sppm-{name}-{pid}` in the system's temporary
/// folder, removed when the test is done with it. A failing test leaves it, to look at.
pub struct Scratch(PathBuf);

impl Scratch {
    /// `name` must differ between the tests that may run at once.
    pub fn new(name: &str) -> Scratch {
        let d = std::env::temp_dir().join(format!("pbrt-sppm-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Scratch(d)
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("left for a look: {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// A [`Scratch`] folder `{kind}-{name}` holding `files` (name, text).
pub fn scratch(kind: &str, name: &str, files: &[(&str, &str)]) -> Scratch {
    let d = Scratch::new(&format!("{kind}-{name}"));
    for (file, text) in files {
        std::fs::write(d.join(file), text).unwrap();
    }
    d
}

/// Loads scene text as if it were the file `tests/data/good/inline.pbrt`.
pub fn load(text: &str) -> Result<SceneDescription, LoadError> {
    let path = Path::new("tests/data/good/inline.pbrt");
    load_scene_from_bytes(path, text.as_bytes().to_vec(), &LoadOptions::default())
}

/// Loads scene text that must load; panics with the error otherwise.
pub fn scene(text: &str) -> SceneDescription {
    load(text).unwrap_or_else(|e| panic!("scene did not load: {e}\n{text}"))
}

/// The `check --json --shapes` report of scene text.
pub fn report(text: &str) -> Value {
    pbrt_sppm::cli::check::report(&scene(text), true)
}

/// The `shapes` array of the report of a world block.
pub fn world_shapes(world: &str) -> Vec<Value> {
    let r = report(&format!("WorldBegin\n{world}\n"));
    r["shapes"].as_array().cloned().unwrap_or_default()
}

pub fn load_file(path: &Path) -> Result<SceneDescription, LoadError> {
    load_scene(path, &LoadOptions::default())
}

pub fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

pub fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-30)
}

/// Row-major 4×4 from the JSON array.
pub fn matrix(v: &Value) -> [f64; 16] {
    let a: Vec<f64> = v.as_array().expect("matrix").iter().map(num).collect();
    a.try_into().expect("16 numbers")
}

/// Every message in the scene's warnings.
pub fn warnings(s: &SceneDescription) -> Vec<String> {
    s.warnings.iter().map(|w| w.message.clone()).collect()
}

/// A test of `kind` (`scenes`, `mitsuba`, `python`, `slurm`) that needs what this
/// machine lacks says so and returns: `SKIPPED: why` on stderr, and a line in the file
/// that the `summary` test target prints after this binary's results, so the skip is
/// in the test summary and never a silent pass. Under CI (`CI=true`, where `.ci/run`
/// installs what the tests need) it fails instead, unless `PBRT_SPPM_ALLOW_SKIP` names
/// the kind (a comma list, or `1` for all).
pub fn cannot_run(kind: &str, test: &str, why: &str) {
    use std::io::Write;
    let allowed = std::env::var("PBRT_SPPM_ALLOW_SKIP").unwrap_or_default();
    let allowed = allowed == "1" || allowed.split(',').any(|k| k.trim() == kind);
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    assert!(!ci || allowed, "{test} cannot run here: {why} (under CI=true every test must run)");
    // One line each in the summary, whatever the reason's own line breaks.
    let why = why.split_whitespace().collect::<Vec<_>>().join(" ");
    eprintln!("SKIPPED: {test}: {why}");
    let _ = std::fs::create_dir_all(env!("CARGO_TARGET_TMPDIR"));
    if let Ok(mut f) = std::fs::OpenOptions::new().create(true).append(true).open(skipped_list()) {
        let _ = writeln!(f, "{test}: {why}");
    }
}

/// Where this run's skipped tests are listed: one file per `cargo test` process (the
/// parent of every test binary it runs), so no earlier run's skips are shown.
pub fn skipped_list() -> PathBuf {
    // SAFETY: getppid has no preconditions.
    let parent = unsafe { libc::getppid() };
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("skipped-tests-{parent}.txt"))
}

/// The Python of a virtual environment `name` under the target directory holding
/// `packages`, made once (and kept across runs while `probe` still runs in it). An
/// error says why it cannot be made: no python3 with `venv` (`.ci/run` installs it
/// where it can), or an unreachable package index.
pub fn python_venv(name: &str, packages: &[&str], probe: &str) -> Result<PathBuf, String> {
    let venv = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let python = venv.join("bin/python");
    let ready = |py: &Path| Command::new(py).args(["-c", probe]).output().is_ok_and(|o| o.status.success());
    if python.exists() && ready(&python) {
        return Ok(python);
    }
    // Built aside and renamed, so an interrupted install never looks finished.
    let building = venv.with_extension(format!("tmp{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&building);
    let made = Command::new("python3").args(["-m", "venv"]).arg(&building).output();
    if !made.as_ref().is_ok_and(|o| o.status.success()) {
        let why = made.map_or_else(|e| e.to_string(), |o| String::from_utf8_lossy(&o.stderr).trim().to_string());
        return Err(format!("python3 cannot make a virtual environment ({why})"));
    }
    let py = building.join("bin/python");
    let pip = |args: &[&str]| Command::new(&py).args(["-m", "pip"]).args(args).output().expect("pip runs");
    let first = packages[0].split(['<', '>', '=', '!', '~', ' ']).next().unwrap_or_default();
    let probe_index = pip(&["index", "versions", first]);
    if !probe_index.status.success() {
        let _ = std::fs::remove_dir_all(&building);
        let last = String::from_utf8_lossy(&probe_index.stderr).lines().last().unwrap_or("no message").to_string();
        return Err(format!("the package index is unreachable ({last})"));
    }
    let install = pip(&[&["install", "--quiet"], packages].concat());
    assert!(install.status.success(), "pip install {packages:?} failed: {}", String::from_utf8_lossy(&install.stderr));
    // Another test process may have finished first; then its environment is used.
    if !(python.exists() && ready(&python)) {
        let _ = std::fs::remove_dir_all(&venv);
        std::fs::rename(&building, &venv).unwrap();
    }
    let _ = std::fs::remove_dir_all(&building);
    // A venv's scripts name its directory, so check the moved one still works.
    assert!(ready(&python), "{} cannot run {probe:?}", python.display());
    Ok(python)
}

/// The linear sRGB of a spectrum (a function of λ in nm), with the film's
/// normalisation: the colour space's white at luminance 1 is (1, 1, 1).
pub fn srgb_of_spectrum(s: impl Fn(f64) -> f64) -> [f64; 3] {
    use pbrt_sppm::spectrum::colorspace::{ColorSpaceName, mul_vec};
    mul_vec(&ColorSpaceName::Srgb.rgb_from_xyz(), pbrt_sppm::spectrum::cie::spectrum_to_xyz(s))
}
