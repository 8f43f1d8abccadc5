//! pbrt's bugs rendered by default and fixed by name (`--fix`): what `check` reports,
//! and each fix against an independent answer. The images with pbrt's bugs are
//! compared with pbrt's own in `pbrt_refs.rs`.

use crate::common::report;
use pbrt_sppm::fixes::{Fix, Fixes};
use pbrt_sppm::integrators::RenderSettings;
use pbrt_sppm::integrators::sppm::Sppm;
use pbrt_sppm::lights::Light;
use pbrt_sppm::render::RenderScene;
use pbrt_sppm::scene::{LoadOptions, SceneDescription, load_scene_from_bytes};
use std::path::Path;
use std::process::Command;

fn scene_with(text: &str, fixes: Fixes) -> SceneDescription {
    let opts = LoadOptions { fixes, ..Default::default() };
    load_scene_from_bytes(Path::new("tests/data/good/inline.pbrt"), text.as_bytes().to_vec(), &opts).unwrap()
}

fn mean(px: &[[f32; 3]]) -> f64 {
    px.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / px.len() as f64
}

fn rendered_mean(text: &str, fixes: Fixes) -> f64 {
    let out = pbrt_sppm::integrators::render(&RenderScene::new(&scene_with(text, fixes)), &RenderSettings::default())
        .unwrap();
    mean(&out.image.pixels)
}

/// (name, line, column, fixed) of each pbrt bug `check` reports.
fn bugs(text: &str) -> Vec<(String, u64, u64, bool)> {
    let r = report(text);
    let list = r["pbrt_bugs"].as_array().expect("a pbrt_bugs list").clone();
    list.iter()
        .map(|b| {
            let n = |k: &str| b[k].as_u64().unwrap();
            (b["name"].as_str().unwrap().to_string(), n("line"), n("column"), b["fixed"].as_bool().unwrap())
        })
        .collect()
}

#[test]
fn check_names_each_bug_at_the_statement_that_triggers_it() {
    let v3 = "Integrator \"sppm\"\nWorldBegin\nLightSource \"infinite\"\n\
              MakeNamedMaterial \"unused\" \"string type\" \"plastic\"\n\
              Material \"plastic\"\nShape \"sphere\"\n\
              Texture \"m\" \"spectrum\" \"marble\"\nMaterial \"matte\" \"texture Kd\" \"m\"\nShape \"sphere\"\n\
              AttributeBegin\nAreaLightSource \"diffuse\"\n\
              Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 1 1 0] \"integer indices\" [0 1 2] \"float alpha\" 0\n\
              AttributeEnd\nWorldEnd\n";
    let got = bugs(v3);
    let want = [
        ("photons-behind", 1, 12),
        ("sky-after-glossy", 3, 13),
        ("plastic-fresnel", 5, 10),
        ("marble-palette", 7, 24),
        ("area-alpha", 11, 17),
    ];
    assert_eq!(got.len(), want.len(), "{got:?}");
    for ((name, line, col, fixed), (wn, wl, wc)) in got.iter().zip(want) {
        assert_eq!((name.as_str(), *line, *col, *fixed), (wn, wl, wc, false), "{got:?}");
    }
    // The v4 ones: a rough coat and `power` on a mesh; a smooth coat triggers nothing.
    let v4 = "WorldBegin\nMaterial \"coateddiffuse\" \"float roughness\" 0.2\nShape \"sphere\"\n\
              Material \"coateddiffuse\" \"float roughness\" 0\nShape \"sphere\"\n\
              AreaLightSource \"diffuse\" \"float power\" 10\n\
              Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0 2 0 0 2 1 0] \"integer indices\" [0 1 2 3 1 4 3 5]\n";
    let names: Vec<String> = bugs(v4).into_iter().map(|b| b.0).collect();
    // Without `Integrator "sppm"` pbrt path-traces: no photons-behind.
    assert_eq!(names, ["layered-weights", "mesh-power"]);
}

