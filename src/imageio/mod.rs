//! Image files: EXR (32-bit float R, G, B, ZIP scanlines; data window = crop window;
//! pbrt's metadata keys) and 8-bit sRGB PNG previews. Writes go to a temporary file in
//! the same folder and are renamed into place, so a crash never leaves half an image.
//! Reading accepts half and float EXRs (pbrt-v3 writes half, pbrt-v4 float), and the
//! other formats scenes name ([`formats`]).

mod exr_read;
mod exr_zip;
pub mod formats;
pub mod grey;
pub mod lookup;
pub mod metrics;
pub mod tev;
pub mod texels;

pub use formats::Format;
pub use grey::Grey;
pub use lookup::{TexelSource, Wrap, lookup};
pub use texels::Texels;

use exr::image::write::layers::WritableLayers;
use exr::prelude::*;
use exr_read::decode_exr;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// exr's prelude has its own `Result`.
type Res<T> = std::result::Result<T, ImageError>;

/// Why an image (or another file written atomically) cannot be read or written.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("cannot read \"{}\": {why}", path.display())]
    Read { path: PathBuf, why: String },
    #[error("cannot write \"{}\": {why}", path.display())]
    Write { path: PathBuf, why: String },
    #[error("cannot rename to \"{}\": {why}", path.display())]
    Rename { path: PathBuf, why: std::io::Error },
    #[error("\"{}\" is a folder", path.display())]
    Folder { path: PathBuf },
    #[error("\"{}\": an image name must end in .exr or .png", path.display())]
    Extension { path: PathBuf },
    /// Bytes that are not an image of the format, or not one we read.
    #[error("{why}")]
    Decode { why: String },
    /// Past a limit (`--limit file-bytes`, `texture-pixels`), or a scene's input file
    /// that cannot be read; the message says which.
    #[error("{0}")]
    Input(String),
    #[error("\"{}\": {source}", path.display())]
    In { path: PathBuf, source: Box<ImageError> },
}

impl ImageError {
    /// A failed write of `path` for the reason `why`.
    pub fn write(path: &Path, why: impl std::fmt::Display) -> ImageError {
        ImageError::Write { path: path.to_path_buf(), why: why.to_string() }
    }

    fn read(path: &Path, why: impl std::fmt::Display) -> ImageError {
        ImageError::Read { path: path.to_path_buf(), why: why.to_string() }
    }

    fn decode(why: impl std::fmt::Display) -> ImageError {
        ImageError::Decode { why: why.to_string() }
    }
}

/// Metadata written into EXR headers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImageMeta {
    pub render_time_seconds: Option<f32>,
    /// SPPM iterations.
    pub samples_per_pixel: Option<i32>,
    pub photons_per_iteration: Option<i64>,
    /// Row-major.
    pub world_to_camera: Option<[f32; 16]>,
    pub software: Option<String>,
}

/// Channels written after R, G and B: a spectral film's buckets.
#[derive(Clone, Debug, PartialEq)]
pub struct Bands {
    /// Channel names (`S0.374,688nm`), in wavelength order.
    pub names: Vec<String>,
    /// Per pixel, one value per name.
    pub values: Vec<f32>,
}

/// An RGB image: the data window of a larger display window.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
    /// A spectral film's buckets (EXR only; pbrt-v4's spectral layout).
    pub bands: Option<Bands>,
    /// Top-left corner of the data window in the display window.
    pub origin: (i32, i32),
    /// Size of the display window (the full resolution).
    pub full: (usize, usize),
    pub meta: ImageMeta,
}

impl RgbImage {
    /// A black image covering the whole display window.
    pub fn new(width: usize, height: usize) -> RgbImage {
        RgbImage::from_pixels(width, height, vec![[0.0; 3]; width * height])
    }

    /// An image of `pixels`, row by row, covering the whole display window.
    pub fn from_pixels(width: usize, height: usize, pixels: Vec<[f32; 3]>) -> RgbImage {
        RgbImage {
            width,
            height,
            pixels,
            bands: None,
            origin: (0, 0),
            full: (width, height),
            meta: ImageMeta::default(),
        }
    }
}

