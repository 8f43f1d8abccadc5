//! pbrt's own sampling of sphere, disk and cylinder area lights, which the renderer
//! follows by default (`--fix shape-sampling` uses [`super::sampling`]'s exact sampling
//! instead).
//!
//! ```text
//! AttributeBegin
//!   AreaLightSource "diffuse" "rgb L" [4 4 4]
//!   Scale 2 2 2                                   # pbrt: object-space area, object radius
//!   Shape "sphere" "float radius" 1 "float zmax" 0.5   # pbrt: samples the whole sphere
//! AttributeEnd
//! ```
//!
//! DEVIATION(pbrt): appearance, `--fix shape-sampling`. pbrt (v3 and v4) samples
//! - a sphere over the *whole* sphere and a disk over the whole disk, whatever
//!   `zmin`/`zmax`/`phimax`/`innerradius` cut away, with the density of the cut shape;
//! - with the shape's *object-space* area (1/Area()) under any transform, and a sphere
//!   seen from outside within the cone of its *object* radius around its world centre;
//! - with normals flipped by `ReverseOrientation` only, not by a handedness swap.
//!
//! So a cut or scaled sphere light emits photons and light samples from where it has no
//! surface, or too much or too little, and a mirrored one-sided light emits its light
//! samples and photons from its back. Cylinders are sampled over their own surface, with
//! the object-space area. (pbrt cannot sample cones, paraboloids and hyperboloids at
//! all: it aborts; here they always use the exact sampling.)

use super::Quadric;
use super::quadric::QuadricShape;
use super::sampling::{ShapeSample, area_to_solid_angle};
use crate::math::{Normal3, Point3, Ray, Vector3};
use glam::DVec3;
use std::f64::consts::TAU;

/// Whether pbrt can sample this quadric (it aborts for the others).
pub fn pbrt_samples(q: &Quadric) -> bool {
    matches!(q, Quadric::Sphere(_) | Quadric::Disk(_) | Quadric::Cylinder(_))
}

impl QuadricShape {
    /// The world normal of object normal `n` (as pbrt transforms normals), flipped by
    /// `ReverseOrientation` alone.
    fn pbrt_normal(&self, n: DVec3) -> DVec3 {
        let n = (self.normal_matrix() * n).normalize_or_zero();
        if self.reverse_orientation { -n } else { n }
    }

    /// pbrt's `Shape::Sample(u)`: a point by (object-space) area, with its (u, v) if
    /// `uv`.
    pub(super) fn sample_area_pbrt(&self, object_area: f64, uv: bool, u: [f32; 2]) -> ShapeSample {
        // The sphere's and disk's points are drawn in f32 as pbrt draws them (its
        // `UniformSampleSphere` and `ConcentricSampleDisk`): an f64 sine and cosine cost
        // 1.5% of `sppm-bench`'s render, which samples a disk light.
        let (p_obj, n_obj) = match &self.quadric {
            Quadric::Sphere(s) => {
                // Unit in f64, so the point lies on the sphere (pbrt reprojects it).
                let d = crate::sampling::uniform_sphere(u).as_dvec3().normalize();
                (d * s.radius as f64, d)
            }
            Quadric::Disk(d) => {
                let p = crate::sampling::concentric_disk(u).as_dvec2() * d.radius as f64;
                (p.extend(d.height as f64), DVec3::Z)
            }
            Quadric::Cylinder(c) => {
                let u = [u[0] as f64, u[1] as f64];
                let z = c.z_min as f64 + u[0] * (c.z_max as f64 - c.z_min as f64);
                let phi = u[1] * c.phi_max as f64;
                let r = c.radius as f64;
                (DVec3::new(r * phi.cos(), r * phi.sin(), z), DVec3::new(phi.cos(), phi.sin(), 0.0))
            }
            _ => (DVec3::ZERO, DVec3::Z),
        };
        let p = self.render_from_object.transform_point3(p_obj);
        let n = self.pbrt_normal(n_obj);
        let uv = if uv { self.uv_of_object_point(p_obj).map(|x| x as f32) } else { [0.0; 2] };
        let pdf = if object_area > 0.0 { (1.0 / object_area) as f32 } else { 0.0 };
        ShapeSample { p: Point3(p.as_vec3()), n: Normal3(n.as_vec3()), uv, pdf }
    }

    /// A sphere's world centre, its object radius, and whether `reference` lies within
    /// that radius of the centre (pbrt's test for area sampling instead of the cone).
    fn pbrt_sphere(&self, reference: Point3) -> Option<(DVec3, f64, bool)> {
        let Quadric::Sphere(s) = &self.quadric else { return None };
        let c = self.render_from_object.transform_point3(DVec3::ZERO);
        let r = s.radius as f64;
        // pbrt first moves the reference towards the centre by its error bound, so that
        // points on the sphere itself count as inside; a relative margin does the same.
        Some((c, r, (c - reference.0.as_dvec3()).length_squared() <= r * r * 1.0001))
    }

    /// pbrt's `Shape::Sample(ref, u)`: a point with its solid-angle density.
    pub(super) fn sample_solid_angle_pbrt(
        &self,
        object_area: f64,
        uv: bool,
        reference: Point3,
        u: [f32; 2],
    ) -> Option<ShapeSample> {
        match self.pbrt_sphere(reference) {
            Some((c, r, false)) => {
                // The point where the cone's ray meets the sphere of the object radius
                // about the world centre, whatever the transform's scale.
                let mut s = self.sample_sphere_cone(reference.0.as_dvec3(), c, r, u, uv)?;
                let n = (s.p.0.as_dvec3() - c).normalize_or_zero();
                s.n = Normal3((if self.reverse_orientation { -n } else { n }).as_vec3());
                Some(s)
            }
            _ => area_to_solid_angle(self.sample_area_pbrt(object_area, uv, u), reference),
        }
    }

    /// pbrt's `Shape::Pdf(ref, wi)` for a direction that reaches the shape.
    pub(super) fn pdf_solid_angle_pbrt(&self, object_area: f64, reference: Point3, wi: Vector3) -> f32 {
        let Some(hit) = self.intersect_t(&Ray::new(reference, wi), f32::INFINITY) else { return 0.0 };
        if let Some((c, r, false)) = self.pbrt_sphere(reference) {
            let cos_max = (1.0 - r * r / (c - reference.0.as_dvec3()).length_squared()).max(0.0).sqrt();
            return (1.0 / (TAU * (1.0 - cos_max))) as f32;
        }
        let si = self.interaction(&hit);
        let d2 = (si.p.0.as_dvec3() - reference.0.as_dvec3()).length_squared();
        // The cosine with the direction asked about, as pbrt: a hit at the reference
        // point itself (d = 0) has density 0, not NaN.
        let cos = si.n.0.as_dvec3().dot(-wi.0.as_dvec3().normalize()).abs();
        if cos == 0.0 || object_area <= 0.0 { 0.0 } else { (d2 / (cos * object_area)) as f32 }
    }
}
