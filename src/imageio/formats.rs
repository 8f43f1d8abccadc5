//! The image formats a scene names, told apart by the file name's extension as pbrt
//! tells them apart:
//!
//! ```text
//! Texture "wood" "spectrum" "imagemap" "string filename" "wood.tga"    # v3 and v4
//! LightSource "infinite" "string filename" "sky.pfm"                   # v3 and v4
//! Texture "tile" "spectrum" "imagemap" "string filename" "tile.jpg"    # v4
//! ```
//!
//! pbrt-v3 reads EXR, PNG, TGA and PFM; pbrt-v4 reads those, QOI with its own reader,
//! and, through stb_image, HDR, JPEG, BMP, GIF (its first frame) and binary PGM and PPM
//! (`P5`, `P6`) as well. The 8-bit formats store sRGB-encoded values (a QOI file may
//! mark its own as linear, which pbrt-v4 honours); EXR, PFM and HDR store linear floats.
//! stb_image's formats lose their alpha in pbrt-v4; PNG and QOI keep it. PFM is read
//! here, as pbrt reads it: rows bottom to top, the header's scale giving the byte order
//! by its sign and multiplying every value by its magnitude.

use super::{ImageError, Res, RgbImage};
use std::path::Path;

/// An image file's format, from its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Exr,
    Png,
    Tga,
    Pfm,
    Hdr,
    Jpeg,
    Bmp,
    Gif,
    Pnm,
    Qoi,
}

/// The names [`Format::of`] knows, for messages.
pub const KNOWN: &str =
    ".exr, .png, .tga, .pfm (pbrt-v3 and pbrt-v4), .hdr, .jpg, .jpeg, .bmp, .gif, .ppm, .pgm, .pnm, .qoi (pbrt-v4)";

impl Format {
    /// The format a file name's extension names (any case), if one we read.
    pub fn of(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "exr" => Format::Exr,
            "png" => Format::Png,
            "tga" => Format::Tga,
            "pfm" => Format::Pfm,
            "hdr" => Format::Hdr,
            "jpg" | "jpeg" => Format::Jpeg,
            "bmp" => Format::Bmp,
            "gif" => Format::Gif,
            "ppm" | "pgm" | "pnm" => Format::Pnm,
            "qoi" => Format::Qoi,
            _ => return None,
        })
    }

    /// 8 bits a channel, sRGB-encoded (read decoded unless a scene asks otherwise).
    pub fn eight_bit(self) -> bool {
        matches!(self, Format::Png | Format::Tga | Format::Jpeg | Format::Bmp | Format::Gif | Format::Pnm | Format::Qoi)
    }

    /// Whether pbrt-v4 keeps the file's alpha, for float textures to take (it reads
    /// the other 8-bit formats through stb_image and keeps their colour alone).
    pub fn keeps_alpha(self) -> bool {
        matches!(self, Format::Png | Format::Qoi)
    }

    /// Whether the 8-bit values in `bytes` are sRGB-encoded: all but those of a QOI
    /// file whose header marks them linear (its 14th byte, the colour space, is 1;
    /// pbrt-v4 reads them so).
    pub fn srgb_bytes(self, bytes: &[u8]) -> bool {
        !(self == Format::Qoi && bytes.get(13) == Some(&1))
    }

    /// Whether pbrt-v3's `ReadImage` reads it (pbrt-v4 reads every format here).
    pub fn read_by_pbrt_v3(self) -> bool {
        matches!(self, Format::Exr | Format::Png | Format::Tga | Format::Pfm)
    }

    /// Whether a scene's encoding parameter (v3 `gamma`, v4 `encoding`) reaches the
    /// values: pbrt-v4 reads every 8-bit format but PNG through stb_image, which it
    /// always takes as sRGB.
    pub fn encoding_is_the_files(self, v3: bool) -> bool {
        self == Format::Png || (v3 && self == Format::Tga)
    }

    fn codec(self) -> Option<image::ImageFormat> {
        Some(match self {
            Format::Png => image::ImageFormat::Png,
            Format::Tga => image::ImageFormat::Tga,
            Format::Hdr => image::ImageFormat::Hdr,
            Format::Jpeg => image::ImageFormat::Jpeg,
            Format::Bmp => image::ImageFormat::Bmp,
            Format::Gif => image::ImageFormat::Gif,
            Format::Pnm => image::ImageFormat::Pnm,
            Format::Qoi => image::ImageFormat::Qoi,
            Format::Exr | Format::Pfm => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            Format::Exr => "EXR",
            Format::Png => "PNG",
            Format::Tga => "TGA",
            Format::Pfm => "PFM",
            Format::Hdr => "HDR",
            Format::Jpeg => "JPEG",
            Format::Bmp => "BMP",
            Format::Gif => "GIF",
            Format::Pnm => "PNM",
            Format::Qoi => "QOI",
        }
    }
}

