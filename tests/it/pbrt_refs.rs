//! Our images against pbrt's own (`tests/data/pbrt-ref/README.md` says how each
//! reference was made): channel means of the whole image and of each tile of a 4×4
//! grid, so a misplaced caustic or a wrong highlight shows even when the whole-image
//! mean hides it.

use crate::common::{load_file, root};
use pbrt_sppm::fixes::{Fix, Fixes};
use pbrt_sppm::imageio::{metrics, read_image};
use pbrt_sppm::integrators::beams::VolumeGather;
use pbrt_sppm::integrators::vcm::Techniques;
use pbrt_sppm::integrators::{Algorithm, RenderSettings};
use pbrt_sppm::render::RenderScene;
use std::ops::Range;

/// Renders `pbrt-scenes/verify/{name}.pbrt` at the scene's own budget and requires the
/// worst tile's channel means within `bound` of `tests/data/pbrt-ref/{name}.exr`
/// (relMSE is printed beside it).
pub fn assert_matches_pbrt(name: &str, bound: f64) {
    assert_matches_reference(name, Fixes::NONE, name, bound);
}

/// As [`assert_matches_pbrt`], rendered with `fixes` and compared with
/// `tests/data/pbrt-ref/{reference}.exr`.
pub fn assert_matches_reference(name: &str, fixes: Fixes, reference: &str, bound: f64) {
    assert_renders_as(name, fixes, Algorithm::Sppm, reference, bound);
}

/// As [`assert_matches_reference`], rendered with `algorithm` at the scene's budget.
pub fn assert_renders_as(name: &str, fixes: Fixes, algorithm: Algorithm, reference: &str, bound: f64) {
    let settings = RenderSettings { algorithm: Some(algorithm), ..Default::default() };
    assert_renders_with(name, fixes, &settings, reference, bound);
}

/// As [`assert_renders_as`], with these settings.
pub fn assert_renders_with(name: &str, fixes: Fixes, settings: &RenderSettings, reference: &str, bound: f64) {
    Check { name, fixes, settings: settings.clone(), reference, bound, share: 1, fine: None, colour: None }.assert();
}

/// The bound of a pbrt-v4 image test (issue 57): 2% on the worst 4×4 tile, or 1.5 ×
/// pbrt-v4's own deviation at the scene's budget (`own`, from
/// `tests/data/pbrt-ref/README.md`) where its own noise does not allow 2%.
pub fn v4_bound(own: f64) -> f64 {
    (1.5 * own).max(0.02)
}

/// The bound of a pbrt-v4 image test on an 8×8 grid (issue 57): 3%, or 1.5 × pbrt-v4's
/// own 8×8 deviation at the scene's budget (`own`: the mean of seeds 1 and 2, whose
/// samples are not the reference's; `docs/tests.md`) where its noise does not allow 3%.
/// Held where ours is within 0.8 of it.
pub fn v4_fine(own: f64) -> f64 {
    (1.5 * own).max(0.03)
}

/// One comparison with a pbrt reference, in full.
pub struct Check<'a> {
    /// `pbrt-scenes/verify/{name}.pbrt`, compared with `tests/data/pbrt-ref/{reference}.exr`.
    pub name: &'a str,
    pub reference: &'a str,
    pub fixes: Fixes,
    pub settings: RenderSettings,
    /// The worst tile's channel means may be this far off (relative).
    pub bound: f64,
    /// Render 1/share of the scene's iterations. The scene files' budgets were set for
    /// pbrt's own noise; where ours is well inside the bound with less (measured, and
    /// deterministic for a seed), the test renders less, at the same bound.
    pub share: u32,
    /// The worst tile of an 8×8 grid may be this far off, where it is checked.
    pub fine: Option<f64>,
    /// What paths carry (`--colour`), where not the file's pbrt's.
    pub colour: Option<pbrt_sppm::spectrum::transport::Colour>,
}

