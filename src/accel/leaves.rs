//! Leaf blocks: for a BVH over a single mesh, each leaf gets one block holding copies
//! of the vertices its triangles use and each triangle's corners as a byte index into
//! them. A ray that reaches the leaf then waits on one run of memory, where reading
//! the mesh would wait on its indices and then on the vertices they name.
//!
//! The copies are the mesh's exact f32 values, so every triangle test gives the same
//! answer as on the mesh; the mesh itself stays as it is and finishes interactions.
//!
//! A block, in 32-bit words, for a leaf of `c` triangles in `g = ⌈c/4⌉` groups of four:
//!
//! ```text
//! [0]                  the leaf's first triangle (the mesh stores its triangles in leaf order)
//! [1 .. 1 + 3g]        corner indices, a byte each, 12 per group: triangle k's at bytes 3k..3k+3
//! [1 + 3g ..]          the vertices, three f32 each
//! ```

use super::bvh::Leaf;
use crate::shapes::{TriangleMesh, corner_lanes_of};
use glam::{Vec3, Vec4};

/// The most triangles in a leaf with a block: its length in words, at most
/// 1 + 3·4 + 3·48 = 157, fits the node's byte-sized tag.
pub const MAX_LEAF: usize = 16;

/// The blocks of all leaves of one BVH, one after another.
#[derive(Clone, Debug, Default)]
pub struct LeafBlocks {
    /// One spare word at the end, so the 16-byte load of a last vertex stays inside.
    words: Vec<u32>,
}

/// One leaf's block.
#[derive(Clone, Copy)]
pub struct Block<'a> {
    first: u32,
    /// Three words of corner bytes per group.
    corners: &'a [u32],
    /// The vertices and the words after them (at least one).
    verts: &'a [u32],
    count: usize,
}

/// A block's most words per triangle: a first-triangle word and three words of
/// corners per group of up to four, and three vertices of three words each.
const MOST_WORDS_PER_TRIANGLE: usize = 1 + 3 + 9;

impl LeafBlocks {
    /// Whether the blocks of a mesh with this many triangles can be referred to by
    /// the BVH's 32-bit references.
    pub fn fit(triangles: usize) -> bool {
        triangles.checked_mul(MOST_WORDS_PER_TRIANGLE).is_some_and(|w| w < u32::MAX as usize)
    }

