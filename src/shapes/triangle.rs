//! Triangle meshes: `Shape "trianglemesh"`, `"plymesh"` and `"objmesh"` all end here.
//!
//! ```text
//! Shape "trianglemesh" "point3 P" [...] "integer indices" [...]
//!       "normal N" [...] "vector3 S" [...] "point2 uv" [...] "integer faceIndices" [...]
//! ```
//! Vertices are shared `f32` triples and indices `u32`, about 18 bytes per triangle for a
//! closed mesh. Like pbrt, positions are stored after the shape's transform is applied.

/// ‖(b − a) × (c − a)‖² = 0 in f64 (glam's order of operations, in scalars: a
/// vector version stalled on its stack copies and took 16 ns a triangle).
fn zero_area([a, b, c]: [[f32; 3]; 3]) -> bool {
    let minus = |u: [f32; 3], v: [f32; 3]| [0, 1, 2].map(|k| f64::from(u[k]) - f64::from(v[k]));
    let ([ex, ey, ez], [fx, fy, fz]) = (minus(b, a), minus(c, a));
    let (x, y, z) = (ey * fz - fy * ez, ez * fx - fz * ex, ex * fy - fx * ey);
    x * x + y * y + z * z == 0.0
}

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

    /// Zero area (in f64, from the stored corners): never hit, never sampled.
    pub fn is_degenerate(&self, tri: usize) -> bool {
        zero_area([0, 1, 2].map(|k| self.p[self.indices[3 * tri + k] as usize]))
    }

    /// How many triangles are [degenerate](Self::is_degenerate), counted on all threads.
    pub fn degenerate_count(&self) -> usize {
        use rayon::prelude::*;
        let corner = |i: u32| self.p[i as usize];
        let count = |run: &[[u32; 3]]| run.iter().filter(|t| zero_area(t.map(corner))).count();
        match self.indices.as_chunks::<3>().0 {
            small if small.len() < 1 << 14 => count(small),
            triangles => triangles.par_chunks(1 << 14).map(count).sum(),
        }
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

    /// Puts triangle `order[k]` at position k and renumbers vertices by first use, so
    /// triangles that are near in a BVH are near in memory (their vertices too).
    /// Per-vertex arrays follow; vertices no triangle uses are dropped.
    pub fn reordered(&self, order: &[u32]) -> TriangleMesh {
        let mut remap = vec![u32::MAX; self.p.len()];
        let mut old_of_new: Vec<u32> = Vec::with_capacity(self.p.len());
        let mut indices = Vec::with_capacity(3 * order.len());
        for &t in order {
            for &v in &self.indices[3 * t as usize..3 * t as usize + 3] {
                if remap[v as usize] == u32::MAX {
                    remap[v as usize] = old_of_new.len() as u32;
                    old_of_new.push(v);
                }
                indices.push(remap[v as usize]);
            }
        }
        fn gather<T: Copy>(v: &[T], at: &[u32]) -> Vec<T> {
            at.iter().map(|&i| v[i as usize]).collect()
        }
        TriangleMesh {
            indices,
            p: gather(&self.p, &old_of_new),
            n: self.n.as_ref().map(|n| gather(n, &old_of_new)),
            s: self.s.as_ref().map(|s| gather(s, &old_of_new)),
            uv: self.uv.as_ref().map(|uv| gather(uv, &old_of_new)),
            face_indices: self.face_indices.as_ref().map(|f| gather(f, order)),
        }
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

use super::{Built, ShapeContext};
use crate::interaction::{Shading, SurfaceInteraction};
use crate::math::float::gamma;
use crate::math::frame::coordinate_system;
use crate::math::{Bounds3, Normal3, Point3, Ray, Vector3};
use crate::parser::Syntax;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::values::Res;
use glam::{Mat4, Vec3, Vec4};

/// Orientation flags of the shape a mesh came from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeshFlags {
    pub reverse_orientation: bool,
    pub swaps_handedness: bool,
    /// Leave the shading normal's derivatives (∂n/∂u, ∂n/∂v) at zero: only bump maps
    /// read them, and in a scene without one their sums were about 2% of a
    /// caustic-glass render's time.
    pub skip_normal_derivatives: bool,
}

/// A ray set up for the watertight test: the axis of largest |d| becomes z, and the
/// shear that maps d to +z. pbrt recomputes this per triangle; it depends on the ray only.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    o: Vec3,
    kz: usize,
    /// (−dx/dz, −dy/dz, 1/dz) after permutation.
    shear: Vec3,
}

