//! The directional part of a guiding distribution: a quadtree over the square that
//! the equal-area cylindrical map spreads the sphere of directions over (Müller et al.
//! 2017, "Practical Path Guiding"). Each node keeps the energy recorded in its four
//! quadrants; sampling descends by those energies and is uniform within a leaf, so
//! the density is piecewise constant on the sphere.
//!
//! A tree is trained in rounds: [`DTree::record`] adds estimates of incident light to
//! the leaves of a tree, then [`DTree::refined`] makes the next round's structure
//! (quadrants holding more than a share `rho` of the energy split, the rest merge) and
//! the filled tree samples while the new one records.

use glam::Vec3;
use std::f32::consts::PI;

/// Deepest level a quadrant may reach (cells of 4⁻²⁰ of the sphere).
pub const MAX_DEPTH: u32 = 20;

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
struct Node {
    /// Energy recorded in each quadrant (x < ½ or not, then y < ½ or not: index
    /// `2·(y ≥ ½) + (x ≥ ½)`).
    sum: [f64; 4],
    /// Each quadrant's node, or 0 for a leaf.
    child: [u32; 4],
}

/// A directional quadtree.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DTree {
    nodes: Vec<Node>,
    /// Records made (their count, whatever their energy).
    samples: u64,
}

impl Default for DTree {
    fn default() -> Self {
        DTree { nodes: vec![Node::default()], samples: 0 }
    }
}

/// The square's point of a unit direction: ((cos θ + 1)/2, φ/2π), φ in [0, 2π).
pub fn to_square(d: Vec3) -> [f32; 2] {
    let phi = d.y.atan2(d.x);
    let v = if phi < 0.0 { phi / (2.0 * PI) + 1.0 } else { phi / (2.0 * PI) };
    [((d.z.clamp(-1.0, 1.0) + 1.0) * 0.5).min(1.0 - f32::EPSILON / 2.0), v.min(1.0 - f32::EPSILON / 2.0)]
}

/// The direction of a point of the square (the inverse of [`to_square`]).
pub fn from_square(p: [f32; 2]) -> Vec3 {
    let z = 2.0 * p[0] - 1.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * p[1]).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// The quadrant of `p` in a node and `p` in the quadrant's own coordinates.
fn quadrant(p: [f32; 2]) -> (usize, [f32; 2]) {
    let (qx, qy) = (p[0] >= 0.5, p[1] >= 0.5);
    let q = 2 * qy as usize + qx as usize;
    let local = |x: f32, hi: bool| (if hi { 2.0 * x - 1.0 } else { 2.0 * x }).clamp(0.0, 1.0 - f32::EPSILON / 2.0);
    (q, [local(p[0], qx), local(p[1], qy)])
}

/// 0 or 1 by the weights `a` and `b` from `u`, which is then stretched over the part of
/// [0, 1) that picked it.
fn pick(u: &mut f64, a: f64, b: f64) -> usize {
    let total = a + b;
    let split = if total > 0.0 { a / total } else { 0.5 };
    let (k, lo, width) = if *u < split { (0, 0.0, split) } else { (1, split, 1.0 - split) };
    *u = ((*u - lo) / width.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0 - f64::EPSILON);
    k
}

