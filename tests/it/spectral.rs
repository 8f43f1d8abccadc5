//! pbrt-v4's files render spectrally (`spectrum::transport`): paths carry wavelengths,
//! named glasses disperse, and pbrt-v3's files stay in RGB.

use crate::common::{load_file, report, root, scene};
use pbrt_sppm::imageio::{metrics, read_image};
use pbrt_sppm::integrators::vcm::Techniques;
use pbrt_sppm::integrators::{Algorithm, RenderSettings, render};
use pbrt_sppm::render::RenderScene;
use pbrt_sppm::scene::SceneDescription;

/// The image of `scene` at `iterations`, as (width, height, pixels).
fn image(scene: &SceneDescription, iterations: u32) -> (usize, usize, Vec<[f32; 3]>) {
    image_with(scene, iterations, Algorithm::Sppm)
}

fn image_with(scene: &SceneDescription, iterations: u32, algorithm: Algorithm) -> (usize, usize, Vec<[f32; 3]>) {
    let settings = RenderSettings { iterations: Some(iterations), algorithm: Some(algorithm), ..Default::default() };
    let bidirectional = algorithm != Algorithm::Sppm;
    let out = render(&RenderScene::for_integrator(scene, bidirectional), &settings).expect("renders").image;
    (out.width, out.height, out.pixels)
}

/// The image's mean RGB at `iterations` SPPM passes.
fn mean_rgb(scene: &SceneDescription, iterations: u32) -> [f64; 3] {
    let (_, _, px) = image(scene, iterations);
    std::array::from_fn(|c| px.iter().map(|p| p[c] as f64).sum::<f64>() / px.len() as f64)
}

