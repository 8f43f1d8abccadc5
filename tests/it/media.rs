//! Participating media: what the files say (both versions' parameters, defaults and
//! errors) and what SPPM renders with them (analytic cases; pbrt's image of the fog
//! box is in `pbrt_refs`).

use crate::common::{load, scene, warnings};
use pbrt_sppm::integrators::RenderSettings;
use pbrt_sppm::integrators::beams::VolumeGather;
use pbrt_sppm::media::Medium;
use pbrt_sppm::render::RenderScene;

fn medium(text: &str) -> pbrt_sppm::media::Homogeneous {
    let s = scene(text);
    match s.media.first().map(|m| m.kind.clone()) {
        Some(Medium::Homogeneous(h)) => h,
        other => panic!("not a homogeneous medium: {other:?}"),
    }
}

fn fog(version_marker: &str, params: &str) -> String {
    format!(
        "{version_marker} MakeNamedMedium \"m\" \"string type\" \"homogeneous\" {params} \
         WorldBegin MediumInterface \"m\" \"\" Shape \"sphere\""
    )
}

const V3: &str = "Film \"image\"";

fn grid(params: &str) -> String {
    format!(
        "Film \"image\" MakeNamedMedium \"m\" \"string type\" \"heterogeneous\" {params} \
         WorldBegin MediumInterface \"m\" \"\" Shape \"sphere\""
    )
}
const V4: &str = "Film \"rgb\"";

/// A pbrt-v4 medium of type `ty` that varies over a box, filling a sphere.
fn v4_grid(ty: &str, params: &str) -> String {
    format!(
        "Film \"rgb\" WorldBegin MakeNamedMedium \"m\" \"string type\" \"{ty}\" {params} \
         MediumInterface \"m\" \"\" Shape \"sphere\""
    )
}

#[test]
fn homogeneous_defaults_presets_and_scale_follow_each_version() {
    let m = medium(&fog(V3, ""));
    assert_eq!((m.sigma_a.rgb.x, m.sigma_s.rgb.z), (0.0011, 3.77), "pbrt-v3's defaults are whole milk's");
    let m = medium(&fog(V4, ""));
    assert_eq!((m.sigma_a.rgb, m.sigma_s.rgb), (glam::Vec3::ONE, glam::Vec3::ONE), "pbrt-v4's default to 1");
    // v3: given coefficients replace the preset's; v4: the preset wins.
    let p = "\"string preset\" \"Ketchup\" \"rgb sigma_a\" [1 2 3] \"float scale\" 2";
    let m = medium(&fog(V3, p));
    assert_eq!((m.sigma_a.rgb.y, m.sigma_s.rgb.x), (4.0, 0.36));
    let m = medium(&fog(V4, p));
    assert_eq!((m.sigma_a.rgb.y, m.sigma_s.rgb.x), (1.94, 0.36));
    assert_eq!(medium(&fog(V4, "\"float g\" 0.5")).phase.g, 0.5);
}

