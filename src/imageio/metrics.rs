//! Image error metrics over all pixels and channels (shared with the tools).

/// Mean squared error.
pub fn mse(a: &[[f32; 3]], r: &[[f32; 3]]) -> f64 {
    mean(a, r, |x, y| (x - y) * (x - y))
}

/// Relative MSE: mean((x − r)² / (r² + 0.01)).
pub fn relmse(a: &[[f32; 3]], r: &[[f32; 3]]) -> f64 {
    mean(a, r, |x, y| (x - y) * (x - y) / (y * y + 0.01))
}

fn mean(a: &[[f32; 3]], r: &[[f32; 3]], f: impl Fn(f64, f64) -> f64) -> f64 {
    let n = (a.len().min(r.len()) * 3).max(1) as f64;
    a.iter()
        .zip(r)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] as f64, q[c] as f64)))
        .map(|(x, y)| f(x, y))
        .sum::<f64>()
        / n
}

/// Mean absolute error.
pub fn mae(a: &[[f32; 3]], r: &[[f32; 3]]) -> f64 {
    mean(a, r, |x, y| (x - y).abs())
}

/// The largest absolute difference in any channel.
pub fn max_abs(a: &[[f32; 3]], r: &[[f32; 3]]) -> f64 {
    a.iter().zip(r).flat_map(|(p, q)| (0..3).map(move |c| (p[c] as f64 - q[c] as f64).abs())).fold(0.0, f64::max)
}

/// The share of pixels whose largest channel difference exceeds `threshold`.
pub fn share_above(a: &[[f32; 3]], r: &[[f32; 3]], threshold: f64) -> f64 {
    let n = a.len().min(r.len()).max(1) as f64;
    a.iter().zip(r).filter(|(p, q)| (0..3).any(|c| (p[c] as f64 - q[c] as f64).abs() > threshold)).count() as f64 / n
}

/// Every metric `pbrt-imgtool diff` reports.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Diff {
    pub mse: f64,
    pub rmse: f64,
    pub relmse: f64,
    pub mae: f64,
    pub max_abs: f64,
    pub share_above: f64,
}

pub fn diff(a: &[[f32; 3]], r: &[[f32; 3]], pixel_threshold: f64) -> Diff {
    let m = mse(a, r);
    Diff {
        mse: m,
        rmse: m.sqrt(),
        relmse: relmse(a, r),
        mae: mae(a, r),
        max_abs: max_abs(a, r),
        share_above: share_above(a, r, pixel_threshold),
    }
}

/// Channel means of each tile of a `grid`×`grid` split (row-major from the top left);
/// tile edges fall at ⌊k·size/grid⌋.
pub fn tile_means(px: &[[f32; 3]], width: usize, height: usize, grid: usize) -> Vec<[f64; 3]> {
    let edge = |k: usize, size: usize| k * size / grid;
    let mut out = Vec::with_capacity(grid * grid);
    for ty in 0..grid {
        for tx in 0..grid {
            let (x0, x1, y0, y1) = (edge(tx, width), edge(tx + 1, width), edge(ty, height), edge(ty + 1, height));
            let mut sum = [0.0f64; 3];
            for y in y0..y1 {
                for p in &px[y * width + x0..y * width + x1] {
                    (0..3).for_each(|c| sum[c] += p[c] as f64);
                }
            }
            let n = ((x1 - x0) * (y1 - y0)).max(1) as f64;
            out.push(sum.map(|s| s / n));
        }
    }
    out
}

