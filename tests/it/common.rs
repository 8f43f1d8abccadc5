//! Helpers shared by the integration tests.

use pbrt_sppm::parser::error::LoadError;
use pbrt_sppm::scene::{LoadOptions, SceneDescription, load_scene, load_scene_from_bytes};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The repository root (tests run there, but be explicit).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
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

/// A prerequisite an opt-in (`#[ignore]`d) test lacks: under CI (`CI=true`) that is a
/// failure unless `PBRT_SPPM_ALLOW_SKIP=1`; elsewhere the test prints why and returns.
pub fn missing_prerequisite(why: &str) {
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let allowed = std::env::var("PBRT_SPPM_ALLOW_SKIP").is_ok_and(|v| v == "1");
    assert!(!ci || allowed, "cannot run under CI: {why} (set PBRT_SPPM_ALLOW_SKIP=1 to allow the skip)");
    eprintln!("SKIPPED: {why}");
}

/// A test that cannot run here and is not a failure for it (a service the machine
/// cannot start): it says so on stderr and in `target/tmp/skipped-tests.txt`, which
/// `.ci/run` prints after the test summary.
pub fn skipped(test: &str, why: &str) {
    use std::io::Write;
    eprintln!("SKIPPED: {test}: {why}");
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("skipped-tests.txt");
    if let Ok(mut f) = std::fs::OpenOptions::new().create(true).append(true).open(path) {
        let _ = writeln!(f, "{test}: {why}");
    }
}