#[test]
fn bad_media_are_located_errors() {
    for (text, want) in [
        (fog(V4, "\"rgb sigma_s\" [1 -1 1]"), "must be at least 0"),
        (fog(V4, "\"float scale\" -2"), "must be at least 0"),
        (fog(V4, "\"float g\" 1.5"), "must lie in [-1, 1]"),
        (fog(V4, "\"rgb sigma_s\" [1e30 1 1] \"float scale\" 1e30"), "beyond the range of 32-bit floats"),
        (grid("\"float density\" [3e38] \"color sigma_s\" [10 10 10]"), "beyond the range of 32-bit floats"),
        (
            "Film \"rgb\" WorldBegin MediumInterface \"nowhere\" \"\" Shape \"sphere\"".into(),
            "\"nowhere\" is not defined",
        ),
        (
            "MakeNamedMedium \"m\" \"string type\" \"plasma\" MediumInterface \"m\" \"\"".into(),
            "unknown medium type \"plasma\"",
        ),
        ("MakeNamedMedium \"m\" \"rgb sigma_a\" [1 1 1] MediumInterface \"m\" \"\"".into(), "needs a \"string type\""),
        // pbrt-v4 creates every named medium, used or not, and has no "heterogeneous".
        (
            "Film \"rgb\" MakeNamedMedium \"m\" \"string type\" \"heterogeneous\" WorldBegin".into(),
            "pbrt-v4 has no medium type \"heterogeneous\"",
        ),
        (grid("\"integer nx\" 0 \"float density\" []"), "nx·ny·nz = 0·1·1"),
        // pbrt-v3 leaves these two out (below); pbrt-v4 stops.
        (v4_grid("uniformgrid", "\"integer nx\" 2 \"float density\" [1 2 3]"), "3 values; nx·ny·nz = 2·1·1 = 2"),
        (v4_grid("uniformgrid", ""), "needs \"float density\" values"),
        (grid("\"float density\" [-1]"), "at least 0, not -1"),
        (grid("\"float density\" [1] \"point p0\" [0 0 0] \"point p1\" [1 0 1]"), "must exceed \"p0\""),
        (v4_grid("uniformgrid", "\"float density\" [1] \"rgb Le\" [1 1 1] \"float temperature\" [900]"), "not both"),
        (
            v4_grid("uniformgrid", "\"float density\" [1 1] \"integer nx\" 2 \"float Lescale\" [1]"),
            "needs nx·ny·nz = 2",
        ),
        (v4_grid("uniformgrid", "\"float density\" [1] \"float temperature\" [900 9]"), "needs nx·ny·nz = 1"),
        (v4_grid("rgbgrid", "\"float g\" 0"), "needs \"rgb sigma_a\" or \"rgb sigma_s\""),
        (v4_grid("rgbgrid", "\"rgb sigma_s\" [1 1 1] \"rgb Le\" [1 1 1]"), "needs \"sigma_a\" for \"Le\""),
        (v4_grid("rgbgrid", "\"rgb sigma_s\" [1 1 1 1 1 1] \"integer nx\" 3"), "nx·ny·nz = 3·1·1"),
        (
            v4_grid("rgbgrid", "\"integer nx\" 2 \"rgb sigma_a\" [1 1 1 2 2 2] \"rgb sigma_s\" [1 1 1]"),
            "= 2 colours; found 1",
        ),
        (v4_grid("rgbgrid", "\"rgb sigma_a\" [1 -1 1]"), "at least 0, not -1"),
        (
            v4_grid("cloud", "\"rgb sigma_s\" [3e38 1 1] \"rgb sigma_a\" [3e38 1 1]"),
            "beyond the range of 32-bit floats",
        ),
    ] {
        let e = load(&text).expect_err(&text).to_string();
        assert!(e.contains(want), "{text}: {e}");
        assert!(e.contains(":1:"), "located: {e}");
    }
}

#[test]
fn what_is_not_rendered_says_so_where_it_is_written() {
    let s = scene(&fog(V3, "\"string preset\" \"Jelly\""));
    assert!(warnings(&s).iter().any(|w| w.contains("unknown medium preset \"Jelly\"")), "{:?}", warnings(&s));
    // NanoVDB media read their file (`tests/it/nanovdb.rs`); a missing one is a
    // located error, as pbrt-v4 stops there too.
    let err = crate::common::load(&v4_grid("nanovdb", "\"string filename\" \"smoke.nvdb\"")).unwrap_err().to_string();
    assert!(err.contains("inline.pbrt:1:") && err.contains("smoke.nvdb"), "{err}");
    // The other types of both versions are rendered as written, colored grids and
    // emission included: nothing skipped or approximated, and pbrt-v4's spectrally.
    for text in [
        v4_grid("cloud", ""),
        v4_grid("uniformgrid", "\"float density\" [1] \"rgb sigma_a\" [1 2 3] \"float temperature\" [1500]"),
        v4_grid("rgbgrid", "\"rgb sigma_a\" [1 2 3] \"rgb Le\" [1 1 1]"),
        fog(V4, "\"rgb Le\" [1 1 1]"),
    ] {
        let s = scene(&text);
        assert_eq!(s.media.len(), 1, "{text}");
        let emits = text.contains("Le") || text.contains("temperature");
        assert_eq!(s.media[0].kind.emissive(), emits, "{text}");
        assert!(s.approximated.is_empty() && s.skipped.is_empty(), "{text}: {:?} {:?}", s.approximated, s.skipped);
        assert!(s.spectral, "{text}");
    }
}

