//! Reading EXR files: the first layer's R, G and B (half or float), or a grey image's
//! one channel, as both pbrts read them:
//!
//! ```text
//! Texture "rough" "float" "imagemap" "string filename" "roughness.exr"   # a Y channel
//! Texture "cut" "float" "imagemap" "string filename" "leaf.exr"          # v4: its A
//! ```
//!
//! pbrt-v3 reads through OpenEXR's `RgbaInputFile`, which gives a luminance-only
//! (`Y`) file as grey; pbrt-v4 reads every channel, and its textures take a file of
//! one channel, whatever its name, as grey. A file with R, G and B is read as colour,
//! its alpha (`A`) kept only where a pbrt-v4 float texture asks for it.

use super::{ImageError, ImageMeta, Res, RgbImage};
use exr::prelude::*;

/// An EXR's colour, and its alpha when asked for and the file has an `A` channel.
pub(super) struct ExrPixels {
    pub image: RgbImage,
    pub alpha: Option<Vec<f32>>,
}

/// The first RGB layer of an EXR, or its grey channel ([`grey_layer`]).
pub(super) fn decode_exr(bytes: &[u8]) -> Res<RgbImage> {
    decode_exr_alpha(bytes, false).map(|e| e.image)
}

/// [`decode_exr`], with the alpha channel if `with_alpha` and the file has one.
pub(super) fn decode_exr_alpha(bytes: &[u8], with_alpha: bool) -> Res<ExrPixels> {
    match rgb_layer(bytes, with_alpha) {
        Ok(pixels) => Ok(pixels),
        // Not R, G and B: perhaps a grey image. A damaged file fails the second
        // reading too, and that reason is given.
        Err(rgb_error) => match grey_layer(bytes) {
            Ok(Some(image)) => Ok(ExrPixels { image, alpha: None }),
            Ok(None) => Err(ImageError::decode(format!(
                "the EXR has no R, G and B channels and no grey one (Y, or a single channel): {rgb_error}"
            ))),
            Err(e) => Err(e),
        },
    }
}

/// The R, G, B (and A) channels of the first layer that has them.
fn rgb_layer(bytes: &[u8], with_alpha: bool) -> std::result::Result<ExrPixels, Error> {
    struct Store {
        width: usize,
        rgb: Vec<[f32; 3]>,
        alpha: Option<Vec<f32>>,
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, channels: &RgbaChannels| {
                let n = res.width() * res.height();
                let alpha = (with_alpha && channels.3.is_some()).then(|| vec![1.0; n]);
                Store { width: res.width(), rgb: vec![[0.0; 3]; n], alpha }
            },
            |s: &mut Store, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                let i = pos.y() * s.width + pos.x();
                s.rgb[i] = [r, g, b];
                if let Some(alpha) = &mut s.alpha {
                    alpha[i] = a;
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))?;
    let layer = image.layer_data;
    let Store { rgb, alpha, .. } = layer.channel_data.pixels;
    Ok(ExrPixels { image: rgb_image(&image.attributes, &layer.attributes, layer.size, rgb), alpha })
}

/// The first layer's grey channel as R = G = B: its `Y`, or its only channel.
/// `None` when the layer has neither (the caller reports why R, G, B were not found).
fn grey_layer(bytes: &[u8]) -> Res<Option<RgbImage>> {
    // Its size was checked against the limits before.
    let image = super::decode_all_channels(bytes, "image", u64::MAX).map_err(ImageError::decode)?;
    let layer = &image.layer_data;
    let channels = &layer.channel_data.list;
    let grey = channels.iter().find(|c| c.name == *"Y").or(match channels.as_slice() {
        [only] => Some(only),
        _ => None,
    });
    let Some(grey) = grey else { return Ok(None) };
    let pixels: Vec<[f32; 3]> = grey.sample_data.values_as_f32().map(|v| [v; 3]).collect();
    if pixels.len() != layer.size.area() {
        return Err(ImageError::decode("the EXR's grey channel does not match its size"));
    }
    Ok(Some(rgb_image(&image.attributes, &layer.attributes, layer.size, pixels)))
}