impl WatertightRay {
    pub fn new(ray: &Ray) -> WatertightRay {
        // Selects and indexes rather than branching: rays arrive in random directions.
        let ad = ray.d.0.abs();
        let x_largest = (ad.x > ad.y) & (ad.x > ad.z);
        let kz = if x_largest { 0 } else { 2 - (ad.y > ad.z) as usize };
        let d = ray.d.0.to_array();
        let d = Vec3::new(d[(kz + 1) % 3], d[(kz + 2) % 3], d[kz]);
        WatertightRay { o: ray.o.0, kz, shear: Vec3::new(-d.x / d.z, -d.y / d.z, 1.0 / d.z) }
    }

    /// The axis the ray is most nearly along: 0 for the permutation (1, 2, 0) of
    /// [`watertight`], 1 for (2, 0, 1), 2 for (0, 1, 2).
    pub fn kz(&self) -> usize {
        self.kz
    }
}

/// The cheap result of a ray–triangle test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub b: [f32; 3],
    /// The corners tested, as stored: the interaction takes them from here rather
    /// than through the mesh's indices, a dependent cache miss.
    pub p: [Vec3; 3],
}

impl TriangleMesh {
    #[inline]
    pub fn corners(&self, tri: usize) -> [Vec3; 3] {
        let i = &self.indices[3 * tri..3 * tri + 3];
        [Vec3::from(self.p[i[0] as usize]), Vec3::from(self.p[i[1] as usize]), Vec3::from(self.p[i[2] as usize])]
    }

    /// The corners of triangles `first..first + 4` for [`edge_candidates`] (past the
    /// last triangle, the last again; the mesh must have one): `[c][axis]` holds
    /// corner c's coordinate on that axis, one lane per triangle.
    #[inline(always)]
    pub fn corner_lanes(&self, first: usize) -> [[Vec4; 3]; 3] {
        let last = (self.indices.len() / 3).saturating_sub(1);
        let idx: [u32; 12] = match self.indices.get(3 * first..3 * first + 12) {
            Some(run) => run.try_into().unwrap_or([0; 12]),
            None => std::array::from_fn(|j| self.indices[3 * (first + j / 3).min(last) + j % 3]),
        };
        // One bounds check for all twelve corners, not one each.
        if idx.iter().fold(0, |most, &v| most.max(v)) < self.p.len() as u32 {
            // SAFETY: every index is below `p.len() as u32`, which is at most `p.len()`.
            corner_lanes_of(&idx, |v| Vec3::from(*unsafe { self.p.get_unchecked(v as usize) }).extend(0.0))
        } else {
            corner_lanes_of(&idx, |v| Vec3::from(self.p[v as usize]).extend(0.0))
        }
    }

    pub fn triangle_bounds(&self, tri: usize) -> Bounds3 {
        let [a, b, c] = self.corners(tri);
        Bounds3::new(a, b).union_point(c)
    }

    /// [`Self::triangle_bounds`], or `None` for a [degenerate](Self::is_degenerate)
    /// triangle, from one read of its corners (the BVH build asks this of every
    /// triangle, twice).
    #[inline]
    pub fn bounds_unless_degenerate(&self, tri: usize) -> Option<Bounds3> {
        let [a, b, c] = self.corners(tri);
        (!zero_area([a, b, c].map(|v| v.to_array()))).then(|| Bounds3::new(a, b).union_point(c))
    }

    /// pbrt's watertight ray–triangle test (pbrt-v3 `Triangle::Intersect`).
    #[inline]
    pub fn intersect_triangle(&self, tri: usize, ray: &Ray, t_max: f32) -> Option<TriangleHit> {
        self.intersect_prepared(tri, &WatertightRay::new(ray), t_max)
    }

