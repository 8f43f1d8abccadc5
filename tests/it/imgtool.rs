//! `pbrt-imgtool`: metric values on small hand-made images, half-float input, the
//! threshold exit status, the heat map, `info`, `convert`, `plot` and `report`.

use pbrt_sppm::imageio::{RgbImage, read_image, write_image};
use std::process::Command;

fn dir(name: &str) -> crate::common::Scratch {
    crate::common::Scratch::new(&format!("imgtool-{name}"))
}

fn image(pixels: Vec<[f32; 3]>) -> RgbImage {
    let mut img = RgbImage::new(pixels.len(), 1);
    img.pixels = pixels;
    img
}

fn tool(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pbrt-imgtool")).args(args).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn diff_reports_every_metric_and_thresholds_the_exit_status() {
    let d = dir("diff");
    let (a, b) = (d.join("a.exr"), d.join("b.exr"));
    write_image(&a, &image(vec![[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]])).unwrap();
    // B (the reference) is half-float, as pbrt-v3 writes.
    {
        use exr::prelude::*;
        let px = [[1.0f32, 2.0, 2.0], [0.0, 0.5, 0.0]];
        let layer = Layer::new(
            (2, 1),
            LayerAttributes::named(""),
            Encoding::SMALL_LOSSLESS,
            SpecificChannels::rgb(|Vec2(x, _): Vec2<usize>| {
                (f16::from_f32(px[x][0]), f16::from_f32(px[x][1]), f16::from_f32(px[x][2]))
            }),
        );
        Image::from_layer(layer).write().to_file(&b).unwrap();
    }
    let heat = d.join("heat.png");
    let (code, out, _) =
        tool(&["diff", a.to_str().unwrap(), b.to_str().unwrap(), "--json", "--heatmap", heat.to_str().unwrap()]);
    assert_eq!(code, Some(0));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let near = |k: &str, want: f64| assert!((v[k].as_f64().unwrap_or(f64::NAN) - want).abs() < 1e-12, "{k}: {}", v[k]);
    near("mse", 1.25 / 6.0);
    near("rmse", (1.25f64 / 6.0).sqrt());
    near("mae", 1.5 / 6.0);
    assert_eq!(v["max_abs"].as_f64(), Some(1.0));
    assert_eq!(v["share_above"].as_f64(), Some(1.0), "both pixels differ by more than 0.01");
    let rel = (1.0 / 4.01 + 0.25 / 0.26) / 6.0;
    assert!((v["relmse"].as_f64().unwrap() - rel).abs() < 1e-9);
    let hm = read_image(&heat).unwrap();
    assert_eq!((hm.width, hm.height), (2, 1));
    assert!(hm.pixels[0][0] > 0.9 && hm.pixels[0][1] > 0.9, "the largest difference is white: {:?}", hm.pixels[0]);
    let (code, _, err) =
        tool(&["diff", a.to_str().unwrap(), b.to_str().unwrap(), "--metric", "rmse", "--threshold", "0.1"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("rmse"));
    let (code, _, _) = tool(&["diff", a.to_str().unwrap(), b.to_str().unwrap(), "--metric", "max", "--threshold", "1"]);
    assert_eq!(code, Some(0));
    let other = d.join("other.exr");
    write_image(&other, &image(vec![[0.0; 3]; 3])).unwrap();
    let (code, _, err) = tool(&["diff", a.to_str().unwrap(), other.to_str().unwrap()]);
    assert_eq!(code, Some(1));
    assert!(err.contains("2x1") && err.contains("3x1"), "{err}");
}

#[test]
fn info_and_convert() {
    let d = dir("info");
    let exr = d.join("info.exr");
    let mut img = image(vec![[0.25, 0.5, 1.0], [0.75, 0.0, -1.0]]);
    img.origin = (3, 4);
    img.full = (10, 10);
    img.meta.samples_per_pixel = Some(7);
    write_image(&exr, &img).unwrap();
    let (code, out, _) = tool(&["info", exr.to_str().unwrap()]);
    assert_eq!(code, Some(0));
    assert!(out.contains("origin (3, 4), size 2x1; display window 10x10"), "{out}");
    assert!(out.contains("samplesPerPixel: 7"));
    assert!(out.contains("R: min 0.25 max 0.75 mean 0.5"), "{out}");
    let png = d.join("conv.png");
    let (code, _, _) = tool(&["convert", exr.to_str().unwrap(), png.to_str().unwrap(), "--exposure", "1"]);
    assert_eq!(code, Some(0));
    let back = read_image(&png).unwrap();
    assert!((back.pixels[0][0] - 0.5).abs() < 0.01 && back.pixels[0][2] == 1.0, "{:?}", back.pixels[0]);
    let exr2 = d.join("conv.exr");
    let (code, _, _) = tool(&["convert", png.to_str().unwrap(), exr2.to_str().unwrap()]);
    assert_eq!(code, Some(0));
    assert!((read_image(&exr2).unwrap().pixels[0][1] - 1.0).abs() < 0.01);
    let (code, _, err) = tool(&["info", "no-such.exr"]);
    assert_eq!(code, Some(1));
    // A spectral film's buckets are listed after R, G, B.
    img.bands = Some(pbrt_sppm::imageio::Bands {
        names: vec!["S0.400,000nm".into(), "S0.600,000nm".into()],
        values: vec![1.0, 2.0, 3.0, 4.0],
    });
    let spectral = d.join("spectral.exr");
    write_image(&spectral, &img).unwrap();
    let (code, out, _) = tool(&["info", spectral.to_str().unwrap()]);
    assert_eq!(code, Some(0));
    assert!(out.contains("channels R G B and 2 spectral buckets"), "{out}");
    assert!(out.contains("S0.600,000nm: min 2 max 4 mean 3"), "{out}");
    assert!(err.contains("no-such.exr"));
}

#[test]
fn plot_draws_one_line_per_csv_and_rejects_a_missing_column() {
    let d = dir("plot");
    let (a, b) = (d.join("fast.csv"), d.join("slow.csv"));
    let csv = |k: f64| {
        let rows: String = (1..=10)
            .map(|i| {
                format!(
                    "{i},{},{},{},{},{}\n",
                    0.1 * i as f64,
                    1000 * i,
                    k / i as f64,
                    (k / i as f64).sqrt(),
                    k / i as f64
                )
            })
            .collect();
        format!("iteration,seconds,photons,mse,rmse,relmse\n{rows}")
    };
    std::fs::write(&a, csv(0.5)).unwrap();
    std::fs::write(&b, csv(2.0)).unwrap();
    let png = d.join("plot.png");
    let (code, _, err) = tool(&["plot", a.to_str().unwrap(), b.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    let img = read_image(&png).unwrap();
    assert_eq!((img.width, img.height), (900, 600));
    // Two differently coloured lines: count pixels that are neither grey nor white.
    let colours: std::collections::HashSet<[u8; 3]> = img
        .pixels
        .iter()
        .map(|p| p.map(|c| (pbrt_sppm::imageio::to_srgb(c) * 255.0).round() as u8))
        .filter(|p| p.iter().max().unwrap() - p.iter().min().unwrap() > 60)
        .collect();
    assert!(colours.len() >= 2, "expected coloured lines, found {colours:?}");
    let short = d.join("short.csv");
    std::fs::write(&short, "iteration,seconds,photons,mse\n1,0.1,10,0.5\n").unwrap();
    let (code, _, err) = tool(&["plot", short.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert_eq!(code, Some(1));
    assert!(err.contains("no 'relmse' column"), "{err}");
    let (code, _, err) = tool(&["plot", a.to_str().unwrap(), "-o", png.to_str().unwrap(), "--metric", "psnr"]);
    assert_eq!(code, Some(2), "clap rejects an unknown metric");
    assert!(err.contains("invalid value 'psnr'"), "{err}");
}

#[test]
fn report_tabulates_the_ladder_and_writes_its_files() {
    let d = dir("report");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/pbrt-scenes/v3/caustic-ring.pbrt");
    let reference = d.join("ref.exr");
    let out = Command::new(env!("CARGO_BIN_EXE_pbrt-sppm"))
        .args([scene, "--spp", "12", "--photons", "20000", "--seed", "9", "--outfile", reference.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let md = d.join("conv.md");
    let args = ["report", scene, "--reference", reference.to_str().unwrap(), "--iterations", "4,1,2"];
    let (code, _, err) = tool(&[&args[..], &["--photons", "20000", "-o", md.to_str().unwrap()]].concat());
    assert_eq!(code, Some(0), "{err}");
    let text = std::fs::read_to_string(&md).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with("| ") && l.contains(" it |"))
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 3, "{text}");
    let iterations: Vec<&str> = rows.iter().map(|r| r[3]).collect();
    assert_eq!(iterations, ["1", "2", "4"], "sorted ladder");
    let photons: Vec<&str> = rows.iter().map(|r| r[4]).collect();
    assert_eq!(photons, ["20000", "40000", "80000"]);
    let relmse: Vec<f64> = rows.iter().map(|r| r[6].parse().unwrap()).collect();
    assert!(relmse[2] < relmse[0], "error falls with iterations: {relmse:?}");
    assert!(text.contains("Fitted log-log slope"), "{text}");
    for ext in ["png", "csv", "exr"] {
        let f = md.with_extension(ext);
        assert!(std::fs::metadata(&f).map(|m| m.len() > 0).unwrap_or(false), "{} missing", f.display());
    }
    let csv = std::fs::read_to_string(md.with_extension("csv")).unwrap();
    assert!(csv.starts_with("iteration,seconds,photons,mse,rmse,relmse\n"));
    assert_eq!(csv.lines().count(), 5, "header and four iterations");
    let (code, _, err) = tool(&["report", scene, "--reference", reference.to_str().unwrap()]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--seconds <SECONDS>"), "a budget ladder is required: {err}");
    // -o into a folder that does not exist yet makes it.
    let nested = d.join("new/folder/r.md");
    let (code, _, err) = tool(&[&args[..], &["--photons", "2000", "-o", nested.to_str().unwrap()]].concat());
    assert_eq!(code, Some(0), "{err}");
    assert!(nested.exists());
}

/// `tiles` prints the whole image's line, each tile's, marks the tiles held to the floor
/// with the deviation it takes there, and a worst line that agrees with the rows.
#[test]
fn tiles_prints_the_whole_image_and_explains_the_floor() {
    let d = dir("tiles");
    // 2 × 2 pixels, a tile each: the lower row is dark (below 5% of the image mean).
    let square = |px: Vec<[f32; 3]>| {
        let mut img = RgbImage::new(2, 2);
        img.pixels = px;
        img
    };
    let reference = square(vec![[1.0; 3], [1.0; 3], [0.01; 3], [0.01; 3]]);
    let ours = square(vec![[1.02; 3], [1.02; 3], [0.011; 3], [0.011; 3]]);
    let (a, b) = (d.join("tiles-a.exr"), d.join("tiles-b.exr"));
    write_image(&a, &ours).unwrap();
    write_image(&b, &reference).unwrap();
    let (code, out, err) =
        tool(&["tiles", a.to_str().unwrap(), b.to_str().unwrap(), "--grid", "2", "--tolerance", "0.05"]);
    let lines: Vec<&str> = out.lines().collect();
    assert!(lines[0].starts_with("image: ratio 1.0208"), "{out}{err}");
    assert!(lines[1].starts_with("tile (0, 0): ratio 1.0200") && !lines[1].contains("floor"), "{out}");
    // |0.011 − 0.01| against 5% of the image mean 0.505: 3.96%, not the ratio's 10%.
    assert!(lines[3].contains("ratio 1.1000") && lines[3].contains("below the floor: R 3.96%"), "{out}");
    assert!(out.contains("worst deviation 3.9604% at tile (0, 1)") && out.contains("5% of B's image mean"), "{out}");
    assert_eq!(code, Some(0), "3.96% is within --tolerance 0.05");
    let (code, ..) = tool(&["tiles", a.to_str().unwrap(), b.to_str().unwrap(), "--grid", "2", "--tolerance", "0.03"]);
    assert_eq!(code, Some(1));
}

/// `plot` without `-o` writes beside the first CSV; a file that is not text is "not a
/// CSV", not a UTF-8 complaint.
#[test]
fn plot_writes_beside_the_csv_and_names_a_file_that_is_not_one() {
    let d = dir("plot-beside");
    let csv = d.join("run-errors.csv");
    std::fs::write(&csv, "iteration,seconds,photons,mse,rmse,relmse\n1,0.5,10,0.4,0.6,0.4\n2,1,20,0.2,0.4,0.2\n")
        .unwrap();
    let (code, out, err) = tool(&["plot", csv.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("run-errors.png") && d.join("run-errors.png").is_file(), "{out}");
    let exr = d.join("not-a-csv.exr");
    write_image(&exr, &image(vec![[1.0; 3]])).unwrap();
    let (code, _, err) = tool(&["plot", exr.to_str().unwrap(), "-o", d.join("p.png").to_str().unwrap()]);
    assert_eq!(code, Some(1));
    assert!(err.contains("not a CSV file"), "{err}");
}
