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
    let mut r = Received { size: (0, 0), channels: Vec::new(), pixels: Vec::new(), updates: 0 };
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
    let scene = crate::common::root().join("pbrt-scenes/v3/cornell-glass.pbrt");
    Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .arg(scene)
        .args(["--spp", spp, "-q", "--display-server", &format!("127.0.0.1:{port}"), "--outfile"])
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