    /// The watertight test with the ray's permutation and shear computed once.
    #[inline(always)]
    pub fn intersect_prepared(&self, tri: usize, r: &WatertightRay, t_max: f32) -> Option<TriangleHit> {
        // One instance per permutation, so the axis shuffle costs nothing per triangle.
        match r.kz {
            0 => watertight::<1, 2, 0>(self.corners(tri), r, t_max),
            1 => watertight::<2, 0, 1>(self.corners(tri), r, t_max),
            _ => watertight::<0, 1, 2>(self.corners(tri), r, t_max),
        }
    }
}

/// The watertight test of the triangle with corners `[p0, p1, p2]`, for a ray whose
/// permutation `r.kz()` is (KX, KY, KZ).
#[inline(always)]
pub fn watertight<const KX: usize, const KY: usize, const KZ: usize>(
    [p0, p1, p2]: [Vec3; 3],
    r: &WatertightRay,
    t_max: f32,
) -> Option<TriangleHit> {
    let permute = |p: Vec3| {
        let v = p - r.o;
        Vec3::new(v[KX], v[KY], v[KZ])
    };
    let (mut p0t, mut p1t, mut p2t) = (permute(p0), permute(p1), permute(p2));
    for p in [&mut p0t, &mut p1t, &mut p2t] {
        p.x += r.shear.x * p.z;
        p.y += r.shear.y * p.z;
    }
    let mut e0 = p1t.x * p2t.y - p1t.y * p2t.x;
    let mut e1 = p2t.x * p0t.y - p2t.y * p0t.x;
    let mut e2 = p0t.x * p1t.y - p0t.y * p1t.x;
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        let f = |a: f32, b: f32, c: f32, d: f32| (a as f64 * b as f64 - c as f64 * d as f64) as f32;
        e0 = f(p1t.x, p2t.y, p1t.y, p2t.x);
        e1 = f(p2t.x, p0t.y, p2t.y, p0t.x);
        e2 = f(p0t.x, p1t.y, p0t.y, p1t.x);
    }
    // Non-short-circuit operators: one branch, not six, for random rays to mispredict.
    let negative = (e0 < 0.0) | (e1 < 0.0) | (e2 < 0.0);
    let positive = (e0 > 0.0) | (e1 > 0.0) | (e2 > 0.0);
    if negative & positive {
        return None;
    }
    let det = e0 + e1 + e2;
    // Degenerate triangles never hit (pbrt-v4 checks this first; checking only the
    // candidates that got this far gives the same answers).
    if det == 0.0 || (p2 - p0).cross(p1 - p0).length_squared() == 0.0 {
        return None;
    }
    // The x and y errors come from the shear, x + sx·z with |sx| ≤ 1, so they scale
    // with z before it is divided by the direction's z.
    let max_z = p0t.z.abs().max(p1t.z.abs()).max(p2t.z.abs());
    p0t.z *= r.shear.z;
    p1t.z *= r.shear.z;
    p2t.z *= r.shear.z;
    let t_scaled = e0 * p0t.z + e1 * p1t.z + e2 * p2t.z;
    if (det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det))
        || (det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det))
    {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // Reject hits whose t is not conservatively greater than zero.
    let max_zt = p0t.z.abs().max(p1t.z.abs()).max(p2t.z.abs());
    let delta_z = gamma(3) * max_zt;
    let max_xt = p0t.x.abs().max(p1t.x.abs()).max(p2t.x.abs());
    let max_yt = p0t.y.abs().max(p1t.y.abs()).max(p2t.y.abs());
    // DEVIATION(pbrt): robustness. pbrt bounds the x and y errors with the z already scaled by
    // 1/d.z, which is off by the direction's length: with a direction of length 1e-5 a
    // triangle of size 1e-6 could never be hit, and with a long one the bound shrinks.
    let delta_x = gamma(5) * (max_xt + max_z);
    let delta_y = gamma(5) * (max_yt + max_z);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t = 3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    // t is the barycentric mix of the corners' distances along the ray, so when every
    // corner is conservatively ahead, so is the hit, whatever the bound on t says.
    // DEVIATION(pbrt): robustness. pbrt rejects on the bound alone, which grows as 1/det: a
    // triangle nearly edge-on to the ray (the rim of a flattened closed mesh) was
    // rejected even at t ≈ 1, and a ray through the edge it shares escaped the mesh.
    let min_zt = p0t.z.min(p1t.z).min(p2t.z);
    let ahead = min_zt > delta_z;
    if t <= delta_t && !ahead {
        return None;
    }
    let t = if ahead { t.clamp(min_zt, max_zt) } else { t };
    if t > t_max {
        return None;
    }
    Some(TriangleHit { t, b: [e0 * inv_det, e1 * inv_det, e2 * inv_det], p: [p0, p1, p2] })
}