/// Width and height from the header alone (EXR is [`super`]'s).
pub(super) fn dimensions(bytes: &[u8], format: Format) -> Res<(u64, u64)> {
    let unreadable = |e: &dyn std::fmt::Display| ImageError::decode(format!("not a readable {}: {e}", format.name()));
    match format.codec() {
        Some(codec) => {
            let (w, h) = image::ImageReader::with_format(std::io::Cursor::new(bytes), codec)
                .into_dimensions()
                .map_err(|e| unreadable(&e))?;
            Ok((w as u64, h as u64))
        }
        None => Pfm::header(bytes).map(|h| (h.width as u64, h.height as u64)).map_err(|e| unreadable(&e)),
    }
}

/// pbrt-v4's stb_image reads binary PGM and PPM alone (`P5`, `P6`), not the text
/// (`P1`–`P3`), bitmap (`P4`) or PAM (`P7`) kinds `image` would read too.
fn binary_pnm(bytes: &[u8], format: Format) -> Res<()> {
    match format == Format::Pnm && !(bytes.starts_with(b"P5") || bytes.starts_with(b"P6")) {
        true => Err(ImageError::decode("pbrt-v4 reads binary PGM and PPM (P5, P6) only")),
        false => Ok(()),
    }
}

/// An image of a format `image` decodes, as that crate gives it.
pub(super) fn decode_codec(bytes: &[u8], format: Format) -> Res<image::DynamicImage> {
    binary_pnm(bytes, format)?;
    let codec = format.codec().ok_or_else(|| ImageError::decode(format!("no codec for {}", format.name())))?;
    image::load_from_memory_with_format(bytes, codec)
        .map_err(|e| ImageError::decode(format!("not a readable {}: {e}", format.name())))
}

/// A PFM file's header: `PF` (colour) or `Pf` (grey), width, height and scale, each
/// a word followed by one whitespace byte.
struct Pfm {
    channels: usize,
    width: usize,
    height: usize,
    scale: f32,
    data_at: usize,
}

impl Pfm {
    fn header(bytes: &[u8]) -> Result<Pfm, String> {
        let mut at = 0;
        let mut word = || -> Result<&str, String> {
            while bytes.get(at).is_some_and(u8::is_ascii_whitespace) {
                at += 1;
            }
            let start = at;
            while bytes.get(at).is_some_and(|b| !b.is_ascii_whitespace()) {
                at += 1;
            }
            let w = std::str::from_utf8(&bytes[start..at]).map_err(|_| "a header word is not text".to_string())?;
            if w.is_empty() || at >= bytes.len() {
                return Err("the header ends early".into());
            }
            at += 1;
            Ok(w)
        };
        let channels = match word()? {
            "PF" => 3,
            "Pf" => 1,
            other => return Err(format!("\"{other}\" is not PF or Pf")),
        };
        let size = |w: &str| w.parse::<usize>().ok().filter(|&n| n > 0).ok_or(format!("bad size \"{w}\""));
        let width = size(word()?)?;
        let height = size(word()?)?;
        let scale = word()?;
        let scale =
            scale.parse::<f32>().ok().filter(|s| s.is_finite() && *s != 0.0).ok_or(format!("bad scale \"{scale}\""))?;
        Ok(Pfm { channels, width, height, scale, data_at: at })
    }
}

