//! Alpha masks: which rays pass through a shape, for each version's rule.

use crate::common::scene;
use pbrt_sppm::fixes::{Fix, Fixes};
use pbrt_sppm::integrators::RenderSettings;
use pbrt_sppm::math::{Point3, Ray, Vector3};
use pbrt_sppm::render::RenderScene;

/// A quad at z = 0 (x, y in [-1, 1], uv over it) with `params`, in front of an opaque
/// quad at z = 1, in a file of syntax `v3` or v4.
fn two_quads(v3: bool, params: &str, textures: &str) -> RenderScene {
    let (pt, uv) = if v3 { ("point", "float uv") } else { ("point3", "point2 uv") };
    let text = format!(
        "WorldBegin\n{textures}\n\
         Shape \"trianglemesh\" \"{pt} P\" [-1 -1 0 1 -1 0 1 1 0 -1 1 0] \"integer indices\" [0 1 2 0 2 3] \
         \"{uv}\" [0 0 1 0 1 1 0 1] {params}\n\
         Shape \"trianglemesh\" \"{pt} P\" [-1 -1 1 1 -1 1 1 1 1 -1 1 1] \"integer indices\" [0 1 2 0 2 3]\n{}",
        if v3 { "WorldEnd\n" } else { "" }
    );
    RenderScene::new(&scene(&text))
}

fn ray_at(x: f32, y: f32) -> Ray {
    Ray::new(Point3::new(x, y, -1.0), Vector3::new(0.0, 0.0, 1.0))
}

/// The z of the surface the ray through (x, y) stops at, if any.
fn stop(s: &RenderScene, x: f32, y: f32) -> Option<f32> {
    s.intersect(&ray_at(x, y)).map(|h| s.geometry.interaction(&h).p.0.z)
}

#[test]
fn v3_alpha_zero_cuts_and_anything_else_is_opaque() {
    assert_eq!(stop(&two_quads(true, "\"float alpha\" 0", ""), 0.1, 0.2), Some(1.0));
    assert_eq!(stop(&two_quads(true, "\"float alpha\" 0.5", ""), 0.1, 0.2), Some(0.0));
    // A texture: 0 on the left half (u < 0.5), 0.3 on the right.
    let tex = "Texture \"half\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float tex1\" 0 \"float tex2\" 0.3";
    let s = two_quads(true, "\"texture alpha\" \"half\"", tex);
    assert_eq!(stop(&s, -0.5, 0.0), Some(1.0));
    assert_eq!(stop(&s, 0.5, 0.0), Some(0.0));
    // t is in units of the original ray's direction, beyond the cut-away surface.
    let hit = s.intersect(&ray_at(-0.5, 0.0)).expect("the back quad");
    assert!((hit.t - 2.0).abs() < 1e-4, "{}", hit.t);
}

#[test]
fn v3_shadowalpha_masks_shadow_rays_only() {
    let s = two_quads(true, "\"float shadowalpha\" 0", "");
    assert_eq!(stop(&s, 0.0, 0.0), Some(0.0), "camera and photon rays still hit it");
    let to_middle = Ray { o: Point3::new(0.0, 0.0, -1.0), d: Vector3::new(0.0, 0.0, 1.5), t_max: 1.0, time: 0.0 };
    assert!(!s.intersect_p(&to_middle), "a shadow ray passes through");
    let plain = two_quads(true, "", "");
    assert!(plain.intersect_p(&to_middle));
}

#[test]
fn v4_alpha_lets_a_fraction_of_rays_through() {
    let s = two_quads(false, "\"float alpha\" 0.25", "");
    let n = 4000;
    let through = (0..n).filter(|i| stop(&s, -0.9 + 1.8 * (*i as f32 + 0.5) / n as f32, 0.37) == Some(1.0)).count();
    let frac = through as f64 / n as f64;
    assert!((frac - 0.75).abs() < 0.04, "{frac} of the rays passed, not 3/4");
    // The same ray gets the same answer.
    let r = ray_at(0.123, 0.456);
    assert_eq!(s.intersect(&r), s.intersect(&r));
    assert_eq!(stop(&two_quads(false, "\"float alpha\" 0", ""), 0.0, 0.0), Some(1.0));
    assert_eq!(stop(&two_quads(false, "\"float alpha\" 1", ""), 0.0, 0.0), Some(0.0));
}

