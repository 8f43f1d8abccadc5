//! `pbrt-imgtool report`: a convergence report for one scene against a reference.
//!
//! ```text
//! pbrt-imgtool report SCENE.pbrt --reference REF.exr (--seconds 1,2,4,8 | --iterations 4,8,16,32)
//!                     [-o report.md] [--photons N] [--seed S] [--nthreads N]
//! ```
//! Writes `report.md` with a table of time, iterations, photons, RMSE and relMSE at each
//! rung of the ladder, the fitted log-log slopes, and beside it `report.csv` (the full
//! `ERRORS.csv`), `report.png` (the plot) and `report.exr` (the final image).
//!
//! The ladder is read off one progressive run rather than re-rendered per rung: SPPM's
//! state after k iterations does not depend on how many iterations will follow (the
//! radius shrinks per pixel from the photon counts alone), so the image a run with budget
//! t would produce is exactly the one this run holds when it passes t.

use crate::plot::{Series, draw, log_slope};
use pbrt_sppm::imageio::{read_image, write_image, write_text};
use pbrt_sppm::integrators::{ErrorRow, Monitor, Plan, RenderSettings, errors_csv};
use pbrt_sppm::render::RenderScene;
use pbrt_sppm::scene::{LoadOptions, load_scene};
use std::fmt::Write;
use std::path::PathBuf;

/// The budget ladder: wall-clock seconds or iteration counts.
enum Ladder {
    Seconds(Vec<f64>),
    Iterations(Vec<u32>),
}

pub struct ReportArgs {
    pub scene: PathBuf,
    pub reference: PathBuf,
    pub out: PathBuf,
    pub seconds: Option<String>,
    pub iterations: Option<String>,
    pub photons: Option<u64>,
    pub seed: Option<u64>,
    pub nthreads: usize,
}

fn list<T: std::str::FromStr + PartialOrd + Copy>(name: &str, text: &str) -> Result<Vec<T>, String> {
    let mut v: Vec<T> = text
        .split(',')
        .map(|s| s.trim().parse().map_err(|_| format!("--{name}: '{s}' is not a number")))
        .collect::<Result<_, _>>()?;
    v.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    Ok(v)
}

fn ladder(a: &ReportArgs) -> Result<Ladder, String> {
    match (&a.seconds, &a.iterations) {
        (Some(s), None) => {
            let v: Vec<f64> = list("seconds", s)?;
            if v.first().is_none_or(|&t| !(t > 0.0 && t.is_finite())) {
                return Err("--seconds needs positive budgets".into());
            }
            Ok(Ladder::Seconds(v))
        }
        (None, Some(s)) => {
            let v: Vec<u32> = list("iterations", s)?;
            if v.first().is_none_or(|&n| n == 0) {
                return Err("--iterations needs positive counts".into());
            }
            Ok(Ladder::Iterations(v))
        }
        _ => Err("report needs exactly one of --seconds or --iterations".into()),
    }
}

/// The rows at each rung: the last iteration finished within a time budget, or the
/// iteration with that count.
fn rungs(rows: &[ErrorRow], ladder: &Ladder) -> Vec<(String, ErrorRow)> {
    match ladder {
        Ladder::Seconds(v) => v
            .iter()
            .filter_map(|&t| rows.iter().rev().find(|r| r.seconds <= t).map(|r| (format!("{t} s"), *r)))
            .collect(),
        Ladder::Iterations(v) => {
            v.iter().filter_map(|&n| rows.iter().find(|r| r.iteration == n).map(|r| (format!("{n} it"), *r))).collect()
        }
    }
}

