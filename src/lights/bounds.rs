//! pbrt-v4's light bounds: where a light is, which way and how strongly it shines, and
//! from those how much it may light a point (`LightBounds::Importance`). pbrt-v4's SPPM
//! picks the light for a visible point's direct light by it (through its BVH light
//! sampler), so that a spot light aimed elsewhere, or a far light, is rarely tried.

use crate::math::bounds::Bounds3;
use crate::math::float::safe_sqrt;
use glam::Vec3;

/// A light's bounds (pbrt-v4's `LightBounds`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub bounds: Bounds3,
    /// The axis of the cone of directions it emits about.
    pub w: Vec3,
    /// Its strength (only ratios between lights matter).
    pub phi: f32,
    /// The cone of the emitters' normals about `w` (−1: every direction).
    pub cos_theta_o: f32,
    /// How far past that cone light leaves (0 for a surface: a quarter turn).
    pub cos_theta_e: f32,
    pub two_sided: bool,
}

impl LightBounds {
    /// A light at a point shining every way (a point or goniometric light).
    pub fn isotropic(p: Vec3, phi: f32) -> LightBounds {
        let bounds = Bounds3::new(p, p);
        LightBounds { bounds, w: Vec3::Z, phi, cos_theta_o: -1.0, cos_theta_e: 0.0, two_sided: false }
    }

    /// How much the light may add at `p` with surface normal `n` (zero vector: in a
    /// medium): φ over the clamped squared distance, times the cosines of the angles
    /// left once every direction the bounds allow has been taken in the light's and the
    /// surface's favour; zero where no direction within them can light `p`.
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        let pc = self.bounds.centroid();
        let d2 = p.distance_squared(pc).max(0.5 * self.bounds.diagonal().length());
        let wi = (p - pc).normalize_or_zero();
        let mut cos_w = self.w.dot(wi);
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
        let cos_b = subtended_cos(&self.bounds, p);
        let sin_b = safe_sqrt(1.0 - cos_b * cos_b);
        let sin_o = safe_sqrt(1.0 - self.cos_theta_o * self.cos_theta_o);
        let (cos_x, sin_x) =
            (cos_sub(sin_w, cos_w, sin_o, self.cos_theta_o), sin_sub(sin_w, cos_w, sin_o, self.cos_theta_o));
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        if cos_p <= self.cos_theta_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if n != Vec3::ZERO {
            let cos_i = wi.dot(n).abs();
            importance *= cos_sub(safe_sqrt(1.0 - cos_i * cos_i), cos_i, sin_b, cos_b);
        }
        importance.max(0.0)
    }
}

/// cos(max(0, a − b)) from the sines and cosines of a and b.
fn cos_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 1.0 } else { cos_a * cos_b + sin_a * sin_b }
}

/// sin(max(0, a − b)).
fn sin_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 0.0 } else { sin_a * cos_b - cos_a * sin_b }
}

/// The cosine of the half angle of the cone from `p` that holds the bounds' bounding
/// sphere; −1 (every direction) from inside it.
fn subtended_cos(b: &Bounds3, p: Vec3) -> f32 {
    let centre = b.centroid();
    let r2 = centre.distance_squared(b.max);
    let d2 = p.distance_squared(centre);
    if d2 < r2 {
        return -1.0;
    }
    safe_sqrt(1.0 - r2 / d2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_light_falls_off_with_the_square_of_distance_and_the_cosine() {
        let l = LightBounds::isotropic(Vec3::new(0.0, 0.0, 2.0), 10.0);
        let near = l.importance(Vec3::ZERO, Vec3::Z);
        let far = l.importance(Vec3::new(0.0, 0.0, -2.0), Vec3::Z);
        assert!((near / far - 4.0).abs() < 1e-4, "{near} {far}");
        let slanted = l.importance(Vec3::new(2.0, 0.0, 0.0), Vec3::Z);
        let d2 = 8.0;
        assert!((slanted - 10.0 / d2 * std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-4, "{slanted}");
    }

    #[test]
    fn a_spot_light_matters_only_within_its_cone() {
        // Aimed down the z axis with a 10° cone and no falloff past it.
        let c = 10f32.to_radians().cos();
        let spot = LightBounds {
            cos_theta_o: c,
            cos_theta_e: 0.9999,
            w: -Vec3::Z,
            ..LightBounds::isotropic(Vec3::Z * 4.0, 1.0)
        };
        assert!(spot.importance(Vec3::ZERO, Vec3::Z) > 0.0);
        assert_eq!(spot.importance(Vec3::new(3.0, 0.0, 0.0), Vec3::Z), 0.0);
    }

    #[test]
    fn a_one_sided_emitter_does_not_light_what_lies_behind_it() {
        let quad = Bounds3 { min: Vec3::new(-1.0, -1.0, 0.0), max: Vec3::new(1.0, 1.0, 0.0) };
        let l =
            LightBounds { bounds: quad, w: Vec3::Z, phi: 1.0, cos_theta_o: 1.0, cos_theta_e: 0.0, two_sided: false };
        assert!(l.importance(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z) > 0.0);
        assert_eq!(l.importance(Vec3::new(0.0, 0.0, -3.0), Vec3::Z), 0.0);
        let both = LightBounds { two_sided: true, ..l };
        assert!(both.importance(Vec3::new(0.0, 0.0, -3.0), Vec3::Z) > 0.0);
    }
}