/// The corners of the four triangles `idx` lists as lanes (`[c][axis]`), with `load`
/// giving a vertex in a `Vec4`'s x, y and z.
#[inline(always)]
pub fn corner_lanes_of(idx: &[u32; 12], load: impl Fn(u32) -> Vec4) -> [[Vec4; 3]; 3] {
    let lane = |c: usize| {
        let m = Mat4::from_cols(load(idx[c]), load(idx[3 + c]), load(idx[6 + c]), load(idx[9 + c])).transpose();
        [m.x_axis, m.y_axis, m.z_axis]
    };
    [lane(0), lane(1), lane(2)]
}

/// Which of four triangles the ray's line crosses, as a bit set: [`watertight`]'s
/// edge functions and sign test, four triangles at a time (`corners[c][axis]` holds
/// corner c's coordinate on that axis for each), with the same operations in the
/// same order. A triangle left out is one [`watertight`] rejects; one with an edge
/// function of exactly zero, which [`watertight`] redoes in f64, is kept. A ray's
/// line crosses few of a leaf's triangles, so the full test runs about once a leaf.
#[inline(always)]
pub fn edge_candidates<const KX: usize, const KY: usize, const KZ: usize>(
    corners: &[[Vec4; 3]; 3],
    r: &WatertightRay,
) -> u32 {
    let (sx, sy) = (Vec4::splat(r.shear.x), Vec4::splat(r.shear.y));
    let sheared = |c: &[Vec4; 3]| {
        let (x, y, z) = (c[KX] - Vec4::splat(r.o[KX]), c[KY] - Vec4::splat(r.o[KY]), c[KZ] - Vec4::splat(r.o[KZ]));
        (x + sx * z, y + sy * z)
    };
    // (`array::map` is not always inlined.)
    let (p0, p1, p2) = (sheared(&corners[0]), sheared(&corners[1]), sheared(&corners[2]));
    let e0 = p1.0 * p2.1 - p1.1 * p2.0;
    let e1 = p2.0 * p0.1 - p2.1 * p0.0;
    let e2 = p0.0 * p1.1 - p0.1 * p1.0;
    let zero = Vec4::ZERO;
    let any_zero = e0.cmpeq(zero) | e1.cmpeq(zero) | e2.cmpeq(zero);
    let negative = e0.cmplt(zero) | e1.cmplt(zero) | e2.cmplt(zero);
    let positive = e0.cmpgt(zero) | e1.cmpgt(zero) | e2.cmpgt(zero);
    (!(negative & positive) | any_zero).bitmask()
}

/// [`edge_candidates`] for eight triangles at once with AVX: `lo` the corner lanes of
/// the first four, `hi` of the next four. The same operations in the same order.
///
/// # Safety
/// The processor must have AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
pub fn edge_candidates8<const KX: usize, const KY: usize, const KZ: usize>(
    lo: &[[Vec4; 3]; 3],
    hi: &[[Vec4; 3]; 3],
    r: &WatertightRay,
) -> u32 {
    use std::arch::x86_64::*;
    let (sx, sy) = (_mm256_set1_ps(r.shear.x), _mm256_set1_ps(r.shear.y));
    let sheared = |c: usize| {
        let axis = |a: usize| {
            let v = _mm256_set_m128(hi[c][a].into(), lo[c][a].into());
            _mm256_sub_ps(v, _mm256_set1_ps(r.o[a]))
        };
        let (x, y, z) = (axis(KX), axis(KY), axis(KZ));
        (_mm256_add_ps(x, _mm256_mul_ps(sx, z)), _mm256_add_ps(y, _mm256_mul_ps(sy, z)))
    };
    let (p0, p1, p2) = (sheared(0), sheared(1), sheared(2));
    let edge =
        |a: (__m256, __m256), b: (__m256, __m256)| _mm256_sub_ps(_mm256_mul_ps(a.0, b.1), _mm256_mul_ps(a.1, b.0));
    let (e0, e1, e2) = (edge(p1, p2), edge(p2, p0), edge(p0, p1));
    let e = [e0, e1, e2];
    let (any_zero, negative, positive) = (any::<_CMP_EQ_OQ>(e), any::<_CMP_LT_OQ>(e), any::<_CMP_GT_OQ>(e));
    (!(negative & positive) | any_zero) & 0xff
}

