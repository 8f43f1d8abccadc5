//! The sums behind a `spectral` film's wavelength buckets ([`crate::spectrum::buckets`]):
//! per pixel and bucket, the lane values of the passes' estimates whose wavelength fell
//! in the bucket. The passes share their wavelengths over the image, so the number of
//! lanes each bucket received is the same for every pixel and follows from the passes
//! alone ([`Buckets::counts`]); a bucket's value is its sum over that count, pbrt-v4's
//! `bucketSums / weightSums` with every weight 1.
//!
//! Lane values are in the units pbrt-v4's film multiplies its radiance into (∫ȳ dλ
//! times it): a light of luminance 1 with a flat spectrum reads 1 in every bucket.

use crate::imageio::Bands;
use crate::spectrum::Rgb;
use crate::spectrum::buckets::Buckets;
use crate::spectrum::sampled::N_SAMPLES;
use std::sync::atomic::{AtomicU64, Ordering};

/// The buckets' running sums. Each pixel's values are written by the one thread that
/// handles the pixel in a pass (camera paths, then its range of splats) and read
/// between passes; so relaxed loads and stores of the f64 bits suffice, and the sums
/// do not depend on the thread count.
pub struct BucketSums {
    pub layout: Buckets,
    /// Per pixel, `layout.count` sums.
    sums: Vec<AtomicU64>,
}

/// One pass's lanes: the bucket each falls in ([`Buckets::of_pass`]).
pub type PassLanes = [usize; N_SAMPLES];

impl BucketSums {
    /// `None` when the sums do not fit in memory.
    pub fn new(layout: Buckets, pixels: usize) -> Option<BucketSums> {
        let n = pixels.checked_mul(layout.count)?;
        let mut sums = Vec::new();
        sums.try_reserve_exact(n).ok()?;
        sums.resize_with(n, || AtomicU64::new(0));
        Some(BucketSums { layout, sums })
    }

    /// Bytes the sums of `pixels` pixels take (for the out-of-memory error).
    pub fn bytes(layout: Buckets, pixels: usize) -> usize {
        pixels.saturating_mul(layout.count).saturating_mul(8)
    }

    /// Pass `pass`'s lanes.
    pub fn lanes(&self, pass: u32) -> PassLanes {
        self.layout.of_pass(pass)
    }

    /// Adds a camera path's estimate `v` (its lanes) at `pixel`.
    #[inline]
    pub fn add(&self, pixel: usize, lanes: &PassLanes, v: Rgb) {
        let at = pixel * self.layout.count;
        for (k, b) in lanes.iter().enumerate() {
            bump(&self.sums[at + b], v[k] as f64);
        }
    }

    /// Adds light tracing's splat `v` at `pixel`, times `scale` (as the pixel's sums
    /// take it): a bucket's mean counts camera paths' and light tracing's light alike.
    // DEVIATION(pbrt): appearance, not reproducible. pbrt-v4's bdpt adds its splats
    // to the buckets over the wavelengths' density and divides them by the passes,
    // not the bucket's count: (λmax − λmin)/(nbuckets · ∫ȳ dλ) = 0.275 of their light
    // with the defaults. How much of a pixel's light that is depends on its MIS
    // weights and light-path count, which are not ours, so our buckets hold the
    // light its R, G, B show (2304 pixels, 4096 passes of a lit box with a glass
    // ball: pbrt-v4's bdpt buckets 0.73–0.80 of its volpath's).
    #[inline]
    pub fn add_splat(&self, pixel: usize, lanes: &PassLanes, v: Rgb, scale: f64) {
        self.add(pixel, lanes, v * scale as f32);
    }

    /// How many sums there are (pixels × buckets).
    pub fn sum_count(&self) -> usize {
        self.sums.len()
    }

    pub fn totals(&self) -> BucketTotals {
        BucketTotals { layout: self.layout, sums: self.save() }
    }

    /// The sums as a checkpoint saves them.
    pub fn save(&self) -> Vec<f64> {
        self.sums.iter().map(|a| f64::from_bits(a.load(Ordering::Relaxed))).collect()
    }

    /// Sets the sums from [`Self::save`]'s; `false` when the length does not match.
    pub fn restore(&mut self, saved: &[f64]) -> bool {
        if saved.len() != self.sums.len() {
            return false;
        }
        for (a, v) in self.sums.iter_mut().zip(saved) {
            *a.get_mut() = v.to_bits();
        }
        true
    }
}

/// The bucket sums of some passes, apart from their running state (what a part holds).
#[derive(Clone, Debug, PartialEq)]
pub struct BucketTotals {
    pub layout: Buckets,
    /// Per pixel, `layout.count` sums.
    pub sums: Vec<f64>,
}

impl BucketTotals {
    /// The channels after `passes`.
    pub fn bands(&self, passes: impl IntoIterator<Item = u32>) -> Bands {
        bands(self.layout, &self.sums, passes)
    }
}

/// The channels of bucket sums `sums` (per pixel, `layout.count`) over `passes`.
pub fn bands(layout: Buckets, sums: &[f64], passes: impl IntoIterator<Item = u32>) -> Bands {
    let n = layout.count;
    let counts = layout.counts(passes);
    let values = sums
        .iter()
        .enumerate()
        .map(|(i, s)| {
            // No lane fell in the bucket: pbrt-v4 writes 0.
            let c = counts[i % n];
            if c > 0.0 { (s / c) as f32 } else { 0.0 }
        })
        .collect();
    Bands { names: (0..n).map(|b| layout.channel(b)).collect(), values }
}

/// Adds `v` to the f64 in `a` (one writer at a time; see [`BucketSums`]).
#[inline]
fn bump(a: &AtomicU64, v: f64) {
    let old = f64::from_bits(a.load(Ordering::Relaxed));
    a.store((old + v).to_bits(), Ordering::Relaxed);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_spectrum_reads_its_value_in_every_bucket() {
        // Every pass adds 2 in each lane: each bucket's mean is 2, whatever its count.
        let b = BucketSums::new(Buckets::DEFAULT, 3).unwrap();
        for pass in 0..64 {
            let lanes = b.lanes(pass);
            (0..3).for_each(|px| b.add(px, &lanes, Rgb::splat(2.0)));
        }
        let bands = b.totals().bands(0..64);
        assert_eq!(bands.names.len(), 16);
        assert!(bands.values.iter().all(|&v| (v - 2.0).abs() < 1e-6), "{:?}", bands.values);
    }

    #[test]
    fn saved_sums_restore_exactly() {
        let b = BucketSums::new(Buckets { count: 4, ..Buckets::DEFAULT }, 2).unwrap();
        let lanes = b.lanes(3);
        b.add(1, &lanes, Rgb::new(0.1, 0.2, 0.3));
        b.add_splat(0, &lanes, Rgb::new(1.0, 2.0, 3.0), 0.5);
        let mut c = BucketSums::new(b.layout, 2).unwrap();
        assert!(c.restore(&b.save()));
        assert_eq!(c.save(), b.save());
        assert!(!c.restore(&[1.0]));
    }
}
