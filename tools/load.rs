//! `pbrt-bench load`: load to first pixel on a generated scene of pbrt-v4's scale, ours
//! beside pbrt-v3 and pbrt-v4 (issue 60).
//!
//! ```text
//! cargo run --release --bin pbrt-bench -- load [--runs 3] [--scale 1] [--dir target/bench-data/load] [--peers ../shared/peers]
//! ```
//!
//! The scene is written once into `--dir` (about 330 MB at scale 1) and nothing large
//! is committed: 192 binary PLY meshes of 65,536 triangles each, placed by the leaves of
//! an `Include` tree seven levels deep; a million instances of four small PLY meshes;
//! four 1024² PNG textures on the meshes' materials. Two top files hold what the two
//! syntaxes spell differently (film, sampler, materials) and include the same rest:
//! `load-v3.pbrt` for pbrt-v3, `load-v4.pbrt` for pbrt-v4 and for us (`--part meshes`
//! and `--part instances` render `meshes-v*.pbrt` and `instances-v*.pbrt`, which
//! include one of the two, to tell their memory apart). Each renders a
//! 32 × 32 image at one sample (ours: one pass of 1,000 light subpaths), so a run is
//! the load, the BVH builds and a first pixel. Runs alternate (ours, pbrt-v3,
//! pbrt-v4, ours, …), each a fresh process: wall time and peak resident memory from
//! outside, medians over `--runs`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::Instant;

pub const HELP: &str = "\
Usage: pbrt-bench load [--runs N] [--scale S] [--part all|meshes|instances] [--dir DIR] [--peers DIR]

Writes a scene of pbrt-v4's scale into DIR (at scale 1: 192 PLY meshes of 65,536
triangles under a 7-level Include tree, a million instances of four small meshes, four
1024x1024 PNG textures; about 330 MB), then renders a 32x32 first pixel of it in fresh
processes, ours beside pbrt-v3 and pbrt-v4 (those found in --peers), alternating, and
prints the median wall time, MB/s and peak memory of each.
  --runs N      runs per renderer (default 3)
  --scale S     meshes and instances times S (default 1; 0.1 for a quick look)
  --part P      render only the meshes or only the instances (default all)
  --dir DIR     where the scene goes (default target/bench-data/load)
  --peers DIR   where pbrt-v3 and pbrt-v4 are (default ../shared/peers)
";

/// How much of each kind the scene holds at a scale.
#[derive(Clone, Copy, Debug)]
struct Size {
    meshes: usize,
    instances: usize,
}

impl Size {
    fn at(scale: f64) -> Size {
        let n = |x: f64| ((x * scale).round() as usize).max(1);
        Size { meshes: n(192.0), instances: n(1e6) }
    }
}

/// Triangles of each big mesh (`bumpy_sphere(128, 256)`) and of each instanced one.
const MESH_TRIANGLES: usize = 2 * 128 * 256;
const INSTANCE_TRIANGLES: usize = 2 * 16 * 64;
/// Levels of the Include tree (2⁷ leaves).
const INCLUDE_DEPTH: u32 = 7;
const TEXTURES: usize = 4;

