//! RGB to spectrum by the sigmoid polynomial of Jakob and Hanika ("A Low-Dimensional
//! Function Space for Efficient Spectral Upsampling", 2019), as pbrt-v4 upsamples the
//! RGB values of its files:
//!
//! ```text
//! "rgb reflectance" [0.8 0.2 0.1]    # bounded: RgbAlbedoSpectrum
//! "rgb sigma_a" [4 1 0.5]            # unbounded: RgbUnboundedSpectrum
//! "rgb L" [10 8 6]                   # emission: RgbIlluminantSpectrum (× the space's white)
//! ```
//! s(λ) = S(c0 λ² + c1 λ + c2), S(x) = ½ + x / (2 √(1 + x²)). The coefficients come
//! from a table of 3 × 64³ fits per colour space (by max component, then the other
//! two over it, then the max on a smoothstep² scale), made by `pbrt-rgb2spec`
//! (`tools/rgb2spec.rs`, the method in `fit.rs`) and interpolated trilinearly.

use super::colorspace::ColorSpaceName;
use std::sync::OnceLock;

/// c0 λ² + c1 λ + c2 through a sigmoid: a smooth spectrum within [0, 1].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RgbSigmoidPolynomial {
    pub c0: f32,
    pub c1: f32,
    pub c2: f32,
}

impl RgbSigmoidPolynomial {
    /// s(λ), λ in nm.
    pub fn eval(&self, lambda: f32) -> f32 {
        sigmoid(self.c2 + lambda * (self.c1 + lambda * self.c0))
    }

    /// The largest value over 360–830 nm: at an end or at the parabola's vertex.
    pub fn max_value(&self) -> f32 {
        let ends = self.eval(360.0).max(self.eval(830.0));
        let vertex = -self.c1 / (2.0 * self.c0);
        if (360.0..=830.0).contains(&vertex) { ends.max(self.eval(vertex)) } else { ends }
    }
}

