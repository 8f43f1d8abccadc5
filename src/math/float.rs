//! Floating-point error tools: `gamma(n)`, ulp steps and `EFloat`, a value with
//! conservative error bounds (pbrt-v3 `core/efloat.h`).
//!
//! Every operation evaluates the value and the interval endpoints, then rounds the
//! endpoints outward by one ulp, so the exact result of the same expression on the exact
//! inputs always lies inside `[lower, upper]`. [`EFloat`] works in `f32` as pbrt-v3
//! does; [`EFloat64`] is the same in `f64` (quadrics solve their quadratic with it).

/// Half of f32's machine epsilon (pbrt's `MachineEpsilon`).
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// pbrt's γ(n) = nε / (1 − nε): bounds the relative error of n roundings.
pub const fn gamma(n: i32) -> f32 {
    (n as f32 * MACHINE_EPSILON) / (1.0 - n as f32 * MACHINE_EPSILON)
}

/// √x, with x below 0 (round-off under a difference of squares) taken as 0.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// γ(n) for f64 arithmetic.
pub const fn gamma64(n: i32) -> f64 {
    let e = f64::EPSILON * 0.5;
    (n as f64 * e) / (1.0 - n as f64 * e)
}

/// The next float up and down, with the results of `next_up` and `next_down` for every
/// input (NaN, infinities and zeros too), written as selects on the bits rather than
/// the standard library's chain of branches: interval arithmetic steps both ends of
/// every sum and product outward, about forty steps in a sphere test, and every spawned
/// ray's origin is stepped off its surface.
pub trait UlpStep: Sized + std::ops::Neg<Output = Self> {
    fn step_up(self) -> Self;

    /// The mirror image of a step up (negation only flips the sign bit).
    #[inline(always)]
    fn step_down(self) -> Self {
        -(-self).step_up()
    }
}

macro_rules! ulp_step {
    ($f:ty, $bits:ty) => {
        impl UlpStep for $f {
            #[inline(always)]
            fn step_up(self) -> $f {
                const SIGN: $bits = 1 << (<$bits>::BITS - 1);
                let (b, inf) = (self.to_bits(), <$f>::INFINITY.to_bits());
                let abs = b & !SIGN;
                let stepped = if b == abs { b.wrapping_add(1) } else { b.wrapping_sub(1) };
                let stepped = if abs == 0 { 1 } else { stepped };
                <$f>::from_bits(if abs > inf || b == inf { b } else { stepped })
            }
        }
    };
}

ulp_step!(f32, u32);
ulp_step!(f64, u64);

macro_rules! efloat {
    ($name:ident, $f:ty) => {
        /// A value with conservative bounds `[low, high]` on its error.
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        pub struct $name {
            v: $f,
            low: $f,
            high: $f,
        }

        impl $name {
            /// An exact value (`err` = 0) or one known to within ±`err`.
            pub fn new(v: $f, err: $f) -> $name {
                if err == 0.0 {
                    $name { v, low: v, high: v }
                } else {
                    $name { v, low: (v - err).step_down(), high: (v + err).step_up() }
                }
            }
            pub fn value(self) -> $f {
                self.v
            }
            pub fn lower(self) -> $f {
                self.low
            }
            pub fn upper(self) -> $f {
                self.high
            }
            /// Half the interval width.
            pub fn absolute_error(self) -> $f {
                (self.high - self.low) * 0.5
            }
            pub fn sqrt(self) -> $name {
                $name { v: self.v.sqrt(), low: self.low.max(0.0).sqrt().step_down(), high: self.high.sqrt().step_up() }
            }
            pub fn abs(self) -> $name {
                if self.low >= 0.0 {
                    self
                } else if self.high <= 0.0 {
                    -self
                } else {
                    $name { v: self.v.abs(), low: 0.0, high: (-self.low).max(self.high) }
                }
            }

            /// Roots t0 ≤ t1 of a t² + b t + c, with the discriminant in wider precision
            /// and the stable form q = −½(b ± √disc) (pbrt-v3 `Quadratic`).
            pub fn quadratic(a: $name, b: $name, c: $name) -> Option<($name, $name)> {
                let (av, bv, cv) = (a.v as f64, b.v as f64, c.v as f64);
                let disc = bv * bv - 4.0 * av * cv;
                if disc < 0.0 {
                    return None;
                }
                let root = disc.sqrt();
                let float_root = $name::new(root as $f, (<$f>::EPSILON * 0.5) * root as $f);
                let q = if bv < 0.0 { (b - float_root) * -0.5 } else { (b + float_root) * -0.5 };
                let (t0, t1) = (q / a, c / q);
                Some(if t0.low > t1.low { (t1, t0) } else { (t0, t1) })
            }
        }

        impl From<$f> for $name {
            fn from(v: $f) -> $name {
                $name::new(v, 0.0)
            }
        }

        impl std::ops::Add for $name {
            type Output = $name;
            fn add(self, o: $name) -> $name {
                $name { v: self.v + o.v, low: (self.low + o.low).step_down(), high: (self.high + o.high).step_up() }
            }
        }

        impl std::ops::Sub for $name {
            type Output = $name;
            fn sub(self, o: $name) -> $name {
                $name { v: self.v - o.v, low: (self.low - o.high).step_down(), high: (self.high - o.low).step_up() }
            }
        }

        impl std::ops::Mul for $name {
            type Output = $name;
            fn mul(self, o: $name) -> $name {
                let p = [self.low * o.low, self.high * o.low, self.low * o.high, self.high * o.high];
                let low = p[0].min(p[1]).min(p[2].min(p[3]));
                let high = p[0].max(p[1]).max(p[2].max(p[3]));
                $name { v: self.v * o.v, low: low.step_down(), high: high.step_up() }
            }
        }

        impl std::ops::Mul<$f> for $name {
            type Output = $name;
            fn mul(self, o: $f) -> $name {
                self * $name::from(o)
            }
        }

        impl std::ops::Div for $name {
            type Output = $name;
            fn div(self, o: $name) -> $name {
                if o.low < 0.0 && o.high > 0.0 {
                    // The divisor's interval holds zero: the quotient may be anything.
                    return $name { v: self.v / o.v, low: <$f>::NEG_INFINITY, high: <$f>::INFINITY };
                }
                let q = [self.low / o.low, self.high / o.low, self.low / o.high, self.high / o.high];
                let low = q[0].min(q[1]).min(q[2].min(q[3]));
                let high = q[0].max(q[1]).max(q[2].max(q[3]));
                $name { v: self.v / o.v, low: low.step_down(), high: high.step_up() }
            }
        }

        impl std::ops::Neg for $name {
            type Output = $name;
            fn neg(self) -> $name {
                $name { v: -self.v, low: -self.high, high: -self.low }
            }
        }
    };
}

