//! The render-ready geometry of a scene: its [`ShapeSet`], one BVH over the world
//! shapes, one per instanced object, and a top-level BVH over instances. Instances
//! share their object's BVH and geometry; only a transform is stored per instance.

pub mod bvh;
mod leaves;

pub use bvh::{Avx, Bvh, Isa, Leaf, Sse};
use leaves::{LeafBlocks, LeafTriangles};

use crate::interaction::SurfaceInteraction;
use crate::math::float::gamma;
use crate::math::{Bounds3, Point3, Ray, Vector3};
use crate::scene::{Geometry as ShapeGeometry, SceneDescription, ShapeDesc};
use crate::shapes::curve::CurveShape;
pub use crate::shapes::{LocalHit, ShapeRef};
use crate::shapes::{
    MeshFlags, QuadricShape, ShapeSet, TriangleHit, TriangleMesh, WatertightRay, edge_candidates, watertight,
};
use glam::{DAffine3, DMat4, Vec3};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

/// Whether a [`Geometry`] keeps the map from its meshes' stored triangles back to
/// the file's numbers.
#[derive(Clone, Copy, PartialEq)]
enum TriangleIds {
    Kept,
    Dropped,
}

/// An instance's, for the top-level SAH: a ray transform and a whole traversal.
const INSTANCE_COST: f32 = 16.0;
/// A triangle's in a leaf block, relative to a node visit: its leaf's memory is one
/// trip, so larger leaves pay (and their blocks share more vertices).
const BLOCK_TRIANGLE_COST: f32 = 0.5;

/// A shape with at least this many primitives has their boxes made on all threads.
const PARALLEL_PRIMS: usize = 1 << 14;

/// A BVH leaf entry: a shape, and its primitive (triangle, patch) (8 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Prim {
    shape: u32,
    tri: u32,
}

/// The shapes of one object (or of the world) and their BVH.
#[derive(Default)]
struct Blas {
    bvh: Bvh,
    /// Leaf entries in BVH order; empty when the BVH holds meshes alone, whose
    /// triangles are then stored in BVH order and copied into `blocks`.
    prims: Vec<Prim>,
    shapes: Vec<ShapeRef>,
    /// Per shape, its mesh, when every shape is a mesh and together they are small
    /// enough for leaf blocks (else empty); `localize` builds the blocks once it has
    /// put the meshes in BVH order.
    block_meshes: Vec<(u32, MeshFlags)>,
    /// The meshes' leaf blocks, which the BVH's leaves then refer to.
    blocks: LeafBlocks,
}

/// A placed object, as rays need it (104 bytes: a million instances are common).
#[derive(Clone, Debug)]
pub struct Instance {
    /// Instance-from-render as a 3 x 4 matrix: mapping rays uses only the top three
    /// rows of the 4 x 4 one (the same operations, so the same bits).
    instance_from_render: DAffine3,
    object: u32,
    /// The instance's position among the scene's `ObjectInstance`s, where its
    /// render-from-instance map, its motion and its first shape's number are (they
    /// are not needed per ray); [`MOVING`] set when its transform is animated (then
    /// the map above is its start).
    placement: u32,
}

/// The bit of [`Instance::placement`] that marks a moving instance: positions are
/// below it ([`crate::scene::instances::MAX_INSTANCES`]).
const MOVING: u32 = 1 << 31;
const _: () = assert!(crate::scene::instances::MAX_INSTANCES <= MOVING as usize);
const _: () = assert!(std::mem::size_of::<Instance>() == 104);

impl Instance {
    fn moving(&self) -> bool {
        self.placement & MOVING != 0
    }

    /// Its position among the scene's instances, in file order.
    fn index(&self) -> usize {
        (self.placement & !MOVING) as usize
    }
}

impl Geometry {
    /// Instance-from-render of instance `inst` at `time`.
    /// (Per ray and instance: the scene's record is read only for a moving one.)
    fn instance_from_render_at<'a>(&self, inst: &'a Instance, time: f32) -> std::borrow::Cow<'a, DAffine3> {
        let motion = if inst.moving() { self.placement(inst).motion() } else { None };
        match motion {
            None => std::borrow::Cow::Borrowed(&inst.instance_from_render),
            Some(m) => std::borrow::Cow::Owned(DAffine3::from_mat4(m.at(time as f64).inverse())),
        }
    }

    /// Render-from-instance of instance `inst` at `time`.
    fn render_from_instance_at(&self, inst: &Instance, time: f32) -> DAffine3 {
        let placement = self.placement(inst);
        match placement.motion() {
            None => placement.world_from_instance_affine(),
            Some(m) => DAffine3::from_mat4(m.at(time as f64)),
        }
    }

    /// The scene's record of an instance.
    fn placement(&self, inst: &Instance) -> crate::scene::Placed<'_> {
        self.placements.get(inst.index())
    }

    /// The `check --shapes` index of the first shape of instance `inst`'s object.
    fn first_shape_index(&self, inst: &Instance) -> u32 {
        self.first_shapes[inst.index()]
    }
}

