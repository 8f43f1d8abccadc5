//! `pbrt-bench converge` with a stand-in peer: a script that answers to pbrt-v3's command
//! line by running our renderer with other random numbers. It checks that each rung gets
//! its own iteration count through the rewritten file, that `@half` halves the film, that
//! the peer's error is measured against the reference the tool reports, and the errors.
#![cfg(unix)]

use pbrt_sppm::imageio::{RgbImage, metrics, read_image};
use std::path::{Path, PathBuf};
use std::process::Command;

fn dir(name: &str) -> crate::common::Scratch {
    crate::common::Scratch::new(&format!("converge-{name}"))
}

/// A small v3 scene whose world sits in an included file; the comment and the bare
/// iteration count test that the rewrite works on tokens, not text.
fn write_scene(d: &Path) -> PathBuf {
    let scene = d.join("scene.pbrt");
    std::fs::write(
        &scene,
        r#"# Integrator "sppm" "integer numiterations" [ 1000 ] (a comment)
LookAt 0 1 -4  0 0.5 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "image" "integer xresolution" 48 "integer yresolution" [ 32 ] "string filename" "x.exr"
Integrator "sppm" "integer photonsperiteration" [ 40000 ] "integer numiterations" 8
WorldBegin
Include "world.pbrt"
WorldEnd
"#,
    )
    .unwrap();
    std::fs::write(
        d.join("world.pbrt"),
        r#"LightSource "point" "point from" [ 0 3 -1 ] "rgb I" [ 8 8 8 ]
Material "matte" "rgb Kd" [ .6 .5 .4 ]
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ]
    "point P" [ -3 0 -3  3 0 -3  3 0 3  -3 0 3 ]
Material "glass"
Translate 0 0.7 0
Shape "sphere" "float radius" [ 0.7 ]
"#,
    )
    .unwrap();
    scene
}

/// `peers/pbrt-v3`: pbrt-v3's flags in, our renderer with random numbers behind.
fn fake_peers(d: &Path) -> PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let peers = d.join("peers");
    std::fs::create_dir_all(&peers).unwrap();
    let script = peers.join("pbrt-v3");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\nwhile [ $# -gt 1 ]; do\n  case \"$1\" in\n    --outfile) out=\"$2\"; shift 2;;\n    \
             --nthreads) n=\"$2\"; shift 2;;\n    *) shift;;\n  esac\ndone\n\
             exec '{}' render \"$1\" --outfile \"$out\" --nthreads \"$n\" --quiet --sampler random --seed 7\n",
            env!("CARGO_BIN_EXE_pbrt-sppm")
        ),
    )
    .unwrap();
    std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755)).unwrap();
    peers
}

fn converge(args: &[&str]) -> (Option<i32>, String, String) {
    converge_in(&std::env::current_dir().unwrap(), args)
}

