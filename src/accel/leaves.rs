//! Leaf blocks: for a BVH over meshes alone, each leaf (of one mesh's triangles) gets
//! one block holding copies of the vertices its triangles use and each triangle's
//! corners as a byte index into them. A ray that reaches the leaf then waits on one run of memory, where reading
//! the mesh would wait on its indices and then on the vertices they name.
//!
//! The copies are the mesh's exact f32 values, so every triangle test gives the same
//! answer as on the mesh; the mesh itself stays as it is and finishes interactions.
//!
//! A block, in 32-bit words, for a leaf of `c` triangles in `g = ⌈c/4⌉` groups of four:
//!
//! ```text
//! [0]                  the leaf's first triangle (the mesh stores its triangles in leaf order)
//! [1]                  the mesh's shape, as the BVH's owner numbers its shapes
//! [2 .. 2 + 3g]        corner indices, a byte each, 12 per group: triangle k's at bytes 3k..3k+3
//! [2 + 3g ..]          the vertices, three f32 each
//! ```
//!
//! The BVH leaf holds the block's offset and, as its tag, the block's vertex count,
//! so the block's length is known, and all of it requested, before any of it arrives.

use super::bvh::{Isa, Leaf};
#[cfg(target_arch = "x86_64")]
use crate::shapes::edge_candidates8;
use crate::shapes::{TriangleMesh, WatertightRay, corner_lanes_of, edge_candidates};
use glam::{UVec4, Vec3, Vec4};
use std::mem::MaybeUninit;

/// The most triangles in a leaf with a block; their at most 48 vertices fit the
/// node's byte-sized tag and [`all_bytes_below`].
pub const MAX_LEAF: usize = 16;

/// The blocks of all leaves of one BVH, one after another.
#[derive(Clone, Debug, Default)]
pub struct LeafBlocks {
    /// One spare word at the end, so the 16-byte load of a last vertex stays inside.
    words: Vec<u32>,
}

/// A leaf's triangles: `first..first + count` of `mesh`, which is `shape` to the
/// BVH's owner.
#[derive(Clone, Copy)]
pub struct LeafTriangles<'a> {
    pub mesh: &'a TriangleMesh,
    pub shape: u32,
    pub first: usize,
    pub count: usize,
}

/// One leaf's block.
#[derive(Clone, Copy)]
pub struct Block<'a> {
    first: u32,
    shape: u32,
    /// Twelve corner bytes per group.
    corners: &'a [u8],
    /// The vertices and one word after them.
    verts: &'a [u32],
    vertex_count: u32,
    count: usize,
}

/// A block's most words per triangle: two header words and three words of corners
/// per group of up to four, and three vertices of three words each.
const MOST_WORDS_PER_TRIANGLE: usize = 2 + 3 + 9;

/// A block's length in words (without the spare word after the last block) for a leaf
/// of `count` triangles using `vertices` vertices. (Traversal asks it of every leaf.)
#[inline(always)]
fn block_len(count: usize, vertices: usize) -> usize {
    2 + 3 * count.div_ceil(4) + 3 * vertices
}

/// A leaf's distinct vertices, the mesh's numbers in the order of their first use,
/// and each corner's place among them.
struct LocalVertices {
    verts: [u32; 3 * MAX_LEAF],
    count: usize,
    corners: [u8; 3 * MAX_LEAF],
}

impl LocalVertices {
    const NONE: LocalVertices = LocalVertices { verts: [0; 3 * MAX_LEAF], count: 0, corners: [0; 3 * MAX_LEAF] };

    fn of(leaf: &LeafTriangles) -> LocalVertices {
        let LeafTriangles { mesh, first, count, .. } = *leaf;
        assert!(count <= MAX_LEAF, "a leaf block holds at most {MAX_LEAF} triangles");
        let mut local = LocalVertices::NONE;
        for (k, &v) in mesh.indices[3 * first..3 * (first + count)].iter().enumerate() {
            local.corners[k] = local.place(v) as u8;
        }
        local
    }

