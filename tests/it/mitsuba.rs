//! `pbrt-sppm export --mitsuba` and `tools/mitsuba_reference.py`: the exported scene
//! matches the loaded one (shapes, front faces, camera, what is reported), and a small
//! diffuse scene renders the same in Mitsuba 3 as in pbrt-sppm.

use crate::common::{root, scene};
use glam::{DMat4, DVec3, Vec3};
use pbrt_sppm::cli::export::{Export, GeometryOut, LightOut, MaterialOut, mitsuba};
use pbrt_sppm::cli::trace::Tracer;
use pbrt_sppm::math::{Point3, Ray, Vector3};
use std::path::{Path, PathBuf};
use std::process::Command;

const CHECK_SCENE: &str = "pbrt-scenes/v3/mitsuba-check.pbrt";

/// The export and our tracer, with pbrt's bugs fixed: Mitsuba is compared with the
/// physically right scene (a hyperboloid, for one, is exported as the surface it sweeps).
fn export_of(text: &str) -> (Export, Tracer) {
    let fixed = || {
        let mut s = scene(text);
        s.fixes = pbrt_sppm::fixes::Fixes::all();
        s
    };
    (mitsuba(&fixed(), "inline"), Tracer::new(&fixed()))
}

fn matrix(row_major: &[f64; 16]) -> DMat4 {
    DMat4::from_cols_array(row_major).transpose()
}

#[test]
fn the_check_scene_exports_native_shapes_materials_and_the_light() {
    let s = crate::common::load_file(&root().join(CHECK_SCENE)).unwrap();
    let e = mitsuba(&s, CHECK_SCENE);
    assert!(e.unsupported.is_empty(), "{:?}", e.unsupported);
    let kinds: Vec<&str> = e
        .shapes
        .iter()
        .map(|s| match s.geometry {
            GeometryOut::Sphere { .. } => "sphere",
            GeometryOut::Cylinder { .. } => "cylinder",
            GeometryOut::Disk { .. } => "disk",
            GeometryOut::Mesh { .. } => "mesh",
        })
        .collect();
    assert_eq!(kinds, ["mesh", "mesh", "sphere", "cylinder", "disk"]);
    let GeometryOut::Sphere { center, radius, flip_normals } = &e.shapes[2].geometry else { unreachable!() };
    assert_eq!((*center, *flip_normals), ([-1.3, 0.7, 0.0], false));
    assert!((radius - 0.7).abs() < 1e-6);
    // Mitsuba's canonical cylinder runs from (0,0,0) to (0,0,1) with radius 1; ours is
    // rotated upright at (1.4, 0, 0.6) with radius 0.5 and height 1.3.
    let GeometryOut::Cylinder { to_world, .. } = &e.shapes[3].geometry else { unreachable!() };
    let m = matrix(to_world);
    assert!(m.transform_point3(DVec3::ZERO).abs_diff_eq(DVec3::new(1.4, 0.0, 0.6), 1e-6));
    assert!(m.transform_point3(DVec3::Z).abs_diff_eq(DVec3::new(1.4, 1.3, 0.6), 1e-6));
    assert!((m.transform_vector3(DVec3::X).length() - 0.5).abs() < 1e-6);
    let GeometryOut::Disk { to_world, .. } = &e.shapes[4].geometry else { unreachable!() };
    let m = matrix(to_world);
    assert!(m.transform_point3(DVec3::X).abs_diff_eq(DVec3::new(1.3, 1.3, 2.5), 1e-6));
    let light = e.shapes[0].emission.as_ref().expect("the quad emits");
    assert_eq!((light.radiance, light.two_sided), ([6.0; 3], false));
    assert!(e.shapes[1..].iter().all(|s| s.emission.is_none()));
    assert!(
        matches!(e.materials[e.shapes[2].material as usize], MaterialOut::Diffuse { reflectance } if reflectance == [0.7, 0.2, 0.15])
    );
    assert_eq!((e.max_depth, e.film.width, e.film.height, e.film.crop), (5, 64, 48, [0, 64, 0, 48]));
    assert!(e.lights.is_empty());
}

