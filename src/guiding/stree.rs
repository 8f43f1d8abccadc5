//! The spatial part of a guiding distribution: a binary tree over a cube around the
//! scene, each node halving its cell along x, y, z in turn, each leaf holding two
//! directional trees ([`DTree`]): the one filled last round, which samples, and the
//! one being filled (Müller et al. 2017). A leaf that received more than a threshold of
//! records in a round splits in two, both halves starting from its trees.

use super::dtree::DTree;
use glam::Vec3;

#[derive(Clone, Debug, PartialEq)]
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
#[derive(Clone, Debug, PartialEq)]
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
        match &self.nodes[self.leaf_index(p)] {
            SNode::Leaf { sampling, .. } => sampling,
            SNode::Inner { .. } => unreachable!("leaf_index ends at a leaf"),
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
    /// copy (`rho`, see [`DTree::refined`]) its next building tree; a leaf given more
    /// than `split_after` records splits first (along the axis after its parent's), both
    /// halves starting from its trees.
    pub fn end_round(&mut self, split_after: u64, rho: f64) {
        let mut stack = vec![(0usize, 0u8)];
        while let Some((i, axis)) = stack.pop() {
            match &self.nodes[i] {
                SNode::Inner { axis, children } => {
                    let next = (*axis + 1) % 3;
                    stack.extend(children.iter().map(|&c| (c as usize, next)));
                }
                SNode::Leaf { building, .. } => {
                    let filled = building.clone();
                    let leaf = || SNode::Leaf { sampling: filled.clone(), building: filled.refined(rho) };
                    if filled.samples() > split_after {
                        let c = self.nodes.len() as u32;
                        self.nodes.push(leaf());
                        self.nodes.push(leaf());
                        self.nodes[i] = SNode::Inner { axis, children: [c, c + 1] };
                    } else {
                        self.nodes[i] = leaf();
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
}