pub fn main(args: &[String]) -> ExitCode {
    let flag = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).cloned();
    let runs: usize = flag("--runs").and_then(|r| r.parse().ok()).unwrap_or(3).max(1);
    let scale: f64 = flag("--scale").and_then(|r| r.parse().ok()).filter(|s: &f64| *s > 0.0).unwrap_or(1.0);
    let dir = PathBuf::from(flag("--dir").unwrap_or_else(|| "target/bench-data/load".into()));
    let peers = PathBuf::from(flag("--peers").unwrap_or_else(|| "../shared/peers".into()));
    let size = Size::at(scale);
    let part = flag("--part").unwrap_or_else(|| "all".into());
    let Some(prefix) = [("all", "load"), ("meshes", "meshes"), ("instances", "instances")]
        .into_iter()
        .find_map(|(name, prefix)| (name == part).then_some(prefix))
    else {
        eprintln!("--part: expected all, meshes or instances, not \"{part}\"");
        return ExitCode::FAILURE;
    };
    let bytes = match generate(&dir, size) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{}: could not write the scene: {e}", dir.display());
            return ExitCode::FAILURE;
        }
    };
    let triangles = size.meshes * MESH_TRIANGLES;
    println!(
        "scene: {} ({:.0} MB; {} meshes, {:.1}M triangles; {} instances of {} triangles; {TEXTURES} textures)",
        dir.display(),
        bytes as f64 / 1e6,
        size.meshes,
        triangles as f64 / 1e6,
        size.instances,
        INSTANCE_TRIANGLES
    );
    let mut contenders = contenders(&dir, &peers, prefix);
    let raced = race(&mut contenders, runs, &dir);
    let _ = std::fs::remove_file(dir.join(FIRST_PIXEL));
    match raced {
        Ok(results) => {
            report(&results, bytes, (prefix != "instances").then_some(size.meshes * MESH_TRIANGLES));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}

/// The image every contender writes, in the scene's folder (their working directory),
/// removed after the race.
const FIRST_PIXEL: &str = "first-pixel.exr";

/// One renderer: its name and how it renders the scene's first pixel.
struct Contender {
    name: &'static str,
    command: Command,
}

/// Ours (beside this tool) and the peers found, each rendering the top files that
/// begin with `prefix`.
fn contenders(dir: &Path, peers: &Path, prefix: &str) -> Vec<Contender> {
    let mut found = Vec::new();
    if let Ok(exe) = std::env::current_exe() {
        let mut c = Command::new(exe.with_file_name("pbrt-sppm"));
        c.args(["render", "--quiet", "--spp", "1", "--photons", "1000", "--outfile"]).arg(FIRST_PIXEL);
        c.arg(format!("{prefix}-v4.pbrt"));
        found.push(Contender { name: "pbrt-sppm", command: c });
    }
    for (name, version, extra) in [("pbrt-v3", 3, &[][..]), ("pbrt-v4", 4, &["--spp", "1"][..])] {
        let Some(exe) = peers.join(name).canonicalize().ok().filter(|p| p.is_file()) else {
            println!("{name}: not found in {}, left out", peers.display());
            continue;
        };
        let mut c = Command::new(exe);
        c.args(["--quiet", "--nthreads", "2"]).args(extra).arg("--outfile").arg(FIRST_PIXEL);
        c.arg(format!("{prefix}-v{version}.pbrt"));
        found.push(Contender { name, command: c });
    }
    for c in &mut found {
        c.command.current_dir(dir).stdin(Stdio::null()).stdout(Stdio::null());
    }
    found
}

/// A contender's name and the (seconds, peak KiB) of each of its runs.
type Runs = (&'static str, Vec<(f64, u64)>);

/// Each contender's runs, alternating contenders.
fn race(contenders: &mut [Contender], runs: usize, dir: &Path) -> Result<Vec<Runs>, String> {
    let mut results: Vec<_> = contenders.iter().map(|c| (c.name, Vec::new())).collect();
    for _ in 0..runs {
        for (c, r) in contenders.iter_mut().zip(&mut results) {
            // Standard error to a file: a pipe nobody reads while the child runs can
            // fill and stall it.
            let log = dir.join(format!("{}.stderr", c.name));
            let file = std::fs::File::create(&log).map_err(|e| format!("{}: {e}", log.display()))?;
            let start = Instant::now();
            let mut child = c.command.stderr(file).spawn().map_err(|e| format!("{}: {e}", c.name))?;
            let (status, kib) = super::wait_with_peak(&mut child)?;
            let secs = start.elapsed().as_secs_f64();
            if !status.success() {
                let text = std::fs::read_to_string(&log).unwrap_or_default();
                return Err(format!("{} failed in {}: {status}\n{text}", c.name, dir.display()));
            }
            r.1.push((secs, kib));
        }
    }
    Ok(results)
}

/// The table; `triangles`: the big meshes' triangles, for memory per million (none
/// when only the instances are rendered).
fn report(results: &[Runs], bytes: u64, triangles: Option<usize>) {
    let ours = results.iter().find(|r| r.0 == "pbrt-sppm").map(|r| super::median(r.1.iter().map(|x| x.0).collect()));
    println!(
        "{:<10} {:>8} {:>7} {:>9} {:>14} {:>9}",
        "renderer", "median s", "MB/s", "peak MiB", "MiB/M triangles", "s / ours"
    );
    for (name, runs) in results {
        let mut runs = runs.clone();
        let (t, kib) = super::median_and_peak(&mut runs);
        let mib = kib as f64 / 1024.0;
        let ratio = ours.map_or(f64::NAN, |o| t / o);
        // Not defined when only the instances are rendered.
        let per_m = triangles.map_or("—".to_string(), |n| format!("{:.1}", mib / (n as f64 / 1e6)));
        println!("{name:<10} {t:>8.2} {:>7.0} {mib:>9.0} {per_m:>14} {ratio:>9.2}", bytes as f64 / 1e6 / t);
    }
    println!("(every run: {})", results.first().map_or(0, |r| r.1.len()));
}

/// Writes the scene into `dir` unless a complete one of this size is there; returns its
/// bytes (every file a load reads).
fn generate(dir: &Path, size: Size) -> std::io::Result<u64> {
    std::fs::create_dir_all(dir)?;
    let stamp = dir.join("complete");
    let want = format!("{} {}", size.meshes, size.instances);
    if let Ok(s) = std::fs::read_to_string(&stamp)
        && let Some((have, bytes)) = s.rsplit_once(' ')
        && have == want
        && let Ok(bytes) = bytes.trim().parse()
    {
        // The top files are small: written every time, so they follow this tool.
        write_tops(dir)?;
        return Ok(bytes);
    }
    let _ = std::fs::remove_file(&stamp);
    write_meshes(dir, size)?;
    write_include_tree(dir, size)?;
    write_instances(dir, size)?;
    write_textures(dir)?;
    write_tops(dir)?;
    let bytes = std::fs::read_dir(dir)?
        .filter_map(Result::ok)
        .filter(|e| e.file_name() != "complete" && !e.file_name().to_string_lossy().ends_with(".stderr"))
        .filter_map(|e| e.metadata().ok())
        .map(|m| m.len())
        .sum();
    std::fs::write(stamp, format!("{want} {bytes}"))?;
    Ok(bytes)
}

/// The big meshes (`m-K.ply`, each a bumpy sphere of its own bumps) and the instanced
/// ones (`i-J.ply`).
fn write_meshes(dir: &Path, size: Size) -> std::io::Result<()> {
    for k in 0..size.meshes {
        let (p, idx) = super::bumpy_sphere(128, 256);
        let s = 1.0 + 0.02 * (k % 7) as f32;
        let p: Vec<[f32; 3]> = p.iter().map(|v| [v[0] * s, v[1] * s, v[2]]).collect();
        super::write_mesh_ply(&dir.join(format!("m-{k}.ply")), &p, &idx)?;
    }
    for j in 0..4 {
        let (p, idx) = super::bumpy_sphere(16, 64);
        let p: Vec<[f32; 3]> = p.iter().map(|v| [v[0], v[1] * (1.0 + j as f32 * 0.3), v[2]]).collect();
        super::write_mesh_ply(&dir.join(format!("i-{j}.ply")), &p, &idx)?;
    }
    Ok(())
}

/// `tree.pbrt` includes two files a level down, down to [`INCLUDE_DEPTH`] levels; the
/// leaves (named by their path, `tree-0110101.pbrt`) place the big meshes in turn.
fn write_include_tree(dir: &Path, size: Size) -> std::io::Result<()> {
    let leaves = 1usize << INCLUDE_DEPTH;
    for level in 0..=INCLUDE_DEPTH {
        for node in 0..1usize << level {
            let name = tree_name(level, node);
            let mut w = std::io::BufWriter::new(std::fs::File::create(dir.join(&name))?);
            if level < INCLUDE_DEPTH {
                for child in [2 * node, 2 * node + 1] {
                    writeln!(w, "AttributeBegin\n  Include \"{}\"\nAttributeEnd", tree_name(level + 1, child))?;
                }
            } else {
                for k in (node..size.meshes).step_by(leaves) {
                    let (x, z) = ((k % 16) as f32 * 3.0 - 24.0, (k / 16) as f32 * 3.0 - 18.0);
                    writeln!(
                        w,
                        "AttributeBegin\n  Translate {x} 1 {z}\n  NamedMaterial \"m{}\"\n  \
                         Shape \"plymesh\" \"string filename\" \"m-{k}.ply\"\nAttributeEnd",
                        k % TEXTURES
                    )?;
                }
            }
            w.flush()?;
        }
    }
    Ok(())
}

fn tree_name(level: u32, node: usize) -> String {
    match level {
        0 => "tree.pbrt".into(),
        _ => format!("tree-{node:0width$b}.pbrt", width = level as usize),
    }
}

/// Four objects of one small mesh each, and `instances.pbrt`: a grid of instances
/// of them, each under its own translation.
fn write_instances(dir: &Path, size: Size) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(dir.join("instances.pbrt"))?);
    for j in 0..4 {
        writeln!(
            w,
            "ObjectBegin \"o{j}\"\n  NamedMaterial \"m{j}\"\n  Shape \"plymesh\" \"string filename\" \"i-{j}.ply\"\nObjectEnd"
        )?;
    }
    let side = (size.instances as f64).sqrt().ceil() as usize;
    for k in 0..size.instances {
        let (x, z) = ((k % side) as f32 * 0.25, (k / side) as f32 * 0.25);
        writeln!(w, "AttributeBegin Translate {x} 0 {z} ObjectInstance \"o{}\" AttributeEnd", k % 4)?;
    }
    w.flush()
}