#[test]
fn shapes_lights_and_the_camera_get_the_media_current_at_their_statements() {
    let s = scene(
        "MakeNamedMedium \"a\" \"string type\" \"homogeneous\" \
         MediumInterface \"\" \"a\" Camera \"perspective\" \
         WorldBegin LightSource \"point\" \
         AttributeBegin MediumInterface \"b\" \"a\" Shape \"sphere\" AttributeEnd Shape \"disk\" \
         MakeNamedMedium \"b\" \"string type\" \"homogeneous\" \"float g\" 0.2",
    );
    let (a, b) = (Some(0), Some(1));
    assert_eq!(s.camera_medium, a);
    assert_eq!(s.lights[0].medium, a);
    assert_eq!((s.shapes[0].media.inside, s.shapes[0].media.outside), (b, a), "a forward reference resolves");
    assert_eq!((s.shapes[1].media.inside, s.shapes[1].media.outside), (None, a));
    assert_eq!(s.media[1].name, "b");
}

fn render(text: &str) -> Vec<[f32; 3]> {
    render_with(text, &RenderSettings::default())
}

fn render_with(text: &str, settings: &RenderSettings) -> Vec<[f32; 3]> {
    pbrt_sppm::integrators::render(&RenderScene::new(&scene(text)), settings).expect("renders").image.pixels
}

/// The world block of a slab test, after WorldBegin: a box of half-size `h` across and
/// 1 in depth about the origin, an interface to medium "ink" (defined by the caller),
/// between the camera on +z and a large emitter of radiance 1 at z = -3.
fn slab_before_an_emitter(h: f32) -> String {
    format!(
        "AttributeBegin MediumInterface \"ink\" \"\" Material \"\" \
          Shape \"trianglemesh\" \"point P\" [-{h} -{h} -1  {h} -{h} -1  {h} {h} -1  -{h} {h} -1  -{h} -{h} 1  {h} -{h} 1  {h} {h} 1  -{h} {h} 1] \
          \"integer indices\" [0 2 1 0 3 2  4 5 6 4 6 7  0 4 7 0 7 3  1 2 6 1 6 5  0 1 5 0 5 4  3 7 6 3 6 2] \
        AttributeEnd \
        AttributeBegin Translate 0 0 -3 AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \
          Material \"matte\" \"rgb Kd\" [0 0 0] \
          Shape \"trianglemesh\" \"point P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] \"integer indices\" [0 1 2 0 2 3] \
        AttributeEnd WorldEnd"
    )
}

fn mean(px: &[[f32; 3]]) -> [f64; 3] {
    let n = px.len() as f64;
    [0, 1, 2].map(|c| px.iter().map(|p| p[c] as f64).sum::<f64>() / n)
}

/// An emitter seen through a slab of absorbing medium: exp(−σa·d) of its radiance, per
/// channel (free-flight sampling with colored σt must stay unbiased).
#[test]
fn an_absorbing_slab_dims_what_is_behind_it_by_beers_law() {
    let ink =
        "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.25 0.5 1] \"rgb sigma_s\" [0 0 0]";
    let text = format!(
        "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 \
        LookAt 0 0 5  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 10 \
        Integrator \"sppm\" \"integer numiterations\" 64 \"integer photonsperiteration\" 1000 \
        {ink} WorldBegin {}",
        slab_before_an_emitter(2.0)
    );
    let m = mean(&render(&text));
    for (c, sigma) in [0.25f64, 0.5, 1.0].into_iter().enumerate() {
        let want = (-sigma * 2.0).exp();
        assert!((m[c] - want).abs() < 0.01 * want + 1e-3, "channel {c}: {} against e^-{} = {want}", m[c], 2.0 * sigma);
    }
}

