//! The image tools on arrays (`pbrt-imgtool diff`, `tiles`, and relMSE) and image
//! files read and written as `pbrt-sppm` does, all in float32 bytes.

use pbrt_sppm::imageio::{RgbImage, metrics, read_image as read_file, write_image as write_file};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::Path;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(write_image, m)?)?;
    m.add_function(wrap_pyfunction!(read_buckets, m)?)?;
    m.add_function(wrap_pyfunction!(diff, m)?)?;
    m.add_function(wrap_pyfunction!(tiles, m)?)?;
    Ok(())
}

/// Little-endian float32 bytes as floats.
pub fn floats(bytes: &[u8]) -> PyResult<Vec<f32>> {
    if !bytes.len().is_multiple_of(4) {
        return Err(PyValueError::new_err("float32 data must be a multiple of 4 bytes"));
    }
    Ok(bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
}

pub fn float_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// An H×W×3 float32 image (row-major from the top left).
pub fn image(bytes: &[u8], width: usize, height: usize) -> PyResult<RgbImage> {
    let v = floats(bytes)?;
    if v.len() != width * height * 3 {
        return Err(PyValueError::new_err(format!(
            "an image of {width}×{height} pixels needs {} floats",
            width * height * 3
        )));
    }
    let mut img = RgbImage::new(width, height);
    img.pixels = v.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    Ok(img)
}

/// An EXR or PNG file (PNG decoded from sRGB): (bytes, width, height).
#[pyfunction]
fn read_image<'py>(py: Python<'py>, path: &str) -> PyResult<(Bound<'py, PyBytes>, usize, usize)> {
    let img = read_file(Path::new(path)).map_err(|e| PyOSError::new_err(e.to_string()))?;
    let values: Vec<f32> = img.pixels.iter().flatten().copied().collect();
    Ok((PyBytes::new(py, &float_bytes(&values)), img.width, img.height))
}

/// A spectral film's buckets: channel names, bytes of height × width × buckets
/// float32, width, height.
type BucketBytes<'py> = (Vec<String>, Bound<'py, PyBytes>, usize, usize);

/// A spectral film's buckets in an EXR, or `None` when it has none.
#[pyfunction]
fn read_buckets<'py>(py: Python<'py>, path: &str) -> PyResult<Option<BucketBytes<'py>>> {
    let os = |e: pbrt_sppm::imageio::ImageError| PyOSError::new_err(e.to_string());
    let Some(bands) = pbrt_sppm::imageio::read_bands(Path::new(path)).map_err(os)? else { return Ok(None) };
    let img = read_file(Path::new(path)).map_err(os)?;
    Ok(Some((bands.names, PyBytes::new(py, &float_bytes(&bands.values)), img.width, img.height)))
}

/// Writes an EXR (float32) or PNG (sRGB, 8 bits), through a temporary file renamed
/// into place.
#[pyfunction]
fn write_image(path: &str, bytes: &[u8], width: usize, height: usize) -> PyResult<()> {
    let img = image(bytes, width, height)?;
    write_file(Path::new(path), &img).map_err(|e| PyOSError::new_err(e.to_string()))
}

/// `pbrt-imgtool diff`'s metrics of `a` against the reference `b`.
#[pyfunction]
#[pyo3(signature = (a, b, width, height, pixel_threshold=0.01))]
fn diff<'py>(
    py: Python<'py>,
    a: &[u8],
    b: &[u8],
    width: usize,
    height: usize,
    pixel_threshold: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let (ia, ib) = (image(a, width, height)?, image(b, width, height)?);
    let d = metrics::diff(&ia.pixels, &ib.pixels, pixel_threshold);
    let out = PyDict::new(py);
    for (k, v) in [
        ("mse", d.mse),
        ("rmse", d.rmse),
        ("relmse", d.relmse),
        ("mae", d.mae),
        ("max_abs", d.max_abs),
        ("share_above", d.share_above),
    ] {
        out.set_item(k, v)?;
    }
    Ok(out)
}

/// `pbrt-imgtool tiles`: the channel means of `a` and `b` (whole image, then each tile
/// row-major from the top left) and the worst deviation with its place and channel.
#[pyfunction]
#[pyo3(signature = (a, b, width, height, grid=4, floor=0.05))]
fn tiles<'py>(
    py: Python<'py>,
    a: &[u8],
    b: &[u8],
    width: usize,
    height: usize,
    grid: usize,
    floor: f64,
) -> PyResult<Bound<'py, PyDict>> {
    if grid == 0 || grid > width.min(height).max(1) || floor.is_nan() || floor < 0.0 {
        return Err(PyValueError::new_err("grid must be 1 to the image's smaller side, floor at least 0"));
    }
    let (ia, ib) = (image(a, width, height)?, image(b, width, height)?);
    let means = |img: &RgbImage| {
        let mut m = metrics::tile_means(&img.pixels, width, height, 1);
        m.extend(metrics::tile_means(&img.pixels, width, height, grid));
        m
    };
    let (d, at, channel) = metrics::worst_mean_deviation(&ia.pixels, &ib.pixels, width, height, grid, floor);
    let out = PyDict::new(py);
    out.set_item("a", means(&ia))?;
    out.set_item("b", means(&ib))?;
    out.set_item("worst", d)?;
    out.set_item("at", at)?;
    out.set_item("channel", ["R", "G", "B"][channel])?;
    Ok(out)
}