/// The closest hit of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// In units of the ray's direction.
    pub t: f32,
    pub local: LocalHit,
    /// The shape's index in `check --shapes` order.
    pub shape_index: u32,
    /// Index into [`Geometry::instances`].
    pub instance: Option<u32>,
    /// The ray's time (where a moving instance was when hit).
    pub time: f32,
}

/// Everything rays can hit.
pub struct Geometry {
    pub shapes: ShapeSet,
    /// In the instances' BVH order.
    pub instances: Vec<Instance>,
    /// The scene's instances (shared, not copied), in file order.
    placements: Arc<crate::scene::Instances>,
    /// Per instance, in file order: the `check --shapes` index of its object's first
    /// shape (shapes are numbered world shapes first, then instance by instance).
    first_shapes: Vec<u32>,
    world: Blas,
    objects: Vec<Blas>,
    tlas: Bvh,
    /// Per mesh: the file's triangle number of each stored triangle (meshes are
    /// reordered to follow their BVH).
    triangle_ids: Vec<Vec<u32>>,
    /// Set where the processor has AVX2: BVH traversal then uses it.
    avx: Option<Avx>,
}

/// How the shapes of one scene are set up: its syntax, and whether meshes may leave
/// out the normal derivatives that only bump maps read.
#[derive(Clone, Copy)]
struct ShapeSetup {
    v4: bool,
    skip_normal_derivatives: bool,
}

fn shape_ref(
    s: &ShapeDesc,
    quadrics: &mut Vec<QuadricShape>,
    curves: &mut Vec<CurveShape>,
    setup: ShapeSetup,
) -> ShapeRef {
    let ShapeSetup { v4, skip_normal_derivatives } = setup;
    let flags = MeshFlags {
        reverse_orientation: s.reverse_orientation,
        swaps_handedness: s.swaps_handedness(),
        skip_normal_derivatives,
    };
    match &s.geometry {
        ShapeGeometry::Quadric(q) => {
            quadrics.push(QuadricShape::new(q.clone(), s.object_to_world, s.reverse_orientation));
            ShapeRef::Quadric(quadrics.len() as u32 - 1)
        }
        ShapeGeometry::Mesh { mesh, .. } => ShapeRef::Mesh { mesh: *mesh, flags },
        ShapeGeometry::Patches { mesh, .. } => ShapeRef::Patches { mesh: *mesh, flags },
        ShapeGeometry::Curves { curves: c, .. } => {
            let curve = CurveShape::new(c.clone(), s.object_to_world, s.reverse_orientation);
            curves.push(CurveShape { error_widths: if v4 { 1.0 } else { 2.0 }, ..curve });
            ShapeRef::Curves(curves.len() as u32 - 1)
        }
    }
}

/// The body of [`Blas::intersect`] for an [`Isa`]. A macro, not a function: a closure
/// is compiled with the target features of the function it is written in, so the leaf
/// test must be written inside the AVX function to be compiled for AVX.
macro_rules! closest_hit {
    ($blas:expr, $isa:expr, $g:expr, $ray:expr, $t_max:expr) => {{
        let wr = WatertightRay::new($ray);
        let mut best = None;
        $blas.bvh.intersect_leaves($isa, $ray, $t_max, |leaf, t_max| {
            let hit = $blas.hit_leaf::<_, false>($isa, $g, leaf, $ray, &wr, t_max)?;
            best = Some(hit);
            Some(hit.0)
        });
        best
    }};
}

/// The body of [`Blas::intersect_p`], as [`closest_hit`] is of `intersect`.
macro_rules! any_hit {
    ($blas:expr, $isa:expr, $g:expr, $ray:expr, $t_max:expr) => {{
        let wr = WatertightRay::new($ray);
        $blas.bvh.intersect_leaves_p($isa, $ray, $t_max, |leaf, t_max| {
            $blas.hit_leaf::<_, true>($isa, $g, leaf, $ray, &wr, t_max).is_some()
        })
    }};
}

