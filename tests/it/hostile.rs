//! Every input answered: one test per class of bad value (arity, type, non-finite,
//! negative), the limits, PLY headers that overflow, output paths checked before any
//! rendering, the command line's refusals, and a closed or full standard output.

use crate::common::{load, root};
use std::process::Command;

fn first_error(text: &str) -> String {
    match load(text) {
        Ok(_) => "loaded".into(),
        Err(e) => e.one_line().replace("tests/data/good/inline.pbrt:", ""),
    }
}

fn dir(name: &str) -> crate::common::Scratch {
    crate::common::Scratch::new(&format!("hostile-{name}"))
}

fn sppm(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm")).args(args).current_dir(root()).output().unwrap();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn light_and_material_parameters_of_the_wrong_arity_are_errors() {
    let cases = [
        (
            "WorldBegin Material \"matte\" \"color Kd\" [ 0.9 0.1 ] Shape \"sphere\"",
            "1:29: error: \"color Kd\": needs 3 values, found 2",
        ),
        ("WorldBegin LightSource \"point\" \"color I\" [ 10 10 ]", "1:32: error: \"color I\": needs 3 values, found 2"),
        (
            "WorldBegin LightSource \"point\" \"point from\" [ 0 0 ]",
            "1:32: error: \"point from\" needs 3 values, found 2",
        ),
        (
            "WorldBegin AreaLightSource \"diffuse\" \"float scale\" [1 2] Shape \"disk\"",
            "1:38: error: \"float scale\" needs exactly one value, found 2",
        ),
        (
            "WorldBegin Material \"glass\" \"float index\" [] Shape \"disk\"",
            "1:29: error: \"float index\" needs exactly one value",
        ),
    ];
    for (text, want) in cases {
        assert_eq!(first_error(text), want, "{text}");
    }
}

#[test]
fn parameters_of_the_wrong_type_are_errors() {
    let cases = [
        (
            "WorldBegin LightSource \"spot\" \"rgb coneangle\" [1 1 1]",
            "\"rgb coneangle\" has the wrong type: expected \"float\"",
        ),
        (
            "WorldBegin Material \"metal\" \"rgb roughness\" [1 1 1] Shape \"disk\"",
            "\"rgb roughness\" has the wrong type: expected \"float\"",
        ),
        (
            "WorldBegin Material \"matte\" \"float Kd\" 1 Shape \"disk\"",
            "\"float Kd\" has the wrong type: expected \"rgb\"",
        ),
    ];
    for (text, want) in cases {
        let got = first_error(text);
        assert!(got.ends_with(want), "{text}\n  got {got}");
    }
    // A spectrum where a texture cannot be used, and a texture name of the wrong kind.
    let got = first_error("WorldBegin LightSource \"point\" \"texture I\" \"t\"");
    assert!(got.ends_with("\"I\" cannot be a texture here; give a spectrum"), "{got}");
}

#[test]
fn non_finite_numbers_are_errors_where_finite_ones_are_needed() {
    let cases = [
        ("Film \"rgb\" \"float scale\" nan WorldBegin", "1:26: error: \"float scale\" must be finite, not NaN"),
        (
            "WorldBegin LightSource \"point\" \"rgb I\" [inf 1 1]",
            "1:40: error: \"rgb I\" must be finite, not [inf 1 1]",
        ),
        (
            "WorldBegin AreaLightSource \"diffuse\" \"rgb L\" [1 nan 1] Shape \"disk\"",
            "1:46: error: \"rgb L\" must be finite, not [1 NaN 1]",
        ),
        (
            "Camera \"perspective\" \"float lensradius\" inf WorldBegin",
            "1:41: error: \"float lensradius\" must be finite, not inf",
        ),
        (
            "WorldBegin Material \"glass\" \"float index\" inf Shape \"disk\"",
            "1:43: error: \"float index\" must be finite, not inf",
        ),
        ("WorldBegin Texture \"t\" \"float\" \"scale\" \"float scale\" nan", "loaded"),
        (
            "WorldBegin Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 nan 1 0] \"integer indices\" [0 1 2]",
            "1:33: error: vertex 2 is at (NaN, 1.0, 0.0): positions must be finite and within ±1e18",
        ),
        (
            "WorldBegin Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"normal N\" [0 0 1 0 0 1 0 0 inf]",
            "1:33: error: the normal of vertex 2 is not finite",
        ),
        ("WorldBegin Shape \"sphere\" \"float radius\" inf", "1:42: error: \"radius\" must be finite, not inf"),
    ];
    for (text, want) in cases {
        assert_eq!(first_error(text), want, "{text}");
    }
    // A texture is checked when a material uses it.
    let text = "WorldBegin Texture \"t\" \"float\" \"scale\" \"float scale\" nan \
                Material \"matte\" \"texture sigma\" \"t\" Shape \"disk\"";
    assert_eq!(first_error(text), "1:54: error: \"float scale\" must be finite, not NaN");
}

