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

use clap::{Parser, Subcommand};
use pbrt_sppm::imageio::{RgbImage, metrics, read_image, write_image};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Compare, inspect and convert images (EXR, PNG).
#[derive(Parser)]
#[command(name = "pbrt-imgtool", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Error metrics of A against the reference B (relMSE = mean((a−b)²/(b² + 0.01))).
    Diff {
        /// The image to compare (EXR or PNG).
        a: String,
        /// The reference.
        b: String,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
        /// The metric --threshold tests.
        #[arg(long, default_value = "relmse", value_parser = ["mse", "rmse", "relmse", "mae", "max"])]
        metric: String,
        /// Exit with status 1 when the metric is above this.
        #[arg(long, allow_negative_numbers = true, value_parser = non_negative)]
        threshold: Option<f64>,
        /// A pixel counts as different when a channel differs by more than this.
        #[arg(long, default_value_t = 0.01, allow_negative_numbers = true, value_parser = non_negative)]
        pixel_threshold: f64,
        /// Write the per-pixel largest difference in false colour (.png or .exr).
        #[arg(long)]
        heatmap: Option<PathBuf>,
    },
    /// Size, windows, metadata and per-channel statistics.
    Info {
        /// The image (EXR or PNG).
        image: String,
    },
    /// EXR → PNG (exposure, then sRGB) or PNG → EXR (sRGB decoded).
    Convert {
        /// The image to read (EXR or PNG).
        input: String,
        /// The image to write: .png from an EXR, .exr from a PNG.
        output: PathBuf,
        /// Exposure in stops.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        exposure: f64,
        /// Write EXR channels as half floats (small reference images).
        #[arg(long)]
        half: bool,
    },
    /// Channel means of A against the reference B, whole image and each tile of a grid;
    /// exits with status 1 when the worst relative deviation is above --tolerance.
    Tiles {
        /// The image to compare (EXR or PNG).
        a: String,
        /// The reference.
        b: String,
        /// Tiles per side.
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=64))]
        grid: u64,
        /// Tile means below this share of the image mean are compared against it.
        #[arg(long, default_value_t = 0.05, value_parser = non_negative)]
        floor: f64,
        /// The largest relative deviation allowed, e.g. 0.02.
        #[arg(long, value_parser = non_negative)]
        tolerance: Option<f64>,
    },
    /// Error against seconds or iterations, log-log, one line per ERRORS.csv.
    Plot {
        /// ERRORS.csv files (`render --mse-reference-out`), one line each.
        #[arg(required = true)]
        csv: Vec<String>,
        /// The plot to write (PNG; default: the first CSV's name with .png).
        #[arg(short, long)]
        o: Option<PathBuf>,
        /// The horizontal axis.
        #[arg(long, default_value = "seconds", value_parser = ["seconds", "iterations"])]
        x: String,
        /// The error plotted.
        #[arg(long, default_value = "relmse", value_parser = ["relmse", "rmse", "mse"])]
        metric: String,
    },
    /// Render a scene once and report its error at each budget against a reference.
    Report {
        /// The scene to render (once, writing its ERRORS.csv as it goes).
        scene: PathBuf,
        /// The reference image the error is measured against.
        #[arg(long)]
        reference: PathBuf,
        /// Budgets in seconds, e.g. 1,2,4,8.
        #[arg(long, conflicts_with = "iterations", required_unless_present = "iterations")]
        seconds: Option<String>,
        /// Budgets in iterations, e.g. 4,8,16.
        #[arg(long)]
        iterations: Option<String>,
        /// The report (its folder is made if needed); report.csv, .png, .exr go beside it.
        #[arg(short, long, default_value = "report.md")]
        o: PathBuf,
        /// Photons per iteration (default: the scene's).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
        photons: Option<u64>,
        /// The render's seed (default: the scene's).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (0: every core).
        #[arg(long, default_value_t = 0)]
        nthreads: usize,
    },
}