/// Four 1024² PNG textures of coloured noise.
fn write_textures(dir: &Path) -> std::io::Result<()> {
    for j in 0..TEXTURES {
        let mut rng = super::Rng(0x5851_f42d_4c95_7f2d ^ j as u64);
        let img = image::RgbImage::from_fn(1024, 1024, |_, _| {
            image::Rgb([(rng.next() * 255.0) as u8, (rng.next() * 255.0) as u8, (rng.next() * 255.0) as u8])
        });
        img.save(dir.join(format!("tex-{j}.png"))).map_err(std::io::Error::other)?;
    }
    Ok(())
}

/// The top files, two per part (pbrt-v3's and pbrt-v4's): what the two spell
/// differently, then the same includes.
fn write_tops(dir: &Path) -> std::io::Result<()> {
    for (prefix, includes) in [
        ("load", &["tree.pbrt", "instances.pbrt"][..]),
        ("meshes", &["tree.pbrt"][..]),
        ("instances", &["instances.pbrt"][..]),
    ] {
        write_top(dir, prefix, includes)?;
    }
    Ok(())
}

fn write_top(dir: &Path, prefix: &str, includes: &[&str]) -> std::io::Result<()> {
    let view = "LookAt 0 60 -60  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n";
    for (version, film, sampler, material, kd, point) in
        [(3, "image", "random", "matte", "Kd", "point"), (4, "rgb", "independent", "diffuse", "reflectance", "point3")]
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(dir.join(format!("{prefix}-v{version}.pbrt")))?);
        write!(w, "{view}")?;
        writeln!(w, "Film \"{film}\" \"integer xresolution\" 32 \"integer yresolution\" 32")?;
        writeln!(w, "Sampler \"{sampler}\" \"integer pixelsamples\" 1")?;
        writeln!(w, "Integrator \"path\" \"integer maxdepth\" 1\nWorldBegin")?;
        writeln!(w, "LightSource \"distant\" \"{point} from\" [0 1 -1] \"{point} to\" [0 0 0]")?;
        for j in 0..TEXTURES {
            writeln!(w, "Texture \"t{j}\" \"spectrum\" \"imagemap\" \"string filename\" \"tex-{j}.png\"")?;
            writeln!(w, "MakeNamedMaterial \"m{j}\" \"string type\" \"{material}\" \"texture {kd}\" \"t{j}\"")?;
        }
        for file in includes {
            writeln!(w, "Include \"{file}\"")?;
        }
        // pbrt-v4 has no WorldEnd: its scene ends with the file.
        if film == "image" {
            writeln!(w, "WorldEnd")?;
        }
        w.flush()?;
    }
    Ok(())
}
