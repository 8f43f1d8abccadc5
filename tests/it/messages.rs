//! What the command line says is true: help texts state the defaults the code plans
//! with; a typo in a type name is "unknown" with the nearest name, answered as the
//! file's pbrt answers it; an empty file is an error; `--display-server` is checked up
//! front; every binary has `--version`; `--time-limit` alone renders until the limit.

use crate::common::{load, root};
use pbrt_sppm::integrators::{Plan, RenderSettings};
use std::process::{Command, Output};

fn cli(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pbrt-sppm")).args(args).output().expect("pbrt-sppm runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The paragraph of `--flag` in `render --help`, on one line.
fn help_of(help: &str, flag: &str) -> String {
    let start = help.find(&format!("--{flag} ")).unwrap_or_else(|| panic!("--{flag} is not in the help"));
    let rest = &help[start..];
    let end = rest[2..].find("\n  -").map_or(rest.len(), |e| e + 2);
    rest[..end].split_whitespace().collect::<Vec<_>>().join(" ")
}

#[test]
fn render_help_states_the_defaults_the_code_plans_with() {
    let out = cli(&["render", "--help"]);
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout).into_owned();
    let scene = load("WorldBegin Shape \"sphere\"").unwrap();
    let plan = Plan::new(&scene.integrator, || 1.0, &RenderSettings::default()).unwrap();
    let lower = |v: &dyn std::fmt::Debug| format!("{v:?}").to_lowercase();
    for (flag, default) in [
        ("volume-gather", plan.volume_gather.name().to_string()),
        ("sampler", lower(&plan.sampler)),
        ("photon-sampling", lower(&plan.photon_sampling)),
        ("passes", lower(&plan.passes)),
        ("connections", plan.connections.name().to_string()),
    ] {
        let text = help_of(&help, flag);
        assert!(text.contains(&format!("Default: `{default}`")), "--{flag} does not say `{default}`: {text}");
    }
    let nthreads = help_of(&help, "nthreads");
    assert!(nthreads.contains("0, the default"), "{nthreads}");
}

#[test]
fn an_unknown_type_name_is_told_apart_from_an_unsupported_one_and_suggests_the_nearest() {
    // pbrt-v4 stops at an unknown name; so do we in a v4 file.
    let e = load("Film \"rgb\" WorldBegin Shape \"sphre\"").unwrap_err().to_string();
    assert!(e.contains("unknown shape type \"sphre\" (did you mean \"sphere\"?)"), "{e}");
    // pbrt-v3 warns, leaves a shape out, and renders an unknown material as matte.
    let s = load("Film \"image\" WorldBegin Shape \"sphre\" Material \"mattte\" \"rgb Kd\" [1 0 0] Shape \"sphere\"");
    let s = s.unwrap();
    let said = crate::common::warnings(&s).join("\n");
    assert!(said.contains("unknown shape type \"sphre\" (did you mean \"sphere\"?); left out"), "{said}");
    assert!(said.contains("unknown material type \"mattte\" (did you mean \"matte\"?)"), "{said}");
    assert_eq!(s.materials.iter().find(|m| m.ty == "mattte").map(|m| m.kind.clone()), {
        let matte = load("Film \"image\" WorldBegin Material \"matte\" \"rgb Kd\" [1 0 0] Shape \"sphere\"").unwrap();
        matte.materials.iter().find(|m| m.ty == "matte").map(|m| m.kind.clone())
    });
    // A name pbrt knows is never "unknown", whether or not we render it in full.
    let s = load("Film \"image\" WorldBegin Material \"kdsubsurface\" Shape \"sphere\"").unwrap();
    assert!(!crate::common::warnings(&s).join("\n").contains("unknown"));
    // Without a camera, sampler, filter, film or integrator pbrt renders nothing.
    for (text, word) in [
        ("Camera \"perspectiv\"", "camera type \"perspectiv\" (did you mean \"perspective\"?)"),
        ("Sampler \"halon\"", "sampler type \"halon\" (did you mean \"halton\"?)"),
        ("PixelFilter \"gausian\"", "filter type \"gausian\" (did you mean \"gaussian\"?)"),
        ("Film \"imag\"", "film type \"imag\" (did you mean \"image\"?)"),
        ("Integrator \"pat\"", "integrator \"pat\" (did you mean \"path\"?)"),
        ("Texture \"t\" \"float\" \"imagemapp\"", "texture class \"imagemapp\" (did you mean \"imagemap\"?)"),
    ] {
        let world = if text.starts_with("Texture") { "Film \"rgb\" WorldBegin " } else { "" };
        let tail = if world.is_empty() { " WorldBegin" } else { "" };
        let e = load(&format!("{world}{text}{tail}")).unwrap_err().to_string();
        assert!(e.contains(&format!("unknown {word}")), "{text}: {e}");
    }
}

