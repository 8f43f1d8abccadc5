//! The source's layout: no two modules of `src/` import each other, directly or through
//! others (a module and its own submodules aside), and no two of its folders, so each
//! concept has one direction of dependence. Paths are read from `use` lines and inline `crate::`/`super::` paths
//! outside comments and test modules.

use crate::common::root;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Module path (`materials::bsdf`) → source text, for every file under `src/`.
fn modules(dir: &Path, prefix: &[String], out: &mut BTreeMap<String, String>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            modules(&path, &[prefix, &[name]].concat(), out);
        } else if let Some(stem) = name.strip_suffix(".rs") {
            let m = if ["mod", "lib", "main"].contains(&stem) {
                prefix.to_vec()
            } else {
                [prefix, &[stem.into()]].concat()
            };
            out.insert(m.join("::"), std::fs::read_to_string(&path).unwrap());
        }
    }
}

/// The longest module that `path`, written in module `from`, names.
fn target(from: &str, path: &str, known: &BTreeMap<String, String>) -> Option<String> {
    let mut parts: Vec<&str> = path.split("::").collect();
    let mut base: Vec<&str> = if from.is_empty() { vec![] } else { from.split("::").collect() };
    match parts.first() {
        Some(&"crate") => base.clear(),
        Some(&"super") => {
            while parts.first() == Some(&"super") {
                base.pop();
                parts.remove(0);
            }
            parts.insert(0, "");
        }
        _ => return None,
    }
    let rest = &parts[1..];
    (0..=rest.len()).rev().map(|k| [&base[..], &rest[..k]].concat().join("::")).find(|m| known.contains_key(m))
}

/// Module → the modules it uses, each neither its ancestor nor its descendant.
fn dependencies(known: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    let path = |s: &str| {
        s.split(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).map(str::to_owned).collect::<Vec<_>>()
    };
    known
        .iter()
        .map(|(m, text)| {
            let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
            let uses = code
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .flat_map(path)
                .filter(|w| w.starts_with("crate::") || w.starts_with("super::"))
                .filter_map(|w| target(m, &w, known))
                .filter(|t| t != m && !m.starts_with(&format!("{t}::")) && !t.starts_with(&format!("{m}::")))
                .collect();
            (m.clone(), uses)
        })
        .collect()
}

/// Whether `to` can be reached from `from`.
fn reaches(g: &BTreeMap<String, BTreeSet<String>>, from: &str, to: &str) -> bool {
    let (mut seen, mut stack) = (BTreeSet::new(), vec![from.to_string()]);
    while let Some(m) = stack.pop() {
        for n in g.get(&m).into_iter().flatten() {
            if n == to {
                return true;
            }
            if seen.insert(n.clone()) {
                stack.push(n.clone());
            }
        }
    }
    false
}

#[test]
fn no_module_of_src_depends_on_itself_through_others() {
    let mut known = BTreeMap::new();
    modules(&root().join("src"), &[], &mut known);
    let g = dependencies(&known);
    assert!(g["materials::bsdf"].contains("materials::lobes"), "the reader sees `use super::lobes`");
    let cycles = cycles(&g);
    assert!(cycles.is_empty(), "import cycles: {cycles:?}");
}

/// Each pair `a ↔ b` where a uses b and b reaches a.
fn cycles(g: &BTreeMap<String, BTreeSet<String>>) -> Vec<String> {
    g.iter().flat_map(|(m, uses)| uses.iter().filter(|u| reaches(g, u, m)).map(move |u| format!("{m} ↔ {u}"))).collect()
}

/// The top-level folder or file of `src/` a module is in (`materials::bsdf` → `materials`).
fn top(module: &str) -> &str {
    module.split("::").next().unwrap_or_default()
}