/// A query method that runs `$body` with AVX2 where the [`Geometry`] holds an [`Avx`],
/// in a second method compiled for it (traversal and leaf tests alike), and with SSE
/// otherwise. The features enabled are those `Avx::detect` checks for.
macro_rules! with_isa {
    ($(#[$doc:meta])* fn $name:ident, $avx_name:ident -> $ret:ty = $body:ident) => {
        $(#[$doc])*
        fn $name(&self, g: &Geometry, ray: &Ray, t_max: f32) -> $ret {
            match g.avx {
                // SAFETY: holding an `Avx` proves the processor has what the AVX
                // method enables.
                #[cfg(target_arch = "x86_64")]
                Some(avx) => unsafe { self.$avx_name(avx, g, ray, t_max) },
                _ => $body!(self, Sse, g, ray, t_max),
            }
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
        fn $avx_name(&self, avx: Avx, g: &Geometry, ray: &Ray, t_max: f32) -> $ret {
            $body!(self, avx, g, ray, t_max)
        }
    };
}

/// The primitives of `shapes` (numbered as in that list), in order, but zero-area
/// ones, which are left out: `localize` then drops such triangles from their mesh, and
/// the map back to file numbers skips them. On all threads, in runs of
/// `PARALLEL_PRIMS` over shapes large and small alike: [`PrimRuns::count`] counts each
/// run's primitives, [`PrimRuns::fill`] writes them and their build records in their
/// final places (temporary lists cost as much again in page faults).
struct PrimRuns<'a> {
    shapes: &'a [ShapeRef],
    set: &'a ShapeSet,
    /// Where each shape's primitives start among all of them, zero-area ones included.
    starts: Vec<usize>,
    /// Per run, the primitives it keeps.
    counts: Vec<usize>,
    /// Per run, the shape of its first primitive; then the last primitive's.
    run_shapes: Vec<usize>,
}

impl<'a> PrimRuns<'a> {
    fn count(shapes: &'a [ShapeRef], set: &'a ShapeSet) -> PrimRuns<'a> {
        let starts: Vec<usize> = std::iter::once(0)
            .chain(shapes.iter().scan(0, |n, &s| {
                *n += set.prim_count(s);
                Some(*n)
            }))
            .collect();
        let all = starts[shapes.len()];
        // The shape holding each run's first primitive (starts[0] is 0: never empty).
        let shape_of = |g: usize| starts.partition_point(|&s| s <= g) - 1;
        let last = all.saturating_sub(1);
        let run_shapes = (0..=all.div_ceil(PARALLEL_PRIMS)).map(|r| shape_of((r * PARALLEL_PRIMS).min(last))).collect();
        let mut runs = PrimRuns { shapes, set, starts, counts: Vec::new(), run_shapes };
        let counts = (0..all.div_ceil(PARALLEL_PRIMS)).into_par_iter().map(|r| {
            let mut n = 0;
            runs.visit(r, &mut |_, _, _| n += 1);
            n
        });
        runs.counts = counts.collect();
        runs
    }

    /// How many primitives the shapes have, zero-area ones included.
    fn all(&self) -> usize {
        self.starts[self.shapes.len()]
    }

    /// How many are kept.
    fn kept(&self) -> usize {
        self.counts.iter().sum()
    }

    /// Calls `kept` with each primitive of run `r` that has a box, in order: its
    /// shape, its number among all the shapes' primitives, and its box.
    fn visit(&self, r: usize, kept: &mut dyn FnMut(usize, usize, Bounds3)) {
        let run = r * PARALLEL_PRIMS..self.all().min((r + 1) * PARALLEL_PRIMS);
        let mut shape = self.run_shapes[r];
        for g in run {
            while self.starts[shape + 1] <= g {
                shape += 1;
            }
            if let Some(b) = self.set.prim_bounds(self.shapes[shape], g - self.starts[shape]) {
                kept(shape, g, b);
            }
        }
    }

    /// Primitive `g` of all the shapes' (zero-area ones counted), found by a binary
    /// search among the shapes of its run only: the build looks up every kept
    /// primitive's shape, and the leaf order its triangle.
    fn prim(&self, g: usize) -> Prim {
        let r = g / PARALLEL_PRIMS;
        let (first, last) = (self.run_shapes[r], self.run_shapes[r + 1]);
        let shape = first + self.starts[first + 1..=last].partition_point(|&s| s <= g);
        Prim { shape: shape as u32, tri: (g - self.starts[shape]) as u32 }
    }

    /// The kept primitives' build records, each costing `cost(its shape)` and holding
    /// the primitive's number among all ([`PrimRuns::prim`] tells which it is),
    /// written straight from their boxes in their final places. A list of boxes to
    /// convert cost 24 bytes a primitive of fresh pages more, and a list of the
    /// primitives beside the records 8 more (100 MB at the load benchmark's peak).
    /// The records are in huge pages: the build reads them over and over, and once
    /// freed, their 2 MiB pages serve the leaf blocks' huge pages without new faults
    /// (the load benchmark's 202 MB of blocks written in 82 ms, not 205; the whole
    /// load in 0.92 of the time).
    fn fill(&self, cost: impl Fn(&ShapeRef) -> f32 + Sync) -> Vec<bvh::PrimInfo> {
        let total = self.kept();
        // Each run written straight into its part of fresh room, on all threads (the
        // first touch of fresh pages is most of the cost): no pass of zeros before it.
        let mut records = crate::hugepages::with_capacity(total);
        let mut rest = &mut records.spare_capacity_mut()[..total];
        let mut slots = Vec::with_capacity(self.counts.len());
        for &n in &self.counts {
            let run;
            (run, rest) = std::mem::take(&mut rest).split_at_mut(n);
            slots.push(run);
        }
        slots.into_par_iter().enumerate().for_each(|(r, run)| {
            let mut i = 0;
            self.visit(r, &mut |shape, g, b| {
                run[i].write(bvh::PrimInfo::new(&b, cost(&self.shapes[shape]), g as u32));
                i += 1;
            });
            // `count` visited the same primitives.
            assert_eq!(i, run.len(), "a run's primitives, counted twice");
        });
        // SAFETY: every run wrote each of its slots (checked above), and the runs
        // cover the first `total` places.
        unsafe { records.set_len(total) };
        records
    }
}

impl Blas {
    fn build(shapes: Vec<ShapeRef>, set: &ShapeSet) -> Blas {
        let runs = PrimRuns::count(&shapes, set);
        let mut block_meshes: Vec<(u32, MeshFlags)> = shapes
            .iter()
            .map_while(|s| match s {
                ShapeRef::Mesh { mesh, flags } => Some((*mesh, *flags)),
                _ => None,
            })
            .collect();
        if block_meshes.len() < shapes.len() || !LeafBlocks::fit(runs.kept()) {
            block_meshes.clear();
        }
        // Leaves of one mesh each, so that a block names one mesh.
        let (bvh, order) = match block_meshes.is_empty() {
            false => {
                let records = runs.fill(|_| BLOCK_TRIANGLE_COST);
                Bvh::build_records(records, leaves::MAX_LEAF, |g| runs.prim(g).shape)
            }
            true => Bvh::build_mixed(runs.fill(|&s| ShapeSet::prim_cost(s))),
        };
        let prims = order.par_iter().map(|&g| runs.prim(g as usize)).collect();
        Blas { bvh, prims, shapes, block_meshes, blocks: LeafBlocks::default() }
    }

    /// Reorders each mesh's triangles into this BVH's leaf order; records the file's
    /// numbers in `ids` and points the primitives at the new positions. A BVH over a
    /// BVH over meshes alone then needs no primitive list: its leaves refer to leaf
    /// blocks.
    fn localize(&mut self, meshes: &mut [Arc<TriangleMesh>], ids: &mut [Vec<u32>]) {
        // Each mesh shape's triangles in leaf order, in one pass over the primitives (a
        // pass per shape was 2.7 s of a 192-mesh scene's 12.6M triangles).
        let mut orders: Vec<Vec<u32>> = vec![Vec::new(); self.shapes.len()];
        for p in &mut self.prims {
            if let ShapeRef::Mesh { .. } = self.shapes[p.shape as usize] {
                let order = &mut orders[p.shape as usize];
                let next = order.len() as u32;
                order.push(p.tri);
                p.tri = next;
            }
        }
        let jobs = orders.into_iter().enumerate().filter_map(|(shape, order)| match self.shapes[shape] {
            ShapeRef::Mesh { mesh, .. } => Some((mesh as usize, order)),
            _ => None,
        });
        // Each copy takes its original's place at once, which frees the original
        // unless the scene still holds it.
        (mesh_slots(meshes, ids, jobs.collect()).into_par_iter()).for_each(|(mesh, id, order)| {
            *mesh = Arc::new(mesh.reordered(&order));
            *id = order;
        });
        if !self.block_meshes.is_empty() {
            let (prims, block_meshes) = (&self.prims, &self.block_meshes);
            // A leaf's triangles are one mesh's (`build_grouped`), numbered one after
            // another from its first's new number.
            let leaves: Vec<LeafTriangles> = (self.bvh.leaves())
                .map(|(first, count)| {
                    let Prim { shape, tri } = prims[first];
                    let mesh = &*meshes[block_meshes[shape as usize].0 as usize];
                    LeafTriangles { mesh, shape, first: tri as usize, count }
                })
                .collect();
            // Gone before the blocks are made: 8 bytes a triangle off the load's peak.
            self.prims = Vec::new();
            let (mut blocks, refs) = LeafBlocks::of_leaves(&leaves);
            let mut refs = refs.into_iter();
            self.bvh.relabel_leaves(|_, _| refs.next().expect("a block for every leaf"));
            blocks.shrink_to_fit();
            self.blocks = blocks;
        }
    }

    with_isa! {
        /// Closest hit: (t, local shape index, what was hit).
        fn intersect, intersect_avx -> Option<(f32, u32, LocalHit)> = closest_hit
    }

    with_isa! {
        /// Whether anything is hit before `t_max`.
        fn intersect_p, intersect_p_avx -> bool = any_hit
    }

    /// The triangle test's axis permutation as const generics: chosen once per leaf,
    /// where it is predictable, and never for rays that reach no leaf.
    #[inline(always)]
    fn hit_leaf<I: Isa, const ANY: bool>(
        &self,
        isa: I,
        g: &Geometry,
        leaf: Leaf,
        ray: &Ray,
        wr: &WatertightRay,
        t_max: f32,
    ) -> Option<(f32, u32, LocalHit)> {
        match wr.kz() {
            0 => self.hit_leaf_permuted::<I, 1, 2, 0, ANY>(isa, g, leaf, ray, wr, t_max),
            1 => self.hit_leaf_permuted::<I, 2, 0, 1, ANY>(isa, g, leaf, ray, wr, t_max),
            _ => self.hit_leaf_permuted::<I, 0, 1, 2, ANY>(isa, g, leaf, ray, wr, t_max),
        }
    }

    /// The closest hit below `t_max` among a leaf's primitives (`ANY`: the first).
    #[inline(always)]
    fn hit_leaf_permuted<I: Isa, const KX: usize, const KY: usize, const KZ: usize, const ANY: bool>(
        &self,
        isa: I,
        g: &Geometry,
        leaf: Leaf,
        ray: &Ray,
        wr: &WatertightRay,
        mut t_max: f32,
    ) -> Option<(f32, u32, LocalHit)> {
        if self.block_meshes.is_empty() {
            return self.hit_mixed_leaf::<KX, KY, KZ, ANY>(g, leaf.prims(), ray, wr, t_max);
        }
        // The block's lines are all requested before the first test waits on its
        // first, so the leaf costs one cache miss's latency, not one per line.
        self.blocks.prefetch(leaf);
        let block = self.blocks.block(leaf)?;
        let shape = block.shape();
        let &(mesh, flags) = self.block_meshes.get(shape as usize)?;
        let mut best = None;
        let groups = block.count().div_ceil(4);
        let mut at = 0;
        while at < groups {
            let (candidates, step) = block.edge_candidates::<I, KX, KY, KZ>(isa, at, wr);
            let triangle = |k| (block.corners(4 * at + k), block.triangle(4 * at + k));
            if let Some((tri, hit)) = hit_candidates::<KX, KY, KZ, ANY>(candidates, triangle, wr, &mut t_max) {
                if ANY {
                    return Some((hit.t, shape, LocalHit::Triangle { mesh, tri, flags, hit }));
                }
                g.shapes.meshes[mesh as usize].prefetch_indices(tri as usize);
                best = Some((hit.t, shape, LocalHit::Triangle { mesh, tri, flags, hit }));
            }
            at += step;
        }
        best
    }

    /// [`Self::hit_leaf_permuted`] for a BVH over several shapes.
    #[inline(always)]
    fn hit_mixed_leaf<const KX: usize, const KY: usize, const KZ: usize, const ANY: bool>(
        &self,
        g: &Geometry,
        leaf: Range<usize>,
        ray: &Ray,
        wr: &WatertightRay,
        mut t_max: f32,
    ) -> Option<(f32, u32, LocalHit)> {
        let mut best = None;
        let mut i = leaf.start;
        while i < leaf.end {
            let prim = self.prims[i];
            // A mesh's triangles that follow each other in the leaf are stored next to
            // each other (`localize`), so up to four go through `hit_four` together.
            let run = self.prims[i..leaf.end]
                .iter()
                .take(4)
                .enumerate()
                .take_while(|(k, p)| p.shape == prim.shape && p.tri == prim.tri.wrapping_add(*k as u32))
                .count();
            let (found, step) = match (self.shapes[prim.shape as usize], run) {
                (ShapeRef::Mesh { mesh, flags }, 2..) => {
                    let m = &g.shapes.meshes[mesh as usize];
                    let first = prim.tri as usize;
                    let triangle = |k| (m.corners(first + k), (first + k) as u32);
                    let candidates = edge_candidates::<KX, KY, KZ>(&m.corner_lanes(first), wr) & ((1 << run) - 1);
                    let hit = hit_candidates::<KX, KY, KZ, ANY>(candidates, triangle, wr, &mut t_max);
                    (hit.map(|(tri, hit)| (hit.t, LocalHit::Triangle { mesh, tri, flags, hit })), run)
                }
                (s, _) => (g.shapes.intersect::<KX, KY, KZ>(s, prim.tri, ray, wr, t_max), 1),
            };
            i += step;
            if let Some((t, local)) = found {
                t_max = t;
                best = Some((t, prim.shape, local));
                if ANY {
                    break;
                }
            }
        }
        best
    }
}

/// The closest hit below `t_max` (`ANY`: the first) among the triangles the edge
/// filter kept (bit k of `candidates`): the full test on the corners and triangle
/// number `triangle(k)` gives. Lowers `t_max` to each hit found.
#[inline(always)]
fn hit_candidates<const KX: usize, const KY: usize, const KZ: usize, const ANY: bool>(
    mut candidates: u32,
    triangle: impl Fn(usize) -> ([Vec3; 3], u32),
    wr: &WatertightRay,
    t_max: &mut f32,
) -> Option<(u32, TriangleHit)> {
    let mut best = None;
    while candidates != 0 {
        let k = candidates.trailing_zeros() as usize;
        candidates &= candidates - 1;
        let (corners, tri) = triangle(k);
        if let Some(hit) = watertight::<KX, KY, KZ>(corners, wr, *t_max) {
            *t_max = hit.t;
            best = Some((tri, hit));
            if ANY {
                break;
            }
        }
    }
    best
}

/// A mesh and its triangle numbers, to replace, with the order to copy it in.
type MeshSlot<'a> = (&'a mut Arc<TriangleMesh>, &'a mut Vec<u32>, Vec<u32>);

/// Each job's mesh and triangle numbers, to replace, with its order: the slots of
/// `meshes` and `ids` that the jobs name (by mesh index), taken apart so that they
/// can be filled on all threads. Where two jobs name one mesh, the later one's.
fn mesh_slots<'a>(
    meshes: &'a mut [Arc<TriangleMesh>],
    ids: &'a mut [Vec<u32>],
    mut jobs: Vec<(usize, Vec<u32>)>,
) -> Vec<MeshSlot<'a>> {
    // Reversed, then sorted stably and deduplicated: the later of two jobs stays.
    jobs.reverse();
    jobs.sort_by_key(|j| j.0);
    jobs.dedup_by_key(|j| j.0);
    let (mut m_rest, mut i_rest, mut at) = (meshes, ids, 0);
    let mut slots = Vec::with_capacity(jobs.len());
    for (mesh, order) in jobs {
        let (m, i);
        (m, m_rest) = std::mem::take(&mut m_rest)[mesh - at..].split_first_mut().expect("a mesh of the scene");
        (i, i_rest) = std::mem::take(&mut i_rest)[mesh - at..].split_first_mut().expect("a mesh of the scene");
        at = mesh + 1;
        slots.push((m, i, order));
    }
    slots
}