/// Each channel's centroid (x, y) over the pixels brighter than its median by more
/// than a tenth of its maximum: where a spot of light lands, by colour.
fn centroids(w: usize, pixels: &[[f32; 3]]) -> [[f64; 2]; 3] {
    std::array::from_fn(|c| {
        let mut v: Vec<f32> = pixels.iter().map(|p| p[c]).collect();
        v.sort_by(f32::total_cmp);
        let (median, max) = (v[v.len() / 2], v[v.len() - 1]);
        let floor = median + 0.1 * (max - median);
        let (mut sum, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for (i, p) in pixels.iter().enumerate() {
            let e = (p[c] - floor).max(0.0) as f64;
            (sum, sx, sy) = (sum + e, sx + e * (i % w) as f64, sy + e * (i / w) as f64);
        }
        [sx / sum, sy / sum]
    })
}

#[test]
fn a_glass_prism_throws_a_rainbow_with_blue_bent_most() {
    let mut prism = load_file(&root().join("pbrt-scenes/v4/prism.pbrt")).expect("loads");
    assert!(prism.spectral, "a pbrt-v4 file renders spectrally");
    // pbrt-v4's own image (1024 passes): where its rainbow's red and blue land.
    let reference = read_image(&root().join("tests/data/pbrt-ref/v4-prism.exr")).expect("the reference");
    let [ref_red, _, ref_blue] = centroids(reference.width, &reference.pixels);
    eprintln!("prism (pbrt-v4): red centroid {ref_red:?}, blue {ref_blue:?}");
    let mut spots = Vec::new();
    for (algorithm, passes) in [(Algorithm::Sppm, 128), (Algorithm::Vcm(Techniques::All), 16)] {
        let (w, h, pixels) = image_with(&prism, passes, algorithm);
        if algorithm == Algorithm::Sppm {
            prism_tiles_match(&pixels, &reference.pixels, (w, h));
        }
        let [red, _, blue] = centroids(w, &pixels);
        // The floor is seen from the prism's side with world +x to the left (pbrt's
        // LookAt): red, bent least, lands farther from the prism, so more to the left.
        let spread = blue[0] - red[0];
        eprintln!("prism ({algorithm:?}): red centroid {red:?}, blue {blue:?}: {spread:.1} pixels apart");
        assert!(spread > 8.0, "{algorithm:?}: the rainbow's blue lies {spread:.1} pixels right of its red");
        assert!((blue[1] - red[1]).abs() < 3.0, "{algorithm:?}: along the rainbow, not across it");
        for (ours, theirs, colour) in [(red, ref_red, "red"), (blue, ref_blue, "blue")] {
            let off = ((ours[0] - theirs[0]).powi(2) + (ours[1] - theirs[1]).powi(2)).sqrt();
            assert!(off < 1.0, "{algorithm:?}: {colour} at {ours:?}, pbrt-v4's at {theirs:?}");
        }
        // The rainbow's colours: each channel's light in the spot's window.
        let (ours, theirs) = (spot_rgb(&pixels), spot_rgb(&reference.pixels));
        eprintln!("prism ({algorithm:?}): spot RGB {ours:?}, pbrt-v4's {theirs:?}");
        for c in 0..3 {
            assert!((ours[c] / theirs[c] - 1.0).abs() < 0.05, "{algorithm:?}: spot {ours:?}, pbrt-v4's {theirs:?}");
        }
        spots.push(spot_power(&pixels));
    }
    // In RGB (one index for all colours) the spot is white: one centroid. Splitting
    // the light moves it, and adds or takes away (almost) nothing: a path that ended
    // its other wavelengths counts once, on either side of a merge.
    prism.spectral = false;
    let (w, _, pixels) = image_with(&prism, 16, Algorithm::Sppm);
    let [red, _, blue] = centroids(w, &pixels);
    assert!((blue[0] - red[0]).abs() < 1.5, "RGB: red {red:?} and blue {blue:?} together");
    let white = spot_power(&pixels);
    eprintln!("spot power: rainbow {spots:?}, white {white}");
    for (algorithm, p) in ["sppm", "vcm"].iter().zip(&spots) {
        assert!((p / white - 1.0).abs() < 0.03, "{algorithm}: the rainbow carries {p}, the white spot {white}");
    }
}

/// The worst 4×4 tile of SPPM's prism at twice the scene's 64 iterations, held to
/// `v4_bound` of pbrt-v4's own 64-iteration image: 2.88%, 3.51%, 1.58% (seeds 1–3,
/// whose samples are not the reference's; 2.28% at its seed 0, which are). Ours: 1.92%,
/// 1.53%, 1.25% (the default seed, seeds 1 and 2); at 64 iterations 2.28–4.74%. The
/// worst tiles are the dim top row's and the rainbow's.
fn prism_tiles_match(ours: &[[f32; 3]], theirs: &[[f32; 3]], (w, h): (usize, usize)) {
    let (worst, at, _) = metrics::worst_mean_deviation(ours, theirs, w, h, 4, 0.05);
    let bound = crate::pbrt_refs::v4_bound(0.0288);
    eprintln!("prism (Sppm): worst tile deviation {:.2}% at {at}", 100.0 * worst);
    assert!(worst <= bound, "prism: worst tile {:.2}% at {at} (bound {:.2}%)", 100.0 * worst, 100.0 * bound);
}

/// The light in the window of the image around the floor's spot (160 × 120 pixels;
/// the rainbow spans x 25–55 along y 75).
fn spot_power(pixels: &[[f32; 3]]) -> f64 {
    spot_rgb(pixels).iter().sum()
}

/// Each channel's light in that window.
fn spot_rgb(pixels: &[[f32; 3]]) -> [f64; 3] {
    let inside = |i: &usize| (15..70).contains(&(i % 160)) && (60..90).contains(&(i / 160));
    std::array::from_fn(|c| (0..pixels.len()).filter(inside).map(|i| pixels[i][c] as f64).sum())
}

#[test]
fn pbrt_v3_files_render_in_rgb_and_pbrt_v4_files_spectrally_media_included() {
    let v3 = scene("LookAt 0 0 5 0 0 0 0 1 0 Camera \"perspective\" WorldBegin Material \"matte\" Shape \"sphere\"");
    assert!(!v3.spectral);
    let base = "Camera \"perspective\" Film \"rgb\" WorldBegin";
    assert!(scene(&format!("{base} Material \"diffuse\" Shape \"sphere\"")).spectral);
    let fog = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" MediumInterface \"fog\" \"\"";
    let foggy = format!("{base} {fog} Material \"interface\" Shape \"sphere\"");
    assert!(scene(&foggy).spectral);
    // `check` says which, and approximates nothing for the media.
    assert_eq!(report(&format!("{base} Shape \"sphere\""))["colour"], "spectral");
    let r = report(&foggy);
    assert_eq!(r["colour"], "spectral");
    assert!(!r["approximated"].to_string().contains("MakeNamedMedium"), "{}", r["approximated"]);
}

/// The RGB of the colour space's white (luminance 1) through `d` units of a medium
/// whose σa is the spectrum pbrt-v4 makes of `sigma_a`: ∫ W(λ)·exp(−σa(λ)·d) x̄ȳz̄ dλ.
fn white_through_dye(sigma_a: [f32; 3], d: f64) -> [f64; 3] {
    use pbrt_sppm::spectrum::colorspace::ColorSpaceName;
    use pbrt_sppm::spectrum::sigmoid::RgbUnboundedSpectrum;
    let space = ColorSpaceName::Srgb;
    let sigma = RgbUnboundedSpectrum::new(space, sigma_a);
    crate::common::srgb_of_spectrum(|l| space.illuminant_at(l.round()) * (-(sigma.eval(l as f32) as f64) * d).exp())
}

#[test]
fn a_dye_filters_light_by_the_transmittance_of_its_spectrum() {
    // White light seen through a 1.5-unit slab of a coloured dye (σa only). Spectrally
    // the transmittance is exp(−σa(λ)·d) per wavelength, which is not the exponential
    // of the RGB σa: the two predictions differ by far more than the test's margin,
    // and each mode must land on its own.
    let (sigma_a, d) = ([0.3f32, 1.2, 2.4], 1.5);
    let text = format!(
        "LookAt 0 0 4 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" 10
        Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8
        Integrator \"sppm\" \"integer photonsperiteration\" 1000
        MakeNamedMedium \"dye\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [{} {} {}] \"rgb sigma_s\" [0 0 0]
        WorldBegin
        AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]
          Shape \"bilinearmesh\" \"point3 P\" [-3 -3 -2  3 -3 -2  -3 3 -2  3 3 -2] AttributeEnd
        AttributeBegin MediumInterface \"dye\" \"\" Material \"interface\" Translate 0 0 -0.25
          Shape \"trianglemesh\" \"integer indices\" [0 2 1 0 3 2 4 5 6 4 6 7 0 4 7 0 7 3 1 2 6 1 6 5 0 1 5 0 5 4 3 7 6 3 6 2]
          \"point3 P\" [-2 -2 -{h} 2 -2 -{h} 2 2 -{h} -2 2 -{h} -2 -2 {h} 2 -2 {h} 2 2 {h} -2 2 {h}]
        AttributeEnd",
        sigma_a[0],
        sigma_a[1],
        sigma_a[2],
        h = d / 2.0
    );
    let mut s = scene(&text);
    assert!(s.spectral);
    let spectral = mean_rgb(&s, 128);
    s.spectral = false;
    let rgb = mean_rgb(&s, 128);
    let want_spectral = white_through_dye(sigma_a, d);
    let want_rgb = sigma_a.map(|k| (-(k as f64) * d).exp());
    eprintln!("dye: spectral {spectral:?} (want {want_spectral:?}), RGB {rgb:?} (want {want_rgb:?})");
    let apart = (0..3).map(|c| (want_spectral[c] / want_rgb[c] - 1.0).abs()).fold(0.0, f64::max);
    assert!(apart > 0.1, "the predictions should differ: {want_spectral:?} against {want_rgb:?}");
    for c in 0..3 {
        let near = |got: f64, want: f64| (got / want - 1.0).abs() < 0.02;
        assert!(near(spectral[c], want_spectral[c]), "spectral {spectral:?} against {want_spectral:?}");
        assert!(near(rgb[c], want_rgb[c]), "RGB {rgb:?} against {want_rgb:?}");
    }
}

