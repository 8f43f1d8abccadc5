//! pbrt's Catmull-Rom spline helpers (`interpolation.cpp`): weights at a point, the
//! integral of a tabulated spline, its inverse, and sampling from a family of splines
//! (one per value of a parameter). The tabulated BSDFs of pbrt-v3's `fourier` material
//! and the BSSRDF profiles of `subsurface` use them.

/// pbrt's `FindInterval`: the last i in [0, n - 2] with `pred(i)`, by bisection.
pub fn find_interval(size: usize, pred: impl Fn(usize) -> bool) -> usize {
    let (mut first, mut len) = (0usize, size);
    while len > 0 {
        let half = len >> 1;
        let middle = first + half;
        if pred(middle) {
            first = middle + 1;
            len -= half + 1;
        } else {
            len = half;
        }
    }
    (first as i64 - 1).clamp(0, size as i64 - 2) as usize
}

/// pbrt's `CatmullRomWeights`: the first of four nodes and their weights at `x`.
pub fn weights(nodes: &[f32], x: f32) -> Option<(i32, [f32; 4])> {
    let n = nodes.len();
    if n < 2 || !(x >= nodes[0] && x <= nodes[n - 1]) {
        return None;
    }
    let idx = find_interval(n, |i| nodes[i] <= x);
    let (x0, x1) = (nodes[idx], nodes[idx + 1]);
    let t = (x - x0) / (x1 - x0);
    let (t2, t3) = (t * t, t * t * t);
    let mut w = [0.0, 2.0 * t3 - 3.0 * t2 + 1.0, -2.0 * t3 + 3.0 * t2, 0.0];
    if idx > 0 {
        let w0 = (t3 - 2.0 * t2 + t) * (x1 - x0) / (x1 - nodes[idx - 1]);
        w[0] = -w0;
        w[2] += w0;
    } else {
        let w0 = t3 - 2.0 * t2 + t;
        w[1] -= w0;
        w[2] += w0;
    }
    if idx + 2 < n {
        let w3 = (t3 - t2) * (x1 - x0) / (nodes[idx + 2] - x0);
        w[1] -= w3;
        w[3] = w3;
    } else {
        let w3 = t3 - t2;
        w[1] -= w3;
        w[2] += w3;
    }
    Some((idx as i32 - 1, w))
}

/// The end derivatives of spline segment `i` over `x` of the values `f` (pbrt's finite
/// differences, one-sided at the ends), scaled to the segment's width.
fn slopes(x: &[f32], i: usize, f: impl Fn(usize) -> f32) -> (f32, f32) {
    let n = x.len();
    let (x0, x1, f0, f1) = (x[i], x[i + 1], f(i), f(i + 1));
    let width = x1 - x0;
    let d0 = if i > 0 { width * (f1 - f(i - 1)) / (x1 - x[i - 1]) } else { f1 - f0 };
    let d1 = if i + 2 < n { width * (f(i + 2) - f0) / (x[i + 2] - x0) } else { f1 - f0 };
    (d0, d1)
}

/// pbrt's `IntegrateCatmullRom`: the integral of the spline through (x, values), with
/// its running integral at each node written to `cdf`.
pub fn integrate(x: &[f32], values: &[f32], cdf: &mut [f32]) -> f32 {
    let mut sum = 0.0;
    cdf[0] = 0.0;
    for i in 0..x.len().saturating_sub(1) {
        let (d0, d1) = slopes(x, i, |k| values[k]);
        sum += ((d0 - d1) * (1.0 / 12.0) + (values[i] + values[i + 1]) * 0.5) * (x[i + 1] - x[i]);
        cdf[i + 1] = sum;
    }
    sum
}

/// pbrt's `InvertCatmullRom`: the x where the spline through (x, values), assumed
/// increasing, takes the value `u` (clamped to the ends).
pub fn invert(x: &[f32], values: &[f32], u: f32) -> f32 {
    let n = x.len();
    // NaN takes the first node, as pbrt's negated comparisons do.
    if u.is_nan() || u <= values[0] {
        return x[0];
    } else if u >= values[n - 1] {
        return x[n - 1];
    }
    let i = find_interval(n, |i| values[i] <= u);
    let (f0, f1) = (values[i], values[i + 1]);
    let (d0, d1) = slopes(x, i, |k| values[k]);
    let (mut a, mut b, mut t) = (0.0f32, 1.0f32, 0.5f32);
    // DEVIATION(pbrt): robustness. pbrt iterates until it converges; 100 steps bound
    // it (bisection alone halves the bracket to below 1e-6 within 20).
    for _ in 0..100 {
        if !(t > a && t < b) {
            t = 0.5 * (a + b);
        }
        let (t2, t3) = (t * t, t * t * t);
        let big =
            (2.0 * t3 - 3.0 * t2 + 1.0) * f0 + (-2.0 * t3 + 3.0 * t2) * f1 + (t3 - 2.0 * t2 + t) * d0 + (t3 - t2) * d1;
        let small = (6.0 * t2 - 6.0 * t) * f0
            + (-6.0 * t2 + 6.0 * t) * f1
            + (3.0 * t2 - 4.0 * t + 1.0) * d0
            + (3.0 * t2 - 2.0 * t) * d1;
        if (big - u).abs() < 1e-6 || b - a < 1e-6 {
            break;
        }
        if big - u < 0.0 {
            a = t;
        } else {
            b = t;
        }
        t -= (big - u) / small;
    }
    x[i] + t * (x[i + 1] - x[i])
}

