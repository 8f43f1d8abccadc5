//! `pbrt-imgtool`: compare, inspect and convert images.
//!
//! ```text
//! pbrt-imgtool diff A.exr B.exr [--json] [--metric mse|rmse|relmse|mae|max] [--threshold T]
//!                   [--pixel-threshold P] [--heatmap diff.png]
//! pbrt-imgtool info IMAGE
//! pbrt-imgtool convert IN OUT [--exposure STOPS]      # EXR→PNG (sRGB) or PNG→EXR
//! pbrt-imgtool plot ERRORS.csv [MORE.csv ...] -o plot.png [--x seconds|iterations]
//! pbrt-imgtool report SCENE.pbrt --reference REF.exr --seconds 1,2,4 [-o report.md]
//! ```
//! `diff` reports MSE, RMSE, relMSE (mean((a−b)²/(b² + 0.01)), B is the reference), MAE,
//! the largest absolute difference, and the share of pixels with a channel differing by
//! more than `--pixel-threshold` (default 0.01). With `--threshold`, the exit status is
//! 1 when `--metric` (default relmse) exceeds it. Half and float EXRs are read.

mod plot;
mod report;

use pbrt_sppm::imageio::{RgbImage, metrics, read_image, write_image};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("diff") => diff(&args[1..]),
        Some("info") => info(&args[1..]),
        Some("convert") => convert(&args[1..]),
        Some("plot") => plot(&args[1..]),
        Some("report") => report(&args[1..]),
        _ => Err("usage: pbrt-imgtool diff|info|convert|plot|report ... (see the README)".into()),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("pbrt-imgtool: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Positional arguments and `--name value` / `--flag` options.
struct Args {
    positional: Vec<String>,
    options: Vec<(String, Option<String>)>,
}

fn parse(args: &[String], flags: &[&str]) -> Args {
    let (mut positional, mut options) = (Vec::new(), Vec::new());
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.strip_prefix("--").or(if a == "-o" { Some("o") } else { None }) {
            Some(name) if flags.contains(&name) => options.push((name.to_string(), None)),
            Some(name) => options.push((name.to_string(), it.next().cloned())),
            None => positional.push(a.clone()),
        }
    }
    Args { positional, options }
}

impl Args {
    fn get(&self, name: &str) -> Option<&str> {
        self.options.iter().rev().find(|(n, _)| n == name).and_then(|(_, v)| v.as_deref())
    }
    fn has(&self, name: &str) -> bool {
        self.options.iter().any(|(n, _)| n == name)
    }
    fn number(&self, name: &str) -> Result<Option<f64>, String> {
        self.get(name).map(|v| v.parse().map_err(|_| format!("--{name}: '{v}' is not a number"))).transpose()
    }
}

fn read(path: &str) -> Result<RgbImage, String> {
    read_image(Path::new(path))
}