#[test]
fn v4_alpha_cuts_quadrics_and_instances() {
    let text = "WorldBegin\n\
        ObjectBegin \"ball\"\nShape \"sphere\" \"float radius\" 1 \"float alpha\" 0\nObjectEnd\n\
        ObjectInstance \"ball\"\n\
        Translate 0 0 3\nShape \"sphere\" \"float radius\" 1\n";
    let s = RenderScene::new(&scene(text));
    let hit = s.intersect(&Ray::new(Point3::new(0.0, 0.0, -5.0), Vector3::new(0.0, 0.0, 1.0))).expect("a hit");
    assert!((s.geometry.interaction(&hit).p.0.z - 2.0).abs() < 1e-4, "the instanced ball is cut away");
}

/// An emitting quad at z = 1 facing down over a diffuse floor, with the light's alpha
/// `params`, in a file of syntax `v3` or v4; 16×16 pixels looking down at the floor.
fn masked_light(v3: bool, params: &str, textures: &str) -> RenderScene {
    masked_light_fixed(v3, params, textures, Fixes::NONE)
}

/// [`masked_light`] with the pbrt bugs in `fixes` fixed.
fn masked_light_fixed(v3: bool, params: &str, textures: &str, fixes: Fixes) -> RenderScene {
    let (pt, uv) = if v3 { ("point", "float uv") } else { ("point3", "point2 uv") };
    let film = if v3 { "image" } else { "rgb" };
    let text = format!(
        "LookAt 0 -3 4  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 40\n\
         Film \"{film}\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
         Integrator \"sppm\" \"integer photonsperiteration\" 2000\n\
         Sampler \"halton\" \"integer pixelsamples\" 4\n\
         WorldBegin\n{textures}\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [5 5 5]\n\
         Shape \"trianglemesh\" \"{pt} P\" [-1 -1 1 -1 1 1 1 1 1 1 -1 1] \"integer indices\" [0 1 2 0 2 3] \
         \"{uv}\" [0 0 0 1 1 1 1 0] {params}\nAttributeEnd\n\
         Shape \"trianglemesh\" \"{pt} P\" [-4 -4 0 4 -4 0 4 4 0 -4 4 0] \"integer indices\" [0 1 2 0 2 3]\n{}",
        if v3 { "WorldEnd\n" } else { "" }
    );
    let mut s = scene(&text);
    s.fixes = fixes;
    RenderScene::new(&s)
}

/// The fraction of light samples from the middle of the floor that the light's alpha
/// mask cuts away (the quad is two lights, one per triangle, of equal area).
fn masked_fraction(s: &RenderScene) -> f64 {
    assert_eq!(s.lights.len(), 2);
    let mut rng = pbrt_sppm::sampling::Rng::new(5);
    let n = 4000;
    let masked = (0..n)
        .filter(|k| {
            let light = &s.lights[k % 2];
            let ls = light.sample_li(&s.geometry.shapes, glam::Vec3::ZERO, rng.uniform2()).expect("a sample");
            s.emission_masked(light, ls.surface.as_ref())
        })
        .count();
    masked as f64 / n as f64
}