pub fn report(a: &ReportArgs) -> Result<(), String> {
    let ladder = ladder(a)?;
    // The folder is made, and checked writable, before the render.
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot make \"{}\": {e}", dir.display()))?;
    }
    pbrt_sppm::imageio::check_writable(&a.out).map_err(|e| e.to_string())?;
    let reference = read_image(&a.reference).map_err(|e| e.to_string())?;
    let scene = load_scene(&a.scene, &LoadOptions::default()).map_err(|e| e.one_line())?;
    let mut settings = RenderSettings { photons: a.photons, seed: a.seed, ..Default::default() };
    match &ladder {
        Ladder::Seconds(v) => {
            settings.time_limit = v.last().copied();
            settings.iterations = Some(u32::MAX);
        }
        Ladder::Iterations(v) => settings.iterations = v.last().copied(),
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(a.nthreads).build().map_err(|e| e.to_string())?;
    let rs = RenderScene::new(&scene);
    let plan = Plan::new(&rs.integrator, || rs.world.radius, &settings).map_err(|e| e.to_string())?;
    let monitor = Monitor { reference: Some(reference), ..Default::default() };
    let out =
        pool.install(|| pbrt_sppm::integrators::run::run(&rs, &plan, &monitor, None)).map_err(|e| e.to_string())?;
    let rows = rungs(&out.errors, &ladder);
    if rows.is_empty() {
        return Err("no iteration finished within the smallest budget; raise the budgets".into());
    }
    let side = |ext: &str| a.out.with_extension(ext);
    write_text(&side("csv"), &errors_csv(&out.errors)).map_err(|e| e.to_string())?;
    write_image(&side("exr"), &out.image).map_err(|e| e.to_string())?;
    let (x_label, x) = match ladder {
        Ladder::Seconds(_) => ("seconds", (|r: &ErrorRow| r.seconds) as fn(&ErrorRow) -> f64),
        Ladder::Iterations(_) => ("iterations", (|r: &ErrorRow| r.iteration as f64) as fn(&ErrorRow) -> f64),
    };
    let series = |metric: &str, f: fn(&ErrorRow) -> f64| Series {
        label: metric.to_string(),
        points: out.errors.iter().map(|r| (x(r), f(r))).filter(|&(p, q)| p > 0.0 && q > 0.0).collect(),
    };
    let (rmse, relmse) = (series("rmse", |r| r.rmse), series("relmse", |r| r.relmse));
    draw(&[rmse, relmse], x_label, "error", &side("png"))?;
    let markdown = markdown(a, &rows, &out.errors, x, x_label);
    write_text(&a.out, &markdown).map_err(|e| e.to_string())
}

fn markdown(
    a: &ReportArgs,
    rungs: &[(String, ErrorRow)],
    all: &[ErrorRow],
    x: fn(&ErrorRow) -> f64,
    x_label: &str,
) -> String {
    let name =
        |ext: &str| a.out.with_extension(ext).file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let slope = |f: fn(&ErrorRow) -> f64| {
        let pts: Vec<(f64, f64)> = all.iter().map(|r| (x(r), f(r))).filter(|&(p, q)| p > 0.0 && q > 0.0).collect();
        log_slope(&pts).map_or("n/a".to_string(), |k| format!("{k:.3}"))
    };
    let mut s = String::new();
    let _ = writeln!(s, "# Convergence of `{}`\n", a.scene.display());
    let _ = writeln!(s, "Reference: `{}`. Threads: {}.\n", a.reference.display(), thread_label(a.nthreads));
    let _ = writeln!(s, "| budget | seconds | iterations | photons | RMSE | relMSE |");
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|");
    for (budget, r) in rungs {
        let _ = writeln!(
            s,
            "| {budget} | {:.3} | {} | {} | {:.4e} | {:.4e} |",
            r.seconds, r.iteration, r.photons, r.rmse, r.relmse
        );
    }
    let _ = writeln!(
        s,
        "\nFitted log-log slope against {x_label} over all {} iterations: RMSE {}, relMSE {}.\n",
        all.len(),
        slope(|r| r.rmse),
        slope(|r| r.relmse)
    );
    let _ = writeln!(s, "![error against {x_label}]({})\n", name("png"));
    let _ = writeln!(s, "Every iteration: [{}]({}). Final image: `{}`.", name("csv"), name("csv"), name("exr"));
    s
}

fn thread_label(n: usize) -> String {
    if n == 0 { format!("all ({})", rayon::current_num_threads()) } else { n.to_string() }
}
