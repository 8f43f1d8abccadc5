//! A bounding volume hierarchy: binned SAH build (parallel for large subtrees, and the
//! bins of large nodes filled on all threads from a sample of their primitives), each
//! node handed its primitives' boxes by its parent's bins or partition, written as
//! 8-wide nodes a wide node at a time (the binary tree is decided as it is written,
//! never stored), with closure-based closest-hit and any-hit traversal using pbrt's
//! conservative slab test: on all eight boxes at once with AVX where the processor has
//! AVX2 (detected at run time, as Embree does), else four at a time with SSE through
//! glam. Both do the same operations in the same order and give the same bits; the
//! caller picks with an [`Isa`] value.
//!
//! DEVIATION(pbrt): no image difference. pbrt and the issue use flat 32-byte binary nodes.
//! Incoherent rays on large meshes wait on one dependent cache miss per node they
//! visit, so the number of visits sets their speed: an 8-wide node visits a third as
//! many levels as a binary one. Each node is 256 bytes (eight 32-byte child records:
//! box and reference), and with leaves of a few triangles the BVH still takes about
//! 18 bytes per triangle.
//!
//! Closest-hit traversal takes the nearest hit child next; the node's other hit
//! children wait in one stack entry, from which the nearest that still starts before
//! the closest hit is taken next. It picks with SSE compares rather than branches,
//! which random rays mispredict. Any-hit traversal takes children in slot order: it
//! needs no order, and coherent shadow rays ran 1.5× faster without one.
//!
//! The BVH knows only boxes: `build` returns the primitive order it wants, and the
//! caller stores its primitives in that order, so leaves index them directly; or it
//! gives each leaf a reference and a tag of its own (`relabel_leaves`), as meshes do
//! for their leaf blocks.

use crate::math::{Bounds3, Ray};
use glam::{Vec3, Vec4};
use rayon::prelude::*;
use std::mem::MaybeUninit;
use std::ops::Range;

/// `WIDTH` children: their boxes (structure of arrays) and references. A child is a
/// node (`count` 0, `child` = node index) or a leaf (`count` primitives from
/// `child`); `valid` marks the slots in use.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
struct Node {
    /// `bounds[0]` the low corners, `bounds[1]` the high ones, per axis.
    bounds: [[Lanes; 3]; 2],
    child: [u32; WIDTH],
    count: [u8; WIDTH],
    /// Per leaf, a byte the caller sets with [`Bvh::relabel_leaves`].
    tag: [u8; WIDTH],
    valid: u8,
    _pad: [u8; 2 * WIDTH - 1],
}

/// Children per node.
const WIDTH: usize = 8;
const _: () = assert!(std::mem::size_of::<Node>() == 32 * WIDTH);

/// The instructions that test a node's boxes: SSE, which every x86-64 processor has,
/// or AVX, all eight boxes at once. The same operations in the same order, so both
/// give the same bits. Sealed: only [`Sse`] and [`Avx`] implement it, so the AVX code
/// runs only for holders of an [`Avx`].
pub trait Isa: Copy + sealed::Sealed {
    const AVX: bool;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::Sse {}
    impl Sealed for super::Avx {}
}

/// SSE (through glam), four boxes at a time.
#[derive(Clone, Copy, Debug)]
pub struct Sse;

/// AVX2. A value exists only where [`Avx::detect`] found the processor has it, so
/// holding one is what makes the AVX code safe to run.
#[derive(Clone, Copy, Debug)]
pub struct Avx(());

impl Isa for Sse {
    const AVX: bool = false;
}

impl Isa for Avx {
    const AVX: bool = true;
}

impl Avx {
    /// AVX2 with the bit instructions that come with it (BMI1/2, LZCNT, POPCNT), if
    /// this processor has them.
    pub fn detect() -> Option<Avx> {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            if has!("avx2") && has!("bmi1") && has!("bmi2") && has!("lzcnt") && has!("popcnt") {
                return Some(Avx(()));
            }
        }
        None
    }
}

impl Node {
    /// Encodes up to `WIDTH` children (box, child, count).
    fn new(kids: &[(Bounds3, u32, u8)]) -> Node {
        let mut node = Node {
            bounds: [[Lanes([f32::INFINITY; WIDTH]); 3], [Lanes([f32::NEG_INFINITY; WIDTH]); 3]],
            child: [0; WIDTH],
            count: [0; WIDTH],
            tag: [0; WIDTH],
            valid: 0,
            _pad: [0; 2 * WIDTH - 1],
        };
        for (slot, &(b, child, count)) in kids.iter().enumerate() {
            for a in 0..3 {
                node.bounds[0][a].0[slot] = b.min[a];
                node.bounds[1][a].0[slot] = b.max[a];
            }
            node.child[slot] = child;
            node.count[slot] = count;
            node.valid |= 1 << slot;
        }
        node
    }

    /// This node with its child nodes' references moved on by `base` (for a subtree
    /// written on its own and appended at `base`).
    fn shifted(mut self, base: u32) -> Node {
        for slot in 0..WIDTH {
            if self.valid & 1 << slot != 0 && self.count[slot] == 0 {
                self.child[slot] += base;
            }
        }
        self
    }

    /// A slot's (child, count, tag).
    #[inline(always)]
    fn slot(&self, slot: usize) -> (u32, u8, u8) {
        (self.child[slot], self.count[slot], self.tag[slot])
    }
}

/// A leaf as traversal hands it over: `count` primitives from `first`, or after
/// [`Bvh::relabel_leaves`] the reference and tag set there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leaf {
    pub first: usize,
    pub count: usize,
    pub tag: u8,
}

impl Leaf {
    pub fn prims(&self) -> Range<usize> {
        self.first..self.first + self.count
    }
}

/// The hierarchy over primitives `0..n` (in the order `build` returned); node 0 is
/// the root.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    bounds: Bounds3,
    /// The node visit's cost the build weighed (for [`Bvh::sah_cost`]).
    traversal_cost: f32,
}

/// A primitive during the build, 32 bytes: its box, with its intersection cost (in
/// triangle tests) in `lo.w` and its index's bits in `hi.w`, so that a union or a
/// centroid is one SIMD operation. The build is bound by memory; as separate fields
/// a record took 48 bytes. Callers with many primitives write these directly
/// ([`Bvh::build_records`]) rather than a list of boxes to be converted.
#[derive(Clone, Copy, Default)]
pub struct PrimInfo {
    lo: Vec4,
    hi: Vec4,
}

impl PrimInfo {
    /// Primitive number `index`, costing `cost` triangle tests, in box `b`.
    pub fn new(b: &Bounds3, cost: f32, index: u32) -> PrimInfo {
        PrimInfo { lo: b.min.extend(cost), hi: b.max.extend(f32::from_bits(index)) }
    }

    fn cost(&self) -> f32 {
        self.lo.w
    }

    fn index(&self) -> u32 {
        self.hi.w.to_bits()
    }

    /// Twice the centroid. Binning only compares centroids with each other, and
    /// doubling is exact, so the bins are those of the centroids themselves.
    fn centroid2(&self) -> Vec4 {
        self.lo + self.hi
    }
}

/// A box as two SIMD corners; the w lanes are not used.
#[derive(Clone, Copy)]
struct Box4 {
    lo: Vec4,
    hi: Vec4,
}

impl Box4 {
    const EMPTY: Box4 = Box4 { lo: Vec4::INFINITY, hi: Vec4::NEG_INFINITY };