/// A slab that absorbs (σa) and emits (Le, pbrt-v4) before nothing: the camera sees
/// ∫₀^d e^(−σa·t)·σa·Le dt = Le·(1 − e^(−σa·d)) per channel in RGB, exactly
/// (homogeneous emission is integrated in closed form; its photons find no surface to
/// land on; the narrow view keeps every ray's path within 1e-4 of d), and per
/// wavelength of pbrt-v4's spectra of σa and Le when spectral.
#[test]
fn an_emitting_slab_glows_with_its_integrated_emission() {
    let text = "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16 \
        LookAt 0 0 5  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 1 \
        Integrator \"sppm\" \"integer photonsperiteration\" 1000 Sampler \"independent\" \"integer pixelsamples\" 4 \
        MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.25 0.5 1] \"rgb sigma_s\" [0 0 0] \
          \"rgb Le\" [2 1 0.5] \"float Lescale\" 2 \
        WorldBegin AttributeBegin MediumInterface \"ink\" \"\" Material \"interface\" \
          Shape \"trianglemesh\" \"point3 P\" [-2 -2 -1  2 -2 -1  2 2 -1  -2 2 -1  -2 -2 1  2 -2 1  2 2 1  -2 2 1] \
          \"integer indices\" [0 2 1 0 3 2  4 5 6 4 6 7  0 4 7 0 7 3  1 2 6 1 6 5  0 1 5 0 5 4  3 7 6 3 6 2] \
        AttributeEnd";
    let mut s = scene(text);
    s.spectral = false;
    let m =
        mean(&pbrt_sppm::integrators::render(&RenderScene::new(&s), &RenderSettings::default()).unwrap().image.pixels);
    for (c, (sigma, le)) in [(0.25f64, 4.0f64), (0.5, 2.0), (1.0, 1.0)].into_iter().enumerate() {
        let want = le * (1.0 - (-sigma * 2.0).exp());
        assert!((m[c] - want).abs() < 1e-3 * want, "channel {c}: {} against {want}", m[c]);
    }
    // Spectrally, over passes whose wavelengths cover the visible range.
    use pbrt_sppm::spectrum::colorspace::ColorSpaceName::Srgb;
    use pbrt_sppm::spectrum::sigmoid::{RgbIlluminantSpectrum, RgbUnboundedSpectrum};
    let (sigma, le) =
        (RgbUnboundedSpectrum::new(Srgb, [0.25, 0.5, 1.0]), RgbIlluminantSpectrum::new(Srgb, [4.0, 2.0, 1.0]));
    let want = crate::common::srgb_of_spectrum(|l| {
        let l = l as f32;
        (le.eval(l) * (1.0 - (-sigma.eval(l) * 2.0).exp())) as f64
    });
    let settings = RenderSettings { iterations: Some(128), ..Default::default() };
    let m = mean(&render_with(text, &settings));
    for c in 0..3 {
        assert!((m[c] / want[c] - 1.0).abs() < 0.01, "spectral: {m:?} against {want:?}");
    }
}

/// Inside a closed sphere that emits L = 1 (two-sided) and reflects nothing, filled with a
/// medium that scatters without absorbing, radiance is 1 everywhere and in every
/// direction: direct light from the walls and the photons' multiple scattering must
/// add up to exactly that (the volume estimate's normalization included), gathered at
/// points or along beams.
#[test]
fn a_scattering_furnace_holds_radiance_one_everywhere() {
    let text = "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8 \
        LookAt 0 0 0  0 0 -1  0 1 0 \
        MakeNamedMedium \"cloud\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [1 1 1] \
          \"float g\" 0.4 \
        MediumInterface \"\" \"cloud\" Camera \"perspective\" \"float fov\" 60 \
        Integrator \"sppm\" \"integer numiterations\" 96 \"integer photonsperiteration\" 20000 \
          \"integer maxdepth\" 200 \"float radius\" 0.15 \
        WorldBegin AttributeBegin MediumInterface \"cloud\" \"\" \
        AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" \"true\" Material \"matte\" \"rgb Kd\" [0 0 0] \
        Shape \"sphere\" \"float radius\" 2 AttributeEnd WorldEnd";
    for gather in [VolumeGather::Points, VolumeGather::Beams] {
        let m = mean(&render_with(text, &RenderSettings { volume_gather: Some(gather), ..Default::default() }));
        for (c, v) in m.iter().enumerate() {
            assert!((v - 1.0).abs() < 0.03, "{gather:?}, channel {c}: {v}");
        }
    }
}

