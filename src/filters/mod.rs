//! pbrt-v4's pixel filters, as its SPPM uses them: each camera ray leaves from an
//! offset to the pixel's centre drawn in proportion to |f|, and what it finds counts
//! in full (pbrt-v4's SPPM drops the filter weight), so the image is the scene seen
//! through the filter's blur. pbrt-v4's default, a Gaussian of radius 1.5, softens
//! every edge by about a pixel.
//!
//! ```text
//! PixelFilter "gaussian" "float xradius" 1.5 "float yradius" 1.5 "float sigma" 0.5  # v4 default
//! PixelFilter "box" "float xradius" 0.5 "float yradius" 0.5
//! PixelFilter "mitchell" "float B" 0.3333 "float C" 0.3333     # radius 2
//! PixelFilter "sinc" "float tau" 3                             # radius 4
//! PixelFilter "triangle"                                       # radius 2
//! ```
//! Box and triangle are sampled exactly, the others as pbrt-v4's `FilterSampler`
//! does: |f| tabulated at 32 cells per unit of radius, constant within a cell. Every
//! filter pbrt-v4 has is separable, so the two axes are drawn apart. pbrt-v3's SPPM
//! starts its rays uniformly in the pixel whatever the filter.
//!
//! vcm and bdpt draw their camera rays the same way for pbrt-v4's files and spread
//! each light-tracing splat over the pixels within the radius, weighted by the density
//! those pixels' rays are drawn with ([`PixelFilter::density`]); so both estimate the
//! image blurred by |f|, as pbrt-v4's path tracers blur it by f.

mod gaussian;
mod mitchell;
mod sinc;
mod triangle;

use crate::parser::params::ParamList;
use crate::values::{self, Range, Res};

/// How one axis of a filter is drawn.
#[derive(Clone, Debug, PartialEq)]
enum Axis {
    Uniform,
    Tent,
    /// The cumulative |f| at the ends of equal cells across [−r, r], from 0 to 1.
    Table(Vec<f32>),
}

/// A filter's radius and how offsets are drawn within it.
#[derive(Clone, Debug, PartialEq)]
pub struct PixelFilter {
    /// pbrt-v4's name for it.
    pub name: String,
    radius: [f32; 2],
    axes: [Axis; 2],
}

impl PixelFilter {
    /// The filter pbrt-v4 makes of `PixelFilter name ...`; `None` for a box of half a
    /// pixel (rays start uniformly in the pixel, as without a filter).
    pub fn new(name: &str, p: &ParamList) -> Res<Option<PixelFilter>> {
        let default = match name {
            "box" => 0.5,
            "gaussian" => 1.5,
            "sinc" => 4.0,
            _ => 2.0,
        };
        let radius = [
            values::float(p, "xradius", default, Range::Positive)?,
            values::float(p, "yradius", default, Range::Positive)?,
        ];
        let profile: Box<dyn Fn(f32, f32) -> f32> = match name {
            "box" if radius == [0.5, 0.5] => return Ok(None),
            "box" => return Ok(Some(PixelFilter { name: name.into(), radius, axes: [Axis::Uniform, Axis::Uniform] })),
            "triangle" => return Ok(Some(PixelFilter { name: name.into(), radius, axes: [Axis::Tent, Axis::Tent] })),
            "gaussian" => Box::new(gaussian::profile(p)?),
            "mitchell" => Box::new(mitchell::profile(p)?),
            "sinc" => Box::new(sinc::profile(p)?),
            _ => return Ok(None), // unknown names are refused where the file is read
        };
        let axes = radius.map(|r| Axis::Table(table(|x| profile(x, r).abs(), r)));
        Ok(Some(PixelFilter { name: name.into(), radius, axes }))
    }

    /// How far the filter reaches from a pixel's centre, in pixels.
    pub fn radius(&self) -> [f32; 2] {
        self.radius
    }

    /// The density [`Self::sample`] draws offset `d` with: |f(d)| / ∫|f| as tabulated
    /// (0 beyond the radius). Light tracing weighs its splats by it, so that what it
    /// adds to a pixel is what the pixel's own rays would have found.
    pub fn density(&self, d: [f32; 2]) -> f32 {
        (0..2)
            .map(|k| {
                let (r, x) = (self.radius[k], d[k]);
                if x.abs() >= r {
                    return 0.0;
                }
                match &self.axes[k] {
                    Axis::Uniform => 0.5 / r,
                    Axis::Tent => (r - x.abs()) / (r * r),
                    Axis::Table(cdf) => {
                        let n = cdf.len() - 1;
                        let i = (((x + r) / (2.0 * r) * n as f32) as usize).min(n - 1);
                        (cdf[i + 1] - cdf[i]) * n as f32 / (2.0 * r)
                    }
                }
            })
            .product()
    }

    /// An offset from the pixel's centre for the uniform numbers `u`.
    pub fn sample(&self, u: [f32; 2]) -> [f32; 2] {
        std::array::from_fn(|k| {
            let r = self.radius[k];
            match &self.axes[k] {
                Axis::Uniform => (2.0 * u[k] - 1.0) * r,
                Axis::Tent => triangle::sample_tent(u[k], r),
                Axis::Table(cdf) => (2.0 * invert(cdf, u[k]) - 1.0) * r,
            }
        })
    }
}

