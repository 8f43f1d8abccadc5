//! A bounding volume hierarchy: binned SAH build (parallel for large subtrees),
//! collapsed into 4-wide nodes, with closure-based closest-hit and any-hit traversal
//! using pbrt's conservative slab test on four boxes at once (SSE through glam).
//!
//! DEVIATION(pbrt): pbrt and the issue use flat 32-byte binary nodes.
//! Incoherent rays on large meshes are bound by dependent cache misses, one per level;
//! a 4-wide node keeps four child boxes in two adjacent cache lines and halves the
//! levels. Each node is 128 bytes (four 32-byte child records: box plus reference), so
//! the BVH still takes well under 32 bytes per triangle.
//!
//! The BVH knows only boxes: `build` returns the primitive order it wants, and the
//! caller stores its primitives in that order, so leaves index them directly.

use crate::math::{Bounds3, Ray};
use glam::{Vec3, Vec4};
use std::mem::MaybeUninit;

/// Four children: their boxes (structure of arrays) and references. A child is a
/// node (`count` 0, `child` = node index), a leaf (`count` primitives from `child`),
/// or empty (`count` = `EMPTY`, an inverted box).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
struct Node4 {
    /// `bounds[0]` the low corners, `bounds[1]` the high ones, per axis.
    bounds: [[[f32; 4]; 3]; 2],
    child: [u32; 4],
    count: [u16; 4],
    _pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<Node4>() == 128);
const EMPTY: u16 = u16::MAX;

impl Default for Node4 {
    fn default() -> Node4 {
        Node4 {
            bounds: [[[f32::INFINITY; 4]; 3], [[f32::NEG_INFINITY; 4]; 3]],
            child: [0; 4],
            count: [EMPTY; 4],
            _pad: [0; 2],
        }
    }
}

impl Node4 {
    fn set(&mut self, slot: usize, b: &Bounds3, child: u32, count: u16) {
        for a in 0..3 {
            self.bounds[0][a][slot] = b.min[a];
            self.bounds[1][a][slot] = b.max[a];
        }
        self.child[slot] = child;
        self.count[slot] = count;
    }
}

/// The hierarchy over primitives `0..n` (in the order `build` returned); node 0 is
/// the root.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node4>,
    bounds: Bounds3,
}

#[derive(Clone, Copy)]
struct PrimInfo {
    bounds: Bounds3,
    centroid: Vec3,
    index: u32,
}

enum BuildNode {
    Leaf { bounds: Bounds3, first: usize, count: usize },
    Interior { bounds: Bounds3, children: Box<(BuildNode, BuildNode)> },
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
        let mut nodes = Vec::new();
        collapse(&root, &mut nodes);
        nodes.shrink_to_fit();
        (Bvh { nodes, bounds: root.bounds() }, info.iter().map(|p| p.index).collect())
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node4>()
    }

    pub fn bounds(&self) -> Bounds3 {
        self.bounds
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
        if self.nodes.is_empty() {
            return false;
        }
        let r = SlabRay::new(ray);
        let mut stack = Stack::new();
        let (mut child, mut count) = (0u32, 0u16);
        loop {
            if count > 0 {
                for prim in child as usize..child as usize + count as usize {
                    if visit(prim, t_max) {
                        return true;
                    }
                }
            } else {
                let node = &self.nodes[child as usize];
                let (t0, mut mask) = r.entries(node, *t_max);
                let t0 = t0.to_array();
                // Sort the hit children farthest first; go on with the nearest, push the rest.
                let mut hits = [(0f32, 0usize); 4];
                let mut n = 0;
                while mask != 0 {
                    let slot = mask.trailing_zeros() as usize & 3;
                    mask &= mask - 1;
                    let t = t0[slot];
                    let mut k = n;
                    while k > 0 && hits[k - 1].0 < t {
                        hits[k] = hits[k - 1];
                        k -= 1;
                    }
                    hits[k] = (t, slot);
                    n += 1;
                }
                if n > 0 {
                    for &(t, slot) in &hits[..n - 1] {
                        stack.push(node.child[slot & 3], node.count[slot & 3], t);
                    }
                    let slot = hits[n - 1].1 & 3;
                    (child, count) = (node.child[slot], node.count[slot]);
                    continue;
                }
            }
            // Pop, skipping entries that now lie beyond the closest hit.
            loop {
                let Some((c, k, t)) = stack.pop() else { return false };
                if t <= *t_max {
                    (child, count) = (c, k);
                    break;
                }
            }
        }
    }
}