#[test]
fn a_saturated_reflectance_under_white_light_keeps_its_rgb_colour() {
    // A red wall lit by a white quad light, seen spectrally and in RGB: the same colour
    // on average (an upsampled reflectance reflects its own RGB under the space's white).
    let text = "LookAt 0 0 3 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" 30
        Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16
        Integrator \"sppm\" \"integer photonsperiteration\" 2000 WorldBegin
        AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]
          Shape \"bilinearmesh\" \"point3 P\" [-2 -2 4  -2 2 4  2 -2 4  2 2 4] AttributeEnd
        Material \"diffuse\" \"rgb reflectance\" [0.8 0.2 0.05]
        Shape \"bilinearmesh\" \"point3 P\" [-3 -3 0  3 -3 0  -3 3 0  3 3 0]";
    let mut s = scene(text);
    let spectral = mean_rgb(&s, 64);
    s.spectral = false;
    let rgb = mean_rgb(&s, 64);
    for c in 0..3 {
        assert!((spectral[c] / rgb[c] - 1.0).abs() < 0.02, "channel {c}: spectral {spectral:?}, RGB {rgb:?}");
    }
}

#[test]
fn colour_chooses_what_paths_carry_whatever_the_version() {
    let dir = crate::common::scratch(
        "spectral",
        "colour",
        &[
            ("v3.pbrt", "Camera \"perspective\" WorldBegin Material \"matte\" Shape \"sphere\""),
            ("v4.pbrt", "Camera \"perspective\" WorldBegin Material \"diffuse\" Shape \"sphere\""),
        ],
    );
    let colour = |file: &str, args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
            .args(["check", "--json", "--quiet"])
            .args(args)
            .arg(dir.join(file))
            .output()
            .expect("runs");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        v["colour"].as_str().expect("a colour").to_string()
    };
    assert_eq!(colour("v3.pbrt", &[]), "rgb");
    assert_eq!(colour("v4.pbrt", &[]), "spectral");
    assert_eq!(colour("v3.pbrt", &["--colour", "spectral"]), "spectral");
    assert_eq!(colour("v4.pbrt", &["--colour", "rgb"]), "rgb");
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .args(["check", "--colour", "grey"])
        .arg(dir.join("v4.pbrt"))
        .output()
        .expect("runs");
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("expected spectral or rgb"));
}

