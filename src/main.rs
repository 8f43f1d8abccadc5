//! The `pbrt-sppm` command line: `[render] SCENE`, `check SCENE`, `trace SCENE`,
//! `export --mitsuba SCENE`. A scene named `-` is read from standard input.

use clap::{Parser, Subcommand};
use pbrt_sppm::fixes::Fixes;
use pbrt_sppm::integrators::adaptive::PhotonSampling;
use pbrt_sppm::integrators::checkpoint::{Checkpoint, Every, Fingerprint};
use pbrt_sppm::integrators::part::Part;
use pbrt_sppm::integrators::passes::{DEFAULT_ALPHA, PassMode};
use pbrt_sppm::integrators::{CheckpointTarget, Plan, RenderOutput, RenderSettings};
use pbrt_sppm::limits::Limits;
use pbrt_sppm::parser::Syntax;
use pbrt_sppm::parser::error::LoadError;
use pbrt_sppm::render::RenderScene;
use pbrt_sppm::sampling::SamplerKind;
use pbrt_sppm::scene::{LoadOptions, SceneDescription, load_scene, load_scene_from_bytes};
use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

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
        /// The scene file (`-` reads standard input).
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
        /// The scene file (`-` reads standard input).
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
    /// Add up the parts of a render (`render --partial`) into its image.
    Merge {
        /// The parts: files written by `render --partial` or `merge --partial`.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// The image to write (`.exr`, or `.png` for an 8-bit sRGB preview).
        #[arg(long, required_unless_present = "partial")]
        outfile: Option<PathBuf>,
        /// Also write the merged part (all the passes summed), to merge with others later.
        #[arg(long, value_name = "FILE.exr")]
        partial: Option<PathBuf>,
        /// Merge even when some passes of the render are in no part (a warning then).
        #[arg(long)]
        allow_gaps: bool,
        /// Print no warnings and no summary.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Print the commands that render a scene in shards on a cluster and merge them.
    Plan(PlanArgs),
    /// Intersect rays (`ox oy oz dx dy dz [tmax]` per line) with the scene; JSON lines out.
    Trace {
        /// The scene file (`-` reads standard input; then give the rays with --rays).
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
    /// Raise or lower a limit, NAME=N (pixels, photons, iterations, maxdepth, file-bytes,
    /// texture-pixels, include-depth, triangles); may be repeated.
    #[arg(long = "limit", value_name = "NAME=N")]
    limits: Vec<String>,
    /// Print no warnings and no summary (errors still go to standard error).
    #[arg(long, short)]
    quiet: bool,
    /// Fix these pbrt bugs instead of rendering them as the file's pbrt does:
    /// NAME,... or `all` (`--fix help` lists them; `check` says which a scene shows).
    #[arg(long = "fix", value_name = "NAME,...|all|help", value_parser = parse_fixes)]
    fixes: Option<Fixes>,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file (`-` reads standard input).
    scene: PathBuf,
    /// The image to write (`.exr`, or `.png` for an 8-bit sRGB preview); default: the
    /// Film's `filename`.
    #[arg(long)]
    outfile: Option<PathBuf>,
    /// Worker threads (0, the default, uses every core).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<usize, 0>)]
    nthreads: Option<usize>,
    /// The seed every random number derives from (default: the Integrator's `seed`).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<u64, 0>)]
    seed: Option<u64>,
    /// What drives camera and photon paths: `sobol` (scrambled low-discrepancy points,
    /// the default) or `random` (independent random numbers).
    #[arg(long, value_parser = parse_sampler)]
    sampler: Option<SamplerKind>,
    /// How photon paths are drawn: `uniform` (independent photons, as pbrt; the
    /// default) or `adaptive` (Markov chains over paths that reach what the camera
    /// sees, for scenes where most photons land out of view).
    #[arg(long, value_parser = parse_photon_sampling)]
    photon_sampling: Option<PhotonSampling>,
    /// SPPM iterations (at least 1), overriding the scene's.
    #[arg(long, visible_alias = "iterations", allow_negative_numbers = true, value_parser = parse_count::<u32, 1>)]
    spp: Option<u32>,
    /// Divide the iteration count by 16 (at least 1 remains), as pbrt-v3 does.
    #[arg(long)]
    quick: bool,
    /// Print the time per phase, the paths traced and the peak memory.
    #[arg(long)]
    stats: bool,
    /// Photons per iteration (at least 1), overriding `photonsperiteration`.
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<u64, 1>)]
    photons: Option<u64>,
    /// The initial photon radius (positive), overriding `radius`.
    #[arg(long, allow_negative_numbers = true, value_parser = parse_positive)]
    radius: Option<f32>,
    /// Stop after the iteration that passes this many seconds (positive).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_positive)]
    time_limit: Option<f32>,
    /// Compare every iteration with this image (needs --mse-reference-out).
    #[arg(long, requires = "mse_reference_out")]
    mse_reference_image: Option<PathBuf>,
    /// Write the per-iteration errors (ERRORS.csv) here (needs --mse-reference-image).
    #[arg(long, requires = "mse_reference_image")]
    mse_reference_out: Option<PathBuf>,
    /// Save the render's state to this file as it goes, at the end, and when
    /// interrupted (Ctrl-C, SIGTERM), so that `--resume` can continue it.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// How often to save: a number of iterations (`10`) or a time (`90s`, `5m`, `2h`);
    /// default 5m.
    #[arg(long, value_name = "N|TIME", value_parser = parse_every)]
    checkpoint_every: Option<Every>,
    /// Continue the render saved in this checkpoint (made from the same scene files and
    /// settings); it goes on saving there unless --checkpoint names another file.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Write the image after iterations 1, 2, 4, 8, … as well as at the end.
    #[arg(long)]
    write_partial_images: bool,
    /// `classic` (pbrt's SPPM, the default) or `independent` (Knaus–Zwicker: each
    /// pass's radius depends only on its index, so passes can be rendered apart and
    /// merged).
    #[arg(long, value_parser = parse_passes)]
    passes: Option<bool>,
    /// How fast independent passes' radius shrinks: r²_{i+1} = r²_i (i+α)/(i+1), 0 < α < 1
    /// (default 2/3).
    #[arg(long, value_parser = parse_alpha)]
    alpha: Option<f64>,
    /// Render only passes A to B−1 of the --spp planned (independent passes).
    #[arg(long, value_name = "A..B", value_parser = parse_pass_range)]
    pass_range: Option<std::ops::Range<u32>>,
    /// Write the sum of the passes rendered to this EXR, for `pbrt-sppm merge`
    /// (independent passes; the image itself is written only when --outfile is given).
    #[arg(long, value_name = "FILE.exr")]
    partial: Option<PathBuf>,
    #[command(flatten)]
    common: Common,
}