#[test]
fn a_file_without_world_begin_is_a_located_error() {
    let dir = crate::common::scratch("msg", "worldbegin", &[]);
    for (name, text, said) in [
        ("empty.pbrt", "", "empty.pbrt:1:1: error: the file is empty"),
        ("options.pbrt", "Film \"rgb\"\n", "options.pbrt:2:1: error: the file ends before WorldBegin"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out = cli(&[path.to_str().unwrap(), "--outfile", dir.join("x.exr").to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(1), "{name}");
        assert!(stderr(&out).contains(said), "{name}: {}", stderr(&out));
        assert!(!dir.join("x.exr").exists(), "{name} wrote an image");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_display_server_address_is_checked_before_loading_and_a_refused_one_warns_once() {
    let scene = root().join("pbrt-scenes/v3/cornell-glass.pbrt");
    let scene = scene.to_str().unwrap();
    for (address, said) in [("localhost", "no port"), ("localhost:0", "is not a number from 1 to 65535")] {
        let out = cli(&[scene, "--display-server", address, "--outfile", "/nonexistent/x.exr"]);
        assert_eq!(out.status.code(), Some(1), "{address}");
        assert!(stderr(&out).starts_with("--display-server: error: "), "{address}: {}", stderr(&out));
        assert!(stderr(&out).contains(said), "{address}: {}", stderr(&out));
    }
    // A port nobody listens on: one warning, and the render goes on.
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let out_file = std::env::temp_dir().join(format!("pbrt-sppm-tev-refused-{}.exr", std::process::id()));
    let address = format!("127.0.0.1:{port}");
    let out = cli(&[scene, "--display-server", &address, "--spp", "3", "--outfile", out_file.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(stderr(&out).matches("warning: cannot connect to tev").count(), 1, "{}", stderr(&out));
    assert!(out_file.exists());
    let _ = std::fs::remove_file(&out_file);
}

#[test]
fn every_binary_says_its_version_and_help_takes_help() {
    let bins = [
        env!("CARGO_BIN_EXE_pbrt-sppm"),
        env!("CARGO_BIN_EXE_pbrt-imgtool"),
        env!("CARGO_BIN_EXE_pbrt-bench"),
        env!("CARGO_BIN_EXE_pbrt-rgb2spec"),
    ];
    for bin in bins {
        let out = Command::new(bin).arg("--version").output().unwrap();
        assert!(out.status.success(), "{bin} --version");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.trim_end().ends_with(env!("CARGO_PKG_VERSION")), "{bin}: {text}");
    }
    let out = cli(&["help", "--help"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("Usage: pbrt-sppm"));
}

#[test]
fn a_time_limit_alone_renders_until_the_limit() {
    // The file asks for 2 iterations; a second of rendering holds many more.
    let text = "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
                Integrator \"sppm\" \"integer numiterations\" 2 \"integer photonsperiteration\" 2000\n\
                WorldBegin\nLightSource \"point\" \"point from\" [0 0 -2]\nShape \"sphere\"\n";
    let dir = crate::common::scratch("msg", "timelimit", &[("s.pbrt", text)]);
    let t = std::time::Instant::now();
    let out = cli(&[
        dir.join("s.pbrt").to_str().unwrap(),
        "--time-limit",
        "1",
        "--outfile",
        dir.join("o.exr").to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(t.elapsed().as_secs_f64() >= 1.0, "stopped before the limit: {}", stderr(&out));
    let image = pbrt_sppm::imageio::read_image(&dir.join("o.exr")).unwrap();
    assert!(image.meta.samples_per_pixel.unwrap() > 2, "{}", stderr(&out));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_pixel_past_f32_is_an_error_at_the_film_that_records_it() {
    // A sky of 1e38 on a surface that reflects more than it receives (pbrt-v3's marble
    // leaves its palette): a pixel past f32's range, found after rendering. The error
    // names the Film statement (whose "scale" is one of the two things to lower), and
    // no image is written.
    let text = "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"orthographic\"\n\
        Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
        Integrator \"sppm\" \"integer numiterations\" 1 \"integer photonsperiteration\" 100 \"integer maxdepth\" 1\n\
        WorldBegin\nLightSource \"infinite\" \"color L\" [1 3e38 1]\n\
        Material \"matte\" \"color Kd\" [2 2 2]\n\
        Shape \"trianglemesh\" \"point P\" [-2 -2 0 2 -2 0 2 2 0 -2 2 0] \"integer indices\" [0 1 2 0 2 3]\nWorldEnd\n";
    let dir = crate::common::scratch("msg", "overflow", &[("inf.pbrt", text)]);
    let out = cli(&[dir.join("inf.pbrt").to_str().unwrap(), "--outfile", dir.join("x.exr").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(err.contains("inf.pbrt:3:6: error: pixel ("), "{err}");
    assert!(err.contains("beyond the range of 32-bit floats: lower the lights or the Film's \"scale\""), "{err}");
    assert!(!dir.join("x.exr").exists(), "an image was written");
}