/// A temporary file beside `path` and the final rename, so no reader sees a half file.
pub fn atomically(path: &Path, write: impl FnOnce(&Path) -> Res<()>) -> Res<()> {
    let tmp = temp_path(path);
    let result = write(&tmp)
        .and_then(|_| std::fs::rename(&tmp, path).map_err(|why| ImageError::Rename { path: path.to_path_buf(), why }));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The temporary name beside `path` that [`atomically`] writes first.
fn temp_path(path: &Path) -> PathBuf {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
    dir.join(format!(".{name}.{}.tmp.{ext}", std::process::id()))
}

/// Writes text atomically (reports, CSV files).
pub fn write_text(path: &Path, text: &str) -> Res<()> {
    atomically(path, |tmp| std::fs::write(tmp, text).map_err(|e| ImageError::write(path, e)))
}

/// Writes by extension: `.exr`, or `.png` for an sRGB preview; any other name is an
/// error (never EXR bytes under another format's name).
pub fn write_image(path: &Path, img: &RgbImage) -> Res<()> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("png") => write_png(path, img),
        Some("exr") => write_exr(path, img),
        _ => Err(ImageError::Extension { path: path.to_path_buf() }),
    }
}

/// Checks, before any work, that a file can be written at `path`: its folder exists and
/// takes a new file (made and removed again), and `path` is not a folder.
pub fn check_writable(path: &Path) -> Res<()> {
    if path.is_dir() {
        return Err(ImageError::Folder { path: path.to_path_buf() });
    }
    let tmp = temp_path(path);
    std::fs::File::create(&tmp).map_err(|e| ImageError::write(path, e))?;
    let _ = std::fs::remove_file(&tmp);
    Ok(())
}

pub fn write_exr(path: &Path, img: &RgbImage) -> Res<()> {
    write_exr_as(path, img, false)
}

/// Half-float RGB (pbrt-v3's output format; small reference images).
pub fn write_exr_half(path: &Path, img: &RgbImage) -> Res<()> {
    write_exr_as(path, img, true)
}

fn write_exr_as(path: &Path, img: &RgbImage, half: bool) -> Res<()> {
    let mut attrs = LayerAttributes::named("");
    attrs.layer_position = Vec2(img.origin.0, img.origin.1);
    attrs.software_name = img.meta.software.as_deref().map(Text::from);
    attrs.world_to_camera = img.meta.world_to_camera;
    let mut put = |k: &str, v: AttributeValue| {
        attrs.other.insert(Text::from(k), v);
    };
    if let Some(t) = img.meta.render_time_seconds {
        put("renderTimeSeconds", AttributeValue::F32(t));
    }
    if let Some(n) = img.meta.samples_per_pixel {
        put("samplesPerPixel", AttributeValue::I32(n));
    }
    if let Some(n) = img.meta.photons_per_iteration {
        put("photonsPerIteration", AttributeValue::I32(n.min(i32::MAX as i64) as i32));
    }
    let (w, pixels, size, full) = (img.width, &img.pixels, (img.width, img.height), img.full);
    let fail = |e: exr::error::Error| ImageError::write(path, e);
    if let Some(bands) = &img.bands {
        put("spectralLayoutVersion", AttributeValue::Text(Text::from("1.0")));
        put("emissiveUnits", AttributeValue::Text(Text::from("W.m^-2.sr^-1")));
        let layer = Layer::new(size, attrs, Encoding::SMALL_LOSSLESS, spectral_channels(pixels, bands));
        let mut image = Image::from_layer(layer);
        image.attributes.display_window = IntegerBounds::new((0, 0), full);
        return atomically(path, |tmp| image.write().to_file(tmp).map_err(fail));
    }
    if half {
        let h = |v: f32| exr::prelude::f16::from_f32(v);
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| pixels[y * w + x].map(h).into());
        let mut image = Image::from_layer(Layer::new(size, attrs, Encoding::SMALL_LOSSLESS, channels));
        image.attributes.display_window = IntegerBounds::new((0, 0), full);
        return atomically(path, |tmp| image.write().to_file(tmp).map_err(fail));
    }
    // The header as `exr` makes it; the blocks compressed here ([`exr_zip`]).
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| pixels[y * w + x].into());
    let mut image = Image::from_layer(Layer::new(size, attrs, Encoding::SMALL_LOSSLESS, channels));
    image.attributes.display_window = IntegerBounds::new((0, 0), full);
    let headers = image.layer_data.infer_headers(&image.attributes);
    atomically(path, |tmp| {
        let file = std::io::BufWriter::new(std::fs::File::create(tmp).map_err(|e| ImageError::write(path, e))?);
        exr::block::write(file, headers, true, |meta, chunks| exr_zip::write_blocks(&meta, chunks, pixels, w))
            .map_err(fail)
    })
}

