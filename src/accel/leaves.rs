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
use glam::{Vec3, Vec4};

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

impl LeafBlocks {
    /// Whether the blocks of a mesh with this many triangles can be referred to by
    /// the BVH's 32-bit references.
    pub fn fit(triangles: usize) -> bool {
        triangles.checked_mul(MOST_WORDS_PER_TRIANGLE).is_some_and(|w| w < u32::MAX as usize)
    }

    /// Appends the block of triangles `first..first + count` of `mesh`, which is
    /// `shape` to the caller; returns its reference and vertex count, the BVH leaf's
    /// reference and tag. The meshes of one store must together [`fit`](Self::fit),
    /// and `count` be at most [`MAX_LEAF`].
    pub fn push(&mut self, mesh: &TriangleMesh, shape: u32, first: usize, count: usize) -> (u32, u8) {
        assert!(count <= MAX_LEAF, "a leaf block holds at most {MAX_LEAF} triangles");
        self.words.pop(); // the previous block's spare word
        let at = self.words.len() as u32;
        let (mut verts, mut vert_count) = ([0u32; 3 * MAX_LEAF], 0);
        let mut corner_bytes = [0u8; 3 * MAX_LEAF];
        for (k, &v) in mesh.indices[3 * first..3 * (first + count)].iter().enumerate() {
            let local = verts[..vert_count].iter().position(|&u| u == v).unwrap_or_else(|| {
                verts[vert_count] = v;
                vert_count += 1;
                vert_count - 1
            });
            corner_bytes[k] = local as u8;
        }
        self.words.extend([first as u32, shape]);
        // Native byte order, so that the bytes lie in memory in this order.
        let corner_words = corner_bytes[..12 * count.div_ceil(4)].chunks_exact(4);
        self.words.extend(corner_words.map(|b| u32::from_ne_bytes([b[0], b[1], b[2], b[3]])));
        self.words.extend(verts[..vert_count].iter().flat_map(|&v| mesh.p[v as usize].map(f32::to_bits)));
        self.words.push(0);
        (at, vert_count as u8)
    }

    /// The blocks of `leaves` and each one's reference and vertex count: the same as
    /// pushing them one after another, on all threads.
    pub fn of_leaves(leaves: &[LeafTriangles]) -> (LeafBlocks, Vec<(u32, u8)>) {
        use rayon::prelude::*;
        let parts: Vec<(LeafBlocks, Vec<(u32, u8)>)> = leaves
            .par_chunks(4096)
            .map(|run| {
                let mut blocks = LeafBlocks::default();
                let refs = run.iter().map(|l| blocks.push(l.mesh, l.shape, l.first, l.count)).collect();
                (blocks, refs)
            })
            .collect();
        // Each run's words end with a spare word that the next run's first block
        // replaces: copied to their places on all threads.
        let lens: Vec<usize> = parts.iter().map(|p| p.0.words.len() - 1).collect();
        let mut words = super::hugepages::with_capacity(lens.iter().sum::<usize>() + 1);
        words.par_extend(rayon::iter::repeat_n(0u32, lens.iter().sum::<usize>() + 1));
        let mut rest = &mut words[..];
        let mut places = Vec::with_capacity(parts.len());
        for &n in &lens {
            let place;
            (place, rest) = std::mem::take(&mut rest).split_at_mut(n);
            places.push(place);
        }
        places
            .into_par_iter()
            .zip(&parts)
            .for_each(|(place, (blocks, _))| place.copy_from_slice(&blocks.words[..place.len()]));
        let mut refs = Vec::with_capacity(leaves.len());
        let mut base = 0;
        for ((_, run_refs), n) in parts.into_iter().zip(lens) {
            refs.extend(run_refs.into_iter().map(|(at, count)| (base + at, count)));
            base += n as u32;
        }
        let all = LeafBlocks { words };
        (all, refs)
    }

    pub fn shrink_to_fit(&mut self) {
        self.words.shrink_to_fit();
    }

    /// See [`super::hugepages`].
    pub fn advise_huge_pages(&self) {
        super::hugepages::advise(&self.words);
    }

    pub fn heap_bytes(&self) -> usize {
        self.words.capacity() * 4
    }

    /// A block's length in words, without the spare word.
    #[inline(always)]
    fn len(leaf: Leaf) -> usize {
        2 + 3 * leaf.count.div_ceil(4) + 3 * leaf.tag as usize
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
