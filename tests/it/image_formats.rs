//! The image formats scenes name (`pbrt-scenes/verify/textures/fmt*`, written by
//! `tools/make_image_formats.py`): each decodes to the picture its PNG holds, and each
//! pbrt version reads the formats it reads. The images rendered with them are compared
//! with pbrt in `pbrt_refs.rs`.

use crate::common::{root, scene, scratch, warnings};
use pbrt_sppm::imageio::read_image;

fn texture(name: &str) -> Vec<[f32; 3]> {
    read_image(&root().join("pbrt-scenes/verify/textures").join(name)).expect(name).pixels
}

/// The largest difference of any channel of any pixel.
fn largest_difference(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
}

#[test]
fn every_format_decodes_to_the_same_picture_the_right_way_up() {
    let png = texture("fmt.png");
    // The white block is in the top left corner: the first row's first texels.
    assert_eq!(png[0], [1.0; 3]);
    assert!(png[16 * 7 + 15][2] < 0.9, "the bottom right corner is no block");
    for (name, tolerance) in [
        ("fmt-bottomup.tga", 0.0),
        ("fmt-rle.tga", 0.0),
        ("fmt.bmp", 0.0),
        // Stored halved, with scale -2.
        ("fmt.pfm", 1e-6),
        // RGBE keeps 8 bits of mantissa.
        ("fmt.hdr", 0.005),
        // Lossy.
        ("fmt.jpg", 0.08),
        // Linear floats, with an alpha channel beside them.
        ("fmt-rgba.exr", 1e-6),
        ("fmt.gif", 0.0),
        ("fmt.ppm", 0.0),
        ("fmt.qoi", 0.0),
        ("fmt-alpha.qoi", 0.0),
    ] {
        let got = texture(name);
        let worst = largest_difference(&got, &png);
        assert!(worst <= tolerance, "{name}: off by {worst} (tolerance {tolerance})");
        assert!(got[0][0] > 0.8 && got[16 * 7][0] < 0.2, "{name} is flipped");
    }
    // A luminance-only EXR reads as grey: its block in the top left, a ramp beside it.
    let grey = texture("fmt-grey.exr");
    assert!(grey.iter().all(|p| p[0] == p[1] && p[1] == p[2]), "fmt-grey.exr is not grey");
    assert!((grey[0][0] - 0.9).abs() < 1e-6 && (grey[16 * 7 + 15][0] - 1.0).abs() < 1e-6);
    assert!((grey[16 * 7][0] - 0.4).abs() < 1e-6, "fmt-grey.exr is flipped");
    // A QOI file marked linear keeps its bytes over 255 (the bottom right texel is
    // (250, 240, 90)); a PGM is grey, the picture's green.
    let linear = texture("fmt-linear.qoi");
    let expected = [250.0 / 255.0, 240.0 / 255.0, 90.0 / 255.0];
    assert!(linear[16 * 7 + 15].iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-6), "{:?}", linear[16 * 7 + 15]);
    let pgm = texture("fmt-grey.pgm");
    let green: Vec<[f32; 3]> = png.iter().map(|c| [c[1]; 3]).collect();
    let worst = largest_difference(&pgm, &green);
    assert!(worst < 1e-6, "fmt-grey.pgm is off the picture's green by {worst}");
}

fn textured(syntax_v4: bool, file: &str) -> String {
    let base = root().join("pbrt-scenes/verify/textures").join(file);
    let path = base.display();
    if syntax_v4 {
        format!(
            "WorldBegin Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"{path}\" \
             Material \"diffuse\" \"texture reflectance\" \"t\" Shape \"sphere\""
        )
    } else {
        format!(
            "Film \"image\" WorldBegin Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"{path}\" \
             Material \"matte\" \"texture Kd\" \"t\" Shape \"sphere\" WorldEnd"
        )
    }
}

/// pbrt-v3 reads EXR, PNG, TGA and PFM; the others are its grey texel there, named in
/// a warning, and read in a pbrt-v4 file.
#[test]
fn each_version_reads_the_formats_its_pbrt_reads() {
    for file in ["fmt-bottomup.tga", "fmt.pfm", "fmt.png"] {
        for v4 in [false, true] {
            let w = warnings(&scene(&textured(v4, file)));
            assert!(w.is_empty(), "{file} (v4 {v4}): {w:?}");
        }
    }
    for (file, format) in [
        ("fmt.jpg", "JPEG"),
        ("fmt.hdr", "HDR"),
        ("fmt.bmp", "BMP"),
        ("fmt.gif", "GIF"),
        ("fmt.ppm", "PNM"),
        ("fmt.qoi", "QOI"),
    ] {
        let w = warnings(&scene(&textured(false, file)));
        let expected = format!("pbrt-v3 does not read {format} images");
        assert!(w.len() == 1 && w[0].contains(&expected), "{file}: {w:?}");
        let w = warnings(&scene(&textured(true, file)));
        assert!(w.is_empty(), "{file} (v4): {w:?}");
    }
}

/// pbrt-v4's `encoding` names `linear`, `sRGB` or `gamma g`; anything else is an
/// error at the parameter, as in pbrt-v4.
#[test]
fn an_unknown_encoding_is_a_located_error() {
    let png = root().join("pbrt-scenes/verify/textures/fmt.png");
    for (encoding, why) in [("gamma two", "is not a gamma value"), ("srgb8", "is not a colour encoding")] {
        let text = format!(
            "WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"{}\" \"string encoding\" \"{encoding}\" \
             Material \"diffuse\" \"texture reflectance\" \"t\" Shape \"sphere\"",
            png.display()
        );
        let Err(err) = crate::common::load(&text) else { panic!("{encoding}: loaded") };
        let err = err.to_string();
        assert!(err.contains("inline.pbrt:2:") && err.contains(why), "{encoding}: {err}");
    }
    let text = format!(
        "WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"{}\" \"string encoding\" \"gamma 2.2\" \
         Material \"diffuse\" \"texture reflectance\" \"t\" Shape \"sphere\"",
        png.display()
    );
    assert!(crate::common::load(&text).is_ok());
}

/// A name of no format we read, and a damaged file of a known one, are located
/// warnings (the grey texel), never a panic.
#[test]
fn unknown_and_damaged_images_are_named() {
    let files = [
        ("bad.tga", "not a targa"),
        ("bad.pfm", "PF\n2 2\n-1\n\0\0"),
        ("x.tiff", ""),
        ("bad.qoi", "qoif"),
        ("text.ppm", "P3\n1 1\n255\n0 0 0\n"),
        ("empty.ppm", "P6\n0 0\n255\n"),
    ];
    let d = scratch("formats", "damaged", &files);
    for (file, why) in [
        ("bad.tga", "not a readable TGA"),
        ("bad.pfm", "the pixels end early"),
        ("x.tiff", "no image format"),
        ("bad.qoi", "not a readable QOI"),
        // pbrt-v4's stb_image reads binary PNM alone.
        ("text.ppm", "binary PGM and PPM (P5, P6) only"),
        ("empty.ppm", "it has no pixels"),
    ] {
        let text = format!(
            "WorldBegin Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"{}\" \
             Material \"diffuse\" \"texture reflectance\" \"t\" Shape \"sphere\"",
            d.join(file).display()
        );
        let w = warnings(&scene(&text));
        assert!(w.len() == 1 && w[0].contains(why), "{file}: {w:?}");
    }
}
