//! Numerical stability on stiff and extreme cases (`docs/stability.md`): the
//! scenes of `pbrt-scenes/stress/`, emitters and film scales far from 1, and SPPM's own
//! state over many iterations. Every image checked here has no NaN or Inf pixel.

use crate::common::{load_file, root, scene};
use pbrt_sppm::imageio::metrics::relmse;
use pbrt_sppm::integrators::sppm::Sppm;
use pbrt_sppm::integrators::vcm::Techniques;
use pbrt_sppm::integrators::{Algorithm, RenderSettings};
use pbrt_sppm::render::RenderScene;

fn mean(px: &[[f32; 3]]) -> f64 {
    px.iter().flat_map(|p| p.iter()).map(|&c| c as f64).sum::<f64>() / (3 * px.len()) as f64
}

fn assert_finite(name: &str, px: &[[f32; 3]]) {
    let bad = px.iter().filter(|p| !p.iter().all(|c| c.is_finite())).count();
    assert_eq!(bad, 0, "{name}: {bad} pixels are NaN or Inf");
}

fn quick() -> RenderSettings {
    RenderSettings { iterations: Some(4), photons: Some(5000), ..RenderSettings::default() }
}

#[test]
fn every_stress_scene_renders_finite_and_lit() {
    let dir = root().join("pbrt-scenes/stress");
    let mut names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    names.retain(|p| p.extension().is_some_and(|e| e == "pbrt"));
    names.sort();
    assert!(names.len() >= 6, "stress scenes: {names:?}");
    // Each with SPPM, vcm and bdpt (the media scenes: dense fog and grids, albedo 1 at
    // maxdepth 100, coincident boundaries, a camera on a boundary).
    let bidirectional = [Algorithm::Vcm(Techniques::All), Algorithm::Vcm(Techniques::Bdpt)];
    for path in names {
        let s = load_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        for algorithm in [Algorithm::Sppm].into_iter().chain(bidirectional) {
            let settings = RenderSettings { algorithm: Some(algorithm), ..quick() };
            let out = pbrt_sppm::integrators::render(
                &RenderScene::for_integrator(&s, algorithm != Algorithm::Sppm),
                &settings,
            )
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let name = format!("{} ({})", path.file_name().unwrap().to_string_lossy(), algorithm.name());
            assert_finite(&name, &out.image.pixels);
            assert!(mean(&out.image.pixels) > 0.0, "{name}: black");
            assert!(out.stats.photons.hits > 0, "{name}: no photon hit anything");
        }
    }
}

/// A light of 1e30 under a film scale of 1e-30, and one of 3e38 (4π·I is past f32's
/// range) under 1e-38, give the image of a light of 1 (or 3) under a scale of 1.
#[test]
fn emitters_and_film_scales_far_from_one_cancel_exactly_enough() {
    let text = std::fs::read_to_string(root().join("pbrt-scenes/stress/extreme-values.pbrt")).unwrap();
    let render = |i: &str, scale: &str| {
        let t = text.replace("1e30 1e30 1e30", &format!("{i} {i} {i}")).replace("[ 1e-30 ]", &format!("[ {scale} ]"));
        pbrt_sppm::integrators::render(&RenderScene::new(&scene(&t)), &quick()).unwrap().image.pixels
    };
    for (i, scale, same_as) in [("1e30", "1e-30", "1"), ("3e38", "1e-38", "3"), ("1e-30", "1e30", "1")] {
        let unit = render(same_as, "1");
        assert!(mean(&unit) > 1e-3);
        let px = render(i, scale);
        assert_finite(i, &px);
        let e = relmse(&px, &unit);
        assert!(e < 1e-9, "light {i} under scale {scale}: relMSE {e:e} against light {same_as} under scale 1");
    }
    // Past f32 on the way out: an error naming the cause, never an Inf pixel.
    let t = text.replace("1e30 1e30 1e30", "3e38 3e38 3e38").replace("[ 1e-30 ]", "[ 1e10 ]");
    let Err(err) = pbrt_sppm::integrators::render(&RenderScene::new(&scene(&t)), &quick()) else { panic!("rendered") };
    assert!(matches!(err, pbrt_sppm::integrators::RenderError::NotFinite { .. }), "{err}");
    assert!(err.to_string().contains("beyond the range of 32-bit floats"), "{err}");
}

