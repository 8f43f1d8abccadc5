//! Owen-scrambled Sobol' points, padded dimension by dimension.
//!
//! Every 1D or 2D sample a path asks for is its own small low-discrepancy sequence: the
//! first one or two Sobol' dimensions, indexed by the sample's index (for a camera
//! path, the iteration; the pixel picks the stream), with the index shuffled and the
//! values Owen-scrambled by seeds hashed from (stream, dimension). Shuffling the index
//! decorrelates one dimension from the next; because the shuffle and the scramble are
//! nested uniform scrambles, any aligned block of 2^m indices is still a (0, m, 2)-net
//! in each 2D pair. This is Burley's construction ("Practical hash-based Owen
//! scrambling", JCGT 2020), the same idea as pbrt-v4's `PaddedSobolSampler`, but it
//! needs no sample count up front, so a render with a time limit keeps its
//! stratification.
//!
//! Only two Sobol' dimensions are used, so no table of direction numbers is needed.

use super::{Sampler, mix64};

/// One point of a padded, scrambled Sobol' sequence: its `index` within the sequence
/// `stream`; each call to `get1d`/`get2d` moves on to the next dimension.
#[derive(Clone, Debug)]
pub struct SobolSample {
    stream: u64,
    /// The index, bit-reversed once (the scrambles work on reversed values).
    reversed_index: u32,
    dimension: u64,
}

impl SobolSample {
    pub fn new(stream: u64, index: u32) -> SobolSample {
        SobolSample { stream, reversed_index: index.reverse_bits(), dimension: 0 }
    }

    /// Seeds for the next dimension: (index shuffle, first value, second value). One
    /// splitmix64 step per dimension: this runs for every number a camera path draws.
    fn next_seeds(&mut self) -> (u32, u32, u32) {
        self.dimension += 1;
        let h = mix64(self.stream.wrapping_add(self.dimension.wrapping_mul(0x9e37_79b9_7f4a_7c15)));
        (h as u32, (h >> 32) as u32, (h.wrapping_mul(0xd1b5_4a32_d192_ed03) >> 32) as u32)
    }

    /// The shuffled index (a nested uniform scramble of the index).
    fn shuffled(&self, seed: u32) -> u32 {
        laine_karras(self.reversed_index, seed).reverse_bits()
    }
}

// The first Sobol' dimension is the radical inverse, reverse(i), so its Owen scramble
// reverse(laine_karras(reverse(reverse(i)))) is reverse(laine_karras(i)).
impl Sampler for SobolSample {
    fn get1d(&mut self) -> f32 {
        let (shuffle, s0, _) = self.next_seeds();
        let i = self.shuffled(shuffle);
        to_unit(laine_karras(i, s0).reverse_bits())
    }

    fn get2d(&mut self) -> [f32; 2] {
        let (shuffle, s0, s1) = self.next_seeds();
        let i = self.shuffled(shuffle);
        [to_unit(laine_karras(i, s0).reverse_bits()), to_unit(laine_karras(sobol1_reversed(i), s1).reverse_bits())]
    }

    /// A dimension is its seeds: skipping one needs no hashing.
    fn skip2d(&mut self) {
        self.dimension += 1;
    }
}

/// The second Sobol' dimension (primitive polynomial x + 1), bit-reversed: its
/// generator matrix is Pascal's triangle mod 2, column k being v_k with v_0 = 2^31 and
/// v_k = v_(k−1) ⊕ (v_(k−1) >> 1); reversed, r_0 = 1 and r_k = r_(k−1) ⊕ (r_(k−1) << 1).
/// Looked up a byte of the index at a time (the shuffled index has bits everywhere).
fn sobol1_reversed(i: u32) -> u32 {
    let t = &SOBOL1_REVERSED;
    t[0][(i & 255) as usize]
        ^ t[1][((i >> 8) & 255) as usize]
        ^ t[2][((i >> 16) & 255) as usize]
        ^ t[3][(i >> 24) as usize]
}

/// `SOBOL1_REVERSED[b][x]`: the XOR of r_(8b+j) over the set bits j of x.
static SOBOL1_REVERSED: [[u32; 256]; 4] = sobol1_tables();

const fn sobol1_tables() -> [[u32; 256]; 4] {
    let mut columns = [0u32; 32];
    let mut r = 1u32;
    let mut k = 0;
    while k < 32 {
        columns[k] = r;
        r ^= r << 1;
        k += 1;
    }
    let mut t = [[0u32; 256]; 4];
    let mut b = 0;
    while b < 4 {
        let mut x = 1;
        while x < 256 {
            // Each entry adds its lowest set bit's column to the entry without it.
            let low = (x as u32).trailing_zeros() as usize;
            t[b][x] = t[b][x & (x - 1)] ^ columns[8 * b + low];
            x += 1;
        }
        b += 1;
    }
    t
}

