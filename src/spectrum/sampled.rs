//! Sampled wavelengths and the values of a spectrum at them: what a pbrt-v4 path
//! carries in place of RGB (`SampledWavelengths`, `SampledSpectrum`).
//!
//! Each path draws [`N_SAMPLES`] wavelengths from one uniform number: the first by the
//! visible-importance density p(λ) ∝ 1/cosh²(0.0072 (λ − 538 nm)) over 360–830 nm,
//! the others by the same inversion at u + i/n (mod 1). A wavelength-dependent event
//! (dispersion) keeps the first and ends the others: their densities become 0 and the
//! first's is divided by n.

use super::cie;

/// Wavelengths per path (pbrt-v4's `NSpectrumSamples` is 4).
// DEVIATION(pbrt): noise only. Three wavelengths ride in the lanes of the vector that
// holds RGB for pbrt-v3's files, so one transport code serves both; the expected image
// is the same, the colour noise of one path a little higher.
pub const N_SAMPLES: usize = 3;

/// Values of a spectrum at a path's wavelengths.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampledSpectrum(pub [f32; N_SAMPLES]);

impl SampledSpectrum {
    pub const ZERO: SampledSpectrum = SampledSpectrum([0.0; N_SAMPLES]);

    pub fn splat(v: f32) -> Self {
        Self([v; N_SAMPLES])
    }

    /// `f` of every value.
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Self(self.0.map(f))
    }

    /// `f` of each pair of values.
    pub fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        Self(std::array::from_fn(|i| f(self.0[i], o.0[i])))
    }

    /// `self / o`, 0 where `o` is 0 (pbrt-v4's `SafeDiv`).
    pub fn safe_div(self, o: Self) -> Self {
        self.zip(o, |a, b| if b != 0.0 { a / b } else { 0.0 })
    }

    pub fn average(self) -> f32 {
        self.0.iter().sum::<f32>() / N_SAMPLES as f32
    }

    pub fn max_component(self) -> f32 {
        self.0.iter().copied().fold(f32::MIN, f32::max)
    }

    pub fn is_black(self) -> bool {
        self.0.iter().all(|&v| v == 0.0)
    }
}

impl std::ops::Add for SampledSpectrum {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        self.zip(o, |a, b| a + b)
    }
}

impl std::ops::Mul for SampledSpectrum {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        self.zip(o, |a, b| a * b)
    }
}

impl std::ops::Mul<f32> for SampledSpectrum {
    type Output = Self;
    fn mul(self, s: f32) -> Self {
        self.map(|a| a * s)
    }
}

/// A path's wavelengths (nm) and the density each was drawn with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    pub lambda: [f32; N_SAMPLES],
    pub pdf: [f32; N_SAMPLES],
}

impl SampledWavelengths {
    /// [`N_SAMPLES`] wavelengths by visible importance from one uniform number in [0, 1).
    pub fn sample_visible(u: f32) -> Self {
        let lambda: [f32; N_SAMPLES] = std::array::from_fn(|i| {
            let mut up = u + i as f32 / N_SAMPLES as f32;
            if up > 1.0 {
                up -= 1.0;
            }
            sample_visible_wavelength(up)
        });
        Self { lambda, pdf: lambda.map(visible_wavelength_pdf) }
    }

    /// [`N_SAMPLES`] wavelengths spread evenly over `lo`..`hi` nm from one uniform
    /// number, each of density 1/(hi − lo) (pbrt-v4's `SampleUniform`).
    pub fn sample_uniform(u: f32, lo: f32, hi: f32) -> Self {
        let delta = (hi - lo) / N_SAMPLES as f32;
        let mut lambda = [lo + u * (hi - lo); N_SAMPLES];
        for i in 1..N_SAMPLES {
            lambda[i] = lambda[i - 1] + delta;
            if lambda[i] > hi {
                lambda[i] = lo + (lambda[i] - hi);
            }
        }
        Self { lambda, pdf: [1.0 / (hi - lo); N_SAMPLES] }
    }

    pub fn pdf(&self) -> SampledSpectrum {
        SampledSpectrum(self.pdf)
    }

    /// Keeps only the first wavelength, for an event that scatters each one its own
    /// way (dispersion).
    pub fn terminate_secondary(&mut self) {
        if self.secondary_terminated() {
            return;
        }
        self.pdf[1..].fill(0.0);
        self.pdf[0] /= N_SAMPLES as f32;
    }

