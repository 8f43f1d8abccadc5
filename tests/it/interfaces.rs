//! The two-way interfaces bidirectional methods need, checked against their own
//! definitions: a light's emission densities (`pdf_le` against what `sample_le` drew,
//! and each density integrating to one), a camera's importance (`we` inverting
//! `generate_ray`, integrating to one over the lens and directions, `sample_wi` agreeing
//! with `we`), and a BSDF both ways (`eval`'s densities against `sample_f`, f carried as
//! importance being the adjoint of f carried as radiance).

use crate::common::scene;
use glam::Vec3;
use pbrt_sppm::interaction::Footprint;
use pbrt_sppm::lights::Light;
use pbrt_sppm::materials::TransportMode;
use pbrt_sppm::math::{Point3, Ray, Vector3};
use pbrt_sppm::render::RenderScene;
use pbrt_sppm::sampling::{Rng, uniform_sphere};

/// Every kind of light, area lights on a quadric, a cut quadric, a triangle mesh and a
/// bilinear patch.
const LIGHTS: &str = r#"
LookAt 0 0 -6  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 64 "integer yresolution" 48
WorldBegin
LightSource "point" "rgb I" [5 5 5] "point3 from" [0 2 0]
LightSource "spot" "rgb I" [5 5 5] "point3 from" [0 3 0] "point3 to" [0 0 0] "float coneangle" 25
LightSource "distant" "point3 from" [1 1 1] "point3 to" [0 0 0] "rgb L" [1 1 1]
LightSource "infinite" "rgb L" [.2 .2 .2]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [2 2 2]
  Translate 1 1 0 Scale 1 2 1
  Shape "sphere" "float radius" 0.3 "float zmin" -0.1
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [2 2 2] "bool twosided" true
  Shape "trianglemesh" "point3 P" [-1 2 -1  1 2 -1  0 2.5 1] "integer indices" [0 1 2]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [2 2 2]
  Shape "bilinearmesh" "point3 P" [-1 -1 2  1 -1 2.5  -1 1 2  1 1 1.5]
AttributeEnd
Shape "sphere" "float radius" 0.5
"#;

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-12
}

#[test]
fn pdf_le_gives_the_densities_sample_le_drew_with() {
    let rs = RenderScene::new(&scene(LIGHTS));
    assert_eq!(rs.lights.len(), 7, "point, spot, distant, infinite and three area lights");
    let shapes = &rs.geometry.shapes;
    let mut rng = Rng::new(7);
    for (k, light) in rs.lights.iter().enumerate() {
        let mut checked = 0;
        for _ in 0..2000 {
            let Some(e) = light.sample_le(shapes, rs.world, rng.uniform2(), rng.uniform2()) else { continue };
            if e.le == Vec3::ZERO {
                continue;
            }
            let (pos, dir) = light.pdf_le(shapes, rs.world, &e.ray, e.n);
            // Delta positions (point, spot) and directions (distant) have density 0 in
            // pbrt's `PDF_Le`; sample_le reports 1 for them.
            let delta_pos = matches!(light, Light::Point(_) | Light::Spot(_));
            let delta_dir = matches!(light, Light::Distant(_));
            assert!(delta_pos || close(pos, e.pdf_pos, 2e-3), "light {k}: position density {pos} vs {}", e.pdf_pos);
            assert!(delta_dir || close(dir, e.pdf_dir, 2e-3), "light {k}: direction density {dir} vs {}", e.pdf_dir);
            checked += 1;
        }
        assert!(checked > 1000, "light {k}: only {checked} emissions");
    }
}

/// E[1/p(x)] over points drawn with density p is the area they are drawn from.
#[test]
fn area_lights_position_densities_integrate_to_one() {
    let rs = RenderScene::new(&scene(LIGHTS));
    let shapes = &rs.geometry.shapes;
    let mut rng = Rng::new(3);
    for light in rs.lights.iter() {
        let Light::Area(a) = light else { continue };
        let n = 20_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let e = light.sample_le(shapes, rs.world, rng.uniform2(), rng.uniform2()).expect("an emission");
            let (pos, _) = light.pdf_le(shapes, rs.world, &e.ray, e.n);
            sum += 1.0 / pos as f64;
        }
        let area = sum / n as f64;
        assert!((area - a.area as f64).abs() < 0.02 * a.area as f64, "area {area} vs {}", a.area);
    }
}