#[test]
fn check_names_rough_transmission_where_a_v3_material_has_it() {
    // Rough glass, translucent and disney's spectrans do; smooth glass, rough glass that
    // passes nothing, and disney without spectrans do not.
    let v3 = "WorldBegin\nMaterial \"glass\" \"float uroughness\" 0.1 \"float vroughness\" 0.1\nShape \"sphere\"\n\
              Material \"glass\"\nShape \"sphere\"\n\
              Material \"glass\" \"float uroughness\" 0.1 \"color Kt\" [0 0 0]\nShape \"sphere\"\n\
              Material \"translucent\"\nShape \"sphere\"\n\
              Material \"disney\"\nShape \"sphere\"\n\
              Material \"disney\" \"float spectrans\" 0.5\nShape \"sphere\"\nWorldEnd\n";
    let got: Vec<(String, u64)> = bugs(v3).into_iter().map(|b| (b.0, b.1)).collect();
    let want = [2, 8, 12].map(|line| ("rough-transmission".to_string(), line));
    assert_eq!(got, want);
    // pbrt-v4's rough dielectric leaves those facets out already.
    let v4 = "WorldBegin\nMaterial \"dielectric\" \"float roughness\" 0.1\nShape \"sphere\"\n";
    assert!(bugs(v4).is_empty(), "{:?}", bugs(v4));
}

#[test]
fn check_says_which_bugs_the_run_fixes() {
    let text = "WorldBegin\nMaterial \"plastic\"\nShape \"sphere\"\nWorldEnd\n";
    let s = scene_with(text, Fixes::NONE.with(Fix::PlasticFresnel));
    let r = pbrt_sppm::cli::check::report(&s, false);
    let b = r["pbrt_bugs"].as_array().unwrap();
    let fixed: Vec<(&str, bool)> =
        b.iter().map(|b| (b["name"].as_str().unwrap(), b["fixed"].as_bool().unwrap())).collect();
    assert_eq!(fixed, [("plastic-fresnel", true)]);
    assert_eq!(r["fixes"], "plastic-fresnel");
}

#[test]
fn the_command_line_takes_fix_names_and_lists_them() {
    let bin = env!("CARGO_BIN_EXE_pbrt-sppm");
    let help = Command::new(bin).args(["--fix", "help"]).output().unwrap();
    assert!(help.status.success());
    let text = String::from_utf8_lossy(&help.stdout);
    for i in &pbrt_sppm::fixes::FIXES {
        assert!(text.contains(i.name), "--fix help lacks {}:\n{text}", i.name);
    }
    let bad =
        Command::new(bin).args(["check", "pbrt-scenes/verify/v3-plastic.pbrt", "--fix", "plastik"]).output().unwrap();
    assert_eq!(bad.status.code(), Some(2), "clap's usage error");
    assert!(String::from_utf8_lossy(&bad.stderr).contains("unknown fix \"plastik\""));
    let out = Command::new(bin)
        .args(["check", "pbrt-scenes/verify/v3-plastic.pbrt", "--json", "--fix", "all"])
        .current_dir(crate::common::root())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["pbrt_bugs"].as_array().unwrap().iter().all(|b| b["fixed"] == true));
}

/// A rough, almost perfectly reflecting metal ball (α = 0.316) under a uniform white
/// sky, in either syntax. Mitsuba 3 renders its export at 0.849 (4096 spp).
fn glossy_ball(v3: bool) -> String {
    let (film, light, metal) = match v3 {
        true => (
            "image",
            "\"color L\" [1 1 1]",
            "\"metal\" \"color eta\" [.2 .2 .2] \"color k\" [8 8 8] \"float roughness\" 0.316 \"bool remaproughness\" \"false\"",
        ),
        false => (
            "rgb",
            "\"rgb L\" [1 1 1]",
            "\"conductor\" \"rgb eta\" [.2 .2 .2] \"rgb k\" [8 8 8] \"float roughness\" 0.1",
        ),
    };
    format!(
        "LookAt 0 0 -5  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 8 \
         Film \"{film}\" \"integer xresolution\" 16 \"integer yresolution\" 16 \
         Integrator \"sppm\" \"integer numiterations\" 16 \"integer photonsperiteration\" 1000 \
         WorldBegin LightSource \"infinite\" {light} Material {metal} Shape \"sphere\" {}",
        if v3 { "WorldEnd" } else { "" }
    )
}

