//! [`Bounded64`]: the value an [`EFloat64`] expression takes, with a bound on how far
//! that expression's interval ends can lie from it, at a fraction of the cost.
//!
//! An `EFloat64` operation rounds its value to nearest, takes the extremes of up to four
//! rounded products for each end and steps both ends out by an ulp. The value is the
//! plain f64 evaluation, so the same expression on `Bounded64` gives the same bits;
//! instead of the ends it carries a radius `r` with `v − r ≤ low ≤ v ≤ high ≤ v + r`.
//! Quadric tests decide with that radius where it leaves no doubt (a root well away
//! from 0, from `t_max` and from the other root), and compute the intervals only where
//! it does.
//!
//! Each rule below bounds the exact distance of the ends from the value by the
//! inputs' radii, adds the rounding of the value and of each end (at most a unit
//! roundoff each, counted here as two: [`U`]) and its ulp step (two more), and then
//! widens the sum by a few roundoffs more and by [`ETA`], which covers steps among
//! subnormals. [`Interval`] lets one generic expression run on either type.

use super::EFloat64;
use super::float::UlpStep;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Twice f64's unit roundoff: every rounding is counted at this size.
const U: f64 = f64::EPSILON;
/// Rounding of the radius's own arithmetic.
const GROW: f64 = 1.0 + 8.0 * U;
/// Far above an ulp among subnormals (4.9e-324), far below any length a ray meets.
const ETA: f64 = 1e-300;

/// A value and a radius that holds the ends of the `EFloat64` interval of the same
/// expression. A radius of +∞ (or NaN) says nothing is known.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bounded64 {
    pub v: f64,
    pub r: f64,
}

/// The arithmetic a quadric's coefficients are written in: [`EFloat64`] to decide
/// with exact interval ends, [`Bounded64`] to decide quickly where that is enough.
pub trait Interval:
    Copy
    + From<f64>
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Mul<f64, Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
}

impl Interval for EFloat64 {}
impl Interval for Bounded64 {}

/// The radius for an exact distance `spread` of the ends from the value, with the
/// roundings of a result of magnitude at most `size`.
#[inline(always)]
fn widened(spread: f64, size: f64) -> f64 {
    (spread + 4.0 * U * size) * GROW + ETA
}

impl Bounded64 {
    /// An `EFloat64`'s value, and a radius that holds its ends.
    #[inline]
    pub fn of(e: EFloat64) -> Bounded64 {
        let (v, low, high) = (e.value(), e.lower(), e.upper());
        Bounded64 { v, r: (v - low).max(high - v) * GROW + ETA }
    }

    /// `EFloat64::new(v, err)`'s value, and a radius that holds its ends, without
    /// computing them: each end is v ∓ err rounded and stepped out an ulp, at most
    /// 2U(|v| + err) beyond err (a subnormal step is within [`ETA`]). An exact value
    /// (err = 0) has both ends at v.
    #[inline(always)]
    pub fn around(v: f64, err: f64) -> Bounded64 {
        let r = if err == 0.0 { 0.0 } else { widened(err, v.abs() + err) };
        Bounded64 { v, r }
    }

    /// Whether the radius says anything (finite value and radius).
    #[inline]
    pub fn is_known(self) -> bool {
        self.v.is_finite() && self.r.is_finite()
    }

    /// The least the interval's low end can be (rounded down).
    #[inline]
    pub fn low_least(self) -> f64 {
        (self.v - self.r).step_down()
    }

    /// The most the interval's high end can be (rounded up).
    #[inline]
    pub fn high_most(self) -> f64 {
        (self.v + self.r).step_up()
    }
}

impl From<f64> for Bounded64 {
    /// An exact value (`EFloat64::from` gives the interval [v, v]).
    fn from(v: f64) -> Bounded64 {
        Bounded64 { v, r: 0.0 }
    }
}

impl Add for Bounded64 {
    type Output = Bounded64;
    #[inline(always)]
    fn add(self, o: Bounded64) -> Bounded64 {
        let spread = self.r + o.r;
        Bounded64 { v: self.v + o.v, r: widened(spread, self.v.abs() + o.v.abs() + spread) }
    }
}

impl Sub for Bounded64 {
    type Output = Bounded64;
    #[inline(always)]
    fn sub(self, o: Bounded64) -> Bounded64 {
        let spread = self.r + o.r;
        Bounded64 { v: self.v - o.v, r: widened(spread, self.v.abs() + o.v.abs() + spread) }
    }
}