fn converge_in(cwd: &Path, args: &[&str]) -> (Option<i32>, String, String) {
    let out =
        Command::new(env!("CARGO_BIN_EXE_pbrt-bench")).arg("converge").args(args).current_dir(cwd).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The table's relMSE for a peer rung.
fn table_relmse(table: &str, peer: &str, n: u32) -> f64 {
    let row =
        table.lines().find(|l| l.starts_with(&format!("| {peer} | {n} |"))).unwrap_or_else(|| panic!("no row for {n}"));
    row.split('|').nth(4).and_then(|s| s.trim().parse().ok()).unwrap()
}

#[test]
fn converge_rewrites_each_rung_and_measures_the_peer_against_the_reference() {
    let d = dir("ok");
    let scene = write_scene(&d);
    let peers = fake_peers(&d);
    let out = d.join("out");
    let spec = format!("{}@half", scene.display());
    let args = ["--runs", "2", "--reference-iterations", "32", "--nthreads", "1", "--peers"];
    let (code, stdout, stderr) =
        converge(&[&args[..], &[peers.to_str().unwrap(), "--out", out.to_str().unwrap(), &spec]].concat());
    assert_eq!(code, Some(0), "{stdout}\n{stderr}");
    assert!(stdout.contains("pbrt-v4: not found, left out"), "{stdout}");
    let folder = out.join("scene@half");
    let reference = std::fs::read_dir(out.join("refs"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.file_name().unwrap().to_string_lossy().starts_with("scene.converge-32-"))
        .expect("the reference is cached under refs/");
    let reference = read_image(&reference).unwrap();
    assert_eq!((reference.width, reference.height), (24, 16), "@half halves the film");
    let noise = reference_noise_from_halves(&out.join("refs/halves"), &reference);
    let mut errors = Vec::new();
    for n in [2u32, 4, 8] {
        let img = read_image(&folder.join(format!("pbrt-v3-{n}.exr"))).unwrap();
        assert_eq!(img.meta.samples_per_pixel, Some(n as i32), "the peer's file asks for {n} iterations");
        assert_eq!((img.width, img.height), (24, 16));
        let e = metrics::relmse(&img.pixels, &reference.pixels);
        let shown = table_relmse(&stdout, "pbrt-v3", n);
        assert!((shown - e).abs() <= 1e-3 * e, "rung {n}: table {shown}, recomputed {e}");
        errors.push(e);
    }
    assert!(errors[2] < errors[0], "the peer's error falls with iterations: {errors:?}");
    let ours = std::fs::read_to_string(folder.join("ours.csv")).unwrap();
    assert!(ours.starts_with("iteration,seconds,photons,mse,rmse,relmse\n"));
    let seconds: Vec<f64> = ours.lines().skip(1).map(|l| l.split(',').nth(1).unwrap().parse().unwrap()).collect();
    assert!(seconds.len() >= 2 && seconds.windows(2).all(|w| w[0] <= w[1]), "{ours}");
    let table = std::fs::read_to_string(folder.join("converge.md")).unwrap();
    assert_eq!(table.lines().filter(|l| l.starts_with("| pbrt-v3 |")).count(), 3);
    let shown: f64 = table.lines().next().and_then(|l| l.rsplit(": ").next()).and_then(|v| v.parse().ok()).unwrap();
    assert!((shown - noise).abs() <= 1e-3 * noise, "the reference's noise: table {shown}, recomputed {noise}");
    assert!(noise > 0.0 && noise < errors[2], "a reference quieter than the peer's longest rung: {noise} {errors:?}");
    let last = table.lines().find(|l| l.starts_with("| pbrt-v3 | 8 |")).unwrap();
    let ratio: f64 = last.split('|').nth(7).and_then(|s| s.trim().parse().ok()).unwrap_or(f64::NAN);
    assert!(ratio > 0.0 && ratio.is_finite(), "an equal-time ratio at the longest rung: {last}");
    assert!(folder.join("converge.png").is_file());
    assert!(stdout.contains("- scene@half: "), "{stdout}");
}

/// The reference is the mean of its two halves (16 iterations each, other seeds), and
/// its own relMSE is a quarter of their squared difference, weighed as relMSE weighs.
fn reference_noise_from_halves(halves: &Path, reference: &RgbImage) -> f64 {
    let mut parts: Vec<PathBuf> = std::fs::read_dir(halves).unwrap().flatten().map(|e| e.path()).collect();
    parts.sort();
    assert_eq!(parts.len(), 2, "two halves: {parts:?}");
    let [a, b] = [&parts[0], &parts[1]].map(|p| read_image(p).unwrap());
    assert_eq!(a.meta.samples_per_pixel, Some(16));
    assert_ne!(a.pixels, b.pixels, "the halves have seeds of their own");
    let mut sum = 0.0;
    for ((p, q), r) in a.pixels.iter().zip(&b.pixels).zip(&reference.pixels) {
        for c in 0..3 {
            let mid = 0.5 * (p[c] as f64 + q[c] as f64);
            assert!((mid - r[c] as f64).abs() <= 1e-6 * (1.0 + mid.abs()), "the reference is the halves' mean");
            sum += (0.5 * (p[c] - q[c]) as f64).powi(2) / (mid * mid + 0.01);
        }
    }
    sum / (3 * a.pixels.len()) as f64
}

#[test]
fn converge_refuses_what_it_cannot_rewrite_or_parse() {
    let d = dir("bad");
    let scene = d.join("nofilm.pbrt");
    std::fs::write(&scene, "Integrator \"sppm\"\nFilm \"image\"\nWorldBegin\n").unwrap();
    let out = d.join("out");
    let peers = d.join("no-peers");
    let spec = format!("{}@half", scene.display());
    let (code, _, stderr) = converge(&["--peers", peers.to_str().unwrap(), "--out", out.to_str().unwrap(), &spec]);
    assert_eq!(code, Some(1));
    assert!(stderr.contains("Film has no xresolution to halve"), "{stderr}");
    let (code, _, stderr) = converge(&["--runs", "0", &spec]);
    assert_eq!(code, Some(1));
    assert!(stderr.contains("--runs: '0' is not a positive integer"), "{stderr}");
    let (code, _, stderr) = converge(&["--frobnicate"]);
    assert_eq!(code, Some(1));
    assert!(stderr.contains("unknown option --frobnicate"), "{stderr}");
}

#[test]
fn ours_args_reach_our_timed_runs_only() {
    let d = dir("args");
    let scene = write_scene(&d);
    let (out, peers) = (d.join("out"), d.join("no-peers"));
    let common = ["--peers", peers.to_str().unwrap(), "--out", out.to_str().unwrap(), "--runs", "1"];
    let spec = format!("{}@half", scene.display());
    // A bad option fails our run, not the reference before it.
    let (code, stdout, stderr) = converge(&[&common[..], &["--ours-args", "--frobnicate", &spec]].concat());
    assert_eq!(code, Some(1), "{stdout}");
    assert!(stdout.contains("rendering the reference"), "{stdout}");
    assert!(stderr.contains("frobnicate"), "{stderr}");
    // Relative paths for --out, the peers and the scene: peers run in the scene's
    // folder under --out, so the tool must not hand them paths relative to here.
    // (The scene's folder must not hold --out: its links would make any path work.)
    fake_peers(&d);
    std::fs::create_dir_all(d.join("scenes")).unwrap();
    write_scene(&d.join("scenes"));
    let args = ["--peers", "peers", "--out", "rel-out", "--runs", "1", "--iterations", "2"];
    let (code, stdout, stderr) = converge_in(
        &d,
        &[&args[..], &["--ours-args", "--photon-sampling adaptive", "scenes/scene.pbrt@half"]].concat(),
    );
    assert_eq!(code, Some(0), "{stdout}\n{stderr}");
    assert!(stdout.contains("ours with --photon-sampling adaptive"), "{stdout}");
    assert!(stdout.contains("| pbrt-v3 | 2 |"), "{stdout}");
    assert!(d.join("rel-out/scene@half/pbrt-v3-2.exr").exists());
}
