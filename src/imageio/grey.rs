//! One value a texel, for float image textures, as each pbrt makes it:
//!
//! ```text
//! Texture "bumps" "float" "imagemap" "string filename" "bumps.png"     # v3: luminance
//! Texture "cut" "float" "imagemap" "string filename" "leaf.png"        # v4: its alpha
//! Material "diffuse" "texture displacement" "bumps"
//! Shape "trianglemesh" "texture alpha" "cut" ...
//! ```
//!
//! pbrt-v3 takes the luminance of the values the file holds (an 8-bit image's bytes
//! over 255, alpha dropped) and then applies `gamma`. pbrt-v4's bilinear lookup takes
//! a PNG's, a QOI's or an EXR's alpha where it has one that is not all opaque, else the
//! mean of the colour channels (a grey image's one channel: an EXR's `Y`, or its only
//! channel, [`super::exr_read`]); a PNG's values, alpha included, are decoded by its
//! `encoding`, a QOI's as its header says, the other 8-bit formats' always as sRGB
//! (stb_image, which drops alpha).

use super::formats::{self, Format};
use super::{ColorEncoding, ImageError, Res, RgbImage, Texels, from_srgb};

/// How a float texture makes one value of a texel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Grey {
    /// pbrt-v3: the luminance of the stored values, sRGB-decoded if `decode`.
    V3 { decode: bool },
    /// pbrt-v4: alpha or the mean, a PNG's values made linear by its `encoding`.
    V4 { png: ColorEncoding },
}

/// pbrt-v3's luminance weights (its `RGBSpectrum::y`).
fn luminance(c: [f32; 3]) -> f32 {
    0.212671 * c[0] + 0.715160 * c[1] + 0.072169 * c[2]
}

/// The grey texels of an image of `format` in `bytes` (its size already checked).
pub(super) fn decode_grey(bytes: &[u8], format: Format, grey: Grey) -> Res<Texels> {
    let (width, height, values): (usize, usize, Vec<f32>) = match format {
        Format::Exr | Format::Pfm => {
            let v4 = matches!(grey, Grey::V4 { .. });
            let (img, alpha) = match format {
                Format::Exr => {
                    let e = super::exr_read::decode_exr_alpha(bytes, v4)?;
                    (e.image, e.alpha.filter(|a| a.iter().any(|&v| v != 1.0)))
                }
                _ => (formats::decode_pfm(bytes)?, None),
            };
            let f = |c: [f32; 3]| match grey {
                Grey::V3 { decode } => stored_luminance(c, decode),
                Grey::V4 { .. } => (c[0] + c[1] + c[2]) / 3.0,
            };
            let values = alpha.unwrap_or_else(|| img.pixels.iter().map(|&c| f(c)).collect());
            (img.width, img.height, values)
        }
        _ => {
            let img = formats::decode_codec(bytes, format)?;
            let (w, h) = (img.width() as usize, img.height() as usize);
            (w, h, codec_values(&img, format, format.srgb_bytes(bytes), grey))
        }
    };
    if values.len() != width * height {
        return Err(ImageError::decode("the image's pixels do not match its size"));
    }
    Ok(Texels::from_image(RgbImage::from_pixels(width, height, values.into_iter().map(|v| [v; 3]).collect())))
}

fn stored_luminance(c: [f32; 3], decode: bool) -> f32 {
    let y = luminance(c);
    if decode { from_srgb(y) } else { y }
}

