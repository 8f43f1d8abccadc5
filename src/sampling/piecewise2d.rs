//! pbrt-v4's `PiecewiseLinear2D` (after Mitsuba's `Marginal2D`): a density on the unit
//! square given by values on an nx × ny grid and interpolated bilinearly, optionally
//! depending on `D` more parameters (each tabulated at its own nodes and interpolated
//! linearly). It is evaluated, sampled (a row by the marginal, then a column by the
//! conditional, each inverting a linear density exactly) and inverted, as pbrt does.
//! The `measured` material's tables are of this kind.
//!
//! Data are laid out `N0 × N1 × … × ny × nx`, x fastest, the first parameter slowest.

use crate::math::catmull_rom::find_interval;

/// A point of the unit square and the density there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlSample {
    pub p: [f32; 2],
    pub pdf: f32,
}

/// The table (pbrt's `PiecewiseLinear2D<Dimension>`).
#[derive(Debug, PartialEq)]
pub struct PiecewiseLinear2D<const D: usize> {
    /// Nodes along x and y (at least 2 each).
    size: [usize; 2],
    /// Cells along x and y.
    cells: [f32; 2],
    /// What `evaluate` multiplies the interpolated value by: the cell count for a
    /// density (its values are per cell of the unit square), 1 for an interpolant.
    scale: f32,
    /// Each parameter's nodes, increasing.
    params: [Vec<f32>; D],
    /// Each parameter's stride in slices (0 for a parameter with one node).
    strides: [usize; D],
    /// The values, scaled so that each slice integrates to 1 when it has CDFs.
    data: Vec<f32>,
    /// Per slice, the running integral over rows (ny values) and along each row (nx
    /// values per row); empty without CDFs.
    marginal_cdf: Vec<f32>,
    conditional_cdf: Vec<f32>,
}

/// The slices a lookup blends (up to 2^D of them) and their weights.
struct Corners {
    slice: [usize; 8],
    weight: [f32; 8],
    n: usize,
}

impl Corners {
    /// The blend of `table` at index `i` of each slice, slices being `size` apart.
    #[inline]
    fn lookup(&self, table: &[f32], i: usize, size: usize) -> f32 {
        (0..self.n).map(|k| self.weight[k] * table[i + self.slice[k] * size]).sum()
    }
}

/// u solving ∫₀ᵘ ((1 − t)·v0 + t·v1) dt = x (pbrt's linear-density inversion).
fn invert_linear(v0: f32, v1: f32, x: f32) -> f32 {
    if (v0 - v1).abs() < 1e-4 * (v0 + v1) {
        2.0 * x / (v0 + v1)
    } else {
        (v0 - (v0 * v0 - 2.0 * x * (v0 - v1)).max(0.0).sqrt()) / (v0 - v1)
    }
}

impl<const D: usize> PiecewiseLinear2D<D> {
    /// A table of `data` (`size` = [nx, ny]) over parameters with nodes `params`. With
    /// `warp` it can be sampled and inverted, and each slice is normalised to a
    /// density; without, it interpolates the values as given (pbrt's `normalize` and
    /// `build_cdf` both false).
    pub fn new(data: &[f32], size: [usize; 2], params: [&[f32]; D], warp: bool) -> Result<Self, String> {
        assert!(D <= 3, "at most three parameters");
        let [nx, ny] = size;
        if nx < 2 || ny < 2 {
            return Err(format!("a {nx} × {ny} grid (at least 2 × 2 needed)"));
        }
        let mut strides = [0; D];
        let mut slices = 1usize;
        for d in (0..D).rev() {
            if params[d].is_empty() {
                return Err("a parameter without nodes".into());
            }
            strides[d] = if params[d].len() > 1 { slices } else { 0 };
            slices = slices.saturating_mul(params[d].len());
        }
        if Some(data.len()) != slices.checked_mul(nx * ny) {
            return Err(format!("{} values for {slices} slices of {nx} × {ny}", data.len()));
        }
        let mut t = PiecewiseLinear2D {
            size,
            cells: [(nx - 1) as f32, (ny - 1) as f32],
            scale: if warp { ((nx - 1) * (ny - 1)) as f32 } else { 1.0 },
            params: params.map(|p| p.to_vec()),
            strides,
            data: data.to_vec(),
            marginal_cdf: Vec::new(),
            conditional_cdf: Vec::new(),
        };
        if warp {
            t.build_cdfs(slices);
        }
        Ok(t)
    }

