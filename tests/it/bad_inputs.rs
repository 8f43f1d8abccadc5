//! Every file in tests/data/bad/ fails to load with the message and location in its
//! `.err` file, and the command line prints it and exits with status 1.

use crate::common::root;
use pbrt_sppm::scene::{LoadOptions, load_scene};
use std::path::Path;

fn bad_cases() -> Vec<(String, String)> {
    let dir = root().join("tests/data/bad");
    let mut cases: Vec<(String, String)> = std::fs::read_dir(&dir)
        .expect("tests/data/bad")
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .filter(|n| n.ends_with(".pbrt"))
        .map(|n| {
            let err = std::fs::read_to_string(dir.join(n.replace(".pbrt", ".err")))
                .unwrap_or_else(|_| panic!("{n} has no .err file"));
            (n, err.trim_end().to_string())
        })
        .collect();
    cases.sort();
    cases
}

#[test]
fn every_bad_input_gives_its_located_error() {
    let cases = bad_cases();
    assert!(cases.len() >= 200, "only {} bad inputs", cases.len());
    let mut failures = Vec::new();
    for (name, expected) in &cases {
        let rel = format!("tests/data/bad/{name}");
        let got = match load_scene(Path::new(&rel), &LoadOptions::default()) {
            Ok(_) => "loaded without error".to_string(),
            Err(e) => e.one_line(),
        };
        if got != format!("tests/data/bad/{expected}") {
            failures.push(format!("{name}\n  expected: tests/data/bad/{expected}\n  got:      {got}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_command_line_prints_the_error_and_exits_with_1() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .args(["check", "tests/data/bad/mesh-index-out-of-range.pbrt", "--json"])
        .current_dir(root())
        .output()
        .expect("run pbrt-sppm");
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        stderr.lines().next(),
        Some(
            "tests/data/bad/mesh-index-out-of-range.pbrt:3:21: error: vertex index 3 is out of range: the mesh has 3 vertices"
        )
    );
    assert!(out.stdout.is_empty(), "no JSON on failure");
}

#[test]
fn a_missing_scene_file_is_an_error_not_a_panic() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .args(["check", "no/such/scene.pbrt"])
        .output()
        .expect("run pbrt-sppm");
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.starts_with("no/such/scene.pbrt: error: cannot read"), "{stderr}");
}

/// A mistyped command is refused naming the commands (not taken for a scene file), and
/// `check --shapes` asks for `--json` rather than being ignored.
#[test]
fn unknown_commands_and_shapes_without_json_are_usage_errors() {
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_pbrt-sppm")).args(args).output().expect("run");
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (code, stderr) = run(&["info", "x.pbrt"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("unknown command \"info\"") && stderr.contains("render, check, export"), "{stderr}");
    let (code, stderr) = run(&["check", "--shapes", "no-such.pbrt"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("--json"), "{stderr}");
    // A file name is still a render.
    let (code, stderr) = run(&["no/such/scene.pbrt"]);
    assert_eq!(code, Some(1));
    assert!(stderr.starts_with("no/such/scene.pbrt: error: cannot read"), "{stderr}");
}

#[test]
fn utf16_files_are_rejected_with_a_message() {
    let dir = crate::common::Scratch::new("utf16");
    let path = dir.join("utf16.pbrt");
    std::fs::write(&path, [0xff, 0xfe, b'W', 0, b'o', 0]).unwrap();
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    let want = format!("{}:1:1: error: \"{}\" is UTF-16", path.display(), path.display());
    assert!(e.one_line().starts_with(&want), "{}", e.one_line());
}
