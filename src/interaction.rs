//! Surface interactions and robust ray spawning (pbrt-v3 `core/interaction.h`).
//!
//! A hit point carries `p_error`, a conservative bound on the distance between the
//! stored `f32` point and the true surface. Rays leaving the surface start at
//! [`offset_ray_origin`]: moved along the normal far enough that the error box lies on
//! the side the ray goes to, then one more ulp away, so a ray never re-hits the surface
//! it leaves.

use crate::math::float::UlpStep;
use crate::math::ray::RayDifferential;
use crate::math::{Normal3, Point3, Ray, Vector3};
use glam::Vec3;

/// pbrt's shadow epsilon for rays towards a point.
pub const SHADOW_EPSILON: f32 = 0.0001;

/// Shading geometry (differs from the geometric one for meshes with normals).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Shading {
    pub n: Normal3,
    pub dpdu: Vector3,
    pub dpdv: Vector3,
    pub dndu: Normal3,
    pub dndv: Normal3,
}

/// A ray–surface hit with pbrt's differential geometry.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceInteraction {
    pub p: Point3,
    pub p_error: Vec3,
    /// The ray parameter of the hit, in units of the ray's direction.
    pub t: f32,
    pub uv: [f32; 2],
    /// Unit geometric normal, oriented by pbrt's rules (never turned toward the ray).
    pub n: Normal3,
    pub dpdu: Vector3,
    pub dpdv: Vector3,
    pub dndu: Normal3,
    pub dndv: Normal3,
    pub shading: Shading,
    /// The time of the ray that found it (motion blur); rays spawned here carry it.
    pub time: f32,
    /// The mesh face's index from `faceIndices` (0 without them, as in pbrt).
    pub face: i32,
}

/// The origin for a ray leaving `p` in direction `w`.
pub fn offset_ray_origin(p: Point3, p_error: Vec3, n: Normal3, w: Vector3) -> Point3 {
    let d = n.0.abs().dot(p_error);
    let mut offset = n.0 * d;
    if n.dot(w) < 0.0 {
        offset = -offset;
    }
    let mut po = p.0 + offset;
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = po[i].step_up();
        } else if offset[i] < 0.0 {
            po[i] = po[i].step_down();
        }
    }
    Point3(po)
}

/// Where direct light is sampled from at a surface point `p` (error `p_error`, normal
/// `n`) seen from `wo`: pbrt-v3 uses the point; pbrt-v4 (`v4`) moves it as a spawned
/// ray's origin is moved, to the side light leaves by when only one side does (`sides`:
/// reflects, transmits; its `SampleLd`). That is an ulp or so for most shapes, but a
/// curve's error bound is its width: a point light near a wide curve is that much
/// nearer to it in pbrt-v4.
pub fn light_sample_point(v4: bool, p: Point3, p_error: Vec3, n: Normal3, sides: (bool, bool), wo: Vec3) -> Point3 {
    match (v4, sides) {
        (true, (true, false)) => offset_ray_origin(p, p_error, n, Vector3(wo)),
        (true, (false, true)) => offset_ray_origin(p, p_error, n, Vector3(-wo)),
        _ => p,
    }
}

impl SurfaceInteraction {
    pub fn spawn_ray(&self, d: Vector3) -> Ray {
        Ray::new(offset_ray_origin(self.p, self.p_error, self.n, d), d).at_time(self.time)
    }

    /// A ray from here to `p2` with `t_max` just short of it.
    pub fn spawn_ray_to(&self, p2: Point3) -> Ray {
        let o = offset_ray_origin(self.p, self.p_error, self.n, p2 - self.p);
        Ray { o, d: p2 - o, t_max: 1.0 - SHADOW_EPSILON, time: self.time }
    }

    /// The interaction seen through the f64 affine map `m` (instance to world).
    ///
    /// `p_error` in world space covers the rounding of the new point to f32, the old
    /// error mapped through `m`, and the f32 rounding a ray spawned from here meets when
    /// it is mapped back into instance space, so spawned rays clear the surface there.
    // DEVIATION(pbrt): robustness. pbrt transforms instances in f32; the rounded matrix and its
    // rounded inverse do not compose to the identity, which lets spawned rays re-hit
    // mirrored or strongly scaled instances. Instances use f64 maps here.
    pub fn transformed_f64(&self, m: &glam::DAffine3) -> SurfaceInteraction {
        let m3 = m.matrix3;
        let normal_m = m3.inverse().transpose();
        let p_i = self.p.0.as_dvec3();
        let p = m.transform_point3(p_i);
        let p32 = p.as_vec3();
        let abs_m = m3.abs();
        let back = abs_m * (crate::math::float::gamma(2) as f64 * p_i.abs());
        let err =
            abs_m * self.p_error.as_dvec3() + back + crate::math::float::gamma64(8) * (abs_m * p_i.abs() + p.abs());
        let p_error = crate::math::float::gamma(2) * p32.abs() + err.as_vec3();
        let v = |x: Vector3| Vector3((m3 * x.0.as_dvec3()).as_vec3());
        let nrm = |x: Normal3| Normal3((normal_m * x.0.as_dvec3()).as_vec3());
        let n = Normal3((normal_m * self.n.0.as_dvec3()).normalize_or_zero().as_vec3());
        let shading_n =
            Normal3((normal_m * self.shading.n.0.as_dvec3()).normalize_or_zero().as_vec3()).face_forward(n.into());
        SurfaceInteraction {
            p: Point3(p32),
            p_error,
            t: self.t,
            uv: self.uv,
            n,
            dpdu: v(self.dpdu),
            dpdv: v(self.dpdv),
            dndu: nrm(self.dndu),
            dndv: nrm(self.dndv),
            shading: Shading {
                n: shading_n,
                dpdu: v(self.shading.dpdu),
                dpdv: v(self.shading.dpdv),
                dndu: nrm(self.shading.dndu),
                dndv: nrm(self.shading.dndv),
            },
            time: self.time,
            face: self.face,
        }
    }
}

