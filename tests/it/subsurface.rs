//! Subsurface scattering: `subsurface` (both versions), `kdsubsurface` and `disney`
//! with a `scatterdistance` (pbrt-v3) read as each pbrt reads them, their BSSRDF probed
//! as pbrt probes it, rendered against pbrt's path tracers; the integrators pbrt runs
//! without the BSSRDF see the glass boundary.

use crate::common::{load, root, scene, warnings};
use crate::pbrt_refs::{Check, v4_bound};
use glam::Vec3;
use pbrt_sppm::imageio::metrics;
use pbrt_sppm::integrators::subsurface::{Entry, exit};
use pbrt_sppm::integrators::vcm::Techniques;
use pbrt_sppm::integrators::{Algorithm, RenderSettings};
use pbrt_sppm::materials::MaterialKind;
use pbrt_sppm::math::{Point3, Ray, Vector3};
use pbrt_sppm::render::RenderScene;
use pbrt_sppm::sampling::Rng;
use pbrt_sppm::scene::{LoadOptions, load_scene_from_bytes};

fn vcm(iterations: u32, seed: u64) -> RenderSettings {
    let algorithm = Some(Algorithm::Vcm(Techniques::All));
    RenderSettings { algorithm, iterations: Some(iterations), seed: Some(seed), ..Default::default() }
}

#[test]
fn subsurface_renders_as_in_pbrt_v3s_path_tracer() {
    // pbrt-v3's path tracer at 64 samples (random sampler, independent of the
    // reference): worst tile 1.52%. Ours at 128 passes: 1.32%, 1.93%, 1.71% (seeds
    // 0, 1, 2), held to 2.5%: the rough block's rare bright probes.
    let settings = vcm(128, 0);
    Check { settings, ..Check::sppm("v3-subsurface", 0.025, 1) }.assert();
}

#[test]
fn disney_bssrdf_renders_as_in_pbrt_v3s_path_tracer() {
    // pbrt-v3's path tracer at 64 samples: worst tile 2.54% (random sampler, independent
    // of the 8,192-sample reference), 1.88% (its halton). Ours at 128 passes: 2.44%,
    // 1.85%, 0.90%, 1.97% (seeds 0–3); at 1,024 0.52%. With the boundary alone (no
    // BSSRDF, as before it was rendered) 67%.
    let settings = vcm(128, 0);
    Check { settings, ..Check::sppm("v3-disney-sss", 0.03, 1) }.assert();
}

#[test]
fn light_behind_a_disney_bssrdf_shows_through_as_in_pbrt_v3() {
    // pbrt-v3's path tracer at 64 samples: worst tile 18% (random sampler, independent
    // of the 8,192-sample reference), 3.4% (its halton). Ours at 128 passes: 2.7%, 3.1%,
    // 6.1%, 4.2% (seeds 0–3). Without the light seen through the rough transmission
    // lobe where a BSSRDF lies below (no technique counted it): 94%.
    let settings = vcm(128, 0);
    Check { settings, ..Check::sppm("v3-disney-backlit", 0.08, 1) }.assert();
}

#[test]
fn subsurface_renders_as_in_pbrt_v4s_volpath() {
    // pbrt-v4's volpath at 64 samples: 1.48%, 1.54% (seeds 1, 2). Ours at 128 passes:
    // 1.78%, 0.83%, 1.49% (seeds 0, 1, 2).
    let settings = vcm(128, 0);
    Check { settings, ..Check::sppm("v4-subsurface", v4_bound(0.0154), 1) }.assert();
}