/// See [`crate::hugepages`]. Folding mesh pages into huge ones copies them: on all
/// threads. Nodes and blocks were written to huge pages already; folding them again
/// costs nothing then, and catches those the kernel could not give at the first write.
fn advise_huge_pages<'a>(meshes: &[Arc<TriangleMesh>], blases: impl Iterator<Item = &'a Blas>) {
    meshes.par_iter().for_each(|m| {
        crate::hugepages::advise(&m.p);
        crate::hugepages::advise(&m.indices);
    });
    for blas in blases {
        rayon::join(|| blas.bvh.advise_huge_pages(), || blas.blocks.advise_huge_pages());
    }
}

/// A render-space ray in instance space: mapped in f64, rounded once to f32, and its
/// origin moved forward by that rounding (pbrt's rule). Returns the ray and the shift
/// `dt` (instance t + dt = render t).
fn instance_ray(instance_from_render: &DAffine3, r: &Ray) -> (Ray, f32) {
    let o = instance_from_render.transform_point3(r.o.0.as_dvec3());
    let d = (instance_from_render.matrix3 * r.d.0.as_dvec3()).as_vec3();
    let o32 = o.as_vec3();
    let o_err = gamma(2) * o32.abs() + (o - o32.as_dvec3()).abs().as_vec3();
    let len2 = d.length_squared();
    let dt = if len2 > 0.0 { d.abs().dot(o_err) / len2 } else { 0.0 };
    (Ray { o: Point3(o32 + d * dt), d: Vector3(d), t_max: r.t_max - dt, time: r.time }, dt)
}