/// The lanes where any of the three edge values compares `CMP` with zero, as bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
fn any<const CMP: i32>(e: [std::arch::x86_64::__m256; 3]) -> u32 {
    use std::arch::x86_64::*;
    let z = _mm256_setzero_ps();
    let c = |v| _mm256_cmp_ps::<CMP>(v, z);
    _mm256_movemask_ps(_mm256_or_ps(_mm256_or_ps(c(e[0]), c(e[1])), c(e[2]))) as u32
}

impl TriangleMesh {
    /// The texture coordinates of a triangle's corners (pbrt's defaults without `uv`).
    #[inline]
    pub(super) fn uvs(&self, tri: usize) -> [glam::Vec2; 3] {
        match &self.uv {
            Some(uv) => {
                let i = &self.indices[3 * tri..3 * tri + 3];
                [0, 1, 2].map(|k| glam::Vec2::from(uv[i[k] as usize]))
            }
            None => [glam::Vec2::new(0.0, 0.0), glam::Vec2::new(1.0, 0.0), glam::Vec2::new(1.0, 1.0)],
        }
    }

    /// Asks the cache for triangle `tri`'s vertex indices, which its interaction reads
    /// (for normals and uv) as soon as the ray's closest hit is known.
    #[inline(always)]
    pub fn prefetch_indices(&self, tri: usize) {
        if let Some(first) = self.indices.get(3 * tri) {
            crate::memory::prefetch(first);
        }
    }

    /// Differential geometry at a hit (pbrt-v3's triangle interaction).
    pub fn interaction(&self, tri: usize, hit: &TriangleHit, flags: MeshFlags) -> SurfaceInteraction {
        let [p0, p1, p2] = hit.p;
        let uv = self.uvs(tri);
        let [b0, b1, b2] = hit.b;
        let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
        let (dp02, dp12) = (p0 - p2, p1 - p2);
        let det = duv02.x * duv12.y - duv02.y * duv12.x;
        let mut dpdu = Vec3::ZERO;
        let mut dpdv = Vec3::ZERO;
        if det.abs() >= 1e-8 {
            let inv = 1.0 / det;
            dpdu = (duv12.y * dp02 - duv02.y * dp12) * inv;
            dpdv = (-duv12.x * dp02 + duv02.x * dp12) * inv;
        }
        if det.abs() < 1e-8 || dpdu.cross(dpdv).length_squared() == 0.0 {
            let ng = (p2 - p0).cross(p1 - p0);
            (dpdu, dpdv) = coordinate_system(ng.normalize_or_zero());
        }
        let abs_sum = (b0 * p0).abs() + (b1 * p1).abs() + (b2 * p2).abs();
        let p_error = gamma(7) * abs_sum;
        let p = b0 * p0 + b1 * p1 + b2 * p2;
        let uv_hit = b0 * uv[0] + b1 * uv[1] + b2 * uv[2];
        let mut n = dp02.cross(dp12).normalize_or_zero();
        if flags.reverse_orientation ^ flags.swaps_handedness {
            n = -n;
        }
        let mut si = SurfaceInteraction {
            p: Point3(p),
            p_error,
            t: hit.t,
            uv: uv_hit.to_array(),
            n: Normal3(n),
            dpdu: Vector3(dpdu),
            dpdv: Vector3(dpdv),
            dndu: Normal3::default(),
            dndv: Normal3::default(),
            shading: Shading { n: Normal3(n), dpdu: Vector3(dpdu), dpdv: Vector3(dpdv), ..Default::default() },
            time: 0.0,
            face: self.face_indices.as_ref().map_or(0, |f| f[tri]),
        };
        if self.n.is_some() || self.s.is_some() {
            self.shading_geometry(tri, hit, flags, &mut si);
        }
        si
    }