    fn union(self, o: Box4) -> Box4 {
        Box4 { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    fn with_point(self, p: Vec4) -> Box4 {
        Box4 { lo: self.lo.min(p), hi: self.hi.max(p) }
    }

    fn bounds3(self) -> Bounds3 {
        Bounds3 { min: self.lo.truncate(), max: self.hi.truncate() }
    }
}

/// The boxes of a run of primitives and of their doubled centroids. A node gets
/// them from its parent's bins, so that it reads its primitives twice (binning,
/// partitioning) rather than four times.
#[derive(Clone, Copy)]
struct Extent {
    bounds: Box4,
    centroids: Box4,
}

impl Extent {
    const EMPTY: Extent = Extent { bounds: Box4::EMPTY, centroids: Box4::EMPTY };

    fn union(self, o: Extent) -> Extent {
        Extent { bounds: self.bounds.union(o.bounds), centroids: self.centroids.union(o.centroids) }
    }

    fn with(self, p: &PrimInfo) -> Extent {
        Extent {
            bounds: self.bounds.union(Box4 { lo: p.lo, hi: p.hi }),
            centroids: self.centroids.with_point(p.centroid2()),
        }
    }

    /// By reading them: on all threads for long runs (unions are exact, so the
    /// result does not depend on how the work is split).
    fn of(prims: &[PrimInfo]) -> Extent {
        if prims.len() <= PARALLEL_THRESHOLD {
            return prims.iter().fold(Extent::EMPTY, Extent::with);
        }
        prims
            .par_chunks(PARALLEL_THRESHOLD)
            .map(|c| c.iter().fold(Extent::EMPTY, Extent::with))
            .reduce(|| Extent::EMPTY, Extent::union)
    }
}

/// Per SAH bin: the summed intersection cost of its primitives and their extent.
/// The sums are f64: exact for the costs the build is given (small multiples of
/// powers of two), so they do not depend on the order they are added in.
#[derive(Clone, Copy)]
struct Bins {
    cost: [f64; BINS],
    extent: [Extent; BINS],
}

impl Bins {
    const EMPTY: Bins = Bins { cost: [0.0; BINS], extent: [Extent::EMPTY; BINS] };
    /// Nodes over more primitives than this fill `SETS` sets of bins, primitive i
    /// going to set i mod `SETS`: consecutive primitives often fall in one bin, and
    /// each would wait on the previous one's update of it.
    const MANY_SETS: usize = 64;
    /// Four sets rather than two (even and odd): the load benchmark's scene in 0.955
    /// and 0.972 of the time (7 pairs each), its 12.6M-triangle build being long runs
    /// of triangles in one bin. Eight gave no more. The sums are exact, so the bins,
    /// and the trees, are the same.
    const SETS: usize = 4;

    fn add(&mut self, p: &PrimInfo, b: usize) {
        self.cost[b] += p.cost() as f64;
        self.extent[b] = self.extent[b].with(p);
    }

    /// Adds `o`'s primitives, in place (a copy of the 864 bytes in and out per merge
    /// was a tenth of the split decisions' time in small nodes).
    fn merge(&mut self, o: &Bins) {
        for b in 0..BINS {
            self.cost[b] += o.cost[b];
            self.extent[b] = self.extent[b].union(o.extent[b]);
        }
    }

    /// The first set with the others merged into it.
    fn merged(sets: &mut [Bins]) -> &Bins {
        let (first, rest) = sets.split_first_mut().expect("at least one set of bins");
        rest.iter().for_each(|set| first.merge(set));
        first
    }

    fn fill(prims: &[PrimInfo], bin_of: impl Fn(Vec4) -> usize) -> Bins {
        if prims.len() <= Bins::MANY_SETS {
            let mut bins = Bins::EMPTY;
            prims.iter().for_each(|p| bins.add(p, bin_of(p.centroid2())));
            return bins;
        }
        let mut sets = [Bins::EMPTY; Bins::SETS];
        let mut runs = prims.chunks_exact(Bins::SETS);
        for run in &mut runs {
            let bins: [usize; Bins::SETS] = std::array::from_fn(|k| bin_of(run[k].centroid2()));
            for k in 0..Bins::SETS {
                sets[k].add(&run[k], bins[k]);
            }
        }
        runs.remainder().iter().for_each(|p| sets[0].add(p, bin_of(p.centroid2())));
        *Bins::merged(&mut sets)
    }

    /// Fills the bins from every `SAMPLE_STEP`-th primitive, on all threads.
    fn of_sample(prims: &[PrimInfo], bin_of: impl Fn(Vec4) -> usize + Sync) -> Bins {
        let fill = |run: &[PrimInfo]| {
            let mut sets = [Bins::EMPTY; Bins::SETS];
            for (k, p) in run.iter().step_by(SAMPLE_STEP).enumerate() {
                sets[k % Bins::SETS].add(p, bin_of(p.centroid2()));
            }
            *Bins::merged(&mut sets)
        };
        let mut runs: Vec<Bins> = prims.par_chunks(BIN_RUN).map(fill).collect();
        *Bins::merged(&mut runs)
    }

    /// Fills the bins from runs of `BIN_RUN` primitives, on all threads.
    fn of(prims: &[PrimInfo], bin_of: impl Fn(Vec4) -> usize + Sync) -> Bins {
        if prims.len() <= BIN_RUN {
            return Bins::fill(prims, bin_of);
        }
        let mut runs: Vec<Bins> = prims.par_chunks(BIN_RUN).map(|c| Bins::fill(c, &bin_of)).collect();
        *Bins::merged(&mut runs)
    }
}

/// How a node's primitives split: the first `mid` go left; the children's extents
/// when the bins give them.
struct Split {
    mid: usize,
    extents: Option<(Extent, Extent)>,
}

impl Split {
    fn at(mid: usize) -> Split {
        Split { mid, extents: None }
    }
}

/// What every node of one build shares.
struct Settings<'a> {
    max_leaf: usize,
    group: &'a (dyn Fn(usize) -> u32 + Sync),
    /// Nodes over more primitives than this write their children's subtrees on all
    /// threads ([`PARALLEL_COLLAPSE`]; tests set it low to nest that several deep).
    parallel_collapse: usize,
    /// Nodes over more primitives than this bin a sample of them ([`SAMPLED_BINNING`];
    /// tests set it past any node to compare with binning them all).
    sample_above: usize,
    /// A node visit's cost in triangle tests.
    traversal_cost: f32,
}

const BINS: usize = 12;
/// Nodes over more primitives than this choose their split from the bins of every
/// `SAMPLE_STEP`-th one (at least 4,096): twelve bins of that many give the split of
/// all of them, or one as good (a 1M-triangle mesh's SAH cost 86.84 against 87.05),
/// and reading a sixteenth of the records (every eighth cache line) took the load
/// benchmark's scene, 12.6M triangles in one BVH, to 0.964 of its wall time (5 pairs).
/// The sides' extents then come from the partition, which reads them all anyway.
const SAMPLED_BINNING: usize = 1 << 16;
const SAMPLE_STEP: usize = 16;
/// Builds of at least this many primitives hand their freed records back to the system
/// (see [`return_freed_heap`]).
const TRIM_PRIMS: usize = 1 << 16;
/// A node visit's cost in triangle tests, for SAH. A visit is a dependent cache miss
/// on large scenes, and a leaf's triangles are fetched together, so leaves of a few
/// triangles pay: with 8-wide nodes this gives 18 bytes of BVH per triangle (2.0
/// gave 35) at the same speed on large meshes and small ones. Quadrics cost more
/// (`shapes::set::QUADRIC_COST`), so they still get leaves of their own.
const TRAVERSAL_COST: f32 = 4.0;
/// A mixed tree ([`Bvh::build_mixed`]) over at most this many primitives stays in the
/// L2 cache whatever its leaves (about 250 KiB at 1 below), so a node visit costs
/// about a triangle test, as pbrt's SAH takes it: [`SMALL_TRAVERSAL_COST`]. Rooms of a
/// few large triangles beside a sphere need it. At 4, a leaf's box spans walls on
/// both sides of the room, and every ray tests them all: `doorway` spent 29% of its
/// time in leaf tests, and renders in 0.83 of the time with this and
/// [`SMALL_MAX_LEAF`] (docs/accel.md). Trees of leaf blocks (meshes alone) keep 4:
/// their leaves are fetched and tested together, and at 1 and 4 a leaf, 300 objects of
/// 4,096 triangles took 137 MB and 0.35 s to render a pixel, against 91 MB and 0.22 s.
const SMALL_TREE: usize = 4096;
const SMALL_TRAVERSAL_COST: f32 = 1.0;
/// A small tree's most primitives in a leaf, pbrt's. SAH weighs each split with its
/// sides as leaves, so where three walls meet (a floor, a ceiling and the wall that
/// joins them: every split leaves a side as large as the whole) it would keep all
/// three in one leaf; a node over more than this splits all the same.
const SMALL_MAX_LEAF: usize = 4;
/// The most primitives in a leaf, unless the caller asks for another limit.
pub const MAX_LEAF: usize = 8;
const PARALLEL_THRESHOLD: usize = 4096;
/// Wide nodes over more primitives than this write their children's subtrees on all
/// threads.
const PARALLEL_COLLAPSE: usize = 1 << 18;
/// Nodes over more primitives than this bin them on all threads, in runs this long.
const BIN_RUN: usize = 1 << 16;

impl Bvh {
    /// Builds over the given boxes, primitive i costing `cost(i)` triangle tests to
    /// intersect; returns the hierarchy and the primitive order.
    pub fn build(bounds: Vec<Bounds3>, cost: impl Fn(usize) -> f32 + Sync) -> (Bvh, Vec<u32>) {
        Bvh::build_with_max_leaf(bounds, cost, MAX_LEAF)
    }

    /// [`Bvh::build`] with at most `max_leaf` (at most 255) primitives per leaf.
    pub fn build_with_max_leaf(
        bounds: Vec<Bounds3>,
        cost: impl Fn(usize) -> f32 + Sync,
        max_leaf: usize,
    ) -> (Bvh, Vec<u32>) {
        Bvh::build_grouped(bounds, cost, max_leaf, |_| 0)
    }

    /// [`Bvh::build_with_max_leaf`] whose leaves each hold primitives of one group
    /// (`group(i)`): a leaf that SAH would fill from several is split by group instead.
    pub fn build_grouped(
        bounds: Vec<Bounds3>,
        cost: impl Fn(usize) -> f32 + Sync,
        max_leaf: usize,
        group: impl Fn(usize) -> u32 + Sync,
    ) -> (Bvh, Vec<u32>) {
        let info: Vec<PrimInfo> =
            bounds.par_iter().enumerate().map(|(i, b)| PrimInfo::new(b, cost(i), i as u32)).collect();
        // The records hold the boxes: not both at the build's peak.
        drop(bounds);
        Bvh::build_records(info, max_leaf, group)
    }

    /// [`Bvh::build_grouped`] from the primitives' records, record i numbered i.
    pub fn build_records(info: Vec<PrimInfo>, max_leaf: usize, group: impl Fn(usize) -> u32 + Sync) -> (Bvh, Vec<u32>) {
        Bvh::build_weighed(info, max_leaf, group, TRAVERSAL_COST)
    }

    /// A tree over primitives of several kinds (triangles beside quadrics, patches or
    /// curves), whose leaves are tested a primitive or a run of four triangles at a
    /// time: where it is small ([`SMALL_TREE`]), weighed and cut as pbrt's is.
    pub fn build_mixed(info: Vec<PrimInfo>) -> (Bvh, Vec<u32>) {
        match info.len() <= SMALL_TREE {
            true => Bvh::build_weighed(info, SMALL_MAX_LEAF, |_| 0, SMALL_TRAVERSAL_COST),
            false => Bvh::build_records(info, MAX_LEAF, |_| 0),
        }
    }