/// Render-space bounds of an object's bounds under an instance map, widened a little.
fn instance_bounds(m: &DMat4, b: Bounds3) -> Bounds3 {
    if b.is_empty() {
        return b;
    }
    crate::math::bounds::transform_bounds_widened(m, [b.min.as_dvec3(), b.max.as_dvec3()])
}

impl Geometry {
    /// Builds the acceleration structures over the scene's shapes (sharing its meshes
    /// until the BVHs reorder their triangles into copies of their own).
    pub fn new(scene: &SceneDescription) -> Geometry {
        Geometry::build(scene, scene.meshes.clone(), TriangleIds::Kept)
    }

    /// As [`Geometry::new`], for rendering: with `meshes` in place of the scene's own,
    /// which it may no longer hold (everything else comes from `scene`). A mesh no one
    /// else holds is freed as soon as its reordered copy is made: the load's peak then
    /// holds one of the two, and the copies reuse the freed pages. The map back to the
    /// file's triangle numbers, which only `trace` reports, is not kept (4 bytes a
    /// triangle).
    pub fn with_meshes(scene: &SceneDescription, meshes: Vec<Arc<TriangleMesh>>) -> Geometry {
        Geometry::build(scene, meshes, TriangleIds::Dropped)
    }

    /// The BVHs over `scene`'s shapes and `meshes`, with or without the triangle map.
    fn build(scene: &SceneDescription, meshes: Vec<Arc<TriangleMesh>>, keep: TriangleIds) -> Geometry {
        let mut set = ShapeSet { meshes, patches: scene.patches.clone(), ..Default::default() };
        let setup = ShapeSetup {
            v4: scene.syntax == crate::parser::Syntax::V4,
            skip_normal_derivatives: !scene.materials.iter().any(|m| m.bump.is_some()),
        };
        let mut refs = |s: &ShapeDesc| shape_ref(s, &mut set.quadrics, &mut set.curves, setup);
        let world_shapes: Vec<ShapeRef> = scene.shapes.iter().map(&mut refs).collect();
        let object_shapes: Vec<Vec<ShapeRef>> =
            scene.objects.iter().map(|o| o.shapes.iter().map(&mut refs).collect()).collect();
        let pbrt_dndu = !scene.fixes.has(crate::fixes::Fix::NormalDerivatives);
        let pbrt_hyperboloid = !scene.fixes.has(crate::fixes::Fix::HyperboloidSurface);
        for q in &mut set.quadrics {
            q.pbrt_normal_derivatives = pbrt_dndu;
            q.skip_normal_derivatives = setup.skip_normal_derivatives;
            if let crate::shapes::Quadric::Hyperboloid(h) = &mut q.quadric {
                h.implicit_fit = pbrt_hyperboloid;
            }
        }
        let mut world = Blas::build(world_shapes, &set);
        let mut objects: Vec<Blas> = object_shapes.into_par_iter().map(|shapes| Blas::build(shapes, &set)).collect();
        let mut triangle_ids = vec![Vec::new(); set.meshes.len()];
        for blas in std::iter::once(&mut world).chain(objects.iter_mut()) {
            blas.localize(&mut set.meshes, &mut triangle_ids);
        }
        if keep == TriangleIds::Dropped {
            triangle_ids = Vec::new();
        }
        advise_huge_pages(&set.meshes, std::iter::once(&world).chain(objects.iter()));
        // Each instance's shapes are numbered after the world's and the instances' before.
        let first_shapes: Vec<u32> = (scene.instances.iter())
            .scan(scene.shapes.len() as u32, |next, i| {
                let first = *next;
                *next += objects[i.object() as usize].shapes.len() as u32;
                Some(first)
            })
            .collect();
        let bounds: Vec<Bounds3> = scene
            .instances
            .par_iter()
            .map(|i| {
                let b = objects[i.object() as usize].bvh.bounds();
                i.motion().map_or_else(|| instance_bounds(&i.world_from_instance(), b), |m| m.motion_bounds(b))
            })
            .collect();
        let (tlas, order) = Bvh::build(bounds, |_| INSTANCE_COST);
        // Made in the TLAS's order at once: a copy in file order and its reordering
        // held two lists at the peak (280 MB more for a million instances).
        let instances: Vec<Instance> = order
            .par_iter()
            .map(|&k| {
                let i = scene.instances.get(k as usize);
                Instance {
                    // The 4 x 4 inverse's top rows, as before (an affine inverse rounds
                    // differently).
                    instance_from_render: DAffine3::from_mat4(i.world_from_instance().inverse()),
                    object: i.object(),
                    placement: k | if i.motion().is_some() { MOVING } else { 0 },
                }
            })
            .collect();
        let placements = scene.instances.clone();
        Geometry {
            shapes: set,
            instances,
            placements,
            first_shapes,
            world,
            objects,
            tlas,
            triangle_ids,
            avx: Avx::detect(),
        }
    }