#[derive(clap::Args)]
struct PlanArgs {
    /// The scene file.
    scene: PathBuf,
    /// Plan for Slurm: an array job of shards, then a merge job once all succeed.
    #[arg(long, required = true)]
    slurm: bool,
    /// The passes of the whole render (its --spp).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<u32, 1>)]
    passes: u32,
    /// How many shards (array tasks) share them (at most --passes).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<u32, 1>)]
    shards: u32,
    /// The folder the parts are written to, which every node must reach (default:
    /// SCENE's name with `.parts`, beside it).
    #[arg(long)]
    parts: Option<PathBuf>,
    /// The merged image (default: SCENE's name with `.exr`, beside it).
    #[arg(long)]
    outfile: Option<PathBuf>,
    /// Cores per shard (sbatch --cpus-per-task; the shard renders with as many threads).
    #[arg(long, default_value_t = 1, value_parser = parse_count::<u32, 1>)]
    cpus_per_task: u32,
    /// The pbrt-sppm the nodes run (default: this one).
    #[arg(long)]
    binary: Option<PathBuf>,
    /// Write the script to this file instead of standard output.
    #[arg(long)]
    write: Option<PathBuf>,
    /// Render options every shard gets, after `--` (such as `-- --photons 200000`).
    #[arg(last = true)]
    render_args: Vec<String>,
}

fn parse_fixes(s: &str) -> Result<Fixes, String> {
    Fixes::parse(s)
}

fn parse_syntax(s: &str) -> Result<Syntax, String> {
    match s {
        "v3" => Ok(Syntax::V3),
        "v4" => Ok(Syntax::V4),
        _ => Err(format!("expected v3 or v4, not \"{s}\"")),
    }
}

fn parse_photon_sampling(s: &str) -> Result<PhotonSampling, String> {
    match s {
        "uniform" => Ok(PhotonSampling::Uniform),
        "adaptive" => Ok(PhotonSampling::Adaptive),
        _ => Err(format!("expected uniform or adaptive, not \"{s}\"")),
    }
}

/// `independent` → true.
fn parse_passes(s: &str) -> Result<bool, String> {
    match s {
        "classic" => Ok(false),
        "independent" => Ok(true),
        _ => Err(format!("expected classic or independent, not \"{s}\"")),
    }
}