/// The camera at the centre of an emitting diffuse sphere (ρ = 0.5, Le = 0.5, maxdepth
/// 5): L = Le (1 + ρ + … + ρ^5). 10^4 iterations of 200 photons: the radius shrinks by
/// orders of magnitude but stays a normal positive number, the state stays finite, and
/// the mean at 10^3 and 10^4 iterations matches the analytic value within 1%.
#[test]
fn ten_thousand_iterations_keep_the_state_finite_and_the_energy() {
    let text = "Film \"rgb\" \"integer xresolution\" 6 \"integer yresolution\" 6 Camera \"perspective\" \"float fov\" 45 \
         Integrator \"sppm\" \"integer maxdepth\" 5 WorldBegin \
         AttributeBegin ReverseOrientation Material \"diffuse\" \"rgb reflectance\" [.5 .5 .5] \
         AreaLightSource \"diffuse\" \"rgb L\" [.5 .5 .5] Shape \"sphere\" AttributeEnd";
    let rs = RenderScene::new(&scene(text));
    let expected = 1.0 - 0.5f64.powi(6);
    let (radius, photons) = (0.2, 200);
    let mut sppm = Sppm::new(&rs, 10_000, photons, radius, 7, Default::default()).unwrap();
    let mut means = Vec::new();
    for k in 1..=10_000 {
        sppm.iterate();
        if k == 1000 || k == 10_000 {
            means.push(mean(&sppm.image()));
        }
    }
    for (m, at) in means.iter().zip([1000, 10_000]) {
        assert!((m - expected).abs() < 0.01 * expected, "mean {m} at {at} iterations, expected {expected}");
    }
    for p in &sppm.pixels {
        assert!(p.radius.is_normal() && p.radius > 0.0 && p.radius < radius as f64, "radius {}", p.radius);
        assert!((p.radius as f32).is_normal(), "the grid's f32 radius {}", p.radius);
        assert!(p.n.is_finite() && p.tau.is_finite() && p.ld.is_finite(), "{p:?}");
    }
    let smallest = sppm.pixels.iter().map(|p| p.radius).fold(f64::INFINITY, f64::min);
    eprintln!("10^4 iterations: smallest radius {smallest:e} (from {radius}), means {means:?}, expected {expected}");
    assert!(smallest < 0.5 * radius as f64, "the radius barely shrank: {smallest}");
}

/// A hyperboloid whose line meets the z axis is refused at its statement.
#[test]
fn a_hyperboloid_through_its_axis_is_a_located_error() {
    let text = "WorldBegin\nShape \"hyperboloid\" \"point p1\" [ 1e-6 0 0 ] \"point p2\" [ 0.5 0 1 ]\n";
    let Err(err) = crate::common::load(text) else { panic!("loaded") };
    let text = err.to_string();
    assert!(text.contains("inline.pbrt:2:") && text.contains("meets the z axis"), "{text}");
}

/// `pbrt-bench stress` at a CI size: every shape family at scales 1e-6…1e6, 0 to 1e7
/// from the origin, under plain, mirrored and sheared, and nearly singular transforms.
/// No spawned ray may hit its own surface again; and most shapes must be found where f32
/// can resolve them (else the count of 0 would prove nothing).
#[test]
fn spawned_rays_never_hit_their_own_surface_at_any_scale_or_distance() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pbrt-bench"))
        .args(["stress", "spawn", "--shapes", "40", "--rays", "60"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    let summary: Vec<&str> = text.lines().skip_while(|l| !l.contains("under 50% hit at")).skip(1).collect();
    assert_eq!(summary.len(), 8, "{text}");
    for line in summary {
        let cols: Vec<&str> = line.split_whitespace().collect();
        let (rays, failures): (u64, u64) = (cols[1].parse().unwrap(), cols[2].parse().unwrap());
        assert_eq!(failures, 0, "{line}");
        assert!(rays > 100_000, "{line}: too few rays were spawned to prove anything");
    }
}

/// The summary lines of a `pbrt-bench stress` part: those after the header line that
/// contains `header`.
fn stress_summary(args: &[&str], header: &str) -> Vec<Vec<String>> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pbrt-bench")).arg("stress").args(args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let lines: Vec<Vec<String>> = text
        .lines()
        .skip_while(|l| !l.contains(header))
        .skip(1)
        .map(|l| l.split_whitespace().map(String::from).collect())
        .collect();
    assert!(!lines.is_empty(), "no summary after {header:?}:\n{text}");
    lines
}

/// `pbrt-bench stress mesh` at a CI size: rays from inside closed meshes, a third of
/// them exactly at vertices and a third at edges, never escape, for world meshes and
/// instances at every resolvable scale and distance.
#[test]
fn rays_from_inside_closed_meshes_never_escape_at_any_scale_or_distance() {
    let rows = stress_summary(&["mesh", "--meshes", "4", "--rays", "300"], "escapes per 10^7");
    let (rays, escapes): (u64, u64) = (rows[0][0].parse().unwrap(), rows[0][1].parse().unwrap());
    assert_eq!(escapes, 0, "{:?}", rows[0]);
    assert!(rays > 100_000, "{:?}: too few rays to prove anything", rows[0]);
}

