//! The `pbrt-sppm` command line: `[render] SCENE`, `check SCENE`, `trace SCENE`,
//! `export --mitsuba SCENE`, `merge PARTS`, `plan --slurm SCENE`. A scene named `-` is
//! read from standard input. The work is the library's ([`pbrt_sppm::job`] renders,
//! [`pbrt_sppm::cli`] the other commands); this file parses, dispatches and prints.

mod args;
mod print;
mod rendering;
mod signals;

use args::{Cli, Command, Common, PlanArgs};
use clap::Parser;
use pbrt_sppm::cli::{check, export, farm, trace};
use pbrt_sppm::fixes::Fixes;
use pbrt_sppm::integrators::part;
use pbrt_sppm::job::{check_output, check_part_path};
use pbrt_sppm::limits::Limits;
use pbrt_sppm::parser::error::LoadError;
use pbrt_sppm::scene::{LoadOptions, SceneDescription, load_scene, load_scene_from_bytes};
use print::{fail, print, say};
use std::io::{IsTerminal, Read};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn main() -> ExitCode {
    pbrt_sppm::heap::for_loading();
    if args::asks_fix_help(std::env::args_os().skip(1)) {
        return print(&Fixes::help());
    }
    let args = match args::with_default_subcommand(std::env::args_os().collect()) {
        Ok(args) => args,
        Err(e) => {
            eprintln!("pbrt-sppm: error: {e}");
            return ExitCode::from(2);
        }
    };
    let cli = Cli::parse_from(args);
    let result = match cli.command {
        Command::Check { scene, json, shapes, common } => load(&scene, &common, Purpose::Inspect).map(|s| match json {
            true => print(&(serde_json::to_string_pretty(&check::report(&s, shapes)).unwrap_or_default() + "\n")),
            false => print(&check::summary(&s)),
        }),
        Command::Trace { scene, rays, common } => load(&scene, &common, Purpose::Inspect).map(|s| trace(&s, rays)),
        Command::Export { scene, mitsuba: _, output, common } => {
            load(&scene, &common, Purpose::Inspect).map(|s| mitsuba(&s, &scene, output, common.quiet))
        }
        Command::Merge { parts, outfile, partial, allow_gaps, quiet } => {
            Ok(merge(&parts, outfile.as_deref(), partial.as_deref(), allow_gaps, quiet))
        }
        Command::Plan(args) => Ok(plan(&args)),
        Command::Render(args) => Ok(rendering::command(&args)),
    };
    result.unwrap_or_else(|code| code)
}

/// What a command loads a scene for.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Purpose {
    /// To render it: the files read are hashed for the render's fingerprint.
    Render,
    /// To report on, trace or export it: no fingerprint, so no hashes.
    Inspect,
}

/// Loads a scene (`-`: standard input) under the command line's limits and fixes,
/// printing its warnings unless quiet.
pub(crate) fn load(scene: &Path, common: &Common, purpose: Purpose) -> Result<SceneDescription, ExitCode> {
    let s = read(scene, common, false, purpose)?;
    if !common.quiet {
        s.warnings.iter().for_each(|w| say!("{w}"));
    }
    Ok(s)
}

/// Loads a scene without printing its warnings; an error is printed on a line of its
/// own (`line_open`: after ending the line a caller left open).
pub(crate) fn read(
    scene: &Path,
    common: &Common,
    line_open: bool,
    purpose: Purpose,
) -> Result<SceneDescription, ExitCode> {
    let end_line = || {
        if line_open {
            say!("");
        }
    };
    let fail = |at: &Path, e: String| {
        end_line();
        fail(at, e)
    };
    let mut limits = Limits::default();
    for spec in &common.limits {
        limits.set(spec).map_err(|e| fail(Path::new("--limit"), e))?;
    }
    let fixes = common.fixes.unwrap_or_default();
    let skip_input_hashes = purpose == Purpose::Inspect;
    let opts = LoadOptions {
        syntax: common.syntax,
        limits,
        fixes,
        colour: common.colour,
        skip_input_hashes,
        ..Default::default()
    };
    let loaded = if scene.as_os_str() == "-" {
        let stdin = Path::new("<stdin>");
        let mut bytes = Vec::new();
        let max = limits.file_bytes;
        if let Err(e) = std::io::stdin().lock().take(max + 1).read_to_end(&mut bytes) {
            return Err(fail(stdin, format!("cannot read: {e}")));
        }
        if bytes.len() as u64 > max {
            return Err(fail(stdin, Limits::over("the scene", "file-bytes", max)));
        }
        // Relative names in a scene from standard input resolve against the current folder.
        load_scene_from_bytes(stdin, bytes, &opts)
    } else {
        load_scene(scene, &opts)
    };
    loaded.map_err(|e| {
        end_line();
        report_error(&e)
    })
}

