//! A bounding volume hierarchy: binned SAH build (parallel for large subtrees), flat
//! 32-byte nodes, and closure-based closest-hit and any-hit traversal with pbrt's
//! conservative slab test.
//!
//! Siblings are stored side by side in one 64-byte-aligned pair, so testing both
//! children of a node touches one cache line; pairs are laid out depth first.
//!
//! The BVH knows only boxes: `build` returns the primitive order it wants, and the
//! caller stores its primitives in that order, so leaves index them directly.

use crate::math::{Bounds3, Ray};
use glam::Vec3;

/// One node: its box, and either two children (the pair at index `offset`) or
/// `count` primitives starting at `offset`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Node {
    min: [f32; 3],
    offset: u32,
    max: [f32; 3],
    count: u16,
    axis: u16,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    fn bounds(&self) -> Bounds3 {
        Bounds3 { min: Vec3::from(self.min), max: Vec3::from(self.max) }
    }
}

/// Two sibling nodes in one cache line.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(64))]
struct Pair([Node; 2]);

/// The hierarchy over primitives `0..n` (in the order `build` returned). The root is
/// slot 0 of pair 0.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pairs: Vec<Pair>,
}

#[derive(Clone, Copy)]
struct PrimInfo {
    bounds: Bounds3,
    centroid: Vec3,
    index: u32,
}

enum BuildNode {
    Leaf { bounds: Bounds3, first: usize, count: usize },
    Interior { bounds: Bounds3, axis: usize, children: Box<(BuildNode, BuildNode)> },
}

const BINS: usize = 12;
const MAX_LEAF: usize = 8;
const PARALLEL_THRESHOLD: usize = 4096;

impl Bvh {
    /// Builds over the given boxes; returns the hierarchy and the primitive order.
    pub fn build(bounds: &[Bounds3]) -> (Bvh, Vec<u32>) {
        if bounds.is_empty() {
            return (Bvh::default(), Vec::new());
        }
        let mut info: Vec<PrimInfo> = bounds
            .iter()
            .enumerate()
            .map(|(i, b)| PrimInfo { bounds: *b, centroid: b.centroid(), index: i as u32 })
            .collect();
        let root = build_recursive(&mut info, 0);
        let mut pairs = vec![Pair::default()];
        flatten(&root, &mut pairs, (0, 0));
        pairs.shrink_to_fit();
        (Bvh { pairs }, info.iter().map(|p| p.index).collect())
    }

    pub fn node_count(&self) -> usize {
        2 * self.pairs.len()
    }

    pub fn heap_bytes(&self) -> usize {
        self.pairs.capacity() * std::mem::size_of::<Pair>()
    }

    pub fn bounds(&self) -> Bounds3 {
        self.pairs.first().map_or(Bounds3::default(), |p| p.0[0].bounds())
    }

    /// Closest hit: `hit(prim, t_max)` returns `Some(t)` for a hit closer than `t_max`.
    /// Returns the final t_max if anything was hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, mut t_max: f32, mut hit: impl FnMut(usize, f32) -> Option<f32>) -> Option<f32> {
        let mut found = false;
        self.traverse(ray, &mut t_max, |prim, t_max| match hit(prim, *t_max) {
            Some(t) => {
                *t_max = t;
                found = true;
                false
            }
            None => false,
        });
        found.then_some(t_max)
    }

    /// Any hit: stops at the first primitive for which `hit(prim, t_max)` is true.
    #[inline]
    pub fn intersect_p(&self, ray: &Ray, t_max: f32, mut hit: impl FnMut(usize, f32) -> bool) -> bool {
        let mut t = t_max;
        self.traverse(ray, &mut t, |prim, t_max| hit(prim, *t_max))
    }

    /// Visits leaves front to back; `visit` returns true to stop.
    #[inline]
    fn traverse(&self, ray: &Ray, t_max: &mut f32, mut visit: impl FnMut(usize, &mut f32) -> bool) -> bool {
        let Some(root) = self.pairs.first().map(|p| p.0[0]) else { return false };
        let r = SlabRay::new(ray);
        if r.entry(&root, *t_max) == f32::INFINITY {
            return false;
        }
        // Far children still to visit (pair * 2 + slot), with their entry distance.
        let mut stack = [(0u32, 0f32); 64];
        let mut sp = 0;
        let mut node = root;
        loop {
            if node.count > 0 {
                for prim in node.offset as usize..node.offset as usize + node.count as usize {
                    if visit(prim, t_max) {
                        return true;
                    }
                }
            } else {
                let pair = &self.pairs[node.offset as usize];
                let (tl, tr) = (r.entry(&pair.0[0], *t_max), r.entry(&pair.0[1], *t_max));
                if tl != f32::INFINITY || tr != f32::INFINITY {
                    let (near, far, t_far) = if tl <= tr { (0, 1, tr) } else { (1, 0, tl) };
                    if t_far != f32::INFINITY {
                        stack[sp] = (2 * node.offset + far, t_far);
                        sp += 1;
                    }
                    node = pair.0[near as usize];
                    continue;
                }
            }
            // Pop, skipping children that now lie beyond the closest hit.
            loop {
                if sp == 0 {
                    return false;
                }
                sp -= 1;
                let (n, t) = stack[sp];
                if t <= *t_max {
                    node = self.pairs[n as usize / 2].0[n as usize % 2];
                    break;
                }
            }
        }
    }
}

