//! Camera orientation against pbrt's conventions, and image files: EXR round trip with
//! crop window and metadata, half-float input, PNG previews, atomic writes.

use crate::common::scene;
use pbrt_sppm::camera::Camera;
use pbrt_sppm::cli::trace::Tracer;
use pbrt_sppm::imageio::{ImageMeta, RgbImage, read_image, write_image};

/// Raster pixels (x, y) whose centre ray hits something, for a scene text.
fn hit_pixels(text: &str, res: usize) -> Vec<(usize, usize)> {
    let s = scene(text);
    let camera = Camera::new(&s.camera, &s.film);
    let tracer = Tracer::new(&s);
    let mut hits = Vec::new();
    for y in 0..res {
        for x in 0..res {
            let ray = camera.generate_ray([x as f32 + 0.5, y as f32 + 0.5], [0.5, 0.5]);
            if tracer.geometry.intersect(&ray).is_some() {
                hits.push((x, y));
            }
        }
    }
    hits
}

fn centroid(p: &[(usize, usize)]) -> (f64, f64) {
    let n = p.len() as f64;
    (p.iter().map(|q| q.0 as f64).sum::<f64>() / n, p.iter().map(|q| q.1 as f64).sum::<f64>() / n)
}

const FILM: &str = "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 64";

#[test]
fn lookat_puts_world_x_on_the_left_like_pbrt() {
    let view = "LookAt 0 0 5  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 60";
    let right =
        hit_pixels(&format!("{FILM} {view} WorldBegin Translate 1.5 0 0 Shape \"sphere\" \"float radius\" 0.5"), 64);
    let (cx, cy) = centroid(&right);
    assert!(cx < 32.0 - 8.0 && (cy - 32.0).abs() < 1.0, "world +x lands at ({cx}, {cy}): expected the left half");
    let up =
        hit_pixels(&format!("{FILM} {view} WorldBegin Translate 0 1.5 0 Shape \"sphere\" \"float radius\" 0.5"), 64);
    let (ux, uy) = centroid(&up);
    assert!(uy < 32.0 - 8.0 && (ux - 32.0).abs() < 1.0, "world +y lands at ({ux}, {uy}): expected the top");
    // The exporters' fix: Scale -1 1 1 before LookAt mirrors the image.
    let mirrored = hit_pixels(
        &format!("{FILM} Scale -1 1 1 {view} WorldBegin Translate 1.5 0 0 Shape \"sphere\" \"float radius\" 0.5"),
        64,
    );
    let (mx, _) = centroid(&mirrored);
    // Pixel x mirrors to 63 − x.
    assert!((mx - (63.0 - cx)).abs() < 0.5, "mirrored camera: {mx} vs {}", 63.0 - cx);
}

#[test]
fn fov_spans_the_shorter_axis_and_orthographic_uses_the_screen_window() {
    // A sphere of angular radius exactly fov/2 fills the shorter (vertical) axis.
    let text = "Film \"rgb\" \"integer xresolution\" 128 \"integer yresolution\" 64 Camera \"perspective\" \"float fov\" 60 \
                WorldBegin Translate 0 0 10 Shape \"sphere\" \"float radius\" 5";
    let hits = hit_pixels(text, 0);
    assert!(hits.is_empty());
    let s = scene(text);
    let camera = Camera::new(&s.camera, &s.film);
    let g = Tracer::new(&s);
    let through = |x: f32, y: f32| g.geometry.intersect(&camera.generate_ray([x, y], [0.5, 0.5])).is_some();
    assert!(through(64.0, 1.0) && through(64.0, 63.0), "top and bottom rows see the sphere");
    assert!(!through(64.0, -0.5) || !through(0.5, 32.0), "beyond the window it does not");
    let ortho = scene(
        "Film \"rgb\" \"integer xresolution\" 10 \"integer yresolution\" 10 Camera \"orthographic\" \"float screenwindow\" [-2 2 -2 2] WorldBegin",
    );
    let cam = Camera::new(&ortho.camera, &ortho.film);
    let r = cam.generate_ray([0.0, 0.0], [0.5, 0.5]);
    assert_eq!((r.o.0.x, r.o.0.y, r.d.0.z), (-2.0, 2.0, 1.0), "top-left corner of the window");
}

