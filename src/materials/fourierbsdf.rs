//! pbrt-v3's `FourierBSDF`: an isotropic BSDF tabulated in the Fourier basis of Jakob
//! et al.'s layered-material framework (`SCATFUN` files, "layerlab"), evaluated and
//! sampled as pbrt-v3 does. The `fourier` material ([`super::fourier`]) reads the file.
//!
//! For every pair of zenith cosines (μi, μo) on a grid of `nMu` nodes over [-1, 1] the
//! file holds the Fourier coefficients in the azimuth difference φ of |μi| f(μi, μo, φ):
//! one series for luminance, or three (luminance, red, blue; green follows). Lookups
//! blend the 4 × 4 nearest pairs by Catmull-Rom weights; sampling inverts the spline in
//! μi and the series in φ. One lobe covers reflection and transmission (relative index
//! `eta`).

use super::shared::Sampled;
use super::transport::TransportMode;
use crate::math::catmull_rom;
use crate::spectrum::Rgb;
use glam::Vec3;
use std::f64::consts::PI;

const MAGIC: &[u8; 8] = b"SCATFUN\x01";
const HEADER: usize = 64;

/// A Fourier BSDF table (pbrt-v3's `FourierBSDFTable`).
#[derive(Debug, PartialEq)]
pub struct FourierTable {
    pub eta: f32,
    /// The longest series.
    pub m_max: usize,
    /// 1 (luminance) or 3 (luminance, red, blue).
    pub channels: usize,
    /// The zenith cosines, increasing over [-1, 1].
    pub mu: Vec<f32>,
    /// Per (μo, μi) pair, at `o * nMu + i`: where its coefficients start and how many
    /// there are per channel.
    offset: Vec<u32>,
    m: Vec<u32>,
    a: Vec<f32>,
    /// Each pair's first luminance coefficient, and per μo row its running integral
    /// over μi.
    a0: Vec<f32>,
    cdf: Vec<f32>,
}

/// Why a file cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FourierError {
    #[error("not a pbrt-v3 Fourier BSDF file (no \"SCATFUN\" version 1 header)")]
    Magic,
    #[error("the file ends inside {0}")]
    Truncated(&'static str),
    #[error("{0}")]
    Unsupported(String),
}

fn le_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

impl FourierTable {
    /// Reads a file as pbrt-v3 does (flags 1: a plain BSDF, one basis, 1 or 3 channels),
    /// with every count and offset checked.
    pub fn read(b: &[u8]) -> Result<FourierTable, FourierError> {
        if b.len() < HEADER || &b[..8] != MAGIC {
            return Err(if b.len() >= 8 && &b[..8] != MAGIC {
                FourierError::Magic
            } else {
                FourierError::Truncated("the header")
            });
        }
        let word = |k: usize| le_u32(b, 8 + 4 * k);
        let (flags, n_mu, n_coeffs, m_max, channels, bases) =
            (word(0), word(1) as usize, word(2) as usize, word(3) as usize, word(4) as usize, word(5));
        let eta = f32::from_bits(word(9));
        if flags != 1 || bases != 1 || !(channels == 1 || channels == 3) {
            let what = format!(
                "flags {flags}, {bases} bases, {channels} channels (pbrt-v3 reads flags 1, one basis, 1 or 3 channels)"
            );
            return Err(FourierError::Unsupported(what));
        }
        if !((2..=4096).contains(&n_mu) && eta.is_finite() && eta > 0.0) {
            return Err(FourierError::Unsupported(format!("{n_mu} zenith nodes, eta {eta}")));
        }
        let pairs = n_mu * n_mu;
        let need = HEADER as u64 + 4 * (n_mu as u64 + 3 * pairs as u64 + n_coeffs as u64);
        if (b.len() as u64) < need {
            return Err(FourierError::Truncated("the tables"));
        }
        let floats =
            |at: usize, n: usize| -> Vec<f32> { (0..n).map(|i| f32::from_bits(le_u32(b, at + 4 * i))).collect() };
        let mu = floats(HEADER, n_mu);
        let cdf = floats(HEADER + 4 * n_mu, pairs);
        let ol_at = HEADER + 4 * (n_mu + pairs);
        let a = floats(ol_at + 8 * pairs, n_coeffs);
        let (mut offset, mut m) = (Vec::with_capacity(pairs), Vec::with_capacity(pairs));
        for i in 0..pairs {
            let (o, len) = (le_u32(b, ol_at + 8 * i), le_u32(b, ol_at + 8 * i + 4));
            if len as usize > m_max || o as u64 + len as u64 * channels as u64 > n_coeffs as u64 {
                return Err(FourierError::Unsupported(format!("pair {i}: {len} coefficients at {o}, past the table")));
            }
            offset.push(o);
            m.push(len);
        }
        // The longest series stored, not the header's claim: each lookup allocates it.
        let m_max = m.iter().copied().max().unwrap_or(0).max(1) as usize;
        let a0 = (0..pairs).map(|i| if m[i] > 0 { a[offset[i] as usize] } else { 0.0 }).collect();
        let ordered = mu.windows(2).all(|w| w[0] < w[1]) && mu.iter().all(|x| x.is_finite());
        if !ordered || a.iter().chain(&cdf).any(|x| !x.is_finite()) {
            return Err(FourierError::Unsupported("zenith nodes out of order or values not finite".into()));
        }
        Ok(FourierTable { eta, m_max, channels, mu, offset, m, a, a0, cdf })
    }