/// A ray prepared for slab tests: origin, reciprocal direction, direction signs.
struct SlabRay {
    o: [f32; 3],
    inv: [f32; 3],
    neg: [bool; 3],
}

impl SlabRay {
    fn new(ray: &Ray) -> SlabRay {
        let inv = (Vec3::ONE / ray.d.0).to_array();
        SlabRay { o: ray.o.0.to_array(), inv, neg: inv.map(|x| x < 0.0) }
    }

    /// The entry distance into the node's box within [0, t_max], or ∞ on a miss.
    /// pbrt's conservative test: the far distances are enlarged by 1 + 2γ(3).
    #[inline(always)]
    fn entry(&self, node: &Node, t_max: f32) -> f32 {
        const SCALE: f32 = 1.0 + 2.0 * crate::math::float::gamma(3);
        let (mut t0, mut t1) = (0.0f32, t_max);
        for a in 0..3 {
            let (near, far) = if self.neg[a] { (node.max[a], node.min[a]) } else { (node.min[a], node.max[a]) };
            let tn = (near - self.o[a]) * self.inv[a];
            let tf = (far - self.o[a]) * self.inv[a] * SCALE;
            // NaN (a ray in a slab's plane) leaves the bound unchanged: no miss.
            t0 = if tn > t0 { tn } else { t0 };
            t1 = if tf < t1 { tf } else { t1 };
        }
        if t0 <= t1 { t0 } else { f32::INFINITY }
    }
}

fn build_recursive(prims: &mut [PrimInfo], first: usize) -> BuildNode {
    let bounds = prims.iter().fold(Bounds3::default(), |b, p| b.union(p.bounds));
    let n = prims.len();
    if n == 1 {
        return BuildNode::Leaf { bounds, first, count: 1 };
    }
    let centroids = prims.iter().fold(Bounds3::default(), |b, p| b.union_point(p.centroid));
    let axis = centroids.max_extent();
    let (lo, hi) = (centroids.min[axis], centroids.max[axis]);
    let mid = if hi <= lo {
        // All centroids coincide: a leaf if it fits, else split by count.
        if n <= MAX_LEAF {
            return BuildNode::Leaf { bounds, first, count: n };
        }
        n / 2
    } else {
        match sah_split(prims, &bounds, axis, lo, hi) {
            Some(mid) => mid,
            None => return BuildNode::Leaf { bounds, first, count: n },
        }
    };
    let (left, right) = prims.split_at_mut(mid);
    let (a, b) = if n > PARALLEL_THRESHOLD {
        rayon::join(|| build_recursive(left, first), || build_recursive(right, first + mid))
    } else {
        (build_recursive(left, first), build_recursive(right, first + mid))
    };
    BuildNode::Interior { bounds, axis, children: Box::new((a, b)) }
}