/// The cumulative table of `f` over [−r, r] in ⌊32 r⌋ cells (at least one), each
/// valued at its centre.
// DEVIATION(pbrt): robustness. At most 4096 cells: pbrt-v4 allocates 32 r of them,
// and a radius of 10⁹ exhausts memory.
fn table(f: impl Fn(f32) -> f32, r: f32) -> Vec<f32> {
    let n = ((32.0 * r) as usize).clamp(1, 4096);
    let mut cdf = Vec::with_capacity(n + 1);
    let mut sum = 0.0f64;
    cdf.push(0.0);
    for i in 0..n {
        sum += f(-r + 2.0 * r * (i as f32 + 0.5) / n as f32) as f64;
        cdf.push(sum as f32);
    }
    if sum > 0.0 {
        cdf.iter_mut().for_each(|c| *c /= sum as f32);
    } else {
        // A filter that is zero everywhere: draw uniformly.
        cdf.iter_mut().enumerate().for_each(|(i, c)| *c = i as f32 / n as f32);
    }
    cdf
}

/// Where in [0, 1] the cumulative table reaches `u`, linear within the cell.
fn invert(cdf: &[f32], u: f32) -> f32 {
    let n = cdf.len() - 1;
    let i = cdf.partition_point(|&c| c <= u).clamp(1, n) - 1;
    let width = cdf[i + 1] - cdf[i];
    let t = if width > 0.0 { ((u - cdf[i]) / width).clamp(0.0, 1.0) } else { 0.5 };
    (i as f32 + t) / n as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parser::params::ParamList;

    fn filter(name: &str) -> PixelFilter {
        PixelFilter::new(name, &ParamList::default()).unwrap().expect("a filter")
    }

    /// The histogram of a million offsets along x, in `bins` bins over [−r, r].
    fn histogram(f: &PixelFilter, bins: usize) -> Vec<f64> {
        let mut h = vec![0.0; bins];
        let n = 1_000_000;
        for i in 0..n {
            let u = [(i as f32 + 0.5) / n as f32, 0.5];
            let x = f.sample(u)[0];
            let b = ((x / f.radius[0] + 1.0) * 0.5 * bins as f32) as usize;
            h[b.min(bins - 1)] += 1.0 / n as f64;
        }
        h
    }

    #[test]
    fn offsets_follow_the_filters_magnitude() {
        for (name, f1) in [
            ("gaussian", Box::new(gaussian::profile(&ParamList::default()).unwrap()) as Box<dyn Fn(f32, f32) -> f32>),
            ("mitchell", Box::new(mitchell::profile(&ParamList::default()).unwrap())),
            ("sinc", Box::new(sinc::profile(&ParamList::default()).unwrap())),
            ("triangle", Box::new(|x: f32, r: f32| (r - x.abs()).max(0.0))),
        ] {
            let f = filter(name);
            let r = f.radius[0];
            let bins = 16;
            let h = histogram(&f, bins);
            // The expected share of each bin: ∫|f| over it, by a fine sum.
            let fine = 4096;
            let w: Vec<f64> =
                (0..fine).map(|i| f1(-r + 2.0 * r * (i as f32 + 0.5) / fine as f32, r).abs() as f64).collect();
            let total: f64 = w.iter().sum();
            for (b, got) in h.iter().enumerate() {
                let want: f64 = w[b * fine / bins..(b + 1) * fine / bins].iter().sum::<f64>() / total;
                assert!((got - want).abs() < 0.002 + 0.01 * want, "{name} bin {b}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn the_density_is_what_offsets_are_drawn_with() {
        // It integrates to 1 over the filter's square, and its x marginal gives each
        // bin of a histogram of the offsets its share.
        let wide_box = PixelFilter { name: "box".into(), radius: [1.0, 2.0], axes: [Axis::Uniform, Axis::Uniform] };
        for f in ["gaussian", "mitchell", "sinc", "triangle"].map(filter).into_iter().chain([wide_box]) {
            let [rx, ry] = f.radius;
            let n = 256;
            let at = |k: usize, r: f32, n: usize| -r + 2.0 * r * (k as f32 + 0.5) / n as f32;
            // ∫ density(x, y) dy by the midpoint rule.
            let marginal = |x: f32| {
                (0..n).map(|j| f.density([x, at(j, ry, n)]) as f64).sum::<f64>() * (2.0 * ry) as f64 / n as f64
            };
            let total = (0..n).map(|i| marginal(at(i, rx, n))).sum::<f64>() * (2.0 * rx) as f64 / n as f64;
            assert!((total - 1.0).abs() < 2e-3, "{}: {total}", f.name);
            let bins = 16;
            for (b, got) in histogram(&f, bins).iter().enumerate() {
                let sub = 32;
                let lo = -rx + 2.0 * rx * b as f32 / bins as f32;
                let width = 2.0 * rx / bins as f32;
                let want = (0..sub).map(|k| marginal(lo + width * (k as f32 + 0.5) / sub as f32)).sum::<f64>()
                    * (width / sub as f32) as f64;
                assert!((got - want).abs() < 0.002 + 0.01 * want, "{} bin {b}: {got} vs {want}", f.name);
            }
        }
    }

    #[test]
    fn a_half_pixel_box_is_no_filter_and_radii_are_read() {
        assert!(PixelFilter::new("box", &ParamList::default()).unwrap().is_none());
        assert_eq!(filter("gaussian").radius, [1.5, 1.5]);
        assert_eq!(filter("sinc").radius, [4.0, 4.0]);
        assert_eq!(filter("mitchell").radius, [2.0, 2.0]);
        let wide = PixelFilter { name: "box".into(), radius: [1.0, 2.0], axes: [Axis::Uniform, Axis::Uniform] };
        assert_eq!(wide.sample([0.0, 1.0]), [-1.0, 2.0]);
        assert_eq!(wide.sample([0.75, 0.5]), [0.5, 0.0]);
    }
}
