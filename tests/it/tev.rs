//! `--display-server`: a fake tev server receives the image as tev's protocol sends it,
//! gets it again after it drops the connection, and a missing server costs nothing.

use pbrt_sppm::imageio::read_image;
use std::io::Read;
use std::net::{TcpListener, TcpStream};
use std::process::Command;

/// What one connection received: the created image's size and channels, and the
/// pixels its tiles filled (RGB, row-major).
struct Received {
    size: (usize, usize),
    channels: Vec<String>,
    pixels: Vec<[f32; 3]>,
    updates: usize,
    /// The image as it stood once every tile's channels had been sent once.
    first: Option<Vec<[f32; 3]>>,
}

fn string(b: &[u8], at: &mut usize) -> String {
    let end = b[*at..].iter().position(|&c| c == 0).expect("NUL-terminated") + *at;
    let s = String::from_utf8_lossy(&b[*at..end]).into_owned();
    *at = end + 1;
    s
}

fn int(b: &[u8], at: &mut usize) -> usize {
    let v = i32::from_le_bytes(b[*at..*at + 4].try_into().unwrap());
    *at += 4;
    v as usize
}

/// Reads messages until the client closes the connection (or `limit` messages).
fn receive(mut stream: TcpStream, limit: usize) -> Received {
    let mut r = Received { size: (0, 0), channels: Vec::new(), pixels: Vec::new(), updates: 0, first: None };
    for _ in 0..limit {
        let mut len = [0u8; 4];
        if stream.read_exact(&mut len).is_err() {
            break;
        }
        let mut body = vec![0u8; u32::from_le_bytes(len) as usize - 4];
        stream.read_exact(&mut body).unwrap();
        let mut at = 1;
        at += 1; // grab focus
        let _title = string(&body, &mut at);
        match body[0] {
            4 => {
                r.size = (int(&body, &mut at), int(&body, &mut at));
                let n = int(&body, &mut at);
                r.channels = (0..n).map(|_| string(&body, &mut at)).collect();
                r.pixels = vec![[f32::NAN; 3]; r.size.0 * r.size.1];
            }
            3 => {
                let name = string(&body, &mut at);
                let c = r.channels.iter().position(|n| *n == name).expect("a created channel");
                let (x, y, w, h) = (int(&body, &mut at), int(&body, &mut at), int(&body, &mut at), int(&body, &mut at));
                let values: Vec<f32> =
                    body[at..].chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
                assert_eq!(values.len(), w * h);
                for (k, v) in values.into_iter().enumerate() {
                    r.pixels[(y + k / w) * r.size.0 + x + k % w][c] = v;
                }
                r.updates += 1;
                if r.first.is_none() && r.pixels.iter().all(|p| p.iter().all(|c| !c.is_nan())) {
                    r.first = Some(r.pixels.clone());
                }
            }
            t => panic!("unexpected message type {t}"),
        }
    }
    r
}

/// The next connection, within 30 s (a client that never comes fails the test rather
/// than hanging it).
fn accept(listener: &TcpListener) -> TcpStream {
    listener.set_nonblocking(true).unwrap();
    let start = std::time::Instant::now();
    loop {
        match listener.accept() {
            Ok((stream, _)) => {
                stream.set_nonblocking(false).unwrap();
                stream.set_read_timeout(Some(std::time::Duration::from_secs(30))).unwrap();
                return stream;
            }
            Err(_) if start.elapsed().as_secs() < 30 => std::thread::sleep(std::time::Duration::from_millis(20)),
            Err(e) => panic!("no connection from the render: {e}"),
        }
    }
}

fn render(port: u16, spp: &str, out: &std::path::Path) -> std::process::Output {
    render_scene(&crate::common::root().join("pbrt-scenes/v3/cornell-glass.pbrt"), port, &["--spp", spp], out)
}

