//! Animated transforms (motion blur), as pbrt's `AnimatedTransform`.
//!
//! ```text
//! TransformTimes 0 1
//! ActiveTransform StartTime  Translate 0 0 0
//! ActiveTransform EndTime    Translate 0.5 0 0
//! ActiveTransform All
//! Shape "sphere"                       # moves from x = 0 to 0.5 while the shutter is open
//! ```
//! Each of the two matrices is split into translation T, rotation R and the rest S
//! (M = T·R·S, R found by polar decomposition); a time between the two transform times
//! takes T and S linearly and R along the shorter great arc of the quaternions (slerp);
//! before the start time the start matrix holds, after the end time the end matrix.
//!
//! pbrt-v4 interpolates in its rendering space, the world moved to put the camera at
//! the origin: a turning instance then also travels, about the camera rather than its
//! own origin. [`AnimatedTransform::framed`] reproduces that.

use super::Bounds3;
use glam::{DMat3, DMat4, DQuat, DVec3};

/// Two transforms and the times they hold at, with their decompositions.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimatedTransform {
    pub start: DMat4,
    pub end: DMat4,
    pub times: [f64; 2],
    t: [DVec3; 2],
    r: [DQuat; 2],
    s: [DMat3; 2],
    /// The interpolation's frame: M(t) = outer · interpolated(outer⁻¹·Mᵢ·inner⁻¹) · inner.
    outer: DMat4,
    inner: DMat4,
}

/// pbrt's decomposition of an affine map: translation, rotation (the polar factor of
/// the linear part, by at most 100 steps of averaging with its inverse transpose) and
/// what is left (scale and shear, S = R⁻¹·M).
fn decompose(m: &DMat4) -> (DVec3, DQuat, DMat3) {
    let t = m.w_axis.truncate();
    let linear = DMat3::from_mat4(*m);
    // DEVIATION(pbrt): robustness. A singular map (a shape scaled to nothing) has no
    // polar factor; pbrt's inverse fails and interpolates garbage. Here it is all "rest":
    // no rotation, the map itself interpolated linearly.
    if linear.determinant().abs() <= 1e-300 || !linear.is_finite() {
        return (t, DQuat::IDENTITY, linear);
    }
    let mut r = linear;
    for _ in 0..100 {
        let next = (r + r.transpose().inverse()) * 0.5;
        let diff = next - r;
        let norm = (0..3).map(|i| diff.row(i).abs().element_sum()).fold(0.0, f64::max);
        r = next;
        if norm <= 1e-4 {
            break;
        }
    }
    // A reflection stays in S: the rotation is R·(−1) then, with S negated.
    let flip = if r.determinant() < 0.0 { -1.0 } else { 1.0 };
    let rot = r * flip;
    let s = rot.inverse() * linear;
    (t, DQuat::from_mat3(&rot).normalize(), s)
}

impl AnimatedTransform {
    /// `start` at `times[0]` and before, `end` at `times[1]` and after.
    pub fn new(start: DMat4, end: DMat4, times: [f64; 2]) -> AnimatedTransform {
        AnimatedTransform::framed(start, end, times, DMat4::IDENTITY, DMat4::IDENTITY)
    }

    /// As [`AnimatedTransform::new`], interpolating outer⁻¹·M·inner⁻¹ instead of M.
    pub fn framed(start: DMat4, end: DMat4, times: [f64; 2], outer: DMat4, inner: DMat4) -> AnimatedTransform {
        let frame = |m: &DMat4| outer.inverse() * *m * inner.inverse();
        let (t0, r0, s0) = decompose(&frame(&start));
        let (t1, mut r1, s1) = decompose(&frame(&end));
        if r0.dot(r1) < 0.0 {
            r1 = -r1;
        }
        AnimatedTransform { start, end, times, t: [t0, t1], r: [r0, r1], s: [s0, s1], outer, inner }
    }

    /// Whether the transform changes with time (pbrt: the two matrices differ).
    pub fn is_animated(&self) -> bool {
        self.start != self.end
    }

    /// The transform at `time`.
    pub fn at(&self, time: f64) -> DMat4 {
        let [t0, t1] = self.times;
        if !self.is_animated() || time <= t0 || t1 <= t0 {
            return self.start;
        }
        if time >= t1 {
            return self.end;
        }
        let u = (time - t0) / (t1 - t0);
        let t = self.t[0].lerp(self.t[1], u);
        let r = DMat3::from_quat(self.r[0].slerp(self.r[1], u));
        let s = self.s[0] * (1.0 - u) + self.s[1] * u;
        self.outer * DMat4::from_translation(t) * DMat4::from_mat3(r * s) * self.inner
    }