/// pbrt-v3 counts the sky twice after the glossy bounce (about 1.7); fixed, and in
/// pbrt-v4, once: what Mitsuba 3 renders.
#[test]
fn a_glossy_ball_under_a_sky_reflects_it_twice_in_pbrt_v3_and_once_fixed_or_in_v4() {
    let pbrt_v3 = rendered_mean(&glossy_ball(true), Fixes::NONE);
    let fixed = rendered_mean(&glossy_ball(true), Fixes::NONE.with(Fix::SkyAfterGlossy));
    let pbrt_v4 = rendered_mean(&glossy_ball(false), Fixes::NONE);
    assert!((1.55..1.85).contains(&pbrt_v3), "as pbrt-v3: {pbrt_v3}");
    assert!((0.80..0.90).contains(&fixed), "v3 fixed: {fixed}");
    assert!((0.80..0.90).contains(&pbrt_v4), "as pbrt-v4: {pbrt_v4}");
}

/// `power` on an emitting mesh: pbrt-v4 gives each of its triangles the whole power
/// (2 triangles, twice the watts); fixed, the mesh emits what the file asks for.
#[test]
fn power_on_a_mesh_is_per_triangle_in_pbrt_v4_and_whole_when_fixed() {
    let text = "WorldBegin AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"float power\" 20 \
                Shape \"trianglemesh\" \"point3 P\" [0 0 0 3 0 0 3 1 0 0 2 0] \"integer indices\" [0 1 2 0 2 3]";
    let emitted = |fixes: Fixes| {
        let rs = RenderScene::new(&scene_with(text, fixes));
        let l: Vec<f32> = rs.lights.iter().map(|l| if let Light::Area(a) = l { a.l.x } else { 0.0 }).collect();
        (rs.lights.iter().map(|l| l.power(rs.world)).sum::<f64>(), l)
    };
    let (pbrt, l) = emitted(Fixes::NONE);
    assert!((pbrt - 40.0).abs() < 1e-3, "as pbrt-v4: {pbrt} W");
    assert!(l[0] != l[1], "the smaller triangle is brighter: {l:?}");
    let (fixed, l) = emitted(Fixes::NONE.with(Fix::MeshPower));
    assert!((fixed - 20.0).abs() < 1e-3, "fixed: {fixed} W");
    assert_eq!(l[0], l[1]);
}

/// An area light whose alpha cuts it away entirely: rays pass through it, and pbrt-v3
/// still lets it emit photons and light samples (the floor is lit). Fixed, nothing
/// emits: the floor is black, exactly.
#[test]
fn a_cut_away_area_light_still_emits_in_pbrt_v3_unless_fixed() {
    let text = "LookAt 0 3 -3  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 60 \
                Film \"image\" \"integer xresolution\" 12 \"integer yresolution\" 12 \
                Integrator \"sppm\" \"integer numiterations\" 4 \"integer photonsperiteration\" 2000 \
                WorldBegin AttributeBegin AreaLightSource \"diffuse\" \"color L\" [4 4 4] \
                Shape \"trianglemesh\" \"point P\" [-1 2 -1 1 2 -1 1 2 1 -1 2 1] \"integer indices\" [0 1 2 0 2 3] \
                \"float alpha\" 0 AttributeEnd \
                Material \"matte\" Shape \"trianglemesh\" \"point P\" [-5 0 -5 5 0 -5 5 0 5 -5 0 5] \
                \"integer indices\" [0 1 2 0 2 3] WorldEnd";
    let pbrt = rendered_mean(text, Fixes::NONE);
    let fixed = rendered_mean(text, Fixes::NONE.with(Fix::AreaAlpha));
    assert!(pbrt > 0.05, "as pbrt-v3, the cut-away light lights the floor: {pbrt}");
    assert_eq!(fixed, 0.0);
}

