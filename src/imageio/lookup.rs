//! Bilinear lookups in images, shared by image textures, normal maps and environment
//! maps.

use super::RgbImage;
use crate::spectrum::Rgb;
use glam::Vec3;

/// How image lookups treat coordinates outside [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Clamp,
    Black,
}

/// What lookups read: an image's size and its texels, row by row.
pub trait TexelSource {
    fn size(&self) -> (usize, usize);
    fn texel(&self, i: usize) -> [f32; 3];
}

impl TexelSource for RgbImage {
    fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    #[inline]
    fn texel(&self, i: usize) -> [f32; 3] {
        self.pixels[i]
    }
}

impl<T: TexelSource> TexelSource for std::sync::Arc<T> {
    fn size(&self) -> (usize, usize) {
        (**self).size()
    }

    #[inline]
    fn texel(&self, i: usize) -> [f32; 3] {
        (**self).texel(i)
    }
}

/// Bilinear lookup at (s, t) with t = 0 at the bottom row unless `top_down`.
pub fn lookup(img: &impl TexelSource, s: f32, t: f32, wrap: Wrap, top_down: bool) -> Rgb {
    let (w, h) = img.size();
    let (w, h) = (w as i64, h as i64);
    if w == 0 || h == 0 {
        return Vec3::ZERO;
    }
    let y = if top_down { t } else { 1.0 - t };
    let (x, y) = (s * w as f32 - 0.5, y * h as f32 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |xi: i64, yi: i64| -> Rgb {
        let (xi, yi) = match wrap {
            Wrap::Repeat => (xi.rem_euclid(w), yi.rem_euclid(h)),
            Wrap::Clamp => (xi.clamp(0, w - 1), yi.clamp(0, h - 1)),
            Wrap::Black if xi < 0 || yi < 0 || xi >= w || yi >= h => return Vec3::ZERO,
            Wrap::Black => (xi, yi),
        };
        Vec3::from(img.texel((yi * w + xi) as usize))
    };
    let (x0, y0) = (x0 as i64, y0 as i64);
    (1.0 - fx) * (1.0 - fy) * texel(x0, y0)
        + fx * (1.0 - fy) * texel(x0 + 1, y0)
        + (1.0 - fx) * fy * texel(x0, y0 + 1)
        + fx * fy * texel(x0 + 1, y0 + 1)
}