impl<'a> Check<'a> {
    /// The scene `name` with SPPM against its own reference at 1/`share` of its budget.
    pub fn sppm(name: &'a str, bound: f64, share: u32) -> Check<'a> {
        let settings = RenderSettings { algorithm: Some(Algorithm::Sppm), ..Default::default() };
        Check { name, reference: name, fixes: Fixes::NONE, settings, bound, share, fine: None, colour: None }
    }

    /// The scene `name` with SPPM against its own reference at `iterations`, more than
    /// the scene's budget where ours needs more than pbrt's to meet a v4 bound.
    pub fn sppm_iterations(name: &'a str, bound: f64, iterations: u32) -> Check<'a> {
        let settings =
            RenderSettings { algorithm: Some(Algorithm::Sppm), iterations: Some(iterations), ..Default::default() };
        Check { name, reference: name, fixes: Fixes::NONE, settings, bound, share: 1, fine: None, colour: None }
    }

    /// Also holds the worst tile of an 8×8 grid to `bound`.
    pub fn fine(self, bound: f64) -> Check<'a> {
        Check { fine: Some(bound), ..self }
    }

    pub fn assert(&self) {
        let name = self.name;
        let options = pbrt_sppm::scene::LoadOptions { colour: self.colour, ..Default::default() };
        let path = root().join(format!("pbrt-scenes/verify/{name}.pbrt"));
        let mut scene = pbrt_sppm::scene::load_scene(&path, &options).expect("the scene loads");
        scene.fixes = self.fixes;
        let mut settings = self.settings.clone();
        if self.share > 1 && settings.iterations.is_none() {
            settings.iterations = Some((scene.integrator.iterations / self.share).max(1));
        }
        let algorithm = settings.algorithm.unwrap_or(Algorithm::Sppm);
        let render_scene = RenderScene::for_integrator(&scene, algorithm != Algorithm::Sppm);
        let ours = pbrt_sppm::integrators::render(&render_scene, &settings).expect("renders").image;
        let gather = settings.volume_gather.map(|g| format!(", {}", g.name())).unwrap_or_default();
        let budget = match self.settings.iterations {
            Some(n) => format!("{n} iterations"),
            None => format!("1/{} budget", self.share),
        };
        let name = format!("{name} ({}{gather}, {}, {budget})", algorithm.name(), self.fixes.names());
        let path = root().join(format!("tests/data/pbrt-ref/{}.exr", self.reference));
        let reference = read_image(&path).expect("the reference");
        assert_eq!((ours.width, ours.height), (reference.width, reference.height));
        let (w, h) = (ours.width, ours.height);
        let (worst, at, _) = metrics::worst_mean_deviation(&ours.pixels, &reference.pixels, w, h, 4, 0.05);
        let (fine, fine_at, _) = metrics::worst_mean_deviation(&ours.pixels, &reference.pixels, w, h, 8, 0.05);
        let relmse = metrics::relmse(&ours.pixels, &reference.pixels);
        eprintln!(
            "{name}: worst tile deviation {:.2}% at {at} (8×8: {:.2}% at {fine_at}); relMSE {relmse:.2e}",
            100.0 * worst,
            100.0 * fine
        );
        let bound = self.bound;
        assert!(
            worst <= bound,
            "{name}: worst tile deviation {:.2}% at {at} (bound {}%)",
            100.0 * worst,
            100.0 * bound
        );
        if let Some(bound) = self.fine {
            assert!(
                fine <= bound,
                "{name}: worst 8×8 tile {:.2}% at {fine_at} (bound {}%)",
                100.0 * fine,
                100.0 * bound
            );
        }
    }
}

#[test]
fn a_glass_sphere_focuses_a_spot_light_as_in_pbrt_v3() {
    // pbrt-v3's own 64-iteration image: worst tile 0.38%, relMSE 6.8e-4.
    // A quarter of the scene's iterations: 0.98% when measured.
    Check::sppm("v3-caustic", 0.02, 4).assert();
}

#[test]
fn procedural_textures_and_mappings_match_pbrt_v3() {
    // pbrt-v3's own 16-iteration image: worst tile 0.33%, relMSE 1.4e-3.
    // A quarter of the scene's iterations: 0.55% when measured.
    Check::sppm("v3-textures", 0.02, 4).assert();
}

#[test]
fn procedural_textures_and_mappings_match_pbrt_v4() {
    // pbrt-v4's own 64-iteration image: worst tile 1.49%, relMSE 5.4e-3.
    // A quarter of the scene's iterations: 1.08% when measured (spectral).
    Check::sppm("v4-textures", v4_bound(0.0149), 4).fine(v4_fine(0.0279)).assert();
}

#[test]
fn alpha_masks_cut_meshes_and_their_shadows_as_in_pbrt_v3() {
    // pbrt-v3's own 64-iteration image: worst tile 1.09%, relMSE 4.0e-3.
    assert_matches_pbrt("v3-alpha", 0.02);
}

#[test]
fn stochastic_alpha_matches_pbrt_v4() {
    // pbrt-v4's own 64-iteration image: worst tile 1.98%, relMSE 3.9e-3. Ours: 2.75%.
    assert_matches_pbrt("v4-alpha", v4_bound(0.0198));
}

#[test]
fn bump_maps_shade_as_in_pbrt_v3() {
    // pbrt-v3's own 64-iteration image: worst tile 0.87%, relMSE 1.2e-3.
    assert_matches_pbrt("v3-bump", 0.02);
}

#[test]
fn displacement_shades_as_in_pbrt_v4() {
    // pbrt-v4's own 64-iteration image: worst tile 1.83%, relMSE 2.7e-3. Ours: 2.05%.
    Check::sppm("v4-bump", v4_bound(0.0183), 1).fine(v4_fine(0.0594)).assert();
}

#[test]
fn mix_blends_lobes_as_in_pbrt_v3() {
    // pbrt-v3's own 64-iteration image: worst tile 0.79%, relMSE 3.3e-3.
    assert_matches_pbrt("v3-mix", 0.02);
}

/// pbrt-v3's `directlighting` and `whitted` leave out indirect light and glossy
/// reflections of lit surfaces: a file asking for either renders their image by
/// default (a room with a glass ball, a mirror and a glossy block under a disk and a
/// point light), and vcm's full light transport is far from it there.
#[test]
fn directlighting_and_whitted_files_render_pbrt_v3s_image() {
    let direct = Algorithm::Vcm(Techniques::Direct);
    for name in ["v3-directlighting", "v3-whitted"] {
        let scene = load_file(&root().join(format!("pbrt-scenes/verify/{name}.pbrt"))).expect("the scene loads");
        assert_eq!(Algorithm::by_default(&scene.integrator), direct, "{name}");
        // pbrt-v3's own 64-sample image: worst tile 0.16%, relMSE 1.1e-4 (a prefix of
        // its reference); ours 0.14% (0.06–0.16% with seeds 0–2), 0.02% at 1,024.
        // Picking one specular branch at random instead of following both left 1.31%.
        // A quarter of the scene's samples: 0.20% when measured.
        let settings = RenderSettings { algorithm: Some(direct), ..Default::default() };
        Check { settings, ..Check::sppm(name, 0.01, 4) }.assert();
    }
    // The same file with everything vcm finds: 1.8 times as bright, 300% off a tile.
    let scene = load_file(&root().join("pbrt-scenes/verify/v3-directlighting.pbrt")).expect("the scene loads");
    let settings = RenderSettings { algorithm: Some(Algorithm::Vcm(Techniques::All)), ..Default::default() };
    let vcm = pbrt_sppm::integrators::render(&RenderScene::for_integrator(&scene, true), &settings).expect("renders");
    let reference = read_image(&root().join("tests/data/pbrt-ref/v3-directlighting.exr")).expect("the reference");
    let mean = |p: &[[f32; 3]]| p.iter().map(|c| (c[0] + c[1] + c[2]) as f64).sum::<f64>();
    let ratio = mean(&vcm.image.pixels) / mean(&reference.pixels);
    assert!(ratio > 1.5, "vcm over pbrt-v3's directlighting: {ratio}");
    // The warning says what renders each file, and never claims vcm's image for an
    // integrator whose output is not light.
    let said = |integrator: &str| {
        let s = crate::common::scene(&format!("Integrator \"{integrator}\" Film \"rgb\" WorldBegin Shape \"sphere\""));
        crate::common::warnings(&s).join("\n")
    };
    assert!(said("whitted").contains("\"whitted\" is rendered with direct"), "{}", said("whitted"));
    assert!(said("path").contains("converges to the same image"), "{}", said("path"));
    let ao = said("ambientocclusion");
    assert!(ao.contains("not this integrator's output") && !ao.contains("same image"), "{ao}");
}

/// pbrt-v3's directlighting lights its first hit whatever `maxdepth` says (the depth
/// bounds only the specular recursion): at 0 its image is the one at 1, direct light
/// without reflections in the glass and the mirror, not black.
#[test]
fn directlighting_at_maxdepth_0_still_lights_what_the_camera_sees() {
    let path = root().join("pbrt-scenes/verify/v3-directlighting.pbrt");
    let text = std::fs::read_to_string(&path).expect("the scene");
    let render = |depth: u32| {
        let text = text
            .replace("\"integer maxdepth\" 5", &format!("\"integer maxdepth\" {depth}"))
            .replace("include/", &format!("{}/include/", path.parent().unwrap().display()));
        let scene = crate::common::scene(&text);
        let settings = RenderSettings { iterations: Some(8), ..Default::default() };
        pbrt_sppm::integrators::render(&RenderScene::for_integrator(&scene, true), &settings).expect("renders").image
    };
    let (zero, one, five) = (render(0), render(1), render(5));
    assert_eq!(zero.pixels, one.pixels, "maxdepth 0 and 1 render the same paths");
    let mean = |p: &[[f32; 3]]| p.iter().map(|c| (c[0] + c[1] + c[2]) as f64).sum::<f64>();
    // Only the light seen through the ball and in the mirror is missing (measured 0.93).
    let ratio = mean(&zero.pixels) / mean(&five.pixels);
    assert!((0.85..0.99).contains(&ratio), "maxdepth 0 over 5: {ratio}");
}

#[test]
fn mix_chooses_a_material_as_in_pbrt_v4() {
    // pbrt-v4's own 64-iteration image: worst tile 2.17%, relMSE 4.4e-3.
    // Half the scene's iterations: 2.81% when measured (spectral).
    Check::sppm("v4-mix", v4_bound(0.0217), 2).assert();
}

#[test]
fn coated_materials_and_diffuse_transmission_match_pbrt_v4() {
    // pbrt-v4's own 128-iteration image: worst tile 0.80%, relMSE 2.4e-3.
    // Twice the scene's iterations: 0.54%, 0.67%, 1.42% (the default seed, seeds 1
    // and 2); at its own 128, 0.73–2.17% (one seed's bright path).
    Check::sppm_iterations("v4-coated", v4_bound(0.0080), 256).fine(v4_fine(0.0656)).assert();
}

#[test]
fn a_mirror_box_reflects_light_and_caustics_as_in_pbrt_v3() {
    // pbrt-v3's own 64-iteration image: worst tile 0.87%, relMSE 6.5e-4.
    // Half the scene's iterations: 0.59% when measured.
    Check::sppm("v3-mirror-box", 0.02, 2).assert();
}

#[test]
fn normal_maps_shade_as_in_pbrt_v4() {
    // pbrt-v4's own 64-iteration image: worst tile 1.58%, relMSE 5.8e-4.
    // Four times the scene's iterations: 1.34%, 0.71%, 1.31% (the default seed, seeds
    // 1 and 2); twice: 2.46%, 0.90%, 2.23%.
    Check::sppm_iterations("v4-normalmap", v4_bound(0.0158), 256).assert();
}

#[test]
fn bilinear_patches_render_as_in_pbrt_v4() {
    // pbrt-v4's own 64-iteration image: worst tile 1.44%, relMSE 2.6e-3.
    // Four times the scene's iterations: 0.78%, 0.58%, 1.66% (the default seed, seeds
    // 1 and 2); twice: 0.94%, 1.25%, 3.03%.
    Check::sppm_iterations("v4-bilinear", v4_bound(0.0144), 256).fine(v4_fine(0.0645)).assert();
}

#[test]
fn v3_materials_side_by_side_match_pbrt_v3() {
    // plastic, uber, translucent, substrate, Oren–Nayar matte, rough glass and rough
    // anisotropic metal. pbrt-v3's own 128-iteration image: worst tile 0.76%, relMSE 2.3e-3.
    // Half the scene's iterations: 0.98% when measured.
    Check::sppm("v3-materials", 0.02, 2).assert();
}

#[test]
fn a_v3_metal_reads_eta_and_k_from_spd_files_as_pbrt_v3() {
    // pbrt-v3's own 128-iteration image: worst tile 0.22%, relMSE 2.9e-4. The metal's
    // tiles are about 0.4% greener than pbrt-v3's at every seed (the reduction of the
    // sampled spectra to RGB differs that little).
    // A quarter of the scene's iterations: 0.76% when measured.
    Check::sppm("v3-metal-spd", 0.02, 4).assert();
}

#[test]
fn a_v4_ply_files_quads_are_bilinear_patches_as_in_pbrt_v4() {
    // pbrt-v4's own 64-iteration image: worst tile 1.45%, relMSE 3.4e-4. Read as
    // pbrt-v3 reads the file (quads split in two), ours is 22% off.
    // A quarter of the scene's iterations: 1.59% when measured (spectral).
    Check::sppm("v4-ply-quads", v4_bound(0.0145), 4).assert();
}

#[test]
fn rough_glass_refracts_and_reflects_as_in_pbrt_v3() {
    // An isotropic and an anisotropic rough glass sphere (1024 iterations of 25,000
    // photons). pbrt-v3's own 1024-iteration image: worst tile 1.53%, relMSE 2.1e-3.
    // With the anisotropic sphere's u and v roughness swapped, ours is 12.7% off.
    // Half the photons (the noise here is mostly the camera paths'): 1.24% at the
    // default seed and 1.19%, 1.73%, 2.02% at seeds 1–3 (2 December; a quarter of the
    // photons: 2.83%, 2.29%, 4.02%, the floor's corners). Close to the bound at some
    // seeds: a sampling change that moves this figure needs more iterations here.
    let settings = RenderSettings { algorithm: Some(Algorithm::Sppm), photons: Some(12_500), ..Default::default() };
    Check { settings, ..Check::sppm("v3-rough-glass", 0.02, 1) }.assert();
}

/// `pbrt-scenes/verify/{name}.pbrt` rendered with these fixes and settings.
fn render_verify(name: &str, fixes: Fixes, settings: &RenderSettings) -> pbrt_sppm::imageio::RgbImage {
    let path = root().join(format!("pbrt-scenes/verify/{name}.pbrt"));
    let mut scene = load_file(&path).expect("the scene loads");
    scene.fixes = fixes;
    let sppm = settings.algorithm == Some(Algorithm::Sppm);
    let render_scene = RenderScene::for_integrator(&scene, !sppm);
    pbrt_sppm::integrators::render(&render_scene, settings).expect("renders").image
}

/// The mean of every channel over `rows` × `cols` of an image.
fn region_mean(image: &pbrt_sppm::imageio::RgbImage, rows: Range<usize>, cols: Range<usize>) -> f64 {
    let w = image.width;
    let inside = |i: &usize| rows.contains(&(i / w)) && cols.contains(&(i % w));
    let (sum, n) = (0..image.pixels.len())
        .filter(inside)
        .fold((0.0, 0), |(s, n), i| (s + image.pixels[i].iter().map(|&c| c as f64).sum::<f64>(), n + 1));
    sum / (3 * n) as f64
}

/// The frosted ball of `v3-rough-transmission.pbrt` (rows 12–51, columns 14–49).
fn ball_mean(image: &pbrt_sppm::imageio::RgbImage) -> f64 {
    region_mean(image, 12..52, 14..50)
}

#[test]
fn frosted_glass_transmits_as_in_pbrt_v3s_bdpt() {
    // pbrt-v3's rough transmission passes light through microfacets facing away from
    // ωo, which its sampling never returns but its density counts: bdpt's MIS weights
    // then give that light part of its share. Ours keep pbrt-v3's density. The ball
    // against pbrt-v3's bdpt (16,384 samples), ours at the file's 256 samples: −0.41%,
    // −0.42%, −0.94% (seeds 0–2; whole image −0.3 to +0.2%). With the density of the
    // facets sampling returns (what we had before), +4.3%, +3.1%, +2.8%; with
    // `--fix rough-transmission`, −2.1%, −2.0%, −2.5%.
    let reference = read_image(&root().join("tests/data/pbrt-ref/v3-rough-transmission.exr")).unwrap();
    let ours = render_verify("v3-rough-transmission", Fixes::NONE, &RenderSettings::default());
    let (a, b) = (ball_mean(&ours), ball_mean(&reference));
    eprintln!("v3-rough-transmission, the ball: ours {a}, pbrt-v3's bdpt {b}");
    assert!((a / b - 1.0).abs() < 0.015, "the ball: ours {a}, pbrt-v3's bdpt {b}");
    // Tile by tile, against gross errors (a missing light, a misplaced highlight): the
    // 4×4 grid's worst tile at 256 samples is noise-bound, 3.0%, 1.5%, 7.4% (seeds 0–2,
    // the dim top row), where the ball's mean above is not.
    let (w, h) = (ours.width, ours.height);
    let (worst, at, _) = metrics::worst_mean_deviation(&ours.pixels, &reference.pixels, w, h, 4, 0.05);
    assert!(worst < 0.10, "worst tile {:.2}% at {at}", 100.0 * worst);
}

#[test]
fn fixed_rough_transmission_leaves_out_back_facing_facets_for_every_technique() {
    // With the fix, f and the density leave out the same facets: bdpt's ball equals
    // next-event estimation's alone (which never weighs against a density). At 128
    // passes (seeds 0–2): 1.29%, 0.55%, −0.24% apart. Were f left on those facets
    // with the density fixed (as we had before), bdpt's ball would be 3–4% brighter
    // than pbrt-v3's and next-event estimation's 2.5% darker. The same samples without
    // the fix: next-event estimation alone 2.1–2.2% brighter (the light those facets
    // pass at its last vertex).
    let fixed = Fixes::NONE.with(Fix::RoughTransmission);
    let mean = |algorithm, fixes| {
        let settings = RenderSettings { algorithm: Some(algorithm), iterations: Some(128), ..Default::default() };
        ball_mean(&render_verify("v3-rough-transmission", fixes, &settings))
    };
    let direct = Algorithm::Vcm(Techniques::Only(pbrt_sppm::integrators::vcm::Technique::Direct));
    let (all, alone) = (mean(Algorithm::Vcm(Techniques::Bdpt), fixed), mean(direct, fixed));
    let unfixed = mean(direct, Fixes::NONE);
    eprintln!("v3-rough-transmission, the ball: fixed bdpt {all}, next-event estimation {alone} ({unfixed} unfixed)");
    assert!((all / alone - 1.0).abs() < 0.025, "fixed: bdpt {all}, next-event estimation alone {alone}");
    assert!(alone < 0.99 * unfixed, "next-event estimation alone: fixed {alone}, unfixed {unfixed}");
}

#[test]
fn plastic_keeps_pbrt_v3s_swapped_fresnel_by_default() {
    // Under a disk area light: the spheres' highlights and the plastic wall. With the
    // fix, ours is 21.8% off pbrt-v3 here.
    // Half the scene's iterations: 1.02% when measured.
    Check::sppm("v3-plastic", 0.02, 2).assert();
}

#[test]
fn fixed_plastic_matches_pbrt_v3_on_reversed_surfaces() {
    // pbrt-v3's swapped indices are right on reversed surfaces: the reference is
    // pbrt-v3's render of the scene with every plastic shape `ReverseOrientation`ed
    // (the physically right coat). Unfixed, ours is 26.8% off it.
    // Half the scene's iterations: 0.60% when measured.
    let fixes = Fixes::NONE.with(Fix::PlasticFresnel);
    Check { fixes, reference: "v3-plastic-reversed", ..Check::sppm("v3-plastic", 0.02, 2) }.assert();
}

#[test]
fn glossy_metal_under_a_sky_is_as_bright_as_in_pbrt_v3() {
    // pbrt-v3 counts the sky twice after a glossy bounce (`--fix sky-after-glossy`).
    assert_matches_pbrt("v3-sky", 0.02);
}

#[test]
fn marble_leaves_its_palette_as_in_pbrt_v3() {
    // A quarter of the scene's iterations: 0.77% when measured.
    Check::sppm("v3-marble", 0.02, 4).assert();
}

#[test]
fn smooth_and_rough_coats_and_mesh_power_match_pbrt_v4() {
    // pbrt-v4's SPPM reflects the disk light in the smooth coats (it follows the path
    // one bounce past the visible point), weighs the rough coat's layers its own way,
    // and gives each triangle of the emitting strip the whole `power`.
    // pbrt-v4's own 128-iteration image: worst tile 0.91%. Ours at the scene's 128
    // iterations (the default seed, seeds 1–3): 2.23%, 0.92%, 0.79%, 1.51%, and on the
    // 8×8 grid 6.65%, 3.44%, 4.14%, 3.79% (the light choice of 2 December; before it
    // 1.11–1.67% and 2.93–7.68%: a few tiles hold rare bright paths). At 192: 1.48%,
    // 1.19%, 0.73%, 0.88%; 8×8 3.28%, 3.58%, 3.92%, 2.80%.
    Check::sppm_iterations("v4-coat", v4_bound(0.0091), 192).fine(v4_fine(0.0281)).assert();
}

#[test]
fn rough_glass_refracts_and_reflects_as_in_pbrt_v4() {
    // pbrt-v4's own 64-iteration image: worst tile 1.48%, relMSE 3.1e-3.
    // Three times the scene's iterations: 1.11%, 1.07%, 0.82% (the default seed,
    // seeds 1 and 2); twice: 1.09%, 1.93%, 1.05%; once: 1.86–3.79%.
    Check::sppm_iterations("v4-rough-glass", v4_bound(0.0148), 192).fine(v4_fine(0.0444)).assert();
}

#[test]
fn the_disney_material_matches_pbrt_v3() {
    // Clearcoat and sheen, an anisotropic rough metal, half metal, a thin leaf lit from
    // behind, under a sky, a disk and a point light. pbrt-v3's own 128-iteration
    // image: worst tile 0.71%. Ours at 128 (the default seed, seeds 1–3): 0.49%,
    // 0.88%, 0.87%, 1.14%; at 512 1.10%, every other tile within 0.3%. Wrong in one
    // part, at the default seed: Smith's correlated masking for the separable 4.6%, no
    // clearcoat 2.3%, no sheen 2.1%, Lambert for the Fresnel diffuse 2.1%, `difftrans`
    // not halved 22%.
    Check::sppm_iterations("v3-disney", 0.02, 128).assert();
}

#[test]
fn a_displaced_ply_mesh_is_refined_and_displaced_as_in_pbrt_v4() {
    // An icosphere refined to edges under 0.08 and displaced by a (u, v) ramp times
    // fBm. pbrt-v4's own 64-iteration image: worst tile 1.45%. Ours (the default
    // seed, seeds 1–3): 0.75%, 1.78%, 1.20%, 1.31%. Unrefined (the file's 80
    // triangles displaced): 41.6%.
    Check::sppm("v4-displacement", v4_bound(0.0145), 1).assert();
}

#[test]
fn thin_glass_reflects_and_passes_light_straight_as_in_pbrt_v4() {
    // A pane and a bubble of `thindielectric` under a spot and a disk light: the floor
    // lit through the pane, the wall lit by what both its faces reflect. pbrt-v4's own
    // 64-iteration image: worst tile 2.04%, 8×8 4.70%. Ours at twice that (the
    // default seed, seeds 1–3): 2.40%, 1.75%, 1.28%, 0.85%; 8×8 3.1–5.6%; at 64,
    // 1.2–3.0% over six seeds. One face's reflectance in place of the pane's (no light
    // bounced between its faces): 14.2% off.
    Check::sppm_iterations("v4-thin-glass", v4_bound(0.0204), 128).fine(v4_fine(0.0470)).assert();
}

#[test]
fn translucent_reflects_and_transmits_as_in_pbrt_v3() {
    // A sphere and a thin panel, lit from both sides (disk area light, point light).
    // A quarter of the scene's iterations: 1.12% when measured.
    Check::sppm("v3-translucent", 0.02, 4).assert();
}

#[test]
fn a_named_camera_sensor_with_white_balance_films_as_in_pbrt_v4() {
    // A Canon balanced for 3200 K under 3200 K light: its curves and fitted matrix
    // decide the colours. pbrt-v4's own 64-iteration image: worst tile 1.22%. Ours at
    // three times the budget: 1.34%, 1.09%, 1.22% (the default seed, seeds 1 and 2);
    // at the budget 1.19–2.32%. Seen as the CIE observer (`--colour rgb`, balanced the
    // same) it is 11.5% off, and without the balance 84%.
    Check::sppm_iterations("v4-sensor", v4_bound(0.0122), 192).fine(v4_fine(0.0479)).assert();
}

#[test]
fn diffuse_transmission_matches_pbrt_v4() {
    // pbrt-v4's own 128-iteration image: worst tile 1.25%.
    // A quarter of the scene's iterations: 1.72% when measured (spectral).
    Check::sppm("v4-difftrans", v4_bound(0.0125), 4).assert();
}

#[test]
fn sphere_and_disk_lights_are_sampled_as_pbrt_v3_samples_them() {
    // A scaled sphere light, a hemisphere light and an annulus light. With `--fix
    // shape-sampling`, ours is 390% off pbrt-v3 here.
    // A quarter of the scene's iterations: 0.52% when measured.
    Check::sppm("v3-shape-lights", 0.02, 4).assert();
}

#[test]
fn a_scaled_sphere_light_is_sampled_as_pbrt_v3_samples_it() {
    // pbrt-v3 samples it with its object radius and area: 97% darker than the same
    // light with the scale folded into its radius.
    assert_matches_pbrt("v3-sphere-light", 0.02);
}

#[test]
fn a_fixed_scaled_sphere_light_is_the_sphere_of_the_scaled_radius() {
    // The independent answer: pbrt-v3's render of the same light as a radius-0.45
    // sphere without the scale, which pbrt samples right.
    let fix = Fixes::NONE.with(Fix::ShapeSampling);
    // A quarter of the scene's iterations: 0.78% when measured.
    Check { fixes: fix, reference: "v3-sphere-light-unscaled", ..Check::sppm("v3-sphere-light", 0.02, 4) }.assert();
}

#[test]
fn a_hyperboloid_is_pbrt_v3s_implicit_fit() {
    // Its segment passes closest to the axis away from z = 0. With `--fix
    // hyperboloid-surface`, ours is 99.6% off pbrt-v3 here.
    assert_matches_pbrt("v3-hyperboloid", 0.02);
}

#[test]
fn a_fixed_hyperboloid_is_the_surface_its_segment_sweeps() {
    // The independent answer: pbrt-v3's render of the swept surface as a 96 × 32 mesh
    // with its normals. The facets alone leave 1.0–1.4% in the rim's tile (our render
    // of the mesh against pbrt-v3's: 1.0%), hence 3%. As pbrt-v3 (unfixed), 51% off.
    let fix = Fixes::NONE.with(Fix::HyperboloidSurface);
    // Half the scene's iterations: 0.78% when measured.
    Check { fixes: fix, reference: "v3-hyperboloid-mesh", ..Check::sppm("v3-hyperboloid", 0.03, 2) }.assert();
}

#[test]
fn nurbs_patches_and_height_fields_are_diced_as_pbrt_v3_dices_them() {
    // A rational bicubic patch (weights 0.6–2.5), a quadratic one over part of its
    // knot range, a height field with a checkerboard in its (u, v). Its control points
    // taken as weight-1 points: 245% off pbrt-v3 here.
    // A quarter of the scene's iterations: 0.71% when measured.
    Check::sppm("v3-nurbs-heightfield", 0.02, 4).assert();
}

#[test]
fn curves_of_every_type_and_basis_render_as_in_pbrt_v3() {
    // Flat, cylinder and ribbon; Bézier and B-spline; cubic and quadratic; a tuft of
    // thin cylinders. pbrt-v3's own 128-iteration image: worst tile 2.4% (a glossy
    // highlight's noise), ours 1.6–2.3% over three seeds. The cylinders drawn flat: 15%
    // off; the ribbon drawn flat: 73%.
    assert_matches_pbrt("v3-curves", 0.04);
}

#[test]
fn curves_render_as_in_pbrt_v4_which_samples_lights_from_their_error_bound() {
    // The same curves in a v4 file. pbrt-v4's own 128-sample image: worst tile 1.5%;
    // ours 2.09%, 2.43%, 2.38% (the default seed, seeds 1 and 2), at twice that 2.48%,
    // 2.44%, 5.16%, at four times 1.20%, 1.67%, 3.19%. Not held to its 2.25%
    // (`v4_bound`): seed 2's outlier is one camera path (in iterations 161–192) that
    // puts 594 into one pixel, 4.5% of its tile's mean. Sampling lights from the curve
    // itself (as for v3 files): 8.2% off, at the wide ribbon.
    assert_matches_pbrt("v4-curves", 0.04);
}

#[test]
fn hair_scatters_as_in_pbrt_v3() {
    // Tufts of hair by sigma_a, colour and melanin, and a wide flat fibre. pbrt-v3's own
    // 128-iteration image: worst tile 0.94%; ours 0.51–1.01% over three seeds. Drawn
    // as the grey diffuse it was before: 70% off.
    // Half the scene's iterations: 1.11% when measured.
    Check::sppm("v3-hair", 0.02, 2).assert();
}

#[test]
fn hair_scatters_as_in_pbrt_v4_with_its_spectral_absorption() {
    // The same fibres in a v4 file. pbrt-v4 absorbs per wavelength, and so do our
    // spectral paths: 1.11% (pbrt-v4's own 128-sample image: 0.87%). Absorbing per RGB
    // channel, as before spectral rendering, the orange and brown fibres were 4.8–5.1%
    // redder than pbrt-v4's over three seeds.
    assert_matches_pbrt("v4-hair", v4_bound(0.0087));
}

#[test]
fn textures_and_skies_of_every_image_format_read_as_in_pbrt_v3_and_v4() {
    // The same picture as TGA (bottom-up; run-length encoded, gamma off), PFM (with
    // gamma on too, which pbrt-v3 applies to floats), PNG and JPEG (pbrt-v3's grey
    // texel), and as float textures (pbrt-v3's luminance of the stored values), under
    // a PNG sky whose values pbrt-v3's infinite light takes as stored. pbrt-v3's own
    // 64-iteration image: 0.13% (the reference's first iterations); ours 0.35%, 0.40%,
    // 0.42% (seeds 0–2). Before TGA and PFM were read, the v3 sky kept its stored
    // values and float textures took their images' grey: 69%.
    assert_matches_pbrt("v3-image-formats", 0.02);
    // pbrt-v4: TGA (its `encoding "linear"` ignored, as stb_image's formats are in
    // pbrt-v4), JPEG, BMP, HDR, PFM, a linear PNG, float textures (the mean of the
    // channels) and an RGBA PNG's alpha cutting a tile, under an sRGB-decoded PNG sky.
    // pbrt-v4's own 64-sample images (seeds 1, 2): 1.50%, 1.46%; ours 0.45%, 0.54%,
    // 0.51% (seeds 0–2). With only EXR and PNG read and float textures of the red
    // channel: 23%.
    assert_matches_pbrt("v4-image-formats", v4_bound(0.0150));
    // pbrt-v4's other formats: GIF, binary PPM and PGM (their `encoding` ignored), QOI
    // (sRGB, linear by its header, its `encoding` ignored), float textures of them and
    // an RGBA QOI's alpha cutting a tile. pbrt-v4's own 64-sample images (seeds 1, 2):
    // 1.49%, 1.50%; ours 0.50%, 0.64%, 0.62% (seeds 0–2). With the linear QOI read as
    // sRGB: 8.8%; with the QOI's alpha unread: 17%.
    assert_matches_pbrt("v4-more-formats", v4_bound(0.0150));
}

#[test]
fn the_films_sample_clamp_is_pbrts() {
    // An orange sphere light seen directly, in a near-mirror and in a glossy ball, under
    // pbrt-v3's `maxsampleluminance` 4 (its `path`) and pbrt-v4's `maxcomponentvalue` 4
    // (its `volpath`); ours by vcm, as the files ask. Unclamped, ours is 310% (v3) and
    // 510% (v4) off pbrt's images on the light. pbrt's own 64-sample images: 1.81% (v3),
    // 1.62% and 1.54% (v4, seeds 1, 2). Ours, seeds 0–2: 8.78%, 8.42%, 8.53% (v3),
    // 6.45%, 8.19%, 8.64% (v4). The rest is what a clamp of each sample cannot share
    // between estimators: where pbrt's path tracer puts a highlight's light in a few
    // large samples, it clamps more of it than vcm does, whose samples are smaller
    // (the balls' highlights 12–18% brighter than pbrt's on 8×8 tiles). And pbrt-v4
    // clamps each sample's estimate from four wavelengths, ours from three, whose
    // estimates spread wider and lose more: the clamped light is 7% darker in red.
    let vcm = Algorithm::Vcm(Techniques::All);
    assert_renders_as("v3-max-luminance", Fixes::NONE, vcm, "v3-max-luminance", 0.12);
    assert_renders_as("v4-max-component", Fixes::NONE, vcm, "v4-max-component", 0.12);
}

#[test]
fn a_sky_seen_through_a_portal_lights_the_room_as_in_pbrt_v4() {
    // A room lit by an equal-area sky through a window that is the light's portal,
    // beside a skylight that is not: the skylight shows black and lets in no direct
    // light. pbrt-v4's SPPM sends photons from the portal's half of the sky across the
    // whole scene, so some come in through the skylight: ours as its. pbrt-v4's own
    // 64-sample images (seeds 1, 2): 3.34%, 3.92%; ours 4.18%, 3.01%, 3.16% (seeds 0–2;
    // 2.10% at 256). With the portal ignored (the whole sky, as before): 618%.
    Check::sppm("v4-portal", v4_bound(0.0363), 1).assert();
    // With `--fix portal-photons` the photons come in through the portal alone, and
    // SPPM agrees with pbrt-v4's path tracer (its 4,096-sample image), which sees the
    // sky only through the portal too: 1.84%, 1.23%, 1.57% (seeds 0–2) at half the
    // photons, which all come in (10 s at the file's 100,000; 1.36%, 1.16% there).
    // pbrt-v4's SPPM image is 46% off it, under the skylight.
    let fixed = Fixes::NONE.with(Fix::PortalPhotons);
    let settings = RenderSettings { algorithm: Some(Algorithm::Sppm), photons: Some(50_000), ..Default::default() };
    Check { reference: "v4-portal-path", fixes: fixed, settings, ..Check::sppm("v4-portal", 0.03, 1) }.assert();
    // vcm's light subpaths enter through the portal (their emission must match the
    // light's radiance): 1.36%, 1.02% (seeds 0, 1) at 32 passes of 20,000.
    let settings = RenderSettings {
        algorithm: Some(Algorithm::Vcm(Techniques::All)),
        iterations: Some(32),
        photons: Some(20_000),
        ..Default::default()
    };
    Check { reference: "v4-portal-path", settings, ..Check::sppm("v4-portal", 0.03, 1) }.assert();
}

#[test]
fn grey_and_rgba_exr_textures_read_as_in_pbrt_v3_and_v4() {
    // A luminance-only EXR (channel Y) as a colour, a mix amount and (v3) with gamma
    // on; an RGBA EXR as a colour and as float textures: pbrt-v3 takes the colour's
    // luminance, pbrt-v4 the alpha (also cutting a tile). pbrt-v3's own 64-iteration
    // image: 0.21% (the reference's first iterations); ours 0.56%, 0.66% (seeds 0, 1).
    // With the grey EXR unread (its stand-in texel, as before grey EXRs were read): 15%.
    assert_matches_pbrt("v3-exr-channels", 0.02);
    // pbrt-v4's own 64-sample images (seeds 1, 2): 1.55%, 1.40%; ours 0.99%, 1.27%,
    // 0.72% (seeds 0–2). With the RGBA file's alpha unread (its colours' mean, as
    // before): 21%.
    assert_matches_pbrt("v4-exr-channels", v4_bound(0.0148));
}

#[test]
fn the_environment_camera_sees_every_direction_as_pbrt_v3() {
    // A room seen whole, latitude by longitude. pbrt-v3's own 64-iteration image:
    // worst tile 1.16%; ours 1.1–1.7% over three seeds. As the perspective camera it
    // used to fall back to: 122% off.
    assert_matches_pbrt("v3-environment", 0.02);
}

#[test]
fn the_spherical_camera_lays_the_sphere_on_an_equal_area_square_as_pbrt_v4() {
    // The same room in pbrt-v4's default mapping. pbrt-v4's own 64-sample image: worst
    // tile 1.87%; ours 1.6–2.1% over three seeds.
    // A quarter of the scene's iterations: 2.03% when measured (spectral).
    Check::sppm("v4-spherical", v4_bound(0.0187), 4).assert();
}

#[test]
fn goniometric_lights_read_their_profiles_as_pbrt_v3_and_v4() {
    // pbrt-v3: a latitude-longitude colour profile, bilinear; its own 64-iteration
    // image: worst tile 0.62%, ours 1.0–1.2% over three seeds (a point light of
    // intensity 5 instead: 129%). pbrt-v4: a square equal-area profile, the channels'
    // mean, nearest texel; its own 64-sample image 2.36%, ours 0.8–1.4% (0.90%
    // spectrally).
    assert_matches_pbrt("v3-goniometric", 0.02);
    assert_matches_pbrt("v4-goniometric", v4_bound(0.0236));
}

#[test]
fn a_v4_environment_map_lights_the_scene_from_its_equal_area_square_as_pbrt_v4() {
    // A square sky with a small sun, turned about two axes: seen directly, in a mirror
    // sphere and by its light and shadows. pbrt-v4's own 64-sample image: worst tile
    // 1.87%, relMSE 7.5e-3; ours with SPPM 0.9–1.6% over three seeds, with vcm 1.6–1.9%.
    // Read as a latitude-longitude map, as before pbrt-v4's mapping was followed: 158%.
    // Spectrally: SPPM 2.50%, vcm 1.55%.
    assert_matches_pbrt("v4-envmap", v4_bound(0.0187));
    assert_renders_as("v4-envmap", Fixes::NONE, Algorithm::Vcm(Techniques::All), "v4-envmap", v4_bound(0.0187));
}

#[test]
fn v4_image_area_lights_emit_their_image_over_the_surfaces_uv_as_pbrt_v4() {
    // A two-sided quad screen and a sphere emitting an 8 x 4 image (warm top, cool
    // bottom, one green corner texel), seen directly and by their light. pbrt-v4's own
    // 64-sample image: worst tile 1.76%, relMSE 3.5e-4; ours with SPPM 2.3–3.0% over
    // three seeds, with vcm 0.5–0.9%. Emitting L uniformly, as before image area lights
    // were read: 969%.
    // Spectrally, SPPM at four times the budget: 0.96%, 1.40%, 0.84% (the default
    // seed, seeds 1 and 2); three times: 1.43–2.54%; once: 1.85–3.22%. vcm: 1.41%.
    Check::sppm_iterations("v4-image-light", v4_bound(0.0176), 256).assert();
    let vcm = Algorithm::Vcm(Techniques::All);
    assert_renders_as("v4-image-light", Fixes::NONE, vcm, "v4-image-light", v4_bound(0.0176));
}

#[test]
fn projection_lights_cast_their_slides_as_pbrt_v3_and_v4() {
    // pbrt-v3 projects the slide upside down, bilinearly; its own 64-iteration image:
    // worst tile 1.14%, ours 1.3–1.7% over three seeds. pbrt-v4 the right way up,
    // nearest texel: its own image 2.03%; ours, spectral, at three times the budget
    // 1.54%, 1.89%, 1.37% (the default seed, seeds 1 and 2), at the budget 2.2–3.2%.
    assert_matches_pbrt("v3-projection", 0.02);
    Check::sppm_iterations("v4-projection", v4_bound(0.0203), 192).fine(v4_fine(0.0395)).assert();
}

#[test]
fn an_alpha_cut_light_still_emits_and_a_scaled_bumped_sphere_shades_as_in_pbrt_v3() {
    // With `--fix area-alpha` ours is 49% off pbrt-v3 here (the cut-away squares stop
    // emitting); `--fix normal-derivatives` moves no tile by more than the noise.
    assert_matches_pbrt("v3-alpha-light-bump", 0.02);
}

#[test]
fn vcm_renders_the_verification_scenes_as_pbrt_within_the_same_bounds() {
    // Each scene at its own budget (vcm passes = its SPPM iterations), against pbrt's
    // image and with SPPM's bound. Left out: scenes whose pbrt SPPM image is not the
    // scene's converged image, so that no correct method matches it: `v3-sky` (pbrt-v3
    // counts the sky twice after glossy bounces), `v3-alpha-light-bump` (pbrt-v3's
    // cut-away light parts emit photons), `v4-coat` (pbrt-v4's layered weights),
    // `v3-shape-lights` (pbrt's object-space shape sampling; `v3-sphere-light` checks
    // the fix against an independent image), `v4-bilinear` (pbrt-v4's SPPM and bdpt
    // differ by 77% on its light); `v3-mix` and `v4-alpha` are checked against pbrt's
    // bdpt instead (their SPPM images differ from pbrt's own bdpt by 33% and 8%). Left
    // out for time (10–80 s each in a release build): `v3-plastic` (0.47% when
    // measured), `v3-rough-glass` and `v3-materials` (1.21–1.59% and 1.33–1.60%, seeds 0
    // and 1; 2.84% and 2.22% while our rough transmission's density left out the
    // facets pbrt-v3's counts: `frosted_glass_transmits_as_in_pbrt_v3s_bdpt`).
    // A quarter (or half) of the passes where that was measured to leave at most 0.6
    // of the bound (vcm's error falls faster than SPPM's, for whose noise the budgets
    // were set); at half: v3-textures 0.68%, v4-bump 2.34%, v3-mix 1.57%. pbrt-v4's
    // scenes at `v4_bound`, spectrally: v4-textures 1.05%, v4-bump 2.49%, v4-mix 2.43%,
    // v4-coated 1.84%, v4-normalmap 1.77%, v4-ply-quads 0.86%, v4-difftrans 1.15%;
    // v4-alpha at its whole budget 0.77%, 1.50%, 0.66% (the default seed, seeds 1 and
    // 2; at half 1.29–1.89%), pbrt-v4's own bdpt at 64 samples 0.36–0.55% (seeds 1–3).
    let settings = RenderSettings { algorithm: Some(Algorithm::Vcm(Techniques::All)), ..Default::default() };
    for (name, reference, bound, share) in [
        ("v3-caustic", "v3-caustic", 0.02, 4),
        ("v3-textures", "v3-textures", 0.02, 2),
        ("v4-textures", "v4-textures", v4_bound(0.0149), 4),
        ("v3-alpha", "v3-alpha", 0.02, 4),
        ("v3-bump", "v3-bump", 0.02, 1),
        ("v4-bump", "v4-bump", v4_bound(0.0183), 2),
        ("v4-mix", "v4-mix", v4_bound(0.0217), 4),
        ("v4-coated", "v4-coated", v4_bound(0.0080), 4),
        ("v3-mirror-box", "v3-mirror-box", 0.02, 1),
        ("v4-normalmap", "v4-normalmap", v4_bound(0.0158), 4),
        ("v3-metal-spd", "v3-metal-spd", 0.02, 4),
        ("v4-ply-quads", "v4-ply-quads", v4_bound(0.0145), 4),
        ("v3-marble", "v3-marble", 0.02, 4),
        ("v3-translucent", "v3-translucent", 0.02, 4),
        ("v4-difftrans", "v4-difftrans", v4_bound(0.0125), 4),
        ("v3-sphere-light", "v3-sphere-light-unscaled", 0.02, 4),
        ("v3-mix", "v3-mix-bdpt", 0.03, 2),
        ("v4-alpha", "v4-alpha-bdpt", v4_bound(0.0055), 1),
    ] {
        Check { reference, settings: settings.clone(), ..Check::sppm(name, bound, share) }.assert();
    }
}

#[test]
fn fog_lit_by_a_spot_beam_and_an_area_light_matches_pbrt_v4_bdpt() {
    // pbrt's SPPM ignores media: the reference is pbrt-v4's bdpt (its volpath agrees
    // within 1.4% in every tile). Ours at 64 × 100,000 photons, radius 0.1, gathering
    // along beams (the default): worst tile 4.0–4.2% over three seeds (with points
    // 5.8–7.1%, in the dim top row: SPPM's photon noise is correlated across pixels;
    // 2.8% at 512 × 200,000, where the top tiles stay 2.5–3% low: kernel balls there
    // cross the fog's boundary, which no photon lies beyond).
    // Spectrally (paths carry the pass's three wavelengths, so each pass's photon noise
    // comes with its own colour): 4.9% at the full budget (RGB 4.0%), 6.1–6.6% over
    // three seeds at half of it (6.9–10.4% at a quarter, where RGB measured 4.91%).
    Check { reference: "v4-fog-box-bdpt", ..Check::sppm("v4-fog-box", 0.10, 2) }.assert();
}

#[test]
fn smoke_in_a_density_grid_matches_pbrt_v3_volpath() {
    // pbrt-v3's SPPM ignores media: the reference is its volpath (4096 samples; its
    // 1024-sample image is within 2.2% of it). Ours at 64 × 100,000 photons: worst tile
    // 2.4–3.0% over three seeds along beams (with points 3.1–5.7%; 3.1% at 256 ×
    // 200,000).
    // Half the scene's iterations: 3.65% when measured.
    Check { reference: "v3-smoke-grid-volpath", ..Check::sppm("v3-smoke-grid", 0.10, 2) }.assert();
}

#[test]
fn a_glass_sphere_focuses_a_spot_light_into_haze_as_pbrt_v4_bdpt() {
    // A volumetric caustic: pbrt-v4's SPPM ignores media and its volpath cannot follow
    // the specular chain from the spot light, so the reference is its bdpt (4096
    // samples). Ours at 48 × 100,000 photons, along beams: worst tile 3.7–11.2% over
    // three seeds, in the focused cone (with points, a ball of few photons: 14.9–21.5%;
    // 5.7% at 256 × 400,000). Spectrally 13.5–16.8% over three seeds: the cone is a
    // few bright pixels, and each pass's photons carry that pass's colour. The bound is
    // for a missing or misplaced cone, not for a few percent.
    assert_matches_reference("v4-volume-caustic", Fixes::NONE, "v4-volume-caustic-bdpt", 0.20);
}

#[test]
fn milk_in_a_glass_sphere_matches_pbrt_v3_bdpt() {
    // A preset medium inside a dielectric: light reaches it only through the glass, so
    // the reference is pbrt-v3's bdpt (16,384 samples). Ours at 64 × 100,000 photons:
    // worst tile 3.3–3.8% over three seeds along beams (points 3.0–3.7%; 3.0% at 256 ×
    // 200,000, in the milk's lower half, where kernels cross the glass, beyond which no
    // photon lies).
    assert_matches_reference("v3-milk-glass", Fixes::NONE, "v3-milk-glass-bdpt", 0.06);
}

#[test]
fn glowing_media_light_the_room_as_pbrt_v4_volpath() {
    // Emission from a homogeneous medium ("Le") and a temperature grid (blackbody),
    // seen directly and lighting the floor and wall through photons that start in the
    // media. pbrt-v4's volpath at 8,192 samples. Ours at 32 × 100,000 photons: worst
    // tile 1.3–2.4% over three seeds along beams (points 1.4–1.8%; 1.9% at 128 ×
    // 200,000).
    // Half the scene's iterations: 1.42% when measured in RGB, 2.82% spectrally.
    Check { reference: "v4-glow-volpath", ..Check::sppm("v4-glow", 0.05, 2) }.assert();
}

#[test]
fn an_rgb_grid_and_a_cloud_match_pbrt_v4_volpath() {
    // pbrt-v4's `rgbgrid` (colored, with unnormalised emission) and procedural `cloud`,
    // under an area light and a spot light; pbrt-v4's volpath at 4,096 samples. Ours
    // at 32 × 100,000 photons: worst tile 2.9–3.6% over three seeds along beams
    // (points 3.4–3.9%; 2.7% at 128 × 200,000).
    // A quarter of the scene's iterations: 3.60% when measured in RGB, 4.68% spectrally
    // (each sample's σ a spectrum, interpolated at the pass's wavelengths).
    Check { reference: "v4-rgbgrid-cloud-volpath", ..Check::sppm("v4-rgbgrid-cloud", 0.08, 4) }.assert();
}

#[test]
fn smoke_in_a_v4_uniform_grid_matches_pbrt_v4_volpath() {
    // The smoke scene as pbrt-v4 writes it (a `uniformgrid`), against pbrt-v4's volpath
    // at 2048 samples (its 1024-sample image is within 1.7% of it). Ours at 64 × 100,000
    // photons: worst tile 2.2–3.3% over three seeds along beams (points 3.4–8.0%; 4.1%
    // at 256 × 200,000).
    // Half the scene's iterations: 5.56% when measured in RGB, 6.78% spectrally
    // (5.1–6.2% over three seeds at the full budget, RGB 2.2%).
    Check { reference: "v4-smoke-grid-volpath", ..Check::sppm("v4-smoke-grid", 0.10, 2) }.assert();
}

#[test]
fn sppm_gathering_at_points_renders_media_as_pbrt() {
    // `--volume-gather points`: a camera path scatters at one point in a medium and
    // gathers photons in a ball there. Worst tiles in the comments above.
    let points = RenderSettings { volume_gather: Some(VolumeGather::Points), ..Default::default() };
    assert_renders_with("v4-fog-box", Fixes::NONE, &points, "v4-fog-box-bdpt", 0.10);
    assert_renders_with("v3-smoke-grid", Fixes::NONE, &points, "v3-smoke-grid-volpath", 0.10);
}

#[test]
fn bdpt_and_vcm_render_media_as_pbrt() {
    // The same media scenes rendered by our bdpt and vcm, whose subpaths scatter in the
    // media and connect through them. At the scenes' budgets, worst tile over three
    // seeds: fog box with bdpt 0.8–1.9% in RGB, 2.5–4.5% spectrally (seeds 1–3, with
    // or without the pixel filter: the passes' shared wavelengths, `docs/spectral.md`;
    // 3.08% at the test's seed), the v3 smoke grid with vcm 0.9–1.6% (SPPM's are
    // 4.0–4.2% and 2.4–3.0% along beams, above). pbrt-v4's own bdpt image of the fog
    // box at 64 samples: 2.26%, 3.79%, 3.15% (seeds 1–3), so `v4_bound` would be 4.7%.
    assert_renders_as("v4-fog-box", Fixes::NONE, Algorithm::Vcm(Techniques::Bdpt), "v4-fog-box-bdpt", 0.04);
    assert_renders_as("v3-smoke-grid", Fixes::NONE, Algorithm::Vcm(Techniques::All), "v3-smoke-grid-volpath", 0.04);
}

#[test]
fn motion_blur_moves_shapes_instances_and_the_camera_as_pbrt_v3() {
    // A sphere sliding, an instance turning a third of a circle and the camera panning
    // while the shutter is open. pbrt-v3's own 64-iteration image: worst tile 2.0%;
    // ours 1.6–2.9% over seeds 0–3. With the start transforms only (the old
    // behaviour): 81% off.
    assert_matches_pbrt("v3-motion", 0.035);
}

#[test]
fn motion_blur_moves_shapes_instances_and_the_camera_as_pbrt_v4() {
    // pbrt-v4 interpolates in its rendering space (the turning box swings about the
    // camera) and renders each SPPM pass at one time. pbrt-v4's own 64-sample image:
    // worst tile 3.3%. Each pass also has one set of wavelengths, and at 64 passes the
    // moving green sphere's colour is 4.0–5.5% off over seeds 0–3 (2.2–3.7% in RGB);
    // at 128 passes 1.6%, at 256 1.0% (seed 0). Times drawn per ray, as for v3 files:
    // 17% at the box; start transforms only: 79%.
    let settings = RenderSettings { algorithm: Some(Algorithm::Sppm), iterations: Some(128), ..Default::default() };
    Check { settings, ..Check::sppm("v4-motion", 0.045, 1) }.fine(v4_fine(0.0684)).assert();
}

#[test]
fn the_realistic_camera_traces_its_lens_as_pbrt_v3() {
    // A stop and a biconvex lens focused at 2 m: the near sphere and the far wall blur.
    // pbrt-v3's own 64-iteration image: worst tile 0.98%; ours 2.0–2.8% over seeds
    // 0–3, whose mean is within 1.1% in every tile. As a pinhole (the old fallback):
    // another picture altogether.
    assert_matches_pbrt("v3-realistic", 0.035);
}

#[test]
fn the_realistic_camera_weighs_its_rays_as_pbrt_v4() {
    // pbrt-v4's upgrade of v3-realistic behind its built-in pentagonal stop: weights
    // cos⁴θ·A/z² times the aperture image (its film takes the exposure). The scene is
    // noisy in pbrt-v4 (bright glass paths): its own 64-sample image is 16% off its
    // 1024-sample one; ours 4.3–7.2% over seeds 0–3, whose mean is within 2.6% in
    // every tile and 0.7% over the image. pbrt-v3's weighting here would be some 30
    // times too bright. Hence 10%.
    assert_matches_pbrt("v4-realistic", 0.10);
}
