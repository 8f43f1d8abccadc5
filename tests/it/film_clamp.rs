//! pbrt's per-sample clamp (`Film "float maxsampleluminance"` in v3, `"float
//! maxcomponentvalue"` in v4): vcm, bdpt and the direct-light integrator bring every
//! camera sample and splat over the bound down to it; SPPM's pixels stay as they are, as
//! in both pbrts. Against pbrt's own images: `pbrt_refs::the_films_sample_clamp_is_pbrts`.

use crate::common::{load, report, root, scene, warnings};
use pbrt_sppm::integrators::vcm::Techniques;
use pbrt_sppm::integrators::{Algorithm, RenderSettings};
use pbrt_sppm::render::RenderScene;
use pbrt_sppm::scene::LoadOptions;
use pbrt_sppm::spectrum::colorspace::{ColorSpaceName, mul_vec};
use pbrt_sppm::spectrum::transport::Colour;

/// Both scenes' bound.
const BOUND: f64 = 4.0;
/// Both scenes' film scale (v3 `scale`, v4 `iso` / 100), which each pbrt applies after
/// the clamp (v3) or counts in it (v4).
const SCALE: f64 = 1.5;

/// What the film bounds, pixel by pixel: pbrt-v3's luminance before the film's scale,
/// pbrt-v4's largest XYZ component (its default sensor's RGB) after the exposure.
/// `clamp: false` renders the scene with its bound removed.
fn measures(name: &str, algorithm: Algorithm, colour: Option<Colour>, clamp: bool) -> Vec<f64> {
    let options = LoadOptions { colour, ..Default::default() };
    let path = root().join(format!("pbrt-scenes/verify/{name}.pbrt"));
    let mut scene = pbrt_sppm::scene::load_scene(&path, &options).expect("the scene loads");
    assert!(scene.film.clamp.is_some(), "{name} has a bound");
    if !clamp {
        scene.film.clamp = None;
    }
    let settings = RenderSettings { algorithm: Some(algorithm), iterations: Some(8), ..Default::default() };
    let render_scene = RenderScene::for_integrator(&scene, algorithm != Algorithm::Sppm);
    let image = pbrt_sppm::integrators::render(&render_scene, &settings).expect("renders").image;
    let xyz = ColorSpaceName::Srgb.xyz_from_rgb();
    let measure = |p: &[f32; 3]| {
        let rgb = p.map(f64::from);
        match name.starts_with("v3") {
            true => (0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2]) / SCALE,
            false => mul_vec(&xyz, rgb).into_iter().fold(f64::MIN, f64::max),
        }
    };
    image.pixels.iter().map(measure).collect()
}

fn largest(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::MIN, f64::max)
}

#[test]
fn vcm_and_bdpt_bring_each_sample_to_the_films_bound() {
    let (vcm, bdpt) = (Algorithm::Vcm(Techniques::All), Algorithm::Vcm(Techniques::Bdpt));
    // Where the light fills a pixel, every sample is over the bound and brought to it,
    // so the pixel sits at the bound (elsewhere light-tracing splats add to the clamped
    // camera samples, as in pbrt's bdpt). Spectral samples estimate XYZ from three
    // wavelengths; each estimate is brought to the bound, so their mean is below it.
    let cases = [("v3-max-luminance", None, 0.9999), ("v4-max-component", Some(Colour::Rgb), 0.9999)];
    let spectral = ("v4-max-component", None, 0.85);
    for (name, colour, low) in cases.into_iter().chain([spectral]) {
        let free = measures(name, vcm, colour, false);
        // Without the bound the light is far over it.
        let top = largest(&free);
        assert!(top > 3.0 * BOUND, "{name} ({colour:?}) unclamped: {top}");
        let light: Vec<usize> = (0..free.len()).filter(|&i| free[i] >= 0.98 * top).collect();
        assert!(light.len() >= 9, "{name}: {} pixels on the light", light.len());
        for algorithm in [vcm, bdpt] {
            let clamped = measures(name, algorithm, colour, true);
            let what = format!("{name} ({}, {colour:?})", algorithm.name());
            for &i in &light {
                let b = clamped[i];
                assert!(b <= BOUND * 1.0001 && b >= BOUND * low, "{what}: pixel {i} at {b}, bound {BOUND}");
            }
        }
    }
}

#[test]
fn sppm_leaves_its_pixels_unclamped_as_pbrts_sppm_does() {
    // Both pbrts' SPPM write their pixels' estimates directly, past the film's clamp.
    for name in ["v3-max-luminance", "v4-max-component"] {
        let b = largest(&measures(name, Algorithm::Sppm, None, true));
        assert!(b > 3.0 * BOUND, "{name}: SPPM's brightest pixel {b}");
    }
}

#[test]
fn each_version_reads_its_own_pbrts_parameter_and_check_reports_it() {
    let world = "WorldBegin\nLightSource \"point\"\nShape \"sphere\"\n";
    let film = |v: &str| report(&format!("{v}\n{world}"))["film"]["clamp"].clone();
    let v3 = film("Film \"image\" \"float maxsampleluminance\" 2 Integrator \"path\"");
    assert_eq!(v3["maxsampleluminance"], 2.0);
    let v4 = film("Film \"rgb\" \"float maxcomponentvalue\" 10");
    assert_eq!(v4["maxcomponentvalue"], 10.0);
    assert!(film("Film \"rgb\"").is_null());
    // The other version's name is not read: an unused parameter, no clamp.
    let s = scene(&format!("Film \"image\" \"float maxcomponentvalue\" 2 Integrator \"path\"\n{world}"));
    assert!(s.film.clamp.is_none());
    assert!(warnings(&s).iter().any(|w| w.contains("\"float maxcomponentvalue\" is not used")));
    // A negative bound is refused where it is written.
    let e = load(&format!("Film \"rgb\" \"float maxcomponentvalue\" -1\n{world}")).expect_err("an error");
    assert!(e.to_string().contains("inline.pbrt:1:38: error: \"float maxcomponentvalue\" must be at least 0"), "{e}");
}
