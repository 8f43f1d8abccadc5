//! `pbrt-bench load` (issue 60): the scene it generates is one both syntaxes' top files
//! describe alike, and one we load; the benchmark times our first pixel when no peer
//! is found.

use crate::common::Scratch;
use std::process::Command;

#[test]
fn the_load_benchmark_writes_a_scene_both_top_files_describe_alike() {
    let scratch = Scratch::new("load-bench");
    let dir = scratch.join("data");
    // The smallest scale: one mesh of 65,536 triangles, one instance.
    let child = Command::new(env!("CARGO_BIN_EXE_pbrt-bench"))
        .args(["load", "--scale", "0.000001", "--runs", "1", "--dir"])
        .arg(&dir)
        .arg("--peers")
        .arg(dir.join("no-peers-here"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("1 meshes") && text.contains("1 instances"), "{text}");
    assert!(text.lines().any(|l| l.starts_with("pbrt-sppm ")), "no row of ours: {text}");
    // The first pixel's image is the race's scratch, not a result: nothing is left.
    assert!(!dir.join("first-pixel.exr").exists(), "the benchmark left its image behind");
    let old_place = std::env::temp_dir().join(format!("pbrt-bench-load-{pid}.exr"));
    assert!(!old_place.exists(), "the benchmark wrote {}", old_place.display());
    let counts = |file: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm")).args(["check", "--json"]).arg(dir.join(file)).output();
        let out = out.unwrap();
        assert!(out.status.success(), "{file}: {}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (v["syntax"].as_str().map(String::from), v["counts"]["triangles"].as_u64(), v["counts"]["instances"].as_u64())
    };
    let (v3, v4) = (counts("load-v3.pbrt"), counts("load-v4.pbrt"));
    assert_eq!(v3.0.as_deref(), Some("v3"));
    assert_eq!(v4.0.as_deref(), Some("v4"));
    // The big mesh less its poles' zero-area triangles, and the instanced one's.
    assert_eq!((v3.1, v3.2), (v4.1, v4.2));
    assert!(v4.1.is_some_and(|t| t > 65_000) && v4.2 == Some(1), "{v4:?}");
    let (meshes, instances) = (counts("meshes-v4.pbrt"), counts("instances-v4.pbrt"));
    assert_eq!((meshes.2, instances.2), (Some(0), Some(1)));
}
