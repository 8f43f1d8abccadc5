//! pbrt-v4's film sensors and white balance.
//!
//! ```text
//! Film "rgb" "string sensor" "cie1931" "float whitebalance" 4500   # balance 4500 K daylight
//! Film "rgb" "string sensor" "nikon_d850" "float iso" 400           # a camera (6500 K default)
//! ```
//! The `cie1931` sensor records XYZ; `whitebalance` (kelvin; 0, the default for
//! cie1931, leaves colours alone) then adapts the white of the standard illuminant of
//! that temperature to the output colour space's white, by von Kries in Bradford's cone
//! space. A named camera's own measured curves are not applied here (noted where a
//! file asks for one); it is balanced as pbrt-v4 balances it, 6500 K unless given.

use super::colorspace::{ColorSpaceName, Matrix3, chromaticity, mul, white_balance};
use super::{cie, daylight};

/// The cameras pbrt-v4 has measured curves for.
pub const NAMED_SENSORS: [&str; 17] = [
    "canon_eos_100d",
    "canon_eos_1dx_mkii",
    "canon_eos_200d",
    "canon_eos_200d_mkii",
    "canon_eos_5d",
    "canon_eos_5d_mkii",
    "canon_eos_5d_mkiii",
    "canon_eos_5d_mkiv",
    "canon_eos_5ds",
    "canon_eos_m",
    "hasselblad_l1d_20c",
    "nikon_d810",
    "nikon_d850",
    "sony_ilce_6400",
    "sony_ilce_7m3",
    "sony_ilce_7rm3",
    "sony_ilce_9",
];

/// The white-balance temperature pbrt-v4 uses: as given, else none for `cie1931` and
/// 6500 K for a camera.
pub fn balance_temperature(sensor: &str, given: f32) -> f32 {
    if given == 0.0 && sensor != "cie1931" { 6500.0 } else { given }
}

/// The white balance for light of temperature `kelvin`, as a matrix on `space`'s RGB.
pub fn white_balance_rgb(kelvin: f64, space: ColorSpaceName) -> Matrix3 {
    let from = chromaticity(cie::spectrum_to_xyz(daylight::std_illuminant(kelvin)));
    let xyz = white_balance(from, space.white());
    mul(&space.rgb_from_xyz(), &mul(&xyz, &space.xyz_from_rgb()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::colorspace::mul_vec;

    #[test]
    fn a_grey_card_under_the_balanced_light_comes_out_grey() {
        // A grey card (0.5) lit by 3200 K light, in sRGB without balance, is orange;
        // balanced for 3200 K it is the grey of the space's white.
        let space = ColorSpaceName::Srgb;
        let light = daylight::std_illuminant(3200.0);
        let norm = cie::luminance_of(&light);
        let xyz = cie::spectrum_to_xyz(|l| 0.5 * light(l) / norm);
        let raw = mul_vec(&space.rgb_from_xyz(), xyz);
        assert!(raw[0] > 1.3 * raw[2], "{raw:?}");
        let balanced = mul_vec(&white_balance_rgb(3200.0, space), raw);
        assert!(balanced.iter().all(|c| (c - balanced[1]).abs() < 1e-3 * balanced[1]), "{balanced:?}");
    }

    #[test]
    fn cameras_balance_to_6500_kelvin_unless_told() {
        assert_eq!(balance_temperature("cie1931", 0.0), 0.0);
        assert_eq!(balance_temperature("nikon_d850", 0.0), 6500.0);
        assert_eq!(balance_temperature("nikon_d850", 3000.0), 3000.0);
    }
}