/// pbrt-v3 makes its camera at WorldEnd, with the medium current there: a
/// `MediumInterface` at the world's top level moves the camera. `--fix camera-medium`
/// keeps the one at `Camera`, as pbrt-v4 does; `check` names the Camera statement.
#[test]
fn pbrt_v3_gives_the_camera_the_medium_current_at_world_end() {
    let text = "MakeNamedMedium \"a\" \"string type\" \"homogeneous\" \
        MediumInterface \"\" \"a\" Camera \"perspective\" \
        WorldBegin MediumInterface \"a\" \"\" Shape \"sphere\" WorldEnd";
    let s = scene(text);
    assert_eq!(s.camera_medium, None, "pbrt-v3: the outside medium at WorldEnd");
    assert!(s.pbrt_bugs.iter().any(|b| b.name == "camera-medium" && b.line == 1), "{:?}", s.pbrt_bugs);
    let opts = pbrt_sppm::scene::LoadOptions { fixes: pbrt_sppm::fixes::Fixes::all(), ..Default::default() };
    let fixed = pbrt_sppm::scene::load_scene_from_bytes(std::path::Path::new("t.pbrt"), text.into(), &opts).unwrap();
    assert_eq!(fixed.camera_medium, Some(0));
    // pbrt-v4 takes the medium at Camera, and nothing is reported.
    let v4 =
        scene(&text.replace("WorldEnd", "").replace("Camera \"perspective\"", "Camera \"perspective\" Film \"rgb\""));
    assert_eq!(v4.camera_medium, Some(0));
    assert!(!v4.pbrt_bugs.iter().any(|b| b.name == "camera-medium"), "{:?}", v4.pbrt_bugs);
}

/// An emitter seen through a grid medium of constant samples: where the samples are
/// flat the density is 1, and it falls linearly to ½ over the outer half-voxel (pbrt's
/// samples sit at voxel centres, zero beyond). A ray along z through the middle meets
/// optical depth σa · 2 · (1 − 1/16) for a box of depth 2 and 4 voxels an axis. (The
/// medium is defined after WorldBegin: before it, the CTM is the camera's and pbrt
/// places the grid in that space.)
#[test]
fn a_grid_slab_dims_what_is_behind_it_by_its_integrated_density() {
    let densities = vec!["1"; 64].join(" ");
    let text = format!(
        "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8 \
        LookAt 0 0 6  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 4 \
        Integrator \"sppm\" \"integer numiterations\" 64 \"integer photonsperiteration\" 1000 \
        WorldBegin \
        MakeNamedMedium \"ink\" \"string type\" \"heterogeneous\" \"color sigma_a\" [0.5 0.5 0.5] \
          \"color sigma_s\" [0 0 0] \"integer nx\" 4 \"integer ny\" 4 \"integer nz\" 4 \"float density\" [{densities}] \
          \"point p0\" [-1 -1 -1] \"point p1\" [1 1 1] {}",
        slab_before_an_emitter(1.0)
    );
    let m = mean(&render(&text));
    let want = (-0.5f64 * 2.0 * (1.0 - 1.0 / 16.0)).exp();
    for (c, v) in m.iter().enumerate() {
        assert!((v - want).abs() < 0.02 * want, "channel {c}: {v}, want {want}");
    }
}