impl Mul for Bounded64 {
    type Output = Bounded64;
    /// Each corner product x'y' lies within |x|r_y + |y|r_x + r_x r_y of xy.
    #[inline(always)]
    fn mul(self, o: Bounded64) -> Bounded64 {
        let spread = self.v.abs() * o.r + o.v.abs() * self.r + self.r * o.r;
        let v = self.v * o.v;
        Bounded64 { v, r: widened(spread, v.abs() + spread) }
    }
}

impl Mul<f64> for Bounded64 {
    type Output = Bounded64;
    #[inline(always)]
    fn mul(self, o: f64) -> Bounded64 {
        self * Bounded64::from(o)
    }
}

impl Div for Bounded64 {
    type Output = Bounded64;
    /// Each corner x'/y' lies within (|y|r_x + |x|r_y) / (|y|(|y| − r_y)) of x/y while
    /// the divisor's interval stays clear of zero; nothing is known otherwise (the
    /// interval quotient is then unbounded).
    #[inline(always)]
    fn div(self, o: Bounded64) -> Bounded64 {
        let v = self.v / o.v;
        let y = o.v.abs();
        let clear_of_zero = o.r < 0.5 * y;
        if !clear_of_zero {
            return Bounded64 { v, r: f64::INFINITY };
        }
        let spread = (y * self.r + self.v.abs() * o.r) / (y * (y - o.r));
        Bounded64 { v, r: widened(spread, v.abs() + spread) }
    }
}

impl Neg for Bounded64 {
    type Output = Bounded64;
    #[inline(always)]
    fn neg(self) -> Bounded64 {
        Bounded64 { v: -self.v, r: self.r }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// A value of random sign and magnitude (10⁻⁶ to 10⁶), with a random error bound,
    /// often 0.
    fn operand(rng: &mut Rng) -> EFloat64 {
        let mut next = || rng.uniform() as f64;
        let mag = 10f64.powf(next() * 12.0 - 6.0);
        let v = if next() < 0.5 { -mag } else { mag };
        let err = if next() < 0.3 { 0.0 } else { v.abs() * 10f64.powf(-16.0 + 15.0 * next()) };
        EFloat64::new(v, err)
    }

    /// A value and its error bound make a radius that holds the interval's ends, at
    /// every magnitude, subnormals and zero included.
    #[test]
    fn a_radius_around_a_value_holds_its_interval() {
        let mut rng = Rng::new(7);
        let odd = [0.0, -0.0, 5e-324, -5e-324, 2.2e-308, f64::MAX / 4.0];
        for k in 0..200_000 {
            let mut next = || rng.uniform() as f64;
            let mag = 10f64.powf(next() * 600.0 - 300.0);
            let v = match k % 7 {
                0 => odd[(next() * 6.0) as usize % 6],
                _ if next() < 0.5 => -mag,
                _ => mag,
            };
            let err = match k % 5 {
                0 => 0.0,
                1 => odd[(next() * 6.0) as usize % 6].abs(),
                _ => v.abs() * 10f64.powf(-17.0 + 16.0 * next()),
            };
            let (e, b) = (EFloat64::new(v, err), Bounded64::around(v, err));
            assert_eq!(e.value().to_bits(), b.v.to_bits());
            if b.is_known() {
                assert!(b.low_least() <= e.lower() && e.upper() <= b.high_most(), "{e:?} outside {b:?}");
            }
        }
    }

    /// Chains of random operations on both types give the same values bit for bit,
    /// and the radius holds the interval's ends at every step.
    #[test]
    fn the_radius_holds_every_interval_end() {
        let mut rng = Rng::new(11);
        for _ in 0..20_000 {
            let mut e = operand(&mut rng);
            let mut b = Bounded64::of(e);
            for _ in 0..6 {
                let x = operand(&mut rng);
                let (ex, bx) = (x, Bounded64::of(x));
                (e, b) = match (rng.uniform() * 5.0) as usize {
                    0 => (e + ex, b + bx),
                    1 => (e - ex, b - bx),
                    2 => (e * ex, b * bx),
                    3 => (e / ex, b / bx),
                    _ => (-e * 2.0, -b * 2.0),
                };
                assert_eq!(e.value().to_bits(), b.v.to_bits());
                if b.is_known() {
                    assert!(b.low_least() <= e.lower() && e.upper() <= b.high_most(), "{e:?} outside {b:?}");
                }
            }
        }
    }
}