#[test]
fn indices_given_as_spectra_disperse_and_floats_do_not() {
    let with = |m: &str| scene(&format!("Camera \"perspective\" WorldBegin {m} Shape \"sphere\""));
    for m in [
        "Material \"dielectric\" \"spectrum eta\" \"glass-BK7\"",
        "Material \"dielectric\" \"spectrum eta\" [400 1.53  700 1.51]",
        "Material \"coateddiffuse\" \"spectrum eta\" \"glass-F11\"",
        "Material \"coatedconductor\" \"spectrum interface.eta\" [400 1.6  700 1.5]",
        // Nothing bends in a pane, but pbrt-v4 keeps one wavelength wherever an
        // index is not a constant.
        "Material \"thindielectric\" \"spectrum eta\" \"glass-BK7\"",
    ] {
        assert!(with(m).materials.iter().any(|d| d.kind.disperses()), "{m}");
    }
    for m in ["Material \"dielectric\" \"float eta\" 1.5", "Material \"coateddiffuse\"", "Material \"thindielectric\""]
    {
        assert!(!with(m).materials.iter().any(|d| d.kind.disperses()), "{m}");
    }
}

#[test]
fn a_checkpoint_resumes_only_in_the_colour_it_was_made_in() {
    let scene = "Camera \"perspective\" Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8
        Sampler \"halton\" \"integer pixelsamples\" 2 Integrator \"sppm\" \"integer photonsperiteration\" 100
        WorldBegin LightSource \"point\" \"rgb I\" [1 1 1] Material \"diffuse\" Shape \"sphere\" \"float radius\" 0.5";
    let dir = crate::common::scratch("spectral", "checkpoint", &[("s.pbrt", scene)]);
    let run = |extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
            .args(["render", "--quiet", "--outfile"])
            .arg(dir.join("out.exr"))
            .args(extra)
            .arg(dir.join("s.pbrt"))
            .output()
            .expect("runs")
    };
    let ck = dir.join("ck.bin");
    let ck = ck.to_str().unwrap();
    assert!(run(&["--checkpoint", ck]).status.success());
    let out = run(&["--resume", ck, "--colour", "rgb"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("colour spectral"), "{err}");
    assert!(run(&["--resume", ck]).status.success());
}

