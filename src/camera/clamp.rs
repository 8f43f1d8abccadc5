//! pbrt's clamp of each sample the film records, against fireflies:
//!
//! ```text
//! Film "image" "float maxsampleluminance" 10      # v3: a sample's luminance at most 10
//! Film "rgb" "float maxcomponentvalue" 10         # v4: each sensor RGB component at most 10
//! ```
//!
//! pbrt scales a sample that is over the bound down to it, keeping its colour: a camera
//! sample's radiance before the pixel filter's weight, and each light-tracing splat.
//! pbrt-v3 bounds the luminance of the radiance, before the film's `scale`. pbrt-v4
//! bounds the largest component of the sensor's RGB: for its default `cie1931` sensor
//! that is XYZ, times the exposure (`iso`/100 × the shutter's time); for a named camera,
//! its own RGB. Neither pbrt's SPPM clamps (it writes its pixels directly), so only our
//! bidirectional and direct-light renders use this.

use crate::spectrum::colorspace::{ColorSpaceName, Matrix3, invert, mul, mul_vec};
use glam::DVec3;

/// The bound a film puts on each sample, as the file gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleClamp {
    /// pbrt-v3's `maxsampleluminance`.
    Luminance(f64),
    /// pbrt-v4's `maxcomponentvalue`.
    SensorComponent(f64),
}

impl SampleClamp {
    /// The film parameter that sets it, and the bound.
    pub fn param(self) -> (&'static str, f64) {
        match self {
            SampleClamp::Luminance(max) => ("maxsampleluminance", max),
            SampleClamp::SensorComponent(max) => ("maxcomponentvalue", max),
        }
    }
}

/// pbrt-v3's luminance weights (`RGBSpectrum::y`).
const Y_WEIGHTS: [f64; 3] = [0.212671, 0.715160, 0.072169];

/// A [`SampleClamp`] ready to apply to samples in the film's output RGB (what
/// `RenderScene::film_rgb` gives, before the film's scale and white balance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clamp {
    max: f64,
    /// The measured quantities (rows) of output RGB: one luminance row for pbrt-v3,
    /// the sensor's three for pbrt-v4.
    rows: Matrix3,
    /// 1 for pbrt-v3's luminance, 3 for pbrt-v4's components.
    count: usize,
}

impl Clamp {
    /// The clamp as it applies to a film with output multiplier `scale` (pbrt-v4:
    /// the exposure) writing `space`, recorded through `xyz_from_sensor` (a named
    /// camera's matrix; `None` for the CIE observer).
    pub fn new(rule: SampleClamp, scale: f64, space: ColorSpaceName, xyz_from_sensor: Option<&Matrix3>) -> Clamp {
        match rule {
            SampleClamp::Luminance(max) => Clamp { max, rows: [Y_WEIGHTS, [0.0; 3], [0.0; 3]], count: 1 },
            SampleClamp::SensorComponent(max) => {
                let xyz = space.xyz_from_rgb();
                let sensor = match xyz_from_sensor {
                    Some(m) => mul(&invert(m), &xyz),
                    None => xyz,
                };
                Clamp { max, rows: sensor.map(|row| row.map(|v| v * scale)), count: 3 }
            }
        }
    }

    /// What a sample of output RGB `rgb` is multiplied by: 1, or less to bring it to
    /// the bound.
    #[inline]
    pub fn factor(&self, rgb: DVec3) -> f64 {
        let measured = mul_vec(&self.rows, rgb.to_array());
        let m = measured[..self.count].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if m > self.max { self.max / m } else { 1.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pbrt_v3_bounds_the_luminance() {
        let c = Clamp::new(SampleClamp::Luminance(2.0), 5.0, ColorSpaceName::Srgb, None);
        assert_eq!(c.factor(DVec3::splat(1.5)), 1.0);
        // White of luminance 4 is halved; the film's scale plays no part.
        assert!((c.factor(DVec3::splat(4.0)) - 0.5).abs() < 1e-5);
        // Pure blue of 20 has luminance 1.44: under the bound.
        assert_eq!(c.factor(DVec3::new(0.0, 0.0, 20.0)), 1.0);
    }

    #[test]
    fn pbrt_v4_bounds_the_largest_exposed_xyz_component() {
        let c = Clamp::new(SampleClamp::SensorComponent(10.0), 2.0, ColorSpaceName::Srgb, None);
        // sRGB white 4 is XYZ (3.80, 4, 4.36), 8.71 at its largest once exposed ×2.
        assert_eq!(c.factor(DVec3::splat(4.0)), 1.0);
        let f = c.factor(DVec3::splat(10.0));
        let z = ColorSpaceName::Srgb.xyz_from_rgb()[2].iter().sum::<f64>() * 10.0 * 2.0;
        assert!((f - 10.0 / z).abs() < 1e-12, "{f}");
        // A camera's own RGB: its matrix's inverse from XYZ.
        let m = [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let cam = Clamp::new(SampleClamp::SensorComponent(10.0), 1.0, ColorSpaceName::Srgb, Some(&m));
        let rgb = DVec3::new(100.0, 0.0, 0.0);
        let xyz = mul_vec(&ColorSpaceName::Srgb.xyz_from_rgb(), rgb.to_array());
        let largest = (xyz[0] / 2.0).max(xyz[1]).max(xyz[2]);
        assert!((cam.factor(rgb) - 10.0 / largest).abs() < 1e-12);
    }
}