/// How a hit point moves across one pixel: ∂p/∂x and ∂p/∂y, from the camera ray's
/// differentials (pbrt's `ComputeDifferentials`). Zero without differentials.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    pub dpdx: Vec3,
    pub dpdy: Vec3,
}

impl Footprint {
    /// Where the differential rays meet the hit's tangent plane; zero where they run
    /// parallel to it.
    pub fn new(si: &SurfaceInteraction, rd: &RayDifferential) -> Footprint {
        let (p, n) = (si.p.0, si.n.0);
        let on_plane = |r: &Ray| {
            let t = -(n.dot(r.o.0) - n.dot(p)) / n.dot(r.d.0);
            t.is_finite().then(|| r.o.0 + t * r.d.0 - p)
        };
        match (on_plane(&rd.rx), on_plane(&rd.ry)) {
            (Some(dpdx), Some(dpdy)) => Footprint { dpdx, dpdy },
            _ => Footprint::default(),
        }
    }

    /// (∂u/∂x, ∂v/∂x, ∂u/∂y, ∂v/∂y) at `si`: the (u, v) offsets that reach `dpdx` and
    /// `dpdy`, solved in the two axes the normal leaves best conditioned (pbrt's rule);
    /// zero where that fails.
    pub fn duv_dxy(&self, si: &SurfaceInteraction) -> [f32; 4] {
        let [a, b] = match si.n.0.abs() {
            m if m.x > m.y && m.x > m.z => [1, 2],
            m if m.y > m.z => [0, 2],
            _ => [0, 1],
        };
        let (du, dv) = (si.dpdu.0, si.dpdv.0);
        let det = du[a] * dv[b] - dv[a] * du[b];
        if det.abs() < 1e-10 {
            return [0.0; 4];
        }
        let solve = |d: Vec3| [(dv[b] * d[a] - dv[a] * d[b]) / det, (du[a] * d[b] - du[b] * d[a]) / det];
        let ([dudx, dvdx], [dudy, dvdy]) = (solve(self.dpdx), solve(self.dpdy));
        let all = [dudx, dvdx, dudy, dvdy];
        if all.iter().all(|x| x.is_finite()) { all } else { [0.0; 4] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pbrt_v4_samples_lights_from_the_side_light_leaves_by() {
        let (p, err, n) = (Point3(Vec3::new(1.0, 2.0, 0.0)), Vec3::splat(0.25), Normal3(Vec3::Z));
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let at = |v4, sides| light_sample_point(v4, p, err, n, sides, wo).0;
        assert_eq!(at(false, (true, false)), p.0, "pbrt-v3: the point itself");
        assert_eq!(at(true, (true, true)), p.0, "both sides: the point itself");
        assert!(at(true, (true, false)).z >= 0.25, "reflecting: toward wo's side");
        assert!(at(true, (false, true)).z <= -0.25, "transmitting: the other side");
    }

    /// A hit at the origin of the plane z = 0 with p(u, v) = (2u, 3v, 0).
    fn plane_hit() -> SurfaceInteraction {
        SurfaceInteraction {
            n: Normal3(Vec3::Z),
            dpdu: Vector3(Vec3::new(2.0, 0.0, 0.0)),
            dpdv: Vector3(Vec3::new(0.0, 3.0, 0.0)),
            ..Default::default()
        }
    }

    #[test]
    fn footprint_follows_the_differential_rays_to_the_tangent_plane() {
        let si = plane_hit();
        // Rays one pixel over start 0.1 to the side and lean: they meet z = 0 at
        // (0.1 + 0.05, 0, 0) and (0, 0.2 − 0.1, 0).
        let rx = Ray::new(Point3::new(0.1, 0.0, 1.0), Vector3::new(0.05, 0.0, -1.0));
        let ry = Ray::new(Point3::new(0.0, 0.2, 2.0), Vector3::new(0.0, -0.05, -1.0));
        let fp = Footprint::new(&si, &RayDifferential { rx, ry });
        assert!((fp.dpdx - Vec3::new(0.15, 0.0, 0.0)).length() < 1e-6, "{:?}", fp.dpdx);
        assert!((fp.dpdy - Vec3::new(0.0, 0.1, 0.0)).length() < 1e-6, "{:?}", fp.dpdy);
        let [dudx, dvdx, dudy, dvdy] = fp.duv_dxy(&si);
        assert!((dudx - 0.075).abs() < 1e-6 && dvdx.abs() < 1e-6, "{dudx} {dvdx}");
        assert!(dudy.abs() < 1e-6 && (dvdy - 0.1 / 3.0).abs() < 1e-6, "{dudy} {dvdy}");
    }

    #[test]
    fn rays_parallel_to_the_plane_give_no_footprint() {
        let si = plane_hit();
        let flat = Ray::new(Point3::new(0.0, 0.0, 1.0), Vector3::new(1.0, 0.0, 0.0));
        let fp = Footprint::new(&si, &RayDifferential { rx: flat, ry: flat });
        assert_eq!(fp, Footprint::default());
        assert_eq!(fp.duv_dxy(&si), [0.0; 4]);
    }
}