/// pbrt-v3 gives a `disney` material a BSSRDF at a hit where it is not thin, has a
/// diffuse weight and its `scatterdistance` there is not black.
#[test]
fn disney_has_a_bssrdf_where_pbrt_v3_makes_one() {
    let plane =
        "Shape \"trianglemesh\" \"point P\" [-9 .5 -9 9 .5 -9 9 .5 9 -9 .5 9] \"integer indices\" [0 1 2 0 2 3]";
    let sd = "\"rgb scatterdistance\" [.2 .2 .2]";
    // A 3D checkerboard of cells 1 wide: black at x in (1, 2) on the plane y = z = 0.5.
    let checker = "Texture \"c\" \"spectrum\" \"checkerboard\" \"integer dimension\" 3 \"rgb tex1\" [.2 .2 .2] \"rgb tex2\" [0 0 0]";
    for (integrator, material, at_x, has) in [
        ("path", sd.to_string(), 0.5, true),
        ("sppm", sd.to_string(), 0.5, false),
        ("path", format!("{sd} \"bool thin\" \"true\""), 0.5, false),
        ("path", String::new(), 0.5, false),
        ("path", format!("{sd} \"float spectrans\" 1"), 0.5, false),
        ("path", format!("{sd} \"float metallic\" 1"), 0.5, false),
        ("path", format!("{sd} \"float metallic\" .5"), 0.5, true),
        ("path", "\"texture scatterdistance\" \"c\"".to_string(), 0.5, true),
        ("path", "\"texture scatterdistance\" \"c\"".to_string(), 1.5, false),
    ] {
        let s = scene(&format!(
            "Film \"image\" Integrator \"{integrator}\" WorldBegin {checker} Material \"disney\" {material} {plane}"
        ));
        let rs = RenderScene::for_integrator(&s, true);
        let ray = Ray::new(Point3(Vec3::new(at_x, 1.0, 0.5)), Vector3(Vec3::new(0.0, -1.0, 0.0)));
        let hit = rs.intersect(&ray).expect("the plane");
        let si = rs.geometry.interaction(&hit);
        assert_eq!(rs.bssrdf(&hit, &si).is_some(), has, "{integrator}: {material} at x = {at_x}");
    }
}

/// pbrt-v3 `path`/`volpath` and pbrt-v4 `volpath` take light through the BSSRDF; the
/// rest of pbrt's integrators see glass, and so do ours for their files.
#[test]
fn only_the_files_whose_pbrt_integrator_takes_the_bssrdf_follow_it() {
    let text = std::fs::read_to_string(root().join("pbrt-scenes/verify/v3-subsurface.pbrt")).unwrap();
    for (v4, integrator, follows) in [
        (false, "path", true),
        (false, "volpath", true),
        (false, "bdpt", false),
        (false, "sppm", false),
        (true, "volpath", true),
        (true, "path", false),
        (true, "bdpt", false),
    ] {
        let film = if v4 { "Film \"rgb\"" } else { "Film \"image\"" };
        let s = scene(&format!(
            "{film}\nIntegrator \"{integrator}\"\nWorldBegin\nMaterial \"subsurface\"\nShape \"sphere\""
        ));
        assert_eq!(RenderScene::for_integrator(&s, true).subsurface, follows, "{integrator} (v4: {v4})");
        assert!(!RenderScene::for_integrator(&s, false).subsurface, "SPPM never follows it");
    }
    // The same scene for pbrt's bdpt renders as one with glass in place of the BSSRDF
    // materials; for its path tracer, far from it (the objects are opaque there).
    let dir = root().join("pbrt-scenes/verify");
    let bdpt = text.replace("Integrator \"path\"", "Integrator \"bdpt\"");
    let glass = bdpt
        .replace(
            "Material \"subsurface\" \"string name\" \"Skin1\" \"float scale\" 10",
            "Material \"glass\" \"float index\" 1.33",
        )
        .replace(
            "Material \"kdsubsurface\" \"color Kd\" [.75 .5 .3] \"color mfp\" [.25 .15 .08]",
            "Material \"glass\" \"float index\" 1.33",
        );
    let render = |text: &str| {
        let path = dir.join("inline.pbrt");
        let s = load_scene_from_bytes(&path, text.as_bytes().to_vec(), &LoadOptions::default()).expect("loads");
        pbrt_sppm::integrators::render(&RenderScene::for_integrator(&s, true), &vcm(16, 3)).expect("renders").image
    };
    let (a, b, c) = (render(&bdpt), render(&glass), render(&text));
    let worst = |x: &pbrt_sppm::imageio::RgbImage| {
        metrics::worst_mean_deviation(&x.pixels, &b.pixels, x.width, x.height, 4, 0.05).0
    };
    assert!(worst(&a) < 0.05, "bdpt's file is not glass: {}", worst(&a));
    assert!(worst(&c) > 0.2, "path's file is glass: {}", worst(&c));
}