    /// The summed coefficients at (μi, μo), per channel `m_max` apart, and the longest
    /// series among them; `None` outside the nodes.
    fn coefficients(&self, mu_i: f32, mu_o: f32, channels: usize) -> Option<(Vec<f32>, usize)> {
        let (oi, wi) = catmull_rom::weights(&self.mu, mu_i)?;
        let (oo, wo) = catmull_rom::weights(&self.mu, mu_o)?;
        let n = self.mu.len();
        let mut ak = vec![0.0f32; self.m_max * channels];
        let mut m_max = 0;
        for (b, &w_o) in wo.iter().enumerate() {
            for (a, &w_i) in wi.iter().enumerate() {
                let w = w_i * w_o;
                if w == 0.0 {
                    continue;
                }
                let pair = (oo + b as i32) as usize * n + (oi + a as i32) as usize;
                let (m, at) = (self.m[pair] as usize, self.offset[pair] as usize);
                m_max = m_max.max(m);
                for c in 0..channels {
                    for k in 0..m {
                        ak[c * self.m_max + k] += w * self.a[at + c * m + k];
                    }
                }
            }
        }
        Some((ak, m_max))
    }

    /// 1/|μi|, times the relative index squared for radiance carried across.
    fn scale(&self, mu_i: f32, mu_o: f32, mode: TransportMode) -> f32 {
        let mut scale = if mu_i != 0.0 { 1.0 / mu_i.abs() } else { 0.0 };
        if mode == TransportMode::Radiance && mu_i * mu_o > 0.0 {
            let eta = if mu_i > 0.0 { 1.0 / self.eta } else { self.eta };
            scale *= eta * eta;
        }
        scale
    }

    /// The colour of luminance `y` and the red and blue series at `cos_phi`.
    fn colour(&self, ak: &[f32], m: usize, y: f32, cos_phi: f32, scale: f32) -> Rgb {
        if self.channels == 1 {
            return Vec3::splat(y * scale);
        }
        let r = fourier(&ak[self.m_max..], m, cos_phi as f64);
        let b = fourier(&ak[2 * self.m_max..], m, cos_phi as f64);
        let g = 1.39829 * y - 0.100913 * b - 0.297375 * r;
        (Vec3::new(r, g, b) * scale).max(Vec3::ZERO)
    }

    /// f(ωo, ωi) in the shading frame (pbrt-v3's `FourierBSDF::f`).
    pub fn f(&self, o: Vec3, i: Vec3, mode: TransportMode) -> Rgb {
        let (mu_i, mu_o) = (-i.z, o.z);
        let cos_phi = cos_d_phi(-i, o);
        let Some((ak, m)) = self.coefficients(mu_i, mu_o, self.channels) else { return Vec3::ZERO };
        let y = fourier(&ak, m, cos_phi as f64).max(0.0);
        self.colour(&ak, m, y, cos_phi, self.scale(mu_i, mu_o, mode))
    }

    /// The density of sampling ωi from ωo (pbrt-v3's `FourierBSDF::Pdf`).
    pub fn pdf(&self, o: Vec3, i: Vec3) -> f32 {
        let (mu_i, mu_o) = (-i.z, o.z);
        let Some((ak, m)) = self.coefficients(mu_i, mu_o, 1) else { return 0.0 };
        let Some((oo, wo)) = catmull_rom::weights(&self.mu, mu_o) else { return 0.0 };
        let n = self.mu.len();
        let rho: f32 = (0..4)
            .filter(|&k| wo[k] != 0.0)
            .map(|k| wo[k] * self.cdf[(oo as usize + k) * n + n - 1] * (2.0 * std::f32::consts::PI))
            .sum();
        let y = fourier(&ak, m, cos_d_phi(-i, o) as f64);
        if rho > 0.0 && y > 0.0 { y / rho } else { 0.0 }
    }

