//! Provisional images inside a long iteration, for `--display-server`.
//!
//! ```text
//! pbrt-sppm render scene.pbrt --display-server localhost:14158
//! ```
//! An iteration's image exists only when it ends, and the first iteration of a large
//! render can take tens of seconds. When a preview is wanted, the camera pass (and
//! SPPM's uniform photon pass) runs in bands of pixels (photons), one after the other,
//! each band in parallel; between bands the engine offers a provisional image: the
//! pixels done so far with this iteration's light, the others as they were, and the
//! photons traced so far scaled up to the whole iteration. Bands change no pixel: each
//! pixel's sums are taken in the same order either way.

use std::ops::Range;

/// Shown between the bands of a long iteration: called with a function that makes the
/// provisional image, which it calls only when it shows one.
pub type Preview<'p> = dyn FnMut(&dyn Fn() -> Vec<[f32; 3]>) + 'p;

/// How many bands a pass is cut into when a preview is wanted.
const BANDS: usize = 16;

/// The ranges `0..n` is run in: [`BANDS`] bands of at least `min` items with a preview,
/// one range without (no cost when nobody looks); none longer than `max`.
pub fn bands(n: usize, min: usize, max: usize, preview: bool) -> Vec<Range<usize>> {
    let size = if preview { n.div_ceil(BANDS).max(min.max(1)) } else { n.max(1) }.min(max.max(1));
    (0..n).step_by(size).map(|s| s..(s + size).min(n)).collect()
}

#[cfg(test)]
mod tests {
    use super::bands;

    #[test]
    fn bands_cover_every_item_once_in_order() {
        let cases = [(0, 4, true), (1, 4, true), (100, 4, true), (1000, 1, true), (1000, 300, true), (77, 4, false)];
        for (n, min, preview) in cases {
            let b = bands(n, min, usize::MAX, preview);
            let flat: Vec<usize> = b.iter().flat_map(|r| r.clone()).collect();
            assert_eq!(flat, (0..n).collect::<Vec<_>>(), "n {n} min {min}");
            assert!(b.len() <= 16 && (preview || b.len() <= 1), "{} bands", b.len());
            assert!(b.iter().rev().skip(1).all(|r| r.len() >= min.min(n)), "a band under the minimum: {b:?}");
        }
        assert_eq!(bands(1000, 1, usize::MAX, true).len(), 16);
        let capped = bands(1000, 1, 300, false);
        assert_eq!(capped, [0..300, 300..600, 600..900, 900..1000]);
    }
}