    /// [`Bvh::build_records`] with a node visit weighed at `traversal_cost`.
    fn build_weighed(
        info: Vec<PrimInfo>,
        max_leaf: usize,
        group: impl Fn(usize) -> u32 + Sync,
        traversal_cost: f32,
    ) -> (Bvh, Vec<u32>) {
        if info.is_empty() {
            return (Bvh::default(), Vec::new());
        }
        let settings = Settings {
            max_leaf: max_leaf.clamp(1, u8::MAX as usize),
            group: &group,
            parallel_collapse: PARALLEL_COLLAPSE,
            sample_above: SAMPLED_BINNING,
            traversal_cost,
        };
        let (bvh, order) = build_with(info, &settings);
        if order.len() >= TRIM_PRIMS {
            return_freed_heap();
        }
        (bvh, order)
    }

    /// Each leaf's (first, count), in the order [`Bvh::relabel_leaves`] visits them.
    pub fn leaves(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.nodes.iter().flat_map(|node| {
            (0..WIDTH)
                .filter(|&slot| node.valid & 1 << slot != 0 && node.count[slot] > 0)
                .map(|slot| (node.child[slot] as usize, node.count[slot] as usize))
        })
    }

    /// Replaces each leaf's (first, tag) by `relabel(first, count)`, for callers that
    /// keep their own per-leaf records; traversal then hands over those instead.
    pub fn relabel_leaves(&mut self, mut relabel: impl FnMut(usize, usize) -> (u32, u8)) {
        for node in &mut self.nodes {
            for slot in 0..WIDTH {
                if node.valid & 1 << slot != 0 && node.count[slot] > 0 {
                    let (child, tag) = relabel(node.child[slot] as usize, node.count[slot] as usize);
                    (node.child[slot], node.tag[slot]) = (child, tag);
                }
            }
        }
    }

    /// See [`crate::hugepages`].
    pub fn advise_huge_pages(&self) {
        crate::hugepages::advise(&self.nodes);
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The tree's SAH cost, in triangle tests per ray through the root's box: each
    /// node's box area (relative to the root's) times a node visit's cost, plus each
    /// leaf's times its primitives. What the build minimises, to compare builds by.
    pub fn sah_cost(&self) -> f64 {
        let root = self.bounds.surface_area() as f64;
        if self.nodes.is_empty() || root <= 0.0 {
            return 0.0;
        }
        let area = |node: &Node, slot: usize| -> f64 {
            let d = [0, 1, 2].map(|a| (node.bounds[1][a].0[slot] - node.bounds[0][a].0[slot]).max(0.0) as f64);
            2.0 * (d[0] * d[1] + d[0] * d[2] + d[1] * d[2])
        };
        let (mut nodes, mut leaves) = (root, 0.0);
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i];
            for slot in (0..WIDTH).filter(|&slot| node.valid & 1 << slot != 0) {
                match node.count[slot] {
                    0 => {
                        nodes += area(node, slot);
                        stack.push(node.child[slot] as usize);
                    }
                    n => leaves += n as f64 * area(node, slot),
                }
            }
        }
        (self.traversal_cost as f64 * nodes + leaves) / root
    }

    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node>()
    }

    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// Closest hit: `hit(prim, t_max)` returns `Some(t)` for a hit closer than `t_max`.
    /// Returns the final t_max if anything was hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32, mut hit: impl FnMut(usize, f32) -> Option<f32>) -> Option<f32> {
        self.intersect_leaves(Sse, ray, t_max, |leaf, mut t_max| {
            let mut found = false;
            for prim in leaf.prims() {
                if let Some(t) = hit(prim, t_max) {
                    (t_max, found) = (t, true);
                }
            }
            found.then_some(t_max)
        })
    }

    /// Any hit: stops at the first primitive for which `hit(prim, t_max)` is true.
    #[inline]
    pub fn intersect_p(&self, ray: &Ray, t_max: f32, mut hit: impl FnMut(usize, f32) -> bool) -> bool {
        self.intersect_leaves_p(Sse, ray, t_max, |leaf, t_max| leaf.prims().any(|prim| hit(prim, t_max)))
    }

    /// Closest hit, a leaf at a time: `hit(leaf, t_max)` returns the closest t below
    /// `t_max` among the leaf's primitives, if any. `isa` picks the node test.
    #[inline(always)]
    pub fn intersect_leaves<I: Isa>(
        &self,
        isa: I,
        ray: &Ray,
        mut t_max: f32,
        mut hit: impl FnMut(Leaf, f32) -> Option<f32>,
    ) -> Option<f32> {
        let mut found = false;
        self.traverse::<I, true>(isa, ray, &mut t_max, |leaf, t_max| {
            if let Some(t) = hit(leaf, *t_max) {
                (*t_max, found) = (t, true);
            }
            false
        });
        found.then_some(t_max)
    }

    /// Any hit, a leaf at a time: stops at the first leaf for which `hit` is true.
    #[inline(always)]
    pub fn intersect_leaves_p<I: Isa>(
        &self,
        isa: I,
        ray: &Ray,
        t_max: f32,
        mut hit: impl FnMut(Leaf, f32) -> bool,
    ) -> bool {
        let mut t = t_max;
        self.traverse::<I, false>(isa, ray, &mut t, |leaf, t_max| hit(leaf, *t_max))
    }

    /// Visits leaves, front to back if `NEAREST`; `visit` returns true to stop.
    #[inline(always)]
    fn traverse<I: Isa, const NEAREST: bool>(
        &self,
        _isa: I,
        ray: &Ray,
        t_max: &mut f32,
        mut visit: impl FnMut(Leaf, &mut f32) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let r = SlabRay::new(ray);
        let mut stack = Stack::new();
        let (mut child, mut count, mut tag) = (0u32, 0u8, 0u8);
        loop {
            if count > 0 {
                if visit(Leaf { first: child as usize, count: count as usize, tag }, t_max) {
                    return true;
                }
            } else {
                let node = &self.nodes[child as usize];
                let (ts, hits) = r.entries::<I>(node, *t_max);
                if hits != 0 {
                    // Go on with one hit child (the nearest); the others wait in one entry.
                    // The entry keeps the nearest's t: its slot bit is what is cleared.
                    // (Writing +∞ into the lane in memory and copying the lanes at once
                    // stalled each push on the store: 15% of a small scene's traversal.)
                    // A lone hit child leaves nothing to wait (an empty entry cost
                    // a store, and a load to drop it).
                    let nearest = ts.first::<I, NEAREST>(hits);
                    let rest = hits & !(1 << nearest);
                    if rest != 0 {
                        stack.push(Pending { ts, node: child, slots: rest });
                    }
                    (child, count, tag) = node.slot(nearest);
                    continue;
                }
            }
            let Some(next) = stack.next::<I, NEAREST>(&self.nodes, *t_max) else { return false };
            (child, count, tag) = next;
        }
    }
}

/// A float per child slot, aligned for AVX loads. Lanes are set through memory:
/// inserting into a register by a variable index compiles to a jump table.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
struct Lanes([f32; WIDTH]);

impl Lanes {
    #[inline(always)]
    fn half(&self, h: usize) -> Vec4 {
        Vec4::from_slice(&self.0[4 * h..4 * h + 4])
    }

    /// The lanes at most `t` as a bit mask.
    #[inline(always)]
    fn at_most<I: Isa>(&self, t: f32) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if I::AVX {
            // SAFETY: an `Avx` value, the only `Isa` with `AVX`, proves the processor has it.
            return unsafe { avx::at_most(self, t) };
        }
        let t = Vec4::splat(t);
        self.half(0).cmple(t).bitmask() | self.half(1).cmple(t).bitmask() << 4
    }

    /// The slot to visit first among `slots`: the nearest, or (for any-hit queries,
    /// which need no order) the lowest. A lone slot is its own nearest: no search.
    #[inline(always)]
    fn first<I: Isa, const NEAREST: bool>(&self, slots: u32) -> usize {
        match NEAREST && slots & slots.wrapping_sub(1) != 0 {
            true => self.nearest::<I>(slots),
            false => slots.trailing_zeros() as usize & (WIDTH - 1),
        }
    }

    /// The slot with the smallest value among `slots` (a nonempty bit set), the lower
    /// slot on ties. Lanes outside `slots` count as +∞, whatever they hold.
    #[inline(always)]
    fn nearest<I: Isa>(&self, slots: u32) -> usize {
        #[cfg(target_arch = "x86_64")]
        if I::AVX {
            // SAFETY: as in `at_most`.
            return unsafe { avx::nearest(self, slots) };
        }
        let inside = |h: usize| {
            let bit = |k: usize| slots >> (4 * h + k) & 1 != 0;
            Vec4::select(glam::BVec4A::new(bit(0), bit(1), bit(2), bit(3)), self.half(h), Vec4::INFINITY)
        };
        let (low, high) = (inside(0), inside(1));
        let least = Vec4::splat(low.min(high).min_element());
        let at_least = low.cmpeq(least).bitmask() | high.cmpeq(least).bitmask() << 4;
        // Should no lane match (a NaN ray), the lowest slot of `slots` is taken.
        ((at_least & slots | slots << WIDTH).trailing_zeros() as usize) & (WIDTH - 1)
    }
}

/// A visited node's hit children that are still to visit: their slots, and the entry t
/// of each hit child (+∞ for the missed; lanes outside `slots` are not read).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pending {
    ts: Lanes,
    node: u32,
    slots: u32,
}

