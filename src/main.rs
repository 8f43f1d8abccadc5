//! The `pbrt-sppm` command line: `[render] SCENE`, `check SCENE`, `trace SCENE`,
//! `export --mitsuba SCENE`.

use clap::{Parser, Subcommand};
use pbrt_sppm::parser::Syntax;
use pbrt_sppm::parser::error::LoadError;
use pbrt_sppm::scene::{LoadOptions, SceneDescription, load_scene};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "pbrt-sppm", version, about = "Renders pbrt-v3/v4 scenes with stochastic progressive photon mapping")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (the default when the first argument is a file).
    Render(RenderArgs),
    /// Parse and build a scene without rendering; report what it contains.
    Check {
        scene: PathBuf,
        /// Print one JSON object (design.md §3) instead of a summary.
        #[arg(long)]
        json: bool,
        /// Add one entry per created shape to the JSON.
        #[arg(long)]
        shapes: bool,
        #[command(flatten)]
        common: Common,
    },
    /// Write the loaded scene for another renderer (README: "Cross-checking with Mitsuba 3").
    Export {
        scene: PathBuf,
        /// The JSON form `tools/mitsuba_reference.py` reads (the only format so far).
        #[arg(long, required = true)]
        mitsuba: bool,
        /// Write here instead of standard output.
        #[arg(long, short)]
        output: Option<PathBuf>,
        #[command(flatten)]
        common: Common,
    },
    /// Intersect rays (`ox oy oz dx dy dz [tmax]` per line) with the scene; JSON lines out.
    Trace {
        scene: PathBuf,
        /// Read rays from this file instead of standard input.
        #[arg(long)]
        rays: Option<PathBuf>,
        #[command(flatten)]
        common: Common,
    },
}

#[derive(clap::Args)]
struct Common {
    /// Read the file as pbrt-v3 or pbrt-v4 syntax instead of detecting it.
    #[arg(long, value_parser = parse_syntax)]
    syntax: Option<Syntax>,
}

#[derive(clap::Args)]
struct RenderArgs {
    scene: PathBuf,
    #[arg(long)]
    outfile: Option<PathBuf>,
    #[arg(long)]
    nthreads: Option<usize>,
    #[arg(long)]
    seed: Option<u64>,
    /// SPPM iterations.
    #[arg(long, alias = "iterations")]
    spp: Option<u32>,
    #[arg(long)]
    quick: bool,
    #[arg(long)]
    stats: bool,
    #[arg(long)]
    photons: Option<u64>,
    #[arg(long)]
    radius: Option<f32>,
    #[arg(long)]
    time_limit: Option<f64>,
    #[arg(long)]
    mse_reference_image: Option<PathBuf>,
    #[arg(long)]
    mse_reference_out: Option<PathBuf>,
    #[command(flatten)]
    common: Common,
}

fn parse_syntax(s: &str) -> Result<Syntax, String> {
    match s {
        "v3" => Ok(Syntax::V3),
        "v4" => Ok(Syntax::V4),
        _ => Err(format!("expected v3 or v4, not \"{s}\"")),
    }
}

/// `pbrt-sppm scene.pbrt ...` means `pbrt-sppm render scene.pbrt ...`.
fn with_default_subcommand(mut args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    const KNOWN: [&str; 9] = ["render", "check", "trace", "export", "help", "--help", "-h", "--version", "-V"];
    if args.len() > 1 && !KNOWN.iter().any(|k| args[1] == *k) {
        args.insert(1, "render".into());
    }
    args
}

fn load(scene: &std::path::Path, common: &Common) -> Result<SceneDescription, ExitCode> {
    load_scene(scene, &LoadOptions { syntax: common.syntax }).map_err(|e| report_error(&e))
}

fn report_error(e: &LoadError) -> ExitCode {
    let text = if std::io::stderr().is_terminal() { e.with_source() } else { e.one_line() };
    eprintln!("{text}");
    ExitCode::FAILURE
}