    /// The CDFs of every slice, sums taken in f64 as pbrt does.
    fn build_cdfs(&mut self, slices: usize) {
        let [nx, ny] = self.size;
        let n = nx * ny;
        self.conditional_cdf = vec![0.0; slices * n];
        self.marginal_cdf = vec![0.0; slices * ny];
        for s in 0..slices {
            let (data, cond) = (&mut self.data[s * n..(s + 1) * n], &mut self.conditional_cdf[s * n..(s + 1) * n]);
            for y in 0..ny {
                let mut sum = 0.0f64;
                for x in 0..nx - 1 {
                    let i = y * nx + x;
                    sum += 0.5 * (data[i] as f64 + data[i + 1] as f64);
                    cond[i + 1] = sum as f32;
                }
            }
            let marg = &mut self.marginal_cdf[s * ny..(s + 1) * ny];
            let mut sum = 0.0f64;
            for y in 0..ny - 1 {
                sum += 0.5 * (cond[(y + 1) * nx - 1] as f64 + cond[(y + 2) * nx - 1] as f64);
                marg[y + 1] = sum as f32;
            }
            // DEVIATION(pbrt): robustness. A slice without mass stays zero (pbrt divides
            // by its zero total and fills it with NaN).
            let total = marg[ny - 1];
            let norm = if total > 0.0 && total.is_finite() { 1.0 / total } else { 0.0 };
            cond.iter_mut().chain(marg.iter_mut()).chain(data.iter_mut()).for_each(|v| *v *= norm);
        }
    }

    /// The slices around `param` and their weights.
    fn corners(&self, param: [f32; D]) -> Corners {
        let mut c = Corners { slice: [0; 8], weight: [0.0; 8], n: 1 };
        c.weight[0] = 1.0;
        for ((nodes, &stride), &x) in self.params.iter().zip(&self.strides).zip(&param) {
            if nodes.len() == 1 {
                continue;
            }
            let i = find_interval(nodes.len(), |k| nodes[k] <= x);
            let w1 = (x - nodes[i]) / (nodes[i + 1] - nodes[i]);
            // NaN (equal nodes, a NaN parameter) falls to the lower node.
            let w1 = if w1.is_nan() { 0.0 } else { w1.clamp(0.0, 1.0) };
            for k in 0..c.n {
                c.slice[k + c.n] = c.slice[k] + (i + 1) * stride;
                c.weight[k + c.n] = c.weight[k] * w1;
                c.slice[k] += i * stride;
                c.weight[k] *= 1.0 - w1;
            }
            c.n *= 2;
        }
        c
    }

    /// The values as stored (scaled to densities when the table has CDFs).
    pub fn values(&self) -> &[f32] {
        &self.data
    }

    /// Nodes along x and y.
    pub fn size(&self) -> [usize; 2] {
        self.size
    }

    /// Each parameter's nodes.
    pub fn params(&self) -> &[Vec<f32>; D] {
        &self.params
    }

    fn slice_size(&self) -> usize {
        self.size[0] * self.size[1]
    }

    /// The density (or the interpolated value, without CDFs) at `p`.
    pub fn evaluate(&self, p: [f32; 2], param: [f32; D]) -> f32 {
        let c = self.corners(param);
        let (i, w) = self.cell(p);
        let (nx, n) = (self.size[0], self.slice_size());
        let v = |k: usize| c.lookup(&self.data, i + k, n);
        let (v00, v10, v01, v11) = (v(0), v(1), v(nx), v(nx + 1));
        let f = (1.0 - w[1]) * ((1.0 - w[0]) * v00 + w[0] * v10) + w[1] * ((1.0 - w[0]) * v01 + w[0] * v11);
        f * self.scale
    }