/// The traversal stack. Each entry is a node on the path to the current one, so its
/// depth is at most the tree's. The inline part is left uninitialised: zeroing it
/// cost more than the rest of a cached traversal step. Entries past it, which only
/// degenerate deep trees need, go to the heap.
struct Stack {
    inline: [MaybeUninit<Pending>; STACK_INLINE],
    len: usize,
    spill: Vec<Pending>,
}

/// Unit tests use a small inline part so that their trees reach the spill path.
const STACK_INLINE: usize = if cfg!(test) { 4 } else { 64 };

impl Stack {
    #[inline(always)]
    fn new() -> Stack {
        Stack { inline: [const { MaybeUninit::uninit() }; STACK_INLINE], len: 0, spill: Vec::new() }
    }

    /// Pushes the entry if it has slots; without a branch while the inline part has room.
    #[inline(always)]
    fn push(&mut self, entry: Pending) {
        if self.len < STACK_INLINE {
            self.inline[self.len].write(entry);
            self.len += (entry.slots != 0) as usize;
        } else if entry.slots != 0 {
            #[cfg(test)]
            tests::SPILLED.with(|s| s.set(true));
            self.spill.push(entry);
        }
    }

    #[inline(always)]
    fn top(&mut self) -> Option<&mut Pending> {
        match self.spill.last_mut() {
            Some(e) => Some(e),
            None if self.len > 0 => {
                // SAFETY: `push` writes every inline entry below `len` before raising
                // `len` past it, and `len` only shrinks in `drop_top`.
                Some(unsafe { self.inline[self.len - 1].assume_init_mut() })
            }
            None => None,
        }
    }

    #[inline(always)]
    fn drop_top(&mut self) {
        if self.spill.pop().is_none() {
            self.len -= 1;
        }
    }

    /// The next waiting child that starts within `t_max`, the nearest if `NEAREST`, as
    /// [`Node::slot`] gives it; entries left with none are dropped.
    #[inline(always)]
    fn next<I: Isa, const NEAREST: bool>(&mut self, nodes: &[Node], t_max: f32) -> Option<(u32, u8, u8)> {
        loop {
            let top = self.top()?;
            let live = top.slots & top.ts.at_most::<I>(t_max);
            if live == 0 {
                self.drop_top();
                continue;
            }
            let slot = top.ts.first::<I, NEAREST>(live);
            top.slots = live & !(1 << slot);
            let node = &nodes[top.node as usize];
            if top.slots == 0 {
                self.drop_top();
            }
            return Some(node.slot(slot));
        }
    }
}

/// The far-distance scale of pbrt's conservative slab test, 1 + 2γ(3).
const SCALE: f32 = 1.0 + 2.0 * crate::math::float::gamma(3);

/// A ray prepared for slab tests on a node's boxes.
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

    /// Entry distances of the node's boxes within [0, t_max] (+∞ for the missed ones),
    /// and a bit mask of the hit ones. pbrt's conservative test: far distances are
    /// enlarged by 1 + 2γ(3); a ray lying in a slab's plane (a NaN) is not a miss.
    #[inline(always)]
    fn entries<I: Isa>(&self, node: &Node, t_max: f32) -> (Lanes, u32) {
        #[cfg(target_arch = "x86_64")]
        if I::AVX {
            // SAFETY: as in `Lanes::at_most`.
            return unsafe { avx::entries(self, node, t_max) };
        }
        let mut t0 = [Vec4::ZERO; WIDTH / 4];
        let mut t1 = [Vec4::splat(t_max); WIDTH / 4];
        for a in 0..3 {
            let n = self.near[a] & 1;
            for h in 0..WIDTH / 4 {
                let tn = (node.bounds[n][a].half(h) - self.o[a]) * self.inv[a];
                let tf = (node.bounds[n ^ 1][a].half(h) - self.o[a]) * self.inv[a] * SCALE;
                // max/min (SSE maxps/minps) keep the second operand when a lane is NaN:
                // pbrt's `if (tNear > t0) t0 = tNear`, lane by lane.
                t0[h] = tn.max(t0[h]);
                t1[h] = tf.min(t1[h]);
            }
        }
        let (mut hits, mut ts) = (0, Lanes([0.0; WIDTH]));
        for h in 0..WIDTH / 4 {
            let hit = t0[h].cmple(t1[h]);
            hits |= hit.bitmask() << (4 * h);
            ts.0[4 * h..4 * h + 4].copy_from_slice(&Vec4::select(hit, t0[h], Vec4::INFINITY).to_array());
        }
        (ts, hits & node.valid as u32)
    }
}

/// The AVX versions of the node test and the lane picks: one 8-wide instruction
/// where SSE takes two. Callers must hold an [`Avx`].
#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{Lanes, Node, SCALE, SlabRay, WIDTH};
    use std::arch::x86_64::*;

    #[target_feature(enable = "avx")]
    #[inline]
    fn load(l: &Lanes) -> __m256 {
        // SAFETY: `Lanes` is eight floats (32 bytes) aligned to 32 bytes.
        unsafe { _mm256_load_ps(l.0.as_ptr()) }
    }

    /// [`SlabRay::entries`].
    #[target_feature(enable = "avx")]
    #[inline]
    pub fn entries(r: &SlabRay, node: &Node, t_max: f32) -> (Lanes, u32) {
        let (mut t0, mut t1) = (_mm256_setzero_ps(), _mm256_set1_ps(t_max));
        for a in 0..3 {
            let n = r.near[a] & 1;
            let (o, inv) = (_mm256_set1_ps(r.o[a].x), _mm256_set1_ps(r.inv[a].x));
            let tn = _mm256_mul_ps(_mm256_sub_ps(load(&node.bounds[n][a]), o), inv);
            let tf = _mm256_mul_ps(_mm256_sub_ps(load(&node.bounds[n ^ 1][a]), o), inv);
            // The operand order of the SSE code, for its NaN rule.
            t0 = _mm256_max_ps(tn, t0);
            t1 = _mm256_min_ps(_mm256_mul_ps(tf, _mm256_set1_ps(SCALE)), t1);
        }
        let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1);
        let mut ts = Lanes([0.0; WIDTH]);
        // SAFETY: as in `load`.
        unsafe { _mm256_store_ps(ts.0.as_mut_ptr(), _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), t0, hit)) };
        (ts, _mm256_movemask_ps(hit) as u32 & node.valid as u32)
    }

    /// [`Lanes::at_most`].
    #[target_feature(enable = "avx")]
    #[inline]
    pub fn at_most(l: &Lanes, t: f32) -> u32 {
        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(load(l), _mm256_set1_ps(t))) as u32
    }

    /// [`Lanes::nearest`].
    #[target_feature(enable = "avx2")]
    #[inline]
    pub fn nearest(l: &Lanes, slots: u32) -> usize {
        // Lanes outside `slots` to +∞, in registers.
        let bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let inside = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(slots as i32), bit), bit);
        let v = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), load(l), _mm256_castsi256_ps(inside));
        // The least lane, in every lane: halves, then pairs, then neighbours.
        let m = _mm256_min_ps(v, _mm256_permute2f128_ps::<1>(v, v));
        let m = _mm256_min_ps(m, _mm256_permute_ps::<0b01_00_11_10>(m));
        let m = _mm256_min_ps(m, _mm256_permute_ps::<0b10_11_00_01>(m));
        let at_least = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_EQ_OQ>(v, m)) as u32;
        ((at_least & slots | slots << WIDTH).trailing_zeros() as usize) & (WIDTH - 1)
    }
}

/// Builds over `info` (not empty), returning the hierarchy and the primitive order.
/// A large build writes its subtrees in pieces on all threads and copies them once,
/// into their final array.
fn build_with(mut info: Vec<PrimInfo>, settings: &Settings) -> (Bvh, Vec<u32>) {
    let root = decide(&mut info, 0, settings, None);
    let bounds = root.bounds();
    let order = |info: &[PrimInfo]| info.par_iter().map(PrimInfo::index).collect();
    if info.len() <= settings.parallel_collapse {
        let mut nodes = Vec::new();
        write_wide(&mut info, 0, root, settings, &mut nodes);
        nodes.shrink_to_fit();
        return (Bvh { nodes, bounds, traversal_cost: settings.traversal_cost }, order(&info));
    }
    let pieces = write_pieces(&mut info, 0, root, settings);
    // The records go before the nodes' final array is made: not both at the peak
    // (32 MB of a million instances' 66 MB of nodes).
    let order = order(&info);
    drop(info);
    (Bvh { nodes: join_pieces(pieces), bounds, traversal_cost: settings.traversal_cost }, order)
}

/// Returns the heap's free pages to the system: the build's records, once freed, may
/// stay resident in the heap while the large arrays made next (instances, leaf blocks)
/// come from fresh mappings beside them. (When the build kept a binary tree of heap
/// blocks, this took 153 MB off the peak of a million instances.)
fn return_freed_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases pages of free chunks; it is thread-safe.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// A node of the binary build, decided but not written: a leaf, or an interior node
/// whose primitives are partitioned at `mid` (its children not decided yet).
#[derive(Clone, Copy)]
enum Decided {
    Leaf { bounds: Bounds3, first: u32, count: u32 },
    Interior { bounds: Bounds3, first: u32, count: u32, mid: u32, extents: Option<(Extent, Extent)> },
}

impl Decided {
    fn bounds(&self) -> Bounds3 {
        match self {
            Decided::Leaf { bounds, .. } | Decided::Interior { bounds, .. } => *bounds,
        }
    }

    /// Its primitives' range within the build.
    fn range(&self) -> Range<usize> {
        let (Decided::Leaf { first, count, .. } | Decided::Interior { first, count, .. }) = *self;
        first as usize..(first + count) as usize
    }
}

