//! Tabulated BSDF files: pbrt-v3's `fourier` material with the file of
//! `tools/make_fourier_bsdf.py`, rendered against pbrt-v3 by SPPM and by vcm; pbrt-v4's
//! `measured` material with the files of `tools/make_measured_bsdf.py`, against
//! pbrt-v4 by SPPM, vcm and in RGB; and files that cannot be read.

use crate::common::scene;
use crate::pbrt_refs::{Check, v4_bound};
use pbrt_sppm::integrators::vcm::Techniques;
use pbrt_sppm::integrators::{Algorithm, RenderSettings};
use pbrt_sppm::materials::MaterialKind;

#[test]
fn a_fourier_bsdf_renders_as_in_pbrt_v3() {
    // pbrt-v3's own 64-iteration image: worst tile 1.08%. Ours at 64: 0.66% (seeds 1,
    // 2: 2.60%, 1.17%: the sphere's rim lit by the area light); at 128: 0.69% (1.09%,
    // 0.49%).
    Check::sppm_iterations("v3-fourier", 0.02, 128).assert();
}

#[test]
fn vcm_renders_a_fourier_bsdf_both_ways() {
    // Light subpaths scatter off it with the adjoint's scale (eta² across). At 128
    // passes: 1.61% (seeds 1, 2: 1.67%, 2.53%), in the blue of tile (1, 2), where
    // pbrt-v3's own bdpt (4096 samples) and SPPM differ by 2.4%: held to 3%.
    let algorithm = Some(Algorithm::Vcm(Techniques::All));
    let settings = RenderSettings { algorithm, iterations: Some(128), ..Default::default() };
    Check { settings, ..Check::sppm("v3-fourier", 0.03, 1) }.assert();
}

#[test]
fn an_unreadable_bsdf_file_is_black_and_noted() {
    let dir = "../../../pbrt-scenes/verify/bsdfs";
    for (file, why) in [("missing.bsdf", "missing.bsdf"), ("../pbrt-ref/README.md", "SCATFUN")] {
        let text =
            format!("WorldBegin\nMaterial \"fourier\" \"string bsdffile\" \"{file}\"\nShape \"sphere\"\nWorldEnd\n");
        let s = scene(&text);
        let noted: Vec<_> = s.approximated.iter().filter(|a| a.what.contains(why)).collect();
        assert_eq!(noted.len(), 1, "{:?}", s.approximated);
        assert!(noted[0].how.contains("black") && noted[0].line == 2, "{:?}", noted[0]);
        assert!(matches!(s.materials[0].kind, MaterialKind::Diffuse { .. }));
    }
    let e =
        crate::common::load("WorldBegin\nMaterial \"fourier\"\nShape \"sphere\"\nWorldEnd\n").unwrap_err().to_string();
    assert!(e.contains("inline.pbrt:2:") && e.contains("needs \"string bsdffile\""), "{e}");
    let s = scene(&format!(
        "WorldBegin\nMaterial \"fourier\" \"string bsdffile\" \"{dir}/glazed.bsdf\"\nShape \"sphere\"\nWorldEnd\n"
    ));
    assert!(s.approximated.is_empty() && matches!(s.materials[0].kind, MaterialKind::Fourier { .. }));
}

/// pbrt-v4's own 64-sample image of `v4-measured`, seeds 1 and 2: worst tile 1.65%,
/// 1.77% (`tests/data/pbrt-ref/README.md`).
const MEASURED_OWN: f64 = 0.0177;

#[test]
fn a_measured_bsdf_renders_as_in_pbrt_v4() {
    // Ours at 64 iterations, seeds 0-2: 1.59%, 1.33%, 0.99% (at 32: 2.46%, 2.57%).
    Check::sppm("v4-measured", v4_bound(MEASURED_OWN), 1).assert();
}

#[test]
fn vcm_renders_a_measured_bsdf() {
    // At 128 passes, seeds 0-2: 0.52%, 1.89%, 1.27% (at 64, seed 1 met a firefly off
    // the anisotropic tile: 3.92%; at 256 it was 0.86%).
    let algorithm = Some(Algorithm::Vcm(Techniques::All));
    let settings = RenderSettings { algorithm, iterations: Some(128), ..Default::default() };
    Check { settings, ..Check::sppm("v4-measured", v4_bound(MEASURED_OWN), 1) }.assert();
}

#[test]
fn rgb_paths_see_a_measured_bsdf_as_spectral_ones_do() {
    // The spectra as reflectances under D65: 1.12% at 64 iterations (as pbrt-v3 reduces
    // a spectrum, without the illuminant, the spheres were 15% too red).
    let colour = Some(pbrt_sppm::spectrum::transport::Colour::Rgb);
    Check { colour, ..Check::sppm("v4-measured", v4_bound(MEASURED_OWN), 1) }.assert();
}

#[test]
fn measured_bsdf_files_that_cannot_be_read_are_located_errors() {
    let dir = "../../../pbrt-scenes/verify/bsdfs";
    for (file, why) in [
        ("missing.bsdf".to_string(), "missing.bsdf"),
        ("../pbrt-ref/README.md".to_string(), "not a tensor file"),
        (format!("{dir}/glazed.bsdf"), "not a tensor file"),
    ] {
        let text = format!("WorldBegin\nMaterial \"measured\"\n  \"string filename\" \"{file}\"\nShape \"sphere\"\n");
        let e = crate::common::load(&text).unwrap_err().to_string();
        assert!(e.contains("inline.pbrt:3:3: error: measured BSDF") && e.contains(why), "{e}");
    }
    let e = crate::common::load("WorldBegin\nMaterial \"measured\"\nShape \"sphere\"\n").unwrap_err().to_string();
    assert!(e.contains("inline.pbrt:2:") && e.contains("needs \"string filename\""), "{e}");
    let s = scene(&format!(
        "WorldBegin\nMaterial \"measured\" \"string filename\" \"{dir}/anodized.bsdf\"\nShape \"sphere\"\n"
    ));
    assert!(s.approximated.is_empty() && matches!(s.materials[0].kind, MaterialKind::Measured { .. }));
}