/// A medium no `MediumInterface` names is listed as never used and not built: the
/// scene renders as one without media (SPPM's pbrt rules, vcm for a `path` file).
#[test]
fn a_medium_nothing_names_is_left_out() {
    let s = scene(
        "MakeNamedMedium \"unused\" \"string type\" \"homogeneous\" Integrator \"path\" WorldBegin Shape \"sphere\"",
    );
    assert!(s.media.is_empty());
    assert!(
        s.skipped.iter().any(|k| k.what == "MakeNamedMedium \"unused\"" && k.why == "never used"),
        "{:?}",
        s.skipped
    );
    assert!(!s.integrator.emitting_media);
}

/// pbrt-v4 leaves an rgbgrid's `Le` (and a temperature grid's blackbody) unnormalised:
/// its film records them ∫ȳ dλ = 106.86 times brighter than the same values on a light.
/// We match it; `check` names the parameter, and `--fix medium-emission` records them
/// as a light's (the image of a scene lit by such a medium alone scales by 1/106.86).
#[test]
fn unnormalised_medium_emission_is_pbrts_by_default_and_a_named_fix() {
    let text = "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8 \
        LookAt 0 0 5  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 20 \
        Sampler \"independent\" \"integer pixelsamples\" 4 Integrator \"sppm\" \"integer photonsperiteration\" 2000 \
        WorldBegin\n\
        MakeNamedMedium \"dye\" \"string type\" \"rgbgrid\" \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [0.5 0.5 0.5]\n\
          \"rgb Le\" [0.02 0.01 0.005] \"point3 p0\" [-1 -1 -1] \"point3 p1\" [1 1 1]\n\
        AttributeBegin MediumInterface \"dye\" \"\" Material \"interface\" Shape \"sphere\" \"float radius\" 1 AttributeEnd\n\
        Material \"diffuse\" Shape \"bilinearmesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  -3 -1 3  3 -1 3]";
    let s = scene(text);
    assert!(s.pbrt_bugs.iter().any(|b| b.name == "medium-emission" && b.line == 3), "{:?}", s.pbrt_bugs);
    let opts = pbrt_sppm::scene::LoadOptions { fixes: pbrt_sppm::fixes::Fixes::all(), ..Default::default() };
    let fixed = pbrt_sppm::scene::load_scene_from_bytes(std::path::Path::new("t.pbrt"), text.into(), &opts).unwrap();
    let settings = RenderSettings::default();
    let image = |s| pbrt_sppm::integrators::render(&RenderScene::new(s), &settings).expect("renders").image.pixels;
    let (pbrt, ours) = (mean(&image(&s)), mean(&image(&fixed)));
    for c in 0..3 {
        assert!(
            pbrt[c] > 0.0 && (pbrt[c] / ours[c] / 106.856895 - 1.0).abs() < 1e-3,
            "channel {c}: {} / {}",
            pbrt[c],
            ours[c]
        );
    }
}

/// Valid but extreme media render finite images: temperatures past where Planck's law
/// underflows (1e30 K, and an offset that overflows), a cloud whose noise overflows.
#[test]
fn extreme_emission_and_noise_render_finite() {
    for params in [
        "\"uniformgrid\" \"float density\" [1] \"float temperature\" [1e30]",
        "\"uniformgrid\" \"float density\" [1] \"float temperature\" [2000] \"float temperatureoffset\" -3e38",
        "\"cloud\" \"float frequency\" 1e38",
    ] {
        let text = format!(
            "LookAt 0 0 5 0 0 0 0 1 0 Camera \"perspective\" \
             Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8 \
             Sampler \"independent\" \"integer pixelsamples\" 2 Integrator \"sppm\" \"integer photonsperiteration\" 500 \
             WorldBegin LightSource \"point\" \"point3 from\" [0 3 3] \
             MakeNamedMedium \"m\" \"string type\" {params} \"point3 p0\" [-1 -1 -1] \
             AttributeBegin MediumInterface \"m\" \"\" Material \"interface\" Shape \"sphere\" AttributeEnd \
             Material \"diffuse\" Shape \"bilinearmesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  -3 -1 3  3 -1 3]"
        );
        let px = render(&text);
        assert!(px.iter().flatten().all(|v| v.is_finite()), "{params}");
        assert!(mean(&px).iter().any(|&m| m > 0.0), "{params}: lit");
    }
}

