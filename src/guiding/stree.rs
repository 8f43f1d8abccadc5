//! The spatial part of a guiding distribution: a binary tree over a cube around the
//! scene, each node halving its cell along x, y, z in turn, each leaf holding two
//! directional trees ([`DTree`]): the one filled last round, which samples, and the
//! one being filled (Müller et al. 2017). A leaf that received more than a threshold of
//! records in a round splits in two, both halves starting from its trees.

use super::dtree::DTree;
use glam::Vec3;

/// The deepest a leaf may be (cells of 2⁻³² of the cube's volume).
pub const MAX_DEPTH: u32 = 32;

#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
enum SNode {
    /// Halved along `axis` at the cell's middle: children below and above.
    Inner {
        axis: u8,
        children: [u32; 2],
    },
    Leaf {
        sampling: DTree,
        building: DTree,
    },
}

/// A spatial-directional tree.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct STree {
    min: Vec3,
    size: f32,
    nodes: Vec<SNode>,
}

impl STree {
    /// One leaf over the cube around `[lo, hi]` (a little larger, so that points on
    /// its faces fall inside).
    pub fn new(lo: Vec3, hi: Vec3) -> STree {
        let size = (hi - lo).max_element().max(1e-6) * 1.001;
        let centre = 0.5 * (lo + hi);
        let leaf = SNode::Leaf { sampling: DTree::default(), building: DTree::default() };
        STree { min: centre - Vec3::splat(0.5 * size), size, nodes: vec![leaf] }
    }

    /// The leaf holding `p` (points outside the cube go to the nearest cell).
    fn leaf_index(&self, p: Vec3) -> usize {
        let mut q = ((p - self.min) / self.size).clamp(Vec3::ZERO, Vec3::splat(1.0 - f32::EPSILON));
        let mut node = 0;
        while let SNode::Inner { axis, children } = &self.nodes[node] {
            let a = *axis as usize;
            let upper = q[a] >= 0.5;
            q[a] = if upper { 2.0 * q[a] - 1.0 } else { 2.0 * q[a] };
            node = children[upper as usize] as usize;
        }
        node
    }

    /// The directional tree that samples at `p`.
    pub fn sampling(&self, p: Vec3) -> &DTree {
        self.sampling_of(self.leaf(p))
    }

    /// The leaf holding `p`, named for [`Self::sampling_of`] (a vertex that keeps it
    /// need not descend the tree again).
    pub fn leaf(&self, p: Vec3) -> u32 {
        self.leaf_index(p) as u32
    }

    /// The directional tree that samples in leaf `leaf` (from [`Self::leaf`]).
    pub fn sampling_of(&self, leaf: u32) -> &DTree {
        match &self.nodes[leaf as usize] {
            SNode::Leaf { sampling, .. } => sampling,
            SNode::Inner { .. } => panic!("node {leaf} is no leaf: ask STree::leaf"),
        }
    }

    /// Records `energy` arriving at `p` from direction `d` (see [`DTree::record`]).
    pub fn record(&mut self, p: Vec3, d: Vec3, energy: f64) {
        let i = self.leaf_index(p);
        if let SNode::Leaf { building, .. } = &mut self.nodes[i] {
            building.record(d, energy);
        }
    }

    /// Leaves in the tree.
    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| matches!(n, SNode::Leaf { .. })).count()
    }

    /// Ends a round: each leaf's filled tree becomes its sampling tree and a refined
    /// copy (`rho`, see [`DTree::refined`]) its next building tree. A leaf given more
    /// than `split_after` records splits first (along the axis after its parent's),
    /// both halves starting from its trees and taken to hold half its records each, so
    /// a busy leaf splits again until its parts are under the threshold (Müller et
    /// al.'s subdivision), down to [`MAX_DEPTH`].
    pub fn end_round(&mut self, split_after: u64, rho: f64) {
        // (node, its axis, its depth, the records a new half is taken to hold).
        let mut stack = vec![(0usize, 0u8, 0u32, None::<u64>)];
        while let Some((i, axis, depth, count)) = stack.pop() {
            let next = (axis + 1) % 3;
            match &self.nodes[i] {
                SNode::Inner { axis, children } => {
                    let next = (*axis + 1) % 3;
                    stack.extend(children.iter().map(|&c| (c as usize, next, depth + 1, None)));
                }
                SNode::Leaf { building, .. } => {
                    let n = count.unwrap_or_else(|| building.samples());
                    if n > split_after.max(1) && depth < MAX_DEPTH {
                        let c = self.nodes.len() as u32;
                        let half = self.nodes[i].clone();
                        self.nodes.push(half.clone());
                        self.nodes.push(half);
                        self.nodes[i] = SNode::Inner { axis, children: [c, c + 1] };
                        stack.extend([c, c + 1].map(|c| (c as usize, next, depth + 1, Some(n / 2))));
                    } else {
                        let filled = building.clone();
                        let building = filled.refined(rho);
                        self.nodes[i] = SNode::Leaf { sampling: filled, building };
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn busy_leaves_split_and_points_find_their_own_leaf() {
        let mut t = STree::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0));
        // Light from +z in the half x < 1, from −z in the other half.
        let record = |t: &mut STree, n: usize| {
            for k in 0..n {
                let x = 2.0 * (k as f32 + 0.5) / n as f32;
                let d = if x < 1.0 { Vec3::Z } else { -Vec3::Z };
                t.record(Vec3::new(x, 0.5, 0.5), d, 1.0);
            }
        };
        record(&mut t, 1000);
        t.end_round(500, 0.01);
        assert_eq!(t.leaf_count(), 2);
        // Both halves start from the whole cell's tree: light from both sides, none
        // from the side (−y falls in a quadrant of its own).
        let half = t.sampling(Vec3::new(0.2, 0.5, 0.5));
        assert_eq!(half, t.sampling(Vec3::new(1.8, 0.5, 0.5)));
        assert!(half.pdf(-Vec3::Z) > 0.1 && half.pdf(-Vec3::Z) == half.pdf(Vec3::Z) && half.pdf(-Vec3::Y) == 0.0);
        record(&mut t, 1000);
        t.end_round(10_000, 0.01);
        assert_eq!(t.leaf_count(), 2);
        let (left, right) = (t.sampling(Vec3::new(0.2, 0.5, 0.5)), t.sampling(Vec3::new(1.8, 0.5, 0.5)));
        assert!(left.pdf(Vec3::Z) > 100.0 * left.pdf(-Vec3::Z).max(1e-3), "{}", left.pdf(Vec3::Z));
        assert!(right.pdf(-Vec3::Z) > 100.0 * right.pdf(Vec3::Z).max(1e-3));
        // Outside the cube: the nearest cell.
        assert_eq!(t.sampling(Vec3::new(-5.0, 0.5, 0.5)), left);
        assert_eq!(t.sampling(Vec3::new(9.0, f32::NAN, 0.5)), right);
    }

    #[test]
    fn a_busy_leaf_splits_until_its_parts_are_under_the_threshold() {
        let mut t = STree::new(Vec3::ZERO, Vec3::ONE);
        for _ in 0..4000 {
            t.record(Vec3::splat(0.3), Vec3::Z, 1.0);
        }
        // 4000 → 2000 → 1000 → 500 records a part: three levels, eight leaves.
        t.end_round(500, 0.01);
        assert_eq!(t.leaf_count(), 8);
        // Each part starts from the whole tree's light.
        let far = t.sampling(Vec3::splat(0.9));
        assert!(far.pdf(Vec3::Z) > 0.3 && far.pdf(-Vec3::Z) == 0.0);
    }
}