    pub fn secondary_terminated(&self) -> bool {
        self.pdf[1..].iter().all(|&p| p == 0.0)
    }

    /// A spectrum given as a function of λ (nm), at these wavelengths.
    pub fn sample(&self, s: impl Fn(f32) -> f32) -> SampledSpectrum {
        SampledSpectrum(self.lambda.map(s))
    }

    /// The CIE XYZ estimate of radiance `l` carried at these wavelengths, as pbrt-v4's
    /// `cie1931` sensor records it (before its lights' photometric normalisation
    /// cancels the ∫ȳ): the average over wavelengths of x̄(λ) L(λ) / p(λ).
    pub fn to_xyz(&self, l: SampledSpectrum) -> [f32; 3] {
        let weighted = l.safe_div(self.pdf());
        let mut xyz = [0.0f32; 3];
        for (i, lambda) in self.lambda.iter().enumerate() {
            let cmf = cie::cmf_at(*lambda as f64);
            for k in 0..3 {
                xyz[k] += cmf[k] as f32 * weighted.0[i];
            }
        }
        xyz.map(|c| c / N_SAMPLES as f32)
    }
}

/// How passes draw their wavelengths: by visible importance over 360–830 nm (pbrt-v4's
/// `rgb` and `gbuffer` films), or evenly over a `spectral` film's range (so that each
/// of its buckets holds a plain mean).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Draw {
    Visible,
    Uniform { lo: f32, hi: f32 },
}

impl Draw {
    pub fn sample(self, u: f32) -> SampledWavelengths {
        match self {
            Draw::Visible => SampledWavelengths::sample_visible(u),
            Draw::Uniform { lo, hi } => SampledWavelengths::sample_uniform(u, lo, hi),
        }
    }
}

/// The inverse of the visible-importance distribution's CDF.
pub fn sample_visible_wavelength(u: f32) -> f32 {
    538.0 - 138.888_89 * (0.856_910_6 - 1.827_502 * u).atanh()
}

/// p(λ) = 0.0039398042 / cosh²(0.0072 (λ − 538)), 0 outside 360–830 nm.
pub fn visible_wavelength_pdf(lambda: f32) -> f32 {
    if !(360.0..=830.0).contains(&lambda) {
        return 0.0;
    }
    0.003_939_804 / (0.0072 * (lambda - 538.0)).cosh().powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visible_wavelengths_cover_the_range_with_their_density() {
        assert!((sample_visible_wavelength(0.0) - 360.0).abs() < 0.1);
        assert!((sample_visible_wavelength(1.0) - 830.0).abs() < 0.1);
        // The density integrates to 1 over 360–830 nm and is the CDF's derivative.
        let total: f32 = (0..4700).map(|i| visible_wavelength_pdf(360.05 + i as f32 * 0.1) * 0.1).sum();
        assert!((total - 1.0).abs() < 1e-3, "{total}");
        let (u, du) = (0.3f32, 1e-3f32);
        let slope = (sample_visible_wavelength(u + du) - sample_visible_wavelength(u - du)) / (2.0 * du);
        let pdf = visible_wavelength_pdf(sample_visible_wavelength(u));
        assert!((slope * pdf - 1.0).abs() < 1e-2, "{slope} {pdf}");
    }

    #[test]
    fn terminating_secondaries_keeps_the_first_at_a_quarter_density() {
        let mut l = SampledWavelengths::sample_visible(0.4);
        let first = l.pdf[0];
        assert!(!l.secondary_terminated());
        l.terminate_secondary();
        l.terminate_secondary();
        assert_eq!(l.pdf, [first / 3.0, 0.0, 0.0]);
    }

    #[test]
    fn a_flat_spectrum_averages_to_the_y_integral() {
        // E[ȳ(λ)/p(λ)] = ∫ȳ: with many wavelength draws, a spectrum of 1 records
        // Y ≈ 106.86, which lights divide out (their photometric normalisation).
        let n = 20_000;
        let y: f64 = (0..n)
            .map(|i| SampledWavelengths::sample_visible((i as f32 + 0.5) / n as f32))
            .map(|l| l.to_xyz(SampledSpectrum::splat(1.0))[1] as f64)
            .sum::<f64>()
            / n as f64;
        assert!((y - cie::y_integral()).abs() < 0.05, "{y}");
    }
}
