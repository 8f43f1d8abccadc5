//! pbrt-v4's `spectral` film: besides R, G and B, the mean radiance in each of
//! `nbuckets` equal wavelength buckets, written as the channels `S0.<centre>nm` of the
//! OpenEXR spectral layout (Fichet et al. 2021, with `,` for the decimal point).
//!
//! ```text
//! Film "spectral" "integer nbuckets" 16 "float lambdamin" 360 "float lambdamax" 830
//!     "string filename" "out.exr"
//! ```
//! Passes then draw their wavelengths evenly over `lambdamin`..`lambdamax`, as pbrt-v4's
//! spectral film has its paths draw them, so that a bucket's value is a plain mean of
//! the radiance that fell in it (and the RGB image sees only light in that range).

use super::sampled::{Draw, N_SAMPLES};

/// The buckets' layout, as the film gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Buckets {
    pub count: usize,
    pub lambda_min: f32,
    pub lambda_max: f32,
}

impl Buckets {
    /// pbrt-v4's defaults: 16 buckets over 360–830 nm.
    pub const DEFAULT: Buckets = Buckets { count: 16, lambda_min: 360.0, lambda_max: 830.0 };

    /// The bucket wavelength `lambda` falls in (pbrt-v4's `LambdaToBucket`: truncated,
    /// then clamped to the ends).
    #[inline]
    pub fn index(&self, lambda: f32) -> usize {
        let n = self.count as f32;
        let b = (n * (lambda - self.lambda_min) / (self.lambda_max - self.lambda_min)) as i64;
        b.clamp(0, self.count as i64 - 1) as usize
    }

    /// Bucket `i`'s channel name: its centre to three decimals (as pbrt-v4 prints it).
    pub fn channel(&self, i: usize) -> String {
        let t = (i as f32 + 0.5) / self.count as f32;
        let centre = (1.0 - t) * self.lambda_min + t * self.lambda_max;
        format!("S0.{}nm", format!("{centre:.3}").replace('.', ","))
    }

    /// How passes draw their wavelengths for this film.
    pub fn draw(&self) -> Draw {
        Draw::Uniform { lo: self.lambda_min, hi: self.lambda_max }
    }

    /// The bucket each lane of pass `pass` falls in (drawn evenly, every lane has a
    /// density).
    pub fn of_pass(&self, pass: u32) -> [usize; N_SAMPLES] {
        super::transport::pass_wavelengths(self.draw(), pass).lambda.map(|l| self.index(l))
    }

    /// How many of the lanes of `passes` fell in each bucket: the passes share their
    /// wavelengths over the image, so every pixel has the same counts.
    pub fn counts(&self, passes: impl IntoIterator<Item = u32>) -> Vec<f64> {
        let mut counts = vec![0.0; self.count];
        for b in passes.into_iter().flat_map(|pass| self.of_pass(pass)) {
            counts[b] += 1.0;
        }
        counts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_are_named_by_their_centres_as_pbrt_v4_names_them() {
        // As in an image pbrt-v4 wrote with the defaults.
        let b = Buckets::DEFAULT;
        assert_eq!(b.channel(0), "S0.374,688nm");
        assert_eq!(b.channel(1), "S0.404,062nm");
        assert_eq!(b.channel(15), "S0.815,312nm");
    }

    #[test]
    fn wavelengths_fall_in_their_bucket_and_the_ends_clamp() {
        let b = Buckets { count: 4, lambda_min: 400.0, lambda_max: 800.0 };
        assert_eq!([399.0, 400.0, 499.9, 500.0, 799.9, 800.0, 900.0].map(|l| b.index(l)), [0, 0, 0, 1, 3, 3, 3]);
    }

    #[test]
    fn passes_fill_the_buckets_evenly() {
        // 2ᵐ passes of three lanes: each of 16 buckets gets 3·2ᵐ/16 lanes, within one.
        let b = Buckets::DEFAULT;
        let counts = b.counts(0..256);
        assert_eq!(counts.iter().sum::<f64>(), 768.0);
        assert!(counts.iter().all(|&c| (c - 48.0).abs() <= 1.0), "{counts:?}");
    }
}