    /// Samples ωi from ωo (pbrt-v3's `FourierBSDF::Sample_f`): μi by the spline, φ by
    /// the luminance series.
    pub fn sample(&self, o: Vec3, u: [f32; 2], mode: TransportMode) -> Option<Sampled> {
        let mu_o = o.z;
        let (mu_i, pdf_mu) = catmull_rom::sample_2d(&self.mu, &self.mu, &self.a0, &self.cdf, mu_o, u[1])?;
        let (ak, m) = self.coefficients(mu_i, mu_o, self.channels)?;
        let (y, pdf_phi, phi) = sample_fourier(&ak, m, u[0]);
        let pdf = (pdf_phi * pdf_mu).max(0.0);
        let sin2_i = (1.0 - mu_i * mu_i).max(0.0);
        let mut norm = (sin2_i / (1.0 - o.z * o.z).max(0.0)).sqrt();
        if norm.is_infinite() {
            norm = 0.0;
        }
        let (sin_phi, cos_phi) = phi.sin_cos();
        let wi = -Vec3::new(norm * (cos_phi * o.x - sin_phi * o.y), norm * (sin_phi * o.x + cos_phi * o.y), mu_i);
        let wi = wi.normalize_or_zero();
        let f = self.colour(&ak, m, y, cos_phi, self.scale(mu_i, mu_o, mode));
        (wi != Vec3::ZERO && pdf > 0.0).then_some(Sampled { wi, f, pdf })
    }
}

/// pbrt's `CosDPhi`: the cosine of the azimuth between two directions.
fn cos_d_phi(a: Vec3, b: Vec3) -> f32 {
    let ab = (a.x * a.x + a.y * a.y) * (b.x * b.x + b.y * b.y);
    if ab == 0.0 {
        return 1.0;
    }
    ((a.x * b.x + a.y * b.y) / ab.sqrt()).clamp(-1.0, 1.0)
}

/// pbrt's `Fourier`: Σ a_k cos(kφ), by the cosines' recurrence, in f64.
fn fourier(a: &[f32], m: usize, cos_phi: f64) -> f32 {
    let (mut value, mut prev, mut cur) = (0.0f64, cos_phi, 1.0f64);
    for &ak in &a[..m] {
        value += ak as f64 * cur;
        let next = 2.0 * cos_phi * cur - prev;
        prev = cur;
        cur = next;
    }
    value as f32
}

/// pbrt's `SampleFourier`: φ with density ∝ the series, by Newton and bisection on
/// half the circle; returns (the series at φ, its density, φ).
fn sample_fourier(ak: &[f32], m: usize, u: f32) -> (f32, f32, f32) {
    let flip = u >= 0.5;
    let u = if flip { 1.0 - 2.0 * (u - 0.5) } else { u * 2.0 } as f64;
    let a0 = ak[0] as f64;
    // F(φ) - u·a0·π and its derivative f(φ), by the sines' and cosines' recurrences.
    let series = |phi: f64| {
        let cos_phi = phi.cos();
        let sin_phi = (1.0 - cos_phi * cos_phi).max(0.0).sqrt();
        let (mut cos_prev, mut cos_cur, mut sin_prev, mut sin_cur) = (cos_phi, 1.0, -sin_phi, 0.0);
        let (mut big_f, mut f) = (a0 * phi, a0);
        for (k, &a_k) in ak.iter().enumerate().take(m).skip(1) {
            let sin_next = 2.0 * cos_phi * sin_cur - sin_prev;
            let cos_next = 2.0 * cos_phi * cos_cur - cos_prev;
            (sin_prev, sin_cur, cos_prev, cos_cur) = (sin_cur, sin_next, cos_cur, cos_next);
            big_f += a_k as f64 * (1.0 / k as f32) as f64 * sin_next;
            f += a_k as f64 * cos_next;
        }
        (big_f - u * a0 * PI, f)
    };
    let (mut a, mut b, mut phi) = (0.0f64, PI, 0.5 * PI);
    let (mut big_f, mut f) = series(phi);
    // DEVIATION(pbrt): robustness. pbrt-v3 iterates until |F| < 1e-6; with large
    // coefficients (a damaged table) rounding keeps |F| above that while Newton stalls
    // inside the bracket, so pbrt-v3 never returns. 100 steps, then φ as it stands.
    for _ in 0..100 {
        if big_f > 0.0 {
            b = phi;
        } else {
            a = phi;
        }
        if big_f.abs() < 1e-6 || b - a < 1e-6 {
            break;
        }
        phi -= big_f / f;
        if !(phi > a && phi < b) {
            phi = 0.5 * (a + b);
        }
        (big_f, f) = series(phi);
    }
    if flip {
        phi = 2.0 * PI - phi;
    }
    (f as f32, (f / a0 / (2.0 * PI)) as f32, phi as f32)
}