/// R, G, B and a spectral film's buckets, as 32-bit floats.
fn spectral_channels(pixels: &[[f32; 3]], bands: &Bands) -> AnyChannels<FlatSamples> {
    let n = bands.names.len();
    let rgb = ["R", "G", "B"].into_iter().enumerate().map(|(c, name)| (name, pixels.iter().map(|p| p[c]).collect()));
    let buckets =
        bands.names.iter().enumerate().map(|(b, name)| {
            (name.as_str(), bands.values.iter().skip(b).step_by(n.max(1)).copied().collect::<Vec<f32>>())
        });
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> =
        rgb.chain(buckets).map(|(name, v)| AnyChannel::new(name, FlatSamples::F32(v))).collect();
    AnyChannels::sort(list)
}

/// A spectral film's buckets in an EXR (channels `S0.<λ>nm`, in wavelength order), or
/// `None` when it has none.
pub fn read_bands(path: &Path) -> Res<Option<Bands>> {
    let bytes = std::fs::read(path).map_err(|e| ImageError::read(path, e))?;
    let max = crate::limits::Limits::default().pixels;
    let image = decode_all_channels(&bytes, "image", max).map_err(|e| ImageError::read(path, e))?;
    let list = &image.layer_data.channel_data.list;
    let nm = |c: &AnyChannel<FlatSamples>| -> Option<f64> {
        let name = c.name.to_string();
        name.strip_prefix("S0.")?.strip_suffix("nm")?.replace(',', ".").parse().ok()
    };
    let mut found: Vec<(f64, &AnyChannel<FlatSamples>)> = list.iter().filter_map(|c| Some((nm(c)?, c))).collect();
    if found.is_empty() {
        return Ok(None);
    }
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = found.len();
    let pixels = found[0].1.sample_data.len();
    let mut values = vec![0f32; pixels * n];
    for (b, (_, c)) in found.iter().enumerate() {
        for (i, v) in c.sample_data.values_as_f32().enumerate() {
            values[i * n + b] = v;
        }
    }
    Ok(Some(Bands { names: found.iter().map(|(_, c)| c.name.to_string()).collect(), values }))
}

/// Every channel of an EXR's first layer; refused from the header alone when it has
/// more than `max_pixels` pixels (`what` names the file in that message).
pub fn decode_all_channels(
    bytes: &[u8],
    what: &str,
    max_pixels: u64,
) -> std::result::Result<Image<Layer<AnyChannels<FlatSamples>>>, String> {
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| format!("not a readable EXR ({e})"))?;
    let size = meta.headers.first().map_or(Vec2(0, 0), |h| h.layer_size);
    if (size.width() as u64).saturating_mul(size.height() as u64) > max_pixels {
        let pixels = format!("the {what}'s {}x{} pixels", size.width(), size.height());
        return Err(crate::limits::Limits::over(pixels, "pixels", max_pixels));
    }
    read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| format!("not a readable EXR ({e})"))
}

/// The sRGB transfer curve.
pub fn to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

/// pbrt-v4's `encoding` of 8-bit values: `"sRGB"`, `"linear"` or `"gamma g"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorEncoding {
    Srgb,
    Linear,
    /// x^g, g kept as its bits (so the encoding can key a cache).
    Gamma(u32),
}

impl ColorEncoding {
    /// An 8-bit value over 255, made linear.
    pub fn to_linear(self, x: f32) -> f32 {
        match self {
            ColorEncoding::Srgb => from_srgb(x),
            ColorEncoding::Linear => x,
            ColorEncoding::Gamma(g) => x.powf(f32::from_bits(g)),
        }
    }
}