    /// The leaf's vertices from its corners' places, as [`Self::of`] gave them (the
    /// first `3 * count` of `places`), and the places after them.
    fn of_places<'p>(leaf: &LeafTriangles, places: &'p [u8]) -> (LocalVertices, &'p [u8]) {
        let (mine, rest) = places.split_at(3 * leaf.count);
        let mut local = LocalVertices::NONE;
        local.corners[..mine.len()].copy_from_slice(mine);
        let indices = &leaf.mesh.indices[3 * leaf.first..3 * (leaf.first + leaf.count)];
        // A vertex's place is the count of those before it at its first use.
        for (&place, &v) in mine.iter().zip(indices) {
            if place as usize == local.count {
                local.verts[local.count] = v;
                local.count += 1;
            }
        }
        (local, rest)
    }

    /// Where `v` is among the vertices so far, added if it is new: four places are
    /// compared at a time. The vertices are distinct, so a match in the places past
    /// `count` (zeros) is never in front of a real one.
    #[inline(always)]
    fn place(&mut self, v: u32) -> usize {
        let (n, key) = (self.count, UVec4::splat(v));
        for (c, four) in self.verts[..4 * n.div_ceil(4)].chunks_exact(4).enumerate() {
            let found = UVec4::from_slice(four).cmpeq(key).bitmask();
            if found != 0 {
                let i = 4 * c + found.trailing_zeros() as usize;
                if i < n {
                    return i;
                }
            }
        }
        self.verts[n] = v;
        self.count += 1;
        n
    }

    /// Writes the leaf's block into `out`, which is [`block_len`] words long: every
    /// word of it (the two head words, three corner words per group of four triangles,
    /// three per vertex), so that fresh room needs no zeros first.
    fn write(&self, leaf: &LeafTriangles, out: &mut [MaybeUninit<u32>]) {
        // The callers mark `out` written after this: it must be exactly the block.
        assert_eq!(out.len(), block_len(leaf.count, self.count), "a block's room");
        let groups = leaf.count.div_ceil(4);
        let (head, rest) = out.split_at_mut(2);
        head[0].write(leaf.first as u32);
        head[1].write(leaf.shape);
        let (corners, verts) = rest.split_at_mut(3 * groups);
        // Native byte order, so that the bytes lie in memory in this order.
        for (w, b) in corners.iter_mut().zip(self.corners.chunks_exact(4)) {
            w.write(u32::from_ne_bytes([b[0], b[1], b[2], b[3]]));
        }
        for (w, &v) in verts.chunks_exact_mut(3).zip(&self.verts[..self.count]) {
            for (word, x) in w.iter_mut().zip(leaf.mesh.p[v as usize]) {
                word.write(x.to_bits());
            }
        }
    }
}

impl LeafBlocks {
    /// Whether the blocks of a mesh with this many triangles can be referred to by
    /// the BVH's 32-bit references.
    pub fn fit(triangles: usize) -> bool {
        triangles.checked_mul(MOST_WORDS_PER_TRIANGLE).is_some_and(|w| w < u32::MAX as usize)
    }

    /// Appends the block of triangles `first..first + count` of `mesh`, which is
    /// `shape` to the caller; returns its reference and vertex count, the BVH leaf's
    /// reference and tag. The meshes of one store must together [`fit`](Self::fit),
    /// and `count` be at most [`MAX_LEAF`]. (The reference [`Self::of_leaves`] is
    /// tested against.)
    #[cfg(test)]
    pub fn push(&mut self, mesh: &TriangleMesh, shape: u32, first: usize, count: usize) -> (u32, u8) {
        let leaf = LeafTriangles { mesh, shape, first, count };
        let local = LocalVertices::of(&leaf);
        self.words.pop(); // the previous block's spare word
        let at = self.words.len();
        let n = block_len(count, local.count);
        self.words.reserve(n + 1);
        local.write(&leaf, &mut self.words.spare_capacity_mut()[..n]);
        // SAFETY: `write` wrote all n words past the end.
        unsafe { self.words.set_len(at + n) };
        self.words.push(0);
        (at as u32, local.count as u8)
    }