/// A still pinhole's rays, set up once in world space, against pbrt's construction
/// worked out here apart: LookAt's frame (right = up × dir, up' = dir × right) applied
/// to the camera-space direction (sx·tan(fov/2), sy·tan(fov/2), 1) of the raster
/// point's screen position, in a screen window that is not centred.
#[test]
fn pinhole_rays_follow_the_lookat_frame_and_the_screen_window() {
    let s = scene(
        "Film \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 30 \
         LookAt 1 2 3  4 2.5 -1  0 1 0 \
         Camera \"perspective\" \"float fov\" 50 \"float screenwindow\" [-1 0.5 -0.75 0.75] WorldBegin",
    );
    let cam = Camera::new(&s.camera, &s.film);
    let (eye, look, up) = ([1.0f64, 2.0, 3.0], [4.0, 2.5, -1.0], [0.0, 1.0, 0.0]);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross =
        |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    let unit = |a: [f64; 3]| {
        let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        [a[0] / l, a[1] / l, a[2] / l]
    };
    let dir = unit(sub(look, eye));
    let right = unit(cross(up, dir));
    let new_up = cross(dir, right);
    let t = (25f64).to_radians().tan();
    for (x, y) in [(0.0, 0.0), (40.0, 30.0), (13.25, 7.5), (39.5, 0.5), (20.0, 15.0)] {
        let (sx, sy) = (-1.0 + x / 40.0 * 1.5, 0.75 - y / 30.0 * 1.5);
        let c = [sx * t, sy * t, 1.0];
        let want = unit([0, 1, 2].map(|i| right[i] * c[0] + new_up[i] * c[1] + dir[i] * c[2]));
        let r = cam.generate_ray([x as f32, y as f32], [0.5, 0.5]);
        let got = [r.d.0.x as f64, r.d.0.y as f64, r.d.0.z as f64];
        let o = [r.o.0.x as f64, r.o.0.y as f64, r.o.0.z as f64];
        for i in 0..3 {
            assert!((got[i] - want[i]).abs() < 1e-6, "({x}, {y}): direction {got:?} against {want:?}");
            assert!((o[i] - eye[i]).abs() < 1e-6, "({x}, {y}): origin {o:?}");
        }
    }
}

#[test]
fn thin_lens_rays_meet_at_the_focal_distance() {
    let s = scene(
        "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32 Camera \"perspective\" \"float fov\" 40 \"float lensradius\" 0.2 \"float focaldistance\" 3 WorldBegin",
    );
    let cam = Camera::new(&s.camera, &s.film);
    let a = cam.generate_ray([10.5, 20.5], [0.1, 0.9]);
    let b = cam.generate_ray([10.5, 20.5], [0.8, 0.3]);
    assert!(a.o.0 != b.o.0, "different lens points");
    let pa = a.at((3.0 - a.o.0.z) / a.d.0.z).0;
    let pb = b.at((3.0 - b.o.0.z) / b.d.0.z).0;
    assert!((pa - pb).length() < 1e-4, "{pa} vs {pb}");
}

fn dir(name: &str) -> crate::common::Scratch {
    crate::common::Scratch::new(&format!("img-{name}"))
}

#[test]
fn exr_round_trip_keeps_crop_window_and_metadata() {
    let mut img = RgbImage::new(5, 3);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        *p = [i as f32 * 0.25, -1.5, 1e6 + i as f32];
    }
    img.origin = (7, 2);
    img.full = (20, 10);
    img.meta = ImageMeta {
        render_time_seconds: Some(1.25),
        samples_per_pixel: Some(16),
        photons_per_iteration: Some(4096),
        world_to_camera: Some(std::array::from_fn(|i| i as f32)),
        software: Some("pbrt-sppm test".into()),
    };
    let d = dir("round");
    let path = d.join("round.exr");
    write_image(&path, &img).unwrap();
    assert_eq!(read_image(&path).unwrap(), img);
    let leftovers: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp."))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

#[test]
fn half_float_exrs_are_read() {
    use exr::prelude::*;
    let d = dir("half");
    let path = d.join("half.exr");
    let layer = Layer::new(
        (2, 1),
        LayerAttributes::named(""),
        Encoding::SMALL_LOSSLESS,
        SpecificChannels::rgb(|Vec2(x, _): Vec2<usize>| {
            (f16::from_f32(x as f32 + 0.5), f16::from_f32(2.0), f16::from_f32(-0.25))
        }),
    );
    Image::from_layer(layer).write().to_file(&path).unwrap();
    let img = read_image(&path).unwrap();
    assert_eq!(img.pixels, vec![[0.5, 2.0, -0.25], [1.5, 2.0, -0.25]]);
}

#[test]
fn png_previews_are_srgb_encoded() {
    let mut img = RgbImage::new(3, 1);
    img.pixels = vec![[0.0, 0.5, 1.0], [0.2140, 0.0031308, 2.0], [-1.0, 0.0, 0.0]];
    let d = dir("preview");
    let path = d.join("preview.png");
    write_image(&path, &img).unwrap();
    let back = read_image(&path).unwrap();
    // 0.5 linear is 188/255 in sRGB; 0.214 linear is 0.4999 (127/255); values clamp.
    let bytes = image::open(&path).unwrap().to_rgb8();
    assert_eq!(bytes.get_pixel(0, 0).0, [0, 188, 255]);
    assert_eq!(bytes.get_pixel(1, 0).0[0], 127);
    assert_eq!(bytes.get_pixel(2, 0).0, [0, 0, 0]);
    assert!((back.pixels[0][1] - 0.5).abs() < 0.01);
}