    /// The world BVH's SAH cost ([`Bvh::sah_cost`]), to compare builds by.
    pub fn sah_cost(&self) -> f64 {
        self.world.bvh.sah_cost()
    }

    /// Whether BVH traversal uses AVX2, as it does by default where the processor has it.
    pub fn uses_avx(&self) -> bool {
        self.avx.is_some()
    }

    /// Turns AVX2 traversal on (where the processor has it) or off. Both give the
    /// same hits; the switch is there to compare them.
    pub fn set_avx(&mut self, on: bool) {
        self.avx = if on { Avx::detect() } else { None };
    }

    /// The box around everything a ray can hit, over the shutter (`None`: nothing).
    pub fn bounds(&self) -> Option<Bounds3> {
        let b = self.world.bvh.bounds().union(self.tlas.bounds());
        (!b.is_empty()).then_some(b)
    }

    /// The closest hit along the ray before `ray.t_max`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut best = None;
        let mut t_max = ray.t_max;
        if let Some((t, shape, local)) = self.world.intersect(self, ray, t_max) {
            t_max = t;
            best = Some(Hit { t, local, shape_index: shape, instance: None, time: ray.time });
        }
        self.tlas.intersect(ray, t_max, |k, t_max| {
            let inst = &self.instances[k];
            let (r, dt) = instance_ray(&self.instance_from_render_at(inst, ray.time), ray);
            let (t, shape, local) = self.objects[inst.object as usize].intersect(self, &r, t_max - dt)?;
            let t = t + dt;
            // The object's shape index for now: the instance's first is added once the
            // closest hit is known (a read of a list by position, once per ray).
            best = Some(Hit { t, local, shape_index: shape, instance: Some(k as u32), time: ray.time });
            Some(t)
        });
        if let Some(Hit { instance: Some(k), shape_index, .. }) = &mut best {
            *shape_index += self.first_shape_index(&self.instances[*k as usize]);
        }
        best
    }

    /// Whether anything is hit before `ray.t_max` (shadow rays).
    pub fn intersect_p(&self, ray: &Ray) -> bool {
        if self.world.intersect_p(self, ray, ray.t_max) {
            return true;
        }
        self.tlas.intersect_p(ray, ray.t_max, |k, t_max| {
            let inst = &self.instances[k];
            let (r, dt) = instance_ray(&self.instance_from_render_at(inst, ray.time), ray);
            self.objects[inst.object as usize].intersect_p(self, &r, t_max - dt)
        })
    }

    /// The full interaction of a hit, in render space.
    pub fn interaction(&self, hit: &Hit) -> SurfaceInteraction {
        let si = SurfaceInteraction { time: hit.time, ..self.shapes.interaction(&hit.local) };
        match hit.instance {
            Some(k) => {
                let m = self.render_from_instance_at(&self.instances[k as usize], hit.time);
                SurfaceInteraction { t: hit.t, ..si.transformed_f64(&m) }
            }
            None => si,
        }
    }

    /// The hit shape as (object, index among that object's shapes), or (None, world
    /// shape index) for shapes outside object definitions.
    pub fn shape_of(&self, hit: &Hit) -> (Option<u32>, u32) {
        match hit.instance {
            None => (None, hit.shape_index),
            Some(k) => {
                let inst = &self.instances[k as usize];
                (Some(inst.object), hit.shape_index - self.first_shape_index(inst))
            }
        }
    }

    /// World shape `index` (in scene order).
    pub fn world_shape(&self, index: usize) -> ShapeRef {
        self.world.shapes[index]
    }

    /// The file's number of stored triangle `tri` of mesh `mesh` (`tri` itself where
    /// the map was not kept: [`Geometry::with_meshes`]).
    pub fn triangle_id(&self, mesh: u32, tri: u32) -> u32 {
        self.triangle_ids.get(mesh as usize).and_then(|ids| ids.get(tri as usize)).copied().unwrap_or(tri)
    }

    /// Bytes of BVH nodes, primitive references, leaf blocks and the triangle-number
    /// maps.
    pub fn accel_bytes(&self) -> usize {
        let blas =
            |b: &Blas| b.bvh.heap_bytes() + b.prims.capacity() * std::mem::size_of::<Prim>() + b.blocks.heap_bytes();
        let ids: usize = self.triangle_ids.iter().map(|v| v.capacity() * 4).sum();
        blas(&self.world) + self.objects.iter().map(blas).sum::<usize>() + self.tlas.heap_bytes() + ids
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `n` triangles, every seventh of zero area.
    fn strip(n: usize) -> Arc<TriangleMesh> {
        let p = (0..n + 2).map(|i| [i as f32, (i % 2) as f32, 0.0]).collect();
        let indices = (0..n as u32).flat_map(|t| if t % 7 == 3 { [t, t, t + 1] } else { [t, t + 1, t + 2] }).collect();
        Arc::new(TriangleMesh { p, indices, ..Default::default() })
    }

    /// The build records name primitives by their number among all the shapes'; each
    /// number must lead back to its shape and triangle across runs and past shapes
    /// with no triangles (as a scan over every shape's start finds them).
    #[test]
    fn primitive_numbers_lead_back_to_shape_and_triangle() {
        let sizes = [0, 0, 3, 0, 3 * PARALLEL_PRIMS + 5, 1, 0, PARALLEL_PRIMS, 2, 0];
        let set = ShapeSet { meshes: sizes.iter().map(|&n| strip(n)).collect(), ..Default::default() };
        let shapes: Vec<ShapeRef> =
            (0..sizes.len() as u32).map(|mesh| ShapeRef::Mesh { mesh, flags: MeshFlags::default() }).collect();
        let runs = PrimRuns::count(&shapes, &set);
        let mut expected = Vec::new();
        for (shape, &n) in sizes.iter().enumerate() {
            expected.extend((0..n as u32).map(|tri| Prim { shape: shape as u32, tri }));
        }
        assert_eq!(runs.all(), expected.len());
        assert!((0..expected.len()).all(|g| runs.prim(g) == expected[g]));
        // The records of the kept ones, by number, as the build's leaf order gives them.
        let kept: Vec<u32> = (0..expected.len() as u32).filter(|&g| expected[g as usize].tri % 7 != 3).collect();
        assert_eq!(runs.kept(), kept.len());
        let (_, mut order) = Bvh::build_records(runs.fill(|_| 1.0), leaves::MAX_LEAF, |g| runs.prim(g).shape);
        order.sort_unstable();
        assert!(order == kept);
    }

    /// The slots come in mesh order, each the mesh's own, and where two jobs name one
    /// mesh the later job's order is the one kept.
    #[test]
    fn mesh_slots_keep_the_later_of_two_jobs() {
        let mut meshes: Vec<Arc<TriangleMesh>> = (1..=4).map(strip).collect();
        let mut ids = vec![Vec::new(); 4];
        let jobs = vec![(2, vec![1, 0]), (0, vec![5]), (2, vec![7]), (3, vec![9])];
        let slots = mesh_slots(&mut meshes, &mut ids, jobs);
        let seen: Vec<(usize, Vec<u32>)> = slots.iter().map(|(m, _, o)| (m.triangle_count(), o.clone())).collect();
        assert_eq!(seen, [(1, vec![5]), (3, vec![7]), (4, vec![9])]);
        for (_, id, order) in slots {
            *id = order;
        }
        assert_eq!(ids, [vec![5], vec![], vec![7], vec![9]]);
    }
}
