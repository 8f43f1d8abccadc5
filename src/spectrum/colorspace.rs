//! pbrt-v4's RGB colour spaces: primaries, white and the matrices between RGB and XYZ.
//!
//! ```text
//! ColorSpace "srgb"          # also "rec2020", "aces2065-1", "dci-p3"
//! Film "rgb" "string colorspace" "rec2020"
//! ```
//! As in pbrt-v4, the white point is the chromaticity of the space's illuminant
//! spectrum (D65, or ACES's white for aces2065-1), not its nominal xy, and the matrix
//! maps RGB (1, 1, 1) to that white at luminance 1.

use super::cie::{self, five_nm};
use super::data::{ILLUM_ACES_D60, ILLUM_D65};
use std::sync::OnceLock;

/// A 3×3 matrix, rows first.
pub type Matrix3 = [[f64; 3]; 3];

/// The colour spaces pbrt-v4 names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorSpaceName {
    Srgb,
    Rec2020,
    Aces2065_1,
    DciP3,
}

impl ColorSpaceName {
    pub const ALL: [ColorSpaceName; 4] = [Self::Srgb, Self::Rec2020, Self::Aces2065_1, Self::DciP3];

    /// The name a scene file uses.
    pub fn name(self) -> &'static str {
        match self {
            Self::Srgb => "srgb",
            Self::Rec2020 => "rec2020",
            Self::Aces2065_1 => "aces2065-1",
            Self::DciP3 => "dci-p3",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The luminance (Y) of an RGB of this space.
    pub fn luminance(self, rgb: [f32; 3]) -> f32 {
        let m = self.xyz_from_rgb();
        (0..3).map(|i| m[1][i] * rgb[i] as f64).sum::<f64>() as f32
    }

    /// A linear sRGB colour in this space (the same XYZ).
    pub fn from_srgb(self, rgb: [f32; 3]) -> [f32; 3] {
        if self == Self::Srgb {
            return rgb;
        }
        let xyz = mul_vec(&Self::Srgb.xyz_from_rgb(), rgb.map(f64::from));
        mul_vec(&self.rgb_from_xyz(), xyz).map(|c| c as f32)
    }

    /// The chromaticities (x, y) of the red, green and blue primaries.
    fn primaries(self) -> [[f64; 2]; 3] {
        match self {
            Self::Srgb => [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]],
            Self::Rec2020 => [[0.708, 0.292], [0.170, 0.797], [0.131, 0.046]],
            Self::Aces2065_1 => [[0.7347, 0.2653], [0.0, 1.0], [0.0001, -0.077]],
            Self::DciP3 => [[0.680, 0.320], [0.265, 0.690], [0.150, 0.060]],
        }
    }

    /// The illuminant whose spectrum is the space's white: 5 nm steps from 300 nm.
    pub fn illuminant(self) -> &'static [f64] {
        match self {
            Self::Aces2065_1 => &ILLUM_ACES_D60,
            _ => &ILLUM_D65,
        }
    }

    /// The illuminant at `lambda` nm, scaled to luminance 1 (as pbrt-v4 normalises its
    /// standard illuminants).
    pub fn illuminant_at(self, lambda: f64) -> f64 {
        let scale = match self {
            Self::Aces2065_1 => {
                *ACES_SCALE.get_or_init(|| 1.0 / cie::luminance_of(|l| five_nm(&ILLUM_ACES_D60, 300.0, l)))
            }
            _ => *D65_SCALE.get_or_init(|| 1.0 / cie::luminance_of(|l| five_nm(&ILLUM_D65, 300.0, l))),
        };
        scale * five_nm(self.illuminant(), 300.0, lambda)
    }

    /// The matrix from this space's RGB to XYZ (made once per space: the luminance
    /// of every emitted colour needs it, and the white takes a 471-term integral).
    pub fn xyz_from_rgb(self) -> Matrix3 {
        static MATRICES: [OnceLock<Matrix3>; 4] = [const { OnceLock::new() }; 4];
        *MATRICES[self as usize].get_or_init(|| {
            let [x, y] = self.white();
            let w = [x / y, 1.0, (1.0 - x - y) / y];
            let columns = self.primaries().map(|[x, y]| [x / y, 1.0, (1.0 - x - y) / y]);
            let rgb: Matrix3 = std::array::from_fn(|r| std::array::from_fn(|c| columns[c][r]));
            let c = mul_vec(&invert(&rgb), w);
            std::array::from_fn(|r| std::array::from_fn(|k| rgb[r][k] * c[k]))
        })
    }

    /// The white's chromaticity: its illuminant's.
    pub fn white(self) -> [f64; 2] {
        static WHITES: [OnceLock<[f64; 2]>; 4] = [const { OnceLock::new() }; 4];
        *WHITES[self as usize].get_or_init(|| chromaticity(cie::spectrum_to_xyz(|l| self.illuminant_at(l))))
    }

    /// The matrix from XYZ to this space's RGB.
    pub fn rgb_from_xyz(self) -> Matrix3 {
        static MATRICES: [OnceLock<Matrix3>; 4] = [const { OnceLock::new() }; 4];
        *MATRICES[self as usize].get_or_init(|| invert(&self.xyz_from_rgb()))
    }
}