#[test]
fn alpha_cuts_area_light_emission_where_it_cuts_the_surface() {
    let half = "Texture \"half\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float tex1\" 0 \"float tex2\" 1";
    // pbrt-v4 masks light samples; pbrt-v3 only with `--fix area-alpha`.
    let fix = Fixes::NONE.with(Fix::AreaAlpha);
    for (v3, fixes) in [(true, fix), (false, Fixes::NONE), (false, fix)] {
        let f = masked_fraction(&masked_light_fixed(v3, "\"texture alpha\" \"half\"", half, fixes));
        assert!((f - 0.5).abs() < 0.03, "v3 {v3}: {f} of the light's samples cut, not half");
        assert_eq!(masked_fraction(&masked_light_fixed(v3, "", "", fixes)), 0.0);
    }
    assert_eq!(masked_fraction(&masked_light(true, "\"texture alpha\" \"half\"", half)), 0.0, "as pbrt-v3");
    // v4: α = 0.25 keeps a quarter of the emitting points.
    let f = masked_fraction(&masked_light(false, "\"float alpha\" 0.25", ""));
    assert!((f - 0.75).abs() < 0.03, "{f}");
    // A light cut away entirely lights nothing: no light samples and no photons
    // (pbrt-v4, and pbrt-v3 fixed; pbrt-v3 itself lets it light the floor).
    for (v3, fixes) in [(true, fix), (false, Fixes::NONE)] {
        let cut = masked_light_fixed(v3, "\"float alpha\" 0", "", fixes);
        let image = pbrt_sppm::integrators::render(&cut, &RenderSettings::default()).expect("renders").image;
        assert!(image.pixels.iter().all(|p| *p == [0.0; 3]), "v3 {v3}: a cut-away light lit the floor");
        let lit = pbrt_sppm::integrators::render(&masked_light(v3, "", ""), &RenderSettings::default())
            .expect("renders")
            .image;
        assert!(lit.pixels.iter().flatten().sum::<f32>() > 0.0);
    }
    let as_pbrt_v3 =
        pbrt_sppm::integrators::render(&masked_light(true, "\"float alpha\" 0", ""), &RenderSettings::default())
            .unwrap()
            .image;
    assert!(as_pbrt_v3.pixels.iter().flatten().sum::<f32>() > 0.0, "pbrt-v3's cut-away light lights the floor");
}

/// pbrt's disk sampling skips a sample's (u, v) where nothing reads it (pbrt's samples
/// have none): an alpha mask on the disk still cuts half of them by angle, and an
/// unmasked disk's samples carry (0, 0).
#[test]
fn a_masked_disk_light_reads_its_samples_uv() {
    let disk = |alpha: &str| {
        let text = format!(
            "LookAt 0 -3 4  0 0 0  0 0 1\nCamera \"perspective\"\n\
             Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n\
             Texture \"half\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float tex1\" 0 \"float tex2\" 1\n\
             AttributeBegin\nTranslate 0 0 1\nRotate 180 1 0 0\nAreaLightSource \"diffuse\" \"rgb L\" [5 5 5]\n\
             Shape \"disk\" \"float radius\" 1 {alpha}\nAttributeEnd\n"
        );
        RenderScene::new(&scene(&text))
    };
    let samples = |s: &RenderScene| {
        assert_eq!(s.lights.len(), 1);
        let mut rng = pbrt_sppm::sampling::Rng::new(5);
        let light = &s.lights[0];
        let all: Vec<_> = (0..4000)
            .map(|_| light.sample_li(&s.geometry.shapes, glam::Vec3::ZERO, rng.uniform2()).expect("a sample"))
            .collect();
        let masked = all.iter().filter(|ls| s.emission_masked(light, ls.surface.as_ref())).count();
        let uv_read = all.iter().any(|ls| ls.surface.as_ref().is_some_and(|x| x.uv != [0.0; 2]));
        (masked as f64 / all.len() as f64, uv_read)
    };
    let (cut, uv_read) = samples(&disk("\"texture alpha\" \"half\""));
    assert!((cut - 0.5).abs() < 0.03 && uv_read, "{cut} of a half-masked disk's samples cut");
    assert_eq!(samples(&disk("")), (0.0, false));
}