/// The traversal stack: (node index or first primitive, primitive count or 0 for a
/// node, entry t). The inline part is left uninitialised: zeroing it cost more than
/// the rest of a cached traversal step. Entries past it, which only degenerate deep
/// trees need, go to the heap.
struct Stack {
    refs: [MaybeUninit<u64>; STACK_INLINE],
    ts: [MaybeUninit<f32>; STACK_INLINE],
    len: usize,
    spill: Vec<(u64, f32)>,
}

const STACK_INLINE: usize = 48;

impl Stack {
    #[inline(always)]
    fn new() -> Stack {
        Stack {
            refs: [const { MaybeUninit::uninit() }; STACK_INLINE],
            ts: [const { MaybeUninit::uninit() }; STACK_INLINE],
            len: 0,
            spill: Vec::new(),
        }
    }

    #[inline(always)]
    fn push(&mut self, child: u32, count: u16, t: f32) {
        let packed = child as u64 | (count as u64) << 32;
        if self.len < STACK_INLINE {
            self.refs[self.len].write(packed);
            self.ts[self.len].write(t);
            self.len += 1;
        } else {
            self.spill.push((packed, t));
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, u16, f32)> {
        let (packed, t) = match self.spill.pop() {
            Some(e) => e,
            None if self.len > 0 => {
                self.len -= 1;
                // SAFETY: `push` wrote every inline entry below `len`, and `len` only
                // shrinks here, past the entry just read.
                unsafe { (self.refs[self.len].assume_init(), self.ts[self.len].assume_init()) }
            }
            None => return None,
        };
        Some((packed as u32, (packed >> 32) as u16, t))
    }
}

/// A ray prepared for slab tests on four boxes at once.
struct SlabRay {
    o: [Vec4; 3],
    inv: [Vec4; 3],
    /// Per axis, which of a node's corners (0 low, 1 high) the ray meets first.
    near: [usize; 3],
}

impl SlabRay {
    fn new(ray: &Ray) -> SlabRay {
        let inv = Vec3::ONE / ray.d.0;
        let o = ray.o.0;
        SlabRay {
            o: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near: [(inv.x < 0.0) as usize, (inv.y < 0.0) as usize, (inv.z < 0.0) as usize],
        }
    }