fn parse_alpha(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(a) if a > 0.0 && a < 1.0 => Ok(a),
        _ => Err(format!("must be a number between 0 and 1 (exclusive), not {s}")),
    }
}

fn parse_pass_range(s: &str) -> Result<std::ops::Range<u32>, String> {
    pbrt_sppm::integrators::passes::parse_range(s)
}

fn parse_every(s: &str) -> Result<Every, String> {
    s.parse()
}

fn parse_sampler(s: &str) -> Result<SamplerKind, String> {
    match s {
        "sobol" => Ok(SamplerKind::Sobol),
        "random" => Ok(SamplerKind::Random),
        _ => Err(format!("expected sobol or random, not \"{s}\"")),
    }
}

/// A whole number of at least `MIN`.
fn parse_count<T: TryFrom<u64>, const MIN: u64>(s: &str) -> Result<T, String> {
    let n: i128 = s.trim().parse().map_err(|_| format!("\"{s}\" is not a whole number"))?;
    if n < MIN as i128 {
        return Err(format!("must be at least {MIN}, not {n}"));
    }
    u64::try_from(n).ok().and_then(|n| T::try_from(n).ok()).ok_or_else(|| format!("{n} is too large"))
}

fn parse_positive(s: &str) -> Result<f32, String> {
    let v: f32 = s.trim().parse().map_err(|_| format!("\"{s}\" is not a number"))?;
    if v > 0.0 && v.is_finite() { Ok(v) } else { Err(format!("must be a positive number, not {s}")) }
}

/// `pbrt-sppm scene.pbrt ...` means `pbrt-sppm render scene.pbrt ...`.
fn with_default_subcommand(mut args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    const KNOWN: [&str; 11] =
        ["render", "check", "trace", "export", "merge", "plan", "help", "--help", "-h", "--version", "-V"];
    if args.len() > 1 && !KNOWN.iter().any(|k| args[1] == *k) {
        args.insert(1, "render".into());
    }
    args
}

/// Whether the arguments hold `--fix help` (or `--fix=help`), which lists the fixes
/// whatever else is given.
fn asks_fix_help(args: impl Iterator<Item = std::ffi::OsString>) -> bool {
    let mut prev_fix = false;
    for a in args {
        if (prev_fix && a == "help") || a == "--fix=help" {
            return true;
        }
        prev_fix = a == "--fix";
    }
    false
}