#[test]
fn check_rays_are_the_cameras_rays_through_the_crop_window() {
    let text = "LookAt 1 2 3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
                Film \"image\" \"integer xresolution\" 40 \"integer yresolution\" 20 \"float cropwindow\" [0.5 1 0 0.5]\n\
                WorldBegin\nShape \"sphere\"\n";
    let s = scene(text);
    let cam = pbrt_sppm::camera::Camera::new(&s.camera, &s.film);
    let e = mitsuba(&s, "inline");
    assert_eq!(e.film.crop, [20, 40, 0, 10]);
    let first = &e.camera.check_rays[0];
    assert_eq!(first.film_uv, [0.5, 0.5]);
    // The crop window's centre is raster (30, 5) of the full 40×20 film.
    let r = cam.generate_ray([30.0, 5.0], [0.5, 0.5]);
    assert_eq!((first.o, first.d), (r.o.0.to_array(), r.d.0.to_array()));
    let wfc = matrix(&e.camera.world_from_camera);
    assert!(wfc.transform_point3(DVec3::ZERO).abs_diff_eq(DVec3::new(1.0, 2.0, 3.0), 1e-9));
}

/// World-space front normals and points to test, per exported shape, as Mitsuba sees
/// them: (shape index, point on the surface, front normal, a length scale). Instances
/// map their object's faces with the inverse transpose, as both renderers do.
fn front_faces(e: &Export) -> Vec<(u32, Vec3, Vec3, f32)> {
    let mut out = local_faces(&e.shapes);
    for inst in &e.instances {
        let m = matrix(&inst.to_world);
        let nm = glam::DMat3::from_mat4(m).inverse().transpose();
        let scale = glam::DMat3::from_mat4(m).determinant().abs().cbrt() as f32;
        out.extend(local_faces(&e.objects[inst.object as usize].shapes).into_iter().map(|(i, p, n, size)| {
            let n = (nm * n.as_dvec3()).normalize().as_vec3();
            (inst.first_shape_index + i, m.transform_point3(p.as_dvec3()).as_vec3(), n, size * scale)
        }));
    }
    out
}

fn local_faces(shapes: &[pbrt_sppm::cli::export::ShapeOut]) -> Vec<(u32, Vec3, Vec3, f32)> {
    let mut out = Vec::new();
    for s in shapes {
        let i = s.shape_index;
        let flip = |n: DVec3, f: bool| if f { -n } else { n };
        match &s.geometry {
            GeometryOut::Sphere { center, radius, flip_normals } => {
                for d in [DVec3::X, DVec3::NEG_Y, DVec3::new(0.3, 0.5, -0.8).normalize()] {
                    let p = DVec3::from(*center) + *radius * d;
                    out.push((i, p.as_vec3(), flip(d, *flip_normals).as_vec3(), *radius as f32));
                }
            }
            GeometryOut::Cylinder { to_world, flip_normals } | GeometryOut::Disk { to_world, flip_normals } => {
                let m = matrix(to_world);
                let nm = glam::DMat3::from_mat4(m).inverse().transpose();
                let disk = matches!(s.geometry, GeometryOut::Disk { .. });
                for phi in [0.3f64, 2.0, 4.5] {
                    let radial = DVec3::new(phi.cos(), phi.sin(), 0.0);
                    let (p, n) = if disk { (0.6 * radial, DVec3::Z) } else { (radial + 0.4 * DVec3::Z, radial) };
                    let n = flip((nm * n).normalize(), *flip_normals);
                    let size = m.transform_vector3(DVec3::X).length() as f32;
                    out.push((i, m.transform_point3(p).as_vec3(), n.as_vec3(), size));
                }
            }
            GeometryOut::Mesh { positions, indices, .. } => {
                let v = |k: u32| Vec3::from_slice(&positions[3 * k as usize..3 * k as usize + 3]);
                let step = (indices.len() / 3 / 60).max(1);
                for t in indices.chunks_exact(3).step_by(step) {
                    let [a, b, c] = [v(t[0]), v(t[1]), v(t[2])];
                    let f = (b - a).cross(c - a);
                    let edge = (b - a).length().max((c - a).length()).max((c - b).length());
                    out.push((i, (a + b + c) / 3.0, f.normalize(), edge));
                }
            }
        }
    }
    out
}