fn main() -> ExitCode {
    let cli = Cli::parse_from(with_default_subcommand(std::env::args_os().collect()));
    match cli.command {
        Command::Check { scene, json, shapes, common } => {
            let s = match load(&scene, &common) {
                Ok(s) => s,
                Err(code) => return code,
            };
            if json {
                let report = pbrt_sppm::check::report(&s, shapes);
                println!("{}", serde_json::to_string_pretty(&report).unwrap_or_default());
            } else {
                s.warnings.iter().for_each(|w| eprintln!("{w}"));
                print_summary(&s);
            }
            ExitCode::SUCCESS
        }
        Command::Trace { scene, rays, common } => match load(&scene, &common) {
            Ok(s) => trace(s, rays),
            Err(code) => code,
        },
        Command::Export { scene, mitsuba: _, output, common } => match load(&scene, &common) {
            Ok(s) => export(&s, &scene, output),
            Err(code) => code,
        },
        Command::Render(args) => match load(&args.scene, &args.common) {
            Ok(s) => render(s, &args),
            Err(code) => code,
        },
    }
}

fn fail(file: &std::path::Path, message: impl std::fmt::Display) -> ExitCode {
    eprintln!("{}: error: {message}", file.display());
    ExitCode::FAILURE
}

/// Renders a loaded scene and writes the image (and ERRORS.csv).
fn render(scene: SceneDescription, args: &RenderArgs) -> ExitCode {
    use pbrt_sppm::imageio::{read_image, write_image};
    use pbrt_sppm::render::{RenderScene, RenderSettings, errors_csv};
    let terminal = std::io::stderr().is_terminal();
    scene.warnings.iter().for_each(|w| eprintln!("{w}"));
    if scene.lights.is_empty() && scene.area_lights.is_empty() {
        eprintln!("{}: warning: the scene has no lights; the image will be black", args.scene.display());
    }
    let reference = match &args.mse_reference_image {
        Some(p) => match read_image(p) {
            Ok(img) => Some(img),
            Err(e) => return fail(p, e),
        },
        None => None,
    };
    let outfile = args.outfile.clone().unwrap_or_else(|| PathBuf::from(&scene.film.filename));
    let settings = RenderSettings {
        iterations: args.spp,
        photons: args.photons,
        radius: args.radius,
        seed: args.seed,
        quick: args.quick,
        time_limit: args.time_limit,
        reference,
        progress: terminal,
    };
    let threads = args.nthreads.unwrap_or(0);
    let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(p) => p,
        Err(e) => return fail(&args.scene, e),
    };
    let scene_path = args.scene.display().to_string();
    let rs = RenderScene::new(scene);
    rs.warnings.iter().for_each(|w| eprintln!("{scene_path}: warning: {w}"));
    let out = match pool.install(|| rs.render(&settings)) {
        Ok(o) => o,
        Err(e) => return fail(&args.scene, e),
    };
    if let Err(e) = write_image(&outfile, &out.image) {
        return fail(&outfile, e);
    }
    if let Some(csv) = &args.mse_reference_out
        && let Err(e) = pbrt_sppm::imageio::write_text(csv, &errors_csv(&out.errors))
    {
        return fail(csv, e);
    }
    if out.stats.visible_points == 0 {
        eprintln!(
            "{}: warning: no camera path reached a diffuse surface; the image holds only direct emission",
            args.scene.display()
        );
    }
    if args.stats {
        print_stats(&out);
    }
    eprintln!(
        "rendered {} iterations ({} photons each) in {:.2} s -> {}",
        out.stats.iterations,
        out.image.meta.photons_per_iteration.unwrap_or(0),
        out.seconds,
        outfile.display()
    );
    ExitCode::SUCCESS
}

