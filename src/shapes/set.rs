//! The render-ready shapes of a scene, and the one place that dispatches on a shape's
//! family. Each family's own file owns its intersection, interaction and sampling; the
//! BVH, the lights and the integrators reach them only through [`ShapeSet`].
//!
//! A shape is split into primitives for the BVH: a quadric is one, a triangle mesh one
//! per triangle, a bilinear patch mesh one per patch. An area light is one light per
//! primitive, as in pbrt.
//!
//! Adding a shape family: its file, a variant in [`ShapeRef`], [`LocalHit`] and
//! [`Piece`], and an arm in each method below.

use super::bilinear::{PatchHit, PatchMesh};
use super::curve::{CurveHit, CurveShape};
use super::quadric::{QuadricHit, QuadricShape};
use super::sampling::{QuadricSampler, ShapeSample, area_to_solid_angle};
use super::triangle::{MeshFlags, TriangleHit, TriangleMesh, WatertightRay, watertight};
use crate::interaction::SurfaceInteraction;
use crate::math::{Bounds3, Point3, Ray, Vector3};
use glam::Vec3;
use std::sync::Arc;

/// A quadric's intersection cost in triangle tests, for SAH: its root solve with
/// error bounds and its partial-shape checks take several times a triangle's.
pub const QUADRIC_COST: f32 = 8.0;
/// A bilinear patch's: one quadratic, two closest-approach solves.
pub const PATCH_COST: f32 = 4.0;
/// A curve piece's: a transform, a frame and a few levels of subdivision.
pub const CURVE_COST: f32 = 16.0;

/// Every shape rays can hit, by family.
#[derive(Default)]
pub struct ShapeSet {
    pub quadrics: Vec<QuadricShape>,
    pub meshes: Vec<Arc<TriangleMesh>>,
    pub patches: Vec<Arc<PatchMesh>>,
    pub curves: Vec<CurveShape>,
}

/// One shape of a BVH: an index into its family's list, and the orientation flags of
/// meshes (whose vertices are stored transformed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShapeRef {
    Quadric(u32),
    Mesh { mesh: u32, flags: MeshFlags },
    Patches { mesh: u32, flags: MeshFlags },
    Curves(u32),
}

/// Which primitive a ray hit, and what finishing the interaction needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LocalHit {
    Quadric(u32, QuadricHit),
    Triangle { mesh: u32, tri: u32, flags: MeshFlags, hit: TriangleHit },
    Patch { mesh: u32, patch: u32, flags: MeshFlags, hit: PatchHit },
    Curve { curves: u32, piece: u32, hit: CurveHit },
}

impl LocalHit {
    /// The primitive's number within its shape (0 for a quadric).
    pub fn prim(&self) -> u32 {
        match self {
            LocalHit::Quadric(..) => 0,
            LocalHit::Triangle { tri, .. } => *tri,
            LocalHit::Patch { patch, .. } => *patch,
            LocalHit::Curve { piece, .. } => *piece,
        }
    }
}

/// A primitive that emits as one area light, with what sampling it needs.
#[derive(Clone, Debug)]
pub enum Piece {
    Quadric { index: u32, sampler: QuadricSampler },
    Triangle { mesh: u32, tri: u32, flags: MeshFlags },
    Patch { mesh: u32, patch: u32, flags: MeshFlags },
}

impl Piece {
    /// The piece, its samples carrying their (u, v) only if `uv` (where they may skip
    /// it: pbrt's quadric sampling).
    pub fn reading_uv(self, uv: bool) -> Piece {
        match self {
            Piece::Quadric { index, sampler: QuadricSampler::Pbrt { object_area, .. } } => {
                Piece::Quadric { index, sampler: QuadricSampler::Pbrt { object_area, uv } }
            }
            p => p,
        }
    }
}