/// ½ + x / (2 √(1 + x²)), with its limits at ±∞.
pub fn sigmoid(x: f32) -> f32 {
    if x.is_infinite() {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + x / (2.0 * (1.0 + x * x).sqrt())
}

/// The fitted coefficients of one colour space.
pub struct RgbToSpectrumTable {
    pub res: usize,
    /// The max component's nodes, smoothstep(smoothstep(k / (res − 1))).
    pub scale: Vec<f32>,
    /// [max component][z][y][x][coefficient], λ in nm.
    pub coeffs: Vec<f32>,
}

impl RgbToSpectrumTable {
    /// The coefficients for an RGB within [0, 1].
    pub fn lookup(&self, rgb: [f32; 3]) -> RgbSigmoidPolynomial {
        let rgb = rgb.map(|c| c.clamp(0.0, 1.0));
        let [r, g, b] = rgb;
        if r == g && g == b {
            // A grey is a constant: S(c2) = r.
            return RgbSigmoidPolynomial { c0: 0.0, c1: 0.0, c2: (r - 0.5) / (r * (1.0 - r)).sqrt() };
        }
        let maxc = if r > g {
            if r > b { 0 } else { 2 }
        } else if g > b {
            1
        } else {
            2
        };
        let res = self.res;
        let z = rgb[maxc];
        let x = rgb[(maxc + 1) % 3] * (res - 1) as f32 / z;
        let y = rgb[(maxc + 2) % 3] * (res - 1) as f32 / z;
        let (xi, yi) = ((x as usize).min(res - 2), (y as usize).min(res - 2));
        let zi = self.scale.partition_point(|&s| s < z).saturating_sub(1).min(res - 2);
        let (dx, dy) = (x - xi as f32, y - yi as f32);
        let dz = (z - self.scale[zi]) / (self.scale[zi + 1] - self.scale[zi]);
        let co = |dx: usize, dy: usize, dz: usize, i: usize| {
            self.coeffs[(((maxc * res + zi + dz) * res + yi + dy) * res + xi + dx) * 3 + i]
        };
        let c: [f32; 3] = std::array::from_fn(|i| {
            let lerp = |t: f32, a: f32, b: f32| (1.0 - t) * a + t * b;
            let plane =
                |dz| lerp(dy, lerp(dx, co(0, 0, dz, i), co(1, 0, dz, i)), lerp(dx, co(0, 1, dz, i), co(1, 1, dz, i)));
            lerp(dz, plane(0), plane(1))
        });
        RgbSigmoidPolynomial { c0: c[0], c1: c[1], c2: c[2] }
    }

    /// The table as `pbrt-rgb2spec` writes it: a little-endian u32 resolution, then
    /// deflated: the scale's and then each coefficient's f32 bit patterns (in
    /// [max component][z][y][x] order) as differences from the previous one, split
    /// into four planes of bytes. Smooth tables compress to about half this way.
    pub fn to_bytes(&self) -> Vec<u8> {
        use std::io::Write;
        let mut bits: Vec<u32> = self.scale.iter().map(|v| v.to_bits()).collect();
        for k in 0..3 {
            bits.extend(self.coeffs.iter().skip(k).step_by(3).map(|v| v.to_bits()));
        }
        let mut prev = 0u32;
        let deltas: Vec<u32> = bits.iter().map(|&b| (b.wrapping_sub(prev), prev = b).0).collect();
        let planes: Vec<u8> = (0..4).flat_map(|p| deltas.iter().map(move |d| d.to_le_bytes()[p])).collect();
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
        z.write_all(&planes).expect("writing to memory");
        let mut out = (self.res as u32).to_le_bytes().to_vec();
        out.extend(z.finish().expect("writing to memory"));
        out
    }

    /// Reads what `to_bytes` wrote; `None` when it does not read back whole.
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        use std::io::Read;
        let res = u32::from_le_bytes(bytes.get(..4)?.try_into().ok()?) as usize;
        let n = res + 9 * res * res * res;
        let mut planes = Vec::with_capacity(4 * n);
        flate2::read::ZlibDecoder::new(&bytes[4..]).read_to_end(&mut planes).ok()?;
        if res < 2 || planes.len() != 4 * n {
            return None;
        }
        let mut prev = 0u32;
        let bits: Vec<u32> = (0..n)
            .map(|i| {
                prev = prev.wrapping_add(u32::from_le_bytes([0, 1, 2, 3].map(|p| planes[p * n + i])));
                prev
            })
            .collect();
        let m = n - res;
        let coeffs = (0..m).map(|i| f32::from_bits(bits[res + (i % 3) * (m / 3) + i / 3])).collect();
        Some(Self { res, scale: bits[..res].iter().map(|&b| f32::from_bits(b)).collect(), coeffs })
    }

    /// The committed table of a colour space, read once.
    pub fn of(space: ColorSpaceName) -> &'static RgbToSpectrumTable {
        static TABLES: [OnceLock<RgbToSpectrumTable>; 4] = [const { OnceLock::new() }; 4];
        let (slot, bytes): (usize, &[u8]) = match space {
            ColorSpaceName::Srgb => (0, include_bytes!("tables/srgb.bin")),
            ColorSpaceName::Rec2020 => (1, include_bytes!("tables/rec2020.bin")),
            ColorSpaceName::Aces2065_1 => (2, include_bytes!("tables/aces2065-1.bin")),
            ColorSpaceName::DciP3 => (3, include_bytes!("tables/dci-p3.bin")),
        };
        TABLES[slot].get_or_init(|| Self::from_bytes(bytes).expect("a committed table reads back"))
    }
}

/// A reflectance within [0, 1] (pbrt-v4's `RGBAlbedoSpectrum`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbAlbedoSpectrum {
    pub rsp: RgbSigmoidPolynomial,
}

impl RgbAlbedoSpectrum {
    pub fn new(space: ColorSpaceName, rgb: [f32; 3]) -> Self {
        Self { rsp: RgbToSpectrumTable::of(space).lookup(rgb) }
    }

    pub fn eval(&self, lambda: f32) -> f32 {
        self.rsp.eval(lambda)
    }
}

/// Any non-negative RGB: a bounded shape times 2·max (pbrt-v4's `RGBUnboundedSpectrum`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbUnboundedSpectrum {
    pub scale: f32,
    pub rsp: RgbSigmoidPolynomial,
}

impl RgbUnboundedSpectrum {
    pub fn new(space: ColorSpaceName, rgb: [f32; 3]) -> Self {
        let scale = 2.0 * rgb[0].max(rgb[1]).max(rgb[2]);
        let shape = if scale > 0.0 { rgb.map(|c| c / scale) } else { [0.0; 3] };
        Self { scale, rsp: RgbToSpectrumTable::of(space).lookup(shape) }
    }

    pub fn eval(&self, lambda: f32) -> f32 {
        self.scale * self.rsp.eval(lambda)
    }
}

/// An emitted RGB: the unbounded shape times the colour space's white spectrum
/// (pbrt-v4's `RGBIlluminantSpectrum`), so (1, 1, 1) emits the space's white.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbIlluminantSpectrum {
    pub space: ColorSpaceName,
    pub shape: RgbUnboundedSpectrum,
}