/// Writes a line to standard error; a closed stderr is not worth a panic.
macro_rules! say {
    ($($t:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

fn load(scene: &Path, common: &Common) -> Result<SceneDescription, ExitCode> {
    let mut limits = Limits::default();
    for spec in &common.limits {
        if let Err(e) = limits.set(spec) {
            return Err(fail(Path::new("--limit"), e));
        }
    }
    let fixes = common.fixes.unwrap_or_default();
    let opts = LoadOptions { syntax: common.syntax, limits, fixes, ..Default::default() };
    let loaded = if scene.as_os_str() == "-" {
        let mut bytes = Vec::new();
        let max = limits.file_bytes;
        if let Err(e) = std::io::stdin().lock().take(max + 1).read_to_end(&mut bytes) {
            return Err(fail(Path::new("<stdin>"), format!("cannot read: {e}")));
        }
        if bytes.len() as u64 > max {
            return Err(fail(Path::new("<stdin>"), Limits::over("the scene", "file-bytes", max)));
        }
        pbrt_sppm::limits::note_input(Path::new("<stdin>"), &bytes);
        // Relative names in a scene from standard input resolve against the current folder.
        load_scene_from_bytes(Path::new("<stdin>"), bytes, &opts)
    } else {
        load_scene(scene, &opts)
    };
    let s = loaded.map_err(|e| report_error(&e))?;
    if !common.quiet {
        s.warnings.iter().for_each(|w| say!("{w}"));
    }
    Ok(s)
}

fn report_error(e: &LoadError) -> ExitCode {
    let text = if std::io::stderr().is_terminal() { e.with_source() } else { e.one_line() };
    say!("{text}");
    ExitCode::FAILURE
}

fn fail(file: &Path, message: impl std::fmt::Display) -> ExitCode {
    say!("{}: error: {message}", file.display());
    ExitCode::FAILURE
}

/// Standard output that reports a failed write (a full disk, a closed pipe) as an error.
fn print(text: &str) -> ExitCode {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(Path::new("<stdout>"), format!("cannot write: {e}")),
    }
}

fn main() -> ExitCode {
    if asks_fix_help(std::env::args_os().skip(1)) {
        return print(&Fixes::help());
    }
    let cli = Cli::parse_from(with_default_subcommand(std::env::args_os().collect()));
    match cli.command {
        Command::Check { scene, json, shapes, common } => match load(&scene, &common) {
            Ok(s) if json => {
                let report = pbrt_sppm::check::report(&s, shapes);
                print(&(serde_json::to_string_pretty(&report).unwrap_or_default() + "\n"))
            }
            Ok(s) => print(&summary(&s)),
            Err(code) => code,
        },
        Command::Trace { scene, rays, common } => match load(&scene, &common) {
            Ok(s) => trace(s, rays),
            Err(code) => code,
        },
        Command::Export { scene, mitsuba: _, output, common } => match load(&scene, &common) {
            Ok(s) => export(&s, &scene, output, common.quiet),
            Err(code) => code,
        },
        Command::Merge { parts, outfile, partial, allow_gaps, quiet } => {
            merge(&parts, outfile.as_deref(), partial.as_deref(), allow_gaps, quiet)
        }
        Command::Plan(args) => plan(&args),
        Command::Render(args) => match load(&args.scene, &args.common) {
            Ok(s) => render(s, &args),
            Err(code) => code,
        },
    }
}

/// Where the image goes and what to blame when it cannot: `--outfile`, or the Film's
/// `filename` parameter at its location.
fn output_path(scene: &SceneDescription, args: &RenderArgs) -> (PathBuf, String) {
    match &args.outfile {
        Some(p) => (p.clone(), "--outfile".to_string()),
        None => {
            let at = scene.film.filename_location.clone().unwrap_or_else(|| "Film \"filename\"".into());
            (PathBuf::from(&scene.film.filename), at)
        }
    }
}

/// Checks an output path before any work: a known extension, and a folder we can write
/// a file in (the temporary file is made and removed).
fn check_output(path: &Path, image: bool) -> Result<(), String> {
    if image {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("exr" | "png")) {
            return Err(format!("\"{}\": the image must end in .exr or .png", path.display()));
        }
    }
    pbrt_sppm::imageio::check_writable(path)
}

/// Renders a loaded scene and writes the image (and ERRORS.csv).
fn render(scene: SceneDescription, args: &RenderArgs) -> ExitCode {
    use pbrt_sppm::imageio::{read_image, write_image};
    use pbrt_sppm::integrators::errors_csv;
    let quiet = args.common.quiet;
    let (outfile, blame) = output_path(&scene, args);
    // A shard writes its part; the image only when asked for by name.
    let write_outfile = args.partial.is_none() || args.outfile.is_some();
    if let Err(code) = check_outputs(&scene, args, write_outfile.then_some(&outfile), &blame) {
        return code;
    }
    let passes = match pass_mode(args) {
        Ok(p) => p,
        Err(e) => return fail(Path::new("--passes"), e),
    };
    if scene.lights.is_empty() && scene.area_lights.is_empty() && !quiet {
        say!("{}: warning: the scene has no lights; the image will be black", args.scene.display());
    }
    let reference = match &args.mse_reference_image {
        Some(p) => match read_image(p) {
            Ok(img) => Some(img),
            Err(e) => return fail(Path::new("--mse-reference-image"), e),
        },
        None => None,
    };
    let mut settings = RenderSettings {
        iterations: args.spp,
        photons: args.photons,
        radius: args.radius,
        seed: args.seed,
        sampler: args.sampler.unwrap_or_default(),
        photon_sampling: args.photon_sampling.unwrap_or_default(),
        quick: args.quick,
        time_limit: args.time_limit.map(f64::from),
        reference,
        progress: std::io::stderr().is_terminal() && !quiet,
        quiet,
        partial_images: args.write_partial_images.then(|| outfile.clone()),
        interrupt: Some(stop_on_signals(quiet)),
        checkpoint: None,
        passes,
        pass_range: args.pass_range.clone(),
    };
    let pool = match rayon::ThreadPoolBuilder::new().num_threads(args.nthreads.unwrap_or(0)).build() {
        Ok(p) => p,
        Err(e) => return fail(Path::new("--nthreads"), e),
    };
    let syntax = format!("{:?}", scene.syntax).to_lowercase();
    let rs = RenderScene::new(scene);
    let plan = match rs.plan(&settings) {
        Ok(plan) => plan,
        Err(e) => return fail(&args.scene, e),
    };
    let fingerprint = fingerprint(args, &plan, &syntax);
    let resume = match checkpointing(args, &fingerprint, &mut settings) {
        Ok(r) => r,
        Err(code) => return code,
    };
    let out = match pool.install(|| rs.render_from(&settings, resume)) {
        Ok(o) => o,
        Err(e) => return fail(&args.scene, e),
    };
    if write_outfile && let Err(e) = write_image(&outfile, &out.image) {
        say!("{blame}: error: {e}");
        return ExitCode::FAILURE;
    }
    if let Some(path) = &args.partial
        && let Err(e) = write_part(&out, fingerprint, &plan, path)
    {
        return fail(Path::new("--partial"), e);
    }
    if let Some(csv) = &args.mse_reference_out
        && let Err(e) = pbrt_sppm::imageio::write_text(csv, &errors_csv(&out.errors))
    {
        return fail(csv, e);
    }
    report(&out, args, write_outfile.then_some(outfile.as_path()))
}

/// Classic SPPM unless asked for independent passes, which a pass range or a part
/// implies.
fn pass_mode(args: &RenderArgs) -> Result<PassMode, String> {
    let sharded = args.pass_range.is_some() || args.partial.is_some();
    let independent = match args.passes {
        Some(false) if sharded => {
            return Err("classic SPPM cannot be split: --pass-range and --partial need independent passes".into());
        }
        Some(i) => i,
        None => sharded,
    };
    match (independent, args.alpha) {
        (false, Some(_)) => Err("--alpha sets the radius of independent passes: add --passes independent".into()),
        (false, None) => Ok(PassMode::Classic),
        (true, alpha) => Ok(PassMode::Independent { alpha: alpha.unwrap_or(DEFAULT_ALPHA) }),
    }
}

/// The part a shard writes: its passes' sums and what they belong to.
fn write_part(out: &RenderOutput, fingerprint: Fingerprint, plan: &Plan, path: &Path) -> Result<(), String> {
    let Some(sums) = out.pass_sums.clone() else { return Err("only independent passes make parts".into()) };
    let img = &out.image;
    let part = Part {
        fingerprint,
        passes: out.passes.clone(),
        seed: plan.seed,
        photons: out.stats.photons.traced,
        photons_per_pass: plan.photons,
        seconds: out.seconds,
        width: img.width,
        height: img.height,
        origin: img.origin,
        full: img.full,
        world_to_camera: img.meta.world_to_camera,
        sums,
    };
    part.write(path)
}

/// Checks every output path before any work: the image, the part, ERRORS.csv, the
/// checkpoint.
fn check_outputs(
    scene: &SceneDescription,
    args: &RenderArgs,
    outfile: Option<&PathBuf>,
    blame: &str,
) -> Result<(), ExitCode> {
    if let Some(outfile) = outfile
        && let Err(e) = check_output(outfile, true)
    {
        say!("{blame}: error: {e}");
        return Err(ExitCode::FAILURE);
    }
    if let Some(p) = &args.partial
        && let Err(e) = check_part_path(p)
    {
        say!("--partial: error: {e}");
        return Err(ExitCode::FAILURE);
    }
    let others = [("--mse-reference-out", &args.mse_reference_out), ("--checkpoint", &args.checkpoint)];
    for (flag, path) in others {
        if let Some(p) = path
            && let Err(e) = check_output(p, false)
        {
            say!("{flag}: error: {e}");
            return Err(ExitCode::FAILURE);
        }
    }
    if args.checkpoint_every.is_some() && args.checkpoint.is_none() && args.resume.is_none() {
        say!("--checkpoint-every: error: it needs --checkpoint FILE (or --resume FILE)");
        return Err(ExitCode::FAILURE);
    }
    check_overrides(scene, args).map_err(|e| {
        say!("{e}");
        ExitCode::FAILURE
    })
}

/// Ctrl-C, SIGTERM and SIGHUP raise the returned flag: the render stops after the
/// iteration under way, saves its checkpoint and writes its image. A second signal
/// ends the process at once.
fn stop_on_signals(quiet: bool) -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let raised = flag.clone();
    let installed = ctrlc::set_handler(move || {
        if raised.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        if !quiet {
            eprintln!("\ninterrupted: finishing this iteration, then saving (interrupt again to quit at once)");
        }
    });
    if let Err(e) = installed
        && !quiet
    {
        say!("warning: cannot catch interrupts ({e}); an interrupted render will be lost");
    }
    flag
}

