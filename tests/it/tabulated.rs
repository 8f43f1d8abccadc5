//! Tabulated BSDF files: pbrt-v3's `fourier` material with the file of
//! `tools/make_fourier_bsdf.py`, rendered against pbrt-v3 by SPPM and by vcm, and files
//! that cannot be read.

use crate::common::scene;
use crate::pbrt_refs::Check;
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
