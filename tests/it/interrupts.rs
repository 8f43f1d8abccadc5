//! Interrupts never lose a render: two SIGINTs 10 ms apart (a double Ctrl-C) stop the
//! iteration under way and write exactly the completed iterations; GNU `timeout -s INT`
//! does the same; a checkpoint left by an aborted render resumes to the uninterrupted
//! image.

use pbrt_sppm::imageio::read_image;
use pbrt_sppm::integrators::checkpoint::Checkpoint;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Long iterations (many photons on a small film), so that signals land inside one.
const SCENE: &str = r#"LookAt 0 2 -4  0 0.5 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "image" "integer xresolution" [ 24 ] "integer yresolution" [ 18 ] "string filename" "out.exr"
Integrator "sppm" "integer numiterations" [ 10000 ] "float radius" [ 0.1 ] "integer photonsperiteration" [ 600000 ]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 6 6 6 ]
  Translate 0 2.5 0
  Rotate 90 1 0 0
  Shape "disk" "float radius" [ 0.5 ]
AttributeEnd
AttributeBegin
  Translate 0 0.6 0
  Material "glass" "float index" [ 1.5 ]
  Shape "sphere" "float radius" [ 0.6 ]
AttributeEnd
Material "matte" "rgb Kd" [ .6 .6 .6 ]
Shape "trianglemesh" "point P" [ -5 0 -5  5 0 -5  5 0 5  -5 0 5 ] "integer indices" [ 0 2 1  0 3 2 ]
"#;

fn dir(name: &str) -> crate::common::Scratch {
    crate::common::scratch("int", name, &[("scene.pbrt", SCENE)])
}

fn cli(d: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"));
    c.current_dir(d).args(["render", "scene.pbrt", "--nthreads", "2"]).args(args);
    c
}

fn pixels(path: &Path) -> Vec<[u32; 3]> {
    read_image(path).unwrap().pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

fn stderr_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn sigint(child: &Child) {
    // SAFETY: kill(2) on our own child's pid; no memory is touched.
    let r = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    assert_eq!(r, 0, "kill failed");
}

/// Starts a render that writes its image after iterations 1, 2, 4, …, and waits until
/// the first is there (one iteration complete, the next under way).
fn started(d: &Path, extra: &[&str]) -> Child {
    let mut args = vec!["--write-partial-images"];
    args.extend_from_slice(extra);
    let child = cli(d, &args).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let t = Instant::now();
    while !d.join("out.exr").exists() {
        assert!(t.elapsed() < Duration::from_secs(120), "no iteration finished in two minutes");
        std::thread::sleep(Duration::from_millis(5));
    }
    // Well inside the second iteration (half a second or more).
    std::thread::sleep(Duration::from_millis(150));
    child
}

/// Two SIGINTs 10 ms apart; the render must end with status 130.
fn interrupted_twice(child: Child) -> Output {
    sigint(&child);
    std::thread::sleep(Duration::from_millis(10));
    sigint(&child);
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", stderr_of(&out));
    out
}

/// The image an uninterrupted render of `n` iterations writes, in another folder.
fn uninterrupted(name: &str, n: u32) -> Vec<[u32; 3]> {
    let d = dir(name);
    let out = cli(&d, &["--spp", &n.to_string(), "--quiet"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let p = pixels(&d.join("out.exr"));
    let _ = std::fs::remove_dir_all(&d);
    p
}

/// The iterations in the written image, after checking the render said so.
fn iterations_written(d: &Path, out: &Output) -> u32 {
    let stderr = String::from_utf8_lossy(&out.stderr);
    let image =
        read_image(&d.join("out.exr")).unwrap_or_else(|e| panic!("no image after the interrupt: {e}\n{stderr}"));
    let n = image.meta.samples_per_pixel.expect("samplesPerPixel") as u32;
    assert!(n >= 1, "{stderr}");
    let said = [format!("wrote the {n} completed"), format!("interrupted after {n} iterations")];
    assert!(
        said.iter().any(|s| stderr.contains(s)),
        "the message does not match the image's {n} iterations:\n{stderr}"
    );
    n
}

#[test]
fn two_interrupts_10_ms_apart_write_exactly_the_completed_iterations() {
    let d = dir("double");
    let out = interrupted_twice(started(&d, &[]));
    let n = iterations_written(&d, &out);
    assert!(stderr_of(&out).contains("interrupted again: stopped the iteration under way"), "{}", stderr_of(&out));
    assert_eq!(pixels(&d.join("out.exr")), uninterrupted("double-ref", n), "not the image of {n} iterations");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn timeout_with_sigint_leaves_the_image_of_the_iterations_done() {
    let d = dir("timeout");
    let mut args = vec!["-s", "INT", "3", env!("CARGO_BIN_EXE_pbrt-sppm"), "render", "scene.pbrt"];
    args.extend(["--nthreads", "2", "--write-partial-images"]);
    let out = Command::new("timeout").current_dir(&d).args(&args).output();
    let Ok(out) = out else {
        return crate::common::cannot_run("timeout", "timeout_with_sigint", "GNU timeout is not installed");
    };
    // timeout's own status for a command it had to signal.
    assert_eq!(out.status.code(), Some(124), "{}", String::from_utf8_lossy(&out.stderr));
    let n = iterations_written(&d, &out);
    assert_eq!(pixels(&d.join("out.exr")), uninterrupted("timeout-ref", n), "not the image of {n} iterations");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_checkpoint_left_by_an_aborted_render_is_whole_and_resumes_to_the_uninterrupted_image() {
    let d = dir("ckpt");
    let out = interrupted_twice(started(&d, &["--checkpoint", "r.ckpt", "--checkpoint-every", "1", "--spp", "8"]));
    let n = iterations_written(&d, &out);
    let saved = Checkpoint::read(&d.join("r.ckpt")).expect("a whole checkpoint");
    assert!(saved.iteration >= 1 && saved.iteration <= n, "checkpoint at {}, image at {n}", saved.iteration);
    let resumed = cli(&d, &["--resume", "r.ckpt", "--spp", "8", "--quiet"]).output().unwrap();
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
    assert!(pixels(&d.join("out.exr")) == uninterrupted("ckpt-ref", 8), "the resumed render differs");
    let _ = std::fs::remove_dir_all(&d);
}