/// A part must be an EXR (it holds 32-bit floats and its metadata).
fn check_part_path(p: &Path) -> Result<(), String> {
    if !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
        return Err(format!("\"{}\": a part is an EXR file and must end in .exr", p.display()));
    }
    pbrt_sppm::imageio::check_writable(p)
}

/// What the render is made from: every file read and every setting that changes
/// the image (the pass range excepted: the parts of one render differ in it).
fn fingerprint(args: &RenderArgs, plan: &Plan, syntax: &str) -> Fingerprint {
    let mut fingerprint = Fingerprint {
        scene: std::path::absolute(&args.scene).unwrap_or_else(|_| args.scene.clone()).display().to_string(),
        inputs: pbrt_sppm::limits::inputs_read().into_iter().map(|(p, h)| (p.display().to_string(), h)).collect(),
        settings: plan.fingerprint_settings(),
    };
    fingerprint.settings.push(("syntax".into(), syntax.into()));
    fingerprint.settings.push(("fix".into(), args.common.fixes.unwrap_or_default().names()));
    fingerprint
}

/// Sets up `--checkpoint` and reads `--resume`'s checkpoint, refusing one made from
/// other scene files or settings, or for another pass range.
fn checkpointing(
    args: &RenderArgs,
    fingerprint: &Fingerprint,
    settings: &mut RenderSettings,
) -> Result<Option<Checkpoint>, ExitCode> {
    let Some(path) = args.checkpoint.as_ref().or(args.resume.as_ref()) else { return Ok(None) };
    let mut fingerprint = fingerprint.clone();
    if let Some(r) = &args.pass_range {
        fingerprint.settings.push(("pass-range".into(), format!("{}..{}", r.start, r.end)));
    }
    let every = args.checkpoint_every.unwrap_or_default();
    settings.checkpoint = Some(CheckpointTarget { path: path.clone(), every, fingerprint: fingerprint.clone() });
    let Some(resume) = &args.resume else { return Ok(None) };
    let c = Checkpoint::read(resume).map_err(|e| fail(resume, e))?;
    c.fingerprint.check(&fingerprint).map_err(|e| fail(resume, format!("cannot resume: {e}")))?;
    Ok(Some(c))
}