pub fn from_srgb(v: f32) -> f32 {
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

pub fn write_png(path: &Path, img: &RgbImage) -> Res<()> {
    let bytes: Vec<u8> = img.pixels.iter().flat_map(|p| p.map(|c| (to_srgb(c) * 255.0).round() as u8)).collect();
    let buf = image::RgbImage::from_raw(img.width as u32, img.height as u32, bytes)
        .ok_or_else(|| ImageError::write(path, "the image size does not match its pixels"))?;
    atomically(path, |tmp| buf.save_with_format(tmp, image::ImageFormat::Png).map_err(|e| ImageError::write(path, e)))
}

/// How an 8-bit image's values become floats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EightBit {
    /// sRGB-decoded (textures, and every image of a pbrt-v4 file).
    Srgb,
    /// Each byte over 255, as pbrt-v3's `ReadImage` gives them to its lights.
    Raw,
}

/// Reads an image for a scene: a regular file within `limits.file_bytes`, whose size
/// (from its header, before decoding) is within `limits.texture_pixels`.
pub fn read_image_within(path: &Path, files: &crate::limits::Files, eight_bit: EightBit) -> Res<RgbImage> {
    read_scene_image(path, files, |bytes, format| decode_any(bytes, format, eight_bit))
}

/// A scene's image by `decode`: its format named by its extension, its file within
/// `limits.file_bytes` and its size (from the header) within `limits.texture_pixels`;
/// errors name the file.
fn read_scene_image<T>(
    path: &Path,
    files: &crate::limits::Files,
    decode: impl FnOnce(&[u8], Format) -> Res<T>,
) -> Res<T> {
    let within = || {
        let format = Format::of(path)
            .ok_or_else(|| ImageError::decode(format!("no image format is named so (known: {})", formats::KNOWN)))?;
        let bytes = files.read(path).map_err(ImageError::Input)?;
        check_pixels(&bytes, format, files.limits.texture_pixels)?;
        decode(&bytes, format)
    };
    within().map_err(|e| ImageError::In { path: path.to_path_buf(), source: Box::new(e) })
}

/// Decodes an image held in memory, refusing (from the header alone) images of more
/// than `max_pixels` pixels.
pub fn decode_image(bytes: &[u8], format: Format, eight_bit: EightBit, max_pixels: u64) -> Res<RgbImage> {
    check_pixels(bytes, format, max_pixels)?;
    decode_any(bytes, format, eight_bit)
}

fn decode_any(bytes: &[u8], format: Format, eight_bit: EightBit) -> Res<RgbImage> {
    match format {
        Format::Exr => decode_exr(bytes),
        Format::Pfm => formats::decode_pfm(bytes),
        _ => decode_codec(bytes, format, eight_bit),
    }
}

/// [`read_image_within`] for textures and normal maps: an 8-bit image is kept as its
/// bytes ([`Texels`]), sRGB-decoded when read.
pub fn read_texels_within(path: &Path, files: &crate::limits::Files) -> Res<Texels> {
    read_scene_image(path, files, |bytes, format| match format {
        Format::Exr => decode_exr(bytes).map(Texels::from_image),
        Format::Pfm => formats::decode_pfm(bytes).map(Texels::from_image),
        _ => decode_codec_texels(bytes, format),
    })
}

/// [`read_texels_within`] for float textures: one value a texel, made as `grey` says.
pub fn read_grey_texels_within(path: &Path, files: &crate::limits::Files, grey: Grey) -> Res<Texels> {
    read_scene_image(path, files, |bytes, format| grey::decode_grey(bytes, format, grey))
}

/// Refuses, from the header alone, an image without pixels or of more than `max_pixels`.
fn check_pixels(bytes: &[u8], format: Format, max_pixels: u64) -> Res<()> {
    let (w, h) = match format {
        Format::Exr => {
            let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
                .map_err(|e| ImageError::decode(format!("not a readable EXR: {e}")))?;
            let header =
                meta.headers.first().ok_or_else(|| ImageError::decode("not a readable EXR: no image in the file"))?;
            (header.layer_size.width() as u64, header.layer_size.height() as u64)
        }
        _ => formats::dimensions(bytes, format)?,
    };
    if w == 0 || h == 0 {
        return Err(ImageError::decode(format!("the image is {w}x{h}: it has no pixels")));
    }
    if w.saturating_mul(h) > max_pixels {
        let what = format!("the image's {w}x{h} pixels");
        return Err(ImageError::Input(crate::limits::Limits::over(what, "texture-pixels", max_pixels)));
    }
    Ok(())
}