impl ShapeSet {
    /// How many BVH primitives the shape has.
    pub fn prim_count(&self, s: ShapeRef) -> usize {
        match s {
            ShapeRef::Quadric(_) => 1,
            ShapeRef::Mesh { mesh, .. } => self.meshes[mesh as usize].triangle_count(),
            ShapeRef::Patches { mesh, .. } => self.patches[mesh as usize].patch_count(),
            ShapeRef::Curves(c) => self.curves[c as usize].piece_count(),
        }
    }

    /// A primitive's bounds; `None` for zero-area ones, which are never hit or sampled.
    pub fn prim_bounds(&self, s: ShapeRef, prim: usize) -> Option<Bounds3> {
        match s {
            ShapeRef::Quadric(q) => Some(self.quadrics[q as usize].bounds()),
            ShapeRef::Mesh { mesh, .. } => self.meshes[mesh as usize].bounds_unless_degenerate(prim),
            ShapeRef::Patches { mesh, .. } => {
                let m = &self.patches[mesh as usize];
                (!m.is_degenerate(prim)).then(|| m.patch_bounds(prim))
            }
            ShapeRef::Curves(c) => Some(self.curves[c as usize].bounds(prim)),
        }
    }

    /// An emitting primitive's bounds.
    pub fn piece_bounds(&self, piece: &Piece) -> Bounds3 {
        match *piece {
            Piece::Quadric { index, .. } => self.quadrics[index as usize].bounds(),
            Piece::Triangle { mesh, tri, .. } => self.meshes[mesh as usize].triangle_bounds(tri as usize),
            Piece::Patch { mesh, patch, .. } => self.patches[mesh as usize].patch_bounds(patch as usize),
        }
    }

    /// A primitive's intersection cost in triangle tests, for SAH.
    pub fn prim_cost(s: ShapeRef) -> f32 {
        match s {
            ShapeRef::Quadric(_) => QUADRIC_COST,
            ShapeRef::Mesh { .. } => 1.0,
            ShapeRef::Patches { .. } => PATCH_COST,
            ShapeRef::Curves(_) => CURVE_COST,
        }
    }