    /// Shading frame from per-vertex N and S; N decides the front side.
    fn shading_geometry(&self, tri: usize, hit: &TriangleHit, flags: MeshFlags, si: &mut SurfaceInteraction) {
        let i = &self.indices[3 * tri..3 * tri + 3];
        let [b0, b1, b2] = hit.b;
        let lerp = |a: &Vec<[f32; 3]>| {
            b0 * Vec3::from(a[i[0] as usize]) + b1 * Vec3::from(a[i[1] as usize]) + b2 * Vec3::from(a[i[2] as usize])
        };
        let ns = match &self.n {
            Some(n) => lerp(n).try_normalize().unwrap_or(si.n.0),
            None => si.n.0,
        };
        let mut ss = match &self.s {
            Some(s) => lerp(s).try_normalize().unwrap_or(si.dpdu.0.normalize_or_zero()),
            None => si.dpdu.0.normalize_or_zero(),
        };
        let mut ts = ss.cross(ns);
        if ts.length_squared() > 0.0 {
            ts = ts.normalize();
            ss = ts.cross(ns);
        } else {
            (ss, ts) = coordinate_system(ns);
        }
        let (dndu, dndv) = match &self.n {
            Some(n) if !flags.skip_normal_derivatives => self.normal_derivatives(tri, n),
            _ => (Vec3::ZERO, Vec3::ZERO),
        };
        if flags.reverse_orientation {
            ts = -ts;
        }
        let shading_n = Normal3(ss.cross(ts).normalize_or_zero());
        si.n = si.n.face_forward(shading_n.into());
        si.shading =
            Shading { n: shading_n, dpdu: Vector3(ss), dpdv: Vector3(ts), dndu: Normal3(dndu), dndv: Normal3(dndv) };
    }

    fn normal_derivatives(&self, tri: usize, n: &[[f32; 3]]) -> (Vec3, Vec3) {
        let i = &self.indices[3 * tri..3 * tri + 3];
        let nv = [0, 1, 2].map(|k| Vec3::from(n[i[k] as usize]));
        let uv = self.uvs(tri);
        let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
        let (dn1, dn2) = (nv[0] - nv[2], nv[1] - nv[2]);
        let det = duv02.x * duv12.y - duv02.y * duv12.x;
        if det.abs() < 1e-8 {
            let dn = (nv[2] - nv[0]).cross(nv[1] - nv[0]);
            if dn.length_squared() == 0.0 {
                return (Vec3::ZERO, Vec3::ZERO);
            }
            return coordinate_system(dn.normalize());
        }
        let inv = 1.0 / det;
        ((duv12.y * dn1 - duv02.y * dn2) * inv, (-duv12.x * dn1 + duv02.x * dn2) * inv)
    }
}

/// `Shape "trianglemesh"` (see [`super::mesh_params`] for its parameters).
pub const NAME: &str = "trianglemesh";

pub fn read(ctx: &mut ShapeContext, p: &mut ParamList, span: Span) -> Res<Built> {
    // pbrt-v3 reports a mesh without `P` or `indices` (a single triangle too) and
    // leaves it out; pbrt-v4 stops, or takes the three points as one triangle.
    let missing = match (p.find("P", &[ParamType::Point3]), p.find("indices", &[ParamType::Integer])) {
        (None, _) => Some("point3 P"),
        (_, None) => Some("integer indices"),
        _ => None,
    };
    if let Some(missing) = missing.filter(|_| ctx.syntax == Some(Syntax::V3)) {
        return ctx.left_out_by_v3(p, span, format!("{NAME} needs \"{missing}\""));
    }
    match super::mesh_params::from_params(p, NAME, span, ctx.warn) {
        Ok(mesh) => Ok(Built::Mesh { mesh, kind: NAME, filename: None }),
        // As is an index past the last vertex (a negative one stays an error: pbrt-v3
        // reads memory before its array).
        Err(e) if super::mesh_params::index_past_the_end(p, 3).is_some() => {
            ctx.left_out_by_v3(p, e.span.unwrap_or(span), e.message)
        }
        Err(e) => Err(e),
    }
}