/// Reads the first RGB(A) layer of an EXR (half or float), or another format by its
/// name (8-bit ones linearised); a name of no known format is read as EXR.
pub fn read_image(path: &Path) -> Res<RgbImage> {
    match Format::of(path).unwrap_or(Format::Exr) {
        Format::Exr => read_exr(path),
        format => {
            let bytes = std::fs::read(path).map_err(|e| ImageError::read(path, e))?;
            decode_any(&bytes, format, EightBit::Srgb).map_err(|e| ImageError::read(path, e))
        }
    }
}

pub fn read_exr(path: &Path) -> Res<RgbImage> {
    let bytes = std::fs::read(path).map_err(|e| ImageError::read(path, e))?;
    decode_exr(&bytes).map_err(|e| ImageError::read(path, e))
}

/// `decode` of each 8-bit value as `image` converts it to f32 from `img`'s colour
/// type (grey converts to slightly other values than colour): the values the general
/// path gives, bit for bit. `None` for other than 8-bit grey or colour.
fn eight_bit_table(img: &image::DynamicImage, decode: impl Fn(f32) -> f32) -> Option<[f32; 256]> {
    use image::DynamicImage as D;
    let values = || (0..=255u8).flat_map(|b| [b, b, b]);
    let row = match img {
        D::ImageLuma8(_) => D::ImageLuma8(image::GrayImage::from_raw(256, 1, (0..=255).collect())?),
        D::ImageLumaA8(_) => {
            D::ImageLumaA8(image::GrayAlphaImage::from_raw(256, 1, (0..=255).flat_map(|b| [b, 255]).collect())?)
        }
        D::ImageRgb8(_) => D::ImageRgb8(image::RgbImage::from_raw(256, 1, values().collect())?),
        D::ImageRgba8(_) => {
            D::ImageRgba8(image::RgbaImage::from_raw(256, 1, (0..=255).flat_map(|b| [b, b, b, 255]).collect())?)
        }
        _ => return None,
    }
    .to_rgb32f();
    Some(std::array::from_fn(|b| decode(row.get_pixel(b as u32, 0).0[0])))
}

impl EightBit {
    fn decode(self, v: f32) -> f32 {
        match self {
            EightBit::Srgb => from_srgb(v),
            EightBit::Raw => v,
        }
    }
}

/// An image `image` decodes as [`Texels`]: 8-bit ones as their bytes and the table of
/// [`eight_bit_table`], so that each texel reads as [`decode_codec`] would give it.
fn decode_codec_texels(bytes: &[u8], format: Format) -> Res<Texels> {
    let img = formats::decode_codec(bytes, format)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let decode: fn(f32) -> f32 = if format.srgb_bytes(bytes) { from_srgb } else { |v| v };
    Ok(match eight_bit_table(&img, decode) {
        Some(values) => Texels::from_bytes(w, h, img.into_rgb8().into_raw(), values),
        None => Texels::from_image(decode_wide(img, format, EightBit::Srgb)),
    })
}

fn decode_codec(bytes: &[u8], format: Format, eight_bit: EightBit) -> Res<RgbImage> {
    let img = formats::decode_codec(bytes, format)?;
    let eight_bit = if format.srgb_bytes(bytes) { eight_bit } else { EightBit::Raw };
    let (w, h) = (img.width() as usize, img.height() as usize);
    // Eight bits a channel: 256 values, decoded once each (a power per value was a
    // tenth of loading a scene of four 1024² textures).
    Ok(match eight_bit_table(&img, |v| eight_bit.decode(v)) {
        Some(decoded) => {
            RgbImage::from_pixels(w, h, img.to_rgb8().pixels().map(|p| p.0.map(|b| decoded[b as usize])).collect())
        }
        None => decode_wide(img, format, eight_bit),
    })
}

/// An image of other than 8-bit grey or colour: a 16-bit PNG decoded channel by
/// channel, or HDR's floats as they are.
fn decode_wide(img: image::DynamicImage, format: Format, eight_bit: EightBit) -> RgbImage {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let decode = |v: f32| if format.eight_bit() { eight_bit.decode(v) } else { v };
    RgbImage::from_pixels(w, h, img.to_rgb32f().pixels().map(|p| p.0.map(decode)).collect())
}