/// From a little in front of each exported front face, looking back at it, our hit
/// must be on that shape with its normal on the same side.
fn assert_front_faces_agree(text: &str) {
    let (e, tracer) = export_of(text);
    let (mut agree, mut inconclusive) = (0, 0);
    for (index, p, n, size) in front_faces(&e) {
        let eps = 0.25 * size;
        let ray = Ray { o: Point3(p + eps * n), d: Vector3(-n), t_max: 2.0 * eps, time: 0.0 };
        let hit = tracer.trace(&ray);
        if hit["hit"] != true || hit["shape_index"] != index {
            inconclusive += 1;
            continue;
        }
        let ours: Vec<f32> = hit["n"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
        let dot = Vec3::from_slice(&ours).dot(n);
        assert!(dot > 0.0, "shape {index} at {p}: exported front {n}, our normal {ours:?}\n{text}");
        agree += 1;
    }
    assert!(agree > 10 * inconclusive.max(1), "{agree} checked, {inconclusive} inconclusive\n{text}");
}

const SHAPES: [&str; 11] = [
    "Shape \"sphere\" \"float radius\" 1",
    "Shape \"sphere\" \"float radius\" 1 \"float zmin\" -0.5 \"float zmax\" 0.8 \"float phimax\" 270",
    "Shape \"cylinder\" \"float radius\" 0.8 \"float zmin\" -0.5 \"float zmax\" 0.5",
    "Shape \"cylinder\" \"float radius\" 0.8 \"float zmin\" -0.5 \"float zmax\" 0.5 \"float phimax\" 200",
    "Shape \"disk\" \"float radius\" 1 \"float height\" 0.2",
    "Shape \"disk\" \"float radius\" 1 \"float innerradius\" 0.3 \"float phimax\" 300",
    "Shape \"cone\" \"float radius\" 1 \"float height\" 1.2 \"float phimax\" 330",
    "Shape \"paraboloid\" \"float radius\" 1 \"float zmin\" 0.1 \"float zmax\" 1",
    "Shape \"hyperboloid\" \"point3 p1\" [0.5 -0.5 -0.5] \"point3 p2\" [-0.3 0.6 0.6]",
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-1 -1 0 1 -1 0 1 1 0.3 -1 1 0]",
    // N opposite to the winding: the front is N's side.
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-1 -1 0 1 -1 0 1 1 0.3 -1 1 0] \
     \"normal N\" [0 0.1 -1 0 0 -1 0.1 0 -1 0 0 -1]",
];

const PLACEMENTS: [&str; 5] = [
    "",
    "ReverseOrientation",
    "Scale -1 1 1",
    "Rotate 30 1 1 0 Scale 1 0.5 2",
    "Scale 1 -1 1 ReverseOrientation Rotate 70 0 1 0",
];

#[test]
fn exported_front_faces_are_our_normals_sides() {
    for placement in PLACEMENTS {
        let world: String = SHAPES
            .iter()
            .enumerate()
            .map(|(i, s)| format!("AttributeBegin\nTranslate {} 0 0\n{placement}\n{s}\nAttributeEnd\n", 5 * i))
            .collect();
        assert_front_faces_agree(&format!("WorldBegin\n{world}"));
    }
}

#[test]
fn instanced_shapes_keep_their_front_faces_under_mirrors() {
    let object: String = SHAPES.iter().map(|s| format!("Translate 5 0 0 {s}\n")).collect();
    for instance in ["", "Scale -1 1 1", "Rotate 40 0 0 1 Scale 1 1 -2"] {
        let text = format!(
            "WorldBegin\nObjectBegin \"o\"\nReverseOrientation\n{object}ObjectEnd\n\
             AttributeBegin\n{instance}\nObjectInstance \"o\"\nAttributeEnd\n\
             AttributeBegin\nTranslate 0 0 -30\n{instance}\nObjectInstance \"o\"\nAttributeEnd\n"
        );
        assert_front_faces_agree(&text);
        // The object goes out once, however many instances place it.
        let e = mitsuba(&scene(&text), "inline");
        assert_eq!((e.shapes.len(), e.objects.len(), e.instances.len()), (0, 1, 2));
        assert_eq!(e.objects[0].shapes.len(), SHAPES.len());
        assert_eq!(e.instances[1].first_shape_index, SHAPES.len() as u32);
    }
}

#[test]
fn a_white_balanced_film_is_reported_as_not_exported() {
    let (e, _) = export_of("Film \"rgb\" \"float whitebalance\" 4000\nWorldBegin\nShape \"sphere\"\n");
    assert!(e.unsupported.iter().any(|u| u.what == "Film \"whitebalance\""), "{:?}", e.unsupported);
}