/// pbrt's `SampleCatmullRom2D`: a family of splines over `nodes2`, one per node of
/// `nodes1` (`values` and their running integrals `cdf`, row by row), blended at
/// `alpha`; draws x with density ∝ the blend and returns (x, its density).
pub fn sample_2d(
    nodes1: &[f32],
    nodes2: &[f32],
    values: &[f32],
    cdf: &[f32],
    alpha: f32,
    u: f32,
) -> Option<(f32, f32)> {
    let n = nodes2.len();
    let (offset, w) = weights(nodes1, alpha)?;
    let at = |array: &[f32], idx: usize| -> f32 {
        (0..4).filter(|&i| w[i] != 0.0).map(|i| array[(offset + i as i32) as usize * n + idx] * w[i]).sum()
    };
    let maximum = at(cdf, n - 1);
    let u = u * maximum;
    let idx = find_interval(n, |i| at(cdf, i) <= u);
    let (f0, f1) = (at(values, idx), at(values, idx + 1));
    let (x0, x1) = (nodes2[idx], nodes2[idx + 1]);
    let width = x1 - x0;
    let u = (u - at(cdf, idx)) / width;
    let (d0, d1) = slopes(nodes2, idx, |k| at(values, k));
    let mut t = if f0 != f1 { (f0 - (f0 * f0 + 2.0 * u * (f1 - f0)).max(0.0).sqrt()) / (f0 - f1) } else { u / f0 };
    let (mut a, mut b) = (0.0f32, 1.0f32);
    for _ in 0..100 {
        if !(t >= a && t <= b) {
            t = 0.5 * (a + b);
        }
        let big = t
            * (f0
                + t * (0.5 * d0
                    + t * ((1.0 / 3.0) * (-2.0 * d0 - d1) + f1 - f0 + t * (0.25 * (d0 + d1) + 0.5 * (f0 - f1)))));
        let fhat = f0 + t * (d0 + t * (-2.0 * d0 - d1 + 3.0 * (f1 - f0) + t * (d0 + d1 + 2.0 * (f0 - f1))));
        if (big - u).abs() < 1e-6 || b - a < 1e-6 {
            return Some((x0 + width * t, fhat / maximum));
        }
        if big - u < 0.0 {
            a = t;
        } else {
            b = t;
        }
        t -= (big - u) / fhat;
    }
    // DEVIATION(pbrt): robustness. pbrt iterates without a bound; a damaged table (a
    // negative coefficient) can keep Newton from converging.
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_reproduce_a_line() {
        let x = [0.0, 0.5, 1.5, 3.0, 5.0];
        for &p in &[0.0, 0.2, 0.5, 1.0, 2.9, 4.99, 5.0] {
            let (o, w) = weights(&x, p).unwrap();
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            let line: f32 =
                (0..4).filter(|&i| w[i] != 0.0).map(|i| w[i] * (2.0 * x[(o + i as i32) as usize] + 1.0)).sum();
            assert!((line - (2.0 * p + 1.0)).abs() < 1e-4, "{p}: {line}");
        }
        assert!(weights(&x, -0.1).is_none() && weights(&x, 5.1).is_none() && weights(&x, f32::NAN).is_none());
    }

    #[test]
    fn the_integral_of_a_quadratic_is_close_and_inverting_it_finds_x_again() {
        let x: Vec<f32> = (0..40).map(|i| i as f32 * 0.05).collect();
        let f: Vec<f32> = x.iter().map(|v| v * v).collect();
        let mut cdf = vec![0.0; x.len()];
        let total = integrate(&x, &f, &mut cdf);
        let exact = 1.95f32.powi(3) / 3.0;
        assert!((total - exact).abs() < 1e-3 * exact, "{total} vs {exact}");
        for &p in &[0.1, 0.77, 1.5, 1.9] {
            let y = p * p;
            assert!((invert(&x, &f, y) - p).abs() < 1e-3, "{p}");
        }
        assert_eq!(invert(&x, &f, -1.0), 0.0);
        assert_eq!(invert(&x, &f, 100.0), 1.95);
    }
}
