//! Images as textures and normal maps keep them. An 8-bit PNG keeps its bytes and
//! the 256 values they decode to (3 bytes a texel instead of 12, as pbrt-v4 keeps
//! 8-bit images); other images keep their `f32` values. Either way a texel reads as
//! the same bits the decoded image would hold.
//!
//! ```text
//! Texture "wood" "spectrum" "imagemap" "string filename" "wood.png"
//! ```

use super::{RgbImage, TexelSource};

/// An image for texture lookups.
#[derive(Clone, Debug, PartialEq)]
pub struct Texels {
    pub width: usize,
    pub height: usize,
    store: Store,
}

#[derive(Clone, Debug, PartialEq)]
enum Store {
    Values(Vec<[f32; 3]>),
    /// Three bytes a texel, each standing for `values[byte]`.
    Bytes {
        rgb: Vec<u8>,
        values: Box<[f32; 256]>,
    },
}

impl Texels {
    /// An 8-bit image: `rgb` bytes, three a texel, each standing for `values[byte]`.
    pub fn from_bytes(width: usize, height: usize, rgb: Vec<u8>, values: [f32; 256]) -> Texels {
        Texels { width, height, store: Store::Bytes { rgb, values: Box::new(values) } }
    }

    /// The values of a decoded image (moved, not copied).
    pub fn from_image(image: RgbImage) -> Texels {
        Texels { width: image.width, height: image.height, store: Store::Values(image.pixels) }
    }

    /// The same image with `f` applied to every channel value (per value, so an 8-bit
    /// image maps its 256 values only).
    pub fn map_values(&self, f: impl Fn(f32) -> f32) -> Texels {
        let store = match &self.store {
            Store::Values(v) => Store::Values(v.iter().map(|p| p.map(&f)).collect()),
            Store::Bytes { rgb, values } => Store::Bytes { rgb: rgb.clone(), values: Box::new(values.map(&f)) },
        };
        Texels { width: self.width, height: self.height, store }
    }
}

impl TexelSource for Texels {
    fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    #[inline]
    fn texel(&self, i: usize) -> [f32; 3] {
        match &self.store {
            Store::Values(v) => v[i],
            Store::Bytes { rgb, values } => [rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]].map(|b| values[b as usize]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bytes and their values read as the decoded image; mapping the values maps
    /// every texel the same way. Fails if a channel indexes another's byte.
    #[test]
    fn bytes_read_as_their_values() {
        let values: [f32; 256] = std::array::from_fn(|b| (b as f32 / 255.0).powf(2.2));
        let rgb: Vec<[u8; 3]> = (0..=255u8).map(|b| [b, b.wrapping_mul(7), 255 - b]).collect();
        let t = Texels::from_bytes(16, 16, rgb.concat(), values);
        let decoded: Vec<[f32; 3]> = rgb.iter().map(|p| p.map(|b| values[b as usize])).collect();
        assert!((0..256).all(|i| t.texel(i) == decoded[i]));
        let halved = t.map_values(|v| v * 0.5);
        assert!((0..256).all(|i| halved.texel(i) == decoded[i].map(|v| v * 0.5)));
    }
}