#[test]
fn what_mitsuba_cannot_render_alike_is_reported() {
    let (e, _) = export_of(
        "WorldBegin\n\
         LightSource \"spot\" \"float coneangle\" 30 \"float conedeltaangle\" 10\n\
         LightSource \"distant\" \"point from\" [0 1 0] \"point to\" [0 0 0] \"rgb L\" [2 2 2]\n\
         LightSource \"infinite\" \"rgb L\" [0.1 0.2 0.3]\n\
         Texture \"c\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [1 1 1] \"rgb tex2\" [0 0 0]\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"bool twosided\" true\nShape \"sphere\"\nAttributeEnd\n\
         Material \"matte\" \"texture Kd\" \"c\"\nShape \"disk\"\n\
         Material \"plastic\"\nShape \"cylinder\"\n\
         Shape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n",
    );
    let why: Vec<String> = e.unsupported.iter().map(|u| format!("{}: {}: {}", u.location, u.what, u.why)).collect();
    let has = |s: &str| why.iter().any(|w| w.contains(s));
    assert!(has("spot light falloff"), "{why:?}");
    assert!(has("two-sided area light"), "{why:?}");
    assert!(has("mean over (u, v)"), "{why:?}");
    assert!(has("\"plastic\""), "{why:?}");
    assert!(has("(curve): exported as round tubes"), "curves are exported as tubes, and say so: {why:?}");
    // The checkerboard's mean is grey; the distant light travels from `from` to `to`.
    let diffuse = e.materials.iter().find_map(|m| match m {
        MaterialOut::Diffuse { reflectance } if reflectance[0] > 0.4 && reflectance[0] < 0.6 => Some(reflectance),
        _ => None,
    });
    assert!(diffuse.is_some_and(|r| (r[0] - 0.5).abs() < 0.02));
    assert!(
        e.lights.iter().any(|l| matches!(l, LightOut::Distant { direction, .. } if *direction == [0.0, -1.0, 0.0]))
    );
    assert!(e.lights.iter().any(|l| matches!(l, LightOut::Constant { radiance } if *radiance == [0.1, 0.2, 0.3])));
    assert!(e.lights.iter().any(|l| matches!(l, LightOut::Spot { cutoff_angle, beam_width, .. }
        if (cutoff_angle - 30.0).abs() < 1e-4 && (beam_width - 20.0).abs() < 1e-4)));
}