#[test]
fn emission_direction_densities_integrate_to_one() {
    let rs = RenderScene::new(&scene(LIGHTS));
    let shapes = &rs.geometry.shapes;
    let mut rng = Rng::new(11);
    for (k, light) in rs.lights.iter().enumerate().filter(|(_, l)| !matches!(l, Light::Distant(_))) {
        // One emission's origin and normal; directions over the whole sphere.
        let e = light.sample_le(shapes, rs.world, [0.3, 0.6], [0.5, 0.5]).expect("an emission");
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let d = uniform_sphere(rng.uniform2());
            let ray = Ray::new(e.ray.o, Vector3(d));
            sum += light.pdf_le(shapes, rs.world, &ray, e.n).1 as f64;
        }
        let integral = 4.0 * std::f64::consts::PI * sum / n as f64;
        assert!((integral - 1.0).abs() < 0.03, "light {k}: ∫ pdf_dir dω = {integral}");
    }
}

fn camera_scene(lens: &str) -> RenderScene {
    let text = format!(
        r#"LookAt 1 2 -6  0 0 0  0 1 0
Camera "perspective" "float fov" 35 {lens}
Film "rgb" "integer xresolution" 80 "integer yresolution" 50
WorldBegin
LightSource "point" "rgb I" [1 1 1]
Shape "sphere""#
    );
    RenderScene::new(&scene(&text))
}

#[test]
fn camera_importance_inverts_generate_ray() {
    for lens in ["", r#""float lensradius" 0.2 "float focaldistance" 5"#] {
        let rs = camera_scene(lens);
        let mut rng = Rng::new(5);
        for _ in 0..1000 {
            let raster = [rng.uniform() * 80.0, rng.uniform() * 50.0];
            let ray = rs.camera.generate_ray(raster, rng.uniform2());
            let (we, back) = rs.camera.we(&ray).expect("a ray through the film has importance");
            assert!(we > 0.0);
            let off = (back[0] - raster[0]).abs().max((back[1] - raster[1]).abs());
            assert!(off < 2e-3, "lens {lens:?}: raster {raster:?} came back as {back:?}");
            let (pos, dir) = rs.camera.pdf_we(&ray);
            assert!(pos > 0.0 && dir > 0.0);
        }
        let behind =
            Ray::new(Point3(Vec3::new(1.0, 2.0, -6.0)), Vector3(Vec3::new(-1.0, -2.0, 6.0).normalize() * -1.0));
        assert!(rs.camera.we(&behind).is_none(), "nothing behind the camera");
    }
}