    /// The blocks of `leaves` and each one's reference and vertex count: the same as
    /// pushing them one after another, on all threads. A first pass finds each
    /// leaf's vertices, keeping only the corners' places (its blocks' lengths follow);
    /// the second writes each block into its place, its vertices read off those
    /// places. (Runs of blocks written apart and then copied together wrote every word
    /// twice, each time into fresh pages: 160 MB more at the peak of a 12.6M-triangle
    /// scene's load.)
    pub fn of_leaves(leaves: &[LeafTriangles]) -> (LeafBlocks, Vec<(u32, u8)>) {
        use rayon::prelude::*;
        const RUN: usize = 4096;
        let runs: Vec<(Vec<u8>, Vec<u8>)> = (leaves.par_chunks(RUN))
            .map(|run| {
                let mut places = Vec::with_capacity(run.iter().map(|l| 3 * l.count).sum());
                let tags = run.iter().map(|l| {
                    let local = LocalVertices::of(l);
                    places.extend_from_slice(&local.corners[..3 * l.count]);
                    local.count as u8
                });
                (tags.collect(), places)
            })
            .collect();
        let mut next = 0usize;
        let refs: Vec<(u32, u8)> = (leaves.iter().zip(runs.iter().flat_map(|r| &r.0)))
            .map(|(l, &tag)| {
                let at = next as u32;
                next += block_len(l.count, tag as usize);
                (at, tag)
            })
            .collect();
        // Each run of blocks written straight into its own part of fresh room, on all
        // threads (the kernel clears the fresh pages on both): no pass of zeros first.
        let mut words = crate::hugepages::with_capacity(next + 1);
        let room = &mut words.spare_capacity_mut()[..next + 1];
        room[next].write(0);
        let mut rest = &mut room[..next];
        let mut parts = Vec::with_capacity(runs.len());
        for (k, run) in refs.chunks(RUN).enumerate() {
            let end = refs.get((k + 1) * RUN).map_or(next, |r| r.0 as usize);
            let part;
            (part, rest) = std::mem::take(&mut rest).split_at_mut(end - run[0].0 as usize);
            parts.push(part);
        }
        parts.into_par_iter().zip(leaves.par_chunks(RUN)).zip(&runs).for_each(|((mut part, run), (_, places))| {
            let mut places = &places[..];
            for l in run {
                let local;
                (local, places) = LocalVertices::of_places(l, places);
                let block;
                (block, part) = std::mem::take(&mut part).split_at_mut(block_len(l.count, local.count));
                local.write(l, block);
            }
            assert!(part.is_empty(), "a run's blocks fill its part");
        });
        // SAFETY: the parts cover the first `next` words, each filled by its run's
        // blocks (checked above), each block written whole; the spare word is 0.
        unsafe { words.set_len(next + 1) };
        (LeafBlocks { words }, refs)
    }

    pub fn shrink_to_fit(&mut self) {
        self.words.shrink_to_fit();
    }

    /// See [`crate::hugepages`].
    pub fn advise_huge_pages(&self) {
        crate::hugepages::advise(&self.words);
    }

    pub fn heap_bytes(&self) -> usize {
        self.words.capacity() * 4
    }

    /// A block's length in words, without the spare word.
    #[inline(always)]
    fn len(leaf: Leaf) -> usize {
        block_len(leaf.count, leaf.tag as usize)
    }