/// Partitions by the cheapest of the bin boundaries; `None` when a leaf is cheaper.
fn sah_split(prims: &mut [PrimInfo], bounds: &Bounds3, axis: usize, lo: f32, hi: f32) -> Option<usize> {
    let n = prims.len();
    let bin_of = |c: Vec3| (((c[axis] - lo) / (hi - lo) * BINS as f32) as usize).min(BINS - 1);
    let mut count = [0usize; BINS];
    let mut bb = [Bounds3::default(); BINS];
    for p in prims.iter() {
        let b = bin_of(p.centroid);
        count[b] += 1;
        bb[b] = bb[b].union(p.bounds);
    }
    // Sweep from the right for the right-hand areas, then from the left.
    let mut right_area = [0f32; BINS];
    let (mut acc, mut acc_n) = (Bounds3::default(), 0usize);
    let mut right_count = [0usize; BINS];
    for i in (1..BINS).rev() {
        acc = acc.union(bb[i]);
        acc_n += count[i];
        right_area[i] = acc.surface_area();
        right_count[i] = acc_n;
    }
    let total = bounds.surface_area().max(f32::MIN_POSITIVE);
    let (mut best, mut best_cost) = (0, f32::INFINITY);
    let (mut left, mut left_n) = (Bounds3::default(), 0usize);
    for i in 0..BINS - 1 {
        left = left.union(bb[i]);
        left_n += count[i];
        let cost =
            // A traversal step costs about two triangle tests (memory bound).
            2.0 + (left_n as f32 * left.surface_area() + right_count[i + 1] as f32 * right_area[i + 1]) / total;
        if cost < best_cost {
            (best, best_cost) = (i, cost);
        }
    }
    if n <= MAX_LEAF && best_cost >= n as f32 {
        return None;
    }
    let mid = partition(prims, |p| bin_of(p.centroid) <= best);
    // A split that leaves one side empty (degenerate bins) falls back to halves.
    Some(if mid == 0 || mid == n { n / 2 } else { mid })
}

fn partition(prims: &mut [PrimInfo], pred: impl Fn(&PrimInfo) -> bool) -> usize {
    let mut i = 0;
    for j in 0..prims.len() {
        if pred(&prims[j]) {
            prims.swap(i, j);
            i += 1;
        }
    }
    i
}

/// Writes `node` into slot `at` and its children, recursively, into new pairs.
fn flatten(node: &BuildNode, pairs: &mut Vec<Pair>, at: (usize, usize)) {
    match node {
        BuildNode::Leaf { bounds, first, count } => {
            pairs[at.0].0[at.1] = Node {
                min: bounds.min.to_array(),
                offset: *first as u32,
                max: bounds.max.to_array(),
                count: *count as u16,
                axis: 0,
            }
        }
        BuildNode::Interior { bounds, axis, children } => {
            let pair = pairs.len();
            pairs.push(Pair::default());
            pairs[at.0].0[at.1] = Node {
                min: bounds.min.to_array(),
                offset: pair as u32,
                max: bounds.max.to_array(),
                count: 0,
                axis: *axis as u16,
            };
            flatten(&children.0, pairs, (pair, 0));
            flatten(&children.1, pairs, (pair, 1));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Point3, Vector3};

    #[test]
    fn finds_the_same_closest_box_as_brute_force() {
        let mut state = 12345u32;
        let mut rnd = || {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        let boxes: Vec<Bounds3> = (0..5000)
            .map(|_| {
                let c = Vec3::new(rnd(), rnd(), rnd()) * 100.0;
                Bounds3::new(c, c + Vec3::new(rnd(), rnd(), rnd()))
            })
            .collect();
        let (bvh, order) = Bvh::build(&boxes);
        let sorted: Vec<Bounds3> = order.iter().map(|&i| boxes[i as usize]).collect();
        for _ in 0..500 {
            let o = Vec3::new(rnd(), rnd(), rnd()) * 100.0;
            let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
            let ray = Ray::new(Point3(o), Vector3(d));
            let inv = Vec3::ONE / d;
            let neg = [(d.x < 0.0) as usize, (d.y < 0.0) as usize, (d.z < 0.0) as usize];
            let entry = |b: &Bounds3, t: f32| b.intersect_p(o, inv, neg, t).map(|t0| t0.max(0.0)).filter(|&t0| t0 < t);
            let brute = boxes.iter().filter_map(|b| entry(b, f32::INFINITY)).fold(f32::INFINITY, f32::min);
            let got = bvh.intersect(&ray, f32::INFINITY, |i, t| entry(&sorted[i], t));
            assert_eq!(got.unwrap_or(f32::INFINITY), brute);
        }
    }
}