fn render_scene(scene: &std::path::Path, port: u16, args: &[&str], out: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .arg(scene)
        .args(args)
        .args(["-q", "--display-server", &format!("127.0.0.1:{port}"), "--outfile"])
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn tev_receives_the_image_and_gets_it_again_after_a_restart() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("tev");
    std::fs::create_dir_all(&dir).unwrap();
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let server = std::thread::spawn(move || {
        // The first connection is dropped after the image is created (tev quitting);
        // the render connects again and sends the whole image.
        let first = receive(accept(&listener), 1);
        let second = receive(accept(&listener), usize::MAX);
        (first, second)
    });
    let out = dir.join("tev.exr");
    let o = render(port, "160", &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (first, second) = server.join().unwrap();
    let image = read_image(&out).unwrap();
    assert_eq!(first.size, (image.width, image.height));
    assert_eq!(second.channels, ["R", "G", "B"]);
    assert!(second.updates >= 3, "{} tile updates", second.updates);
    // The last image tev holds is the one written.
    assert!(second.pixels.iter().zip(&image.pixels).all(|(a, b)| a == b), "tev's image differs from the EXR");
}

#[test]
fn a_missing_tev_server_does_not_stop_the_render() {
    let port = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port(); // closed again
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("tev-missing.exr");
    let o = render(port, "4", &out);
    assert!(o.status.success() && out.is_file(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A wall filling the view, lit directly by an area light behind the camera, with a
/// glass sphere before it, at 256 × 256: sixteen bands of camera paths when a preview
/// is wanted, each with directly lit pixels.
const WALL: &str = r#"LookAt 0 0 4  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "image" "integer xresolution" [ 256 ] "integer yresolution" [ 256 ]
Sampler "random" "integer pixelsamples" [ 1 ]
Integrator "sppm" "integer numiterations" [ 1 ] "integer photonsperiteration" [ 30000 ] "float radius" [ 0.05 ]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 4 4 4 ]
  Translate 0 0 5
  Rotate 180 0 1 0
  Shape "disk" "float radius" [ 1 ]
AttributeEnd
Material "matte" "rgb Kd" [ 0.7 0.7 0.7 ]
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point P" [ -3 -3 -1  3 -3 -1  3 3 -1  -3 3 -1 ]
Material "glass"
Shape "sphere" "float radius" [ 0.5 ]
"#;

/// The first iteration of a render is shown while it runs: the first image tev holds
/// has the top of the film rendered and its bottom still black, and the last is the
/// one written. Both SPPM and vcm (whose camera subpaths run in bands too).
#[test]
fn tev_sees_the_first_iteration_part_way_through() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("tev-preview");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("wall.pbrt");
    std::fs::write(&scene, WALL).unwrap();
    for integrator in ["sppm", "vcm"] {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let server = std::thread::spawn(move || receive(accept(&listener), usize::MAX));
        let out = dir.join(format!("{integrator}.exr"));
        let o = render_scene(&scene, port, &["--integrator", integrator], &out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let got = server.join().unwrap();
        let image = read_image(&out).unwrap();
        assert!(
            got.pixels.iter().zip(&image.pixels).all(|(a, b)| a == b),
            "{integrator}: tev's last image is not the EXR"
        );
        let first = got.first.expect("a whole image sent");
        let rows = |img: &[[f32; 3]], r: std::ops::Range<usize>| -> f32 {
            img[r.start * 256..r.end * 256].iter().map(|p| p[0] + p[1] + p[2]).sum()
        };
        assert!(rows(&image.pixels, 0..8) > 0.0 && rows(&image.pixels, 248..256) > 0.0, "{integrator}: a dark film");
        assert!(rows(&first, 0..8) > 0.0, "{integrator}: the first preview has no light at the top");
        assert_eq!(rows(&first, 248..256), 0.0, "{integrator}: the first image shown was not a preview");
        assert!(got.updates >= 2 * 3 * 4, "{integrator}: {} tile updates, not two images", got.updates);
    }
}

/// The preview made after the last band of photons is the image the iteration ends
/// with, where the estimate allows it exactly: every pass of independent passes, and
/// classic SPPM's first iteration (later ones shrink the radius at the update, which a
/// preview does not). A wrong scale of the photons traced so far breaks it.
#[test]
fn the_last_preview_of_an_iteration_is_the_image_it_ends_with() {
    use pbrt_sppm::integrators::passes::PassMode;
    use pbrt_sppm::integrators::sppm::Sppm;
    let desc = crate::common::scene(WALL);
    let rs = pbrt_sppm::render::RenderScene::new(&desc);
    for mode in [PassMode::Classic, PassMode::Independent { alpha: 2.0 / 3.0 }] {
        let mut sppm = Sppm::new(&rs, 3, 30_000, 0.05, 0, Default::default()).unwrap().with_passes(mode, 0).unwrap();
        for it in 0..3 {
            let mut last = Vec::new();
            sppm.iterate_showing(Some(&mut |image: &dyn Fn() -> Vec<[f32; 3]>| last = image()));
            if it > 0 && mode == PassMode::Classic {
                continue;
            }
            let image = sppm.image();
            let worst =
                last.iter().zip(&image).flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs() / b[c].max(1e-3)));
            let worst = worst.fold(0.0f32, f32::max);
            assert!(worst < 1e-4, "{mode:?}, iteration {it}: the last preview is {worst} off the image");
            assert!(image.iter().any(|p| p[0] > 0.0));
        }
    }
}

/// Part way through the photons, a preview scales those traced so far up to the whole
/// iteration: halfway, the light they add (here the sphere's caustic) is what the
/// iteration's image holds, not half of it.
#[test]
fn a_preview_part_way_through_the_photons_scales_them_up() {
    use pbrt_sppm::integrators::sppm::Sppm;
    let desc = crate::common::scene(WALL);
    let rs = pbrt_sppm::render::RenderScene::new(&desc);
    let mut sppm = Sppm::new(&rs, 1, 200_000, 0.05, 0, Default::default()).unwrap();
    let mut shown = Vec::new();
    sppm.iterate_showing(Some(&mut |image: &dyn Fn() -> Vec<[f32; 3]>| shown.push(image())));
    let sum = |img: &[[f32; 3]]| img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>();
    // 16 bands of camera paths, then the bands of photons.
    let photon_bands = shown.len() - 16;
    assert!(photon_bands >= 8, "{photon_bands} bands of photons");
    let direct = sum(&shown[15]);
    let (half, last) = (sum(&shown[16 + photon_bands / 2 - 1]) - direct, sum(&sppm.image()) - direct);
    assert!(last > 0.01 * direct, "no caustic: {last} beside {direct}");
    assert!((half / last - 1.0).abs() < 0.2, "halfway the photons add {half}, the whole iteration {last}");
}