#[test]
fn an_area_light_whose_power_overflows_on_its_shape_is_an_error_in_every_integrator() {
    // The load checks `power` alone; over a tiny triangle it becomes an infinite
    // radiance, which vcm and bdpt used to drop (an image without the light).
    let d = dir("light-overflow");
    let scene = d.join("overflow.pbrt");
    let text = "Camera \"perspective\" Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
        Sampler \"halton\" \"integer pixelsamples\" 1\nWorldBegin\n\
        LightSource \"point\" \"point3 from\" [0 0 -1]\n\
        AttributeBegin AreaLightSource \"diffuse\" \"float power\" 1e38\n\
        Shape \"trianglemesh\" \"point3 P\" [0 0 5 1e-10 0 5 0 1e-10 5] \"integer indices\" [0 1 2]\n\
        AttributeEnd\nShape \"sphere\" \"float radius\" 10\n";
    std::fs::write(&scene, text).unwrap();
    for integrator in ["sppm", "vcm", "bdpt"] {
        let out = d.join(format!("{integrator}.exr"));
        let (out_path, scene_path) = (out.to_str().unwrap(), scene.to_str().unwrap());
        let (code, err) = sppm(&["render", "--quiet", "--integrator", integrator, "--outfile", out_path, scene_path]);
        assert_eq!(code, Some(1), "{integrator}: {err}");
        assert!(
            err.contains("world shape 0") && err.contains("beyond the range of 32-bit floats"),
            "{integrator}: {err}"
        );
        assert!(!out.exists(), "{integrator} wrote an image");
    }
}

#[test]
fn huge_vertices_are_errors_and_do_not_blank_the_scene() {
    let got = first_error(
        "WorldBegin Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 3e38 1 0] \"integer indices\" [0 1 2]",
    );
    assert_eq!(got, "1:33: error: vertex 2 is at (3e38, 1.0, 0.0): positions must be finite and within ±1e18");
}

#[test]
fn negative_emission_and_reflectance_are_errors() {
    let cases = [
        (
            "WorldBegin LightSource \"point\" \"rgb I\" [-1 1 1]",
            "1:40: error: \"rgb I\" must be at least 0, not [-1 1 1]",
        ),
        (
            "WorldBegin LightSource \"point\" \"float scale\" -2",
            "1:46: error: \"float scale\" must be at least 0, not -2",
        ),
        (
            "WorldBegin Material \"matte\" \"rgb Kd\" [.5 -.5 .5] Shape \"disk\"",
            "1:38: error: \"rgb Kd\" must be at least 0, not [0.5 -0.5 0.5]",
        ),
        (
            "WorldBegin Material \"dielectric\" \"float eta\" -1.5 Shape \"disk\"",
            "1:46: error: \"float eta\" must be greater than 0, not -1.5",
        ),
        (
            "Camera \"perspective\" \"float lensradius\" -1 WorldBegin",
            "1:41: error: \"float lensradius\" must be at least 0, not -1",
        ),
    ];
    for (text, want) in cases {
        assert_eq!(first_error(text), want, "{text}");
    }
}