#[test]
fn the_cli_writes_json_and_reports_errors_with_locations() {
    let bin = env!("CARGO_BIN_EXE_pbrt-sppm");
    let out = Command::new(bin).args(["export", "--mitsuba", CHECK_SCENE]).current_dir(root()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!((v["format"].as_str(), v["version"].as_u64()), (Some("pbrt-sppm-export"), Some(1)));
    assert_eq!(v["shapes"].as_array().map(Vec::len), Some(5));
    let dir = tempdir("cli");
    let bad = dir.join("bad.pbrt");
    std::fs::write(&bad, "WorldBegin\nShape \"sphere\" \"float radius\" [\n").unwrap();
    let out = Command::new(bin).args(["export", "--mitsuba"]).arg(&bad).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.pbrt:2:") && err.contains("error:"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The script checks its input before it needs Mitsuba, so any python3 runs this.
#[test]
fn the_script_rejects_what_is_not_an_export() {
    let dir = tempdir("script");
    let script = root().join("tools/mitsuba_reference.py");
    for (text, message) in [
        ("{\"format\": ", "1:12: not JSON"),
        ("{\"format\": \"other\", \"version\": 1}", "not a pbrt-sppm-export version 1 document"),
    ] {
        let json = dir.join("scene.json");
        std::fs::write(&json, text).unwrap();
        let Ok(out) = Command::new("python3").arg(&script).arg(&json).arg(dir.join("out.exr")).output() else {
            return crate::common::cannot_run("python", "the Mitsuba script's checks", "python3 is not installed");
        };
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.starts_with(&format!("{}: error: {message}", json.display())), "{err}");
    }
    assert!(!dir.join("out.exr").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

fn tempdir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("mitsuba-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(cmd: &mut Command) -> std::process::Output {
    cmd.output().unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"))
}

/// A virtual environment with `mitsuba`, made once under the target directory and
/// shared by the tests of this process; `None` (with a message) when it cannot be made
/// (see [`crate::common::python_venv`]).
fn mitsuba_python() -> Option<PathBuf> {
    static VENV: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    match VENV.get_or_init(|| crate::common::python_venv("mitsuba-venv", &["mitsuba"], "import mitsuba")) {
        Ok(python) => Some(python.clone()),
        Err(why) => {
            crate::common::cannot_run("mitsuba", "the Mitsuba cross-check", why);
            None
        }
    }
}

/// Stated bound: relMSE ≤ 1.5e-3 and every channel's mean within 1%. Measured on this
/// scene: relMSE 6.0e-4 against a 1024-spp Mitsuba render (SPPM noise and kernel blur;
/// Mitsuba's own 1024-spp noise is 5e-5), channel means within 0.15%. An 8% change of
/// the floor's reflectance alone gives relMSE 2.2e-3.
#[test]
fn mitsuba_and_sppm_agree_on_a_small_diffuse_scene() {
    let Some(python) = mitsuba_python() else { return };
    let dir = tempdir("render");
    let json = dir.join("scene.json");
    let bin = env!("CARGO_BIN_EXE_pbrt-sppm");
    let out = run(Command::new(bin)
        .args(["export", "--mitsuba", CHECK_SCENE, "--fix", "all", "-o"])
        .arg(&json)
        .current_dir(root()));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let theirs = dir.join("mitsuba.exr");
    let script = root().join("tools/mitsuba_reference.py");
    let out = run(Command::new(&python).arg(script).arg(&json).arg(&theirs).args(["--spp", "1024"]));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let ours = dir.join("sppm.exr");
    // Mitsuba is physically right, so pbrt's bugs are fixed for the comparison.
    let out = run(Command::new(bin).args([CHECK_SCENE, "--fix", "all", "--outfile"]).arg(&ours).current_dir(root()));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let read = |p: &Path| pbrt_sppm::imageio::read_image(p).unwrap();
    let (a, b) = (read(&ours), read(&theirs));
    assert_eq!((a.width, a.height), (b.width, b.height));
    let rel = pbrt_sppm::imageio::metrics::relmse(&a.pixels, &b.pixels);
    assert!(rel <= 1.5e-3, "relMSE {rel:e} against Mitsuba");
    for c in 0..3 {
        let mean = |img: &pbrt_sppm::imageio::RgbImage| img.pixels.iter().map(|p| p[c] as f64).sum::<f64>();
        let (ma, mb) = (mean(&a), mean(&b));
        assert!((ma / mb - 1.0).abs() < 0.01, "channel {c}: mean {ma} against Mitsuba's {mb}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A rotated equirectangular map seen directly: Mitsuba's `envmap` must look up the
/// same texels as our infinite light (its axes are a reflection of pbrt's). Measured:
/// relMSE 1.2e-4 (pixel filtering at the map's sharp edges); a mapping with the
/// reflection left out gives about 57.
#[test]
fn mitsuba_reads_environment_maps_as_we_do() {
    let Some(python) = mitsuba_python() else { return };
    let dir = tempdir("envmap");
    let mut map = pbrt_sppm::imageio::RgbImage::new(64, 32);
    for (i, p) in map.pixels.iter_mut().enumerate() {
        let (x, y) = (i % 64, i / 64);
        *p = [if x < 32 && (x / 16) % 2 == 0 { 0.9 } else { 0.05 }, if y < 16 { 0.8 } else { 0.1 }, x as f32 / 64.0];
    }
    pbrt_sppm::imageio::write_exr(&dir.join("sky.exr"), &map).unwrap();
    std::fs::write(
        dir.join("env.pbrt"),
        "LookAt 0 0 0  0.3 1 0.2  0 0 1\nCamera \"perspective\" \"float fov\" 100\n\
         Film \"image\" \"integer xresolution\" 48 \"integer yresolution\" 32\n\
         Integrator \"sppm\" \"integer numiterations\" 64 \"integer photonsperiteration\" 100\n\
         WorldBegin\nRotate 30 0.2 1 0.4\nLightSource \"infinite\" \"string mapname\" \"sky.exr\" \"color scale\" [2 2 2]\n",
    )
    .unwrap();
    let bin = env!("CARGO_BIN_EXE_pbrt-sppm");
    let out = run(Command::new(bin)
        .args(["export", "--mitsuba", "env.pbrt", "--fix", "all", "-o", "env.json"])
        .current_dir(&dir));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let script = root().join("tools/mitsuba_reference.py");
    let out =
        run(Command::new(&python).arg(script).args(["env.json", "mitsuba.exr", "--spp", "256"]).current_dir(&dir));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = run(Command::new(bin).args(["env.pbrt", "--fix", "all", "--outfile", "sppm.exr"]).current_dir(&dir));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let read = |n: &str| pbrt_sppm::imageio::read_image(&dir.join(n)).unwrap();
    let rel = pbrt_sppm::imageio::metrics::relmse(&read("sppm.exr").pixels, &read("mitsuba.exr").pixels);
    assert!(rel < 2e-3, "relMSE {rel:e} against Mitsuba");
    let _ = std::fs::remove_dir_all(&dir);
}