/// An image of `pixels` with the header's windows and pbrt's metadata keys.
fn rgb_image(image: &ImageAttributes, layer: &LayerAttributes, size: Vec2<usize>, pixels: Vec<[f32; 3]>) -> RgbImage {
    let get_f32 = |k: &str| match layer.other.get(&Text::from(k)) {
        Some(AttributeValue::F32(v)) => Some(*v),
        _ => None,
    };
    let get_i32 = |k: &str| match layer.other.get(&Text::from(k)) {
        Some(AttributeValue::I32(v)) => Some(*v),
        _ => None,
    };
    let display = image.display_window;
    RgbImage {
        width: size.width(),
        height: size.height(),
        pixels,
        bands: None,
        origin: (layer.layer_position.x() - display.position.x(), layer.layer_position.y() - display.position.y()),
        full: (display.size.width(), display.size.height()),
        meta: ImageMeta {
            render_time_seconds: get_f32("renderTimeSeconds"),
            samples_per_pixel: get_i32("samplesPerPixel"),
            photons_per_iteration: get_i32("photonsPerIteration").map(i64::from),
            world_to_camera: layer.world_to_camera,
            software: layer.software_name.as_ref().map(|t| t.to_string()),
        },
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// An EXR in memory of 2 × 1 pixels with the named channels, each pixel's value of
    /// a channel given by `value(channel index, x)`.
    pub fn exr_of(names: &[&str], value: impl Fn(usize, usize) -> f32) -> Vec<u8> {
        let channels: Vec<AnyChannel<FlatSamples>> = (0..names.len())
            .map(|c| AnyChannel::new(names[c], FlatSamples::F32((0..2).map(|x| value(c, x)).collect())))
            .collect();
        let layer = Layer::new(
            (2, 1),
            LayerAttributes::named(""),
            Encoding::UNCOMPRESSED,
            AnyChannels::sort(channels.into_iter().collect()),
        );
        let mut bytes = Vec::new();
        Image::from_layer(layer).write().to_buffered(std::io::Cursor::new(&mut bytes)).expect("encode");
        bytes
    }

    #[test]
    fn a_grey_exr_is_its_y_or_its_only_channel() {
        let y = exr_of(&["Y"], |_, x| 0.25 + x as f32);
        assert_eq!(decode_exr(&y).expect("Y").pixels, vec![[0.25; 3], [1.25; 3]]);
        let z = exr_of(&["Z"], |_, x| 2.0 * x as f32);
        assert_eq!(decode_exr(&z).expect("Z").pixels, vec![[0.0; 3], [2.0; 3]]);
        // Y beside other channels is still the grey one.
        let ya = exr_of(&["A", "Y"], |c, _| [0.5, 0.75][c]);
        assert_eq!(decode_exr(&ya).expect("Y, A").pixels, vec![[0.75; 3]; 2]);
        let neither = exr_of(&["Z", "depth"], |_, _| 1.0);
        let err = decode_exr(&neither).expect_err("no colour, no grey").to_string();
        assert!(err.contains("no R, G and B channels and no grey one"), "{err}");
    }

    #[test]
    fn colour_comes_with_its_alpha_only_when_asked_for() {
        let rgba = exr_of(&["R", "G", "B", "A"], |c, x| if c == 3 { 0.5 * x as f32 } else { 0.1 * (c + 1) as f32 });
        let plain = decode_exr_alpha(&rgba, false).expect("rgba");
        assert!(plain.alpha.is_none());
        assert_eq!(plain.image.pixels[1], [1, 2, 3].map(|k| 0.1 * k as f32));
        assert_eq!(decode_exr_alpha(&rgba, true).expect("rgba").alpha, Some(vec![0.0, 0.5]));
        let rgb = exr_of(&["R", "G", "B"], |_, _| 1.0);
        assert!(decode_exr_alpha(&rgb, true).expect("rgb").alpha.is_none());
    }
}