/// On a plane, light leaving anywhere is found by probes along the normal: Sp over
/// the probe's density averages to the profile's integral, the effective albedo, which
/// `kdsubsurface` sets to Kd.
#[test]
fn probes_on_a_plane_recover_the_effective_albedo() {
    for (v4, text) in [
        (false, "Film \"image\" WorldBegin Material \"kdsubsurface\" \"rgb Kd\" [.2 .5 .8] \"rgb mfp\" [.1 .05 .2]"),
        (
            true,
            "Film \"rgb\" Integrator \"volpath\" WorldBegin Material \"subsurface\" \"rgb reflectance\" [.2 .5 .8] \"rgb mfp\" [.1 .05 .2]",
        ),
        // Burley's profile integrates to the colour over the plane.
        (
            false,
            "Film \"image\" Integrator \"path\" WorldBegin Material \"disney\" \"rgb color\" [.2 .5 .8] \"rgb scatterdistance\" [.5 .25 1]",
        ),
    ] {
        let s = scene(&format!(
            "{text} Shape \"trianglemesh\" \"point3 P\" [-1e3 0 -1e3 1e3 0 -1e3 1e3 0 1e3 -1e3 0 1e3] \"integer indices\" [0 1 2 0 2 3]"
        ));
        let rs = RenderScene::for_integrator(&s, true);
        rs.begin_pass(0);
        let ray = Ray::new(Point3(Vec3::new(0.3, 1.0, 0.2)), Vector3(Vec3::new(0.0, -1.0, 0.0)));
        let hit = rs.intersect(&ray).expect("the plane");
        let si = rs.geometry.interaction(&hit);
        let (profile, eta, material) = rs.bssrdf(&hit, &si).expect("a BSSRDF");
        let n = si.shading.n.0;
        let ss = si.shading.dpdu.0.normalize();
        let entry = Entry { profile, eta, material, po: si.p.0, frame: [ss, n.cross(ss), n], time: 0.0 };
        let (mut sum, mut rng, count) = (glam::DVec3::ZERO, Rng::new(5), 200_000);
        for _ in 0..count {
            if let Some(e) = exit(&rs, &entry, &mut rng) {
                sum += e.weight.as_dvec3();
            }
        }
        let mean = sum / count as f64;
        // pbrt-v4's albedo is a spectrum: the lanes hold it at the pass's wavelengths.
        let rgb = Vec3::new(0.2, 0.5, 0.8);
        let want = rs.pass_spectrum().map_or(rgb, |p| p.albedo(rgb));
        let got = mean.as_vec3();
        assert!((got - want).abs().max_element() < 0.02, "v4 {v4}: {got} against {want}");
    }
}