fn report_error(e: &LoadError) -> ExitCode {
    let text = if std::io::stderr().is_terminal() { e.with_source() } else { e.one_line() };
    say!("{text}");
    ExitCode::FAILURE
}

/// Writes the Mitsuba export; what cannot go over is also warned about on stderr.
fn mitsuba(s: &SceneDescription, scene: &Path, output: Option<PathBuf>, quiet: bool) -> ExitCode {
    if let Some(path) = &output
        && let Err(e) = check_output(path, false)
    {
        return fail(Path::new("--output"), e);
    }
    let e = export::mitsuba(s, &scene.display().to_string());
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
    if let Some(p) = outfile
        && let Err(e) = pbrt_sppm::imageio::write_image(p, &merged.part.image())
    {
        return fail(p, e);
    }
    if let Some(p) = partial
        && let Err(e) = merged.part.write(p)
    {
        return fail(p, e);
    }
    if !quiet {
        print::merged(&merged, paths.len(), outfile.or(partial).unwrap_or(Path::new("-")));
    }
    ExitCode::SUCCESS
}

/// Prints (or writes) the script that submits a render's shards and their merge.
fn plan(args: &PlanArgs) -> ExitCode {
    if let Some(w) = &args.write
        && let Err(e) = check_output(w, false)
    {
        return fail(Path::new("--write"), e);
    }
    if let Err(e) = args.check_shard_options() {
        return fail(Path::new("plan"), e);
    }
    // A scene that does not load fails here, not on every node.
    let common = Common { syntax: None, limits: Vec::new(), quiet: true, fixes: None, colour: None };
    if let Err(code) = load(&args.scene, &common, Purpose::Inspect) {
        return code;
    }
    let absolute = |p: &Path| normalized(p).display().to_string();
    // Under the current folder, not beside the scene (which may be someone else's).
    let stem = args.scene.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let beside = |ext: &str| PathBuf::from(format!("{stem}.{ext}"));
    let binary = args.binary.clone().or_else(|| std::env::current_exe().ok()).unwrap_or_else(|| "pbrt-sppm".into());
    let plan = farm::ShardPlan::new(farm::ShardPlan {
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

/// An absolute path with `.` and `..` resolved by name (the file need not exist), so
/// the scripts `plan` writes name every file one way.
fn normalized(p: &Path) -> PathBuf {
    use std::path::Component;
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// Answers ray queries line by line; a malformed line is an error naming the line.
fn trace(scene: &SceneDescription, rays: Option<PathBuf>) -> ExitCode {
    let name = rays.as_ref().map_or("<stdin>".to_string(), |p| p.display().to_string());
    let input: Box<dyn std::io::BufRead> = match &rays {
        Some(p) => match std::fs::File::open(p) {
            Ok(f) => Box::new(std::io::BufReader::new(f)),
            Err(e) => return fail(Path::new(&name), format!("cannot read: {e}")),
        },
        None => Box::new(std::io::stdin().lock()),
    };
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    match trace::Tracer::new(scene).answer(input, &mut out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(trace::TraceError::Line { line, message }) => {
            let _ = std::io::Write::flush(&mut out);
            fail(Path::new(&format!("{name}:{line}")), message)
        }
        Err(e @ trace::TraceError::Write(_)) => fail(Path::new("<stdout>"), e),
    }
}