/// ∫∫ We cos θ dω dA_lens = 1 over the film, and the direction density integrates to
/// one there. (Rays also reach a pixel filter's margin around it, 1 pixel for the
/// default Gaussian, where light tracing finds what the edge pixels' rays see.)
#[test]
fn camera_importance_integrates_to_one() {
    for (lens, area) in [("", 1.0), (r#""float lensradius" 0.2 "float focaldistance" 5"#, 0.04 * std::f64::consts::PI)]
    {
        let rs = camera_scene(lens);
        let cam_o = rs.camera.generate_ray([40.0, 25.0], [0.5, 0.5]).o.0;
        let axis = rs.camera.generate_ray([40.0, 25.0], [0.5, 0.5]).d.0;
        let (a, b) = pbrt_sppm::math::frame::coordinate_system(axis);
        let mut rng = Rng::new(9);
        let n = 400_000;
        let (mut we_sum, mut pdf_sum) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let l = 0.2 * pbrt_sppm::sampling::concentric_disk(rng.uniform2());
            let o = if lens.is_empty() { cam_o } else { cam_o + a * l.x + b * l.y };
            let d = uniform_sphere(rng.uniform2());
            let ray = Ray::new(Point3(o), Vector3(d));
            let on_film = |r: [f32; 2]| (0.0..=80.0).contains(&r[0]) && (0.0..=50.0).contains(&r[1]);
            if let Some((we, _)) = rs.camera.we(&ray).filter(|(_, r)| on_film(*r)) {
                we_sum += (we * d.dot(axis)) as f64;
                pdf_sum += rs.camera.pdf_we(&ray).1 as f64;
            }
        }
        let sphere = 4.0 * std::f64::consts::PI / n as f64;
        let (we_integral, pdf_integral) = (we_sum * sphere * area, pdf_sum * sphere);
        assert!((we_integral - 1.0).abs() < 0.03, "lens {lens:?}: ∫∫ We cos = {we_integral}");
        assert!((pdf_integral - 1.0).abs() < 0.03, "lens {lens:?}: ∫ pdf_dir = {pdf_integral}");
    }
}

#[test]
fn camera_sample_wi_agrees_with_we() {
    let rs = camera_scene(r#""float lensradius" 0.2 "float focaldistance" 5"#);
    let mut rng = Rng::new(1);
    let mut found = 0;
    for _ in 0..500 {
        let p = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 2.0;
        let Some(s) = rs.camera.sample_wi(p, rng.uniform2(), 0.0) else { continue };
        let (we, raster) = rs.camera.we(&Ray::new(Point3(s.p_lens), Vector3(-s.wi))).expect("on the film");
        assert!(close(we, s.we, 1e-5) && raster == s.raster);
        assert!((s.p_lens + -s.wi * (s.p_lens - p).length() - p).length() < 1e-4);
        assert!(s.pdf > 0.0);
        found += 1;
    }
    assert!(found > 400, "points in front of the camera see its lens: {found}");
}

/// A sphere of each material, hit from the camera: its BSDF's two-way evaluation.
fn bsdfs() -> Vec<pbrt_sppm::materials::Bsdf> {
    let materials = [
        r#""diffuse" "rgb reflectance" [.5 .5 .5]"#,
        r#""conductor" "float roughness" 0.3"#,
        r#""dielectric" "float roughness" 0.3 "float eta" 1.5"#,
        r#""coateddiffuse" "float roughness" 0.2"#,
        r#""diffusetransmission""#,
    ];
    let mut out = Vec::new();
    for m in materials {
        let text = format!(
            "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\nMaterial {m}\nShape \"sphere\""
        );
        let rs = RenderScene::new(&scene(&text));
        let ray = Ray::new(Point3(Vec3::new(0.2, 0.3, -5.0)), Vector3(Vec3::Z));
        let hit = rs.intersect(&ray).expect("the sphere");
        let si = rs.geometry.interaction(&hit);
        out.push(rs.bsdf(&hit, &si, &Footprint::default()).expect("a surface"));
    }
    out
}

#[test]
fn bsdf_eval_matches_sampling_both_ways() {
    let mut rng = Rng::new(21);
    for (k, bsdf) in bsdfs().iter().enumerate() {
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            for _ in 0..300 {
                let wo = uniform_sphere(rng.uniform2());
                let Some(s) = bsdf.sample_f(wo, rng.uniform2(), rng.uniform(), mode) else { continue };
                if s.specular || s.proportional {
                    continue;
                }
                let e = bsdf.eval(wo, s.wi, mode);
                assert!(close(e.pdf, s.pdf, 1e-3), "bsdf {k} {mode:?}: pdf {} vs sampled {}", e.pdf, s.pdf);
                let back = bsdf.eval(s.wi, wo, mode.adjoint());
                assert_eq!(e.pdf_rev, back.pdf, "bsdf {k}: the reverse density is the other walk's");
            }
        }
    }
}

/// f carried as importance is the adjoint of f carried as radiance: f*(ωo, ωi) = f(ωi, ωo)
/// (what refraction's η² scaling must respect).
#[test]
fn bsdf_importance_is_the_adjoint_of_radiance() {
    let mut rng = Rng::new(4);
    // The coated material (3) estimates f by random walks: adjoint only on average.
    for (k, bsdf) in bsdfs().iter().enumerate().filter(|(k, _)| *k != 3) {
        let mut compared = 0;
        for _ in 0..2000 {
            let (wo, wi) = (uniform_sphere(rng.uniform2()), uniform_sphere(rng.uniform2()));
            let importance = bsdf.eval(wo, wi, TransportMode::Importance).f;
            let radiance = bsdf.eval(wi, wo, TransportMode::Radiance).f;
            if radiance.max_element() > 1e-4 {
                let rel = (importance - radiance).abs().max_element() / radiance.max_element();
                assert!(rel < 1e-3, "bsdf {k}: f*({wo}, {wi}) = {importance} but f({wi}, {wo}) = {radiance}");
                compared += 1;
            }
        }
        assert!(compared > 200, "bsdf {k}: {compared} pairs compared");
    }
}
