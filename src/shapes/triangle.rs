//! Triangle meshes: `Shape "trianglemesh"`, `"plymesh"` and `"objmesh"` all end here.
//!
//! ```text
//! Shape "trianglemesh" "point3 P" [...] "integer indices" [...]
//!       "normal N" [...] "vector3 S" [...] "point2 uv" [...] "integer faceIndices" [...]
//! ```
//! Vertices are shared `f32` triples and indices `u32`, about 18 bytes per triangle for a
//! closed mesh. Like pbrt, positions are stored after the shape's transform is applied.

/// One triangle mesh's vertex data (already in the space of its transform).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub p: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
    pub n: Option<Vec<[f32; 3]>>,
    pub s: Option<Vec<[f32; 3]>>,
    pub uv: Option<Vec<[f32; 2]>>,
    pub face_indices: Option<Vec<i32>>,
}

impl TriangleMesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn vertices(&self, tri: usize) -> [glam::DVec3; 3] {
        let v = |k: usize| glam::DVec3::from(self.p[self.indices[3 * tri + k] as usize].map(f64::from));
        [v(0), v(1), v(2)]
    }

    /// Σ ½‖(p1 − p0) × (p2 − p0)‖.
    pub fn area(&self) -> f64 {
        (0..self.triangle_count())
            .map(|t| {
                let [a, b, c] = self.vertices(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Area after the linear map `m`: ½‖cof(m)·(e1 × e2)‖ per triangle, where the
    /// cofactor matrix cof(m) = det(m)·m⁻ᵀ maps cross products.
    pub fn area_under(&self, m: glam::DMat3) -> f64 {
        let det = m.determinant();
        if det == 0.0 {
            // A flattening map: transform the vertices themselves.
            return (0..self.triangle_count())
                .map(|t| {
                    let [a, b, c] = self.vertices(t).map(|v| m * v);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum();
        }
        let cof = det * m.inverse().transpose();
        (0..self.triangle_count())
            .map(|t| {
                let [a, b, c] = self.vertices(t);
                0.5 * (cof * (b - a).cross(c - a)).length()
            })
            .sum()
    }

    /// Bounds of the referenced vertices.
    pub fn bounds(&self) -> Option<[glam::DVec3; 2]> {
        let mut it = self.indices.iter().map(|&i| glam::DVec3::from(self.p[i as usize].map(f64::from)));
        let first = it.next()?;
        Some(it.fold([first, first], |[lo, hi], p| [lo.min(p), hi.max(p)]))
    }

    /// Heap bytes held by this mesh.
    pub fn heap_bytes(&self) -> usize {
        self.p.capacity() * 12
            + self.indices.capacity() * 4
            + self.n.as_ref().map_or(0, |v| v.capacity() * 12)
            + self.s.as_ref().map_or(0, |v| v.capacity() * 12)
            + self.uv.as_ref().map_or(0, |v| v.capacity() * 8)
            + self.face_indices.as_ref().map_or(0, |v| v.capacity() * 4)
    }
}
