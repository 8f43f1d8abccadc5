//! Sampling points on shapes, by area and by solid angle from a reference point, with
//! the matching densities.
//!
//! DEVIATION(pbrt): appearance, `--fix shape-sampling` (pbrt's own sampling is in
//! `pbrt_sampling`, the default for spheres, disks and cylinders). pbrt samples the
//! *full* sphere and disk even for partial shapes (returning the partial shape's pdf),
//! and uses object-space areas under any transform; it has no sampling for cones,
//! paraboloids and hyperboloids (robustness: always this module's). Here every quadric
//! is sampled over exactly its own surface with a density w.r.t. world-space area:
//! - exactly uniform (pdf = 1/area) for spheres, cylinders, disks and cones under
//!   similarity transforms (Archimedes for spheres, ρ² for disks, √ for cones);
//! - otherwise from a table of the world-space area element J(u,v) = |M ∂p/∂u × M ∂p/∂v|
//!   over (u,v) cells, uniform inside each cell: pdf_A = p(u,v) / J(u,v), exact at every
//!   point and close to uniform.
//!
//! Sampled normals follow the same orientation rule as intersections (pbrt's area
//! sampling applies only ReverseOrientation, not the handedness flip).

use super::quadric::QuadricShape;
use super::{Quadric, TriangleMesh};
use crate::math::{Normal3, Point3, Ray, Vector3};
use glam::{DMat3, DVec3};
use std::f64::consts::TAU;

/// A sampled point with its normal, texture coordinates (for alpha masks) and density
/// (w.r.t. area or solid angle).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeSample {
    pub p: Point3,
    pub n: Normal3,
    pub uv: [f32; 2],
    pub pdf: f32,
}

/// How a quadric's points are drawn.
#[derive(Clone, Debug, PartialEq)]
pub enum QuadricSampler {
    /// Exactly uniform; the world area.
    Uniform { area: f64 },
    /// Cells of (u,v): `nu × nv`, cumulative weights (J × cell size), their total.
    Table { nu: usize, nv: usize, cdf: Vec<f64>, total: f64 },
    /// As pbrt samples spheres, disks and cylinders ([`super::pbrt_sampling`]), with
    /// the object-space area. `uv`: whether samples carry their (u, v), which only an
    /// emission image or an alpha mask reads; else (0, 0), sparing an arctangent a
    /// sample (pbrt's samples have none).
    Pbrt { object_area: f64, uv: bool },
}

const TABLE_RES: usize = 32;

impl QuadricShape {
    fn linear(&self) -> DMat3 {
        DMat3::from_mat4(self.render_from_object)
    }

    /// World-space area element at (u, v).
    fn area_element(&self, u: f64, v: f64) -> f64 {
        let m = self.linear();
        (m * self.quadric.dpdu(u, v)).cross(m * self.quadric.dpdv(u, v)).length()
    }

    /// The sampler for this shape (built once per emitter).
    pub fn sampler(&self) -> QuadricSampler {
        let similarity = super::similarity_scale(self.linear());
        let analytic =
            matches!(self.quadric, Quadric::Sphere(_) | Quadric::Cylinder(_) | Quadric::Disk(_) | Quadric::Cone(_));
        if let (Some(_), true) = (similarity, analytic) {
            return QuadricSampler::Uniform { area: self.quadric.world_area(self.linear()) };
        }
        // Under a similarity J does not depend on u: one column of cells suffices.
        let nu = if similarity.is_some() { 1 } else { TABLE_RES };
        let nv = 2 * TABLE_RES;
        let mut cdf = Vec::with_capacity(nu * nv);
        let mut total = 0.0;
        for j in 0..nv {
            for i in 0..nu {
                let (u, v) = ((i as f64 + 0.5) / nu as f64, (j as f64 + 0.5) / nv as f64);
                total += self.area_element(u, v).max(1e-300) / (nu * nv) as f64;
                cdf.push(total);
            }
        }
        QuadricSampler::Table { nu, nv, cdf, total }
    }