/// The worst relative deviation of `a`'s channel means from the reference's, over the
/// whole image and every tile of a `grid`×`grid` split. A mean below `floor` × the
/// reference's whole-image mean of that channel is compared against that floor, so
/// near-black tiles are held to an absolute bound instead of a ratio of noise.
/// Returns (deviation, "where": `image` or `tile (x, y)`, channel).
pub fn worst_mean_deviation(
    a: &[[f32; 3]],
    r: &[[f32; 3]],
    width: usize,
    height: usize,
    grid: usize,
    floor: f64,
) -> (f64, String, usize) {
    let whole = |px: &[[f32; 3]]| tile_means(px, width, height, 1)[0];
    let (wa, wr) = (whole(a), whole(r));
    let mut worst = (0.0, String::new(), 0);
    let mut consider = |ma: [f64; 3], mr: [f64; 3], at: String| {
        for c in 0..3 {
            let d = (ma[c] - mr[c]).abs() / mr[c].max(floor * wr[c]).max(1e-30);
            if d > worst.0 || worst.1.is_empty() {
                worst = (d, at.clone(), c);
            }
        }
    };
    consider(wa, wr, "image".into());
    let (ta, tr) = (tile_means(a, width, height, grid), tile_means(r, width, height, grid));
    for (k, (ma, mr)) in ta.into_iter().zip(tr).enumerate() {
        consider(ma, mr, format!("tile ({}, {})", k % grid, k / grid));
    }
    worst
}

/// A false colour for t in [0, 1]: black → blue → red → yellow → white.
pub fn heat(t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0) * 4.0;
    let stops = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0]];
    let i = (t as usize).min(3);
    let f = t - i as f32;
    [0, 1, 2].map(|c| stops[i][c] * (1.0 - f) + stops[i + 1][c] * f)
}

/// Least-squares slope of log(y) against log(x); `None` with fewer than two distinct x.
pub fn log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points.iter().map(|&(x, y)| (x.ln(), y.ln())).collect();
    let n = logs.len() as f64;
    let (mx, my) = logs.iter().fold((0.0, 0.0), |(a, b), &(x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = logs.iter().fold((0.0, 0.0), |(a, b), &(x, y)| (a + (x - mx) * (y - my), b + (x - mx).powi(2)));
    (sxx > 1e-12).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_slope_recovers_power_laws() {
        let pts: Vec<(f64, f64)> = (1..20).map(|i| (i as f64, 3.0 * (i as f64).powf(-0.75))).collect();
        assert!((log_slope(&pts).unwrap() + 0.75).abs() < 1e-12);
        assert_eq!(log_slope(&[(2.0, 1.0), (2.0, 5.0)]), None, "one distinct x has no slope");
    }

    #[test]
    fn tile_means_find_a_local_difference_a_whole_image_mean_hides() {
        let (w, h) = (8, 8);
        let r = vec![[1.0f32; 3]; w * h];
        // Brighter in the top-left 2×2 tile, darker by as much in the bottom-right one.
        let a: Vec<[f32; 3]> = (0..w * h)
            .map(|i| match (i % w / 2, i / w / 2) {
                (0, 0) => [1.2; 3],
                (3, 3) => [0.8; 3],
                _ => [1.0; 3],
            })
            .collect();
        assert_eq!(tile_means(&a, w, h, 4)[0], [1.2f32 as f64; 3]);
        let (d, at, _) = worst_mean_deviation(&a, &r, w, h, 4, 0.05);
        assert!((d - 0.2).abs() < 1e-6 && at == "tile (0, 0)", "{d} {at}");
        let (d, at, _) = worst_mean_deviation(&a, &r, w, h, 1, 0.05);
        assert!(d < 1e-6 && at == "image", "the whole-image mean is unchanged: {d}");
    }

    #[test]
    fn metrics_on_a_hand_made_pair() {
        let a = [[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]];
        let r = [[1.0, 2.0, 2.0], [0.0, 0.5, 0.0]];
        // Differences: 0,0,1 and 0,-0.5,0 over six samples.
        assert_eq!(mse(&a, &r), (1.0 + 0.25) / 6.0);
        assert_eq!(mae(&a, &r), 1.5 / 6.0);
        assert_eq!(max_abs(&a, &r), 1.0);
        assert_eq!(share_above(&a, &r, 0.6), 0.5);
        let rel = (1.0 / (4.0 + 0.01) + 0.25 / (0.25 + 0.01)) / 6.0;
        assert!((relmse(&a, &r) - rel).abs() < 1e-12);
        assert_eq!(heat(0.0), [0.0; 3]);
        assert_eq!(heat(1.0), [1.0; 3]);
    }
}