#[test]
fn limits_are_located_errors_that_name_their_flag() {
    let cases = [
        (
            "Film \"rgb\" \"integer xresolution\" 1000000 \"integer yresolution\" 1000000 WorldBegin",
            "1:6: error: the film's 1000000x1000000 = 1000000000000 pixels is over the limit of 268435456 (raise it with --limit pixels=N)",
        ),
        (
            "Integrator \"sppm\" \"integer photonsperiteration\" 2000000000 WorldBegin",
            "1:49: error: photonsperiteration 2000000000 is over the limit of 268435456 (raise it with --limit photons=N)",
        ),
        (
            "Integrator \"sppm\" \"integer maxdepth\" 100000000 WorldBegin",
            "1:38: error: maxdepth 100000000 is over the limit of 65536 (raise it with --limit maxdepth=N)",
        ),
        (
            "Integrator \"sppm\" \"integer iterations\" 2000000000 WorldBegin",
            "1:40: error: 2000000000 SPPM iterations is over the limit of 16777216 (raise it with --limit iterations=N)",
        ),
        ("WorldBegin Include \"/dev/zero\"", "1:20: error: cannot read \"/dev/zero\": not a regular file"),
    ];
    for (text, want) in cases {
        assert_eq!(first_error(text), want, "{text}");
    }
    let d = dir("limits");
    let scene = d.join("big.pbrt");
    std::fs::write(&scene, "Film \"rgb\" \"integer xresolution\" 20000 \"integer yresolution\" 20000 WorldBegin")
        .unwrap();
    let (code, err) = sppm(&["check", scene.to_str().unwrap()]);
    assert_eq!(code, Some(1), "{err}");
    // 4·10⁸ pixels pass the pixel limit once raised, and then need more memory than
    // any test machine has free.
    let (code, err) = sppm(&["check", scene.to_str().unwrap(), "--limit", "pixels=4e8"]);
    assert!(code == Some(1) && err.contains("1:6: error: the memory the scene needs"), "{err}");
    let (code, err) = sppm(&["check", scene.to_str().unwrap(), "--limit", "pixels=4e8", "--limit", "memory=1e15"]);
    assert_eq!(code, Some(0), "the flags raise the limits: {err}");
    let (code, err) = sppm(&["check", scene.to_str().unwrap(), "--limit", "pixles=4"]);
    assert_eq!((code, err.contains("unknown limit \"pixles\"")), (Some(1), true), "{err}");
}

/// A flat grid mesh of 2·n² triangles over (n+1)² vertices.
fn grid_mesh(n: usize) -> String {
    let p: Vec<String> = (0..=n).flat_map(|j| (0..=n).map(move |i| format!("{i} 0 {j}"))).collect();
    let k = |i: usize, j: usize| j * (n + 1) + i;
    let quads = (0..n).flat_map(|j| (0..n).map(move |i| (i, j)));
    let t: Vec<String> = quads
        .map(|(i, j)| {
            format!("{} {} {} {} {} {}", k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j), k(i + 1, j + 1), k(i, j + 1))
        })
        .collect();
    format!("Shape \"trianglemesh\" \"point P\" [{}] \"integer indices\" [{}]", p.join(" "), t.join(" "))
}

#[test]
fn scenes_that_need_more_memory_than_the_limit_stop_at_the_statement() {
    use pbrt_sppm::memory::{BASE_BYTES, INSTANCE_BYTES, PIXEL_BYTES, RENDER_BYTES, TRIANGLE_BYTES, VERTEX_BYTES};
    let d = dir("memory");
    let check = |name: &str, text: &str, limit: u64| {
        let path = d.join(name);
        std::fs::write(&path, text).unwrap();
        let limit = format!("memory={limit}");
        let (code, err) = sppm(&["check", path.to_str().unwrap(), "--quiet", "--limit", &limit]);
        (code, err.replace(&format!("{}:", path.display()), ""))
    };
    // Two meshes of 20,000 triangles: the second passes a limit the first fits in.
    let mesh = grid_mesh(100);
    let one = BASE_BYTES + 20_000 * TRIANGLE_BYTES + 101 * 101 * VERTEX_BYTES;
    let two = one + 20_000 * TRIANGLE_BYTES + 101 * 101 * VERTEX_BYTES;
    let film = "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 32\n";
    let text = format!("{film}WorldBegin\n{mesh}\n{mesh}\n");
    let (code, err) = check("meshes.pbrt", &text, two - 1);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.starts_with("4:22: error: the memory the scene needs by here, about "), "{err}");
    assert!(err.contains("(40k triangles), is over the limit of") && err.contains("--limit memory=N"), "{err}");
    let all = two + 64 * 32 * PIXEL_BYTES + RENDER_BYTES;
    assert_eq!(check("meshes.pbrt", &text, all - 1).1.split(": error").next(), Some("1:6"), "the film's pixels last");
    let (code, err) = check("meshes.pbrt", &text, all);
    assert_eq!(code, Some(0), "{err}");
    // Instances, one a line: the seventh passes the limit.
    let uses = "ObjectInstance \"o\"\n".repeat(10);
    let text = format!("{film}WorldBegin\nObjectBegin \"o\"\nShape \"sphere\"\nObjectEnd\n{uses}");
    let (_, err) = check("instances.pbrt", &text, BASE_BYTES + 7 * INSTANCE_BYTES - 1);
    assert!(err.starts_with("12:1: error: ") && err.contains("(7 instances)"), "{err}");
    // `check --json` reports the estimate and the limit.
    let path = d.join("meshes.pbrt");
    std::fs::write(&path, format!("{film}WorldBegin\n{mesh}\n")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .args(["check", "--json", path.to_str().unwrap(), "--limit", "memory=5e9"])
        .output()
        .unwrap();
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let memory = &report["memory"];
    assert_eq!(memory["estimate_bytes"].as_u64(), Some(one + 64 * 32 * PIXEL_BYTES + RENDER_BYTES), "{memory}");
    assert_eq!(
        (memory["limit_bytes"].as_u64(), memory["limit_is_free_memory"].as_bool()),
        (Some(5_000_000_000), Some(false))
    );
}