/// The summary after a render; exit code 130 when it was interrupted.
fn report(out: &RenderOutput, args: &RenderArgs, outfile: Option<&Path>) -> ExitCode {
    let code = if out.interrupted { ExitCode::from(130) } else { ExitCode::SUCCESS };
    if args.common.quiet {
        return code;
    }
    if out.stats.visible_points == 0 {
        say!(
            "{}: warning: no camera path reached a diffuse surface; the image holds only direct emission",
            args.scene.display()
        );
    }
    if args.stats {
        print_stats(out);
    }
    let what = if out.interrupted { "interrupted after" } else { "rendered" };
    let done = match &out.pass_sums {
        Some(_) => format!("independent passes {}", out.passes),
        None => format!("{} iterations", out.stats.iterations),
    };
    let to: Vec<String> = outfile.into_iter().chain(args.partial.as_deref()).map(|p| p.display().to_string()).collect();
    say!(
        "{what} {done} ({} photons each) in {:.2} s -> {}",
        out.image.meta.photons_per_iteration.unwrap_or(0),
        out.seconds,
        to.join(", ")
    );
    if out.interrupted
        && let Some(c) = args.checkpoint.as_ref().or(args.resume.as_ref())
    {
        say!("continue with --resume {}", c.display());
    }
    code
}

/// Command-line values the scene's limits also bound.
fn check_overrides(scene: &SceneDescription, args: &RenderArgs) -> Result<(), String> {
    let l = &scene.limits;
    if let Some(n) = args.spp.filter(|&n| n as u64 > l.iterations) {
        return Err(format!("--spp: error: {}", Limits::over(format!("{n} iterations"), "iterations", l.iterations)));
    }
    if let Some(n) = args.photons.filter(|&n| n > l.photons) {
        return Err(format!("--photons: error: {}", Limits::over(format!("{n} photons"), "photons", l.photons)));
    }
    Ok(())
}

fn print_stats(out: &pbrt_sppm::integrators::RenderOutput) {
    let s = &out.stats;
    let peak = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|t| t.lines().find_map(|l| l.strip_prefix("VmHWM:").map(|v| v.trim().to_string())))
        .unwrap_or_else(|| "unknown".into());
    say!(
        "stats: camera pass {:.3} s, grid {:.3} s, photons {:.3} s, update {:.3} s",
        s.camera_seconds,
        s.grid_seconds,
        s.photon_seconds,
        s.update_seconds
    );
    say!(
        "stats: {} camera paths, {} photon paths, {} photon hits, peak memory {peak}",
        s.camera_rays,
        s.photons.traced,
        s.photons.hits
    );
    let p = &s.photons;
    if p.uniform > 0 {
        let wasted = 1.0 - p.uniform_deposited as f64 / p.uniform as f64;
        say!("stats: {:.3}% of uniform photon paths reached no visible point", 100.0 * wasted);
    }
    if p.mutations > 0 {
        let rate = p.accepted as f64 / p.mutations as f64;
        say!("stats: adaptive photons: {} mutations, {:.3} accepted", p.mutations, rate);
    }
}