/// The RGB a smooth conductor reflects at normal incidence of the colour space's white
/// (luminance 1), its η and k read at each wavelength from `eta` and `k`.
fn white_off_metal(eta: impl Fn(f32) -> f32, k: impl Fn(f32) -> f32) -> [f64; 3] {
    use glam::Vec3;
    use pbrt_sppm::spectrum::colorspace::ColorSpaceName::Srgb;
    crate::common::srgb_of_spectrum(|l| {
        let lf = l as f32;
        let fr = pbrt_sppm::materials::microfacet::fr_conductor(1.0, Vec3::splat(eta(lf)), Vec3::splat(k(lf)));
        Srgb.illuminant_at(l.round()) * fr.x as f64
    })
}

#[test]
fn named_metals_reflect_their_measured_spectra() {
    // A smooth copper plane (pbrt-v4's default conductor) seen head-on, reflecting a
    // large white emitter behind the camera. Spectrally its colour is Fresnel's at each
    // wavelength of the measured η and k; upsampling their RGB reductions instead gives
    // another colour (2.8% more red, 4.7% less blue), which the test tells apart.
    use pbrt_sppm::spectrum::colorspace::ColorSpaceName::Srgb;
    use pbrt_sppm::spectrum::sigmoid::RgbUnboundedSpectrum;
    use pbrt_sppm::spectrum::{named_samples, named_spectrum, piecewise_linear};
    let text = "LookAt 0 0 1 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" 5
        Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4
        Integrator \"sppm\" \"integer photonsperiteration\" 100
        WorldBegin
        AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true
          Material \"diffuse\" \"rgb reflectance\" [0 0 0]
          Shape \"bilinearmesh\" \"point3 P\" [-50 -50 2  50 -50 2  -50 50 2  50 50 2] AttributeEnd
        Material \"conductor\"
        Shape \"bilinearmesh\" \"point3 P\" [-5 -5 0  5 -5 0  -5 5 0  5 5 0]";
    let s = scene(text);
    let got = mean_rgb(&s, 128);
    let (eta, k) = (named_samples("metal-Cu-eta").unwrap(), named_samples("metal-Cu-k").unwrap());
    let want = white_off_metal(|l| piecewise_linear(&eta, l), |l| piecewise_linear(&k, l));
    let up = |n: &str| RgbUnboundedSpectrum::new(Srgb, named_spectrum(n).unwrap().to_array());
    let (ue, uk) = (up("metal-Cu-eta"), up("metal-Cu-k"));
    let upsampled = white_off_metal(|l| ue.eval(l), |l| uk.eval(l));
    eprintln!("copper: {got:?}; measured spectra {want:?}; upsampled RGB {upsampled:?}");
    for c in 0..3 {
        assert!((got[c] / want[c] - 1.0).abs() < 0.01, "{got:?} against {want:?}");
    }
    assert!((0..3).any(|c| (upsampled[c] / want[c] - 1.0).abs() > 0.02), "the test cannot tell them apart");
    // Every metal pbrt-v4 names reads, its RGB the reduction of its samples.
    for m in ["Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"] {
        for part in ["eta", "k"] {
            let name = format!("metal-{m}-{part}");
            let (rgb, t) = (named_spectrum(&name).unwrap(), named_samples(&name).unwrap());
            assert!(t.first().unwrap().0 <= 360.0 && t.last().unwrap().0 >= 830.0, "{name} covers the visible range");
            let reduced = pbrt_sppm::spectrum::sampled_to_rgb(&t);
            assert!(
                (rgb - reduced).abs().max_element() <= 0.01 * reduced.max_element().max(1.0),
                "{name}: {rgb} vs {reduced}"
            );
        }
    }
}

