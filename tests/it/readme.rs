//! The README stays a manual that works: at most 700 lines; its test command is the
//! one `.ci/run` runs; every `pbrt-sppm` and `pbrt-imgtool` command in its `sh` blocks
//! parses (no usage error), and those on the bundled scenes run (renders cut to one
//! iteration), in a scratch folder that sees the repository's `pbrt-scenes/`.

use crate::common::root;
use std::path::Path;
use std::process::Command;

/// The command lines of the README's `sh` blocks: continuations joined, comments cut.
fn sh_commands(readme: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_sh = false;
    let mut pending = String::new();
    for line in readme.lines() {
        if line.starts_with("```") {
            in_sh = !in_sh && line.trim() == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        let code = line.split(" #").next().unwrap_or("").trim_end();
        match code.strip_suffix('\\') {
            Some(head) => pending.push_str(head),
            None => {
                pending.push_str(code);
                if !pending.trim().is_empty() {
                    out.push(pending.trim().to_string());
                }
                pending.clear();
            }
        }
    }
    out
}

/// The programs of ours a command line runs (a pipeline's parts too).
fn ours(command: &str) -> bool {
    command.split('|').any(|part| {
        let first = part.split_whitespace().next().unwrap_or("");
        matches!(first, "pbrt-sppm" | "pbrt-imgtool") || part.trim().starts_with("cargo run --release --")
    })
}

#[test]
fn the_readme_is_at_most_700_lines_and_its_test_command_is_what_ci_runs() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(lines <= 700, "README.md has {lines} lines");
    let commands = sh_commands(&readme);
    let test = commands.iter().find(|c| c.starts_with("cargo test")).expect("a test command");
    let ci = std::fs::read_to_string(root().join(".ci/run")).unwrap();
    assert!(ci.lines().any(|l| l.trim_start_matches("exec ").trim() == test), "{test} is not what .ci/run runs");
}

#[test]
fn every_command_in_the_readme_parses_and_those_on_bundled_scenes_run() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("readme-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&scratch).unwrap();
    std::os::unix::fs::symlink(root().join("pbrt-scenes"), scratch.join("pbrt-scenes")).unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_pbrt-sppm")).parent().unwrap().to_path_buf();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let mut ran = 0;
    for command in sh_commands(&readme).iter().filter(|c| ours(c)) {
        let bundled = command.contains("pbrt-scenes/");
        let mut line = command.replace("cargo run --release --", "pbrt-sppm");
        let renders = bundled && !line.contains(" trace ") && !line.contains(" export ") && !line.contains(" check ");
        if renders {
            line.push_str(" --spp 1");
        }
        let out = Command::new("sh").arg("-c").arg(&line).current_dir(&scratch).env("PATH", &path).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_ne!(out.status.code(), Some(2), "`{command}` is a usage error: {err}");
        assert!(!err.contains("unexpected argument") && !err.contains("Usage:"), "`{command}`: {err}");
        if bundled {
            assert!(out.status.success(), "`{command}` failed on the bundled scene: {err}");
        }
        ran += 1;
    }
    assert!(ran >= 8, "only {ran} commands of ours in the README's sh blocks");
    let _ = std::fs::remove_dir_all(&scratch);
}