/// The chromaticity (x, y) of XYZ.
pub fn chromaticity([x, y, z]: [f64; 3]) -> [f64; 2] {
    [x / (x + y + z), y / (x + y + z)]
}

/// The von Kries adaptation in Bradford's cone space that takes white `from` (x, y)
/// to white `to`, on XYZ (pbrt-v4's `WhiteBalance`).
pub fn white_balance(from: [f64; 2], to: [f64; 2]) -> Matrix3 {
    const LMS_FROM_XYZ: Matrix3 = [[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]];
    let xyz = |[x, y]: [f64; 2]| [x / y, 1.0, (1.0 - x - y) / y];
    let (src, dst) = (mul_vec(&LMS_FROM_XYZ, xyz(from)), mul_vec(&LMS_FROM_XYZ, xyz(to)));
    let scaled: Matrix3 = std::array::from_fn(|r| LMS_FROM_XYZ[r].map(|v| v * dst[r] / src[r]));
    mul(&invert(&LMS_FROM_XYZ), &scaled)
}

/// `a · b`.
pub fn mul(a: &Matrix3, b: &Matrix3) -> Matrix3 {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

static D65_SCALE: OnceLock<f64> = OnceLock::new();
static ACES_SCALE: OnceLock<f64> = OnceLock::new();

/// `m · v`.
pub fn mul_vec(m: &Matrix3, v: [f64; 3]) -> [f64; 3] {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

/// The inverse of a non-singular 3×3 matrix (by cofactors).
pub fn invert(m: &Matrix3) -> Matrix3 {
    let cof = |r: usize, c: usize| {
        let (r0, r1, c0, c1) = ((r + 1) % 3, (r + 2) % 3, (c + 1) % 3, (c + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    let det = m[0][0] * cof(0, 0) + m[0][1] * cof(0, 1) + m[0][2] * cof(0, 2);
    std::array::from_fn(|r| std::array::from_fn(|c| cof(c, r) / det))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_colour_moved_between_spaces_keeps_its_xyz() {
        let c = [0.8f32, 0.3, 0.05];
        for space in ColorSpaceName::ALL {
            let moved = space.from_srgb(c);
            assert!((space.luminance(moved) - ColorSpaceName::Srgb.luminance(c)).abs() < 1e-5, "{space:?}");
            let back = mul_vec(&space.xyz_from_rgb(), moved.map(f64::from));
            let xyz = mul_vec(&ColorSpaceName::Srgb.xyz_from_rgb(), c.map(f64::from));
            assert!((0..3).all(|k| (back[k] - xyz[k]).abs() < 1e-5), "{space:?}: {back:?} vs {xyz:?}");
        }
        assert_eq!(ColorSpaceName::Srgb.from_srgb(c), c);
    }

    #[test]
    fn the_srgb_matrix_is_the_published_one() {
        // IEC 61966-2-1's XYZ → sRGB matrix (D65): our white is D65's spectrum's own
        // chromaticity, so the entries agree to about 1e-3.
        let published = [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]];
        let m = ColorSpaceName::Srgb.rgb_from_xyz();
        for (row, want) in m.iter().zip(published) {
            for (got, want) in row.iter().zip(want) {
                assert!((got - want).abs() < 2e-3, "{m:?}");
            }
        }
    }

    #[test]
    fn white_balance_takes_one_white_to_the_other_and_keeps_luminance_near() {
        let (from, to) = ([0.4369, 0.4041], ColorSpaceName::Srgb.white());
        let m = white_balance(from, to);
        let src = [from[0] / from[1], 1.0, (1.0 - from[0] - from[1]) / from[1]];
        let got = chromaticity(mul_vec(&m, src));
        assert!((got[0] - to[0]).abs() < 1e-9 && (got[1] - to[1]).abs() < 1e-9, "{got:?}");
        // Bradford's published adaptation from illuminant A to D65 (Lindbloom), and the
        // identity for a white onto itself.
        let a_to_d65 = white_balance([0.44757, 0.40745], [0.31271, 0.32902]);
        let published = [
            [0.8446965, -0.1179225, 0.3948108],
            [-0.1366303, 1.1041226, 0.1291718],
            [0.0798489, -0.1348999, 3.1924009],
        ];
        for r in 0..3 {
            for c in 0..3 {
                assert!((a_to_d65[r][c] - published[r][c]).abs() < 1e-3, "{a_to_d65:?}");
            }
        }
        let same = white_balance(to, to);
        assert!((0..3).all(|r| (0..3).all(|c| (same[r][c] - if r == c { 1.0 } else { 0.0 }).abs() < 1e-12)));
    }

    #[test]
    fn white_is_one_in_every_space() {
        for space in ColorSpaceName::ALL {
            let xyz = cie::spectrum_to_xyz(|l| space.illuminant_at(l));
            assert!((xyz[1] - 1.0).abs() < 1e-9, "{space:?}: {xyz:?}");
            let rgb = mul_vec(&space.rgb_from_xyz(), xyz);
            assert!(rgb.iter().all(|c| (c - 1.0).abs() < 1e-9), "{space:?}: {rgb:?}");
        }
    }
}