#[test]
fn parameters_are_read_as_each_pbrt_reads_them() {
    let kind = |text: &str| scene(text).materials.into_iter().find(|m| m.ty.contains("subsurface")).unwrap().kind;
    // Rendered, not approximated.
    for text in [
        "Film \"image\" WorldBegin Material \"kdsubsurface\" Shape \"sphere\"",
        "WorldBegin Material \"subsurface\" Shape \"sphere\"",
    ] {
        let s = scene(text);
        assert!(s.approximated.is_empty(), "{:?}", s.approximated);
        assert!(matches!(s.materials[0].kind, MaterialKind::Subsurface(_)));
    }
    // A measured medium by name; an unknown one is pbrt-v3's warning and pbrt-v4's error.
    let MaterialKind::Subsurface(m) =
        kind("WorldBegin Material \"subsurface\" \"string name\" \"Ketchup\" Shape \"sphere\"")
    else {
        panic!()
    };
    assert!(format!("{:?}", m.coefficients).contains("0.061"), "{:?}", m.coefficients);
    // pbrt-v3 lets `sigma_a`/`sigma_s` override a name's; pbrt-v4 takes the name's.
    let sigma_a = |text: &str| match kind(text) {
        MaterialKind::Subsurface(m) => match m.coefficients {
            pbrt_sppm::materials::subsurface::Coefficients::Sigma { sigma_a, .. } => format!("{sigma_a:?}"),
            c => panic!("{c:?}"),
        },
        _ => panic!(),
    };
    let both = "Material \"subsurface\" \"string name\" \"Ketchup\" \"rgb sigma_a\" [7 7 7] \"rgb sigma_s\" [1 1 1]";
    assert!(sigma_a(&format!("Film \"image\" WorldBegin {both} Shape \"sphere\"")).contains("7.0"));
    assert!(sigma_a(&format!("WorldBegin {both} Shape \"sphere\"")).contains("0.061"));
    let s = load("Film \"image\" WorldBegin\nMaterial \"subsurface\" \"string name\" \"Ketchop\" Shape \"sphere\"")
        .unwrap();
    assert!(warnings(&s).join("\n").contains("named medium \"Ketchop\" not found; the default"), "{:?}", warnings(&s));
    let e = load("WorldBegin\nMaterial \"subsurface\" \"string name\" \"Ketchop\" Shape \"sphere\"")
        .unwrap_err()
        .to_string();
    assert!(e.contains("inline.pbrt:2:23: error: named medium \"Ketchop\" not found"), "{e}");
    let e =
        load("WorldBegin\nMaterial \"subsurface\" \"rgb sigma_a\" [1 1 1] Shape \"sphere\"").unwrap_err().to_string();
    assert!(e.contains(":2:") && e.contains("\"sigma_a\" is given without \"sigma_s\""), "{e}");
    let e = load("WorldBegin\nMaterial \"subsurface\" \"float eta\" 0 Shape \"sphere\"").unwrap_err().to_string();
    assert!(e.contains(":2:") && e.contains("\"eta\" must be positive"), "{e}");
    // pbrt-v4 reads `reflectance`; pbrt-v3's subsurface has no such parameter.
    let MaterialKind::Subsurface(m) =
        kind("WorldBegin Material \"subsurface\" \"rgb reflectance\" [.5 .5 .5] Shape \"sphere\"")
    else {
        panic!()
    };
    assert!(format!("{:?}", m.coefficients).starts_with("Diffuse"));
    let s = load("Film \"image\" WorldBegin Material \"subsurface\" \"rgb reflectance\" [.5 .5 .5] Shape \"sphere\"")
        .unwrap();
    assert!(warnings(&s).join("\n").contains("reflectance"), "{:?}", warnings(&s));
    // Tables are shared by (g, η).
    let s = scene(
        "WorldBegin Material \"subsurface\" Shape \"sphere\" Material \"subsurface\" \"float scale\" 2 Shape \"sphere\"",
    );
    let tables: Vec<_> = s
        .materials
        .iter()
        .map(|m| match &m.kind {
            MaterialKind::Subsurface(x) => x.table().clone(),
            _ => panic!(),
        })
        .collect();
    assert!(std::sync::Arc::ptr_eq(&tables[0], &tables[1]));
}