/// A media file that asks for `volpath`, `path` or `bdpt` is rendered by vcm or bdpt, as
/// a vacuum file is; one whose media emit is rendered by SPPM (its photons start in
/// them), and the warning says why. `--integrator` still picks any method.
#[test]
fn media_files_asking_for_path_tracing_get_vcm_unless_their_media_emit() {
    use pbrt_sppm::integrators::vcm::Techniques;
    use pbrt_sppm::integrators::{Algorithm, Plan};
    let file = |integrator: &str, le: &str| {
        scene(&format!(
            "Integrator \"{integrator}\" MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" {le} \
             Film \"rgb\" WorldBegin AttributeBegin MediumInterface \"fog\" \"\" Material \"interface\" \
             Shape \"sphere\" AttributeEnd"
        ))
    };
    let chosen = |s: &pbrt_sppm::scene::SceneDescription, settings: &RenderSettings| {
        Plan::new(&s.integrator, || 1.0, settings).expect("a plan").algorithm
    };
    let default = RenderSettings::default();
    for (asked, method, le, expected) in [
        ("volpath", "vcm", "", Algorithm::Vcm(Techniques::All)),
        ("bdpt", "bdpt", "", Algorithm::Vcm(Techniques::Bdpt)),
        ("volpath", "sppm", "\"rgb Le\" [1 1 1]", Algorithm::Sppm),
    ] {
        let s = file(asked, le);
        assert_eq!(chosen(&s, &default), expected, "{asked} {le}");
        let w = warnings(&s);
        assert!(w.iter().any(|w| w.contains(&format!("\"{asked}\" is rendered with {method}"))), "{w:?}");
    }
    let glowing = file("volpath", "\"rgb Le\" [1 1 1]");
    assert!(warnings(&glowing).iter().any(|w| w.contains("emitting media")), "{:?}", warnings(&glowing));
    let asked = RenderSettings { algorithm: Some(Algorithm::Vcm(Techniques::All)), ..Default::default() };
    assert_eq!(chosen(&glowing, &asked), Algorithm::Vcm(Techniques::All));
}

/// In fog of σt = 10⁴ (a mean free path of 10⁻⁴) a merging ball of radius 0.05 would
/// average light over 500 mean free paths: vcm leaves merging out there, and agrees
/// with bdpt (it came out 37% dark when it merged).
#[test]
fn vcm_does_not_merge_where_the_ball_spans_many_mean_free_paths() {
    use pbrt_sppm::integrators::Algorithm;
    use pbrt_sppm::integrators::vcm::Techniques;
    let s = crate::common::load_file(&crate::common::root().join("pbrt-scenes/stress/dense-fog.pbrt")).unwrap();
    let mean = |t: Techniques| {
        let settings =
            RenderSettings { algorithm: Some(Algorithm::Vcm(t)), iterations: Some(16), ..Default::default() };
        let px =
            pbrt_sppm::integrators::render(&RenderScene::for_integrator(&s, true), &settings).unwrap().image.pixels;
        px.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / px.len() as f64
    };
    let (vcm, bdpt) = (mean(Techniques::All), mean(Techniques::Bdpt));
    assert!(bdpt > 0.0 && (vcm / bdpt - 1.0).abs() < 0.02, "vcm {vcm}, bdpt {bdpt}");
}

/// pbrt-v3 does not know pbrt-v4's medium types: it warns and what they fill is vacuum.
#[test]
fn a_v4_medium_type_in_a_v3_file_is_vacuum_with_a_warning() {
    let text = "Film \"image\" MakeNamedMedium \"smoke\" \"string type\" \"uniformgrid\" \"float density\" [1] \
                WorldBegin AttributeBegin MediumInterface \"smoke\" \"\" Material \"\" Shape \"sphere\" AttributeEnd WorldEnd";
    let s = scene(text);
    assert!(s.media.is_empty(), "{:?}", s.media);
    let skipped: Vec<_> = s.skipped.iter().filter(|k| k.what.contains("uniformgrid")).collect();
    assert!(skipped.len() == 1 && skipped[0].why.contains("pbrt-v3 has no such medium type"), "{:?}", s.skipped);
}