#[test]
fn a_failed_write_leaves_no_file() {
    let img = RgbImage::new(2, 2);
    let d = dir("failed-write");
    let path = d.join("no-such-folder").join("x.exr");
    assert!(write_image(&path, &img).is_err());
    assert!(!path.exists());
}

/// A grey card under a white distant light, filmed with `film` (v4).
fn grey_card(film: &str) -> [f64; 3] {
    use pbrt_sppm::integrators::RenderSettings;
    use pbrt_sppm::render::RenderScene;
    let text = format!(
        "LookAt 0 0 5  0 0 0  0 1 0 Camera \"orthographic\"\n\
         Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8 {film}\n\
         Sampler \"halton\" \"integer pixelsamples\" 64\n\
         Integrator \"sppm\" \"integer maxdepth\" 1 \"integer photonsperiteration\" 10\n\
         WorldBegin LightSource \"distant\" \"point3 from\" [0 0 5] \"point3 to\" [0 0 0] \"rgb L\" [1 1 1]\n\
         Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n\
         Shape \"bilinearmesh\" \"point3 P\" [-9 -9 0  9 -9 0  -9 9 0  9 9 0]"
    );
    let image = pbrt_sppm::integrators::render(&RenderScene::new(&scene(&text)), &RenderSettings::default()).unwrap();
    let n = image.image.pixels.len() as f64;
    let sum =
        image.image.pixels.iter().fold([0.0; 3], |s, p| [s[0] + p[0] as f64, s[1] + p[1] as f64, s[2] + p[2] as f64]);
    sum.map(|c| c / n)
}

#[test]
fn whitebalance_adapts_the_lights_white_as_pbrt_v4s_film_does() {
    use pbrt_sppm::spectrum::colorspace::{ColorSpaceName, mul_vec};
    use pbrt_sppm::spectrum::sensor::white_balance_rgb;
    // Unbalanced, the card is grey (to the 0.25% its 64 passes' shared wavelengths
    // leave, `spectrum::transport`); balanced for 3000 K light it turns blue by the
    // Bradford adaptation from 3000 K to D65 (pbrt-v4: `whitebalance`, sensor cie1931).
    let plain = grey_card("");
    assert!((plain[0] - plain[2]).abs() < 4e-3 * plain[1], "{plain:?}");
    let balanced = grey_card("\"float whitebalance\" 3000");
    let want = mul_vec(&white_balance_rgb(3000.0, ColorSpaceName::Srgb), plain);
    assert!((0..3).all(|k| (balanced[k] - want[k]).abs() < 1e-5 * want[1]), "{balanced:?} vs {want:?}");
    assert!(balanced[2] > 3.0 * balanced[0], "{balanced:?}");
    // A named camera films the wavelengths through its curves and its fitted matrix,
    // which holds its balance (6500 K unless told; `spectrum::sensor` tests it against
    // pbrt-v4). Rendered in RGB it cannot: there it is the CIE observer, balanced the
    // same, and noted.
    let camera = "Film \"rgb\" \"string sensor\" \"nikon_d850\" WorldBegin";
    let s = scene(camera);
    assert!(s.film.sensor.is_some() && s.film.white_balance.is_none());
    assert!(s.approximated.is_empty(), "{:?}", s.approximated);
    let r = crate::common::report(camera);
    assert_eq!(
        (&r["film"]["sensor"], &r["film"]["filter"]),
        (&serde_json::json!("nikon_d850"), &serde_json::json!("gaussian"))
    );
    let summary = pbrt_sppm::cli::check::summary(&s);
    assert!(summary.contains("sensor nikon_d850, filter gaussian"), "{summary}");
    let rgb = pbrt_sppm::scene::LoadOptions {
        colour: Some(pbrt_sppm::spectrum::transport::Colour::Rgb),
        ..Default::default()
    };
    let path = std::path::Path::new("tests/data/good/inline.pbrt");
    let s = pbrt_sppm::scene::load_scene_from_bytes(path, camera.as_bytes().to_vec(), &rgb).unwrap();
    assert!(s.film.sensor.is_none() && s.film.white_balance.is_some());
    assert!(s.approximated.iter().any(|a| a.what == "sensor \"nikon_d850\""), "{:?}", s.approximated);
    let err = crate::common::load("Film \"rgb\" \"string sensor\" \"nikon_d805\" WorldBegin").unwrap_err().to_string();
    assert!(err.contains("unknown sensor \"nikon_d805\" (did you mean \"nikon_d850\"?)"), "{err}");
    // A temperature whose light underflows is refused where pbrt-v4 writes NaN.
    let err = crate::common::load("Film \"rgb\" \"float whitebalance\" 10 WorldBegin").unwrap_err().to_string();
    assert!(err.contains("inline.pbrt:1:") && err.contains("no visible colour"), "{err}");
    assert!(scene("Film \"rgb\" \"float whitebalance\" 1000 WorldBegin").film.white_balance.is_some());
}