/// A quad lit from behind by a point light, which a wall behind the light bounces back
/// onto it, seen from the front: pbrt counts the photons that reach its visible points
/// from behind in M (radii shrink); fixed, they are left out and the radii stay. The
/// image is black either way.
#[test]
fn photons_from_behind_shrink_the_radius_unless_fixed() {
    let text = "LookAt 0 0 -3  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 30 \
                Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8 \
                WorldBegin LightSource \"point\" \"point3 from\" [0 0 1] \"rgb I\" [5 5 5] \
                Material \"diffuse\" Shape \"bilinearmesh\" \"point3 P\" [-2 -2 0 2 -2 0 -2 2 0 2 2 0] \
                Shape \"bilinearmesh\" \"point3 P\" [-9 -9 2 9 -9 2 -9 9 2 9 9 2]";
    let radii = |fixes: Fixes| {
        let rs = RenderScene::new(&scene_with(text, fixes));
        let mut sppm = Sppm::new(&rs, 4, 20_000, 0.5, 0, Default::default()).unwrap();
        (0..4).for_each(|_| sppm.iterate());
        assert_eq!(mean(&sppm.image()), 0.0);
        sppm.pixels.iter().map(|p| p.radius).fold(0.0, f64::max)
    };
    assert!(radii(Fixes::NONE) < 0.45, "as pbrt: {}", radii(Fixes::NONE));
    assert_eq!(radii(Fixes::NONE.with(Fix::PhotonsBehind)), 0.5);
}

/// pbrt-v4's SPPM follows a camera path one bounce past its visible point: a smooth
/// coat over a black base, lit only by a large area light, shows the light's
/// reflection (Fresnel about 4% at normal incidence).
#[test]
fn a_smooth_coat_reflects_an_area_light_as_in_pbrt_v4() {
    let text = "LookAt 0 0 -5  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 5 \
                Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8 \
                Sampler \"halton\" \"integer pixelsamples\" 256 Integrator \"sppm\" \
                WorldBegin AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \
                Translate 0 0 -6 Shape \"disk\" \"float radius\" 100 AttributeEnd \
                Material \"coateddiffuse\" \"rgb reflectance\" [0 0 0] \"float roughness\" 0 \
                Shape \"bilinearmesh\" \"point3 P\" [-2 -2 0 2 -2 0 -2 2 0 2 2 0]";
    let l = rendered_mean(text, Fixes::NONE);
    assert!((0.035..0.045).contains(&l), "reflected {l}, expected about 0.04");
}

/// A sphere of radius 1 under `Scale 2` with `ReverseOrientation`: its world normal is
/// −p/1 in object terms, so ∂n/∂u is −∂p/∂u (object). pbrt transforms the object ∂n/∂u
/// (= ∂p/∂u) as a normal, halving it, and keeps its sign: half the size, the wrong way.
#[test]
fn pbrt_halves_and_keeps_the_sign_of_a_scaled_reversed_spheres_normal_derivative() {
    use pbrt_sppm::math::{Point3, Ray, Vector3};
    use pbrt_sppm::shapes::quadric::QuadricShape;
    use pbrt_sppm::shapes::{Quadric, sphere::Sphere};
    let m = glam::DMat4::from_scale(glam::DVec3::splat(2.0));
    let q = Quadric::Sphere(Sphere::new(1.0, -1.0, 1.0, 360.0));
    let mut shape = QuadricShape::new(q.clone(), m, true);
    let ray = Ray::new(Point3::new(0.3, -5.0, 0.4), Vector3::new(0.0, 1.0, 0.0));
    let fixed = shape.interaction(&shape.intersect_t(&ray, f32::INFINITY).unwrap());
    shape.pbrt_normal_derivatives = true;
    let pbrt = shape.interaction(&shape.intersect_t(&ray, f32::INFINITY).unwrap());
    // The fix: the derivative of the reported normal, by finite differences in u.
    let [u, v] = fixed.uv.map(f64::from);
    let normal = |u: f64| -(m.transform_point3(q.point(u, v)) / 2.0);
    let h = 1e-4;
    let want = ((normal(u + h) - normal(u - h)) / (2.0 * h)).as_vec3();
    assert!((fixed.dndu.0 - want).length() < 1e-3 * want.length(), "fixed {} vs {want}", fixed.dndu.0);
    assert!((pbrt.dndu.0 + 0.5 * want).length() < 1e-3 * want.length(), "pbrt {} vs {}", pbrt.dndu.0, -0.5 * want);
}