fn non_negative(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v >= 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("expected a number of at least 0, not \"{s}\"")),
    }
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Diff { a, b, json, metric, threshold, pixel_threshold, heatmap } => {
            diff(&a, &b, json, &metric, threshold, pixel_threshold, heatmap.as_deref())
        }
        Command::Info { image } => info(&image),
        Command::Convert { input, output, exposure, half } => convert(&input, &output, exposure, half),
        Command::Tiles { a, b, grid, floor, tolerance } => tiles(&a, &b, grid as usize, floor, tolerance),
        Command::Plot { csv, o, x, metric } => {
            let out = o.unwrap_or_else(|| Path::new(&csv[0]).with_extension("png"));
            plot(&csv, &out, &x, &metric).and_then(|_| say(&format!("wrote {}\n", out.display())))
        }
        Command::Report { scene, reference, seconds, iterations, o, photons, seed, nthreads } => {
            let r = report::ReportArgs { scene, reference, out: o, seconds, iterations, photons, seed, nthreads };
            report::report(&r).and_then(|()| say(&format!("wrote {}\n", r.out.display())))
        }
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            let _ = writeln!(std::io::stderr(), "pbrt-imgtool: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Standard output; a failed write (closed pipe, full disk) is an error, not a panic.
fn say(text: &str) -> Result<ExitCode, String> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| format!("cannot write to standard output: {e}"))?;
    Ok(ExitCode::SUCCESS)
}

fn read(path: &str) -> Result<RgbImage, String> {
    read_image(Path::new(path)).map_err(|e| e.to_string())
}

fn tiles(x: &str, y: &str, grid: usize, floor: f64, tolerance: Option<f64>) -> Result<ExitCode, String> {
    let (ia, ib) = (read(x)?, read(y)?);
    if (ia.width, ia.height) != (ib.width, ib.height) {
        return Err(format!("{x} is {}x{}, {y} is {}x{}", ia.width, ia.height, ib.width, ib.height));
    }
    let (w, h) = (ia.width, ia.height);
    let whole = (metrics::tile_means(&ia.pixels, w, h, 1)[0], metrics::tile_means(&ib.pixels, w, h, 1)[0]);
    let mut text = tile_line("image", whole.0, whole.1, whole.1, floor);
    let (ma, mb) = (metrics::tile_means(&ia.pixels, w, h, grid), metrics::tile_means(&ib.pixels, w, h, grid));
    for (k, (a, b)) in ma.iter().zip(&mb).enumerate() {
        text += &tile_line(&format!("tile ({}, {})", k % grid, k / grid), *a, *b, whole.1, floor);
    }
    let (d, at, c) = metrics::worst_mean_deviation(&ia.pixels, &ib.pixels, w, h, grid, floor);
    text += &format!(
        "worst deviation {:.4}% at {at}, channel {} (|A − B| over B's mean, or over {}% of B's image mean \
         where that is larger)\n",
        100.0 * d,
        ["R", "G", "B"][c],
        100.0 * floor
    );
    say(&text)?;
    Ok(if tolerance.is_some_and(|t| d > t) { ExitCode::FAILURE } else { ExitCode::SUCCESS })
}

/// One row of `tiles`: the ratio of A's channel means to B's, and for a region darker
/// than the floor the deviation it is held to (against the floor, not the ratio).
fn tile_line(at: &str, a: [f64; 3], b: [f64; 3], image: [f64; 3], floor: f64) -> String {
    let ratio = [0, 1, 2].map(|c| if b[c] > 0.0 { format!("{:.4}", a[c] / b[c]) } else { "-".into() });
    let dark: Vec<String> = (0..3)
        .filter(|&c| b[c] < floor * image[c])
        .map(|c| format!("{} {:.2}%", ["R", "G", "B"][c], 100.0 * (a[c] - b[c]).abs() / (floor * image[c]).max(1e-30)))
        .collect();
    let note = if dark.is_empty() { String::new() } else { format!("  (below the floor: {})", dark.join(", ")) };
    format!("{at}: ratio {}{note}\n", ratio.join(" "))
}

