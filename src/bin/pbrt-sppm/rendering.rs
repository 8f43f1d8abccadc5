//! `pbrt-sppm render`: checks the flags that need no scene, loads the scene (saying so
//! on a terminal), renders on a worker thread and writes the outputs; a second
//! interrupt writes the completed iterations from here (see [`crate::signals`]).

use crate::args::RenderArgs;
use crate::print::{self, fail, say};
use crate::{Purpose, load, read, signals};
use pbrt_sppm::cli::check;
use pbrt_sppm::integrators::Algorithm;
use pbrt_sppm::integrators::completed::{Abort, Snapshot};
use pbrt_sppm::job::Job;
use pbrt_sppm::scene::SceneDescription;
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

/// The whole render command.
pub fn command(args: &RenderArgs) -> ExitCode {
    if let Err(code) = early_checks(args) {
        return code;
    }
    let start = std::time::Instant::now();
    match loading(args) {
        Ok(scene) => render(scene, args, start.elapsed().as_secs_f64()),
        Err(code) => code,
    }
}

/// What a render's flags can be checked for before the scene loads.
fn early_checks(args: &RenderArgs) -> Result<(), ExitCode> {
    if let Some(a) = &args.display_server {
        pbrt_sppm::imageio::tev::resolve(a).map_err(|e| fail(Path::new("--display-server"), e))?;
    }
    Ok(())
}

/// [`load`] for a render: on a terminal (and without `--quiet`) a line says that loading
/// started and, when it ends, how long it took, what the scene holds and which method
/// renders it, so a large scene is not a silent wait. Errors and warnings come on lines
/// of their own.
fn loading(args: &RenderArgs) -> Result<SceneDescription, ExitCode> {
    let (scene, common) = (&args.scene, &args.common);
    let tell = !common.quiet && std::io::stderr().is_terminal();
    if !tell {
        return load(scene, common, Purpose::Render);
    }
    eprint!("loading {} ...", scene.display());
    let start = std::time::Instant::now();
    let s = read(scene, common, true, Purpose::Render)?;
    let method = args.integrator.unwrap_or_else(|| Algorithm::by_default(&s.integrator)).name();
    eprintln!(" {:.2} s: {}; {method}", start.elapsed().as_secs_f64(), check::counts_line(&s));
    s.warnings.iter().for_each(|w| say!("{w}"));
    Ok(s)
}

/// Renders a loaded scene and writes the image, the part and `ERRORS.csv`. The render
/// runs on a worker thread so that a second interrupt can write the completed
/// iterations while an iteration is still under way (see [`signals`]). `read_seconds`:
/// how long reading the scene took, for `--stats`.
fn render(scene: SceneDescription, args: &RenderArgs, read_seconds: f64) -> ExitCode {
    let quiet = args.common.quiet;
    let signals = signals::install(quiet);
    let request = match args.request(signals.stop.clone(), signals.completed.clone()) {
        Ok(r) => r,
        Err(e) => return fail(Path::new("--passes"), e),
    };
    if !quiet {
        print::before_render(&scene, args);
    }
    let pool = match rayon::ThreadPoolBuilder::new().num_threads(args.nthreads.unwrap_or(0)).build() {
        Ok(p) => p,
        Err(e) => return fail(Path::new("--nthreads"), e),
    };
    let set_up = std::time::Instant::now();
    // The render scene keeps what it needs of the description, which goes.
    let job = pool.install(|| Job::plan(scene, request));
    let load = print::LoadTimes { read_seconds, set_up_seconds: set_up.elapsed().as_secs_f64() };
    let job = match job {
        Ok(job) => {
            pbrt_sppm::heap::for_rendering();
            job
        }
        Err(e) => {
            say!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let done = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            // Said even if the render panics, so the loop below never waits forever.
            let _done = signals::DoneOnDrop(&signals.done);
            let out = pool.install(|| job.resume().and_then(|resume| job.run(resume)));
            out.and_then(|out| job.write(&out).map(|()| out))
        });
        while let Ok(signals::Event::Abort) = signals.events.recv() {
            match signals.completed.abort() {
                Abort::Now(snapshot) => std::process::exit(aborted(&job, snapshot, quiet)),
                Abort::Saving if !quiet => say!("\ninterrupted again: the render is saving; letting it finish"),
                Abort::Soon if !quiet => say!("\ninterrupted again: the iteration under way ends soon, then saving"),
                Abort::Saving | Abort::Soon => {}
            }
        }
        worker.join().unwrap_or_else(|p| std::panic::resume_unwind(p))
    });
    match done {
        Ok(out) => print::rendered(&job, &out, args, load),
        Err(e) => {
            say!("{e}");
            ExitCode::FAILURE
        }
    }
}

/// A second interrupt: writes the completed iterations' image and ERRORS.csv; the exit
/// status for [`std::process::exit`] (130, or 1 when writing failed).
fn aborted(job: &Job, snapshot: Option<Box<Snapshot>>, quiet: bool) -> i32 {
    let Some(snapshot) = snapshot else {
        say!("\ninterrupted again: stopped before any iteration finished; nothing written");
        return 130;
    };
    if let Err(e) = job.write_snapshot(&snapshot) {
        say!("\ninterrupted again: stopped, but the image could not be written: {e}");
        return 1;
    }
    if !quiet {
        let to = job
            .image
            .as_ref()
            .map_or("no image (a shard writes its part only when it finishes)".into(), |i| i.0.display().to_string());
        let n = snapshot.iterations;
        say!("\ninterrupted again: stopped the iteration under way; wrote the {n} completed -> {to}");
        if let Some(c) = job.checkpoint_path().filter(|c| c.exists()) {
            say!("the checkpoint keeps its last save; continue with --resume {}", c.display());
        }
    }
    130
}