impl RgbIlluminantSpectrum {
    pub fn new(space: ColorSpaceName, rgb: [f32; 3]) -> Self {
        Self { space, shape: RgbUnboundedSpectrum::new(space, rgb) }
    }

    pub fn eval(&self, lambda: f32) -> f32 {
        // pbrt-v4 samples its illuminants at the nearest whole nanometre.
        self.shape.eval(lambda) * self.space.illuminant_at((lambda as f64).round()) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::cie;
    use crate::spectrum::colorspace::mul_vec;
    use crate::spectrum::data::COLORCHECKER_OHTA;

    /// The sRGB of a reflectance lit by the space's white (linear, 5 nm table from
    /// 380 nm, zero outside it).
    fn srgb_of(reflectance: impl Fn(f64) -> f64) -> [f64; 3] {
        let space = ColorSpaceName::Srgb;
        let xyz = cie::spectrum_to_xyz(|l| reflectance(l) * space.illuminant_at(l));
        mul_vec(&space.rgb_from_xyz(), xyz)
    }

    #[test]
    fn colorchecker_patches_keep_their_rgb_through_the_upsampling() {
        // Each patch's measured reflectance → sRGB under D65 → sigmoid spectrum →
        // sRGB again. Worst channel error measured: 5.5e-4 (the table is interpolated
        // between fits; a table indexed the wrong way round is off by tenths).
        let mut worst = 0.0f64;
        for (name, table) in &COLORCHECKER_OHTA {
            let rgb = srgb_of(|l| cie::five_nm(table, 380.0, l));
            let clamped = rgb.map(|c| c.clamp(0.0, 1.0) as f32);
            let spectrum = RgbAlbedoSpectrum::new(ColorSpaceName::Srgb, clamped);
            let back = srgb_of(|l| spectrum.eval(l as f32) as f64);
            for k in 0..3 {
                worst = worst.max((back[k] - clamped[k] as f64).abs());
            }
            assert!((0..3).all(|k| (back[k] - clamped[k] as f64).abs() < 2e-3), "{name}: {rgb:?} → {back:?}");
        }
        eprintln!("worst round-trip error {worst:.2e}");
    }

    #[test]
    fn greys_are_flat_and_extremes_are_exact() {
        let table = RgbToSpectrumTable::of(ColorSpaceName::Srgb);
        for v in [0.0, 0.18, 0.5, 1.0] {
            let s = table.lookup([v; 3]);
            for l in [360.0, 500.0, 830.0] {
                assert!((s.eval(l) - v).abs() < 1e-6, "{v} at {l}: {}", s.eval(l));
            }
        }
        // A pure red reflects long wavelengths and little else.
        let red = table.lookup([1.0, 0.0, 0.0]);
        assert!(red.eval(700.0) > 0.9 && red.eval(450.0) < 0.1, "{red:?}");
        // Values outside [0, 1] are clamped into the table, never read past it.
        assert_eq!(table.lookup([1.5, -0.2, 0.0]), red);
    }

    #[test]
    fn unbounded_and_emitted_rgb_scale_by_twice_the_max() {
        let u = RgbUnboundedSpectrum::new(ColorSpaceName::Srgb, [4.0, 2.0, 1.0]);
        assert_eq!(u.scale, 8.0);
        let back = srgb_of(|l| u.eval(l as f32) as f64);
        assert!((back[0] - 4.0).abs() < 0.03 && (back[2] - 1.0).abs() < 0.03, "{back:?}");
        // Emission of (1, 1, 1) is the space's white: D65, flat shape 0.5 × 2.
        let e = RgbIlluminantSpectrum::new(ColorSpaceName::Srgb, [1.0; 3]);
        let d65 = ColorSpaceName::Srgb.illuminant_at(560.0) as f32;
        assert!((e.eval(560.0) - d65).abs() < 1e-5 * d65);
    }

    #[test]
    fn every_committed_table_reads_back_and_fits_its_space() {
        for space in ColorSpaceName::ALL {
            let t = RgbToSpectrumTable::of(space);
            assert_eq!((t.res, t.scale.len(), t.coeffs.len()), (64, 64, 9 * 64 * 64 * 64));
            assert!(t.coeffs.iter().all(|c| c.is_finite()), "{space:?}");
            let bytes = t.to_bytes();
            let again = RgbToSpectrumTable::from_bytes(&bytes).unwrap();
            assert!(again.coeffs == t.coeffs && again.scale == t.scale);
        }
        assert!(RgbToSpectrumTable::from_bytes(&[64, 0, 0, 0, 1, 2, 3]).is_none());
    }
}