    /// The cell holding `p` (its first node's index) and `p`'s place in it.
    fn cell(&self, p: [f32; 2]) -> (usize, [f32; 2]) {
        let [nx, ny] = self.size;
        let (x, y) = (p[0] * self.cells[0], p[1] * self.cells[1]);
        // Negative and NaN positions fall to cell 0, as `as usize` saturates.
        let (cx, cy) = ((x as usize).min(nx - 2), (y as usize).min(ny - 2));
        (cy * nx + cx, [x - cx as f32, y - cy as f32])
    }

    /// A point drawn from the density by `u`, and its density.
    pub fn sample(&self, u: [f32; 2], param: [f32; D]) -> PlSample {
        let [nx, ny] = self.size;
        let n = self.slice_size();
        let c = self.corners(param);
        let one_minus = 1.0 - f32::EPSILON / 2.0;
        let (mut ux, mut uy) = (u[0].clamp(1.0 - one_minus, one_minus), u[1].clamp(1.0 - one_minus, one_minus));
        let marginal = |k: usize| c.lookup(&self.marginal_cdf, k, ny);
        let row = find_interval(ny, |k| marginal(k) < uy);
        uy -= marginal(row);
        let row_at = row * nx;
        let r0 = c.lookup(&self.conditional_cdf, row_at + nx - 1, n);
        let r1 = c.lookup(&self.conditional_cdf, row_at + 2 * nx - 1, n);
        let ty = invert_linear(r0, r1, uy);
        ux *= (1.0 - ty) * r0 + ty * r1;
        let conditional = |k: usize| {
            (1.0 - ty) * c.lookup(&self.conditional_cdf, row_at + k, n)
                + ty * c.lookup(&self.conditional_cdf, row_at + nx + k, n)
        };
        let col = find_interval(nx, |k| conditional(k) < ux);
        ux -= conditional(col);
        let at = row_at + col;
        let v = |k: usize| c.lookup(&self.data, at + k, n);
        let c0 = (1.0 - ty) * v(0) + ty * v(nx);
        let c1 = (1.0 - ty) * v(1) + ty * v(nx + 1);
        let tx = invert_linear(c0, c1, ux);
        let p = [(col as f32 + tx) / self.cells[0], (row as f32 + ty) / self.cells[1]];
        let pdf = ((1.0 - tx) * c0 + tx * c1) * self.cells[0] * self.cells[1];
        finite(p, pdf)
    }

    /// The inverse of [`Self::sample`]: the square's point that samples to `p`, and the
    /// density at `p`.
    pub fn invert(&self, p: [f32; 2], param: [f32; D]) -> PlSample {
        let [nx, ny] = self.size;
        let n = self.slice_size();
        let c = self.corners(param);
        let (i, w) = self.cell(p);
        let row = i / nx;
        let v = |k: usize| c.lookup(&self.data, i + k, n);
        let c0 = (1.0 - w[1]) * v(0) + w[1] * v(nx);
        let c1 = (1.0 - w[1]) * v(1) + w[1] * v(nx + 1);
        let pdf = (1.0 - w[0]) * c0 + w[0] * c1;
        let mut x = w[0] * (c0 + 0.5 * w[0] * (c1 - c0));
        let cond = |k: usize| c.lookup(&self.conditional_cdf, k, n);
        x += (1.0 - w[1]) * cond(i) + w[1] * cond(i + nx);
        let (r0, r1) = (cond(row * nx + nx - 1), cond(row * nx + 2 * nx - 1));
        x /= (1.0 - w[1]) * r0 + w[1] * r1;
        let mut y = w[1] * (r0 + 0.5 * w[1] * (r1 - r0));
        y += c.lookup(&self.marginal_cdf, row, ny);
        finite([x, y], pdf * self.cells[0] * self.cells[1])
    }
}

