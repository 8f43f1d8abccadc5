//! Helpers for the sampling tests of several modules (test builds only): a small
//! deterministic generator and the histogram a χ²-style test compares with a density.

/// A 64-bit LCG's top 24 bits as a number in [0, 1).
pub fn lcg(s: &mut u64) -> f32 {
    *s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    ((*s >> 40) as f32) / (1u64 << 24) as f32
}

/// Counts of `n` points of the unit square in a `bins` × `bins` grid (row-major in y).
pub fn histogram(n: usize, bins: usize, mut point: impl FnMut() -> [f32; 2]) -> Vec<usize> {
    let mut hist = vec![0usize; bins * bins];
    let cell = |v: f32| ((v * bins as f32) as usize).min(bins - 1);
    for _ in 0..n {
        let p = point();
        hist[cell(p[1]) * bins + cell(p[0])] += 1;
    }
    hist
}

/// The mean of `f` over cell `k` of a `bins` × `bins` grid, by an `m` × `m` midpoint rule.
pub fn cell_mean(bins: usize, k: usize, m: usize, f: impl Fn([f32; 2]) -> f64) -> f64 {
    let (bx, by) = (k % bins, k / bins);
    let sum: f64 = (0..m * m)
        .map(|j| {
            let x = (bx as f32 + ((j % m) as f32 + 0.5) / m as f32) / bins as f32;
            let y = (by as f32 + ((j / m) as f32 + 0.5) / m as f32) / bins as f32;
            f([x, y])
        })
        .sum();
    sum / (m * m) as f64
}