/// Decides the node over `prims` (starting at `first` in the final order; `known`, its
/// extent if the parent's bins gave it): a leaf, or a split, partitioning `prims`.
fn decide(prims: &mut [PrimInfo], first: usize, settings: &Settings, known: Option<Extent>) -> Decided {
    let extent = known.unwrap_or_else(|| Extent::of(prims));
    let bounds = extent.bounds.bounds3();
    let n = prims.len();
    let (first, count) = (first as u32, n as u32);
    if n == 1 {
        return Decided::Leaf { bounds, first, count };
    }
    let centroids = extent.centroids.bounds3();
    let axis = centroids.max_extent();
    let (lo, hi) = (centroids.min[axis], centroids.max[axis]);
    let split = if hi <= lo {
        // All centroids coincide: a leaf if it fits, else split by count.
        (n > settings.max_leaf).then(|| Split::at(n / 2))
    } else {
        // The axis as a constant: a lane picked by a run-time index was a branch per
        // primitive in the binning loop.
        match axis {
            0 => sah_split::<0>(prims, &bounds, lo, hi, settings),
            1 => sah_split::<1>(prims, &bounds, lo, hi, settings),
            _ => sah_split::<2>(prims, &bounds, lo, hi, settings),
        }
    };
    match split.or_else(|| split_groups(prims, settings.group).map(Split::at)) {
        Some(Split { mid, extents }) => Decided::Interior { bounds, first, count, mid: mid as u32, extents },
        None => Decided::Leaf { bounds, first, count },
    }
}

/// The two children of `node` decided (on two threads for large nodes), or `None` for
/// a leaf; `prims` are the node's own, partitioned at its split.
fn open(prims: &mut [PrimInfo], node: Decided, settings: &Settings) -> Option<(Decided, Decided)> {
    let Decided::Interior { first, mid, extents, .. } = node else { return None };
    let (first, mid) = (first as usize, mid as usize);
    let n = prims.len();
    let (left, right) = prims.split_at_mut(mid);
    let (el, er) = extents.map_or((None, None), |(l, r)| (Some(l), Some(r)));
    Some(match n > PARALLEL_THRESHOLD {
        true => rayon::join(|| decide(left, first, settings, el), || decide(right, first + mid, settings, er)),
        false => (decide(left, first, settings, el), decide(right, first + mid, settings, er)),
    })
}

/// A node's children in the `WIDTH`-wide tree: its binary descendants, up to `WIDTH`
/// of them, opening the largest interior one first (`prims` are the node's, starting
/// at `base`).
fn wide_kids(prims: &mut [PrimInfo], base: usize, node: Decided, settings: &Settings) -> ([Decided; WIDTH], usize) {
    let mut kids = [node; WIDTH];
    let mut n = 1;
    let mut open_at = |kids: &mut [Decided; WIDTH], i: usize, n: usize| {
        let r = kids[i].range();
        if let Some((a, b)) = open(&mut prims[r.start - base..r.end - base], kids[i], settings) {
            // Removed from its place, its two children go last.
            kids.copy_within(i + 1..n, i);
            (kids[n - 1], kids[n]) = (a, b);
        }
    };
    if matches!(node, Decided::Interior { .. }) {
        open_at(&mut kids, 0, 1);
        n = 2;
    }
    while n < WIDTH {
        let open = kids[..n]
            .iter()
            .enumerate()
            .filter(|(_, k)| matches!(k, Decided::Interior { .. }))
            .max_by(|a, b| a.1.bounds().surface_area().total_cmp(&b.1.bounds().surface_area()))
            .map(|(i, _)| i);
        let Some(i) = open else { break };
        open_at(&mut kids, i, n);
        n += 1;
    }
    (kids, n)
}

/// Writes `node` (over `prims`, starting at `base`) and, recursively, its subtree as
/// `WIDTH`-wide nodes in pre-order, on this thread; returns its index. The binary
/// tree is decided a wide node at a time and never stored.
fn write_wide(prims: &mut [PrimInfo], base: usize, node: Decided, settings: &Settings, nodes: &mut Vec<Node>) -> u32 {
    let (kids, n) = wide_kids(prims, base, node, settings);
    let index = nodes.len();
    nodes.push(Node::new(&[]));
    let mut encoded = [(Bounds3::default(), 0u32, 0u8); WIDTH];
    for (slot, k) in kids[..n].iter().enumerate() {
        let r = k.range();
        encoded[slot] = leaf_slot(k).unwrap_or_else(|| {
            (k.bounds(), write_wide(&mut prims[r.start - base..r.end - base], r.start, *k, settings, nodes), 0)
        });
    }
    nodes[index] = Node::new(&encoded[..n]);
    index as u32
}

/// A leaf's slot (box, first, count), or `None` for an interior node.
fn leaf_slot(k: &Decided) -> Option<(Bounds3, u32, u8)> {
    match *k {
        Decided::Leaf { bounds, first, count } => Some((bounds, first, count as u8)),
        Decided::Interior { .. } => None,
    }
}

/// The nodes of a large node's subtree (over `prims`, starting at `base`) in
/// pre-order, as pieces: the node itself, then its children's subtrees, written on all
/// threads. A piece's child references count from the piece's own first node, so
/// [`join_pieces`] only adds each piece's place. Copied together at each large level,
/// as they were, a 12.6M-triangle scene's nodes went twice into fresh huge pages.
fn write_pieces(prims: &mut [PrimInfo], base: usize, node: Decided, settings: &Settings) -> Vec<Vec<Node>> {
    let (kids, n) = wide_kids(prims, base, node, settings);
    let kids = &kids[..n];
    let below: Vec<Vec<Vec<Node>>> = kid_slices(prims, base, kids)
        .into_par_iter()
        .map(|(k, slice)| match leaf_slot(&k) {
            Some(_) => Vec::new(),
            None if slice.len() > settings.parallel_collapse => write_pieces(slice, k.range().start, k, settings),
            None => {
                let mut sub = Vec::new();
                write_wide(slice, k.range().start, k, settings, &mut sub);
                vec![sub]
            }
        })
        .collect();
    let mut encoded = [(Bounds3::default(), 0u32, 0u8); WIDTH];
    let mut next = 1;
    for (slot, (k, pieces)) in kids.iter().zip(&below).enumerate() {
        encoded[slot] = leaf_slot(k).unwrap_or((k.bounds(), next, 0));
        next += pieces.iter().map(Vec::len).sum::<usize>() as u32;
    }
    let mut all = vec![vec![Node::new(&encoded[..n])]];
    all.extend(below.into_iter().flatten());
    all
}

/// The pieces of [`write_pieces`] as one array, copied once into room whose pages
/// are huge from the first write when it is large (`crate::hugepages`), on all
/// threads: the first write of fresh pages is most of the copy's cost, and on one
/// thread it left the other idle for 0.2 s of a 12.6M-triangle scene's load.
fn join_pieces(pieces: Vec<Vec<Node>>) -> Vec<Node> {
    let starts: Vec<usize> = std::iter::once(0)
        .chain(pieces.iter().scan(0, |n, p| {
            *n += p.len();
            Some(*n)
        }))
        .collect();
    let total = starts[pieces.len()];
    let node = |i: usize| {
        let p = starts.partition_point(|&s| s <= i) - 1;
        pieces[p][i - starts[p]].shifted(starts[p] as u32)
    };
    let mut nodes = crate::hugepages::with_capacity(total);
    // An indexed iterator: rayon writes each run of it in place.
    nodes.par_extend((0..total).into_par_iter().map(node));
    nodes
}

/// Each kid with its own primitives: disjoint parts of `prims` (which start at `base`),
/// in the kids' order.
fn kid_slices<'a>(prims: &'a mut [PrimInfo], base: usize, kids: &[Decided]) -> Vec<(Decided, &'a mut [PrimInfo])> {
    let mut by_start: Vec<usize> = (0..kids.len()).collect();
    by_start.sort_by_key(|&k| kids[k].range().start);
    let mut slices: Vec<Option<&'a mut [PrimInfo]>> = (0..kids.len()).map(|_| None).collect();
    let (mut rest, mut at) = (prims, base);
    for k in by_start {
        let r = kids[k].range();
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(r.start - at);
        let (mine, tail) = tail.split_at_mut(r.len());
        (slices[k], rest, at) = (Some(mine), tail, r.end);
    }
    kids.iter().zip(slices).map(|(k, s)| (*k, s.unwrap_or_default())).collect()
}