    /// The block of a leaf the BVH handed over; `None` for a reference this store did
    /// not make.
    #[inline(always)]
    pub fn block(&self, leaf: Leaf) -> Option<Block<'_>> {
        let words = self.words.get(leaf.first..leaf.first + Self::len(leaf) + 1)?;
        let [first, shape, rest @ ..] = words else { return None };
        let (corners, verts) = rest.split_at_checked(3 * leaf.count.div_ceil(4))?;
        // SAFETY: the same memory as `corners`, read as bytes: u8 needs no alignment
        // and takes any bit pattern, and the borrow keeps the words alive and unchanged.
        let corners = unsafe { std::slice::from_raw_parts(corners.as_ptr().cast::<u8>(), 4 * corners.len()) };
        Some(Block { first: *first, shape: *shape, corners, verts, vertex_count: leaf.tag as u32, count: leaf.count })
    }

    /// Asks the cache for the lines of the leaf's block past its first, which the
    /// first corner load waits on anyway, so they all arrive together.
    #[inline(always)]
    pub fn prefetch(&self, leaf: Leaf) {
        let start = self.words.as_ptr().wrapping_add(leaf.first) as usize;
        crate::memory::prefetch_lines((start | 63) + 1..start + 4 * Self::len(leaf));
    }
}

impl Block<'_> {
    /// The mesh's number of the block's triangle `k`.
    #[inline(always)]
    pub fn triangle(&self, k: usize) -> u32 {
        self.first + k as u32
    }

    pub fn count(&self) -> usize {
        self.count
    }

    /// The block's mesh, as the caller of [`LeafBlocks::push`] named it.
    #[inline(always)]
    pub fn shape(&self) -> u32 {
        self.shape
    }

    /// Group `g`'s corners for [`crate::shapes::edge_candidates`] (triangles past the
    /// block's last have the first vertex for every corner).
    #[inline(always)]
    pub fn corner_lanes(&self, g: usize) -> [[Vec4; 3]; 3] {
        let bytes: [u8; 12] = self.corners[12 * g..12 * g + 12].try_into().unwrap_or_default();
        let idx = bytes.map(u32::from);
        let word = |w: usize| u32::from_ne_bytes([bytes[4 * w], bytes[4 * w + 1], bytes[4 * w + 2], bytes[4 * w + 3]]);
        // One bounds check for all twelve: each vertex and the word after it.
        let loadable = self.vertex_count.min(128);
        if all_bytes_below([word(0), word(1), word(2)], loadable) {
            // SAFETY: every index v is below `loadable`, at most the block's vertex
            // count, so 3v + 4 is at most `verts.len()`: the vertices and one word.
            corner_lanes_of(&idx, |v| load4(unsafe { self.verts.get_unchecked(3 * v as usize..3 * v as usize + 4) }))
        } else {
            corner_lanes_of(&idx, |v| load4(&self.verts[3 * v as usize..3 * v as usize + 4]))
        }
    }

    /// The triangles from group `g` on that the edge filter keeps, as bits from the
    /// group's first, and how many groups it looked at: two with AVX while two are
    /// left, else one.
    #[inline(always)]
    pub fn edge_candidates<I: Isa, const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        _isa: I,
        g: usize,
        wr: &WatertightRay,
    ) -> (u32, usize) {
        let left = self.count - 4 * g;
        #[cfg(target_arch = "x86_64")]
        if I::AVX && left > 4 {
            let (lo, hi) = (self.corner_lanes(g), self.corner_lanes(g + 1));
            // SAFETY: an `Avx` value, the only `Isa` with `AVX`, proves the processor has it.
            let kept = unsafe { edge_candidates8::<KX, KY, KZ>(&lo, &hi, wr) };
            return (kept & lanes_below(left), 2);
        }
        (edge_candidates::<KX, KY, KZ>(&self.corner_lanes(g), wr) & lanes_below(left.min(4)), 1)
    }

    /// Triangle k's corners.
    #[inline(always)]
    pub fn corners(&self, k: usize) -> [Vec3; 3] {
        let vertex = |j: usize| {
            let v = 3 * self.corners[j] as usize;
            let v = &self.verts[v..v + 3];
            Vec3::new(f32::from_bits(v[0]), f32::from_bits(v[1]), f32::from_bits(v[2]))
        };
        [vertex(3 * k), vertex(3 * k + 1), vertex(3 * k + 2)]
    }
}