fn diff(args: &[String]) -> Result<ExitCode, String> {
    let a = parse(args, &["json"]);
    let [x, y] = a.positional.as_slice() else { return Err("diff needs two images".into()) };
    let (ia, ib) = (read(x)?, read(y)?);
    if (ia.width, ia.height) != (ib.width, ib.height) {
        return Err(format!("{x} is {}x{}, {y} is {}x{}", ia.width, ia.height, ib.width, ib.height));
    }
    let d = metrics::diff(&ia.pixels, &ib.pixels, a.number("pixel-threshold")?.unwrap_or(0.01));
    if let Some(out) = a.get("heatmap") {
        heatmap(&ia, &ib, d.max_abs, Path::new(out))?;
    }
    if a.has("json") {
        println!("{}", serde_json::to_string(&d).unwrap_or_default());
    } else {
        println!(
            "MSE {:.6e}  RMSE {:.6e}  relMSE {:.6e}  MAE {:.6e}  max |diff| {:.6e}  pixels above threshold {:.4}%",
            d.mse,
            d.rmse,
            d.relmse,
            d.mae,
            d.max_abs,
            100.0 * d.share_above
        );
    }
    let metric = a.get("metric").unwrap_or("relmse");
    let value = match metric {
        "mse" => d.mse,
        "rmse" => d.rmse,
        "relmse" => d.relmse,
        "mae" => d.mae,
        "max" => d.max_abs,
        other => return Err(format!("unknown metric '{other}' (mse, rmse, relmse, mae, max)")),
    };
    match a.number("threshold")? {
        Some(t) if value > t => {
            eprintln!("{metric} {value:.6e} is above the threshold {t:.6e}");
            Ok(ExitCode::FAILURE)
        }
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// Per-pixel largest channel difference, scaled by the maximum, in false colour.
fn heatmap(a: &RgbImage, b: &RgbImage, max: f64, out: &Path) -> Result<(), String> {
    let mut img = RgbImage::new(a.width, a.height);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        let d = (0..3).map(|c| (a.pixels[i][c] - b.pixels[i][c]).abs()).fold(0f32, f32::max);
        // The PNG writer applies sRGB; undo it so the palette lands as designed.
        *p = metrics::heat(if max > 0.0 { (d as f64 / max) as f32 } else { 0.0 }).map(pbrt_sppm::imageio::from_srgb);
    }
    write_image(&out.with_extension("png"), &img)
}

fn info(args: &[String]) -> Result<ExitCode, String> {
    let a = parse(args, &[]);
    let [path] = a.positional.as_slice() else { return Err("info needs one image".into()) };
    let img = read(path)?;
    println!("{path}: {}x{} pixels, channels R G B", img.width, img.height);
    println!(
        "data window: origin ({}, {}), size {}x{}; display window {}x{}",
        img.origin.0, img.origin.1, img.width, img.height, img.full.0, img.full.1
    );
    let m = &img.meta;
    if let Some(t) = m.render_time_seconds {
        println!("renderTimeSeconds: {t}");
    }
    if let Some(n) = m.samples_per_pixel {
        println!("samplesPerPixel: {n}");
    }
    if let Some(n) = m.photons_per_iteration {
        println!("photonsPerIteration: {n}");
    }
    if let Some(s) = &m.software {
        println!("software: {s}");
    }
    if let Some(w) = m.world_to_camera {
        println!("worldToCamera: {w:?}");
    }
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let v: Vec<f32> = img.pixels.iter().map(|p| p[c]).collect();
        let (lo, hi) = v.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
        let mean = v.iter().map(|&x| x as f64).sum::<f64>() / v.len().max(1) as f64;
        println!("{name}: min {lo} max {hi} mean {mean}");
    }
    Ok(ExitCode::SUCCESS)
}

fn convert(args: &[String]) -> Result<ExitCode, String> {
    let a = parse(args, &[]);
    let [input, output] = a.positional.as_slice() else { return Err("convert needs an input and an output".into()) };
    let mut img = read(input)?;
    let scale = 2f64.powf(a.number("exposure")?.unwrap_or(0.0)) as f32;
    img.pixels.iter_mut().for_each(|p| *p = p.map(|c| c * scale));
    write_image(&PathBuf::from(output), &img)?;
    Ok(ExitCode::SUCCESS)
}

fn plot(args: &[String]) -> Result<ExitCode, String> {
    let a = parse(args, &[]);
    let out = a.get("o").ok_or("plot needs -o plot.png")?;
    let x = match a.get("x").unwrap_or("seconds") {
        "iterations" | "iteration" => "iteration",
        "seconds" => "seconds",
        other => return Err(format!("--x {other}: expected seconds or iterations")),
    };
    let metric = a.get("metric").unwrap_or("relmse");
    if a.positional.is_empty() {
        return Err("plot needs at least one ERRORS.csv".into());
    }
    let series =
        a.positional.iter().map(|p| plot::read_series(Path::new(p), x, metric)).collect::<Result<Vec<_>, _>>()?;
    plot::draw(&series, x, metric, Path::new(out))?;
    Ok(ExitCode::SUCCESS)
}

fn report(args: &[String]) -> Result<ExitCode, String> {
    let a = parse(args, &[]);
    let [scene] = a.positional.as_slice() else { return Err("report needs one scene file".into()) };
    let whole = |name: &str| a.number(name).map(|v| v.map(|n| n as u64));
    let r = report::ReportArgs {
        scene: PathBuf::from(scene),
        reference: PathBuf::from(a.get("reference").ok_or("report needs --reference REF.exr")?),
        out: report::output(a.get("o")),
        seconds: a.get("seconds").map(str::to_string),
        iterations: a.get("iterations").map(str::to_string),
        photons: whole("photons")?,
        seed: whole("seed")?,
        nthreads: whole("nthreads")?.unwrap_or(0) as usize,
    };
    report::report(&r)?;
    println!("wrote {}", r.out.display());
    Ok(ExitCode::SUCCESS)
}