/// Partitions by the cheapest of the bin boundaries; `None` when a leaf is cheaper.
/// `lo` and `hi` bound the doubled centroids on axis `AXIS`. Nodes over
/// `settings.sample_above` primitives bin a sample of them ([`SAMPLED_BINNING`]).
fn sah_split<const AXIS: usize>(
    prims: &mut [PrimInfo],
    bounds: &Bounds3,
    lo: f32,
    hi: f32,
    settings: &Settings,
) -> Option<Split> {
    let max_leaf = settings.max_leaf;
    let n = prims.len();
    // Through i32: the same bins (the value lies in 0..=BINS, or is NaN: 0), with a
    // shorter conversion than to a 64-bit unsigned. A multiplication by the bins per
    // unit, where a division per primitive was: a 1M-triangle build in 0.83 of the
    // time (3 pairs of medians of 5), the same SAH cost. A centroid on a bin's edge
    // may round into the next bin, so trees can differ from the division's there.
    let scale = BINS as f32 / (hi - lo);
    let bin_of = |c: Vec4| (((c[AXIS] - lo) * scale) as i32).min(BINS as i32 - 1) as usize;
    let sampled = n > settings.sample_above;
    let bins = match sampled {
        true => Bins::of_sample(prims, bin_of),
        false => Bins::of(prims, bin_of),
    };
    let area = |e: &Extent| e.bounds.bounds3().surface_area();
    // Sweep from the right for the right-hand areas, then from the left.
    let mut right_area = [0f32; BINS];
    let (mut acc, mut acc_cost) = (Extent::EMPTY, 0f32);
    let mut right_cost = [0f32; BINS];
    for i in (1..BINS).rev() {
        acc = acc.union(bins.extent[i]);
        acc_cost += bins.cost[i] as f32;
        right_area[i] = area(&acc);
        right_cost[i] = acc_cost;
    }
    let total = bounds.surface_area().max(f32::MIN_POSITIVE);
    let (mut best, mut best_cost) = (0, f32::INFINITY);
    let (mut left, mut left_cost) = (Extent::EMPTY, 0f32);
    for i in 0..BINS - 1 {
        left = left.union(bins.extent[i]);
        left_cost += bins.cost[i] as f32;
        let split = settings.traversal_cost + (left_cost * area(&left) + right_cost[i + 1] * right_area[i + 1]) / total;
        if split < best_cost {
            (best, best_cost) = (i, split);
        }
    }
    if n <= max_leaf && best_cost >= left_cost + bins.cost[BINS - 1] as f32 {
        return None;
    }
    let side = |bins: &[Extent]| bins.iter().fold(Extent::EMPTY, |a, &e| a.union(e));
    let (left, right) = (side(&bins.extent[..=best]), side(&bins.extent[best + 1..]));
    // `bin_of` never decreases as the centroid grows, so the bins up to `best` hold
    // exactly the centroids up to the largest among them: one comparison a primitive
    // where the bin took a division (the partition was a third of the build). A NaN
    // centroid (bin 0) would make that largest one NaN: then the bins decide.
    let last_left = left.centroids.hi[AXIS];
    let pred = |p: &PrimInfo| match last_left.is_nan() {
        false => p.centroid2()[AXIS] <= last_left || p.centroid2()[AXIS].is_nan(),
        true => bin_of(p.centroid2()) <= best,
    };
    if sampled {
        // The sample's extents are not the sides': the partition takes theirs.
        let mut sides = [Extent::EMPTY; 2];
        let mid = partition_with(prims, pred, |p, side| sides[side] = sides[side].with(p));
        if mid == 0 || mid == n {
            return Some(Split::at(n / 2));
        }
        return Some(Split { mid, extents: Some((sides[0], sides[1])) });
    }
    let mid = partition(prims, pred);
    if cfg!(test) {
        let (l, r) = prims.split_at(mid);
        assert!(l.iter().all(|p| bin_of(p.centroid2()) <= best) && r.iter().all(|p| bin_of(p.centroid2()) > best));
    }
    // A split that leaves one side empty (degenerate bins) falls back to halves.
    if mid == 0 || mid == n {
        return Some(Split::at(n / 2));
    }
    Some(Split { mid, extents: Some((left, right)) })
}

/// For a would-be leaf whose primitives are of several groups: the first one's group
/// to the left, the others to the right. `None` when they are all of one group.
fn split_groups(prims: &mut [PrimInfo], group: &dyn Fn(usize) -> u32) -> Option<usize> {
    let g = group(prims.first()?.index() as usize);
    if prims.iter().all(|p| group(p.index() as usize) == g) {
        return None;
    }
    Some(partition(prims, |p| group(p.index() as usize) == g))
}

/// Moves the primitives `pred` keeps to the front, in the order a swap per kept one
/// gives (the first kept one swapped with the first place, and so on). A block of
/// primitives is tested first, noting the places of the kept ones without a branch
/// (the predicate is a coin toss on the upper levels); then they are swapped into
/// place. Swapping as each was tested (with selects, the partition was two fifths
/// of the split decisions' samples) reloaded the place the last step had just
/// stored; this order took the load scene's wall time to 0.96 (7 pairs).
fn partition(prims: &mut [PrimInfo], pred: impl Fn(&PrimInfo) -> bool) -> usize {
    partition_with(prims, pred, |_, _| ())
}

