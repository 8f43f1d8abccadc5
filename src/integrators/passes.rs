//! Independent passes (Knaus and Zwicker, "Progressive photon mapping: a probabilistic
//! approach", 2011): pass i gathers with one radius for every pixel that depends only
//! on i, so each pass is an independent estimate and the image is their average. Any
//! set of passes can then be rendered anywhere and summed.
//!
//! ```text
//! pbrt-sppm render scene.pbrt --passes independent --alpha 0.6667
//! pbrt-sppm render scene.pbrt --spp 64 --pass-range 16..32 --partial p16.part.exr
//! ```
//! The radius: r_1 is the Integrator's `radius`, and
//! r_{i+1}² = r_i² · (i + α)/(i + 1), so r_i² = r_1² · ∏_{k<i} (k + α)/(k + 1).

use std::fmt;
use std::ops::Range;

/// How the passes of a render relate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum PassMode {
    /// pbrt's SPPM: each pixel's radius and flux carry over from pass to pass.
    #[default]
    Classic,
    /// Knaus–Zwicker: every pass stands alone, its radius set by its index.
    Independent { alpha: f64 },
}

/// Knaus and Zwicker's recommended α (the same 2/3 as pbrt's γ).
pub const DEFAULT_ALPHA: f64 = 2.0 / 3.0;

impl PassMode {
    pub fn is_independent(self) -> bool {
        matches!(self, PassMode::Independent { .. })
    }

    /// The mode `--passes` (`independent`: `Some(true)`), `--alpha` and a split render
    /// (`--pass-range` or `--partial`) ask for. Classic SPPM unless independent passes
    /// are asked for or implied by the split; with `vcm`/`bdpt` (`bidirectional`), whose
    /// passes are independent already, α is its radius schedule.
    pub fn asked(
        independent: Option<bool>,
        alpha: Option<f64>,
        split: bool,
        bidirectional: bool,
    ) -> Result<PassMode, String> {
        let independent = match independent {
            Some(false) if split => {
                return Err("classic SPPM cannot be split: --pass-range and --partial need independent passes".into());
            }
            Some(i) => i,
            None => split,
        };
        match (independent, alpha) {
            (false, Some(alpha)) if bidirectional => Ok(PassMode::Independent { alpha }),
            (false, Some(_)) => Err("--alpha sets the radius of independent passes: add --passes independent".into()),
            (false, None) => Ok(PassMode::Classic),
            (true, alpha) => Ok(PassMode::Independent { alpha: alpha.unwrap_or(DEFAULT_ALPHA) }),
        }
    }
}

impl fmt::Display for PassMode {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            PassMode::Classic => write!(f, "classic"),
            PassMode::Independent { alpha } => write!(f, "independent (alpha {alpha})"),
        }
    }
}

/// The gather radius of pass `pass` (counted from 0) whose first radius is `r1`. The
/// same operations in the same order on every machine, so every shard agrees.
pub fn radius(r1: f64, alpha: f64, pass: u32) -> f64 {
    let mut r2 = r1 * r1;
    for k in 1..=pass {
        r2 *= (k as f64 + alpha) / (k as f64 + 1.0);
    }
    r2.sqrt()
}

/// Parses `A..B` (passes A to B−1, counted from 0).
pub fn parse_range(s: &str) -> Result<Range<u32>, String> {
    let bad = || format!("\"{s}\" is not a pass range A..B (passes A to B-1, from 0), such as 0..16");
    let (a, b) = s.trim().split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
    if a >= b {
        return Err(format!("the pass range {a}..{b} is empty: it needs A < B"));
    }
    Ok(a..b)
}

/// A set of passes as sorted, disjoint, non-adjacent half-open ranges.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PassSet(Vec<Range<u32>>);

impl PassSet {
    pub fn from_range(r: Range<u32>) -> PassSet {
        let mut s = PassSet::default();
        s.insert(r);
        s
    }

    pub fn ranges(&self) -> &[Range<u32>] {
        &self.0
    }