/// `pbrt-bench stress grazing` at a CI size: rays tangent to every quadric, through
/// rims, poles and apexes, under every transform. No hit may be invalid (a NaN or zero
/// normal at a pole or apex was) or off the surface; hits and misses agree with the f64
/// reference on all but at most 10^-4 of the rays it can judge.
#[test]
fn grazing_rays_on_every_quadric_agree_with_an_f64_reference() {
    let rows = stress_summary(&["grazing", "--shapes", "10", "--rays", "40"], "grazing failures per 10^7");
    assert_eq!(rows.len(), 6, "{rows:?}");
    for r in rows {
        let n: Vec<u64> = r[1..6].iter().map(|x| x.parse().unwrap()).collect();
        let (judged, invalid, off, wrong) = (n[1], n[2], n[3], n[4]);
        assert!(judged > 10_000, "{r:?}: too few judged rays");
        assert_eq!((invalid, off), (0, 0), "{r:?}");
        assert!(wrong * 10_000 <= judged, "{r:?}");
    }
}

/// Hits exactly on the axis (a sphere's pole, a cone's apex, a paraboloid's vertex, a
/// disk's centre) have a finite unit normal; all but the apex along the axis.
#[test]
fn hits_on_the_axis_have_a_unit_normal() {
    use glam::{DMat4, Vec3};
    use pbrt_sppm::math::{Point3, Ray, Vector3};
    use pbrt_sppm::shapes::{Cone, Disk, Paraboloid, Quadric, QuadricShape, sphere::Sphere};
    let cases = [
        (Quadric::Sphere(Sphere::new(1.0, -1.0, 1.0, 360.0)), 1.0, true),
        (Quadric::Cone(Cone::new(1.0, 1.0, 360.0)), 1.0, false),
        (Quadric::Paraboloid(Paraboloid::new(1.0, 0.0, 1.0, 360.0)), 0.0, true),
        (Quadric::Disk(Disk::new(0.5, 1.0, 0.0, 360.0)), 0.5, true),
    ];
    for (q, z, along_axis) in cases {
        let s = QuadricShape::new(q.clone(), DMat4::IDENTITY, false);
        let down = Ray::new(Point3(Vec3::new(0.0, 0.0, 3.0)), Vector3(Vec3::new(0.0, 0.0, -1.0)));
        let up = Ray::new(Point3(Vec3::new(0.0, 0.0, -3.0)), Vector3(Vec3::new(0.0, 0.0, 1.0)));
        for ray in [down, up] {
            let Some(hit) = s.intersect_t(&ray, f32::INFINITY) else { continue };
            if (hit.p_obj.z - z).abs() > 1e-9 {
                continue;
            }
            let si = s.interaction(&hit);
            let n = si.n.0;
            assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-5, "{q:?}: {n:?}");
            assert!(si.dpdu.0.is_finite() && si.dpdv.0.is_finite(), "{q:?}: {:?} {:?}", si.dpdu, si.dpdv);
            if along_axis {
                assert!(n.z.abs() > 0.999, "{q:?}: {n:?}");
            }
        }
    }
}

/// Rays from inside a cone leaving through its apex (within f32's rounding of it) cross
/// the surface there: the two nappes' roots nearly meet, and the discriminant's
/// cancellation must not turn the crossing into a miss.
#[test]
fn rays_leaving_a_cone_through_its_apex_hit_it() {
    use glam::{DMat4, DVec3};
    use pbrt_sppm::math::{Point3, Ray, Vector3};
    use pbrt_sppm::sampling::Rng;
    use pbrt_sppm::shapes::{Cone, Quadric, QuadricShape};
    let s = QuadricShape::new(Quadric::Cone(Cone::new(1.0, 1.0, 360.0)), DMat4::IDENTITY, false);
    let mut rng = Rng::new(44);
    let mut misses = 0;
    for _ in 0..20_000 {
        // Within 30° of the axis: inside the 45° cone, so the ray is inside it below
        // the apex and outside above.
        let (theta, phi) =
            (std::f64::consts::FRAC_PI_6 * rng.uniform() as f64, std::f64::consts::TAU * rng.uniform() as f64);
        let d = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        let o = DVec3::Z - (0.5 + rng.uniform() as f64) * d;
        let ray = Ray::new(Point3(o.as_vec3()), Vector3(d.as_vec3()));
        misses += s.intersect_t(&ray, f32::INFINITY).is_none() as u32;
    }
    assert_eq!(misses, 0);
}

/// `pbrt-bench --help` and each command's `--help` describe it and start no work (a
/// closed pipe: `hostile::a_full_or_closed_standard_output_is_an_error_not_a_panic`).
#[test]
fn pbrt_bench_explains_itself() {
    let bench = env!("CARGO_BIN_EXE_pbrt-bench");
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-help");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let asks = [&["--help"][..], &["help"], &["sppm", "--help"], &["parse", "--help"], &["rays", "-h"]];
    for args in asks.into_iter().chain([&["converge", "--help"][..], &["stress", "--help"]]) {
        let out = std::process::Command::new(bench).args(args).current_dir(&dir).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success() && text.contains("Usage: pbrt-bench"), "{args:?}: {text}");
        assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "{args:?} wrote files");
    }
}