/// A PFM's pixels, top row first.
pub(super) fn decode_pfm(bytes: &[u8]) -> Res<RgbImage> {
    let bad = |e: String| ImageError::decode(format!("not a readable PFM: {e}"));
    let h = Pfm::header(bytes).map_err(bad)?;
    let row = h.channels * h.width;
    let need = row.checked_mul(h.height).and_then(|n| n.checked_mul(4)).ok_or_else(|| bad("too large".into()))?;
    let data = bytes.get(h.data_at..).filter(|d| d.len() >= need).ok_or_else(|| bad("the pixels end early".into()))?;
    let little = h.scale < 0.0;
    let scale = h.scale.abs();
    let value = |i: usize| {
        let b: [u8; 4] = data[4 * i..4 * i + 4].try_into().expect("four bytes");
        let v = if little { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) };
        // As pbrt: a scale of magnitude 1 leaves the values' bits alone.
        if scale != 1.0 { v * scale } else { v }
    };
    let mut pixels = Vec::with_capacity(h.width * h.height);
    for y in (0..h.height).rev() {
        for x in 0..h.width {
            let i = y * row + x * h.channels;
            pixels.push(if h.channels == 3 { [value(i), value(i + 1), value(i + 2)] } else { [value(i); 3] });
        }
    }
    Ok(RgbImage::from_pixels(h.width, h.height, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pfm(magic: &str, w: usize, h: usize, scale: &str, values: &[f32], little: bool) -> Vec<u8> {
        let mut bytes = format!("{magic}\n{w} {h}\n{scale}\n").into_bytes();
        for v in values {
            bytes.extend(if little { v.to_le_bytes() } else { v.to_be_bytes() });
        }
        bytes
    }

    /// Rows run bottom to top; the scale's sign is the byte order and its magnitude
    /// multiplies; grey files give grey pixels.
    #[test]
    fn pfm_reads_as_pbrt_reads_it() {
        let values = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let little = decode_pfm(&pfm("PF", 1, 2, "-1.0", &values, true)).unwrap();
        assert_eq!(little.pixels, vec![[4.0, 5.0, 6.0], [1.0, 2.0, 3.0]]);
        let big = decode_pfm(&pfm("PF", 1, 2, "2", &values, false)).unwrap();
        assert_eq!(big.pixels, vec![[8.0, 10.0, 12.0], [2.0, 4.0, 6.0]]);
        let grey = decode_pfm(&pfm("Pf", 2, 1, "-1", &[0.25, 0.5], true)).unwrap();
        assert_eq!(grey.pixels, vec![[0.25; 3], [0.5; 3]]);
        assert_eq!(dimensions(&pfm("Pf", 2, 1, "-1", &[0.25, 0.5], true), Format::Pfm).unwrap(), (2, 1));
    }

    /// Damaged headers and short data are errors, never a panic or a wrong image.
    #[test]
    fn damaged_pfms_are_refused() {
        for bytes in [
            pfm("P6", 1, 1, "-1", &[0.0; 3], true),
            pfm("PF", 2, 2, "-1", &[0.0; 11], true),
            pfm("PF", 0, 2, "-1", &[], true),
            pfm("PF", 1, 1, "0", &[0.0; 3], true),
            pfm("PF", 1, 1, "nan", &[0.0; 3], true),
            b"PF\n1".to_vec(),
            b"PF 99999999999 99999999999 -1 ".to_vec(),
            Vec::new(),
        ] {
            assert!(decode_pfm(&bytes).is_err(), "{:?}", String::from_utf8_lossy(&bytes));
        }
    }

    #[test]
    fn formats_follow_the_extension_in_any_case() {
        assert_eq!(Format::of(Path::new("a/b.TGA")), Some(Format::Tga));
        assert_eq!(Format::of(Path::new("b.jpeg")), Some(Format::Jpeg));
        assert_eq!(Format::of(Path::new("b.tiff")), None);
        assert_eq!(Format::of(Path::new("b")), None);
        assert!(Format::Tga.eight_bit() && !Format::Hdr.eight_bit() && !Format::Jpeg.read_by_pbrt_v3());
    }
}