/// The second dimension in plain order (for tests).
#[cfg(test)]
fn sobol1(i: u32) -> u32 {
    sobol1_reversed(i).reverse_bits()
}

/// A hash in which each bit depends only on the bits below it (Vegdahl's improvement of
/// Laine and Karras's): on a bit-reversed value, an Owen scramble.
fn laine_karras(mut v: u32, seed: u32) -> u32 {
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v
}

fn to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every aligned block of 2^m consecutive indices puts exactly one point in each
    /// cell of every 2^a × 2^(m−a) grid (a (0, m, 2)-net), for any stream and dimension.
    #[test]
    fn blocks_are_nets_in_every_dimension_pair() {
        for stream in [0u64, 1, 0xdead_beef] {
            for m in [4u32, 6, 8] {
                for block in [0u32, 3] {
                    let mut points: Vec<SobolSample> =
                        (0..1u32 << m).map(|k| SobolSample::new(stream, (block << m) + k)).collect();
                    for _dimension in 0..5 {
                        let uv: Vec<[f32; 2]> = points.iter_mut().map(|s| s.get2d()).collect();
                        for a in 0..=m {
                            let (nx, ny) = (1usize << a, 1usize << (m - a));
                            let mut seen = vec![false; nx * ny];
                            for p in &uv {
                                let cell = (p[0] * nx as f32) as usize + nx * (p[1] * ny as f32) as usize;
                                assert!(!seen[cell], "stream {stream} m {m} block {block} grid {nx}x{ny}");
                                seen[cell] = true;
                            }
                        }
                    }
                }
            }
        }
    }

    /// 1D samples of one block are stratified: one in each of 2^m equal intervals.
    /// Skipping a 2D sample leaves the samples after it as drawing it would.
    #[test]
    fn skipping_a_sample_keeps_the_ones_after() {
        for k in [0u32, 5, 1000] {
            let (mut a, mut b) = (SobolSample::new(9, k), SobolSample::new(9, k));
            a.get2d();
            b.skip2d();
            assert_eq!((a.get2d(), a.get1d()), (b.get2d(), b.get1d()));
        }
    }

    #[test]
    fn one_dimensional_blocks_are_stratified() {
        let m = 7;
        let mut points: Vec<SobolSample> = (0..1u32 << m).map(|k| SobolSample::new(42, k)).collect();
        for _ in 0..4 {
            let mut seen = vec![false; 1 << m];
            for s in &mut points {
                let cell = (s.get1d() * (1 << m) as f32) as usize;
                assert!(!seen[cell]);
                seen[cell] = true;
            }
        }
    }

    /// Successive dimensions of one point are not correlated (the shuffles differ), and
    /// different streams give different points.
    #[test]
    fn dimensions_and_streams_are_decorrelated() {
        let n = 4096u32;
        let (mut sxy, mut sx, mut sy, mut sxx, mut syy) = (0f64, 0f64, 0f64, 0f64, 0f64);
        for k in 0..n {
            let mut s = SobolSample::new(7, k);
            let (x, y) = (s.get1d() as f64, s.get1d() as f64);
            sxy += x * y;
            sx += x;
            sy += y;
            sxx += x * x;
            syy += y * y;
        }
        let nf = n as f64;
        let cov = sxy / nf - sx * sy / (nf * nf);
        let corr = cov / ((sxx / nf - (sx / nf).powi(2)) * (syy / nf - (sy / nf).powi(2))).sqrt();
        assert!(corr.abs() < 0.05, "correlation {corr}");
        assert_ne!(SobolSample::new(1, 5).get2d(), SobolSample::new(2, 5).get2d());
    }

    #[test]
    fn sobol_matches_the_known_second_dimension() {
        // Sobol' dimension 2 in index (not Gray-code) order: v = 1/2, 3/4, 5/8, 15/16, …
        let want = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for (i, w) in want.iter().enumerate() {
            assert_eq!(sobol1(i as u32) as f64 / 2f64.powi(32), *w, "index {i}");
        }
        // The byte tables against the matrix applied bit by bit, over every byte.
        let direct = |mut i: u32| {
            let (mut x, mut v) = (0u32, 1u32 << 31);
            while i != 0 {
                x ^= v * (i & 1);
                i >>= 1;
                v ^= v >> 1;
            }
            x
        };
        for i in [0x0000_0100u32, 0x00ff_0000, 0x8000_0001, 0xdead_beef, u32::MAX, 12_345_678] {
            assert_eq!(sobol1(i), direct(i), "index {i:#x}");
        }
    }
}
