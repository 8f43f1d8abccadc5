//! Checkpoints: a render killed at any moment and resumed gives the uninterrupted
//! render's pixels; a checkpoint from other files or settings is refused; a checkpoint
//! that cannot be written is a warning and the last good one is kept.

use pbrt_sppm::imageio::read_image;
use pbrt_sppm::integrators::checkpoint::Checkpoint;
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

const SCENE: &str = r#"LookAt 0 2 -4  0 0.5 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "image" "integer xresolution" [ 40 ] "integer yresolution" [ 30 ] "string filename" "out.exr"
Integrator "sppm" "integer numiterations" [ 60 ] "float radius" [ 0.1 ] "integer photonsperiteration" [ 400 ]
WorldBegin
LightSource "point" "point from" [ 0 3 0 ] "color I" [ 8 8 8 ]
Include "geometry.pbrt"
"#;

const GEOMETRY: &str = r#"AttributeBegin
  Translate 0 0.6 0
  Material "glass" "float index" [ 1.5 ]
  Shape "sphere" "float radius" [ 0.6 ]
AttributeEnd
Material "matte" "color Kd" [ .6 .6 .6 ]
Shape "trianglemesh" "point P" [ -5 0 -5  5 0 -5  5 0 5  -5 0 5 ] "integer indices" [ 0 2 1  0 3 2 ]
"#;

fn dir(name: &str) -> crate::common::Scratch {
    crate::common::scratch("ckpt", name, &[("scene.pbrt", SCENE), ("geometry.pbrt", GEOMETRY)])
}

fn cli(d: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"));
    c.current_dir(d).args(["render", "scene.pbrt", "--nthreads", "2"]);
    c
}

fn run(d: &Path, args: &[&str]) -> Output {
    cli(d).args(args).output().unwrap()
}

fn pixels(path: &Path) -> Vec<[u32; 3]> {
    read_image(path).unwrap().pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

/// ERRORS.csv without its seconds column (the only one that may differ).
fn errors_without_time(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .map(|l| l.split(',').enumerate().filter(|c| c.0 != 1).map(|c| c.1).collect::<Vec<_>>().join(","))
        .collect()
}

/// Kill delays between 5% and 50% of an uninterrupted render's time `t`, from a
/// small generator (deterministic, so a failure repeats).
fn delays(mut state: u64, t: Duration) -> impl Iterator<Item = Duration> {
    std::iter::from_fn(move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        Some(t.mul_f64(0.05 + 0.45 * (state >> 11) as f64 / (1u64 << 53) as f64))
    })
}