/// `--fix subsurface-walk` is a glass boundary over a homogeneous medium of the
/// material's coefficients: the image of the same scene written that way by hand.
#[test]
fn the_walk_is_glass_over_the_materials_medium() {
    let text = std::fs::read_to_string(root().join("pbrt-scenes/verify/v3-subsurface.pbrt")).unwrap();
    let sphere_only = ball_only(&text);
    let by_hand = sphere_only
        .replace(
            "WorldBegin\n",
            "WorldBegin\nMakeNamedMedium \"skin\" \"string type\" \"homogeneous\" \"string preset\" \"Skin1\" \"float scale\" 10\n",
        )
        .replace("Material \"subsurface\" \"string name\" \"Skin1\" \"float scale\" 10", "Material \"glass\" \"float index\" 1.33\n  MediumInterface \"skin\" \"\"");
    let dir = root().join("pbrt-scenes/verify");
    let render = |text: &str, fixes: pbrt_sppm::fixes::Fixes| {
        let path = dir.join("inline.pbrt");
        let mut s = load_scene_from_bytes(&path, text.as_bytes().to_vec(), &LoadOptions::default()).expect("loads");
        s.fixes = fixes;
        let rs = RenderScene::for_integrator(&s, true);
        (pbrt_sppm::integrators::render(&rs, &vcm(8, 1)).expect("renders").image, rs.subsurface)
    };
    let walk = pbrt_sppm::fixes::Fixes::NONE.with(pbrt_sppm::fixes::Fix::SubsurfaceWalk);
    let ((a, a_bssrdf), (b, _), (c, _)) = (
        render(&sphere_only, walk),
        render(&by_hand, pbrt_sppm::fixes::Fixes::NONE),
        render(&sphere_only, Default::default()),
    );
    assert!(!a_bssrdf, "the walk leaves the BSSRDF out");
    let dev = |x: &pbrt_sppm::imageio::RgbImage| {
        metrics::worst_mean_deviation(&x.pixels, &b.pixels, x.width, x.height, 4, 0.05).0
    };
    assert!(dev(&a) < 0.02, "the walk differs from glass over the medium by {}", dev(&a));
    assert!(dev(&c) > 0.05, "the BSSRDF's image is the walk's: {}", dev(&c));
    // `check` names the fix where a path tracer's file has the material, not elsewhere.
    let bugs = |t: &str| scene(t).pbrt_bugs.iter().map(|b| b.name.clone()).collect::<Vec<_>>();
    assert!(bugs(&text).contains(&"subsurface-walk".to_string()));
    assert!(
        !bugs(&text.replace("Integrator \"path\"", "Integrator \"sppm\"")).contains(&"subsurface-walk".to_string())
    );
}

/// The techniques' weights sum to one on paths through a BSSRDF: camera paths that find
/// the lights by themselves (weight 1) render the ball as all of vcm's techniques do.
#[test]
fn camera_paths_alone_render_the_ball_as_all_techniques_do() {
    let text = std::fs::read_to_string(root().join("pbrt-scenes/verify/v3-subsurface.pbrt")).unwrap();
    let ball = ball_only(&text);
    let dir = root().join("pbrt-scenes/verify");
    let s = load_scene_from_bytes(&dir.join("inline.pbrt"), ball.into_bytes(), &LoadOptions::default()).unwrap();
    let rs = RenderScene::for_integrator(&s, true);
    let mean = |techniques: Techniques, passes: u32| {
        let settings = RenderSettings { algorithm: Some(Algorithm::Vcm(techniques)), ..vcm(passes, 7) };
        let image = pbrt_sppm::integrators::render(&rs, &settings).expect("renders").image;
        let w = image.width;
        let (sum, n) = image
            .pixels
            .iter()
            .enumerate()
            .filter(|(i, _)| (32..66).contains(&(i / w)) && (24..66).contains(&(i % w)))
            .fold((0.0f64, 0u32), |(s, n), (_, p)| (s + (p[0] + p[1] + p[2]) as f64, n + 1));
        sum / n as f64
    };
    let hits = Techniques::Only(pbrt_sppm::integrators::vcm::Technique::EmitterHit);
    let (all, alone) = (mean(Techniques::All, 64), mean(hits, 256));
    eprintln!("the ball: all techniques {all}, emitters found alone {alone}");
    assert!((all / alone - 1.0).abs() < 0.02, "all {all}, emitters found alone {alone}");
}

/// `v3-subsurface.pbrt`'s text without its `kdsubsurface` block: the ball alone.
fn ball_only(text: &str) -> String {
    let block = text.find("AttributeBegin\n  Material \"kdsubsurface\"").unwrap();
    let end = text[block..].find("AttributeEnd").unwrap() + block + "AttributeEnd".len();
    format!("{}{}", &text[..block], &text[end..])
}