/// The values of an image `image` decoded: `to_rgba32f` gives 8- and 16-bit values
/// over their largest, as pbrt divides them.
fn codec_values(img: &image::DynamicImage, format: Format, srgb: bool, grey: Grey) -> Vec<f32> {
    let rgba = img.to_rgba32f();
    match grey {
        Grey::V3 { decode } => rgba.pixels().map(|p| stored_luminance([p[0], p[1], p[2]], decode)).collect(),
        Grey::V4 { png } => {
            let d = |v: f32| match format {
                Format::Png => png.to_linear(v),
                f if f.eight_bit() && srgb => from_srgb(v),
                _ => v,
            };
            let colour_alpha = matches!(img.color(), image::ColorType::Rgba8 | image::ColorType::Rgba16);
            let alpha = format.keeps_alpha() && colour_alpha && rgba.pixels().any(|p| p[3] != 1.0);
            match alpha {
                true => rgba.pixels().map(|p| d(p[3])).collect(),
                false => rgba.pixels().map(|p| (d(p[0]) + d(p[1]) + d(p[2])) / 3.0).collect(),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imageio::TexelSource;

    fn png(img: image::DynamicImage) -> Vec<u8> {
        let mut bytes = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).expect("encode");
        bytes
    }

    fn first(bytes: &[u8], grey: Grey) -> f32 {
        decode_grey(bytes, Format::Png, grey).expect("decodes").texel(0)[0]
    }

    /// A coloured texel: pbrt-v3's luminance of the bytes, then gamma; pbrt-v4's mean
    /// of the decoded channels, or of the stored ones where linear.
    #[test]
    fn each_version_makes_its_grey_of_a_coloured_texel() {
        let bytes = png(image::DynamicImage::ImageRgb8(image::RgbImage::from_pixel(1, 1, image::Rgb([200, 100, 50]))));
        let c = [200.0 / 255.0, 100.0 / 255.0, 50.0 / 255.0];
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        assert!(close(first(&bytes, Grey::V3 { decode: false }), luminance(c)));
        assert!(close(first(&bytes, Grey::V3 { decode: true }), from_srgb(luminance(c))));
        assert!(close(first(&bytes, Grey::V4 { png: ColorEncoding::Linear }), (c[0] + c[1] + c[2]) / 3.0));
        let mean = c.map(from_srgb).iter().sum::<f32>() / 3.0;
        assert!(close(first(&bytes, Grey::V4 { png: ColorEncoding::Srgb }), mean));
        let gamma = ColorEncoding::Gamma(1.6f32.to_bits());
        let powered = c.map(|v| v.powf(1.6)).iter().sum::<f32>() / 3.0;
        assert!(close(first(&bytes, Grey::V4 { png: gamma }), powered));
    }

    /// pbrt-v4 takes a PNG's alpha, decoded as its colours are, where it is not all
    /// opaque; an opaque alpha leaves the mean; pbrt-v3 ignores alpha.
    #[test]
    fn pbrt_v4_takes_a_pngs_alpha_where_it_cuts() {
        let rgba = |a: u8| {
            png(image::DynamicImage::ImageRgba8(image::RgbaImage::from_fn(2, 1, |x, _| {
                image::Rgba([255, 255, 255, if x == 0 { a } else { 255 }])
            })))
        };
        let cut = rgba(64);
        assert!((first(&cut, Grey::V4 { png: ColorEncoding::Linear }) - 64.0 / 255.0).abs() < 1e-6);
        assert!((first(&cut, Grey::V4 { png: ColorEncoding::Srgb }) - from_srgb(64.0 / 255.0)).abs() < 1e-6);
        assert!((first(&cut, Grey::V3 { decode: false }) - 1.0).abs() < 1e-5);
        assert!((first(&rgba(255), Grey::V4 { png: ColorEncoding::Srgb }) - 1.0).abs() < 1e-6);
    }

    /// The same rule for an EXR's alpha, and a grey EXR's one channel for either pbrt.
    #[test]
    fn pbrt_v4_takes_an_exrs_alpha_where_it_cuts() {
        use crate::imageio::exr_read::tests::exr_of;
        let value = |alpha: f32| move |c: usize, x: usize| if c == 3 { [alpha, 1.0][x] } else { [0.2, 0.4, 0.9][c] };
        let exr = exr_of(&["R", "G", "B", "A"], value(0.25));
        let texel = |bytes: &[u8], grey| decode_grey(bytes, Format::Exr, grey).expect("decodes").texel(0)[0];
        let v4 = Grey::V4 { png: ColorEncoding::Srgb };
        assert_eq!(texel(&exr, v4), 0.25);
        assert!((texel(&exr, Grey::V3 { decode: false }) - luminance([0.2, 0.4, 0.9])).abs() < 1e-6);
        let opaque = exr_of(&["R", "G", "B", "A"], value(1.0));
        assert!((texel(&opaque, v4) - 0.5).abs() < 1e-6);
        let grey = exr_of(&["Y"], |_, _| 0.3);
        assert!((texel(&grey, v4) - 0.3).abs() < 1e-6);
        assert!((texel(&grey, Grey::V3 { decode: false }) - 0.3).abs() < 1e-6);
    }
}