/// A shared table, compared by address.
pub type Table = super::shared::Shared<FourierTable>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::sampling::uniform_sphere;

    fn glazed() -> FourierTable {
        let dir = env!("CARGO_MANIFEST_DIR");
        FourierTable::read(&std::fs::read(format!("{dir}/pbrt-scenes/verify/bsdfs/glazed.bsdf")).unwrap()).unwrap()
    }

    fn dir(cos_theta: f32, phi: f32) -> Vec3 {
        let s = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), cos_theta)
    }

    #[test]
    fn the_test_file_is_read() {
        let t = glazed();
        assert_eq!((t.eta, t.channels, t.mu.len()), (1.2, 3, 25));
        assert_eq!((t.mu[0], t.mu[12], t.mu[24]), (-1.0, 0.0, 1.0));
        // The gloss: brighter toward the mirror direction than away from it, brown
        // (red over blue), and a faint transmission.
        let o = dir(0.6, 0.0);
        let mirror = Vec3::new(-o.x, -o.y, o.z);
        let off = dir(0.6, 2.0);
        let (fm, fo) = (t.f(o, mirror, TransportMode::Radiance), t.f(o, off, TransportMode::Radiance));
        assert!(fm.x > 3.0 * fo.x && fo.x > fo.z, "{fm} {fo}");
        let through = t.f(o, -o, TransportMode::Radiance);
        assert!(through.z > through.x && through.z < fm.z, "{through}");
    }

    #[test]
    fn sampling_follows_the_density_it_reports() {
        // Each sample's f and density are those of f and pdf at its direction, and the
        // densities integrate to 1 over the sphere (by the samples' own estimate).
        let t = glazed();
        let mut rng = Rng::new(3);
        for mu_o in [0.9f32, 0.4, -0.7] {
            let o = dir(mu_o, 0.3);
            let (mut hits, n) = (0, 20000);
            for _ in 0..n {
                let Some(s) = t.sample(o, rng.uniform2(), TransportMode::Radiance) else { continue };
                hits += 1;
                let (f, pdf) = (t.f(o, s.wi, TransportMode::Radiance), t.pdf(o, s.wi));
                assert!((s.pdf - pdf).abs() <= 1e-2 * pdf.max(1e-3), "{mu_o}: pdf {} vs {pdf}", s.pdf);
                assert!((s.f - f).abs().max_element() <= 2e-2 * f.max_element().max(1e-3), "{mu_o}: {} vs {f}", s.f);
            }
            assert!(hits > n * 99 / 100, "{mu_o}: {hits} samples of {n}");
            // ∫ pdf dω by uniform sphere sampling.
            let m = 200_000;
            let total: f64 = (0..m).map(|_| t.pdf(o, uniform_sphere(rng.uniform2())) as f64).sum::<f64>()
                * 4.0
                * std::f64::consts::PI
                / m as f64;
            assert!((total - 1.0).abs() < 0.03, "{mu_o}: the density integrates to {total}");
        }
    }

    #[test]
    fn damaged_files_are_errors_never_panics() {
        let dir = env!("CARGO_MANIFEST_DIR");
        let good = std::fs::read(format!("{dir}/pbrt-scenes/verify/bsdfs/glazed.bsdf")).unwrap();
        assert_eq!(FourierTable::read(b"SCATFUN\x02"), Err(FourierError::Magic));
        for end in (0..good.len()).step_by(997) {
            assert!(FourierTable::read(&good[..end]).is_err(), "cut at {end}");
        }
        let mut rng = Rng::new(5);
        for _ in 0..300 {
            let mut b = good.clone();
            let at = (rng.uniform() * b.len() as f32) as usize % b.len();
            b[at] ^= 1 << ((rng.uniform() * 8.0) as u32 % 8);
            let r = std::panic::catch_unwind(|| {
                if let Ok(t) = FourierTable::read(&b) {
                    let o = super::tests::dir(0.5, 0.1);
                    let _ = (t.f(o, -o, TransportMode::Importance), t.pdf(o, -o));
                    let _ = t.sample(o, [0.3, 0.7], TransportMode::Radiance);
                }
            });
            assert!(r.is_ok(), "flipping a bit of byte {at} panicked");
        }
    }
}
