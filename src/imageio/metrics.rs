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