#[test]
fn no_folder_of_src_depends_on_itself_through_others() {
    // The families (shapes, materials, lights, …) are read by `scene`, so none may read
    // `scene`; between folders, as between modules, dependence goes one way.
    let mut known = BTreeMap::new();
    modules(&root().join("src"), &[], &mut known);
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, uses) in dependencies(&known) {
        let from = top(&m).to_string();
        let to: Vec<String> = uses.iter().map(|u| top(u).to_string()).filter(|t| *t != from).collect();
        g.entry(from).or_default().extend(to);
    }
    assert!(g["scene"].contains("materials"), "the scene reads the material family");
    let cycles = cycles(&g);
    assert!(cycles.is_empty(), "folders that import each other: {cycles:?}");
}

/// (lines, file, name) of each function in `text` longer than `limit` lines, counted
/// from its `fn` line to its closing brace.
fn long_functions(file: &str, text: &str, limit: usize) -> Vec<(usize, String, String)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let t = line.trim_start();
        let t = t.strip_prefix("pub(crate) ").or_else(|| t.strip_prefix("pub(super) ")).unwrap_or(t);
        let t = t.strip_prefix("pub ").unwrap_or(t);
        let Some(rest) = t.strip_prefix("fn ") else { continue };
        if line.trim_end().ends_with(';') {
            continue;
        }
        let (mut depth, mut opened) = (0i32, false);
        let end = lines[i..].iter().position(|l| {
            for c in l.chars() {
                match c {
                    '{' => (depth, opened) = (depth + 1, true),
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            opened && depth == 0
        });
        let n = end.map_or(0, |e| e + 1);
        if n > limit {
            let name = rest.split(|c: char| !(c.is_alphanumeric() || c == '_')).next().unwrap_or("").to_string();
            out.push((n, file.to_string(), name));
        }
    }
    out
}

#[test]
fn no_function_in_src_is_longer_than_80_lines() {
    let mut known = BTreeMap::new();
    modules(&root().join("src"), &[], &mut known);
    let long: Vec<_> = known.iter().flat_map(|(m, text)| long_functions(m, text, 80)).collect();
    assert!(long.is_empty(), "functions over 80 lines (lines, module, name): {long:?}");
    // The counter sees a long function when there is one.
    let body = "fn f() {\n".to_string() + &"    let x = 1;\n".repeat(85) + "}\n";
    assert_eq!(long_functions("probe", &body, 80).len(), 1);
}

/// The binary parses the command line and prints; the work is the library's
/// (`job` renders, `cli` holds the other commands), so its entry point stays short
/// and the library exports no command module at its top level.
#[test]
fn the_binary_is_the_command_line_only() {
    let main = std::fs::read_to_string(root().join("src/bin/pbrt-sppm/main.rs")).unwrap();
    let lines = main.lines().count();
    assert!(lines <= 300, "src/bin/pbrt-sppm/main.rs has {lines} lines");
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).unwrap();
    for command in ["check", "trace", "export", "farm", "fuzzing"] {
        assert!(!lib.contains(&format!("pub mod {command};")), "lib.rs exports `{command}` at its top level");
    }
}

/// `tools/pgo-build.sh` is opt-in, so nothing else runs it: it must at least parse,
/// refuse an unknown argument before building anything, and train on scene folders
/// that exist (a renamed folder would silently train on nothing).
#[test]
fn the_pgo_script_parses_and_trains_on_existing_scenes() {
    let script = root().join("tools/pgo-build.sh");
    let Ok(out) = std::process::Command::new("bash").arg("-n").arg(&script).output() else {
        crate::common::cannot_run("bash", "the_pgo_script_parses", "no `bash` on PATH");
        return;
    };
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = std::process::Command::new("bash").arg(&script).arg("--bogus").output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("usage"));
    let text = std::fs::read_to_string(&script).unwrap();
    let scenes: Vec<&str> = text.split_whitespace().filter(|w| w.starts_with("pbrt-scenes/")).collect();
    assert!(scenes.len() >= 5, "{scenes:?}");
    for scene in scenes {
        let dir = scene.trim_end_matches(';').trim_end_matches("*.pbrt");
        assert!(root().join(dir).exists(), "tools/pgo-build.sh trains on {scene}, which is absent");
    }
}
