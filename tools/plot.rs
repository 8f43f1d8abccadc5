//! `pbrt-imgtool plot`: error against time (or iterations) on log-log axes.
//!
//! ```text
//! pbrt-imgtool plot ERRORS.csv [MORE.csv ...] -o plot.png [--x seconds|iterations]
//!                   [--metric relmse|rmse|mse]
//! ```
//! Each file becomes one line labelled with its name and the slope of a least-squares
//! fit of log(error) against log(x); an unbiased Monte Carlo estimator converges with
//! slope −1 in MSE (−½ in RMSE), SPPM a little slower because of its shrinking radius.

use pbrt_sppm::imageio::ImageError;
pub use pbrt_sppm::imageio::metrics::log_slope;
use plotters::prelude::*;
use std::path::Path;

/// One column pair read from an `ERRORS.csv`.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// Reads `x` and `metric` columns, keeping the rows where both are positive (log axes).
pub fn read_series(path: &Path, x: &str, metric: &str) -> Result<Series, String> {
    let points: Vec<(f64, f64)> = read_columns(path, &[x, metric])?
        .into_iter()
        .map(|row| (row[0], row[1]))
        .filter(|&(px, py)| px > 0.0 && py > 0.0 && px.is_finite() && py.is_finite())
        .collect();
    if points.is_empty() {
        return Err(format!("{}: no rows with positive {x} and {metric}", path.display()));
    }
    let label = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    Ok(Series { label, points })
}

/// The named columns of every row of an `ERRORS.csv`-shaped file, in the order named.
pub fn read_columns(path: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let text = String::from_utf8(bytes)
        .map_err(|_| format!("{}: not a CSV file (it is not text; plot reads ERRORS.csv files)", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').map(str::trim).collect();
    let columns: Vec<usize> = names
        .iter()
        .map(|name| {
            header.iter().position(|h| h == name).ok_or_else(|| format!("{}: no '{name}' column", path.display()))
        })
        .collect::<Result<_, _>>()?;
    let mut rows = Vec::new();
    for (n, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let row = columns.iter().map(|&i| fields.get(i).and_then(|f| f.parse().ok()));
        rows.push(row.collect::<Option<Vec<f64>>>().ok_or_else(|| format!("{}:{}: bad row", path.display(), n + 2))?);
    }
    Ok(rows)
}

/// Registers the bundled font once (plotters' `ab_glyph` backend has no system fonts).
fn register_font() -> Result<(), String> {
    static FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| "the bundled font could not be loaded".to_string())
}

/// Draws the series into a PNG (written to a temporary file and renamed).
pub fn draw(series: &[Series], x_label: &str, metric: &str, out: &Path) -> Result<(), String> {
    register_font()?;
    let all = series.iter().flat_map(|s| s.points.iter());
    let (x0, x1, y0, y1) = all.fold((f64::MAX, f64::MIN, f64::MAX, f64::MIN), |(a, b, c, d), &(x, y)| {
        (a.min(x), b.max(x), c.min(y), d.max(y))
    });
    let (w, h) = (900, 600);
    let mut pixels = vec![0u8; 3 * (w * h) as usize];
    render(series, (x0, x1, y0, y1), x_label, metric, BitMapBackend::with_buffer(&mut pixels, (w, h)))?;
    // Encoded by the `image` crate the renderer uses (plotters' own encoder would
    // build a second, older version of it).
    let png = image::RgbImage::from_raw(w, h, pixels).ok_or("plot: the buffer does not match its size")?;
    let draw = |tmp: &Path| png.save_with_format(tmp, image::ImageFormat::Png).map_err(|e| ImageError::write(out, e));
    pbrt_sppm::imageio::atomically(out, draw).map_err(|e| e.to_string())
}

fn render(
    series: &[Series],
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    x_label: &str,
    metric: &str,
    backend: BitMapBackend,
) -> Result<(), String> {
    let root = backend.into_drawing_area();
    let e = |e: DrawingAreaErrorKind<_>| format!("plot: {e}");
    root.fill(&WHITE).map_err(e)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{metric} against {x_label}"), ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        // Padding keeps single points and flat lines inside a visible range.
        .build_cartesian_2d(
            (x0 / 1.2..x1 * 1.2).log_scale().with_key_points(key_points(x0 / 1.2, x1 * 1.2)),
            (y0 / 1.5..y1 * 1.5).log_scale().with_key_points(key_points(y0 / 1.5, y1 * 1.5)),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(metric)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(e)?;
    for (i, s) in series.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let slope = log_slope(&s.points).map_or("n/a".into(), |k| format!("{k:.2}"));
        chart
            .draw_series(LineSeries::new(s.points.iter().copied(), colour.stroke_width(2)))
            .map_err(e)?
            .label(format!("{} (slope {slope})", s.label))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

/// Ticks at 1, 2 and 5 times the powers of ten within [lo, hi] (plotters' log axes
/// label only powers of ten, so a run from 0.85 to 7.75 s had a single tick).
fn key_points(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (k0..=k1).flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k))).filter(|v| (lo..=hi).contains(v)).collect()
}

/// A short tick label: up to three significant decimals, no trailing zeros.
fn tick(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}