#[test]
fn a_gzip_bomb_stops_at_the_file_limit() {
    use std::io::Write;
    let d = dir("gzip");
    let path = d.join("bomb.pbrt.gz");
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    enc.write_all(&vec![b' '; 4 << 20]).unwrap();
    std::fs::write(&path, enc.finish().unwrap()).unwrap();
    let (code, err) = sppm(&["check", path.to_str().unwrap(), "--limit", "file-bytes=1e6"]);
    assert_eq!(code, Some(1));
    assert!(
        err.contains("the decompressed data is over the limit of 1000000 (raise it with --limit file-bytes=N)"),
        "{err}"
    );
    let cut = d.join("cut.pbrt.gz");
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let (code, err) = sppm(&["check", cut.to_str().unwrap()]);
    assert_eq!(code, Some(1));
    assert!(err.starts_with(&format!("{}:1:1: error: ", cut.display())) && err.contains("truncated gzip"), "{err}");
}

#[test]
fn ply_headers_that_overflow_or_lie_are_errors() {
    let d = dir("ply");
    let scene = d.join("s.pbrt");
    std::fs::write(&scene, "WorldBegin Shape \"plymesh\" \"string filename\" \"a.ply\"").unwrap();
    let cases: [(&str, &str); 6] = [
        (
            "ply\nformat ascii 1.0\nelement vertex 18446744073709551616\nproperty float x\nend_header\n",
            "the count is not a whole number that fits",
        ),
        ("ply\nformat ascii 99999999999999999999.0\nelement vertex 1\nend_header\n", "only PLY version 1.0 is read"),
        (
            "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
            "the header declares 1000000000 \"vertex\" elements, more than the 0 bytes after it can hold",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n5 0 1 2 0 1\n",
            "face 0 has 5 vertices (pbrt reads triangles and quads)",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1.5\n",
            "face 0: vertex index 1.5 is not a whole number",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -3\n",
            "triangle 0 has vertex index -3, but there are 3 vertices",
        ),
    ];
    for (ply, want) in cases {
        std::fs::write(d.join("a.ply"), ply).unwrap();
        let e = crate::common::load_file(&scene).err().map(|e| e.one_line()).unwrap_or_default();
        assert!(e.contains("s.pbrt:1:46: error: a.ply: ") && e.ends_with(want), "{ply}\n  got {e}");
    }
}

#[test]
fn the_output_path_is_checked_before_any_rendering() {
    let d = dir("out");
    let scene = d.join("s.pbrt");
    // A scene that takes minutes to render: the error must come at once.
    std::fs::write(
        &scene,
        "Film \"rgb\" \"integer xresolution\" 2000 \"integer yresolution\" 2000 \"string filename\" \"no/such/dir/x.exr\"\n\
         Integrator \"sppm\" \"integer iterations\" 100000 WorldBegin LightSource \"point\" Shape \"sphere\"",
    )
    .unwrap();
    let start = std::time::Instant::now();
    let (code, err) = sppm(&[scene.to_str().unwrap()]);
    assert_eq!(code, Some(1));
    let at = format!("{}:1:84: error: cannot write \"no/such/dir/x.exr\"", scene.display());
    assert!(err.starts_with(&at), "{err}");
    let (code, err) = sppm(&[scene.to_str().unwrap(), "--outfile", "out.jpg"]);
    assert_eq!(code, Some(1));
    assert!(err.starts_with("--outfile: error: \"out.jpg\": the image must end in .exr or .png"), "{err}");
    let (code, err) = sppm(&[
        scene.to_str().unwrap(),
        "--outfile",
        d.join("a.exr").to_str().unwrap(),
        "--mse-reference-image",
        "r.exr",
        "--mse-reference-out",
        "no/dir/e.csv",
    ]);
    assert_eq!(code, Some(1));
    assert!(err.starts_with("--mse-reference-out: error: cannot write"), "{err}");
    assert!(start.elapsed().as_secs() < 30, "nothing was rendered");
    assert!(!d.join("a.exr").exists());
}