/// `image` with the values its file stores, where the scene's encoding reaches them
/// ([`Format::encoding_is_the_files`]): 8-bit images are read sRGB-decoded, so they
/// are encoded back (for linear image textures and normal maps).
pub fn stored_values(name: &str, image: Arc<Texels>, v3: bool) -> Arc<Texels> {
    match Format::of(Path::new(name)) {
        Some(f) if f.encoding_is_the_files(v3) => Arc::new(image.map_values(to_srgb)),
        _ => image,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A float EXR, its blocks compressed by [`exr_zip`], reads back bit for bit through
    /// `exr`'s own reader: a crop window (origin and a height that is no multiple of
    /// the 16 lines a block holds), smooth rows that compress and noisy ones that are
    /// stored raw, and the header says ZIP in 16-line scanline blocks.
    #[test]
    fn float_exrs_read_back_bit_for_bit() {
        let (w, h) = (37, 45);
        let mut state = 7u32;
        let mut noise = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let x = f32::from_bits(state ^ (state >> 15).wrapping_mul(0x2c1b_3c6d));
            if x.is_finite() { x } else { 0.5 }
        };
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| match i / w < 20 {
                true => [(i % w) as f32 * 0.25, (i / w) as f32, -2.0],
                false => [noise(), noise(), noise() * 1e6],
            })
            .collect();
        let mut img = RgbImage::from_pixels(w, h, pixels.clone());
        (img.origin, img.full) = ((5, 9), (64, 64));
        let dir = std::env::temp_dir().join(format!("pbrt-sppm-exr-zip-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("crop.exr");
        write_exr(&path, &img).unwrap();
        let back = read_exr(&path).unwrap();
        let meta = exr::meta::MetaData::read_from_file(&path, true).unwrap();
        let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
        let sizes: Vec<usize> = (exr::block::read(file, true).unwrap().all_chunks(true).unwrap())
            .map(|c| match c.unwrap().compressed_block {
                exr::block::chunk::CompressedBlock::ScanLine(b) => b.compressed_pixels_le.len(),
                _ => panic!("scanline blocks"),
            })
            .collect();
        std::fs::remove_dir_all(&dir).unwrap();
        // Blocks of lines 0–15 (smooth) and 32–44 (noise, 13 lines, stored raw).
        assert_eq!(sizes.len(), 3);
        assert!(sizes[0] < 16 * w * 12 / 2, "{sizes:?}");
        assert_eq!(sizes[2], 13 * w * 12, "{sizes:?}");
        assert_eq!((back.width, back.height, back.origin, back.full), (w, h, (5, 9), (64, 64)));
        let bits = |v: &[[f32; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back.pixels), bits(&pixels));
        let header = &meta.headers[0];
        assert_eq!(header.compression, Compression::ZIP16);
        assert_eq!(header.blocks, exr::meta::BlockDescription::ScanLines);
    }

    /// 8-bit PNGs (colour and grey, with alpha and without) decode through the table to the bits the general
    /// path (f32 conversion, then `from_srgb`) gives, for every value.
    #[test]
    fn eight_bit_pngs_decode_as_the_general_path() {
        let colour = image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(256, 3, |x, y| {
            image::Rgb([x as u8, (x as u8).wrapping_mul(7), (y * 90) as u8])
        }));
        let grey = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(256, 1, |x, _| image::Luma([x as u8])));
        // With alpha, of every value.
        let grey_alpha = image::DynamicImage::ImageLumaA8(image::GrayAlphaImage::from_fn(256, 2, |x, y| {
            image::LumaA([x as u8, (x as u8).wrapping_mul(3).wrapping_add(y as u8)])
        }));
        let colour_alpha = image::DynamicImage::ImageRgba8(image::RgbaImage::from_fn(256, 2, |x, y| {
            image::Rgba([x as u8, 255 - x as u8, (y * 90) as u8, (x as u8).wrapping_mul(5)])
        }));
        for img in [colour, grey, grey_alpha, colour_alpha] {
            let mut png = Vec::new();
            img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).expect("encode");
            let got = decode_codec(&png, Format::Png, EightBit::Srgb).expect("decode");
            let want: Vec<[f32; 3]> = img.to_rgb32f().pixels().map(|p| p.0.map(from_srgb)).collect();
            let bits = |v: &[[f32; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got.pixels), bits(&want));
        }
    }
}
