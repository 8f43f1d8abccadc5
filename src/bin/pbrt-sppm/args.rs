//! The command line: every subcommand and flag, their values checked as they are
//! parsed, and the render flags turned into a [`Request`].

use clap::{Parser, Subcommand};
use pbrt_sppm::fixes::Fixes;
use pbrt_sppm::guiding::Guiding;
use pbrt_sppm::integrators::adaptive::PhotonSampling;
use pbrt_sppm::integrators::beams::VolumeGather;
use pbrt_sppm::integrators::checkpoint::Every;
use pbrt_sppm::integrators::passes::PassMode;
use pbrt_sppm::integrators::vcm::emission_map::EmissionSampling;
use pbrt_sppm::integrators::vcm::links::Connections;
use pbrt_sppm::integrators::{Algorithm, RenderSettings};
use pbrt_sppm::job::Request;
use pbrt_sppm::parser::Syntax;
use pbrt_sppm::sampling::SamplerKind;
use pbrt_sppm::spectrum::transport::Colour;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(name = "pbrt-sppm", version, about = "Renders pbrt-v3/v4 scenes with stochastic progressive photon mapping")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene (the default when the first argument is a file).
    Render(RenderArgs),
    /// Parse and build a scene without rendering; report what it contains.
    Check {
        /// The scene file (`-` reads standard input).
        scene: PathBuf,
        /// Print one JSON object (its fields: README, "Command line") instead of a summary.
        #[arg(long)]
        json: bool,
        /// Add one entry per created shape to the JSON (with --json only).
        #[arg(long, requires = "json")]
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
pub struct Common {
    /// Read the file as pbrt-v3 or pbrt-v4 syntax instead of detecting it.
    #[arg(long, value_parser = parse_syntax)]
    pub syntax: Option<Syntax>,
    /// What paths carry: `spectral` (sampled wavelengths, as pbrt-v4) or `rgb` (as
    /// pbrt-v3). Default: as the file's pbrt (scenes with media: rgb).
    #[arg(long, value_parser = parse_colour)]
    pub colour: Option<Colour>,
    /// Raise or lower a limit, NAME=N (pixels, photons, iterations, maxdepth, file-bytes,
    /// texture-pixels, include-depth, triangles); may be repeated.
    #[arg(long = "limit", value_name = "NAME=N")]
    pub limits: Vec<String>,
    /// Print no warnings and no summary (errors still go to standard error).
    #[arg(long, short)]
    pub quiet: bool,
    /// Fix these pbrt bugs instead of rendering them as the file's pbrt does:
    /// NAME,... or `all` (`--fix help` lists them; `check` says which a scene shows).
    #[arg(long = "fix", value_name = "NAME,...|all|help", value_parser = parse_fixes)]
    pub fixes: Option<Fixes>,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// The scene file (`-` reads standard input).
    pub scene: PathBuf,
    /// The image to write (`.exr`, or `.png` for an 8-bit sRGB preview); default: the
    /// Film's `filename`.
    #[arg(long)]
    pub outfile: Option<PathBuf>,
    /// Worker threads (0, the default, uses every core).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<usize, 0>)]
    pub nthreads: Option<usize>,
    /// The seed every random number derives from (default: the Integrator's `seed`).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<u64, 0>)]
    pub seed: Option<u64>,
    /// What drives camera paths and vcm's light subpaths: `sobol` (scrambled
    /// low-discrepancy points) or `random` (independent random numbers). Default: `sobol`.
    #[arg(long, value_parser = parse_sampler)]
    pub sampler: Option<SamplerKind>,
    /// How photon paths are drawn: `uniform` (independent photons, as pbrt) or
    /// `adaptive` (Markov chains over paths that reach what the camera sees, for scenes
    /// where most photons land out of view). Default: `uniform`.
    #[arg(long, value_parser = parse_photon_sampling)]
    pub photon_sampling: Option<PhotonSampling>,
    /// Path guiding for vcm and bdpt: `on` (camera subpaths also draw directions from
    /// a map of incident light learnt over the first 31 passes), `light` (light
    /// subpaths draw from a map of where camera subpaths arrive from), `both` or
    /// `off`. Default: `off`.
    #[arg(long, value_parser = str::parse::<Guiding>)]
    pub guiding: Option<Guiding>,
    /// How vcm's and bdpt's light subpaths leave area and distant lights: `auto` (from
    /// a map of what the camera sees, for a light whose subpaths rarely reach it, such
    /// as the sun outside a room lit through a window), `own` (the light's own
    /// sampling, as pbrt) or `seen` (the map wherever it sends subpaths elsewhere).
    /// Default: `auto`.
    #[arg(long, value_parser = str::parse::<EmissionSampling>)]
    pub emission: Option<EmissionSampling>,
    /// What vcm's and bdpt's camera vertices connect to: `paired` (every vertex of one
    /// light subpath), `cached` (vertices drawn from the whole pass, by a table of
    /// where connections found light, learnt over the first four passes) or `auto`
    /// (`cached` where under half of those four passes' connections carried light and
    /// drawing by the table would at least double that share, else `paired`; `--stats`
    /// says which). Default: `auto`.
    #[arg(long, value_parser = str::parse::<Connections>)]
    pub connections: Option<Connections>,
    /// How SPPM gathers photons in participating media: `beams` (every medium segment
    /// of a camera path gathers the photons near it) or `points` (a camera path
    /// scatters at a point and gathers photons in a ball there). Default: `beams`
    /// (`points` with adaptive photons).
    #[arg(long, value_parser = str::parse::<VolumeGather>)]
    pub volume_gather: Option<VolumeGather>,
    /// `sppm`, `vcm` (vertex connection and merging), `bdpt` (vcm without merging) or
    /// `direct` (pbrt-v3's whitted and directlighting image: direct light and specular
    /// chains only); default: what the file asks for (`sppm` → sppm, `bdpt` → bdpt,
    /// `whitted` and `directlighting` → direct, other integrators → vcm). `vcm-only-T`
    /// renders technique T alone (emitterhit, direct, connect, lighttrace, merge).
    #[arg(long, value_parser = parse_integrator)]
    pub integrator: Option<Algorithm>,
    /// SPPM iterations (at least 1), overriding the scene's.
    #[arg(long, visible_alias = "iterations", allow_negative_numbers = true, value_parser = parse_count::<u32, 1>)]
    pub spp: Option<u32>,
    /// Divide the iteration count by 16 (at least 1 remains), as pbrt-v3 does.
    #[arg(long)]
    pub quick: bool,
    /// Print the time to read and set up the scene, the time per phase, the paths traced and the peak memory.
    #[arg(long)]
    pub stats: bool,
    /// Photons per iteration (at least 1), overriding `photonsperiteration`; for vcm and
    /// bdpt, fixes the light subpaths per pass (otherwise chosen after four passes).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<u64, 1>)]
    pub photons: Option<u64>,
    /// The initial photon radius (positive), overriding `radius`.
    #[arg(long, allow_negative_numbers = true, value_parser = parse_positive)]
    pub radius: Option<f32>,
    /// Render until this many seconds (positive) have passed, finishing the iteration
    /// under way: as many iterations as fit, or at most --spp when it is given.
    #[arg(long, allow_negative_numbers = true, value_parser = parse_positive)]
    pub time_limit: Option<f32>,
    /// Compare every iteration with this image (needs --mse-reference-out).
    #[arg(long, requires = "mse_reference_out")]
    pub mse_reference_image: Option<PathBuf>,
    /// Write the per-iteration errors (ERRORS.csv) here (needs --mse-reference-image).
    #[arg(long, requires = "mse_reference_image")]
    pub mse_reference_out: Option<PathBuf>,
    /// Save the render's state to this file as it goes, at the end, and when
    /// interrupted (Ctrl-C, SIGTERM), so that `--resume` can continue it.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// How often to save: a number of iterations (`10`) or a time (`90s`, `5m`, `2h`);
    /// default 5m.
    #[arg(long, value_name = "N|TIME", value_parser = parse_every)]
    pub checkpoint_every: Option<Every>,
    /// Continue the render saved in this checkpoint (made from the same scene files and
    /// settings); it goes on saving there unless --checkpoint names another file.
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,
    /// Write the image after iterations 1, 2, 4, 8, … as well as at the end.
    #[arg(long)]
    pub write_partial_images: bool,
    /// Show the image in tev as it converges (tev's address, as pbrt-v4 spells it:
    /// HOST:PORT, tev's default being localhost:14158).
    #[arg(long, value_name = "HOST:PORT")]
    pub display_server: Option<String>,
    /// `classic` (pbrt's SPPM) or `independent` (Knaus–Zwicker: each pass's radius
    /// depends only on its index, so passes can be rendered apart and merged).
    /// Default: `classic`.
    #[arg(long, value_parser = parse_passes)]
    pub passes: Option<bool>,
    /// How fast independent passes' radius shrinks: r²_{i+1} = r²_i (i+α)/(i+1), 0 < α < 1
    /// (default 2/3).
    #[arg(long, value_parser = parse_alpha)]
    pub alpha: Option<f64>,
    /// Render only passes A to B−1 of the --spp planned (independent passes).
    #[arg(long, value_name = "A..B", value_parser = parse_pass_range)]
    pub pass_range: Option<std::ops::Range<u32>>,
    /// Write the sum of the passes rendered to this EXR, for `pbrt-sppm merge`
    /// (independent passes; the image itself is written only when --outfile is given).
    #[arg(long, value_name = "FILE.exr")]
    pub partial: Option<PathBuf>,
    #[command(flatten)]
    pub common: Common,
}

#[derive(clap::Args)]
pub struct PlanArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Plan for Slurm: an array job of shards, then a merge job once all succeed.
    #[arg(long, required = true)]
    pub slurm: bool,
    /// The passes of the whole render (its --spp).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<u32, 1>)]
    pub passes: u32,
    /// How many shards (array tasks) share them (at most --passes).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_count::<u32, 1>)]
    pub shards: u32,
    /// The folder the parts are written to, which every node must reach (default:
    /// SCENE's name with `.parts`, in the current folder).
    #[arg(long)]
    pub parts: Option<PathBuf>,
    /// The merged image (default: SCENE's name with `.exr`, in the current folder).
    #[arg(long)]
    pub outfile: Option<PathBuf>,
    /// Cores per shard (sbatch --cpus-per-task; the shard renders with as many threads).
    #[arg(long, default_value_t = 1, value_parser = parse_count::<u32, 1>)]
    pub cpus_per_task: u32,
    /// The pbrt-sppm the nodes run (default: this one).
    #[arg(long)]
    pub binary: Option<PathBuf>,
    /// Write the script to this file instead of standard output.
    #[arg(long)]
    pub write: Option<PathBuf>,
    /// Render options every shard gets, after `--` (such as `-- --photons 200000`).
    #[arg(last = true)]
    pub render_args: Vec<String>,
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

fn parse_colour(s: &str) -> Result<Colour, String> {
    Colour::from_name(s).ok_or_else(|| format!("expected spectral or rgb, not \"{s}\""))
}

fn parse_photon_sampling(s: &str) -> Result<PhotonSampling, String> {
    match s {
        "uniform" => Ok(PhotonSampling::Uniform),
        "adaptive" => Ok(PhotonSampling::Adaptive),
        _ => Err(format!("expected uniform or adaptive, not \"{s}\"")),
    }
}

fn parse_integrator(s: &str) -> Result<Algorithm, String> {
    s.parse()
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
    s.parse()
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

/// `pbrt-sppm scene.pbrt ...` means `pbrt-sppm render scene.pbrt ...`. A first argument
/// that is a bare word (no `.`, no path separator, no such file) is a mistyped command:
/// the error names the commands.
pub fn with_default_subcommand(mut args: Vec<std::ffi::OsString>) -> Result<Vec<std::ffi::OsString>, String> {
    const KNOWN: [&str; 11] =
        ["render", "check", "trace", "export", "merge", "plan", "help", "--help", "-h", "--version", "-V"];
    let Some(first) = args.get(1) else { return Ok(args) };
    // `help --help` (and `help check --help`) asks what `help` asks: clap's own `help`
    // word takes no flags.
    if first == "help" && args[2..].iter().any(|a| a == "--help" || a == "-h") {
        let mut rest: Vec<_> = args.drain(2..).filter(|a| a != "--help" && a != "-h").collect();
        args.truncate(1);
        rest.push("--help".into());
        args.extend(rest);
        return Ok(args);
    }
    if KNOWN.iter().any(|k| first == *k) {
        return Ok(args);
    }
    let word = first.to_string_lossy();
    let bare = !word.starts_with('-') && !word.contains(['.', '/', '\\']) && word != "-";
    if bare && !Path::new(first).exists() {
        return Err(format!(
            "unknown command \"{word}\": the commands are render, check, export, merge, plan and trace \
             (a scene file alone means render)"
        ));
    }
    args.insert(1, "render".into());
    Ok(args)
}

/// Whether the arguments hold `--fix help` (or `--fix=help`), which lists the fixes
/// whatever else is given.
pub fn asks_fix_help(args: impl Iterator<Item = std::ffi::OsString>) -> bool {
    let mut prev_fix = false;
    for a in args {
        if (prev_fix && a == "help") || a == "--fix=help" {
            return true;
        }
        prev_fix = a == "--fix";
    }
    false
}

impl RenderArgs {
    /// The job these flags ask for; `interrupt` is raised by a signal handler, and
    /// `completed` keeps the last completed iteration for a second one.
    pub fn request(
        &self,
        interrupt: std::sync::Arc<std::sync::atomic::AtomicBool>,
        completed: std::sync::Arc<pbrt_sppm::integrators::completed::Completed>,
    ) -> Result<Request, String> {
        let quiet = self.common.quiet;
        let settings = RenderSettings {
            algorithm: self.integrator,
            iterations: self.spp,
            photons: self.photons,
            radius: self.radius,
            seed: self.seed,
            sampler: self.sampler.unwrap_or_default(),
            photon_sampling: self.photon_sampling.unwrap_or_default(),
            volume_gather: self.volume_gather,
            quick: self.quick,
            time_limit: self.time_limit.map(f64::from),
            passes: self.pass_mode()?,
            pass_range: self.pass_range.clone(),
            guiding: self.guiding.unwrap_or_default(),
            emission: self.emission,
            connections: self.connections,
        };
        Ok(Request {
            scene: self.scene.clone(),
            settings,
            outfile: self.outfile.clone(),
            part: self.partial.clone(),
            reference: self.mse_reference_image.clone(),
            errors_csv: self.mse_reference_out.clone(),
            checkpoint: self.checkpoint.clone(),
            checkpoint_every: self.checkpoint_every,
            resume: self.resume.clone(),
            partial_images: self.write_partial_images,
            progress: std::io::IsTerminal::is_terminal(&std::io::stderr()) && !quiet,
            quiet,
            interrupt: Some(interrupt),
            completed: Some(completed),
            display_server: self.display_server.clone(),
        })
    }

    /// See [`PassMode::asked`].
    fn pass_mode(&self) -> Result<PassMode, String> {
        let split = self.pass_range.is_some() || self.partial.is_some();
        let bidirectional = self.integrator.is_some_and(|a| a != Algorithm::Sppm);
        PassMode::asked(self.passes, self.alpha, split, bidirectional)
    }
}

impl PlanArgs {
    /// The options after `--` must be render options that leave the split to the plan.
    pub fn check_shard_options(&self) -> Result<(), String> {
        let mut argv = vec!["pbrt-sppm".to_string(), "render".into(), self.scene.display().to_string()];
        argv.extend(self.render_args.iter().cloned());
        let parsed =
            Cli::try_parse_from(argv).map_err(|e| e.to_string().lines().next().unwrap_or_default().to_string())?;
        let Command::Render(r) = parsed.command else {
            return Err("the options after -- must be render options".into());
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
                 (--passes, --shards, --parts, --outfile, --cpus-per-task), and a shard must render all its \
                 passes with uniform photons"
            )),
            None => Ok(()),
        }
    }
}
