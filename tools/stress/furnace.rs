//! `pbrt-bench stress furnace`: SPPM's own state over a long progressive run.
//!
//! ```text
//! pbrt-bench stress furnace [--iterations 100000]
//! ```
//! The camera sits at the centre of an emitting diffuse sphere (ρ = 0.5, Le = 0.5,
//! maxdepth 5), 6 × 6 pixels, 200 photons an iteration, initial radius 0.2: every pixel
//! sees L = Le (1 + ρ + … + ρ^5) = 0.984375. At each power of ten the sweep prints the
//! mean, its error, and the smallest and largest radius; at the end, whether every
//! pixel's radius is a normal f32 and τ, N and Ld are finite. The test suite runs the
//! same scene for 10^4 iterations.

use pbrt_sppm::integrators::sppm::Sppm;
use pbrt_sppm::render::RenderScene;
use pbrt_sppm::scene::{LoadOptions, load_scene_from_bytes};
use std::path::Path;
use std::time::Instant;

const SCENE: &str = "Film \"rgb\" \"integer xresolution\" 6 \"integer yresolution\" 6 \
    Camera \"perspective\" \"float fov\" 45 Integrator \"sppm\" \"integer maxdepth\" 5 WorldBegin \
    AttributeBegin ReverseOrientation Material \"diffuse\" \"rgb reflectance\" [.5 .5 .5] \
    AreaLightSource \"diffuse\" \"rgb L\" [.5 .5 .5] Shape \"sphere\" AttributeEnd";

pub fn run(iterations: u32) {
    let scene = match load_scene_from_bytes(Path::new("furnace.pbrt"), SCENE.into(), &LoadOptions::default()) {
        Ok(s) => s,
        Err(e) => panic!("the furnace scene did not load: {e}"),
    };
    let rs = RenderScene::new(&scene);
    let expected = 1.0 - 0.5f64.powi(6);
    let radius = 0.2;
    let mut sppm = match Sppm::new(&rs, iterations, 200, radius, 7, Default::default()) {
        Ok(s) => s,
        Err(e) => panic!("the furnace did not start: {e}"),
    };
    println!("\nwhite furnace, 6×6 pixels, 200 photons an iteration, expected mean {expected}");
    println!(
        "{:>10} {:>10} {:>12} {:>12} {:>12} {:>9}",
        "iteration", "mean", "rel. error", "min radius", "max radius", "seconds"
    );
    let start = Instant::now();
    let mut next = 1000;
    for k in 1..=iterations {
        sppm.iterate();
        if k == next || k == iterations {
            let px = sppm.image();
            let mean = px.iter().flat_map(|p| p.iter()).map(|&c| c as f64).sum::<f64>() / (3 * px.len()) as f64;
            let (lo, hi) =
                sppm.pixels.iter().fold((f64::INFINITY, 0f64), |a, p| (a.0.min(p.radius), a.1.max(p.radius)));
            let secs = start.elapsed().as_secs_f64();
            println!("{k:>10} {mean:>10.6} {:>+12.2e} {lo:>12.4e} {hi:>12.4e} {secs:>9.1}", mean / expected - 1.0);
            next *= 10;
        }
    }
    let normal = sppm.pixels.iter().all(|p| (p.radius as f32).is_normal() && p.radius > 0.0);
    let finite = sppm.pixels.iter().all(|p| p.n.is_finite() && p.tau.is_finite() && p.ld.is_finite());
    println!("every radius a normal f32: {normal}; τ, N and Ld finite: {finite}");
}
