//! `pbrt-bench`: benchmarks (speed lives here, never in tests).
//!
//! ```text
//! cargo run --release --bin pbrt-bench -- parse [--runs 5] [--dir target/bench-data] [--peers ../shared/peers]
//! cargo run --release --bin pbrt-bench -- load [--runs 3] [--scale 1] [--dir target/bench-data/load] [--peers ../shared/peers]
//! cargo run --release --bin pbrt-bench -- rays [--runs 5] [--dir target/bench-data] [--dump] [--sse]
//! cargo run --release --bin pbrt-bench -- sppm [--runs 3] [SCENE.pbrt ...]
//! cargo run --release --bin pbrt-bench -- converge [SCENE.pbrt[@half] ...] [--runs 3] ...
//! cargo run --release --bin pbrt-bench -- stress [spawn|mesh|grazing|furnace] [--shapes N] [--rays N] ...
//! ```
//! `stress` runs the numerical stress sweeps: self-intersections of spawned rays,
//! escapes from closed meshes, grazing rays against an f64 reference, and a long
//! progressive run (see `stress/mod.rs`).
//! `converge` measures error against wall time beside pbrt-v3 and pbrt-v4 (see
//! `converge.rs`).
//! `sppm` renders each scene (default: the bundled `pbrt-scenes/v3/*.pbrt` scenes) at 1
//! and 2 threads and prints the median seconds per iteration and per million photons.
//! `rays` builds a 1M-triangle bumpy sphere (through a binary PLY, as a scene would),
//! times the BVH build, then 1M coherent camera rays and 1M incoherent random rays for
//! closest hit and any hit on 1 and 2 threads, and reports bytes per triangle. Last, it
//! times the incoherent rays that hit apart from those that miss (1 thread, best of
//! `--runs`): the hitting 28% take nearly all the time.
//! `--dump` also writes the mesh and rays as raw little-endian arrays for
//! `tools/embree_bench.py`, which traces the same rays with Embree. Traversal uses AVX2
//! where the processor has it; `--sse` times the SSE node test instead.
//! `parse` generates a 50 MB scene with one inline `trianglemesh`, a scene naming a
//! 1M-triangle binary PLY, and a scene with 25,000 instances of a 30,000-triangle PLY,
//! then loads each `--runs` times, every run in a fresh process so its peak memory
//! (VmHWM) is its own, and prints the median whole-process time, MB/s and peak memory.
//! When `--peers` holds `pbrt-v3`, it reads the same files in alternate runs (A B A B):
//! they have no `WorldEnd`, so pbrt-v3 parses and creates the shapes, then stops.
//! `load` times load to first pixel on a generated scene of pbrt-v4's scale, beside
//! pbrt-v3 and pbrt-v4 (see `load.rs`).

mod converge;
mod load;
mod stress;
// pbrt-imgtool also reads ERRORS.csv files with it; here only drawing is used.
#[allow(dead_code)]
mod plot;

use pbrt_sppm::scene::{LoadOptions, load_scene};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

fn main() -> ExitCode {
    quiet_on_closed_pipe();
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).is_some_and(|a| a == "--version" || a == "-V") {
        println!("pbrt-bench {}", env!("CARGO_PKG_VERSION"));
        return ExitCode::SUCCESS;
    }
    if let Some(text) = help(&args) {
        print!("{text}");
        return ExitCode::SUCCESS;
    }
    let flag = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).cloned();
    match args.get(1).map(String::as_str) {
        Some("parse") => {
            let runs = flag("--runs").and_then(|r| r.parse().ok()).unwrap_or(5);
            let dir = PathBuf::from(flag("--dir").unwrap_or_else(|| "target/bench-data".into()));
            let peers = PathBuf::from(flag("--peers").unwrap_or_else(|| "../shared/peers".into()));
            parse_bench(&dir, runs, &peers)
        }
        Some("rays") => {
            let runs = flag("--runs").and_then(|r| r.parse().ok()).unwrap_or(5);
            let dir = PathBuf::from(flag("--dir").unwrap_or_else(|| "target/bench-data".into()));
            rays_bench(&dir, runs, args.iter().any(|a| a == "--dump"), args.iter().any(|a| a == "--sse"))
        }
        Some("sppm") => {
            let runs = flag("--runs").and_then(|r| r.parse().ok()).unwrap_or(3);
            let scenes: Vec<PathBuf> = args[2..].iter().filter(|a| a.ends_with(".pbrt")).map(PathBuf::from).collect();
            sppm_bench(scenes, runs)
        }
        Some("converge") => converge::main(&args[2..]),
        Some("load") => load::main(&args[2..]),
        Some("stress") => stress::main(&args[2..]),
        Some("--once") => match args.get(2) {
            Some(scene) => once(Path::new(scene)),
            None => usage(),
        },
        _ => usage(),
    }
}