/// `p` and `pdf`, or a zero density where a degenerate table made them non-finite.
fn finite(p: [f32; 2], pdf: f32) -> PlSample {
    if p[0].is_finite() && p[1].is_finite() && pdf.is_finite() {
        PlSample { p, pdf }
    } else {
        PlSample { p: [0.5, 0.5], pdf: 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::testing::{cell_mean, histogram, lcg};

    /// A 5 × 4 slice pair over one parameter with two nodes.
    fn table() -> PiecewiseLinear2D<1> {
        let a: Vec<f32> = (0..20).map(|k| 0.2 + ((k * 7) % 5) as f32).collect();
        let b: Vec<f32> = (0..20).map(|k| 1.0 + (k % 3) as f32 * 2.0).collect();
        let data: Vec<f32> = a.iter().chain(&b).copied().collect();
        PiecewiseLinear2D::new(&data, [5, 4], [&[0.0, 1.0]], true).unwrap()
    }

    #[test]
    fn the_density_integrates_to_one_and_sampling_inverts() {
        let t = table();
        for param in [0.0, 0.3, 1.0] {
            // Midpoint rule over the square: a bilinear density is integrated exactly
            // cell by cell in the limit; 400 × 400 is within 1e-3.
            let m = 400;
            let sum: f32 = (0..m * m)
                .map(|k| t.evaluate([((k % m) as f32 + 0.5) / m as f32, ((k / m) as f32 + 0.5) / m as f32], [param]))
                .sum::<f32>()
                / (m * m) as f32;
            assert!((sum - 1.0).abs() < 1e-3, "param {param}: integral {sum}");
            let mut s = 7;
            for _ in 0..200 {
                let u = [lcg(&mut s), lcg(&mut s)];
                let x = t.sample(u, [param]);
                let back = t.invert(x.p, [param]);
                assert!(
                    (back.p[0] - u[0]).abs() < 2e-3 && (back.p[1] - u[1]).abs() < 2e-3,
                    "{u:?} -> {x:?} -> {back:?}"
                );
                let pdf = t.evaluate(x.p, [param]);
                assert!((pdf - x.pdf).abs() < 1e-3 * pdf.max(1.0), "{pdf} vs {}", x.pdf);
                assert!((back.pdf - x.pdf).abs() < 1e-3 * pdf.max(1.0));
            }
        }
    }

    #[test]
    fn samples_follow_the_density() {
        // χ²-style check on a 4 × 4 histogram: counts within 5σ of their expectation.
        let t = table();
        let (n, bins) = (200_000, 4usize);
        let mut s = 11;
        let hist = histogram(n, bins, || t.sample([lcg(&mut s), lcg(&mut s)], [0.3]).p);
        for (k, &count) in hist.iter().enumerate() {
            let expected = cell_mean(bins, k, 200, |p| t.evaluate(p, [0.3]) as f64) / (bins * bins) as f64 * n as f64;
            assert!((count as f64 - expected).abs() < 5.0 * expected.sqrt() + 1.0, "bin {k}: {count} vs {expected}");
        }
    }

    #[test]
    fn interpolants_keep_their_values_and_degenerate_tables_stay_finite() {
        let t = PiecewiseLinear2D::<0>::new(&[1.0, 2.0, 3.0, 4.0], [2, 2], [], false).unwrap();
        assert_eq!(t.evaluate([0.0, 0.0], []), 1.0);
        assert_eq!(t.evaluate([1.0, 1.0], []), 4.0);
        assert_eq!(t.evaluate([0.5, 0.5], []), 2.5);
        let zero = PiecewiseLinear2D::<0>::new(&[0.0; 4], [2, 2], [], true).unwrap();
        let s = zero.sample([0.3, 0.6], []);
        assert!(s.pdf == 0.0 && s.p.iter().all(|v| v.is_finite()));
        let nan = PiecewiseLinear2D::<0>::new(&[f32::NAN, 1.0, 1.0, 1.0], [2, 2], [], true).unwrap();
        for u in [[0.1, 0.2], [0.9, 0.9]] {
            let s = nan.sample(u, []);
            assert!(s.pdf.is_finite() && s.p.iter().all(|v| v.is_finite()));
            assert!(nan.invert(s.p, []).pdf.is_finite());
        }
        assert!(PiecewiseLinear2D::<0>::new(&[1.0; 3], [3, 1], [], true).is_err());
        assert!(PiecewiseLinear2D::<1>::new(&[1.0; 4], [2, 2], [&[0.0, 1.0]], true).is_err());
    }
}