    /// Appends the block of triangles `first..first + count` of `mesh`; returns its
    /// reference and length for the BVH's leaf. The mesh must [`fit`](Self::fit), and
    /// `count` be at most [`MAX_LEAF`].
    pub fn push(&mut self, mesh: &TriangleMesh, first: usize, count: usize) -> (u32, u8) {
        assert!(count <= MAX_LEAF, "a leaf block holds at most {MAX_LEAF} triangles");
        self.words.pop(); // the previous block's spare word
        let at = self.words.len() as u32;
        let mut verts: Vec<u32> = Vec::with_capacity(3 * count);
        let mut corner_bytes = vec![0u8; 12 * count.div_ceil(4)];
        for (k, &v) in mesh.indices[3 * first..3 * (first + count)].iter().enumerate() {
            let local = verts.iter().position(|&u| u == v).unwrap_or_else(|| {
                verts.push(v);
                verts.len() - 1
            });
            corner_bytes[k] = local as u8;
        }
        self.words.push(first as u32);
        self.words.extend(corner_bytes.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])));
        self.words.extend(verts.iter().flat_map(|&v| mesh.p[v as usize].map(f32::to_bits)));
        let len = self.words.len() - at as usize;
        self.words.push(0);
        (at, len as u8)
    }

    pub fn shrink_to_fit(&mut self) {
        self.words.shrink_to_fit();
    }

    pub fn heap_bytes(&self) -> usize {
        self.words.capacity() * 4
    }

    /// The block of a leaf the BVH handed over; `None` for a reference this store did
    /// not make.
    #[inline(always)]
    pub fn block(&self, leaf: Leaf) -> Option<Block<'_>> {
        let words = self.words.get(leaf.first..leaf.first + leaf.tag as usize + 1)?;
        let (&first, rest) = words.split_first()?;
        let (corners, verts) = rest.split_at_checked(3 * leaf.count.div_ceil(4))?;
        Some(Block { first, corners, verts, count: leaf.count })
    }

    /// Asks the cache for the lines of the leaf's block past its first, which the
    /// first corner load waits on anyway, so they all arrive together.
    #[inline(always)]
    pub fn prefetch(&self, leaf: Leaf) {
        #[cfg(target_arch = "x86_64")]
        {
            let start = self.words.as_ptr().wrapping_add(leaf.first) as usize;
            let end = start + 4 * leaf.tag as usize;
            for line in ((start | 63) + 1..end).step_by(64) {
                // SAFETY: a prefetch reads nothing the program sees and cannot fault;
                // it is `unsafe` only for its `sse` target feature, which every x86_64 has.
                unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(line as *const i8) };
            }
        }
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

    /// Group `g`'s corners for [`crate::shapes::edge_candidates`] (triangles past the
    /// block's last have the first vertex for every corner).
    #[inline(always)]
    pub fn corner_lanes(&self, g: usize) -> [[Vec4; 3]; 3] {
        let w = &self.corners[3 * g..3 * g + 3];
        let bytes = [w[0].to_le_bytes(), w[1].to_le_bytes(), w[2].to_le_bytes()];
        let idx: [u32; 12] = std::array::from_fn(|j| bytes[j / 4][j % 4] as u32);
        // One bounds check for all twelve: the vertex and the word after it.
        let most = idx.iter().fold(0, |m, &v| m.max(v)) as usize;
        if 3 * most + 4 <= self.verts.len() {
            // SAFETY: every index is at most `most`, whose four words lie in `verts`.
            corner_lanes_of(&idx, |v| load4(unsafe { self.verts.get_unchecked(3 * v as usize..3 * v as usize + 4) }))
        } else {
            corner_lanes_of(&idx, |v| load4(&self.verts[3 * v as usize..3 * v as usize + 4]))
        }
    }

    /// Triangle k's corners.
    #[inline(always)]
    pub fn corners(&self, k: usize) -> [Vec3; 3] {
        let byte = |j: usize| (self.corners[j / 4].to_le_bytes()[j % 4] as usize) * 3;
        let vertex = |j: usize| {
            let v = &self.verts[byte(j)..byte(j) + 3];
            Vec3::new(f32::from_bits(v[0]), f32::from_bits(v[1]), f32::from_bits(v[2]))
        };
        [vertex(3 * k), vertex(3 * k + 1), vertex(3 * k + 2)]
    }
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
            let (at, tag) = blocks.push(&mesh, first, count);
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

    #[test]
    fn shared_vertices_are_copied_once_per_block() {
        let mesh = strip(16);
        let mut blocks = LeafBlocks::default();
        let (_, tag) = blocks.push(&mesh, 0, 16);
        // 16 strip triangles use 18 vertices: 1 + 3·4 + 3·18 words.
        assert_eq!(tag, 1 + 12 + 54);
        assert_eq!(blocks.block(Leaf { first: 0, count: 16, tag: tag + 1 }).map(|b| b.count()), None);
    }

    #[test]
    fn meshes_too_large_for_32_bit_references_do_not_fit() {
        assert!(LeafBlocks::fit(0) && LeafBlocks::fit(1_000_000));
        assert!(LeafBlocks::fit(u32::MAX as usize / MOST_WORDS_PER_TRIANGLE - 1));
        assert!(!LeafBlocks::fit(u32::MAX as usize / MOST_WORDS_PER_TRIANGLE + 1));
        assert!(!LeafBlocks::fit(usize::MAX));
    }
}