    /// Entry distances of the four boxes within [0, t_max], and a bit mask of the hit
    /// ones. pbrt's conservative test: far distances are enlarged by 1 + 2γ(3); a ray
    /// lying in a slab's plane (a NaN) is not a miss.
    #[inline(always)]
    fn entries(&self, node: &Node4, t_max: f32) -> (Vec4, u32) {
        const SCALE: f32 = 1.0 + 2.0 * crate::math::float::gamma(3);
        let mut t0 = Vec4::ZERO;
        let mut t1 = Vec4::splat(t_max);
        for a in 0..3 {
            let n = self.near[a] & 1;
            let tn = (Vec4::from_array(node.bounds[n][a]) - self.o[a]) * self.inv[a];
            let tf = (Vec4::from_array(node.bounds[n ^ 1][a]) - self.o[a]) * self.inv[a] * SCALE;
            // max/min (SSE maxps/minps) keep the second operand when a lane is NaN:
            // pbrt's `if (tNear > t0) t0 = tNear`, lane by lane.
            t0 = tn.max(t0);
            t1 = tf.min(t1);
        }
        (t0, t0.cmple(t1).bitmask())
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
    BuildNode::Interior { bounds, children: Box::new((a, b)) }
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

impl BuildNode {
    fn bounds(&self) -> Bounds3 {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
        }
    }
}

/// Writes `node` (and, recursively, its subtree) as 4-wide nodes; returns its index.
/// A binary node's up to four grandchildren become its children, opening the largest
/// interior child first.
fn collapse(node: &BuildNode, nodes: &mut Vec<Node4>) -> u32 {
    let mut kids: Vec<&BuildNode> = match node {
        BuildNode::Leaf { .. } => vec![node],
        BuildNode::Interior { children, .. } => vec![&children.0, &children.1],
    };
    while kids.len() < 4 {
        let open = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| matches!(k, BuildNode::Interior { .. }))
            .max_by(|a, b| a.1.bounds().surface_area().total_cmp(&b.1.bounds().surface_area()))
            .map(|(i, _)| i);
        let Some(i) = open else { break };
        if let BuildNode::Interior { children, .. } = kids.remove(i) {
            kids.push(&children.0);
            kids.push(&children.1);
        }
    }
    let index = nodes.len();
    nodes.push(Node4::default());
    for (slot, k) in kids.into_iter().enumerate() {
        match k {
            BuildNode::Leaf { bounds, first, count } => nodes[index].set(slot, bounds, *first as u32, *count as u16),
            BuildNode::Interior { bounds, .. } => {
                let child = collapse(k, nodes);
                nodes[index].set(slot, bounds, child, 0);
            }
        }
    }
    index as u32
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

    #[test]
    fn the_stack_is_last_in_first_out_past_its_inline_part() {
        let mut stack = Stack::new();
        for i in 0..3 * STACK_INLINE as u32 {
            stack.push(u32::MAX - i, (i % 9) as u16, i as f32);
        }
        for i in (0..3 * STACK_INLINE as u32).rev() {
            assert_eq!(stack.pop(), Some((u32::MAX - i, (i % 9) as u16, i as f32)));
        }
        assert_eq!(stack.pop(), None);
    }

    /// Boxes at exponentially growing x make SAH peel a few off per level: a ray along
    /// them needs 94 stack entries here, past the inline 48.
    #[test]
    fn deep_trees_traverse_like_brute_force() {
        let boxes: Vec<Bounds3> = (0..160)
            .map(|i| {
                let x = 1.5f32.powi(i);
                Bounds3::new(Vec3::new(x, -0.5, -0.5), Vec3::new(1.01 * x, 0.5, 0.5))
            })
            .collect();
        let (bvh, order) = Bvh::build(&boxes);
        let sorted: Vec<Bounds3> = order.iter().map(|&i| boxes[i as usize]).collect();
        for (o, d) in [(Vec3::new(-1.0, 0.1, 0.0), Vec3::X), (Vec3::new(1e29, 0.0, 0.2), -Vec3::X)] {
            let ray = Ray::new(Point3(o), Vector3(d));
            let inv = Vec3::ONE / d;
            let neg = [(inv.x < 0.0) as usize, (inv.y < 0.0) as usize, (inv.z < 0.0) as usize];
            let entry = |b: &Bounds3, t: f32| b.intersect_p(o, inv, neg, t).map(|t0| t0.max(0.0)).filter(|&t0| t0 < t);
            let brute = boxes.iter().filter_map(|b| entry(b, f32::INFINITY)).fold(f32::INFINITY, f32::min);
            let got = bvh.intersect(&ray, f32::INFINITY, |i, t| entry(&sorted[i], t));
            assert!(brute.is_finite());
            assert_eq!(got.unwrap_or(f32::INFINITY), brute);
            // Every box is visited by an any-hit query that never stops.
            let mut seen = 0;
            bvh.intersect_p(&ray, f32::INFINITY, |i, t| {
                seen += entry(&sorted[i], t).is_some() as usize;
                false
            });
            assert_eq!(seen, boxes.len());
        }
    }
}