#[test]
fn the_command_line_refuses_what_it_cannot_do() {
    let scene = "pbrt-scenes/v3/cornell-glass.pbrt";
    for (args, want) in [
        (vec!["--spp", "0"], "must be at least 1, not 0"),
        (vec!["--photons", "0"], "must be at least 1, not 0"),
        (vec!["--nthreads", "-1"], "must be at least 0, not -1"),
        (vec!["--radius", "-1"], "must be a positive number, not -1"),
        (vec!["--mse-reference-image", "r.exr"], "--mse-reference-out <MSE_REFERENCE_OUT>"),
        (vec!["--treshold", "1"], "unexpected argument '--treshold'"),
    ] {
        let (code, err) = sppm(&[&[scene][..], &args].concat());
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("use '-- -1'"), "{err}");
    }
    let out = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm")).args(["render", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    for flag in [
        "--outfile",
        "--nthreads",
        "--seed",
        "--spp",
        "--quick",
        "--stats",
        "--photons",
        "--radius",
        "--time-limit",
        "--mse-reference-image",
        "--mse-reference-out",
        "--syntax",
        "--limit",
        "--quiet",
    ] {
        let described = help.lines().any(|l| l.trim_start().starts_with(flag) || l.contains(&format!(", {flag}")));
        assert!(described, "{flag} is not in render --help:\n{help}");
    }
    assert!(help.contains("[alias: --iterations]"), "{help}");
}

#[test]
fn a_scene_can_come_from_standard_input() {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .args(["check", "-", "--json"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(b"WorldBegin Shape \"sphere\" \"float radius\" 2").unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["counts"]["sphere"], 1);
}

#[test]
fn a_full_or_closed_standard_output_is_an_error_not_a_panic() {
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full");
    let Ok(full) = full else {
        eprintln!("SKIPPED: /dev/full is not available");
        return;
    };
    let out = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .args(["check", "pbrt-scenes/v3/cornell-glass.pbrt", "--json"])
        .current_dir(root())
        .stdout(full)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.starts_with("<stdout>: error: cannot write") && !err.contains("panicked"), "{err}");
    // A reader that goes away (`| head`): the write fails, and that is reported, not a panic.
    let d = dir("stdout");
    let img = d.join("a.exr");
    pbrt_sppm::imageio::write_image(&img, &pbrt_sppm::imageio::RgbImage::new(2, 2)).unwrap();
    let out =
        with_stdout_closed(Command::new(env!("CARGO_BIN_EXE_pbrt-imgtool")).args(["info", img.to_str().unwrap()]));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
    // pbrt-bench ends quietly (it panicked in `println!`).
    let mut bench = Command::new(env!("CARGO_BIN_EXE_pbrt-bench"));
    let out = with_stdout_closed(bench.args(["stress", "spawn", "--shapes", "5", "--rays", "5"]));
    assert_ne!(out.status.code(), Some(101), "panicked: {}", String::from_utf8_lossy(&out.stderr));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}