efloat!(EFloat, f32);
efloat!(EFloat64, f64);

#[cfg(test)]
mod tests {
    use super::*;

    /// A tiny deterministic generator for the property test.
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn value(&mut self) -> f64 {
            let mag = 10f64.powf(self.next() * 8.0 - 4.0);
            if self.next() < 0.5 { -mag } else { mag }
        }
    }

    #[test]
    fn bounds_always_contain_the_f64_evaluation() {
        let mut rng = Lcg(7);
        for _ in 0..100_000 {
            let (x, y) = (rng.value() as f32, rng.value() as f32);
            let (ex, ey) = (EFloat::from(x), EFloat::from(y));
            let (px, py) = (x as f64, y as f64);
            let op = (rng.next() * 6.0) as usize;
            let (e, precise) = match op {
                0 => (ex + ey, px + py),
                1 => (ex - ey, px - py),
                2 => (ex * ey, px * py),
                3 => (ex / ey, px / py),
                4 => (ex.abs().sqrt(), px.abs().sqrt()),
                _ => ((ex * ey + ex) * ey - ey, (px * py + px) * py - py),
            };
            assert!(e.lower() as f64 <= precise && precise <= e.upper() as f64, "op {op}: {x} {y}: {e:?} vs {precise}");
        }
    }

    #[test]
    fn quadratic_roots_bracket_the_exact_roots() {
        // (t − 2)(t − 3) = t² − 5t + 6.
        let (t0, t1) = EFloat::quadratic(1.0.into(), (-5.0).into(), 6.0.into()).unwrap_or_default();
        assert!(t0.lower() <= 2.0 && 2.0 <= t0.upper() && t1.lower() <= 3.0 && 3.0 <= t1.upper());
        assert!(EFloat::quadratic(1.0.into(), 0.0.into(), 1.0.into()).is_none());
    }

    #[test]
    fn gamma_and_ulp_steps() {
        assert!((gamma(3) - 3.0 * MACHINE_EPSILON).abs() < 1e-12);
        assert_eq!((-0.0f32).next_up(), f32::from_bits(1));
        assert!(gamma64(5) < 1e-15);
    }

    /// The select-based steps give `next_up`'s and `next_down`'s bits for zeros,
    /// subnormals, the largest finite values, infinities, NaNs (each with either sign)
    /// and random bit patterns.
    #[test]
    fn ulp_steps_are_the_standard_librarys() {
        let mut rng = crate::sampling::Rng::new(5);
        let f64_special = [0u64, 1, 0x000f_ffff_ffff_ffff, 0x0010_0000_0000_0000, 0x7fef_ffff_ffff_ffff];
        let f64_special =
            f64_special.into_iter().chain([0x7ff0_0000_0000_0000, 0x7ff8_0000_0000_0000, 1 | 0x7ff0 << 48]);
        let f32_special = [0u32, 1, 0x007f_ffff, 0x0080_0000, 0x7f7f_ffff, 0x7f80_0000, 0x7fc0_0000, 0x7f80_0001];
        let randoms: Vec<u64> = (0..100_000).map(|_| (rng.next_u32() as u64) << 32 | rng.next_u32() as u64).collect();
        let doubles = f64_special.flat_map(|b| [b, b | 1 << 63]).chain(randoms.iter().copied());
        for x in doubles.map(f64::from_bits) {
            assert_eq!(x.step_up().to_bits(), x.next_up().to_bits(), "up from {:#x}", x.to_bits());
            assert_eq!(x.step_down().to_bits(), x.next_down().to_bits(), "down from {:#x}", x.to_bits());
        }
        let singles = f32_special.into_iter().flat_map(|b| [b, b | 1 << 31]);
        for y in singles.chain(randoms.iter().flat_map(|&b| [b as u32, (b >> 32) as u32])).map(f32::from_bits) {
            assert_eq!(y.step_up().to_bits(), y.next_up().to_bits(), "up from {:#x}", y.to_bits());
            assert_eq!(y.step_down().to_bits(), y.next_down().to_bits(), "down from {:#x}", y.to_bits());
        }
    }
}
