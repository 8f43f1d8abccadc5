//! The render-ready geometry of a scene: quadrics and meshes, one BVH over the world
//! shapes, one per instanced object, and a top-level BVH over instances. Instances
//! share their object's BVH and geometry; only a transform is stored per instance.

pub mod bvh;

pub use bvh::Bvh;

use crate::interaction::SurfaceInteraction;
use crate::math::{Bounds3, Ray, Transform};
use crate::scene::{Geometry as ShapeGeometry, SceneDescription, ShapeDesc};
use crate::shapes::{MeshFlags, QuadricHit, QuadricShape, TriangleHit, TriangleMesh};
use rayon::prelude::*;

/// A shape of a BVH: a quadric or a whole mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShapeRef {
    Quadric(u32),
    Mesh { mesh: u32, flags: MeshFlags },
}

/// A BVH leaf entry: a shape, and the triangle for meshes (8 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Prim {
    shape: u32,
    tri: u32,
}

/// The shapes of one object (or of the world) and their BVH.
#[derive(Default)]
struct Blas {
    bvh: Bvh,
    prims: Vec<Prim>,
    shapes: Vec<ShapeRef>,
}

/// A placed object.
#[derive(Clone, Debug)]
pub struct Instance {
    pub render_from_instance: Transform,
    pub instance_from_render: Transform,
    object: u32,
    /// The `check --shapes` index of the object's first shape for this instance.
    first_shape_index: u32,
    /// The instance's position among the scene's `ObjectInstance`s.
    pub index: u32,
}

/// Which primitive a ray hit, and what finishing the interaction needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LocalHit {
    Quadric(u32, QuadricHit),
    Triangle { mesh: u32, tri: u32, flags: MeshFlags, hit: TriangleHit },
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
}

/// Everything rays can hit.
pub struct Geometry {
    pub quadrics: Vec<QuadricShape>,
    pub meshes: Vec<TriangleMesh>,
    pub instances: Vec<Instance>,
    world: Blas,
    objects: Vec<Blas>,
    tlas: Bvh,
}

fn shape_ref(s: &ShapeDesc, quadrics: &mut Vec<QuadricShape>) -> ShapeRef {
    match &s.geometry {
        ShapeGeometry::Quadric(q) => {
            quadrics.push(QuadricShape::new(q.clone(), s.object_to_world, s.reverse_orientation));
            ShapeRef::Quadric(quadrics.len() as u32 - 1)
        }
        ShapeGeometry::Mesh { mesh, .. } => ShapeRef::Mesh {
            mesh: *mesh,
            flags: MeshFlags { reverse_orientation: s.reverse_orientation, swaps_handedness: s.swaps_handedness() },
        },
    }
}

impl Blas {
    fn build(shapes: Vec<ShapeRef>, quadrics: &[QuadricShape], meshes: &[TriangleMesh]) -> Blas {
        let mut prims = Vec::new();
        let mut bounds = Vec::new();
        for (i, s) in shapes.iter().enumerate() {
            match s {
                ShapeRef::Quadric(q) => {
                    prims.push(Prim { shape: i as u32, tri: u32::MAX });
                    bounds.push(quadrics[*q as usize].bounds());
                }
                ShapeRef::Mesh { mesh, .. } => {
                    let m = &meshes[*mesh as usize];
                    for t in 0..m.triangle_count() {
                        prims.push(Prim { shape: i as u32, tri: t as u32 });
                        bounds.push(m.triangle_bounds(t));
                    }
                }
            }
        }
        let (bvh, order) = Bvh::build(&bounds);
        let prims = order.iter().map(|&i| prims[i as usize]).collect();
        Blas { bvh, prims, shapes }
    }

    /// Closest hit: (t, local shape index, what was hit).
    fn intersect(&self, g: &Geometry, ray: &Ray, t_max: f32) -> Option<(f32, u32, LocalHit)> {
        let mut best = None;
        self.bvh.intersect(ray, t_max, |i, t_max| {
            let prim = self.prims[i];
            let hit = self.hit_prim(g, prim, ray, t_max)?;
            best = Some((prim.shape, hit.1));
            Some(hit.0)
        });
        let (shape, local) = best?;
        let t = match local {
            LocalHit::Quadric(_, h) => h.t,
            LocalHit::Triangle { hit, .. } => hit.t,
        };
        Some((t, shape, local))
    }