/// Renders with `--checkpoint` (resuming once a checkpoint exists), killing the process
/// with SIGKILL after each delay, until a run finishes; after every kill the checkpoint
/// must be absent or whole. Returns the kills that landed before the end.
fn kill_and_resume(d: &Path, extra: &[&str], seed: u64, t: Duration) -> usize {
    let ckpt = d.join("c.ckpt");
    let mut kills = 0;
    for delay in delays(seed, t).take(200) {
        let mut c = cli(d);
        c.args(["--outfile", "part.exr", "--checkpoint", "c.ckpt", "--checkpoint-every", "1", "-q"]).args(extra);
        if ckpt.exists() {
            c.args(["--resume", "c.ckpt"]);
        }
        let mut child = c.spawn().unwrap();
        let start = Instant::now();
        while start.elapsed() < delay {
            if let Some(status) = child.try_wait().unwrap() {
                assert!(status.success(), "a resumed run failed: {status}");
                return kills;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        child.kill().unwrap();
        child.wait().unwrap();
        kills += 1;
        if ckpt.exists() {
            Checkpoint::read(&ckpt).unwrap_or_else(|e| panic!("a kill left a torn checkpoint: {e}"));
        }
    }
    panic!("the render did not finish after {kills} kills");
}

#[test]
fn a_render_killed_at_random_moments_and_resumed_matches_an_uninterrupted_one() {
    let cases = [
        ("uniform", &[][..], 1),
        ("adaptive", &["--photon-sampling", "adaptive"][..], 2),
        ("vcm", &["--integrator", "vcm"][..], 3),
        // Both guides: the checkpoint saves the importance tree beside the light's.
        ("guided", &["--integrator", "vcm", "--guiding", "both"][..], 4),
        // Cached connections: the table is not saved; a resumed run replays the pilot.
        ("cached", &["--integrator", "vcm", "--connections", "cached"][..], 5),
        ("cached-photons", &["--integrator", "vcm", "--connections", "cached", "--photons", "300"][..], 6),
    ];
    for (name, extra, seed) in cases {
        let d = dir(name);
        let start = Instant::now();
        let out = run(&d, &[&["--outfile", "full.exr", "-q"], extra].concat());
        let t = start.elapsed();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let reference = ["--mse-reference-image", "full.exr"];
        let out = run(
            &d,
            &[&["--outfile", "full2.exr", "--mse-reference-out", "full.csv", "-q"], &reference[..], extra].concat(),
        );
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let args = [&["--mse-reference-out", "part.csv"], &reference[..], extra].concat();
        // `t` was measured on a machine that may since have become less busy: if the
        // runs finished before three kills landed, start over with shorter delays.
        let (mut kills, mut t) = (0, t);
        for _ in 0..4 {
            ["c.ckpt", "part.exr", "part.csv"].iter().for_each(|f| drop(std::fs::remove_file(d.join(f))));
            kills = kill_and_resume(&d, &args, seed, t);
            if kills >= 3 {
                break;
            }
            t /= 2;
        }
        eprintln!("{name}: {kills} kills");
        assert!(kills >= 3, "{name}: only {kills} kills landed; the test proves nothing");
        assert!(pixels(&d.join("part.exr")) == pixels(&d.join("full.exr")), "{name}: resumed pixels differ");
        let (full, part) = (errors_without_time(&d.join("full.csv")), errors_without_time(&d.join("part.csv")));
        assert_eq!(part.len(), 61, "{name}: ERRORS.csv keeps every iteration's row across resumes");
        assert_eq!(part, full, "{name}: ERRORS.csv rows differ");
        let c = Checkpoint::read(&d.join("c.ckpt")).unwrap();
        assert_eq!(c.iteration, 60);
        let _ = std::fs::remove_dir_all(&d);
    }
}

#[test]
fn a_checkpoint_from_other_files_or_settings_is_refused_with_what_differs() {
    let d = dir("refuse");
    let out = run(&d, &["--outfile", "a.exr", "--checkpoint", "c.ckpt", "--spp", "4", "-q"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let refused = |args: &[&str], why: &str| {
        let out = run(&d, &[&["--outfile", "b.exr", "--resume", "c.ckpt", "--spp", "4"], args].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("c.ckpt: error: cannot resume") && err.contains(why), "{args:?}: {err}");
        assert!(!d.join("b.exr").exists(), "nothing rendered");
    };
    refused(&["--photons", "401"], "made with photons 400, this run has 401");
    refused(&["--seed", "3"], "made with seed 0, this run has 3");
    refused(&["--sampler", "random"], "made with sampler sobol, this run has random");
    // Resuming a finished render rewrites its image at once, unchanged.
    let out = run(&d, &["--outfile", "b.exr", "--resume", "c.ckpt", "--spp", "4", "-q"]);
    assert!(out.status.success());
    assert!(pixels(&d.join("b.exr")) == pixels(&d.join("a.exr")));
    std::fs::remove_file(d.join("b.exr")).unwrap();
    std::fs::write(d.join("geometry.pbrt"), GEOMETRY.replace(".6 .6 .6", ".5 .6 .6")).unwrap();
    refused(&[], "geometry.pbrt\" has changed since");
    std::fs::write(d.join("geometry.pbrt"), GEOMETRY).unwrap();
    let mut torn = std::fs::read(d.join("c.ckpt")).unwrap();
    torn.truncate(torn.len() - 100);
    std::fs::write(d.join("c.ckpt"), torn).unwrap();
    let out = run(&d, &["--outfile", "b.exr", "--resume", "c.ckpt", "--spp", "4"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("c.ckpt: error: the checkpoint is damaged"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_unwritable_checkpoint_is_a_warning_and_the_last_good_one_is_kept() {
    let d = dir("unwritable");
    let out = run(&d, &["--outfile", "full.exr", "-q", "--spp", "400"]);
    assert!(out.status.success());
    let child = cli(&d)
        .args(["--outfile", "part.exr", "--checkpoint", "c.ckpt", "--checkpoint-every", "1", "--spp", "400"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !d.join("c.ckpt").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint was written");
        std::thread::sleep(Duration::from_millis(1));
    }
    // The writer's temporary name taken by a folder: every later write fails. (Retried
    // while a write in progress holds the name.)
    let tmp = d.join(format!(".c.ckpt.{}.tmp.ckpt", child.id()));
    while let Err(e) = std::fs::create_dir(&tmp) {
        assert_eq!(e.kind(), std::io::ErrorKind::AlreadyExists, "{e}");
        assert!(start.elapsed() < Duration::from_secs(60), "the temporary file never went away");
    }
    let saved = Checkpoint::read(&d.join("c.ckpt")).unwrap().iteration;
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("c.ckpt: warning: cannot write") && err.contains("the last good checkpoint is kept"), "{err}");
    assert!(pixels(&d.join("part.exr")) == pixels(&d.join("full.exr")), "the render went on");
    let kept = Checkpoint::read(&d.join("c.ckpt")).unwrap().iteration;
    assert!(kept < 400 && kept <= saved + 1, "saved {saved}, kept {kept}");
    let out = run(&d, &["--outfile", "resumed.exr", "--resume", "c.ckpt", "--spp", "400", "-q"]);
    assert!(out.status.success());
    assert!(pixels(&d.join("resumed.exr")) == pixels(&d.join("full.exr")));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn partial_images_are_written_at_powers_of_two() {
    let d = dir("partial");
    let mut child =
        cli(&d).args(["--outfile", "q.exr", "--write-partial-images", "--spp", "100000", "-q"]).spawn().unwrap();
    let start = Instant::now();
    let mut seen = Vec::new();
    while seen.len() < 4 && start.elapsed() < Duration::from_secs(120) {
        if let Ok(img) = read_image(&d.join("q.exr"))
            && let Some(n) = img.meta.samples_per_pixel
            && seen.last() != Some(&n)
        {
            seen.push(n);
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(seen.len() >= 4, "partial images seen: {seen:?}");
    assert!(seen.iter().all(|n| n.count_ones() == 1), "only powers of two: {seen:?}");
    assert!(seen.windows(2).all(|w| w[1] > w[0]), "{seen:?}");
    let _ = std::fs::remove_dir_all(&d);
}

/// A moving scene resumes bit for bit too, with SPPM and vcm: its times come from the
/// pass (v4) or from each path's own numbers (v3), never from the run.
#[test]
fn a_moving_scene_resumed_from_a_checkpoint_matches_an_uninterrupted_one() {
    let d = dir("motion");
    let moving = GEOMETRY.replace(
        "  Translate 0 0.6 0\n",
        "  Translate 0 0.6 0\n  ActiveTransform EndTime\n  Translate 0.8 0 0\n  ActiveTransform All\n",
    );
    std::fs::write(d.join("geometry.pbrt"), moving).unwrap();
    for integrator in ["sppm", "vcm"] {
        let whole = run(&d, &["--integrator", integrator, "--spp", "6", "-q", "--outfile", "whole.exr"]);
        assert!(whole.status.success(), "{}", String::from_utf8_lossy(&whole.stderr));
        let common =
            ["--integrator", integrator, "--spp", "6", "-q", "--outfile", "part.exr", "--checkpoint", "m.ckpt"];
        let first = run(&d, &[&common[..], &["--time-limit", "0.000001"]].concat());
        assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
        let rest = run(&d, &[&common[..], &["--resume", "m.ckpt"]].concat());
        assert!(rest.status.success(), "{}", String::from_utf8_lossy(&rest.stderr));
        assert!(pixels(&d.join("part.exr")) == pixels(&d.join("whole.exr")), "{integrator}: resumed differs");
        std::fs::remove_file(d.join("m.ckpt")).ok();
    }
}

/// Fog resumes bit for bit with beams and with points: the beams' radius comes from the
/// iteration, their estimates live in the pixels' direct light.
#[test]
fn a_foggy_scene_resumed_from_a_checkpoint_matches_an_uninterrupted_one() {
    let d = dir("fog");
    let foggy = SCENE.replace(
        "WorldBegin\n",
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_s\" [0.4 0.4 0.4] \"rgb sigma_a\" [0.1 0.1 0.1]\n\
         MediumInterface \"\" \"fog\"\nWorldBegin\n",
    );
    std::fs::write(d.join("scene.pbrt"), foggy).unwrap();
    let mut images = Vec::new();
    for gather in ["beams", "points"] {
        let whole = run(&d, &["--volume-gather", gather, "--spp", "6", "-q", "--outfile", "whole.exr"]);
        assert!(whole.status.success(), "{}", String::from_utf8_lossy(&whole.stderr));
        let common = ["--volume-gather", gather, "--spp", "6", "-q", "--outfile", "part.exr", "--checkpoint", "f.ckpt"];
        let first = run(&d, &[&common[..], &["--time-limit", "0.000001"]].concat());
        assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
        let rest = run(&d, &[&common[..], &["--resume", "f.ckpt"]].concat());
        assert!(rest.status.success(), "{}", String::from_utf8_lossy(&rest.stderr));
        assert!(pixels(&d.join("part.exr")) == pixels(&d.join("whole.exr")), "{gather}: resumed differs");
        // A checkpoint of one gather is refused by the other.
        let other = if gather == "beams" { "points" } else { "beams" };
        let mixed =
            run(&d, &["--volume-gather", other, "--spp", "6", "-q", "--outfile", "x.exr", "--resume", "f.ckpt"]);
        assert!(!mixed.status.success() && String::from_utf8_lossy(&mixed.stderr).contains("volume-gather"));
        images.push(pixels(&d.join("whole.exr")));
        std::fs::remove_file(d.join("f.ckpt")).ok();
    }
    assert!(images[0] != images[1], "beams and points rendered the same image");
}

/// vcm with cached connections resumes bit for bit when stopped during the pilot
/// (the random kills above stop it past the pilot), with the pilot's choice of light
/// subpaths and with `--photons` fixing them: the table the pilot learnt is not in the
/// checkpoint, so the resumed render plays the pilot again before the first pass that
/// draws by it.
#[test]
fn cached_connections_resumed_from_a_checkpoint_match_an_uninterrupted_render() {
    let d = dir("cached-connections");
    for photons in [&[][..], &["--photons", "300"]] {
        let args = [&["--integrator", "vcm", "-q"], photons].concat();
        let render_with = |connections: &str, extra: &[&str]| {
            let out = run(&d, &[&args[..], &["--connections", connections], extra].concat());
            assert!(out.status.success(), "{photons:?}: {}", String::from_utf8_lossy(&out.stderr));
        };
        let render = |extra: &[&str]| render_with("cached", extra);
        render(&["--spp", "7", "--outfile", "whole.exr"]);
        render_with("paired", &["--spp", "7", "--outfile", "paired.exr"]);
        let whole = pixels(&d.join("whole.exr"));
        assert!(whole != pixels(&d.join("paired.exr")), "{photons:?}: no connection was drawn from the cache");
        let common = ["--spp", "7", "--outfile", "part.exr", "--checkpoint", "c.ckpt"];
        render(&[&common[..], &["--time-limit", "0.000001"]].concat());
        render(&[&common[..], &["--resume", "c.ckpt"]].concat());
        assert!(pixels(&d.join("part.exr")) == whole, "{photons:?}: resumed differs");
    }
    let _ = std::fs::remove_dir_all(&d);
}