#[test]
fn lights_given_as_spectra_emit_them_exactly() {
    // A diffuse orange plane under a uniform sky whose `L` is a spectrum (a 2700 K
    // blackbody; the fluorescent F11): the plane's radiance is ρ(λ)·L(λ) at each
    // wavelength, L at luminance 1 as pbrt-v4 normalises it. Upsampling the sky's RGB
    // instead would light the plane with a metamer of it, which the orange tells apart.
    use pbrt_sppm::spectrum::colorspace::ColorSpaceName::Srgb;
    use pbrt_sppm::spectrum::named::illuminant_named;
    use pbrt_sppm::spectrum::sigmoid::{RgbAlbedoSpectrum, RgbIlluminantSpectrum};
    let rho = [0.8f32, 0.3, 0.05];
    let albedo = RgbAlbedoSpectrum::new(Srgb, rho);
    for (sky, spectrum) in [
        (
            "\"blackbody L\" [2700]",
            Box::new(|l: f64| pbrt_sppm::spectrum::daylight::blackbody_normalized(l, 2700.0))
                as Box<dyn Fn(f64) -> f64>,
        ),
        ("\"spectrum L\" \"stdillum-F11\"", Box::new(illuminant_named("stdillum-F11").unwrap())),
    ] {
        let text = format!(
            "LookAt 0 0 2 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" 20
            Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8
            Integrator \"sppm\" \"integer photonsperiteration\" 1000
            WorldBegin LightSource \"infinite\" {sky}
            Material \"diffuse\" \"rgb reflectance\" [{} {} {}]
            Shape \"bilinearmesh\" \"point3 P\" [-50 -50 0  50 -50 0  -50 50 0  50 50 0]",
            rho[0], rho[1], rho[2]
        );
        let got = mean_rgb(&scene(&text), 256);
        let y = pbrt_sppm::spectrum::cie::luminance_of(&spectrum);
        let want = crate::common::srgb_of_spectrum(|l| albedo.eval(l as f32) as f64 * spectrum(l.round()) / y);
        let sky_rgb = crate::common::srgb_of_spectrum(|l| spectrum(l.round()) / y);
        let metamer = RgbIlluminantSpectrum::new(Srgb, sky_rgb.map(|c| c as f32));
        let upsampled = crate::common::srgb_of_spectrum(|l| (albedo.eval(l as f32) * metamer.eval(l as f32)) as f64);
        eprintln!("{sky}: rendered {got:?}; exact {want:?}; upsampled sky {upsampled:?}");
        // Rendered within 0.12% of the largest channel; the upsampled skies are 0.61%
        // (blackbody) and 6.7% (F11) off.
        let off = |v: [f64; 3]| (0..3).map(|c| (v[c] - want[c]).abs() / want[0]).fold(0.0, f64::max);
        assert!(off(got) < 0.004, "{sky}: {got:?} against {want:?}");
        assert!(off(upsampled) > 0.004, "{sky}: the test cannot tell the exact sky from its metamer");
    }
}

#[test]
fn a_colour_space_sets_what_rgb_means_and_what_the_film_writes() {
    // A grey plane under a 3000 K sky: the film records the sky's colour in the scene's
    // colour space, so the same light gives other numbers in rec2020 than in sRGB.
    use pbrt_sppm::spectrum::colorspace::{ColorSpaceName, mul_vec};
    let render_in = |space: &str| {
        let text = format!(
            "ColorSpace \"{space}\" LookAt 0 0 2 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" 20
            Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8
            Integrator \"sppm\" \"integer photonsperiteration\" 1000
            WorldBegin LightSource \"infinite\" \"blackbody L\" [3000]
            Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]
            Shape \"bilinearmesh\" \"point3 P\" [-50 -50 0  50 -50 0  -50 50 0  50 50 0]"
        );
        let s = scene(&text);
        assert_eq!(s.color_space.name(), space);
        mean_rgb(&s, 128)
    };
    let sky = |l: f64| pbrt_sppm::spectrum::daylight::blackbody_normalized(l.round(), 3000.0);
    let xyz = pbrt_sppm::spectrum::cie::spectrum_to_xyz(sky);
    for space in [ColorSpaceName::Srgb, ColorSpaceName::Rec2020] {
        let want = mul_vec(&space.rgb_from_xyz(), xyz).map(|c| 0.5 * c / xyz[1]);
        let got = render_in(space.name());
        eprintln!("{}: {got:?} against {want:?}", space.name());
        for c in 0..3 {
            assert!((got[c] - want[c]).abs() < 0.005 * want[0], "{}: {got:?} against {want:?}", space.name());
        }
    }
    assert_eq!(report("ColorSpace \"aces2065-1\" Film \"rgb\" WorldBegin")["colour_space"], "aces2065-1");
}
