//! Which light a point's direct light is sampled from, in proportion to how much each
//! may light it (pbrt-v4's SPPM does this with its `BVHLightSampler`):
//!
//! ```text
//! LightSource "spot" ...            # aimed elsewhere: importance 0, rarely tried
//! AttributeBegin AreaLightSource "diffuse" ... Shape ... AttributeEnd
//! LightSource "infinite" ...        # no bounds: chosen with 1/(lights at infinity + 1)
//! ```
//! Lights at infinity share a fixed probability, as pbrt-v4's sampler gives them; the
//! others go by [`LightBounds::importance`]. With few lights pbrt-v4's tree is that
//! ratio exactly; with more it approximates it. Any choice renders the same mean.

use super::Light;
use super::bounds::LightBounds;
use crate::sampling::{Pick, rest_of};
use crate::shapes::ShapeSet;
use glam::Vec3;

/// Lights chosen per point. Beyond this many, the cost of weighing each for every
/// sample outgrows what it saves, and the caller chooses otherwise.
pub const MAX_LIGHTS: usize = 64;

/// Each light's share of the importance never falls below this fraction of the mean
/// share, so that a bound that is too tight can only add noise, never a bias.
// DEVIATION(pbrt): noise only. pbrt-v4 never tries a light of importance 0.
const FLOOR: f32 = 1e-3;

#[derive(Clone, Debug)]
pub struct LightChoice {
    bounded: Vec<(usize, LightBounds)>,
    infinite: Vec<usize>,
}

impl LightChoice {
    /// The choice among `lights`, or `None` past [`MAX_LIGHTS`].
    pub fn new(lights: &[Light], shapes: &ShapeSet) -> Option<LightChoice> {
        if lights.len() > MAX_LIGHTS {
            return None;
        }
        let (mut bounded, mut infinite) = (Vec::new(), Vec::new());
        for (i, l) in lights.iter().enumerate() {
            match l.bounds(shapes) {
                Some(b) => bounded.push((i, b)),
                None => infinite.push(i),
            }
        }
        Some(LightChoice { bounded, infinite })
    }

    /// A light for the point `p` with normal `n` (zero in a medium), from a uniform
    /// `u`.
    pub fn choose(&self, u: f32, p: Vec3, n: Vec3) -> Option<Pick> {
        let n_inf = self.infinite.len();
        if self.bounded.is_empty() && n_inf == 0 {
            return None;
        }
        let p_inf = n_inf as f32 / (n_inf + usize::from(!self.bounded.is_empty())) as f32;
        if u < p_inf || self.bounded.is_empty() {
            let p = Pick::uniform(u as f64 / p_inf as f64, n_inf);
            return Some(Pick { index: self.infinite[p.index], pmf: p_inf / n_inf as f32, rest: p.rest });
        }
        let u = ((u - p_inf) / (1.0 - p_inf)).clamp(0.0, 1.0);
        let mut weights = [0.0f32; MAX_LIGHTS];
        let weights = &mut weights[..self.bounded.len()];
        for (w, (_, b)) in weights.iter_mut().zip(&self.bounded) {
            *w = b.importance(p, n);
        }
        let sum: f32 = weights.iter().sum();
        let floor = if sum > 0.0 && sum.is_finite() { FLOOR * sum / weights.len() as f32 } else { 1.0 };
        weights.iter_mut().for_each(|w| *w = if w.is_finite() { w.max(floor) } else { floor });
        let total: f32 = weights.iter().sum();
        let target = u * total;
        // The first light whose running sum passes the target (the last one, if
        // rounding leaves the target at the total), and the sum below it.
        let (mut below, mut pick) = (0.0, weights.len() - 1);
        for (k, w) in weights.iter().enumerate() {
            if target < below + w || k == pick {
                pick = k;
                break;
            }
            below += w;
        }
        let pmf = (1.0 - p_inf) * weights[pick] / total;
        let rest = rest_of((target - below) as f64, weights[pick] as f64);
        Some(Pick { index: self.bounded[pick].0, pmf, rest })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::point::PointLight;

    fn point(p: Vec3, i: f32) -> Light {
        Light::Point(PointLight { p, i: Vec3::splat(i) })
    }

    #[test]
    fn the_nearer_light_is_chosen_more_and_the_weights_stay_unbiased() {
        let shapes = ShapeSet::default();
        let lights = [point(Vec3::new(0.0, 0.0, 1.0), 1.0), point(Vec3::new(0.0, 0.0, 10.0), 1.0)];
        let choice = LightChoice::new(&lights, &shapes).expect("few lights");
        let (mut counts, mut sum_w) = ([0usize; 2], [0.0f64; 2]);
        let n = 100_000;
        for k in 0..n {
            let pick = choice.choose((k as f32 + 0.5) / n as f32, Vec3::ZERO, Vec3::Z).unwrap();
            counts[pick.index] += 1;
            sum_w[pick.index] += 1.0 / pick.pmf as f64;
        }
        assert!(counts[0] > 90 * counts[1], "{counts:?}");
        // Each light's weight 1/p, summed over the times it is chosen, estimates n.
        for w in sum_w {
            assert!((w / n as f64 - 1.0).abs() < 0.02, "{sum_w:?}");
        }
    }

    /// Whichever branch picks it (lights at infinity or bounded ones), a light's
    /// rests over stratified numbers are stratified too.
    #[test]
    fn each_light_keeps_a_stratified_rest() {
        let shapes = ShapeSet::default();
        let sky = Light::Infinite(crate::lights::infinite::InfiniteLight {
            l: Vec3::ONE,
            sky: crate::lights::infinite::Sky::Uniform,
        });
        let lights = [point(Vec3::new(0.0, 0.0, 1.0), 1.0), sky, point(Vec3::new(0.0, 0.0, 3.0), 1.0)];
        let choice = LightChoice::new(&lights, &shapes).expect("few lights");
        let n = 6_000;
        let mut rests = vec![Vec::new(); 3];
        for k in 0..n {
            let pick = choice.choose((k as f32 + 0.5) / n as f32, Vec3::ZERO, Vec3::Z).unwrap();
            rests[pick.index].push(pick.rest);
        }
        for r in &mut rests {
            assert!(r.len() > 100, "{}", r.len());
            r.sort_by(f32::total_cmp);
            let m = r.len() as f32;
            for (j, x) in r.iter().enumerate() {
                assert!(*x >= (j as f32 - 0.01) / m && *x < (j as f32 + 1.01) / m, "{j} of {m}: {x}");
            }
        }
    }

    #[test]
    fn a_light_of_no_importance_is_still_tried_now_and_then() {
        let shapes = ShapeSet::default();
        let spot_away = crate::lights::spot::SpotLight {
            p: Vec3::new(0.0, 0.0, 2.0),
            frame: [Vec3::X, Vec3::Y, Vec3::Z],
            i: Vec3::ONE,
            cos_total: 0.99,
            cos_start: 0.99,
            smooth: true,
        };
        let lights = [point(Vec3::new(0.0, 0.0, 2.0), 1.0), Light::Spot(spot_away)];
        let choice = LightChoice::new(&lights, &shapes).unwrap();
        let picks: Vec<_> = (0..10_000).filter_map(|k| choice.choose(k as f32 / 1e4, Vec3::ZERO, Vec3::Z)).collect();
        let spot = picks.iter().filter(|p| p.index == 1).count();
        assert!(spot > 0 && spot < 10, "{spot}");
    }
}
