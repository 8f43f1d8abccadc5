//! Axis-aligned boxes with pbrt's conservative ray–box test.

use super::float::gamma;
use glam::{DMat4, DVec3, Vec3};

/// Bounds of a box's 8 corners under `m` (f64, for placing shapes and instances).
pub fn transform_bounds(m: &DMat4, b: [DVec3; 2]) -> [DVec3; 2] {
    (0..8)
        .map(|i| {
            let c = DVec3::new(b[i & 1].x, b[(i >> 1) & 1].y, b[(i >> 2) & 1].z);
            m.transform_point3(c)
        })
        .fold([DVec3::INFINITY, DVec3::NEG_INFINITY], |[lo, hi], p| [lo.min(p), hi.max(p)])
}

/// [`transform_bounds`] in f32, widened by a relative 1e-6 (and a little more) so the
/// rounding to f32 never leaves a corner outside.
pub fn transform_bounds_widened(m: &DMat4, b: [DVec3; 2]) -> Bounds3 {
    let [lo, hi] = transform_bounds(m, b);
    let grow = |v: DVec3, s: f64| (v + s * (v.abs() * 1e-6 + DVec3::splat(1e-30))).as_vec3();
    Bounds3 { min: grow(lo, -1.0), max: grow(hi, 1.0) }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Bounds3 {
    /// The empty box (min = +∞, max = −∞), the identity of `union`.
    fn default() -> Bounds3 {
        Bounds3 { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY }
    }
}

impl Bounds3 {
    pub fn new(a: Vec3, b: Vec3) -> Bounds3 {
        Bounds3 { min: a.min(b), max: a.max(b) }
    }
    pub fn union(self, o: Bounds3) -> Bounds3 {
        Bounds3 { min: self.min.min(o.min), max: self.max.max(o.max) }
    }
    pub fn union_point(self, p: Vec3) -> Bounds3 {
        Bounds3 { min: self.min.min(p), max: self.max.max(p) }
    }
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }
    pub fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
    pub fn diagonal(&self) -> Vec3 {
        self.max - self.min
    }
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.diagonal();
        2.0 * (d.x * d.y + d.x * d.z + d.y * d.z)
    }
    pub fn max_extent(&self) -> usize {
        let d = self.diagonal();
        if d.x > d.y && d.x > d.z {
            0
        } else if d.y > d.z {
            1
        } else {
            2
        }
    }
    /// Position of `p` relative to the box: 0 at min, 1 at max, per axis.
    pub fn offset(&self, p: Vec3) -> Vec3 {
        let d = self.diagonal();
        let mut o = p - self.min;
        for i in 0..3 {
            if d[i] > 0.0 {
                o[i] /= d[i];
            }
        }
        o
    }

    /// Whether the ray from `o` along `d` (t ≥ 0) may meet the box: false only where
    /// it misses the box grown by 10⁻⁵ of its size and place, in f64, so that no
    /// shape's own rounded test finds a hit inside a box this excludes. An empty or
    /// unbounded box, or a ray that is not finite, may always meet it.
    pub fn may_meet_ray(&self, o: Vec3, d: Vec3) -> bool {
        let bounded = self.min.is_finite() && self.max.is_finite() && !self.is_empty();
        if !bounded || !o.is_finite() || !d.is_finite() {
            return true;
        }
        let size = self.min.abs().max(self.max.abs()).max_element() + self.diagonal().max_element();
        let pad = 1e-5 * size as f64 + f64::from(f32::MIN_POSITIVE);
        let (lo, hi) = (self.min.as_dvec3() - pad, self.max.as_dvec3() + pad);
        let (o, d) = (o.as_dvec3(), d.as_dvec3());
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < lo[a] || o[a] > hi[a] {
                    return false;
                }
                continue;
            }
            let (near, far) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            t0 = t0.max(near.min(far));
            t1 = t1.min(near.max(far));
        }
        t0 <= t1
    }

    /// pbrt's slab test with precomputed 1/d and direction signs; the far distances
    /// are enlarged by 1 + 2γ(3) so that rounding never misses a box the ray truly
    /// crosses. Returns the entry distance (negative when the origin is inside).
    #[inline]
    pub fn intersect_p(&self, o: Vec3, inv_d: Vec3, neg: [usize; 3], t_max: f32) -> Option<f32> {
        let b = [self.min, self.max];
        let scale = 1.0 + 2.0 * gamma(3);
        let (mut t_min, mut t_far) = (f32::NEG_INFINITY, f32::INFINITY);
        for a in 0..3 {
            let near = (b[neg[a]][a] - o[a]) * inv_d[a];
            let far = (b[1 - neg[a]][a] - o[a]) * inv_d[a] * scale;
            if t_min > far || near > t_far {
                return None;
            }
            if near > t_min {
                t_min = near;
            }
            if far < t_far {
                t_far = far;
            }
        }
        (t_min < t_max && t_far > 0.0).then_some(t_min)
    }
}

#[cfg(test)]
mod tests {
    use super::Bounds3;
    use glam::Vec3;

    /// Rays through the box (from outside, from inside, grazing a face, parallel to an
    /// axis) may meet it; rays pointing away from it or passing beside it do not;
    /// an empty box or a ray that is not finite is never ruled out.
    #[test]
    fn may_meet_ray_rules_out_only_clear_misses() {
        let b = Bounds3::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 3.0, 4.0));
        let toward = |o: Vec3, p: Vec3| b.may_meet_ray(o, (p - o).normalize());
        assert!(toward(Vec3::ZERO, b.centroid()));
        assert!(b.may_meet_ray(b.centroid(), Vec3::new(0.3, -0.8, 0.1).normalize()));
        assert!(toward(Vec3::new(0.0, 2.0, 3.5), Vec3::new(3.0, 2.0, 3.5)), "along a face");
        assert!(b.may_meet_ray(Vec3::new(1.5, 2.5, -10.0), Vec3::Z), "parallel to two axes");
        assert!(!b.may_meet_ray(Vec3::new(1.5, 2.5, -10.0), -Vec3::Z), "pointing away");
        assert!(!b.may_meet_ray(Vec3::new(1.5, 5.0, -10.0), Vec3::Z), "beside it");
        assert!(!toward(Vec3::ZERO, Vec3::new(10.0, 2.5, 3.5)), "passing below");
        assert!(Bounds3::default().may_meet_ray(Vec3::ZERO, Vec3::X));
        assert!(b.may_meet_ray(Vec3::splat(f32::NAN), Vec3::X));
        // A ray just outside a face, closer than the margin, is kept.
        assert!(b.may_meet_ray(Vec3::new(0.0, 3.0 + 1e-6, 3.5), Vec3::X));
    }
}
