//! pbrt-v3's `DisneyBSSRDF`: the radial profile Burley (2015) fitted to diffusion, two
//! exponentials in the distance r, for a `disney` material with a `scatterdistance`
//! that is not `thin` ([`super::disney::bssrdf`]):
//!
//! ```text
//! Material "disney" "rgb color" [.8 .5 .4] "rgb scatterdistance" [.3 .12 .06]
//! ```
//! Sr(r) = R (e^(−r/d) + e^(−r/(3d))) / (8π d r), with R the diffuse colour and
//! d = 0.2 × `scatterdistance` (pbrt-v3's factor). Over the plane it integrates to R;
//! a radius is drawn from one exponential a quarter of the time and from the other the
//! rest, and the density is the two mixed in that proportion, as pbrt-v3 draws it.

use crate::spectrum::Rgb;
use glam::Vec3;
use std::f32::consts::PI;

/// The smallest radius the profile is evaluated at (its 1/r is infinite at 0).
const R_MIN: f32 = 1e-6;

/// One exit point's profile: the colour R and the distance d per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Burley {
    pub r: Rgb,
    pub d: Rgb,
}

impl Burley {
    /// The profile of a `scatterdistance` and a colour (pbrt-v3 scales the distance by
    /// 0.2, "from personal communication from Brent Burley and Matt Chiang").
    pub fn new(r: Rgb, scatter_distance: Rgb) -> Burley {
        Burley { r, d: 0.2 * scatter_distance.max(Vec3::ZERO) }
    }

    /// pbrt-v3's `Sr`.
    // DEVIATION(pbrt): robustness. A channel whose distance is 0 gives 0/0 in pbrt-v3
    // (NaN in the pixel); here it gives nothing.
    pub fn sr(&self, r: f32) -> Rgb {
        let r = r.max(R_MIN);
        let mut out = Vec3::ZERO;
        for ch in 0..3 {
            let d = self.d[ch];
            if d > 0.0 {
                out[ch] = self.r[ch] * ((-r / d).exp() + (-r / (3.0 * d)).exp()) / (8.0 * PI * d * r);
            }
        }
        out
    }

    /// pbrt-v3's `Sample_Sr`: `None` where the channel has no distance.
    pub fn sample_sr(&self, ch: usize, u: f32) -> Option<f32> {
        let d = self.d[ch];
        if d <= 0.0 {
            return None;
        }
        let (scale, u) = if u < 0.25 { (d, u * 4.0) } else { (3.0 * d, (u - 0.25) / 0.75) };
        let u = u.min(1.0 - f32::EPSILON / 2.0);
        Some(scale * (1.0 / (1.0 - u)).ln())
    }

    /// pbrt-v3's `Pdf_Sr`, per unit area of the plane the radius is drawn in.
    pub fn pdf_sr(&self, ch: usize, r: f32) -> f32 {
        let d = self.d[ch];
        if d <= 0.0 {
            return 0.0;
        }
        let r = r.max(R_MIN);
        0.25 * (-r / d).exp() / (2.0 * PI * d * r) + 0.75 * (-r / (3.0 * d)).exp() / (6.0 * PI * d * r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ f(r) 2πr dr over (0, ∞), by the midpoint rule in u = 1 − e^(−r/s).
    fn radial_integral(f: impl Fn(f32) -> f64, s: f32) -> f64 {
        let n = 200_000;
        (0..n)
            .map(|i| {
                let u = (i as f64 + 0.5) / n as f64;
                let r = -(s as f64) * (1.0 - u).ln();
                // dr = s / (1 − u) du
                f(r as f32) * 2.0 * std::f64::consts::PI * r * s as f64 / (1.0 - u) / n as f64
            })
            .sum()
    }

    #[test]
    fn the_profile_integrates_to_its_colour_and_its_density_to_one() {
        let b = Burley::new(Vec3::new(0.8, 0.5, 0.2), Vec3::new(0.5, 0.1, 0.02));
        for ch in 0..3 {
            let s = 3.0 * b.d[ch];
            let sr = radial_integral(|r| b.sr(r)[ch] as f64, s);
            assert!((sr - b.r[ch] as f64).abs() < 2e-3 * b.r[ch] as f64, "{ch}: {sr}");
            let pdf = radial_integral(|r| b.pdf_sr(ch, r) as f64, s);
            assert!((pdf - 1.0).abs() < 2e-3, "{ch}: {pdf}");
        }
    }

    #[test]
    fn sampled_radii_follow_the_density() {
        let b = Burley::new(Vec3::ONE, Vec3::new(1.0, 0.3, 0.05));
        let ch = 1;
        let n = 200_000;
        let edges: Vec<f32> = (0..=12).map(|i| i as f32 * 0.02).collect();
        let mut counts = vec![0u32; edges.len() - 1];
        for i in 0..n {
            let r = b.sample_sr(ch, (i as f32 + 0.5) / n as f32).unwrap();
            if let Some(k) = edges.windows(2).position(|w| r >= w[0] && r < w[1]) {
                counts[k] += 1;
            }
        }
        for (k, w) in edges.windows(2).enumerate() {
            // ∫ pdf 2πr dr over the bin, by the midpoint rule on 400 steps.
            let m = 400;
            let p: f64 = (0..m)
                .map(|j| {
                    let r = w[0] + (w[1] - w[0]) * (j as f32 + 0.5) / m as f32;
                    (b.pdf_sr(ch, r) * 2.0 * PI * r * (w[1] - w[0]) / m as f32) as f64
                })
                .sum();
            let got = counts[k] as f64 / n as f64;
            assert!((got - p).abs() < 0.01 * p + 1e-4, "bin {k}: {got} against {p}");
        }
    }

    #[test]
    fn a_channel_without_distance_gives_nothing_and_no_nan() {
        let b = Burley::new(Vec3::ONE, Vec3::new(0.1, 0.0, 0.1));
        assert_eq!(b.sr(0.05)[1], 0.0);
        assert!(b.sr(0.0).is_finite());
        assert_eq!(b.sample_sr(1, 0.5), None);
        assert_eq!(b.pdf_sr(1, 0.05), 0.0);
    }
}