fn print_stats(out: &pbrt_sppm::render::RenderOutput) {
    let s = &out.stats;
    let peak = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|t| t.lines().find_map(|l| l.strip_prefix("VmHWM:").map(|v| v.trim().to_string())))
        .unwrap_or_else(|| "unknown".into());
    eprintln!(
        "stats: camera pass {:.3} s, grid {:.3} s, photons {:.3} s, update {:.3} s",
        s.camera_seconds, s.grid_seconds, s.photon_seconds, s.update_seconds
    );
    eprintln!(
        "stats: {} camera paths, {} photon paths, {} photon hits, peak memory {peak}",
        s.camera_rays, s.photon_paths, s.photon_hits
    );
}

/// Writes the Mitsuba export; what cannot go over is also warned about on stderr.
fn export(s: &SceneDescription, scene: &std::path::Path, output: Option<PathBuf>) -> ExitCode {
    s.warnings.iter().for_each(|w| eprintln!("{w}"));
    let e = pbrt_sppm::export::mitsuba(s, &scene.display().to_string());
    for u in &e.unsupported {
        let at = if u.location.is_empty() { scene.display().to_string() } else { u.location.clone() };
        eprintln!("{at}: warning: export: {}: {}", u.what, u.why);
    }
    let text = match serde_json::to_string(&e) {
        Ok(t) => t + "\n",
        Err(err) => return fail(scene, err),
    };
    match output {
        Some(path) => match pbrt_sppm::imageio::write_text(&path, &text) {
            Ok(()) => ExitCode::SUCCESS,
            Err(err) => fail(&path, err),
        },
        None => {
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            if out.write_all(text.as_bytes()).and_then(|()| out.flush()).is_err() {
                return ExitCode::FAILURE;
            }
            ExitCode::SUCCESS
        }
    }
}

/// Answers ray queries line by line; a malformed line is an error naming the line.
fn trace(scene: SceneDescription, rays: Option<PathBuf>) -> ExitCode {
    use std::io::{BufRead, Write};
    let name = rays.as_ref().map_or("<stdin>".to_string(), |p| p.display().to_string());
    let input: Box<dyn BufRead> = match &rays {
        Some(p) => match std::fs::File::open(p) {
            Ok(f) => Box::new(std::io::BufReader::new(f)),
            Err(e) => {
                eprintln!("{name}: error: cannot read: {e}");
                return ExitCode::FAILURE;
            }
        },
        None => Box::new(std::io::stdin().lock()),
    };
    let tracer = pbrt_sppm::trace::Tracer::new(scene);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for (i, line) in input.lines().enumerate() {
        let result = line.map_err(|e| e.to_string()).and_then(|l| tracer.line(&l));
        match result {
            Ok(Some(v)) => {
                if writeln!(out, "{v}").is_err() {
                    return ExitCode::FAILURE;
                }
            }
            Ok(None) => {}
            Err(e) => {
                let _ = out.flush();
                eprintln!("{name}:{}: error: {e}", i + 1);
                return ExitCode::FAILURE;
            }
        }
    }
    if out.flush().is_err() { ExitCode::FAILURE } else { ExitCode::SUCCESS }
}

fn print_summary(s: &SceneDescription) {
    let r = pbrt_sppm::check::report(s, false);
    println!("syntax      {}", s.syntax.name());
    println!("film        {}x{} -> {}", s.film.x_resolution, s.film.y_resolution, s.film.filename);
    let i = &s.integrator;
    println!(
        "sppm        {} iterations, maxdepth {}, {} photons/iteration, radius {}",
        i.iterations, i.max_depth, i.photons_per_iteration, i.radius
    );
    if let Some(c) = r["counts"].as_object() {
        let parts: Vec<String> =
            c.iter().filter(|(_, v)| v.as_u64() != Some(0)).map(|(k, v)| format!("{k} {v}")).collect();
        println!("counts      {}", parts.join(", "));
    }
    for k in &s.skipped {
        println!("skipped     {}:{}:{}: {} ({})", k.file, k.line, k.column, k.what, k.why);
    }
}