#[test]
fn check_reports_scaled_emitters_and_bumped_scaled_quadrics() {
    let text = "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\"\nScale 2 2 2\nShape \"sphere\"\nAttributeEnd\n\
                AttributeBegin\nAreaLightSource \"diffuse\"\nShape \"disk\" \"float innerradius\" 0.5\nAttributeEnd\n\
                AttributeBegin\nAreaLightSource \"diffuse\"\nTranslate 3 0 0\nShape \"sphere\"\nAttributeEnd\n\
                Texture \"b\" \"float\" \"fbm\"\nMaterial \"diffuse\" \"texture displacement\" \"b\"\n\
                AttributeBegin\nScale 1 1 3\nShape \"cylinder\"\nAttributeEnd\nShape \"cylinder\"\n";
    let got: Vec<(String, u64)> = bugs(text).into_iter().map(|b| (b.0, b.1)).collect();
    let want = [("shape-sampling", 3), ("shape-sampling", 8), ("normal-derivatives", 17)];
    assert_eq!(got, want.map(|(n, l)| (n.to_string(), l)));
}

#[test]
fn check_reports_hyperboloids_whose_implicit_fit_is_another_surface() {
    let text = |p1: &str, p2: &str| {
        format!("WorldBegin\nShape \"hyperboloid\" \"point p1\" [{p1}] \"point p2\" [{p2}]\nWorldEnd\n")
    };
    // Closest to the axis at z = 0.5: pbrt-v3's fit (waist at z = 0) is another surface.
    let names: Vec<String> = bugs(&text("1 0 0", "0 1 1")).into_iter().map(|b| b.0).collect();
    assert_eq!(names, ["hyperboloid-surface"]);
    // Closest at z = 0: the fit is the swept surface.
    assert!(bugs(&text("1 0 -1", "0 1 1")).is_empty());
}

#[test]
fn a_sky_over_matte_alone_triggers_nothing_in_v3() {
    let matte = "WorldBegin\nLightSource \"infinite\"\nMaterial \"matte\"\nShape \"sphere\"\nWorldEnd\n";
    assert!(bugs(matte).is_empty());
    let metal = matte.replace("\"matte\"", "\"metal\"");
    let names: Vec<String> = bugs(&metal).into_iter().map(|b| b.0).collect();
    assert_eq!(names, ["sky-after-glossy"]);
}

#[test]
fn pbrt_v4s_double_alpha_mask_is_reported_only_for_fractional_alpha() {
    let text = |alpha: &str| {
        format!(
            "WorldBegin\nAreaLightSource \"diffuse\"\n\
             Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 1 1 0] \"integer indices\" [0 1 2] \"float alpha\" {alpha}\n"
        )
    };
    let names = |a: &str| bugs(&text(a)).into_iter().map(|b| b.0).collect::<Vec<_>>();
    assert_eq!(names("0.5"), ["area-alpha"]);
    assert!(names("0").is_empty(), "0 or 1 masks the same once or twice");
}

