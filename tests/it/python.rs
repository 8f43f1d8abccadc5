//! The Python package (`tools/python`): built with maturin into a virtual environment
//! and tested there with its pytest suite, which compares it with the command line.

use crate::common::{Scratch, cannot_run, python_venv, root};
use std::path::Path;
use std::process::Command;

/// The package's wheel, built by maturin with this test binary's profile (so a
/// `cargo test` reuses the crates it built), installed in the environment.
fn install(venv: &Path, wheels: &Path) {
    let _ = std::fs::remove_dir_all(wheels);
    let mut build = Command::new(venv.join("bin/maturin"));
    build.args(["build", "--quiet", "--interpreter"]).arg(venv.join("bin/python")).arg("--out").arg(wheels);
    if !cfg!(debug_assertions) {
        build.arg("--release");
    }
    let out = build.current_dir(root().join("tools/python")).output().expect("maturin runs");
    assert!(out.status.success(), "maturin build failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let wheel = std::fs::read_dir(wheels)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|e| e == "whl"));
    let wheel = wheel.expect("maturin wrote a wheel");
    let name = wheel.file_name().unwrap().to_string_lossy().into_owned();
    assert!(name.contains("abi3"), "{name} is not an abi3 wheel");
    let out = Command::new(venv.join("bin/python"))
        .args(["-m", "pip", "install", "--quiet", "--force-reinstall", "--no-deps"])
        .arg(&wheel)
        .output()
        .expect("pip runs");
    assert!(out.status.success(), "pip install {name} failed:\n{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn the_python_package_builds_and_its_tests_pass() {
    let packages = ["maturin>=1.5,<2", "numpy", "pytest"];
    let python = match python_venv("python-venv", &packages, "import maturin, numpy, pytest") {
        Ok(p) => p,
        Err(why) => return cannot_run("python", "the Python package's tests", &why),
    };
    let venv = python.parent().and_then(Path::parent).unwrap().to_path_buf();
    install(&venv, &Path::new(env!("CARGO_TARGET_TMPDIR")).join("python-wheels"));
    // pytest's temporary folders go in ours, removed with it, not left in /tmp.
    let temp = Scratch::new("pytest");
    let out = Command::new(&python)
        .args(["-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", "--basetemp"])
        .arg(temp.join("base"))
        .arg("tests")
        .current_dir(root().join("tools/python"))
        .env("PBRT_SPPM_BIN", env!("CARGO_BIN_EXE_pbrt-sppm"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("pytest runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "pytest failed:\n{text}\n{}", String::from_utf8_lossy(&out.stderr));
    // Given the binary, nothing may skip: every comparison with the command line ran.
    assert!(!text.contains("skipped"), "pytest skipped tests:\n{text}");
    eprintln!("{}", text.lines().last().unwrap_or_default());
}