fn diff(
    x: &str,
    y: &str,
    json: bool,
    metric: &str,
    threshold: Option<f64>,
    pixel_threshold: f64,
    heat: Option<&Path>,
) -> Result<ExitCode, String> {
    if let Some(out) = heat {
        check_image_name(out)?;
    }
    let (ia, ib) = (read(x)?, read(y)?);
    if (ia.width, ia.height) != (ib.width, ib.height) {
        return Err(format!("{x} is {}x{}, {y} is {}x{}", ia.width, ia.height, ib.width, ib.height));
    }
    let d = metrics::diff(&ia.pixels, &ib.pixels, pixel_threshold);
    if let Some(out) = heat {
        heatmap(&ia, &ib, d.max_abs, out)?;
    }
    let text = if json {
        serde_json::to_string(&d).unwrap_or_default()
    } else {
        format!(
            "MSE {:.6e}  RMSE {:.6e}  relMSE {:.6e}  MAE {:.6e}  max |diff| {:.6e}  pixels off by more than {pixel_threshold} (--pixel-threshold): {:.4}%",
            d.mse,
            d.rmse,
            d.relmse,
            d.mae,
            d.max_abs,
            100.0 * d.share_above
        )
    };
    say(&(text + "\n"))?;
    let value = match metric {
        "mse" => d.mse,
        "rmse" => d.rmse,
        "mae" => d.mae,
        "max" => d.max_abs,
        _ => d.relmse,
    };
    match threshold {
        Some(t) if value > t || value.is_nan() => {
            let _ = writeln!(std::io::stderr(), "{metric} {value:.6e} is above the threshold {t:.6e}");
            Ok(ExitCode::FAILURE)
        }
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// An image output name must say its format.
fn check_image_name(path: &Path) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("exr" | "png") => pbrt_sppm::imageio::check_writable(path).map_err(|e| e.to_string()),
        _ => Err(format!("\"{}\": an image name must end in .exr or .png", path.display())),
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
    write_image(out, &img).map_err(|e| e.to_string())
}

fn info(path: &str) -> Result<ExitCode, String> {
    use std::fmt::Write as _;
    let img = read(path)?;
    let is_exr = !path.to_ascii_lowercase().ends_with(".png");
    let bands = if is_exr { pbrt_sppm::imageio::read_bands(Path::new(path)).map_err(|e| e.to_string())? } else { None };
    let mut out = String::new();
    let extra = bands.as_ref().map(|b| format!(" and {} spectral buckets", b.names.len())).unwrap_or_default();
    let _ = writeln!(out, "{path}: {}x{} pixels, channels R G B{extra}", img.width, img.height);
    let _ = writeln!(
        out,
        "data window: origin ({}, {}), size {}x{}; display window {}x{}",
        img.origin.0, img.origin.1, img.width, img.height, img.full.0, img.full.1
    );
    let m = &img.meta;
    if let Some(t) = m.render_time_seconds {
        let _ = writeln!(out, "renderTimeSeconds: {t}");
    }
    if let Some(n) = m.samples_per_pixel {
        let _ = writeln!(out, "samplesPerPixel: {n}");
    }
    if let Some(n) = m.photons_per_iteration {
        let _ = writeln!(out, "photonsPerIteration: {n}");
    }
    if let Some(s) = &m.software {
        let _ = writeln!(out, "software: {s}");
    }
    if let Some(w) = m.world_to_camera {
        let _ = writeln!(out, "worldToCamera: {w:?}");
    }
    let mut channel = |name: &str, v: Vec<f32>| {
        let (lo, hi) = v.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
        let mean = v.iter().map(|&x| x as f64).sum::<f64>() / v.len().max(1) as f64;
        let _ = writeln!(out, "{name}: min {lo} max {hi} mean {mean}");
    };
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        channel(name, img.pixels.iter().map(|p| p[c]).collect());
    }
    for (k, name) in bands.iter().flat_map(|b| b.names.iter().enumerate()) {
        let b = bands.as_ref().expect("named");
        channel(name, b.values.iter().skip(k).step_by(b.names.len()).copied().collect());
    }
    say(&out)
}

fn convert(input: &str, output: &Path, exposure: f64, half: bool) -> Result<ExitCode, String> {
    check_image_name(output)?;
    let is_exr = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if half && !is_exr {
        return Err(format!("--half writes EXR; \"{}\" is not .exr", output.display()));
    }
    let mut img = read(input)?;
    let scale = 2f64.powf(exposure) as f32;
    img.pixels.iter_mut().for_each(|p| *p = p.map(|c| c * scale));
    if half {
        pbrt_sppm::imageio::write_exr_half(output, &img).map_err(|e| e.to_string())?
    } else {
        write_image(output, &img).map_err(|e| e.to_string())?
    }
    Ok(ExitCode::SUCCESS)
}

fn plot(csv: &[String], out: &Path, x: &str, metric: &str) -> Result<ExitCode, String> {
    if !out.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        return Err(format!("\"{}\": the plot is written as PNG; name it .png", out.display()));
    }
    pbrt_sppm::imageio::check_writable(out).map_err(|e| e.to_string())?;
    let x = if x == "iterations" { "iteration" } else { "seconds" };
    let series = csv.iter().map(|p| plot::read_series(Path::new(p), x, metric)).collect::<Result<Vec<_>, _>>()?;
    plot::draw(&series, x, metric, out)?;
    Ok(ExitCode::SUCCESS)
}