    fn hit_prim(&self, g: &Geometry, prim: Prim, ray: &Ray, t_max: f32) -> Option<(f32, LocalHit)> {
        match self.shapes[prim.shape as usize] {
            ShapeRef::Quadric(q) => {
                let h = g.quadrics[q as usize].intersect_t(ray, t_max)?;
                Some((h.t, LocalHit::Quadric(q, h)))
            }
            ShapeRef::Mesh { mesh, flags } => {
                let hit = g.meshes[mesh as usize].intersect_triangle(prim.tri as usize, ray, t_max)?;
                Some((hit.t, LocalHit::Triangle { mesh, tri: prim.tri, flags, hit }))
            }
        }
    }

    fn intersect_p(&self, g: &Geometry, ray: &Ray, t_max: f32) -> bool {
        self.bvh.intersect_p(ray, t_max, |i, t_max| self.hit_prim(g, self.prims[i], ray, t_max).is_some())
    }
}

impl Geometry {
    /// Builds the acceleration structures, taking the scene's meshes.
    pub fn new(scene: &mut SceneDescription) -> Geometry {
        let meshes = std::mem::take(&mut scene.meshes);
        let mut quadrics = Vec::new();
        let world_shapes: Vec<ShapeRef> = scene.shapes.iter().map(|s| shape_ref(s, &mut quadrics)).collect();
        let object_shapes: Vec<Vec<ShapeRef>> =
            scene.objects.iter().map(|o| o.shapes.iter().map(|s| shape_ref(s, &mut quadrics)).collect()).collect();
        let world = Blas::build(world_shapes, &quadrics, &meshes);
        let objects: Vec<Blas> =
            object_shapes.into_par_iter().map(|shapes| Blas::build(shapes, &quadrics, &meshes)).collect();
        let mut next = scene.shapes.len() as u32;
        let mut instances: Vec<Instance> = scene
            .instances
            .iter()
            .enumerate()
            .map(|(k, i)| {
                let t = Transform::from_dmat4(i.world_from_instance);
                let first_shape_index = next;
                next += objects[i.object as usize].shapes.len() as u32;
                Instance {
                    render_from_instance: t,
                    instance_from_render: t.inverse(),
                    object: i.object,
                    first_shape_index,
                    index: k as u32,
                }
            })
            .collect();
        let bounds: Vec<Bounds3> =
            instances.iter().map(|i| i.render_from_instance.bounds(objects[i.object as usize].bvh.bounds())).collect();
        let (tlas, order) = Bvh::build(&bounds);
        instances = order.iter().map(|&k| instances[k as usize].clone()).collect();
        Geometry { quadrics, meshes, instances, world, objects, tlas }
    }

    /// The closest hit along the ray before `ray.t_max`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut best = None;
        let mut t_max = ray.t_max;
        if let Some((t, shape, local)) = self.world.intersect(self, ray, t_max) {
            t_max = t;
            best = Some(Hit { t, local, shape_index: shape, instance: None });
        }
        self.tlas.intersect(ray, t_max, |k, t_max| {
            let inst = &self.instances[k];
            let (r, dt) = inst.instance_from_render.ray(ray);
            let (t, shape, local) = self.objects[inst.object as usize].intersect(self, &r, t_max - dt)?;
            let t = t + dt;
            best = Some(Hit { t, local, shape_index: inst.first_shape_index + shape, instance: Some(k as u32) });
            Some(t)
        });
        best
    }

    /// Whether anything is hit before `ray.t_max` (shadow rays).
    pub fn intersect_p(&self, ray: &Ray) -> bool {
        if self.world.intersect_p(self, ray, ray.t_max) {
            return true;
        }
        self.tlas.intersect_p(ray, ray.t_max, |k, t_max| {
            let inst = &self.instances[k];
            let (r, dt) = inst.instance_from_render.ray(ray);
            self.objects[inst.object as usize].intersect_p(self, &r, t_max - dt)
        })
    }

    /// The full interaction of a hit, in render space.
    pub fn interaction(&self, hit: &Hit) -> SurfaceInteraction {
        let si = match hit.local {
            LocalHit::Quadric(q, h) => self.quadrics[q as usize].interaction(&h),
            LocalHit::Triangle { mesh, tri, flags, hit: h } => {
                self.meshes[mesh as usize].interaction(tri as usize, &h, flags)
            }
        };
        match hit.instance {
            Some(k) => {
                SurfaceInteraction { t: hit.t, ..si.transformed(&self.instances[k as usize].render_from_instance) }
            }
            None => si,
        }
    }

    /// Bytes of BVH nodes and primitive references.
    pub fn accel_bytes(&self) -> usize {
        let blas = |b: &Blas| b.bvh.heap_bytes() + b.prims.capacity() * std::mem::size_of::<Prim>();
        blas(&self.world) + self.objects.iter().map(blas).sum::<usize>() + self.tlas.heap_bytes()
    }
}
