//! The render loop: iterations of SPPM until the count or the time limit, with the
//! error against a reference after each (`ERRORS.csv`) and a progress bar.

use super::report::{ErrorRow, progress_bar};
use crate::render::RenderScene;

/// Command-line overrides and reporting for a render.
#[derive(Clone, Debug, Default)]
pub struct RenderSettings {
    /// SPPM iterations (`--spp`/`--iterations`).
    pub iterations: Option<u32>,
    pub photons: Option<u64>,
    pub radius: Option<f32>,
    pub seed: Option<u64>,
    pub sampler: crate::sampling::SamplerKind,
    /// How photon paths are drawn (`--photon-sampling`).
    pub photon_sampling: super::adaptive::PhotonSampling,
    /// Divide the iteration count by 16 (pbrt-v3's `--quick`).
    pub quick: bool,
    /// Stop after the iteration that passes this many seconds.
    pub time_limit: Option<f64>,
    /// Compare against this image after every iteration (`--mse-reference-image`).
    pub reference: Option<crate::imageio::RgbImage>,
    /// Print a progress bar with ETA on stderr.
    pub progress: bool,
}

pub struct RenderOutput {
    pub image: crate::imageio::RgbImage,
    pub stats: super::sppm::Stats,
    pub errors: Vec<ErrorRow>,
    pub seconds: f64,
}

impl RenderScene {
    /// Renders with SPPM (scene loading excluded from the timings).
    pub fn render(&self, settings: &RenderSettings) -> Result<RenderOutput, String> {
        use crate::imageio::{ImageMeta, RgbImage, metrics};
        let start = std::time::Instant::now();
        let i = &self.integrator;
        let mut iterations = settings.iterations.unwrap_or(i.iterations);
        if settings.quick {
            iterations = (iterations / 16).max(1);
        }
        let photons = settings.photons.unwrap_or(i.photons_per_iteration).max(1);
        let radius = settings.radius.unwrap_or(i.radius);
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!("the radius must be positive, not {radius}"));
        }
        let mut sppm = super::sppm::Sppm::new(
            self,
            iterations,
            photons,
            radius,
            settings.seed.unwrap_or(i.seed),
            (settings.sampler, settings.photon_sampling),
        )?;
        let [x0, x1, y0, y1] = self.film.pixel_bounds;
        let (w, h) = ((x1 - x0) as usize, (y1 - y0) as usize);
        if let Some(r) = &settings.reference
            && (r.width, r.height) != (w, h)
            && (r.width, r.height) != (self.film.x_resolution as usize, self.film.y_resolution as usize)
        {
            return Err(format!("the reference image is {}x{}, the render {w}x{h}", r.width, r.height));
        }
        let mut errors = Vec::new();
        for it in 0..iterations {
            sppm.iterate();
            let seconds = start.elapsed().as_secs_f64();
            if let Some(r) = &settings.reference {
                let img = sppm.image();
                let refpx = crop_reference(r, self.film.pixel_bounds);
                let mse = metrics::mse(&img, &refpx);
                errors.push(ErrorRow {
                    iteration: it + 1,
                    seconds,
                    photons: sppm.stats.photons.traced,
                    mse,
                    rmse: mse.sqrt(),
                    relmse: metrics::relmse(&img, &refpx),
                });
            }
            if settings.progress {
                progress_bar(it + 1, iterations, seconds);
            }
            if settings.time_limit.is_some_and(|t| seconds >= t) {
                break;
            }
        }
        if settings.progress {
            eprintln!();
        }
        let seconds = start.elapsed().as_secs_f64();
        let image = RgbImage {
            width: w,
            height: h,
            pixels: sppm.image(),
            origin: (x0 as i32, y0 as i32),
            full: (self.film.x_resolution as usize, self.film.y_resolution as usize),
            meta: ImageMeta {
                render_time_seconds: Some(seconds as f32),
                samples_per_pixel: Some(sppm.iteration as i32),
                photons_per_iteration: Some(photons as i64),
                world_to_camera: Some(self.world_to_camera),
                software: Some(format!("pbrt-sppm {}", env!("CARGO_PKG_VERSION"))),
            },
        };
        Ok(RenderOutput { image, stats: sppm.stats.clone(), errors, seconds })
    }
}

/// The reference's pixels under the render's data window (the reference may be the
/// full image or already cropped).
fn crop_reference(r: &crate::imageio::RgbImage, bounds: [u32; 4]) -> Vec<[f32; 3]> {
    let [x0, x1, y0, y1] = bounds.map(|v| v as usize);
    if r.width == x1 - x0 && r.height == y1 - y0 {
        return r.pixels.clone();
    }
    (y0..y1).flat_map(|y| (x0..x1).map(move |x| r.pixels[y * r.width + x])).collect()
}