    /// Bounds of `b` under the transform at every time between the two: the boxes at
    /// 65 times, each widened by the way its corners travel to the next (a corner moves
    /// at most π/2 times its chord along the arc between two steps of under 180°).
    pub fn motion_bounds(&self, b: Bounds3) -> Bounds3 {
        if b.is_empty() || !self.is_animated() {
            return super::bounds::transform_bounds_widened(&self.start, [b.min.as_dvec3(), b.max.as_dvec3()]);
        }
        const STEPS: usize = 64;
        let corners: Vec<DVec3> = (0..8)
            .map(|k| {
                let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
                DVec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let [t0, t1] = self.times;
        let at = |i: usize| {
            let m = self.at(t0 + (t1 - t0) * i as f64 / STEPS as f64);
            corners.iter().map(|c| m.transform_point3(*c)).collect::<Vec<_>>()
        };
        let (mut lo, mut hi, mut step) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0.0f64);
        let mut prev = at(0);
        for i in 0..=STEPS {
            let now = if i == 0 { prev.clone() } else { at(i) };
            for (p, q) in now.iter().zip(&prev) {
                (lo, hi, step) = (lo.min(*p), hi.max(*p), step.max(p.distance(*q)));
            }
            prev = now;
        }
        let pad = DVec3::splat(step * std::f64::consts::FRAC_PI_2 * 0.5);
        super::bounds::transform_bounds_widened(&DMat4::IDENTITY, [lo - pad, hi + pad])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn close(a: DMat4, b: DMat4) -> bool {
        a.to_cols_array().iter().zip(b.to_cols_array()).all(|(x, y)| (x - y).abs() < 1e-9)
    }

    #[test]
    fn ends_hold_their_matrices_and_the_middle_turns_halfway() {
        let start = DMat4::from_translation(DVec3::new(1.0, 2.0, 3.0)) * DMat4::from_scale(DVec3::new(2.0, 1.0, 1.0));
        let end = DMat4::from_translation(DVec3::new(3.0, 2.0, 3.0))
            * DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2)
            * DMat4::from_scale(DVec3::new(4.0, 1.0, 1.0));
        let a = AnimatedTransform::new(start, end, [0.0, 1.0]);
        assert!(close(a.at(0.0), start) && close(a.at(-1.0), start));
        assert!(close(a.at(1.0), end) && close(a.at(2.0), end));
        let half = DMat4::from_translation(DVec3::new(2.0, 2.0, 3.0))
            * DMat4::from_rotation_z(std::f64::consts::FRAC_PI_4)
            * DMat4::from_scale(DVec3::new(3.0, 1.0, 1.0));
        assert!(close(a.at(0.5), half), "{:?}", a.at(0.5));
        // Round trips through the decomposition, a mirror included.
        let mirror = DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)) * DMat4::from_rotation_y(0.7);
        let m = AnimatedTransform::new(mirror, mirror * DMat4::from_translation(DVec3::X), [0.0, 1.0]);
        assert!(close(m.at(1e-12), mirror));
    }

    #[test]
    fn a_shape_scaled_to_nothing_shrinks_linearly() {
        let a = AnimatedTransform::new(DMat4::IDENTITY, DMat4::from_scale(DVec3::ZERO), [0.0, 1.0]);
        assert!(close(a.at(0.25), DMat4::from_scale(DVec3::splat(0.75))), "{:?}", a.at(0.25));
        assert!(a.at(0.5).is_finite());
    }

    #[test]
    fn motion_bounds_hold_the_box_at_every_time() {
        let start = DMat4::from_rotation_y(0.0);
        let end = DMat4::from_translation(DVec3::new(0.0, 1.0, 0.0)) * DMat4::from_rotation_y(3.0);
        let a = AnimatedTransform::new(start, end, [0.2, 0.8]);
        let b = Bounds3::new(Vec3::new(1.0, -0.1, -0.1), Vec3::new(2.0, 0.1, 0.1));
        let mb = a.motion_bounds(b);
        for i in 0..=1000 {
            let m = a.at(i as f64 / 1000.0);
            for k in 0..8 {
                let c = DVec3::new([1.0, 2.0][k & 1], [-0.1, 0.1][(k >> 1) & 1], [-0.1, 0.1][(k >> 2) & 1]);
                let p = m.transform_point3(c).as_vec3();
                assert!(p.cmpge(mb.min).all() && p.cmple(mb.max).all(), "{p} outside {mb:?}");
            }
        }
    }
}
