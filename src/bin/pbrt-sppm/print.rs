//! What the command line prints: errors, standard output that reports a failed write,
//! and the summaries after a render and a merge.

use crate::args::RenderArgs;
use pbrt_sppm::integrators::RenderOutput;
use pbrt_sppm::integrators::part::Merged;
use pbrt_sppm::job::Job;
use pbrt_sppm::scene::SceneDescription;
use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

/// Writes a line to standard error; a closed stderr is not worth a panic.
macro_rules! say {
    ($($t:tt)*) => {{
        let _ = std::io::Write::write_fmt(&mut std::io::stderr(), format_args!("{}\n", format_args!($($t)*)));
    }};
}
pub(crate) use say;

/// `FILE: error: MESSAGE` on standard error; exit code 1.
pub fn fail(file: &Path, message: impl std::fmt::Display) -> ExitCode {
    say!("{}: error: {message}", file.display());
    ExitCode::FAILURE
}

/// Standard output that reports a failed write (a full disk, a closed pipe) as an error.
pub fn print(text: &str) -> ExitCode {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(Path::new("<stdout>"), format!("cannot write: {e}")),
    }
}

/// What a render should know before it starts: a scene without lights, and for a file
/// without an Integrator line, what renders it instead of pbrt's path tracer.
pub fn before_render(scene: &SceneDescription, args: &RenderArgs) {
    let at = args.scene.display();
    if scene.lights.is_empty() && scene.area_lights.is_empty() {
        say!("{at}: warning: the scene has no lights; the image will be black");
    }
    if args.integrator.is_none()
        && let Some(note) = pbrt_sppm::cli::check::implied_integrator(scene)
    {
        say!("{at}: {note}");
    }
}

/// How long a render took to start: reading the scene (parsing, meshes, image files),
/// then setting it up to render (acceleration structures, lights, the film).
#[derive(Clone, Copy)]
pub struct LoadTimes {
    pub read_seconds: f64,
    pub set_up_seconds: f64,
}

/// The summary after a render; exit code 130 when it was interrupted.
pub fn rendered(job: &Job, out: &RenderOutput, args: &RenderArgs, load: LoadTimes) -> ExitCode {
    let code = if out.interrupted { ExitCode::from(130) } else { ExitCode::SUCCESS };
    if args.common.quiet {
        return code;
    }
    // SPPM's visible points; vcm counts light vertices there, which a render without
    // light subpaths (`direct`) never stores.
    let stores = !out.stats.bidirectional || out.stats.photons.traced > 0;
    if out.stats.visible_points == 0 && stores {
        say!(
            "{}: warning: no camera path reached a diffuse surface; the image holds only direct emission",
            args.scene.display()
        );
    }
    if args.stats {
        say!("stats: scene read {:.3} s, set up to render {:.3} s", load.read_seconds, load.set_up_seconds);
        stats(out);
    }
    let what = if out.interrupted { "interrupted after" } else { "rendered" };
    let done = match &out.pass_sums {
        Some(_) => format!("independent passes {}", out.passes),
        None if out.stats.iterations == 1 => "1 iteration".to_string(),
        None => format!("{} iterations", out.stats.iterations),
    };
    let image = job.image.as_ref().map(|i| i.0.as_path());
    let to: Vec<String> = image.into_iter().chain(args.partial.as_deref()).map(|p| p.display().to_string()).collect();
    let each = match (out.stats.bidirectional, out.image.meta.photons_per_iteration.unwrap_or(0)) {
        // `direct` traces none.
        (true, 0) => String::new(),
        (true, n) => format!(" ({n} light subpaths each)"),
        (false, n) => format!(" ({n} photons each)"),
    };
    say!("{what} {done}{each} in {:.2} s -> {}", out.seconds, to.join(", "));
    if out.interrupted
        && let Some(c) = job.checkpoint_path()
    {
        say!("continue with --resume {}", c.display());
    }
    code
}

/// `--stats` after the load line: the time per phase, the paths traced and the peak memory.
fn stats(out: &RenderOutput) {
    let s = &out.stats;
    let peak = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|t| t.lines().find_map(|l| l.strip_prefix("VmHWM:").map(|v| v.trim().to_string())))
        .unwrap_or_else(|| "unknown".into());
    if s.bidirectional {
        say!(
            "stats: light subpaths {:.3} s, grid {:.3} s, camera subpaths {:.3} s, light tracing splats {:.3} s",
            s.photon_seconds,
            s.grid_seconds,
            s.camera_seconds,
            s.update_seconds
        );
        say!(
            "stats: {} camera subpaths, {} light subpaths, {} light vertices stored, peak memory {peak}",
            s.camera_rays,
            s.photons.traced,
            s.visible_points
        );
        if s.prefix_pixels > 0 {
            say!(
                "stats: {} pixels trace {} rays a pass for light seen through perfect specular chains",
                s.prefix_pixels,
                pbrt_sppm::integrators::vcm::PREFIX_RAYS
            );
        }
        if s.connections > 0 {
            let clear = 100.0 * s.connections_clear as f64 / s.connections as f64;
            say!("stats: {} connections, {clear:.0}% of them unoccluded", s.connections);
        }
        if let Some(u) = s.connections_auto {
            let chose = if u.draws() { "cached" } else { "paired" };
            say!(
                "stats: connections auto: {chose} ({:.0}% of the pilot's connections carried light; drawn by its table, {:.0}% would)",
                100.0 * u.paired,
                100.0 * u.predicted
            );
        }
        if s.connection_draws > 0 {
            say!("stats: cached connections: {} drawn a camera vertex", s.connection_draws);
        }
        return;
    }
    let beams =
        if s.beam_seconds > 0.0 { format!(" (gathering along beams {:.3} s)", s.beam_seconds) } else { String::new() };
    say!(
        "stats: camera pass {:.3} s, grid {:.3} s, photons {:.3} s{beams}, update {:.3} s",
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

/// The summary after a merge.
pub fn merged(m: &Merged, files: usize, to: &Path) {
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