/// The bits of the first `n` (at most 8) lanes.
#[inline(always)]
fn lanes_below(n: usize) -> u32 {
    (1u32 << n.min(8)) - 1
}

/// Whether every byte of the words is below `n` (at most 128), four bytes at a time:
/// for a byte b, (b | 0x80) − n borrows nothing from the next byte, and its high bit
/// is set exactly when b mod 128 ≥ n; b's own high bit is set when b ≥ 128.
#[inline(always)]
fn all_bytes_below(w: [u32; 3], n: u32) -> bool {
    const HIGH: u32 = 0x8080_8080;
    let over = |w: u32| w | (w | HIGH).wrapping_sub(n * 0x0101_0101);
    (over(w[0]) | over(w[1]) | over(w[2])) & HIGH == 0
}

/// A vertex's three words, and the next, as a `Vec4` (the fourth lane is unused).
#[inline(always)]
fn load4(w: &[u32]) -> Vec4 {
    Vec4::new(f32::from_bits(w[0]), f32::from_bits(w[1]), f32::from_bits(w[2]), f32::from_bits(w[3]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of triangles over a grid, so that neighbours share vertices, with
    /// coordinates whose low bits a lossy copy would change.
    fn strip(triangles: usize) -> TriangleMesh {
        let columns = triangles / 2 + 2;
        let p = (0..2 * columns).map(|i| [i as f32 / 3.0 + 1e-7, (i / columns) as f32 * 0.1, (i as f32).sqrt()]);
        let indices = (0..triangles as u32).flat_map(|t| {
            let (c, up) = (t / 2, t % 2 == 1);
            let n = columns as u32;
            if up { [c + 1, n + c + 1, n + c] } else { [c, c + 1, n + c] }
        });
        TriangleMesh { p: p.collect(), indices: indices.collect(), ..Default::default() }
    }

    #[test]
    fn blocks_hold_the_mesh_corners_exactly() {
        let mesh = strip(200);
        let mut blocks = LeafBlocks::default();
        // Leaves of every size up to the most, one after another.
        let mut leaves = Vec::new();
        let (mut first, mut count) = (0, 1);
        while first + count <= mesh.triangle_count() {
            let (at, tag) = blocks.push(&mesh, count as u32, first, count);
            leaves.push((Leaf { first: at as usize, count, tag }, first));
            first += count;
            count = count % MAX_LEAF + 1;
        }
        assert!(leaves.len() > MAX_LEAF);
        for (leaf, first) in leaves {
            blocks.prefetch(leaf);
            let block = blocks.block(leaf).expect("a block this store made");
            assert_eq!(block.count(), leaf.count);
            for k in 0..leaf.count {
                assert_eq!(block.triangle(k) as usize, first + k);
                assert_eq!(block.shape() as usize, leaf.count);
                let bits = |c: [Vec3; 3]| c.map(|v| v.to_array().map(f32::to_bits));
                assert_eq!(bits(block.corners(k)), bits(mesh.corners(first + k)));
            }
            for g in 0..leaf.count.div_ceil(4) {
                let (got, want) = (block.corner_lanes(g), mesh.corner_lanes(first + 4 * g));
                for lane in 0..(leaf.count - 4 * g).min(4) {
                    for (c, a) in (0..3).flat_map(|c| (0..3).map(move |a| (c, a))) {
                        assert_eq!(got[c][a][lane].to_bits(), want[c][a][lane].to_bits());
                    }
                }
            }
        }
    }

    /// Blocks made on all threads, over several runs of leaves, are the words and
    /// references of pushing the leaves one after another.
    #[test]
    fn blocks_of_many_leaves_are_those_pushed_in_turn() {
        let mesh = strip(150_000);
        let (mut leaves, mut first) = (Vec::new(), 0);
        while first + MAX_LEAF <= mesh.triangle_count() {
            let count = 1 + (first * 7) % MAX_LEAF;
            leaves.push(LeafTriangles { mesh: &mesh, shape: (first % 5) as u32, first, count });
            first += count;
        }
        assert!(leaves.len() > 2 * 4096, "several runs");
        let mut pushed = LeafBlocks::default();
        let refs: Vec<(u32, u8)> = leaves.iter().map(|l| pushed.push(l.mesh, l.shape, l.first, l.count)).collect();
        let (all, all_refs) = LeafBlocks::of_leaves(&leaves);
        assert!(all.words == pushed.words && all_refs == refs);
    }

    /// The four-at-a-time search gives each corner the place a search from the front
    /// gives, with vertex 0 (which the unused places also hold) among the corners.
    #[test]
    fn corner_places_are_those_of_a_plain_search() {
        let mut state = 7u32;
        for leaf in 0..2000 {
            let count = 1 + leaf % MAX_LEAF;
            let spread = 1 + (leaf / MAX_LEAF) % 60;
            let indices: Vec<u32> = (0..3 * count)
                .map(|_| {
                    state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    (state >> 8) % spread as u32
                })
                .collect();
            let mesh = TriangleMesh { p: vec![[0.0; 3]; 64], indices: indices.clone(), ..Default::default() };
            let l = LeafTriangles { mesh: &mesh, shape: 0, first: 0, count };
            let local = LocalVertices::of(&l);
            let mut verts: Vec<u32> = Vec::new();
            for (k, &v) in indices.iter().enumerate() {
                let place = verts.iter().position(|&u| u == v).unwrap_or_else(|| {
                    verts.push(v);
                    verts.len() - 1
                });
                assert_eq!(local.corners[k] as usize, place, "{indices:?}");
            }
            assert_eq!(&local.verts[..local.count], &verts[..]);
            let (again, rest) = LocalVertices::of_places(&l, &local.corners[..3 * count]);
            assert!(rest.is_empty() && again.verts == local.verts && again.count == local.count);
        }
    }

    #[test]
    fn shared_vertices_are_copied_once_per_block() {
        let mesh = strip(16);
        let mut blocks = LeafBlocks::default();
        let (_, tag) = blocks.push(&mesh, 0, 0, 16);
        // 16 strip triangles use 18 vertices; the block is 2 + 3·4 + 3·18 words.
        assert_eq!(tag, 18);
        assert_eq!(blocks.words.len(), 2 + 12 + 54 + 1);
        assert_eq!(blocks.block(Leaf { first: 0, count: 16, tag: tag + 1 }).map(|b| b.count()), None);
    }

    #[test]
    fn the_byte_check_agrees_with_comparing_each_byte() {
        for n in 0..=128u32 {
            for b in 0..=255u32 {
                for pos in 0..12 {
                    // b at one position among bytes just below n (or 0).
                    let fill = n.saturating_sub(1) * 0x0101_0101;
                    let mut w = [fill; 3];
                    w[pos / 4] = w[pos / 4] & !(0xff << (8 * (pos % 4))) | b << (8 * (pos % 4));
                    let want = w.iter().all(|x| x.to_le_bytes().iter().all(|&y| (y as u32) < n));
                    assert_eq!(all_bytes_below(w, n), want, "n {n} byte {b} at {pos}");
                }
            }
        }
    }

    #[test]
    fn meshes_too_large_for_32_bit_references_do_not_fit() {
        assert!(LeafBlocks::fit(0) && LeafBlocks::fit(1_000_000));
        assert!(LeafBlocks::fit(u32::MAX as usize / MOST_WORDS_PER_TRIANGLE - 1));
        assert!(!LeafBlocks::fit(u32::MAX as usize / MOST_WORDS_PER_TRIANGLE + 1));
        assert!(!LeafBlocks::fit(usize::MAX));
    }
}