    /// (u, v) for two uniform numbers, and the density p(u, v) for table sampling.
    fn sample_uv(&self, s: &QuadricSampler, u: [f64; 2]) -> ([f64; 2], Option<f64>) {
        match s {
            QuadricSampler::Uniform { .. } | QuadricSampler::Pbrt { .. } => (self.uniform_uv(u), None),
            QuadricSampler::Table { nu, nv, cdf, total } => {
                let target = u[0] * total;
                let cell = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1);
                let lo = if cell == 0 { 0.0 } else { cdf[cell - 1] };
                let w = cdf[cell] - lo;
                let inner = if w > 0.0 { ((target - lo) / w).clamp(0.0, 1.0 - f64::EPSILON) } else { 0.5 };
                let (i, j) = (cell % nu, cell / nu);
                let uv = [(i as f64 + inner) / *nu as f64, (j as f64 + u[1]) / *nv as f64];
                (uv, Some(w / total * (*nu * *nv) as f64))
            }
        }
    }

    /// Exactly area-uniform (u, v) for spheres, cylinders, disks and cones.
    fn uniform_uv(&self, u: [f64; 2]) -> [f64; 2] {
        let v = match &self.quadric {
            Quadric::Sphere(s) => {
                // z uniform in [zmin, zmax] is area-uniform (Archimedes); v is linear in θ.
                let r = s.radius as f64;
                let z = s.z_min as f64 + u[1] * (s.z_max as f64 - s.z_min as f64);
                let (ta, tb) =
                    ((s.z_min as f64 / r).clamp(-1.0, 1.0).acos(), (s.z_max as f64 / r).clamp(-1.0, 1.0).acos());
                let theta = (z / r).clamp(-1.0, 1.0).acos();
                if tb == ta { 0.5 } else { (theta - ta) / (tb - ta) }
            }
            Quadric::Disk(d) => {
                let (r, ri) = (d.radius as f64, d.inner_radius as f64);
                let rho = (ri * ri + u[1] * (r * r - ri * ri)).sqrt();
                if r == ri { 0.0 } else { (r - rho) / (r - ri) }
            }
            Quadric::Cone(_) => 1.0 - (1.0 - u[1]).sqrt(),
            _ => u[1],
        };
        [u[0], v]
    }

    /// The density w.r.t. world area at (u, v).
    pub fn pdf_area_uv(&self, s: &QuadricSampler, uv: [f64; 2]) -> f64 {
        match s {
            QuadricSampler::Uniform { area } => 1.0 / area,
            QuadricSampler::Pbrt { object_area, .. } => 1.0 / object_area,
            QuadricSampler::Table { nu, nv, cdf, total } => {
                let i = ((uv[0] * *nu as f64) as usize).min(nu - 1);
                let j = ((uv[1] * *nv as f64) as usize).min(nv - 1);
                let cell = j * nu + i;
                let w = cdf[cell] - if cell == 0 { 0.0 } else { cdf[cell - 1] };
                let p_uv = w / total * (*nu * *nv) as f64;
                p_uv / self.area_element(uv[0], uv[1])
            }
        }
    }

    /// The world point and oriented normal at (u, v).
    fn point_normal(&self, uv: [f64; 2]) -> (DVec3, DVec3) {
        let m = self.linear();
        let p = self.render_from_object.transform_point3(self.quadric.point(uv[0], uv[1]));
        let mut n =
            (m * self.quadric.dpdu(uv[0], uv[1])).cross(m * self.quadric.dpdv(uv[0], uv[1])).normalize_or_zero();
        if self.reverse_orientation {
            n = -n;
        }
        (p, n)
    }

    /// A point by area; `pdf` is w.r.t. world-space area.
    pub fn sample_area(&self, s: &QuadricSampler, u: [f32; 2]) -> ShapeSample {
        if let QuadricSampler::Pbrt { object_area, uv } = s {
            return self.sample_area_pbrt(*object_area, *uv, u);
        }
        let (uv, p_uv) = self.sample_uv(s, [u[0] as f64, u[1] as f64]);
        let (p, n) = self.point_normal(uv);
        let pdf = match p_uv {
            None => self.pdf_area_uv(s, uv),
            Some(p_uv) => p_uv / self.area_element(uv[0], uv[1]),
        };
        let uv = uv.map(|x| x as f32);
        ShapeSample { p: Point3(p.as_vec3()), n: Normal3(n.as_vec3()), uv, pdf: pdf as f32 }
    }

    /// The world centre and radius of a full sphere under a similarity transform.
    fn full_sphere(&self) -> Option<(DVec3, f64)> {
        let Quadric::Sphere(s) = &self.quadric else { return None };
        let full = s.z_min <= -s.radius && s.z_max >= s.radius && s.phi_max as f64 >= TAU - 1e-6;
        let s2 = super::similarity_scale(self.linear())?;
        full.then(|| (self.render_from_object.transform_point3(DVec3::ZERO), s.radius as f64 * s2.sqrt()))
    }

    /// A point as seen from `reference`; `pdf` is w.r.t. solid angle at `reference`.
    /// Full spheres seen from outside sample the cone they subtend (pbrt); everything
    /// else converts an area sample.
    pub fn sample_solid_angle(&self, s: &QuadricSampler, reference: Point3, u: [f32; 2]) -> Option<ShapeSample> {
        if let QuadricSampler::Pbrt { object_area, uv } = s {
            return self.sample_solid_angle_pbrt(*object_area, *uv, reference, u);
        }
        let r = reference.0.as_dvec3();
        if let Some((c, radius)) = self.full_sphere() {
            let d2 = (c - r).length_squared();
            if d2 > radius * radius * 1.0001 {
                return self.sample_sphere_cone(r, c, radius, u, true);
            }
        }
        area_to_solid_angle(self.sample_area(s, u), reference)
    }

    /// A point of the sphere (centre `c`, `radius`) seen from `r` through its cone of
    /// directions, with its (u, v) if `uv`.
    pub(super) fn sample_sphere_cone(
        &self,
        r: DVec3,
        c: DVec3,
        radius: f64,
        u: [f32; 2],
        uv: bool,
    ) -> Option<ShapeSample> {
        let axis = (c - r).normalize();
        let d2 = (c - r).length_squared();
        let cos_max = (1.0 - radius * radius / d2).max(0.0).sqrt();
        let cos_t = 1.0 - u[0] as f64 * (1.0 - cos_max);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = TAU * u[1] as f64;
        let (a, b) = crate::math::frame::coordinate_system(axis.as_vec3());
        let w = sin_t * phi.cos() * a.as_dvec3() + sin_t * phi.sin() * b.as_dvec3() + cos_t * axis;
        // The nearer intersection of the ray r + t w with the sphere.
        let oc = r - c;
        let bq = oc.dot(w);
        let disc = (bq * bq - (oc.length_squared() - radius * radius)).max(0.0);
        let t = -bq - disc.sqrt();
        let p = r + t * w;
        let mut n = (p - c).normalize();
        if self.reverse_orientation != (DMat3::from_mat4(self.render_from_object).determinant() < 0.0) {
            n = -n;
        }
        let pdf = 1.0 / (TAU * (1.0 - cos_max));
        let uv = match uv {
            true => self.uv_of_object_point(self.object_from_render.transform_point3(p)).map(|x| x as f32),
            false => [0.0; 2],
        };
        Some(ShapeSample { p: Point3(p.as_vec3()), n: Normal3(n.as_vec3()), uv, pdf: pdf as f32 })
    }

    /// The area density [`QuadricShape::sample_area`] gives the surface point `p`.
    pub fn pdf_area(&self, s: &QuadricSampler, p: Point3) -> f32 {
        if let QuadricSampler::Pbrt { object_area, .. } = s {
            return (1.0 / object_area) as f32;
        }
        let uv = self.uv_of_object_point(self.object_from_render.transform_point3(p.0.as_dvec3()));
        self.pdf_area_uv(s, uv) as f32
    }

    /// The solid-angle density of [`QuadricShape::sample_solid_angle`] for direction `wi`
    /// (0 when the ray misses).
    pub fn pdf_solid_angle(&self, s: &QuadricSampler, reference: Point3, wi: Vector3) -> f32 {
        if let QuadricSampler::Pbrt { object_area, .. } = s {
            return self.pdf_solid_angle_pbrt(*object_area, reference, wi);
        }
        let ray = Ray::new(reference, wi);
        let Some(hit) = self.intersect_t(&ray, f32::INFINITY) else { return 0.0 };
        if let Some((c, radius)) = self.full_sphere() {
            let d2 = (c - reference.0.as_dvec3()).length_squared();
            if d2 > radius * radius * 1.0001 {
                let cos_max = (1.0 - radius * radius / d2).max(0.0).sqrt();
                return (1.0 / (TAU * (1.0 - cos_max))) as f32;
            }
        }
        let si = self.interaction(&hit);
        let pdf_a = self.pdf_area_uv(s, self.uv_of(&hit));
        let d2 = (si.p.0.as_dvec3() - reference.0.as_dvec3()).length_squared();
        let cos = si.n.0.as_dvec3().dot(-wi.0.as_dvec3().normalize()).abs();
        if cos == 0.0 { 0.0 } else { (pdf_a * d2 / cos) as f32 }
    }
}