impl DTree {
    /// Energy recorded in all.
    pub fn total(&self) -> f64 {
        self.nodes[0].sum.iter().sum()
    }

    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Nodes in the tree (1 for a single root).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Adds `energy` (an estimate of incident light, already divided by the density
    /// its direction was drawn with) in direction `d`. Non-finite or negative energies
    /// count as a sample of nothing.
    pub fn record(&mut self, d: Vec3, energy: f64) {
        self.samples += 1;
        if !(energy.is_finite() && energy > 0.0) {
            return;
        }
        let (mut node, mut p) = (0usize, to_square(d));
        loop {
            let (q, local) = quadrant(p);
            self.nodes[node].sum[q] += energy;
            match self.nodes[node].child[q] {
                0 => return,
                c => (node, p) = (c as usize, local),
            }
        }
    }

    /// The density on the sphere (per steradian) of [`Self::sample`]; uniform
    /// (1/4π) while nothing is recorded.
    pub fn pdf(&self, d: Vec3) -> f32 {
        let total = self.total();
        if total <= 0.0 {
            return 1.0 / (4.0 * PI);
        }
        let (mut node, mut p, mut density) = (0usize, to_square(d), 1.0f64);
        loop {
            let n = &self.nodes[node];
            let (q, local) = quadrant(p);
            let sum: f64 = n.sum.iter().sum();
            if sum <= 0.0 {
                return 0.0;
            }
            density *= 4.0 * n.sum[q] / sum;
            match n.child[q] {
                0 => return (density / (4.0 * std::f64::consts::PI)) as f32,
                c => (node, p) = (c as usize, local),
            }
        }
    }

    /// A direction drawn by the recorded energy (uniform while nothing is recorded).
    /// At each level the first number picks the quadrant's x half by the halves'
    /// energies and the second its y half given x, each then stretched over the half
    /// it picked, so both carry one bit per level and the leaf's point is uniform.
    pub fn sample(&self, u: [f32; 2]) -> Vec3 {
        if self.total() <= 0.0 {
            return from_square(u);
        }
        let (mut node, mut u) = (0usize, [u[0] as f64, u[1] as f64]);
        // The leaf's corner and size in the square, refined level by level.
        let (mut origin, mut size) = ([0.0f64; 2], 1.0f64);
        loop {
            let e = &self.nodes[node].sum;
            // The x half, by the halves' energies (quadrants 0, 2 low; 1, 3 high).
            let (low, high) = (e[0] + e[2], e[1] + e[3]);
            let qx = pick(&mut u[0], low, high);
            let qy = pick(&mut u[1], e[qx], e[2 + qx]);
            let q = 2 * qy + qx;
            size *= 0.5;
            origin[0] += size * qx as f64;
            origin[1] += size * qy as f64;
            match self.nodes[node].child[q] {
                0 => break,
                c => node = c as usize,
            }
        }
        from_square([(origin[0] + size * u[0]) as f32, (origin[1] + size * u[1]) as f32])
    }

    /// The next round's tree: each quadrant whose share of this tree's energy is above
    /// `rho` is split (down to [`MAX_DEPTH`]), the others are leaves; all sums zero. A
    /// quadrant that is a leaf here is taken to spread its energy evenly below it, so
    /// it splits again while its quarters are above `rho` too (Müller et al.'s rule:
    /// a bright quadrant reaches its depth in one round, not one level per round).
    pub fn refined(&self, rho: f64) -> DTree {
        let total = self.total();
        let mut out = DTree { nodes: vec![Node::default()], samples: 0 };
        if total <= 0.0 {
            return out;
        }
        // (the node of `self` whose quadrants are copied, or none below a leaf, where
        // each quadrant holds `even`; the copy in `out`; its depth).
        let mut stack = vec![(Some(0usize), 0.0f64, 0usize, 1u32)];
        while let Some((old, even, new, depth)) = stack.pop() {
            for q in 0..4 {
                let (sum, below) = match old {
                    Some(o) => (self.nodes[o].sum[q], self.nodes[o].child[q] as usize),
                    None => (even, 0),
                };
                if depth >= MAX_DEPTH || sum / total <= rho {
                    continue;
                }
                let c = out.nodes.len();
                out.nodes.push(Node::default());
                out.nodes[new].child[q] = c as u32;
                stack.push(match below {
                    0 => (None, sum / 4.0, c, depth + 1),
                    b => (Some(b), 0.0, c, depth + 1),
                });
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::testing::{cell_mean, histogram, lcg};

    /// A tree trained on light from around +x+z (a cone of half-angle ~25°) plus a
    /// little from everywhere, over three rounds.
    fn trained() -> DTree {
        let mut s = 3;
        let sun = Vec3::new(1.0, 0.0, 1.0).normalize();
        let mut tree = DTree::default();
        for _ in 0..3 {
            let mut next = tree.refined(0.01);
            for _ in 0..20_000 {
                let d = from_square([lcg(&mut s), lcg(&mut s)]);
                let energy = if d.dot(sun) > 0.9 { 50.0 } else { 1.0 };
                next.record(d, energy * 4.0 * PI as f64);
            }
            tree = next;
        }
        tree
    }

    #[test]
    fn the_map_is_its_own_inverse_and_keeps_area() {
        let mut s = 1;
        for _ in 0..1000 {
            let p = [lcg(&mut s), lcg(&mut s)];
            let q = to_square(from_square(p));
            assert!((p[0] - q[0]).abs() < 1e-5 && ((p[1] - q[1]).abs() < 1e-5 || (p[1] - q[1]).abs() > 1.0 - 1e-5));
        }
        // Equal areas: a band of the square's x holds that share of the sphere.
        let n = 200_000;
        let near_pole =
            (0..n).filter(|_| to_square(crate::sampling::uniform_sphere([lcg(&mut s), lcg(&mut s)]))[0] > 0.9).count();
        assert!((near_pole as f64 / n as f64 - 0.1).abs() < 0.003, "{near_pole}");
    }

    #[test]
    fn the_density_integrates_to_one_and_favours_the_light() {
        let t = trained();
        assert!(t.node_count() > 20, "{} nodes", t.node_count());
        let (n, mut sum) = (2048usize, 0.0f64);
        for k in 0..n * n {
            let p = [((k % n) as f32 + 0.5) / n as f32, ((k / n) as f32 + 0.5) / n as f32];
            sum += t.pdf(from_square(p)) as f64;
        }
        let integral = sum * 4.0 * std::f64::consts::PI / (n * n) as f64;
        assert!((integral - 1.0).abs() < 1e-3, "∫pdf = {integral}");
        let sun = Vec3::new(1.0, 0.0, 1.0).normalize();
        assert!(t.pdf(sun) > 20.0 * t.pdf(-sun), "{} vs {}", t.pdf(sun), t.pdf(-sun));
        assert_eq!(DTree::default().pdf(sun), 1.0 / (4.0 * PI));
    }

    #[test]
    fn samples_follow_the_density() {
        // χ² over a 16 × 16 grid of the square: each cell's count within 5σ of the
        // density's integral over it.
        let t = trained();
        let (n, bins) = (400_000usize, 16usize);
        let mut s = 9;
        let hist = histogram(n, bins, || to_square(t.sample([lcg(&mut s), lcg(&mut s)])));
        let mut chi2 = 0.0;
        for (k, &count) in hist.iter().enumerate() {
            let mean = cell_mean(bins, k, 16, |p| t.pdf(from_square(p)) as f64);
            let expected = mean * 4.0 * std::f64::consts::PI / (bins * bins) as f64 * n as f64;
            assert!((count as f64 - expected).abs() < 5.0 * expected.sqrt() + 2.0, "cell {k}: {count} vs {expected}");
            chi2 += (count as f64 - expected).powi(2) / expected.max(1.0);
        }
        // 255 degrees of freedom: the mean is 255, 5σ above it about 368.
        assert!(chi2 < 368.0, "χ² {chi2}");
    }

    #[test]
    fn refining_splits_where_the_energy_is_and_bad_records_count_as_nothing() {
        let mut t = DTree::default();
        t.record(Vec3::Z, f64::NAN);
        t.record(Vec3::Z, -1.0);
        assert_eq!((t.samples(), t.total()), (2, 0.0));
        assert_eq!(t.refined(0.01).node_count(), 1);
        for _ in 0..10 {
            t.record(Vec3::Z, 1.0);
        }
        // All the energy in one direction: one chain of nodes down to the deepest level.
        let mut r = t.refined(0.01);
        for _ in 0..MAX_DEPTH {
            r.record(Vec3::Z, 1.0);
            r = r.refined(0.01);
        }
        assert_eq!(r.node_count() as u32, MAX_DEPTH);
        r.record(Vec3::Z, 1.0);
        assert!(r.pdf(Vec3::Z) > 1e9);
        assert!(r.sample([0.3, 0.7]).distance(Vec3::Z) < 1e-2);
    }
}
