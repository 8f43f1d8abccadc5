//! Path guiding (`--guiding on|light|both`): guided vcm and bdpt converge to pbrt's
//! images within the bounds unguided vcm is held to, and a guided render is the same
//! image for any thread count and any split of its passes into shards (the split's
//! later shards replay the training passes). Resuming is checked with the other
//! checkpoint cases (`checkpoint.rs`).

use crate::common::scene;
use crate::pbrt_refs::{Check, v4_bound};
use pbrt_sppm::guiding::Guiding;
use pbrt_sppm::integrators::vcm::Techniques;
use pbrt_sppm::integrators::{Algorithm, RenderSettings};
use pbrt_sppm::render::RenderScene;

fn guided(techniques: Techniques, guiding: Guiding) -> RenderSettings {
    RenderSettings { algorithm: Some(Algorithm::Vcm(techniques)), guiding, ..Default::default() }
}

#[test]
fn guided_renders_converge_to_pbrts_images() {
    // Scenes lit by area lights, with diffuse, glossy and transmitting surfaces (the
    // last unfolded), at the bounds and budgets of the unguided vcm test (bdpt at the
    // whole budget: unguided, a quarter leaves 3.31% on `v4-mix`); camera subpaths,
    // light subpaths or both guided.
    for (name, reference, bound, share, techniques, guiding) in [
        ("v3-sphere-light", "v3-sphere-light-unscaled", 0.02, 4, Techniques::All, Guiding::Camera),
        ("v3-metal-spd", "v3-metal-spd", 0.02, 4, Techniques::All, Guiding::Both),
        ("v4-difftrans", "v4-difftrans", v4_bound(0.0125), 4, Techniques::All, Guiding::Light),
        ("v4-mix", "v4-mix", v4_bound(0.0217), 1, Techniques::Bdpt, Guiding::Both),
    ] {
        Check { reference, settings: guided(techniques, guiding), ..Check::sppm(name, bound, share) }.assert();
    }
}

#[test]
fn a_guided_render_is_the_same_for_any_thread_count() {
    let text = std::fs::read_to_string(crate::common::root().join("pbrt-scenes/v3/cornell-glass.pbrt")).unwrap();
    let sc = RenderScene::new(&scene(&text));
    // Pass 0 trains the first round, passes 1 and 2 the second while the first guides
    // them, pass 3 is guided by both.
    let s = RenderSettings { iterations: Some(4), photons: Some(3000), ..guided(Techniques::All, Guiding::Both) };
    let pixels = |threads| crate::vcm::pixels_on_threads(&sc, &s, threads);
    let (one, two) = (pixels(1), pixels(2));
    assert!(one.iter().any(|p| p[0] > 0.0), "the image is black");
    let same = one.iter().zip(&two).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits));
    assert!(same, "guided images differ between 1 and 2 threads");
    // Each guide alone changes the image: both are drawn from.
    let render = |guiding| pbrt_sppm::integrators::render(&sc, &RenderSettings { guiding, ..s.clone() });
    let plain = render(Guiding::Off).unwrap().image.pixels;
    for alone in [Guiding::Camera, Guiding::Light] {
        let px = render(alone).unwrap().image.pixels;
        assert!(px != plain && px != one, "{alone:?} guiding changed nothing: is its guide drawn from?");
    }
}

#[test]
fn any_split_of_a_guided_render_merges_to_the_single_machine_render() {
    // The second shard starts mid-round: it replays passes 0..3 to train its guide.
    crate::vcm::assert_split_merges("guided", &["--integrator", "vcm", "--guiding", "both"], ["0..3", "3..6"]);
}

#[test]
fn a_guided_white_furnace_gives_the_geometric_series() {
    // Every weight counts the guided mixtures' densities, on both subpaths: leaving
    // the camera's out where light subpaths take its reverse density leaves weights
    // that do not sum to one: the mean 0.62% and 0.70% low (vcm, bdpt), where the
    // right weights leave it 0.10% high at 64 passes.
    let text = crate::vcm::furnace("AreaLightSource \"diffuse\" \"rgb L\" [.5 .5 .5]");
    for techniques in [Techniques::All, Techniques::Bdpt] {
        assert_furnace(&text, 10, (techniques, Guiding::Camera), 0.003);
    }
    // The light subpaths' guide: a narrow view (5°) makes the importance camera
    // subpaths bring peaked, far from the BSDF (on the wide view the mixture is close
    // to it and its densities barely matter). 40 × 40 pixels, 64 passes, seeds 1–3:
    // right, 0.07–0.12% high; the light mixture left out of the camera's reverse
    // densities, 0.28% low (vcm, light) and 0.42–0.45% (bdpt, both); out of the
    // light vertices' forward densities in connections, 0.42–0.47% low (bdpt, both).
    let narrow = text.replace("\"float fov\" 45", "\"float fov\" 5").replace("resolution\" 10", "resolution\" 40");
    assert!(narrow.contains("\"float fov\" 5") && narrow.contains("yresolution\" 40"));
    for case in [(Techniques::All, Guiding::Light), (Techniques::Bdpt, Guiding::Both)] {
        assert_furnace(&narrow, 40, case, 0.0025);
    }
}

/// Renders a white furnace guided (64 passes) and checks its mean against the
/// geometric series of its six edges within `bound` (relative).
fn assert_furnace(text: &str, width: usize, (techniques, guiding): (Techniques, Guiding), bound: f64) {
    let sc = RenderScene::new(&scene(text));
    let settings = RenderSettings { iterations: Some(64), ..guided(techniques, guiding) };
    let px = pbrt_sppm::integrators::render(&sc, &settings).unwrap().image.pixels;
    let mean = crate::vcm::means(&px, width)[0] / 3.0;
    let expected = 1.0 - 0.5f64.powi(6);
    let (techniques, guiding) = (format!("{techniques:?}"), format!("{guiding:?}"));
    assert!((mean - expected).abs() < bound * expected, "{techniques}, {guiding}: {mean}, expected {expected}");
}

#[test]
fn guiding_an_sppm_render_is_a_clear_error() {
    let d = crate::shards::dir("guided-sppm");
    let err = crate::shards::error(&d, &["render", "scene.pbrt", "--guiding", "on", "--outfile", "x.exr"]);
    assert!(err.contains("path guiding is for vcm and bdpt") && err.contains("--guiding off"), "{err}");
    assert!(!d.join("x.exr").exists());
    let _ = std::fs::remove_dir_all(&d);
}