/// Converts an area-density sample to solid angle at `reference`.
pub fn area_to_solid_angle(s: ShapeSample, reference: Point3) -> Option<ShapeSample> {
    let d = (s.p.0 - reference.0).as_dvec3();
    let dist2 = d.length_squared();
    if dist2 == 0.0 {
        return None;
    }
    let cos = s.n.0.as_dvec3().dot(-d / dist2.sqrt()).abs();
    if cos == 0.0 {
        return None;
    }
    Some(ShapeSample { pdf: (s.pdf as f64 * dist2 / cos) as f32, ..s })
}

impl TriangleMesh {
    /// A point uniformly on one triangle (pbrt-v4's low-distortion mapping); pdf = 1/area.
    /// The normal follows the intersection rule (N decides the side when present).
    pub fn sample_triangle(&self, tri: usize, u: [f32; 2], flags: super::MeshFlags) -> ShapeSample {
        let [p0, p1, p2] = self.vertices(tri);
        let (b0, b1) = if u[0] < u[1] {
            let b0 = u[0] as f64 / 2.0;
            (b0, u[1] as f64 - b0)
        } else {
            let b1 = u[1] as f64 / 2.0;
            (u[0] as f64 - b1, b1)
        };
        let b2 = 1.0 - b0 - b1;
        let p = b0 * p0 + b1 * p1 + b2 * p2;
        let mut n = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        if let Some(ns) = &self.n {
            let i = &self.indices[3 * tri..3 * tri + 3];
            let v = |k: usize| DVec3::from(ns[i[k] as usize].map(f64::from));
            let interp = b0 * v(0) + b1 * v(1) + b2 * v(2);
            let interp = if flags.reverse_orientation { -interp } else { interp };
            if n.dot(interp) < 0.0 {
                n = -n;
            }
        } else if flags.reverse_orientation ^ flags.swaps_handedness {
            n = -n;
        }
        let area = 0.5 * (p1 - p0).cross(p2 - p0).length();
        let [t0, t1, t2] = self.uvs(tri);
        let uv = (b0 as f32 * t0 + b1 as f32 * t1 + b2 as f32 * t2).to_array();
        ShapeSample { p: Point3(p.as_vec3()), n: Normal3(n.as_vec3()), uv, pdf: (1.0 / area) as f32 }
    }

    /// The area density of `sample_triangle`: one over the triangle's area.
    pub fn pdf_triangle_area(&self, tri: usize) -> f32 {
        let [p0, p1, p2] = self.vertices(tri);
        (2.0 / (p1 - p0).cross(p2 - p0).length()) as f32
    }

    /// Solid-angle density of area-sampling triangle `tri` from `reference` along `wi`.
    pub fn pdf_triangle_solid_angle(&self, tri: usize, reference: Point3, wi: Vector3) -> f32 {
        let Some(hit) = self.intersect_triangle(tri, &Ray::new(reference, wi), f32::INFINITY) else { return 0.0 };
        let [p0, p1, p2] = self.vertices(tri);
        let area = 0.5 * (p1 - p0).cross(p2 - p0).length();
        let d = wi.0.as_dvec3() * hit.t as f64;
        let n = (p1 - p0).cross(p2 - p0).normalize();
        let cos = n.dot(wi.0.as_dvec3().normalize()).abs();
        if cos == 0.0 { 0.0 } else { (d.length_squared() / (cos * area)) as f32 }
    }
}