/// Writes the Mitsuba export; what cannot go over is also warned about on stderr.
fn export(s: &SceneDescription, scene: &Path, output: Option<PathBuf>, quiet: bool) -> ExitCode {
    if let Some(path) = &output
        && let Err(e) = check_output(path, false)
    {
        return fail(Path::new("--output"), e);
    }
    let e = pbrt_sppm::export::mitsuba(s, &scene.display().to_string());
    for u in e.unsupported.iter().filter(|_| !quiet) {
        let at = if u.location.is_empty() { scene.display().to_string() } else { u.location.clone() };
        say!("{at}: warning: export: {}: {}", u.what, u.why);
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
        None => print(&text),
    }
}

/// Reads parts, adds them up and writes the image (and the merged part).
fn merge(paths: &[PathBuf], outfile: Option<&Path>, partial: Option<&Path>, allow_gaps: bool, quiet: bool) -> ExitCode {
    use pbrt_sppm::integrators::part;
    if let Some(p) = outfile
        && let Err(e) = check_output(p, true)
    {
        return fail(Path::new("--outfile"), e);
    }
    if let Some(p) = partial
        && let Err(e) = check_part_path(p)
    {
        return fail(Path::new("--partial"), e);
    }
    let merged = match part::merge(paths, allow_gaps) {
        Ok(m) => m,
        Err(e) => return fail(Path::new("merge"), e),
    };
    let written = outfile.map(|p| (p, pbrt_sppm::imageio::write_image(p, &merged.part.image())));
    let written = written.into_iter().chain(partial.map(|p| (p, merged.part.write(p))));
    for (path, result) in written {
        if let Err(e) = result {
            return fail(path, e);
        }
    }
    if !quiet {
        merge_summary(&merged, paths.len(), outfile.or(partial).unwrap_or(Path::new("-")));
    }
    ExitCode::SUCCESS
}

fn merge_summary(m: &pbrt_sppm::integrators::part::Merged, files: usize, to: &Path) {
    for d in &m.duplicates {
        say!("{}: warning: the same passes as another part, and identical: counted once", d.display());
    }
    if !m.missing.ranges().is_empty() {
        say!(
            "merge: warning: passes {} are in no part; the image averages the {} passes there are",
            m.missing,
            m.part.passes.count()
        );
    }
    say!(
        "merged {files} parts: passes {} ({} photons traced, {:.2} s of rendering) -> {}",
        m.part.passes,
        m.part.photons,
        m.part.seconds,
        to.display()
    );
}

/// Prints (or writes) the script that submits a render's shards and their merge.
fn plan(args: &PlanArgs) -> ExitCode {
    if let Some(w) = &args.write
        && let Err(e) = check_output(w, false)
    {
        return fail(Path::new("--write"), e);
    }
    if let Err(e) = check_shard_options(args) {
        return fail(Path::new("plan"), e);
    }
    // A scene that does not load fails here, not on every node.
    let common = Common { syntax: None, limits: Vec::new(), quiet: true, fixes: None };
    if let Err(code) = load(&args.scene, &common) {
        return code;
    }
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf()).display().to_string();
    let beside = |ext: &str| args.scene.with_extension(ext);
    let binary = args.binary.clone().or_else(|| std::env::current_exe().ok()).unwrap_or_else(|| "pbrt-sppm".into());
    let plan = pbrt_sppm::farm::ShardPlan::new(pbrt_sppm::farm::ShardPlan {
        binary: absolute(&binary),
        scene: absolute(&args.scene),
        passes: args.passes,
        shards: args.shards,
        parts: absolute(&args.parts.clone().unwrap_or_else(|| beside("parts"))),
        outfile: absolute(&args.outfile.clone().unwrap_or_else(|| beside("exr"))),
        cpus_per_task: args.cpus_per_task,
        render_args: args.render_args.clone(),
    });
    let script = match plan {
        Ok(p) => p.slurm_script(),
        Err(e) => return fail(Path::new("plan"), e),
    };
    match &args.write {
        Some(w) => match pbrt_sppm::imageio::write_text(w, &script) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => fail(w, e),
        },
        None => print(&script),
    }
}