    /// The hit of primitive `prim` of `s` before `t_max`. `wr` is the ray prepared for
    /// the watertight triangle test with axes (KX, KY, KZ).
    #[inline(always)]
    pub fn intersect<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        s: ShapeRef,
        prim: u32,
        ray: &Ray,
        wr: &WatertightRay,
        t_max: f32,
    ) -> Option<(f32, LocalHit)> {
        match s {
            ShapeRef::Quadric(q) => {
                let h = self.quadrics[q as usize].intersect_t(ray, t_max)?;
                Some((h.t, LocalHit::Quadric(q, h)))
            }
            ShapeRef::Mesh { mesh, flags } => {
                let hit = watertight::<KX, KY, KZ>(self.meshes[mesh as usize].corners(prim as usize), wr, t_max)?;
                Some((hit.t, LocalHit::Triangle { mesh, tri: prim, flags, hit }))
            }
            ShapeRef::Patches { mesh, flags } => {
                let hit = self.patches[mesh as usize].intersect(prim as usize, ray, t_max)?;
                Some((hit.t, LocalHit::Patch { mesh, patch: prim, flags, hit }))
            }
            ShapeRef::Curves(curves) => {
                let hit = self.curves[curves as usize].intersect(prim as usize, ray, t_max)?;
                Some((hit.t, LocalHit::Curve { curves, piece: prim, hit }))
            }
        }
    }

    /// The full interaction of a hit, in the space the shape is stored in.
    pub fn interaction(&self, hit: &LocalHit) -> SurfaceInteraction {
        match *hit {
            LocalHit::Quadric(q, h) => self.quadrics[q as usize].interaction(&h),
            LocalHit::Triangle { mesh, tri, flags, hit } => {
                self.meshes[mesh as usize].interaction(tri as usize, &hit, flags)
            }
            LocalHit::Patch { mesh, patch, flags, hit } => {
                self.patches[mesh as usize].interaction(patch as usize, &hit, flags)
            }
            LocalHit::Curve { curves, hit, .. } => self.curves[curves as usize].interaction(&hit),
        }
    }

    /// The shape's emitting pieces with their areas, one per primitive. Zero-area
    /// primitives keep their slot (lights are found by primitive number) with area 0.
    /// `pbrt_sampling`: spheres, disks and cylinders are sampled as pbrt samples them,
    /// with their object-space area (see `pbrt_sampling`).
    pub fn pieces(&self, s: ShapeRef, pbrt_sampling: bool) -> Vec<(Piece, f64)> {
        match s {
            ShapeRef::Quadric(index) => {
                let q = &self.quadrics[index as usize];
                if pbrt_sampling && super::pbrt_sampling::pbrt_samples(&q.quadric) {
                    let object_area = q.quadric.world_area(glam::DMat3::IDENTITY);
                    return vec![(
                        Piece::Quadric { index, sampler: QuadricSampler::Pbrt { object_area, uv: true } },
                        object_area,
                    )];
                }
                let area = q.quadric.world_area(glam::DMat3::from_mat4(q.render_from_object));
                vec![(Piece::Quadric { index, sampler: q.sampler() }, area)]
            }
            ShapeRef::Mesh { mesh, flags } => {
                let m = &self.meshes[mesh as usize];
                (0..m.triangle_count())
                    .map(|t| {
                        let [a, b, c] = m.vertices(t);
                        (Piece::Triangle { mesh, tri: t as u32, flags }, 0.5 * (b - a).cross(c - a).length())
                    })
                    .collect()
            }
            ShapeRef::Patches { mesh, flags } => {
                let m = &self.patches[mesh as usize];
                (0..m.patch_count()).map(|k| (Piece::Patch { mesh, patch: k as u32, flags }, m.patch_area(k))).collect()
            }
            // Curves never emit: the scene builder drops area lights on them.
            ShapeRef::Curves(_) => Vec::new(),
        }
    }

    /// A point on a piece: by solid angle as seen from `reference`, or by area.
    pub fn sample_piece(&self, piece: &Piece, reference: Option<Point3>, u: [f32; 2]) -> Option<ShapeSample> {
        let by_area = match piece {
            Piece::Quadric { index, sampler } => {
                let q = &self.quadrics[*index as usize];
                return match reference {
                    Some(r) => q.sample_solid_angle(sampler, r, u),
                    None => Some(q.sample_area(sampler, u)),
                };
            }
            Piece::Triangle { mesh, tri, flags } => {
                self.meshes[*mesh as usize].sample_triangle(*tri as usize, u, *flags)
            }
            Piece::Patch { mesh, patch, flags } => self.patches[*mesh as usize].sample(*patch as usize, u, *flags)?,
        };
        match reference {
            Some(r) => area_to_solid_angle(by_area, r),
            None => Some(by_area),
        }
    }

    /// The area density `sample_piece` (by area) gives the point `p` of a piece, whose
    /// normal there is `n`.
    pub fn pdf_piece_area(&self, piece: &Piece, p: Point3, n: Vec3) -> f32 {
        match piece {
            Piece::Quadric { index, sampler } => self.quadrics[*index as usize].pdf_area(sampler, p),
            Piece::Triangle { mesh, tri, .. } => self.meshes[*mesh as usize].pdf_triangle_area(*tri as usize),
            Piece::Patch { mesh, patch, .. } => self.patches[*mesh as usize].pdf_area(*patch as usize, p, n),
        }
    }

    /// The solid-angle density `sample_piece` gives direction `wi` from `p`.
    pub fn pdf_piece(&self, piece: &Piece, p: Point3, wi: Vector3) -> f32 {
        match piece {
            Piece::Quadric { index, sampler } => self.quadrics[*index as usize].pdf_solid_angle(sampler, p, wi),
            Piece::Triangle { mesh, tri, .. } => {
                self.meshes[*mesh as usize].pdf_triangle_solid_angle(*tri as usize, p, wi)
            }
            Piece::Patch { mesh, patch, .. } => self.patches[*mesh as usize].pdf_solid_angle(*patch as usize, p, wi),
        }
    }
}