    /// The number of passes.
    pub fn count(&self) -> u64 {
        self.0.iter().map(|r| (r.end - r.start) as u64).sum()
    }

    /// Passes in both sets.
    pub fn intersection(&self, other: &PassSet) -> PassSet {
        let mut out = PassSet::default();
        for a in &self.0 {
            for b in &other.0 {
                let r = a.start.max(b.start)..a.end.min(b.end);
                if r.start < r.end {
                    out.insert(r);
                }
            }
        }
        out
    }

    /// Adds passes, merging touching ranges.
    pub fn insert(&mut self, r: Range<u32>) {
        if r.start >= r.end {
            return;
        }
        self.0.push(r);
        self.0.sort_by_key(|r| r.start);
        let mut merged: Vec<Range<u32>> = Vec::with_capacity(self.0.len());
        for r in self.0.drain(..) {
            match merged.last_mut() {
                Some(last) if r.start <= last.end => last.end = last.end.max(r.end),
                _ => merged.push(r),
            }
        }
        self.0 = merged;
    }

    pub fn union(&self, other: &PassSet) -> PassSet {
        let mut out = self.clone();
        other.0.iter().for_each(|r| out.insert(r.clone()));
        out
    }

    /// The passes of `0..n` not in the set.
    pub fn missing_from(&self, n: u32) -> PassSet {
        let mut out = PassSet::default();
        let mut next = 0;
        for r in &self.0 {
            out.insert(next..r.start.min(n));
            next = next.max(r.end);
        }
        out.insert(next..n);
        out
    }
}

impl fmt::Display for PassSet {
    /// `0..4,8..12`; `-` when empty.
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        if self.0.is_empty() {
            return write!(f, "-");
        }
        let parts: Vec<String> = self.0.iter().map(|r| format!("{}..{}", r.start, r.end)).collect();
        write!(f, "{}", parts.join(","))
    }
}

impl std::str::FromStr for PassSet {
    type Err = String;
    fn from_str(s: &str) -> Result<PassSet, String> {
        let mut out = PassSet::default();
        if s.trim() == "-" {
            return Ok(out);
        }
        for part in s.split(',') {
            let r = parse_range(part)?;
            if out.intersection(&PassSet::from_range(r.clone())).count() > 0 {
                return Err(format!("\"{s}\" names some passes twice"));
            }
            out.insert(r);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_radius_follows_the_product_formula() {
        let (r1, a) = (0.5f64, 2.0 / 3.0);
        assert_eq!(radius(r1, a, 0), r1);
        let r2 = r1 * r1 * (1.0 + a) / 2.0 * (2.0 + a) / 3.0;
        assert!((radius(r1, a, 2) - r2.sqrt()).abs() < 1e-15);
        // r_i² i^(1−α) tends to a constant.
        let c = |i: u32| radius(r1, a, i).powi(2) * (i as f64 + 1.0).powf(1.0 - a);
        assert!((c(100_000) / c(10_000) - 1.0).abs() < 1e-4, "{} {}", c(10_000), c(100_000));
    }

    #[test]
    fn pass_sets_merge_intersect_and_find_gaps() {
        let s: PassSet = "8..12,0..4".parse().unwrap();
        assert_eq!(s.to_string(), "0..4,8..12");
        assert_eq!(s.count(), 8);
        assert_eq!(s.missing_from(16).to_string(), "4..8,12..16");
        assert_eq!(s.missing_from(10).to_string(), "4..8");
        let t: PassSet = "4..8".parse().unwrap();
        assert_eq!(s.union(&t).to_string(), "0..12");
        assert_eq!(s.intersection(&t).count(), 0);
        assert_eq!(s.intersection(&"3..9".parse().unwrap()).to_string(), "3..4,8..9");
        assert!("0..4,2..6".parse::<PassSet>().is_err());
        assert!("4..4".parse::<PassSet>().is_err());
        assert!("a..4".parse::<PassSet>().is_err());
        assert_eq!("-".parse::<PassSet>().unwrap().count(), 0);
    }
}