/// pbrt-v3's SPPM draws each photon's time apart from the camera paths', so the
/// turning box of v3-motion gathers photons that landed where it is at other times.
/// `--fix motion-time` renders each pass at one time: then SPPM and bdpt (whose
/// subpaths share their pass's time) agree. Measured at 128 passes: fixed 2.1% apart,
/// pbrt-v3's way 13% at the box.
#[test]
fn motion_time_fix_lights_moving_surfaces_as_bdpt_does() {
    use pbrt_sppm::imageio::metrics;
    use pbrt_sppm::integrators::Algorithm;
    let path = crate::common::root().join("pbrt-scenes/verify/v3-motion.pbrt");
    let render = |fixes: Fixes, algorithm: Algorithm| {
        let mut scene = crate::common::load_file(&path).unwrap();
        scene.fixes = fixes;
        let rs = RenderScene::for_integrator(&scene, algorithm != Algorithm::Sppm);
        let settings = RenderSettings { algorithm: Some(algorithm), iterations: Some(128), ..Default::default() };
        pbrt_sppm::integrators::render(&rs, &settings).unwrap().image
    };
    let bdpt = render(Fixes::NONE, Algorithm::Vcm(pbrt_sppm::integrators::vcm::Techniques::Bdpt));
    let worst = |img: &pbrt_sppm::imageio::RgbImage| {
        metrics::worst_mean_deviation(&img.pixels, &bdpt.pixels, img.width, img.height, 4, 0.05).0
    };
    let (fixed, pbrt) = (
        worst(&render(Fixes::NONE.with(Fix::MotionTime), Algorithm::Sppm)),
        worst(&render(Fixes::NONE, Algorithm::Sppm)),
    );
    assert!(fixed < 0.035, "fixed: {:.2}% off bdpt", 100.0 * fixed);
    assert!(pbrt > 0.08, "as pbrt-v3: only {:.2}% off bdpt", 100.0 * pbrt);
}

/// pbrt-v4 measures an equal-area map's `illuminance` with half its texels' solid
/// angle, so a floor under it gets twice the lux asked for; fixed, it gets what the
/// file asks for. A grey floor (reflectance 0.5) under π lux seen from above has
/// luminance 0.5·π/π = 0.5 (pbrt-v4: 1.0; measured with its SPPM 1.01 under a grey
/// map, 0.97 under this blue sky, where its spectral colours shift; ours 1.00).
#[test]
fn an_equal_area_maps_illuminance_is_doubled_in_pbrt_v4_unless_fixed() {
    let text = "LookAt 0 5 0  0 0 0  0 0 1 Camera \"orthographic\" \
                Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8 \
                Sampler \"halton\" \"integer pixelsamples\" 64 \
                Integrator \"sppm\" \"integer maxdepth\" 1 \"integer photonsperiteration\" 2000 \"float radius\" 0.5 \
                WorldBegin AttributeBegin Rotate -90 1 0 0 \
                LightSource \"infinite\" \"string filename\" \"../../../pbrt-scenes/verify/textures/sky-equalarea.exr\" \
                \"float illuminance\" 3.14159265 AttributeEnd \
                Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5] \
                Shape \"trianglemesh\" \"point3 P\" [-3 0 -3 3 0 -3 3 0 3 -3 0 3] \"integer indices\" [0 1 2 0 2 3]";
    // Illuminance weighs colours by luminance: so does the check.
    let luminance = |fixes: Fixes| {
        let out =
            pbrt_sppm::integrators::render(&RenderScene::new(&scene_with(text, fixes)), &RenderSettings::default());
        let px = out.unwrap().image.pixels;
        px.iter().map(|p| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64).sum::<f64>() / px.len() as f64
    };
    let (pbrt, fixed) = (luminance(Fixes::NONE), luminance(Fixes::NONE.with(Fix::MapIlluminance)));
    assert!((fixed - 0.5).abs() < 0.01, "fixed: {fixed}");
    assert!((pbrt / fixed - 2.0).abs() < 1e-3, "as pbrt-v4: {pbrt} against {fixed}");
    let names: Vec<String> = bugs(text).into_iter().map(|b| b.0).collect();
    assert!(names.contains(&"map-illuminance".to_string()), "{names:?}");
    // Without `illuminance`, or with a constant sky, nothing to fix.
    let plain = text.replace("\"float illuminance\" 3.14159265", "");
    assert!(!bugs(&plain).into_iter().any(|b| b.0 == "map-illuminance"));
}