/// The options after `--` must be render options that leave the split to the plan.
fn check_shard_options(args: &PlanArgs) -> Result<(), String> {
    let mut argv = vec!["pbrt-sppm".to_string(), "render".into(), args.scene.display().to_string()];
    argv.extend(args.render_args.iter().cloned());
    let parsed = Cli::try_parse_from(argv).map_err(|e| e.to_string().lines().next().unwrap_or_default().to_string())?;
    let r = match parsed.command {
        Command::Render(r) => r,
        _ => return Err("the options after -- must be render options".into()),
    };
    let taken = [
        ("--spp", r.spp.is_some()),
        ("--pass-range", r.pass_range.is_some()),
        ("--partial", r.partial.is_some()),
        ("--outfile", r.outfile.is_some()),
        ("--nthreads", r.nthreads.is_some()),
        ("--passes", r.passes.is_some()),
        ("--checkpoint", r.checkpoint.is_some()),
        ("--resume", r.resume.is_some()),
        ("--time-limit", r.time_limit.is_some()),
        ("--write-partial-images", r.write_partial_images),
        ("--mse-reference-image", r.mse_reference_image.is_some()),
        ("--quick", r.quick),
        ("--photon-sampling", r.photon_sampling == Some(PhotonSampling::Adaptive)),
    ];
    match taken.iter().find(|t| t.1) {
        Some((flag, _)) => Err(format!(
            "{flag} cannot be given to the shards: the plan sets the passes, the parts and the threads \
             (--passes, --shards, --parts, --outfile, --cpus-per-task), and a shard must render all its passes \
             with uniform photons"
        )),
        None => Ok(()),
    }
}

/// Answers ray queries line by line; a malformed line is an error naming the line.
fn trace(scene: SceneDescription, rays: Option<PathBuf>) -> ExitCode {
    use std::io::BufRead;
    let name = rays.as_ref().map_or("<stdin>".to_string(), |p| p.display().to_string());
    let input: Box<dyn BufRead> = match &rays {
        Some(p) => match std::fs::File::open(p) {
            Ok(f) => Box::new(std::io::BufReader::new(f)),
            Err(e) => return fail(Path::new(&name), format!("cannot read: {e}")),
        },
        None => Box::new(std::io::stdin().lock()),
    };
    let tracer = pbrt_sppm::trace::Tracer::new(scene);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for (i, line) in input.lines().enumerate() {
        let result = line.map_err(|e| e.to_string()).and_then(|l| tracer.line(&l));
        match result {
            Ok(Some(v)) => {
                if let Err(e) = writeln!(out, "{v}") {
                    return fail(Path::new("<stdout>"), format!("cannot write: {e}"));
                }
            }
            Ok(None) => {}
            Err(e) => {
                let _ = out.flush();
                say!("{name}:{}: error: {e}", i + 1);
                return ExitCode::FAILURE;
            }
        }
    }
    match out.flush() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(Path::new("<stdout>"), format!("cannot write: {e}")),
    }
}

fn summary(s: &SceneDescription) -> String {
    use std::fmt::Write as _;
    let r = pbrt_sppm::check::report(s, false);
    let mut out = String::new();
    let _ = writeln!(out, "syntax      {}", s.syntax.name());
    let _ = writeln!(out, "film        {}x{} -> {}", s.film.x_resolution, s.film.y_resolution, s.film.filename);
    let i = &s.integrator;
    let _ = writeln!(
        out,
        "sppm        {} iterations, maxdepth {}, {} photons/iteration, radius {}",
        i.iterations, i.max_depth, i.photons_per_iteration, i.radius
    );
    if let Some(c) = r["counts"].as_object() {
        let parts: Vec<String> =
            c.iter().filter(|(_, v)| v.as_u64() != Some(0)).map(|(k, v)| format!("{k} {v}")).collect();
        let _ = writeln!(out, "counts      {}", parts.join(", "));
    }
    for k in &s.skipped {
        let _ = writeln!(out, "skipped     {}:{}:{}: {} ({})", k.file, k.line, k.column, k.what, k.why);
    }
    for a in &s.approximated {
        let _ = writeln!(out, "approximated {}:{}:{}: {} ({})", a.file, a.line, a.column, a.what, a.how);
    }
    for b in &s.pbrt_bugs {
        let how = if b.fixed { "fixed (--fix)" } else { "rendered as pbrt does" };
        let _ = writeln!(out, "pbrt bug    {}:{}:{}: {} ({how})", b.file, b.line, b.column, b.name);
    }
    if s.pbrt_bugs.iter().any(|b| !b.fixed) {
        let _ = writeln!(
            out,
            "            (`--fix NAME` renders the physically right image; `--fix help` says what each changes)"
        );
    }
    out
}