fn usage() -> ExitCode {
    eprint!("{HELP}");
    ExitCode::FAILURE
}

const HELP: &str = "\
pbrt-bench: benchmarks (whole processes, medians; speed claims live here, never in tests)

Usage: pbrt-bench <COMMAND> [OPTIONS]      (pbrt-bench <COMMAND> --help: its options)

Commands:
  sppm      seconds per SPPM iteration and per million photons, 1 and 2 threads
  converge  error (relMSE) against wall time, ours beside pbrt-v3 and pbrt-v4
  parse     loading speed and peak memory on generated scenes, beside pbrt-v3
  load      load to first pixel on a generated scene of pbrt-v4's scale, beside pbrt-v3 and pbrt-v4
  rays      BVH build and ray throughput on a 1M-triangle mesh
  stress    numerical stress sweeps (spawned rays, closed meshes, grazing rays, furnace)
";

const HELP_SPPM: &str = "\
Usage: pbrt-bench sppm [--runs N] [SCENE.pbrt ...]

Renders each scene (default: pbrt-scenes/v3/*.pbrt) at 1 and 2 threads and prints the
median seconds per iteration and per million photons.
  --runs N   runs per scene and thread count (default 3)
";

const HELP_PARSE: &str = "\
Usage: pbrt-bench parse [--runs N] [--dir DIR] [--peers DIR]

Writes three large scenes (a 50 MB inline mesh, a 1M-triangle binary PLY, 25,000
instances of a 30,000-triangle PLY) into DIR, then loads each in fresh processes and
prints the median time, MB/s and peak memory; pbrt-v3 reads the same files in
alternate runs when DIR holds it.
  --runs N      loads per scene (default 5)
  --dir DIR     where the generated scenes go (default target/bench-data; about 90 MB)
  --peers DIR   where pbrt-v3 is (default ../shared/peers)
";

const HELP_RAYS: &str = "\
Usage: pbrt-bench rays [--runs N] [--dir DIR] [--dump] [--sse]

Builds a 1M-triangle bumpy sphere (through a binary PLY), times the BVH build, then 1M
coherent and 1M incoherent rays, closest and any hit, on 1 and 2 threads.
  --runs N    repetitions, median (default 5)
  --dir DIR   where the PLY goes (default target/bench-data)
  --dump      also write the mesh and rays as raw arrays for tools/embree_bench.py
  --sse       time the SSE node test instead of AVX2
";

/// The help a `--help` (or `-h`, or `help`) asks for, if any: the whole tool's or a
/// command's. Asking never starts a benchmark.
fn help(args: &[String]) -> Option<String> {
    let asked = args.iter().skip(1).any(|a| a == "--help" || a == "-h") || args.get(1).is_some_and(|a| a == "help");
    if !asked {
        return None;
    }
    Some(match args.get(1).map(String::as_str) {
        Some("sppm") => HELP_SPPM.into(),
        Some("parse") => HELP_PARSE.into(),
        Some("rays") => HELP_RAYS.into(),
        Some("converge") => converge::HELP.into(),
        Some("load") => load::HELP.into(),
        Some("stress") => stress::HELP.into(),
        _ => HELP.into(),
    })
}

/// A closed pipe (`pbrt-bench ... | head`) ends the process quietly, as it ends a C
/// tool, instead of panicking in `println!`.
fn quiet_on_closed_pipe() {
    #[cfg(target_os = "linux")]
    // SAFETY: sets the default disposition of one signal before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Loads one scene in this process as `check` does (its files unhashed: hashes are
/// made for a render's fingerprint); prints `seconds peak_kib triangles`.
fn once(scene: &Path) -> ExitCode {
    let start = Instant::now();
    let s = match load_scene(scene, &LoadOptions { skip_input_hashes: true, ..Default::default() }) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let secs = start.elapsed().as_secs_f64();
    let tris: usize = s.meshes.iter().map(|m| m.triangle_count()).sum();
    println!("{secs} {} {tris}", peak_kib());
    ExitCode::SUCCESS
}

fn peak_kib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

fn parse_bench(dir: &Path, runs: usize, peers: &Path) -> ExitCode {
    if let Err(e) = std::fs::create_dir_all(dir) {
        eprintln!("{}: {e}", dir.display());
        return ExitCode::FAILURE;
    }
    let cases = [
        ("inline trianglemesh (50 MB text)", ensure(dir, "inline.pbrt", write_inline_mesh)),
        ("plymesh, 1M triangles (binary)", ensure(dir, "ply1m.pbrt", write_ply_scene)),
        ("25,000 instances of a 30k-triangle PLY", ensure(dir, "instances.pbrt", write_instances)),
    ];
    let pbrt_v3 = std::path::absolute(peers.join("pbrt-v3")).ok().filter(|p| p.is_file());
    match &pbrt_v3 {
        Some(p) => println!("pbrt-v3: {} (whole process, parse and shapes: the files have no WorldEnd)", p.display()),
        None => println!("pbrt-v3: not found in {}; only ours is timed", peers.display()),
    }
    println!(
        "{:<40} {:>6} {:>8} {:>7} {:>9} {:>10} {:>7} {:>9} {:>6}",
        "case", "MB", "ours s", "MB/s", "peak MiB", "pbrt-v3 s", "MB/s", "peak MiB", "ratio"
    );
    for (name, scene) in cases {
        let Ok((scene, bytes)) = scene else {
            eprintln!("could not write the {name} input");
            return ExitCode::FAILURE;
        };
        let (mut ours, mut peer) = (Vec::new(), Vec::new());
        // A B A B: both renderers see the same drift in the machine's speed.
        for _ in 0..runs {
            match load_once(&scene) {
                Ok(r) => ours.push(r),
                Err(e) => {
                    eprintln!("{name}: {e}");
                    return ExitCode::FAILURE;
                }
            }
            if let Some(exe) = &pbrt_v3 {
                match pbrt_v3_parse(exe, &scene) {
                    Ok(r) => peer.push(r),
                    Err(e) => {
                        eprintln!("{name}: pbrt-v3: {e}");
                        return ExitCode::FAILURE;
                    }
                }
            }
        }
        let mb = bytes as f64 / 1e6;
        let (t, kib) = median_and_peak(&mut ours);
        print!("{name:<40} {mb:>6.1} {t:>8.3} {:>7.1} {:>9.1}", mb / t, kib as f64 / 1024.0);
        if peer.is_empty() {
            println!();
        } else {
            let (tp, kp) = median_and_peak(&mut peer);
            println!(" {tp:>10.3} {:>7.1} {:>9.1} {:>5.2}x", mb / tp, kp as f64 / 1024.0, tp / t);
        }
    }
    ExitCode::SUCCESS
}

/// The median seconds and the largest peak memory (KiB) of some runs.
fn median_and_peak(runs: &mut [(f64, u64)]) -> (f64, u64) {
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    (runs[runs.len() / 2].0, runs.iter().map(|r| r.1).max().unwrap_or(0))
}

/// Loads a scene in a fresh process of ours (so its peak memory is its own); the
/// process's wall time from outside, as pbrt-v3's is measured.
fn load_once(scene: &Path) -> Result<(f64, u64), String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let start = Instant::now();
    let out = Command::new(exe).args(["--once", &scene.to_string_lossy()]).output().map_err(|e| e.to_string())?;
    let secs = start.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&out.stdout);
    let v: Vec<f64> = text.split_whitespace().filter_map(|x| x.parse().ok()).collect();
    match v.as_slice() {
        [_, kib, ..] if out.status.success() => Ok((secs, *kib as u64)),
        _ => Err(String::from_utf8_lossy(&out.stderr).into_owned()),
    }
}

/// pbrt-v3 reads a scene without `WorldEnd` (it parses, creates every shape, and
/// stops before building the accelerator or rendering); its wall time and peak memory.
fn pbrt_v3_parse(exe: &Path, scene: &Path) -> Result<(f64, u64), String> {
    let out = std::env::temp_dir().join(format!("pbrt-bench-{}.exr", std::process::id()));
    let start = Instant::now();
    let mut child = Command::new(exe)
        .args(["--quiet", "--nthreads", "2", "--outfile"])
        .arg(&out)
        .arg(scene)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .map_err(|e| e.to_string())?;
    let (status, kib) = wait_with_peak(&mut child)?;
    let secs = start.elapsed().as_secs_f64();
    if !status.success() {
        return Err(format!("exited with {status}"));
    }
    Ok((secs, kib))
}

/// Waits for a child; its peak resident memory (KiB) from the kernel's accounting.
fn wait_with_peak(child: &mut std::process::Child) -> Result<(std::process::ExitStatus, u64), String> {
    #[cfg(target_os = "linux")]
    {
        let (mut status, mut usage) = (0i32, std::mem::MaybeUninit::<libc::rusage>::zeroed());
        // SAFETY: wait4 writes the status and usage of our own child into the pointers.
        let pid = unsafe { libc::wait4(child.id() as i32, &mut status, 0, usage.as_mut_ptr()) };
        if pid < 0 {
            return Err(std::io::Error::last_os_error().to_string());
        }
        // SAFETY: wait4 succeeded, so it filled the struct.
        let usage = unsafe { usage.assume_init() };
        use std::os::unix::process::ExitStatusExt;
        Ok((std::process::ExitStatus::from_raw(status), usage.ru_maxrss as u64))
    }
    #[cfg(not(target_os = "linux"))]
    {
        child.wait().map(|s| (s, 0)).map_err(|e| e.to_string())
    }
}

/// Writes an input once; returns the scene path and the bytes a load reads.
fn ensure(dir: &Path, name: &str, write: fn(&Path) -> std::io::Result<u64>) -> std::io::Result<(PathBuf, u64)> {
    let path = dir.join(name);
    let size_file = dir.join(format!("{name}.bytes"));
    let cached = std::fs::read_to_string(&size_file).ok().and_then(|s| s.trim().parse().ok());
    if let (true, Some(bytes)) = (path.exists(), cached) {
        return Ok((path, bytes));
    }
    let bytes = write(&path)?;
    std::fs::write(size_file, bytes.to_string())?;
    Ok((path, bytes))
}

/// A deterministic pseudo-random stream (xorshift), for vertex jitter.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A grid of `n × n` quads as positions and triangle indices.
fn grid(n: usize) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let p = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| (i, j)))
        .map(|(i, j)| [i as f32 / n as f32, j as f32 / n as f32, 0.0])
        .map(|[x, y, _]| [x, y, rng.next() * 0.01])
        .collect();
    let mut idx = Vec::with_capacity(6 * n * n);
    for j in 0..n {
        for i in 0..n {
            let v = |di: usize, dj: usize| ((j + dj) * (n + 1) + i + di) as u32;
            idx.extend([v(0, 0), v(1, 0), v(1, 1), v(0, 0), v(1, 1), v(0, 1)]);
        }
    }
    (p, idx)
}

fn write_inline_mesh(path: &Path) -> std::io::Result<u64> {
    let (p, idx) = grid(850); // 1.4M triangles, about 50 MB of text
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [")?;
    for v in &p {
        writeln!(w, "{:.6} {:.6} {:.6}", v[0], v[1], v[2])?;
    }
    writeln!(w, "] \"integer indices\" [")?;
    for t in idx.chunks(3) {
        writeln!(w, "{} {} {}", t[0], t[1], t[2])?;
    }
    writeln!(w, "]")?;
    w.flush()?;
    Ok(std::fs::metadata(path)?.len())
}

fn write_ply(path: &Path, n: usize) -> std::io::Result<u64> {
    let (p, idx) = grid(n);
    write_mesh_ply(path, &p, &idx)?;
    Ok(std::fs::metadata(path)?.len())
}

fn write_ply_scene(path: &Path) -> std::io::Result<u64> {
    let ply = path.with_extension("ply");
    let bytes = write_ply(&ply, 708)?; // 1,002,528 triangles
    let name = ply.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    std::fs::write(path, format!("WorldBegin\nShape \"plymesh\" \"string filename\" \"{name}\"\n"))?;
    Ok(bytes + std::fs::metadata(path)?.len())
}

fn write_instances(path: &Path) -> std::io::Result<u64> {
    let ply = path.with_extension("ply");
    let bytes = write_ply(&ply, 123)?;
    let name = ply.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "WorldBegin\nObjectBegin \"g\"\nShape \"plymesh\" \"string filename\" \"{name}\"\nObjectEnd")?;
    for k in 0..25_000 {
        let m =
            [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, (k % 160) as f32, 0.0, (k / 160) as f32, 1.0];
        let m: Vec<String> = m.iter().map(|x| x.to_string()).collect();
        writeln!(w, "AttributeBegin\n  Transform [ {} ]\n  ObjectInstance \"g\"\nAttributeEnd", m.join(" "))?;
    }
    w.flush()?;
    Ok(bytes + std::fs::metadata(path)?.len())
}

/// A sphere of `nt × np` quads with a bumpy radius (2·nt·np triangles).
fn bumpy_sphere(nt: usize, np: usize) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut p = Vec::with_capacity((nt + 1) * np);
    for i in 0..=nt {
        let theta = std::f32::consts::PI * i as f32 / nt as f32;
        for j in 0..np {
            let phi = std::f32::consts::TAU * j as f32 / np as f32;
            let r = 1.0 + 0.05 * (7.0 * theta).sin() * (11.0 * phi).cos();
            p.push([r * theta.sin() * phi.cos(), r * theta.sin() * phi.sin(), r * theta.cos()]);
        }
    }
    let mut idx = Vec::with_capacity(6 * nt * np);
    for i in 0..nt {
        for j in 0..np {
            let v = |di: usize, dj: usize| ((i + di) * np + (j + dj) % np) as u32;
            idx.extend([v(0, 0), v(1, 0), v(1, 1), v(0, 0), v(1, 1), v(0, 1)]);
        }
    }
    (p, idx)
}

fn write_mesh_ply(path: &Path, p: &[[f32; 3]], idx: &[u32]) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        p.len(),
        idx.len() / 3
    )?;
    for v in p {
        for c in v {
            w.write_all(&c.to_le_bytes())?;
        }
    }
    for t in idx.chunks(3) {
        w.write_all(&[3])?;
        for i in t {
            w.write_all(&i.to_le_bytes())?;
        }
    }
    w.flush()
}

fn write_f32s(path: &Path, v: impl Iterator<Item = f32>) -> std::io::Result<()> {
    let bytes: Vec<u8> = v.flat_map(f32::to_le_bytes).collect();
    std::fs::write(path, bytes)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// (coherent camera rays, incoherent random rays), 1M each.
fn ray_sets() -> (Vec<pbrt_sppm::math::Ray>, Vec<pbrt_sppm::math::Ray>) {
    use pbrt_sppm::math::{Point3, Ray, Vector3};
    let res = 1024;
    let tan = (22.5f32).to_radians().tan();
    let camera = (0..res * res)
        .map(|k| {
            let (x, y) = ((k % res) as f32 + 0.5, (k / res) as f32 + 0.5);
            let d = Vector3::new((2.0 * x / res as f32 - 1.0) * tan, (1.0 - 2.0 * y / res as f32) * tan, -1.0);
            Ray::new(Point3::new(0.0, 0.0, 3.0), d)
        })
        .collect();
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let random = (0..res * res)
        .map(|_| {
            let o = Point3::new(3.0 * rng.next() - 1.5, 3.0 * rng.next() - 1.5, 3.0 * rng.next() - 1.5);
            let z = 1.0 - 2.0 * rng.next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * rng.next();
            Ray::new(o, Vector3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect();
    (camera, random)
}

fn rays_bench(dir: &Path, runs: usize, dump: bool, sse: bool) -> ExitCode {
    use pbrt_sppm::accel::Geometry;
    use rayon::prelude::*;
    let (p, idx) = bumpy_sphere(500, 1000);
    let ply = dir.join("bumpy.ply");
    let scene_path = dir.join("bumpy.pbrt");
    let written = std::fs::create_dir_all(dir)
        .and_then(|_| write_mesh_ply(&ply, &p, &idx))
        .and_then(|_| std::fs::write(&scene_path, "WorldBegin\nShape \"plymesh\" \"string filename\" \"bumpy.ply\"\n"));
    if let Err(e) = written {
        eprintln!("{}: {e}", dir.display());
        return ExitCode::FAILURE;
    }
    let scene = match load_scene(&scene_path, &LoadOptions::default()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let tris = scene.meshes[0].triangle_count();
    let mesh_bytes = scene.meshes[0].heap_bytes();
    let build_times: Vec<f64> = (0..runs)
        .map(|_| {
            let s = load_scene(&scene_path, &LoadOptions::default()).unwrap_or_else(|_| scene_clone_empty());
            let t = Instant::now();
            let g = Geometry::new(&s);
            let secs = t.elapsed().as_secs_f64();
            drop(g);
            secs
        })
        .collect();
    let mut geometry = Geometry::new(&scene);
    geometry.set_avx(!sse);
    println!("node test: {}", if geometry.uses_avx() { "AVX2" } else { "SSE" });
    println!(
        "mesh: {tris} triangles, {:.1} bytes/triangle; BVH {:.1} bytes/triangle",
        mesh_bytes as f64 / tris as f64,
        geometry.accel_bytes() as f64 / tris as f64
    );
    println!("BVH build (median of {runs}): {:.3} s; SAH cost {:.2}", median(build_times), geometry.sah_cost());
    let (camera, random) = ray_sets();
    if dump {
        let ok = write_f32s(&dir.join("vertices.f32"), p.iter().flatten().copied())
            .and_then(|_| {
                std::fs::write(dir.join("indices.u32"), idx.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<u8>>())
            })
            .and_then(|_| write_f32s(&dir.join("camera_o.f32"), camera.iter().flat_map(|r| r.o.to_array())))
            .and_then(|_| write_f32s(&dir.join("camera_d.f32"), camera.iter().flat_map(|r| r.d.to_array())))
            .and_then(|_| write_f32s(&dir.join("random_o.f32"), random.iter().flat_map(|r| r.o.to_array())))
            .and_then(|_| write_f32s(&dir.join("random_d.f32"), random.iter().flat_map(|r| r.d.to_array())));
        if let Err(e) = ok {
            eprintln!("dump: {e}");
            return ExitCode::FAILURE;
        }
    }
    println!("{:<22} {:>8} {:>14} {:>14} {:>10}", "rays", "threads", "closest Mray/s", "any-hit Mray/s", "hits");
    for (name, rays) in [("coherent (camera)", &camera), ("incoherent (random)", &random)] {
        for threads in [1usize, 2] {
            let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else {
                return ExitCode::FAILURE;
            };
            let time = |any: bool| -> (f64, usize) {
                let mut hits = 0;
                let secs = median(
                    (0..runs)
                        .map(|_| {
                            let t = Instant::now();
                            hits = pool.install(|| {
                                rays.par_chunks(4096)
                                    .map(|c| {
                                        c.iter()
                                            .filter(|r| {
                                                if any {
                                                    geometry.intersect_p(r)
                                                } else {
                                                    geometry.intersect(r).is_some()
                                                }
                                            })
                                            .count()
                                    })
                                    .sum()
                            });
                            t.elapsed().as_secs_f64()
                        })
                        .collect(),
                );
                (rays.len() as f64 / secs / 1e6, hits)
            };
            let ((closest, hits), (any, any_hits)) = (time(false), time(true));
            if hits != any_hits {
                eprintln!("closest and any-hit disagree: {hits} vs {any_hits}");
                return ExitCode::FAILURE;
            }
            println!("{name:<22} {threads:>8} {closest:>14.2} {any:>14.2} {hits:>10}");
        }
    }
    hit_miss_split(&geometry, &random, runs);
    ExitCode::SUCCESS
}

/// Where incoherent closest-hit time goes: rays that hit against rays that miss, one
/// thread, best of `runs`.
fn hit_miss_split(geometry: &pbrt_sppm::accel::Geometry, rays: &[pbrt_sppm::math::Ray], runs: usize) {
    let (hit, miss): (Vec<_>, Vec<_>) = rays.iter().partition(|r| geometry.intersect(r).is_some());
    for (name, set) in [("hitting", &hit), ("missing", &miss)] {
        let best = (0..runs)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(set.iter().filter(|r| geometry.intersect(r).is_some()).count());
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min);
        let ns = best * 1e9 / set.len().max(1) as f64;
        println!("incoherent, {name} rays only: {} rays, {ns:.0} ns per closest-hit ray", set.len());
    }
}

fn scene_clone_empty() -> pbrt_sppm::scene::SceneDescription {
    pbrt_sppm::scene::load_scene_from_bytes(Path::new("empty.pbrt"), b"WorldBegin".to_vec(), &LoadOptions::default())
        .expect("the empty scene loads")
}

fn sppm_bench(mut scenes: Vec<PathBuf>, runs: usize) -> ExitCode {
    use pbrt_sppm::integrators::RenderSettings;
    use pbrt_sppm::render::RenderScene;
    if scenes.is_empty() {
        scenes = ["sppm-bench", "cornell-glass", "quadric-gallery", "caustic-ring"]
            .iter()
            .map(|n| PathBuf::from(format!("pbrt-scenes/v3/{n}.pbrt")))
            .collect();
    }
    println!(
        "{:<34} {:>7} {:>6} {:>10} {:>10} {:>9} {:>12}",
        "scene", "threads", "iters", "photons", "total s", "s/iter", "s/Mphoton"
    );
    for path in scenes {
        let scene = match load_scene(&path, &LoadOptions::default()) {
            Ok(s) => RenderScene::new(&s),
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::FAILURE;
            }
        };
        for threads in [1usize, 2] {
            let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else {
                return ExitCode::FAILURE;
            };
            let mut times = Vec::new();
            let (mut iters, mut photons) = (0, 0);
            for _ in 0..runs {
                let Ok(out) = pool.install(|| pbrt_sppm::integrators::render(&scene, &RenderSettings::default()))
                else {
                    return ExitCode::FAILURE;
                };
                times.push(out.seconds);
                (iters, photons) = (out.stats.iterations, out.stats.photons.traced);
            }
            let t = median(times);
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            println!(
                "{name:<34} {threads:>7} {iters:>6} {photons:>10} {t:>10.3} {:>9.4} {:>12.3}",
                t / iters.max(1) as f64,
                t / (photons.max(1) as f64 / 1e6)
            );
        }
    }
    ExitCode::SUCCESS
}