/// With beams, photons in media are gathered in blocks that fill at the same photon
/// chunks whatever the bands a preview cuts the photon pass into: the image is the same
/// bit for bit with tev watching or not, and the beams add light the points would
/// (the fog box's in-scattered indirect light).
#[test]
fn beams_give_the_same_image_with_a_preview_and_without() {
    use pbrt_sppm::integrators::sppm::Sppm;
    let desc = crate::common::load_file(&crate::common::root().join("pbrt-scenes/verify/v4-fog-box.pbrt")).unwrap();
    let rs = RenderScene::new(&desc);
    let render = |gather, preview: bool| {
        let mut sppm = Sppm::new(&rs, 2, 60_000, 0.1, 0, Default::default()).unwrap().with_volume_gather(gather);
        for _ in 0..2 {
            let mut shown = 0;
            let mut show = |_: &dyn Fn() -> Vec<[f32; 3]>| shown += 1;
            sppm.iterate_showing(preview.then_some(&mut show));
            assert_eq!(shown > 0, preview);
        }
        sppm.image()
    };
    let (watched, alone) = (render(VolumeGather::Beams, true), render(VolumeGather::Beams, false));
    assert!(watched == alone, "a preview changed the image");
    let (beams, points) = (mean(&alone), mean(&render(VolumeGather::Points, false)));
    assert!((beams[1] / points[1] - 1.0).abs() < 0.1, "beams {beams:?}, points {points:?}");
}

/// pbrt-v3 looks a medium's name up when a shape is made, and where it finds none
/// (never defined, defined later, or a definition it could not make) it says so and
/// goes on in vacuum; pbrt-v4 stops at each.
#[test]
fn v3_media_pbrt_v3_cannot_find_are_vacuum_and_v4_stops() {
    let sphere = "MediumInterface \"m\" \"\" Shape \"sphere\"";
    let defined = |params: &str| format!("MakeNamedMedium \"m\" {params}");
    for (before, why) in [
        (String::new(), "is not defined (MakeNamedMedium)"),
        (defined("\"rgb sigma_a\" [1 1 1]"), "no \"string type\""),
        (defined("\"string type\" \"plasma\""), "unknown medium type \"plasma\""),
        (defined("\"string type\" \"heterogeneous\""), "a grid without \"float density\" values"),
        (defined("\"string type\" \"heterogeneous\" \"integer nx\" 2 \"float density\" [1 2 3]"), "3 density values"),
    ] {
        let v3 = scene(&format!("{V3} WorldBegin {before} {sphere}"));
        assert!(v3.media.is_empty() && v3.shapes[0].media.inside.is_none(), "{before}: vacuum");
        let w: Vec<String> = warnings(&v3).into_iter().filter(|m| m.contains("vacuum")).collect();
        assert!(w.len() == 1 && w[0].contains(why), "{before}: {w:?}");
        let e = load(&format!("{V4} WorldBegin {before} {sphere}")).expect_err(&before).to_string();
        assert!(e.contains(":1:"), "{before}: located: {e}");
    }
    // A name used before its definition: vacuum there in v3, the definition in v4.
    let early = |film: &str| {
        format!(
            "{film} WorldBegin {sphere} Shape \"disk\" MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \
             Shape \"cylinder\" {sphere}"
        )
    };
    let inside = |s: &pbrt_sppm::scene::SceneDescription| s.shapes.iter().map(|s| s.media.inside).collect::<Vec<_>>();
    let v3 = scene(&early(V3));
    assert_eq!(inside(&v3), [None, None, Some(0), Some(0)]);
    let early_uses: Vec<_> = v3.warnings.iter().filter(|w| w.message.contains("before its MakeNamedMedium")).collect();
    let first_shape = early(V3).find("\"sphere\"").expect("a shape") as u32 + 1;
    assert!(early_uses.len() == 1 && early_uses[0].column == first_shape, "{early_uses:?}");
    assert_eq!(inside(&scene(&early(V4))), [Some(0); 4]);
}