/// Runs a command whose standard output is closed before it prints anything (a reader
/// that went away, as `| head` does).
fn with_stdout_closed(cmd: &mut Command) -> std::process::Output {
    let mut child = cmd
        .current_dir(root())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

#[test]
fn imgtool_rejects_unknown_flags_and_keeps_its_promises() {
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_pbrt-imgtool")).args(args).current_dir(root()).output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr))
    };
    let (code, err) = run(&["diff", "a.exr", "b.exr", "--treshold", "0.001"]);
    assert_eq!(code, Some(2), "a misspelt flag must not disable the gate: {err}");
    for sub in ["diff", "info", "convert", "plot", "report"] {
        let (code, help) = run(&[sub, "--help"]);
        assert_eq!(code, Some(0), "{sub}: {help}");
        assert!(help.contains("Usage: pbrt-imgtool"), "{sub}: {help}");
    }
    let d = dir("imgtool");
    let img = d.join("a.exr");
    pbrt_sppm::imageio::write_image(&img, &pbrt_sppm::imageio::RgbImage::new(2, 2)).unwrap();
    let heat = d.join("heat.exr");
    let (code, err) = run(&["diff", img.to_str().unwrap(), img.to_str().unwrap(), "--heatmap", heat.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    assert!(pbrt_sppm::imageio::read_exr(&heat).is_ok(), "--heatmap heat.exr writes an EXR named heat.exr");
    assert!(!d.join("heat.png").exists());
    let (code, err) = run(&["convert", img.to_str().unwrap(), d.join("x.jpg").to_str().unwrap()]);
    assert_eq!(code, Some(1));
    assert!(err.contains("must end in .exr or .png"), "{err}");
}

#[test]
fn approximations_are_listed_and_the_readme_names_every_kind() {
    let s = crate::common::scene(
        "WorldBegin MakeNamedMaterial \"c\" \"string type\" \"coateddiffuse\" \
         MakeNamedMaterial \"m\" \"string type\" \"matte\" \
         Material \"mix\" \"string namedmaterial1\" \"c\" \"string namedmaterial2\" \"m\" Shape \"disk\" \
         MakeNamedMaterial \"h\" \"string type\" \"hair\" \
         Material \"mix\" \"string namedmaterial1\" \"h\" \"string namedmaterial2\" \"m\" Shape \"disk\" \
         Texture \"f\" \"float\" \"marble\" \
         Material \"matte\" \"texture sigma\" \"f\" Shape \"disk\"",
    );
    let how: Vec<&str> = s.approximated.iter().map(|a| a.how.as_str()).collect();
    use pbrt_sppm::scene::Approx;
    let expected = [Approx::CoatInBlend, Approx::HairInBlend, Approx::UnsupportedTexture];
    assert_eq!(how, expected.map(Approx::how));
    let json = pbrt_sppm::cli::check::report(&s, false);
    assert_eq!(json["approximated"].as_array().map(Vec::len), Some(3));
    assert_eq!(json["approximated"][0]["line"], 1);
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    for a in Approx::ALL {
        assert!(readme.contains(a.how()), "the README does not list: {}", a.how());
    }
}

#[test]
fn zero_area_triangles_are_dropped_and_the_rest_keep_their_file_numbers() {
    // Triangle 1 is a sliver of zero area (a repeated corner); 0 and 2 are real.
    let text = "WorldBegin AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \
                Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0  5 0 0  6 0 0  5 1 0] \
                \"integer indices\" [0 1 2  0 0 1  3 4 5]";
    let s = crate::common::scene(text);
    assert!(
        crate::common::warnings(&s).iter().any(|w| w == "1 of 3 triangles have zero area and are dropped"),
        "{:?}",
        s.warnings
    );
    let tracer = pbrt_sppm::cli::trace::Tracer::new(&s);
    let hit = |o: &str| -> serde_json::Value {
        let line = tracer.line(&format!("{o} 0 0 1")).unwrap().unwrap();
        serde_json::from_str(&line.to_string()).unwrap()
    };
    assert_eq!(hit("5.2 0.2 -1")["triangle"], 2, "file numbers survive the drop");
    assert_eq!(hit("0.2 0.2 -1")["triangle"], 0);
    let rs = pbrt_sppm::render::RenderScene::new(&crate::common::scene(text));
    assert_eq!(rs.lights.len(), 2, "one light per kept triangle");
}

/// A v3 run of `NamedMaterial` statements naming nothing, then as many shapes: each
/// statement is resolved once (a walk of the run per shape was quadratic: 10¹⁰ steps
/// here), and every shape keeps the material before the run, as in pbrt-v3.
#[test]
fn a_long_run_of_undefined_named_materials_resolves_once_per_statement() {
    const N: usize = 100_000;
    let mut text = String::from("Film \"image\"\nWorldBegin\nMaterial \"plastic\"\n");
    (0..N).for_each(|k| text.push_str(&format!("NamedMaterial \"m{k}\"\n")));
    (0..N).for_each(|_| text.push_str("Shape \"sphere\"\n"));
    let s = crate::common::scene(&text);
    assert_eq!(s.shapes.len(), N);
    assert!(s.shapes.iter().all(|sh| s.materials[sh.material as usize].ty == "plastic"));
    let undefined = s.warnings.iter().filter(|w| w.message.contains("is not defined; the current material")).count();
    assert_eq!(undefined, N, "one warning per statement");
}