/// [`partition`], calling `tested` with each primitive and its side (0 kept, 1 not)
/// before it moves.
#[inline(always)]
fn partition_with(
    prims: &mut [PrimInfo],
    pred: impl Fn(&PrimInfo) -> bool,
    mut tested: impl FnMut(&PrimInfo, usize),
) -> usize {
    const BLOCK: usize = 64;
    let mut kept = [0u8; BLOCK];
    let mut i = 0;
    for start in (0..prims.len()).step_by(BLOCK) {
        let end = (start + BLOCK).min(prims.len());
        let mut n = 0;
        for (at, p) in prims[start..end].iter().enumerate() {
            kept[n] = at as u8;
            let keep = pred(p);
            tested(p, !keep as usize);
            n += keep as usize;
        }
        // Places before `start` are settled: no swap below reaches a later block.
        for &at in &kept[..n] {
            prims.swap(i, start + at as usize);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Subtrees written in pieces on all threads, nested several levels deep, give
    /// the nodes of the one-thread writer in the same order. Fails if a piece's child
    /// references are counted from the wrong place.
    #[test]
    fn pieces_join_into_the_serial_nodes() {
        let mut rng = crate::sampling::Rng::new(11);
        let info: Vec<PrimInfo> = (0..20_000)
            .map(|i| {
                let c = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 100.0;
                PrimInfo::new(&Bounds3::new(c, c + Vec3::splat(rng.uniform())), 1.0, i)
            })
            .collect();
        let group = |_: usize| 0;
        let build = |parallel_collapse: usize| {
            let sample_above = SAMPLED_BINNING;
            build_with(
                info.clone(),
                &Settings {
                    max_leaf: MAX_LEAF,
                    group: &group,
                    parallel_collapse,
                    sample_above,
                    traversal_cost: TRAVERSAL_COST,
                },
            )
        };
        let (serial, serial_order) = build(usize::MAX);
        let (pieces, order) = build(64);
        assert!(serial.nodes.len() > 100 && serial.nodes == pieces.nodes && serial_order == order);
    }

    /// Large nodes choose their split from a sample of their primitives: the tree
    /// differs from binning them all, but is as good (SAH cost within 1%). Its boxes
    /// stay tight and its shape independent of the thread count: the test below builds
    /// past `SAMPLED_BINNING` too.
    #[test]
    fn sampled_bins_split_as_well_as_all_of_them() {
        let mut rng = crate::sampling::Rng::new(5);
        // Clusters of several sizes and densities, so that the upper splits matter.
        let info: Vec<PrimInfo> = (0..300_000u32)
            .map(|i| {
                let k = (i % 7) as f32;
                let centre = Vec3::new(k * 13.0, (k * k) % 5.0 * 9.0, 0.0);
                let spread = 1.0 + k * k;
                let c = centre + Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * spread;
                PrimInfo::new(&Bounds3::new(c, c + Vec3::splat(0.05 * rng.uniform())), 1.0, i)
            })
            .collect();
        let group = |_: usize| 0;
        let build = |sample_above: usize| {
            let settings = Settings {
                max_leaf: MAX_LEAF,
                group: &group,
                parallel_collapse: PARALLEL_COLLAPSE,
                sample_above,
                traversal_cost: TRAVERSAL_COST,
            };
            build_with(info.clone(), &settings).0
        };
        let (sampled, all) = (build(SAMPLED_BINNING), build(usize::MAX));
        assert!(sampled.nodes != all.nodes, "the sample must have decided some split");
        let (a, b) = (sampled.sah_cost(), all.sah_cost());
        assert!((a - b).abs() < 0.01 * b, "SAH cost {a} sampled against {b}");
    }

    /// The block partition gives the order of the plain one (a swap as each kept
    /// primitive is found), on lengths around the block's, with few, half and most
    /// primitives kept. Fails if a block's kept places are swapped out of order.
    #[test]
    fn block_partition_is_the_swap_per_kept_order() {
        fn reference(prims: &mut [PrimInfo], pred: impl Fn(&PrimInfo) -> bool) -> usize {
            let mut i = 0;
            for j in 0..prims.len() {
                if pred(&prims[j]) {
                    prims.swap(i, j);
                    i += 1;
                }
            }
            i
        }
        let mut rng = crate::sampling::Rng::new(7);
        for len in [0, 1, 2, 63, 64, 65, 127, 128, 129, 1000] {
            for keep in [0.05, 0.5, 0.95] {
                let prims: Vec<PrimInfo> = (0..len)
                    .map(|i| {
                        let x = rng.uniform();
                        PrimInfo::new(&Bounds3 { min: Vec3::splat(x), max: Vec3::splat(x) }, 1.0, i)
                    })
                    .collect();
                let pred = |p: &PrimInfo| p.lo.x < keep;
                let (mut a, mut b) = (prims.clone(), prims);
                assert_eq!(partition(&mut a, pred), reference(&mut b, pred));
                assert!(a.iter().zip(&b).all(|(p, q)| p.index() == q.index()), "len {len}, keep {keep}");
            }
        }
    }

    /// pbrt's box test for the ray (o, d): the entry t, clamped to 0, below `t`.
    fn box_entry(o: Vec3, d: Vec3) -> impl Fn(&Bounds3, f32) -> Option<f32> {
        let inv = Vec3::ONE / d;
        let neg = [(inv.x < 0.0) as usize, (inv.y < 0.0) as usize, (inv.z < 0.0) as usize];
        move |b, t| b.intersect_p(o, inv, neg, t).map(|t0| t0.max(0.0)).filter(|&t0| t0 < t)
    }

    /// The smallest entry t over all boxes, by brute force.
    fn closest_entry(boxes: &[Bounds3], entry: &impl Fn(&Bounds3, f32) -> Option<f32>) -> f32 {
        boxes.iter().filter_map(|b| entry(b, f32::INFINITY)).fold(f32::INFINITY, f32::min)
    }

    thread_local! {
        /// Set when a traversal stack spilled past its inline part on this thread.
        pub static SPILLED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
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
        let (bvh, order) = Bvh::build(boxes.clone(), |_| 1.0);
        let sorted: Vec<Bounds3> = order.iter().map(|&i| boxes[i as usize]).collect();
        for _ in 0..500 {
            let o = Vec3::new(rnd(), rnd(), rnd()) * 100.0;
            let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
            let (ray, entry) = (Ray::new(Point3(o), Vector3(d)), box_entry(o, d));
            let brute = closest_entry(&boxes, &entry);
            let got = bvh.intersect(&ray, f32::INFINITY, |i, t| entry(&sorted[i], t));
            assert_eq!(got.unwrap_or(f32::INFINITY), brute);
            if let Some(avx) = Avx::detect() {
                assert_eq!(closest_with(avx, &bvh, &ray, |i, t| entry(&sorted[i], t)), brute);
            }
        }
    }

    /// The closest hit through `intersect_leaves` with the given node test.
    fn closest_with(isa: impl Isa, bvh: &Bvh, ray: &Ray, hit: impl Fn(usize, f32) -> Option<f32>) -> f32 {
        let t = bvh.intersect_leaves(isa, ray, f32::INFINITY, |leaf, t_max| {
            leaf.prims().fold(None, |best: Option<f32>, i| hit(i, best.unwrap_or(t_max)).or(best))
        });
        t.unwrap_or(f32::INFINITY)
    }

    /// AVX and SSE node tests agree to the bit on boxes and rays that include pbrt's
    /// hard cases: rays along an axis (infinite inverses), origins on a slab's plane
    /// (NaN distances), flat and empty boxes, and t_max of 0 and ∞.
    #[test]
    fn the_avx_node_test_gives_the_sse_bits() {
        let Some(_avx) = Avx::detect() else { return };
        let mut state = 99u32;
        let mut rnd = || {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            state >> 8
        };
        // Values from a small set, so planes, flat boxes and axis rays are common.
        let mut pick = |set: &[f32]| set[rnd() as usize % set.len()];
        let coords = [-2.0, -1.0, -0.0, 0.0, 0.5, 1.0, 3.0, 1e30, f32::INFINITY, f32::NEG_INFINITY];
        let dirs = [-1.0, -0.25, -0.0, 0.0, 0.3, 1.0, 1e-30];
        let (mut hits, mut nan_lanes) = (0, 0);
        for _ in 0..20_000 {
            let kids: Vec<(Bounds3, u32, u8)> = (0..1 + pick(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]) as usize)
                .map(|s| {
                    let a = Vec3::new(pick(&coords), pick(&coords), pick(&coords));
                    let b = Vec3::new(pick(&coords), pick(&coords), pick(&coords));
                    (Bounds3 { min: a.min(b), max: a.max(b) }, s as u32, 1)
                })
                .collect();
            let node = Node::new(&kids);
            let o = Vec3::new(pick(&coords[..8]), pick(&coords[..8]), pick(&coords[..8]));
            let d = Vec3::new(pick(&dirs), pick(&dirs), pick(&dirs));
            let r = SlabRay::new(&Ray::new(Point3(o), Vector3(d)));
            let t_max = pick(&[0.0, 0.75, 2.0, f32::INFINITY]);
            let (sse, avx) = (r.entries::<Sse>(&node, t_max), r.entries::<Avx>(&node, t_max));
            assert_eq!(sse.1, avx.1);
            assert_eq!(sse.0.0.map(f32::to_bits), avx.0.0.map(f32::to_bits));
            let t = pick(&[0.0, 0.5, 1.0, f32::INFINITY]);
            assert_eq!(sse.0.at_most::<Sse>(t), avx.0.at_most::<Avx>(t));
            hits += sse.1.count_ones();
            nan_lanes += ((o - Vec3::from(node.bounds[0].map(|l| l.0[0]))) / d).is_nan() as u32;
        }
        assert!(hits > 10_000 && nan_lanes > 100, "the cases must include hits and NaN slabs ({hits}, {nan_lanes})");
    }

    /// The records of `boxes`, each costing `cost`, for [`Bvh::build_mixed`].
    fn records(boxes: &[Bounds3], cost: f32) -> Vec<PrimInfo> {
        boxes.iter().enumerate().map(|(i, b)| PrimInfo::new(b, cost, i as u32)).collect()
    }

    /// Four unit boxes a box apart: cheap primitives share one leaf, costly ones
    /// (quadrics) get a leaf each, so a ray through one box tests one primitive.
    #[test]
    fn costly_primitives_get_leaves_of_their_own() {
        let boxes: Vec<Bounds3> = (0..4)
            .map(|i| Bounds3::new(Vec3::new(2.0 * i as f32, 0.0, 0.0), Vec3::new(2.0 * i as f32 + 1.0, 1.0, 1.0)))
            .collect();
        let ray = Ray::new(Point3(Vec3::new(0.5, 0.5, -1.0)), Vector3(Vec3::Z));
        let tested = |cost: f32| {
            let (bvh, _) = Bvh::build(boxes.clone(), |_| cost);
            let mut n = 0;
            bvh.intersect_p(&ray, f32::INFINITY, |_, _| {
                n += 1;
                false
            });
            n
        };
        assert_eq!(tested(1.0), 4);
        assert_eq!(tested(8.0), 1);
    }

    /// A small mixed BVH weighs a node visit as pbrt does, so the six walls of a room
    /// (two triangles each, both with the wall's box) get leaves of their own: no
    /// leaf's box spans two walls. At the other trees' weight opposite walls share
    /// leaves, and every ray in the room tests them all.
    #[test]
    fn a_small_mixed_trees_walls_get_leaves_of_their_own() {
        let (lo, hi) = (Vec3::new(-2.0, 0.0, 0.0), Vec3::new(2.0, 2.5, 7.0));
        let wall = |axis: usize, at: Vec3| {
            let (mut a, mut b) = (lo, hi);
            (a[axis], b[axis]) = (at[axis], at[axis]);
            Bounds3::new(a, b)
        };
        let walls: Vec<Bounds3> = (0..3).flat_map(|axis| [wall(axis, lo), wall(axis, hi)]).collect();
        let triangles: Vec<Bounds3> = walls.iter().flat_map(|&w| [w, w]).collect();
        let flat_leaves = |(bvh, order): &(Bvh, Vec<u32>)| {
            bvh.leaves().all(|(first, count)| {
                let mut prims = order[first..first + count].iter().map(|&i| triangles[i as usize]);
                let b = prims.next().map(|p| prims.fold(p, Bounds3::union));
                b.is_some_and(|b| b.diagonal().min_element() == 0.0)
            })
        };
        assert!(flat_leaves(&Bvh::build_mixed(records(&triangles, 1.0))));
        assert!(!flat_leaves(&Bvh::build(triangles.clone(), |_| 1.0)));
    }

    /// A node of `WIDTH` leaves, slot s holding primitive s.
    fn leaf_node() -> Node {
        let kids: Vec<(Bounds3, u32, u8)> = (0..WIDTH as u32).map(|s| (Bounds3::default(), s, 1)).collect();
        Node::new(&kids)
    }

    fn pending(ts: [f32; WIDTH], slots: u32) -> Pending {
        Pending { ts: Lanes(ts), node: 0, slots }
    }

    #[test]
    fn the_stack_gives_children_nearest_first_and_skips_those_past_t_max() {
        let nodes = [leaf_node()];
        let mut stack = Stack::new();
        stack.push(pending([3.0, 9.0, 1.0, f32::INFINITY, f32::INFINITY, 2.0, 2.0, 5.0], 0b1110_0111));
        // Slots 1 and 7 start past t_max; 5 and 6 tie, the lower first.
        let mut order = Vec::new();
        while let Some((prim, count, _)) = stack.next::<Sse, true>(&nodes, 4.0) {
            assert_eq!(count, 1);
            order.push(prim);
        }
        assert_eq!(order, [2, 5, 6, 0]);
        assert!(stack.top().is_none(), "exhausted entries are dropped");
        // Any-hit queries take the slots in order.
        stack.push(pending([3.0, 9.0, 1.0, f32::INFINITY, f32::INFINITY, 2.0, 2.0, 5.0], 0b1110_0111));
        let unordered: Vec<u32> =
            std::iter::from_fn(|| stack.next::<Sse, false>(&nodes, 4.0).map(|(p, ..)| p)).collect();
        assert_eq!(unordered, [0, 2, 5, 6]);
        // Entries without slots are never pushed.
        stack.push(pending([0.0; WIDTH], 0));
        assert!(stack.next::<Sse, true>(&nodes, f32::INFINITY).is_none());
    }

    #[test]
    fn the_stack_is_last_in_first_out_past_its_inline_part() {
        let nodes = [leaf_node()];
        let mut stack = Stack::new();
        for i in 0..3 * STACK_INLINE {
            stack.push(pending([i as f32; WIDTH], 1 << (i % WIDTH)));
        }
        for i in (0..3 * STACK_INLINE).rev() {
            assert_eq!(stack.next::<Sse, true>(&nodes, f32::INFINITY), Some(((i % WIDTH) as u32, 1, 0)));
        }
        assert_eq!(stack.next::<Sse, true>(&nodes, f32::INFINITY), None);
    }

    #[test]
    fn nearest_is_the_smallest_entry_among_the_slots() {
        let mut state = 7u32;
        let mut rnd = || {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            state >> 8
        };
        for _ in 0..10_000 {
            // Few distinct values, so ties (broken by the lower slot) are common.
            let t0: [f32; WIDTH] = std::array::from_fn(|_| [0.0, 0.5, 1.0, f32::INFINITY][rnd() as usize % 4]);
            let slots = rnd() % (1 << WIDTH);
            if slots == 0 {
                continue;
            }
            let best = (0..WIDTH).filter(|s| slots >> s & 1 != 0).min_by(|&a, &b| t0[a].total_cmp(&t0[b])).unwrap();
            // Lanes outside the slots hold anything (a visited child's t): ignored.
            assert_eq!(Lanes(t0).nearest::<Sse>(slots), best);
            if let Some(_avx) = Avx::detect() {
                assert_eq!(Lanes(t0).nearest::<Avx>(slots), best);
            }
        }
    }

    /// Two overlapping boxes of cost 1: one leaf of both (a node visit, 4, and 2 in the
    /// root's box). Two far apart of cost 16: two leaves, each counted by its
    /// primitives (4 + a + b over the root's area). A small mixed tree weighs the
    /// visit 1.
    #[test]
    fn sah_cost_counts_node_visits_and_leaf_primitives() {
        let unit = |x: f32| Bounds3::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0));
        let (bvh, _) = Bvh::build(vec![unit(0.0), unit(0.5)], |_| 1.0);
        assert_eq!(bvh.sah_cost(), 6.0);
        let (bvh, _) = Bvh::build_mixed(records(&[unit(0.0), unit(0.5)], 1.0));
        assert_eq!(bvh.sah_cost(), 3.0);
        let (bvh, _) = Bvh::build(vec![unit(0.0), unit(99.0)], |_| 16.0);
        let root = unit(0.0).union(unit(99.0)).surface_area() as f64;
        let want = 4.0 + 2.0 * unit(0.0).surface_area() as f64 / root;
        assert!((bvh.sah_cost() - want).abs() < 1e-9, "{} against {want}", bvh.sah_cost());
        assert_eq!(Bvh::default().sah_cost(), 0.0);
    }

    /// Boxes at exponentially growing x make SAH peel a few off per level, so a ray
    /// along them needs more stack than the inline part holds.
    #[test]
    fn deep_trees_traverse_like_brute_force() {
        let boxes: Vec<Bounds3> = (0..460)
            .map(|i| {
                let x = 1.2f32.powi(i);
                Bounds3::new(Vec3::new(x, -0.5, -0.5), Vec3::new(1.01 * x, 0.5, 0.5))
            })
            .collect();
        let (bvh, order) = Bvh::build(boxes.clone(), |_| 1.0);
        let sorted: Vec<Bounds3> = order.iter().map(|&i| boxes[i as usize]).collect();
        for (o, d) in [(Vec3::new(-1.0, 0.1, 0.0), Vec3::X), (Vec3::new(1e38, 0.0, 0.2), -Vec3::X)] {
            let (ray, entry) = (Ray::new(Point3(o), Vector3(d)), box_entry(o, d));
            let brute = closest_entry(&boxes, &entry);
            let got = bvh.intersect(&ray, f32::INFINITY, |i, t| entry(&sorted[i], t));
            assert!(brute.is_finite());
            assert_eq!(got.unwrap_or(f32::INFINITY), brute);
            if let Some(avx) = Avx::detect() {
                assert_eq!(closest_with(avx, &bvh, &ray, |i, t| entry(&sorted[i], t)), brute);
            }
            // Every box is visited by an any-hit query that never stops.
            let mut seen = 0;
            bvh.intersect_p(&ray, f32::INFINITY, |i, t| {
                seen += entry(&sorted[i], t).is_some() as usize;
                false
            });
            assert_eq!(seen, boxes.len());
        }
        assert!(SPILLED.with(|s| s.get()), "the tree must be deep enough to spill the stack");
    }

    /// `relabel_leaves` sees every leaf once, the leaves cover the primitives once, and
    /// traversal then hands over the new reference and tag with the old count.
    #[test]
    fn relabeled_leaves_reach_traversal() {
        let boxes: Vec<Bounds3> = (0..300)
            .map(|i| {
                let c = Vec3::new((i % 7) as f32, (i / 7 % 6) as f32, (i / 42) as f32);
                Bounds3::new(c, c + Vec3::splat(0.9))
            })
            .collect();
        let (mut bvh, _) = Bvh::build_with_max_leaf(boxes.clone(), |_| 0.5, 16);
        let mut covered = vec![0; boxes.len()];
        let mut leaves = Vec::new();
        bvh.relabel_leaves(|first, count| {
            assert!((1..=16).contains(&count));
            covered[first..first + count].iter_mut().for_each(|c| *c += 1);
            leaves.push((first, count));
            (1_000_000 + first as u32, count as u8 + 100)
        });
        assert!(covered.iter().all(|&c| c == 1));
        assert!(leaves.iter().any(|&(_, count)| count > MAX_LEAF), "larger leaves than the default");
        let ray = Ray::new(Point3(Vec3::new(-1.0, 0.45, 0.45)), Vector3(Vec3::X));
        let mut seen = Vec::new();
        bvh.intersect_leaves_p(Sse, &ray, f32::INFINITY, |leaf, _| {
            assert_eq!(leaf.tag as usize, leaf.count + 100);
            seen.push((leaf.first - 1_000_000, leaf.count));
            false
        });
        assert!(!seen.is_empty() && seen.iter().all(|l| leaves.contains(l)));
    }

    /// Two groups' boxes interleaved in space (a cheap cost, large leaves allowed): every
    /// leaf holds one group's primitives, and they are still covered once; without
    /// groups the same boxes share leaves.
    #[test]
    fn grouped_leaves_hold_one_group() {
        let boxes: Vec<Bounds3> = (0..400)
            .map(|i| {
                let c = Vec3::new((i % 10) as f32 * 0.3, (i / 10 % 8) as f32 * 0.3, (i / 80) as f32 * 0.3);
                Bounds3::new(c, c + Vec3::splat(0.5))
            })
            .collect();
        let group = |i: usize| i.is_multiple_of(3) as u32;
        let leaves = |bvh: &mut Bvh, order: &[u32]| {
            let mut mixed = 0;
            let mut covered = vec![0; order.len()];
            bvh.relabel_leaves(|first, count| {
                let groups: Vec<u32> = order[first..first + count].iter().map(|&i| group(i as usize)).collect();
                mixed += groups.iter().any(|&g| g != groups[0]) as usize;
                covered[first..first + count].iter_mut().for_each(|c| *c += 1);
                (first as u32, 0)
            });
            assert!(covered.iter().all(|&c| c == 1));
            mixed
        };
        let (mut bvh, order) = Bvh::build_grouped(boxes.clone(), |_| 0.5, 16, group);
        assert_eq!(leaves(&mut bvh, &order), 0);
        let (mut bvh, order) = Bvh::build_with_max_leaf(boxes.clone(), |_| 0.5, 16);
        assert!(leaves(&mut bvh, &order) > 0, "the case must mix groups without them");
    }

    /// A build large enough to bin and collapse on all threads (`BIN_RUN`,
    /// `PARALLEL_COLLAPSE`) and to hand extents
    /// down from the bins: every child box is exactly the union of what lies under
    /// it, and the tree is the same on one thread as on several.
    #[test]
    fn large_builds_have_tight_boxes_on_any_thread_count() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let boxes: Vec<Bounds3> = (0..PARALLEL_COLLAPSE + 3 * BIN_RUN)
            .map(|_| {
                let c = Vec3::new(next(), next(), next()) * 100.0;
                Bounds3::new(c, c + Vec3::new(next(), next(), next()))
            })
            .collect();
        // Costs of several sizes, as quadrics and triangles mix.
        let cost = |i: usize| 1.0 + (i % 7) as f32 * 0.1;
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
            pool.install(|| Bvh::build(boxes.clone(), cost))
        };
        let (bvh, order) = on(2);
        let (one, one_order) = on(1);
        assert!(bvh.nodes == one.nodes && order == one_order, "the tree must not depend on the thread count");
        let sorted: Vec<Bounds3> = order.iter().map(|&i| boxes[i as usize]).collect();
        // The union of what lies under a node's slot, checked against the slot's box.
        fn under(bvh: &Bvh, sorted: &[Bounds3], node: usize, slot: usize) -> Bounds3 {
            let n = &bvh.nodes[node];
            let (child, count, _) = n.slot(slot);
            let below = match count {
                0 => (0..WIDTH)
                    .filter(|&k| bvh.nodes[child as usize].valid & 1 << k != 0)
                    .fold(Bounds3::default(), |b, k| b.union(under(bvh, sorted, child as usize, k))),
                c => sorted[child as usize..child as usize + c as usize]
                    .iter()
                    .fold(Bounds3::default(), |b, &x| b.union(x)),
            };
            let stored = Bounds3::new(
                Vec3::from_array(std::array::from_fn(|a| n.bounds[0][a].0[slot])),
                Vec3::from_array(std::array::from_fn(|a| n.bounds[1][a].0[slot])),
            );
            assert_eq!(stored, below, "node {node} slot {slot}");
            below
        }
        let all = (0..WIDTH)
            .filter(|&k| bvh.nodes[0].valid & 1 << k != 0)
            .fold(Bounds3::default(), |b, k| b.union(under(&bvh, &sorted, 0, k)));
        assert_eq!(all, boxes.iter().fold(Bounds3::default(), |b, &x| b.union(x)));
        assert_eq!(bvh.bounds(), all);
    }
}
