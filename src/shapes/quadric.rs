//! Render-ready quadrics: intersection, interaction and bounds of the six quadrics
//! under their transform.
//!
//! Intersection is two-stage, as in pbrt-v4: [`QuadricShape::intersect_t`] finds the hit
//! parameter and object-space point (used during traversal and for shadow rays);
//! [`QuadricShape::interaction`] builds the full differential geometry for the closest
//! hit only.
//!
//! DEVIATION(pbrt): the ray is taken to object space and the quadratic solved with
//! [`EFloat64`] intervals (pbrt uses f32 `EFloat`, which fails pbrt's own reintersection
//! test for cones and paraboloids, pbrt-v3 #44). Hits are refined onto the surface in
//! f64, so the stored f32 point is within about one ulp of the true surface; `p_error`
//! bounds that, and spawned rays clear it.
//! DEVIATION(pbrt): the hyperboloid is intersected as the surface swept by the segment
//! p1→p2 (the surface its (u,v) and area describe); pbrt intersects an implicit form
//! with its waist at z = 0, which differs unless the segment's closest approach to the
//! axis is at z = 0 (pbrt-v3 #168).

use super::{Hyperboloid, Quadric};
use crate::interaction::{Shading, SurfaceInteraction};
use crate::math::float::{gamma, gamma64};
use crate::math::{Bounds3, EFloat64, Normal3, Point3, Ray, Vector3};
use glam::{DMat3, DMat4, DVec3, Vec3};
use std::f64::consts::TAU;

type E = EFloat64;

/// A quadric with its transform and orientation, ready to intersect.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadricShape {
    pub quadric: Quadric,
    pub render_from_object: DMat4,
    pub object_from_render: DMat4,
    pub reverse_orientation: bool,
}

/// The cheap result of a ray–quadric test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricHit {
    pub t: f32,
    pub p_obj: DVec3,
    pub phi: f64,
}

/// Object-space derivatives at a hit.
struct Local {
    uv: [f64; 2],
    dpdu: DVec3,
    dpdv: DVec3,
    d2_uu: DVec3,
    d2_uv: DVec3,
    d2_vv: DVec3,
}

impl QuadricShape {
    pub fn new(quadric: Quadric, render_from_object: DMat4, reverse_orientation: bool) -> QuadricShape {
        QuadricShape {
            quadric,
            object_from_render: render_from_object.inverse(),
            render_from_object,
            reverse_orientation,
        }
    }

    /// Render-space bounds of the object bounds' corners, widened by a few ulps.
    pub fn bounds(&self) -> Bounds3 {
        let b = crate::math::bounds::transform_bounds(&self.render_from_object, self.quadric.object_bounds());
        let grow = |v: DVec3, s: f64| (v + s * (v.abs() * 1e-6 + DVec3::splat(1e-30))).as_vec3();
        Bounds3 { min: grow(b[0], -1.0), max: grow(b[1], 1.0) }
    }

    /// The ray in object space, each coordinate with its f64 rounding bound.
    fn object_ray(&self, r: &Ray) -> ([E; 3], [E; 3]) {
        let m = self.object_from_render;
        let (o, d) = (r.o.0.as_dvec3(), r.d.0.as_dvec3());
        let row = |i: usize| m.row(i);
        let op = |i: usize| {
            let w = row(i);
            let v = w.x * o.x + w.y * o.y + w.z * o.z + w.w;
            let e = gamma64(4) * ((w.x * o.x).abs() + (w.y * o.y).abs() + (w.z * o.z).abs() + w.w.abs());
            E::new(v, e)
        };
        let dp = |i: usize| {
            let w = row(i);
            let v = w.x * d.x + w.y * d.y + w.z * d.z;
            E::new(v, gamma64(3) * ((w.x * d.x).abs() + (w.y * d.y).abs() + (w.z * d.z).abs()))
        };
        ([op(0), op(1), op(2)], [dp(0), dp(1), dp(2)])
    }

    /// The first hit with 0 < t < t_max, if any.
    pub fn intersect_t(&self, r: &Ray, t_max: f32) -> Option<QuadricHit> {
        let (o, d) = self.object_ray(r);
        let t_max = t_max as f64;
        let (t, p, phi) = match &self.quadric {
            Quadric::Disk(k) => {
                let h = k.height as f64;
                if d[2].value() == 0.0 {
                    return None;
                }
                let t = (E::from(h) - o[2]) / d[2];
                if t.lower() <= 0.0 || t.upper() >= t_max {
                    return None;
                }
                let mut p = at(o, d, t.value());
                let dist2 = p.x * p.x + p.y * p.y;
                let (r, ri) = (k.radius as f64, k.inner_radius as f64);
                if dist2 > r * r || dist2 < ri * ri {
                    return None;
                }
                p.z = h;
                let phi = phi_of(p.x, p.y);
                if phi > k.phi_max as f64 {
                    return None;
                }
                (t.value(), p, phi)
            }
            q => {
                let (a, b, c) = coefficients(q, o, d);
                let (t0, t1) = E::quadratic(a, b, c)?;
                if t0.upper() > t_max || t1.lower() <= 0.0 {
                    return None;
                }
                let try_root = |t: E| -> Option<(f64, DVec3, f64)> {
                    let p = refine(q, at(o, d, t.value()));
                    accept(q, p).map(|phi| (t.value(), p, phi))
                };
                if t0.lower() > 0.0
                    && let Some(hit) = try_root(t0)
                {
                    return Some(QuadricHit { t: hit.0 as f32, p_obj: hit.1, phi: hit.2 });
                }
                if t1.upper() > t_max {
                    return None;
                }
                try_root(t1)?
            }
        };
        Some(QuadricHit { t: t as f32, p_obj: p, phi })
    }

    /// Any hit before t_max (shadow rays).
    pub fn intersect_p(&self, r: &Ray, t_max: f32) -> bool {
        self.intersect_t(r, t_max).is_some()
    }

    /// (u, v) of a hit in f64 (the interaction stores them rounded to f32).
    pub fn uv_of(&self, hit: &QuadricHit) -> [f64; 2] {
        local(&self.quadric, hit.p_obj, hit.phi).uv
    }

    /// (u, v) of an object-space point on the surface.
    pub fn uv_of_object_point(&self, p_obj: DVec3) -> [f64; 2] {
        local(&self.quadric, p_obj, phi_of(p_obj.x, p_obj.y)).uv
    }

    /// Full differential geometry at a hit found by [`QuadricShape::intersect_t`].
    pub fn interaction(&self, hit: &QuadricHit) -> SurfaceInteraction {
        let l = local(&self.quadric, hit.p_obj, hit.phi);
        let m = self.render_from_object;
        let m3 = DMat3::from_mat4(m);
        // The map is affine, so world derivatives of every order are m3 times the
        // object ones; Weingarten on those gives the derivatives of the world normal.
        // DEVIATION(pbrt): pbrt transforms object-space ∂n/∂u as a normal (off by the
        // scale under scaling) and does not flip it with ReverseOrientation; ours are the
        // derivatives of the normal we report.
        let world = Local {
            uv: l.uv,
            dpdu: m3 * l.dpdu,
            dpdv: m3 * l.dpdv,
            d2_uu: m3 * l.d2_uu,
            d2_uv: m3 * l.d2_uv,
            d2_vv: m3 * l.d2_vv,
        };
        let (dpdu, dpdv) = (world.dpdu, world.dpdv);
        let mut n = dpdu.cross(dpdv).normalize_or_zero();
        let (mut dndu, mut dndv) = weingarten(&world);
        if self.reverse_orientation {
            (n, dndu, dndv) = (-n, -dndu, -dndv);
        }
        let p = m.transform_point3(hit.p_obj);
        let p32 = p.as_vec3();
        // The f32 rounding of p, the f64 work before it, and any distance left between
        // the refined point and the surface (mapped by the largest column of m).
        let off_surface = residual(&self.quadric, hit.p_obj) * (m3.abs() * DVec3::ONE);
        let f64_slop = gamma64(16) * (m3.abs() * hit.p_obj.abs() + m.w_axis.truncate().abs() + p.abs()) + off_surface;
        let p_error = gamma(2) * p32.abs() + f64_slop.as_vec3() + Vec3::splat(f32::MIN_POSITIVE);
        let nv = Normal3(n.as_vec3());
        let shading = Shading {
            n: nv,
            dpdu: Vector3(dpdu.as_vec3()),
            dpdv: Vector3(dpdv.as_vec3()),
            dndu: Normal3(dndu.as_vec3()),
            dndv: Normal3(dndv.as_vec3()),
        };
        SurfaceInteraction {
            p: Point3(p32),
            p_error,
            t: hit.t,
            uv: [l.uv[0] as f32, l.uv[1] as f32],
            n: nv,
            dpdu: shading.dpdu,
            dpdv: shading.dpdv,
            dndu: shading.dndu,
            dndv: shading.dndv,
            shading,
        }
    }
}

fn at(o: [E; 3], d: [E; 3], t: f64) -> DVec3 {
    DVec3::new(o[0].value() + t * d[0].value(), o[1].value() + t * d[1].value(), o[2].value() + t * d[2].value())
}

/// φ in [0, 2π).
fn phi_of(x: f64, y: f64) -> f64 {
    let phi = y.atan2(x);
    if phi < 0.0 { phi + TAU } else { phi }
}

/// Swept-surface coefficients of a hyperboloid: ρ²(v) = α v² + β v + γ, v = (z − z1)/Δz.
fn sweep(h: &Hyperboloid) -> (f64, f64, f64, f64, f64) {
    let (p1, p2) = (h.p1.as_dvec3(), h.p2.as_dvec3());
    let dl = p2 - p1;
    (dl.x * dl.x + dl.y * dl.y, 2.0 * (p1.x * dl.x + p1.y * dl.y), p1.x * p1.x + p1.y * p1.y, p1.z, dl.z)
}

/// a t² + b t + c for the implicit form F(o + t d) = 0.
fn coefficients(q: &Quadric, o: [E; 3], d: [E; 3]) -> (E, E, E) {
    let [ox, oy, oz] = o;
    let [dx, dy, dz] = d;
    match q {
        Quadric::Sphere(s) => {
            let r = s.radius as f64;
            (
                dx * dx + dy * dy + dz * dz,
                (dx * ox + dy * oy + dz * oz) * 2.0,
                ox * ox + oy * oy + oz * oz - E::from(r * r),
            )
        }
        Quadric::Cylinder(s) => {
            let r = s.radius as f64;
            (dx * dx + dy * dy, (dx * ox + dy * oy) * 2.0, ox * ox + oy * oy - E::from(r * r))
        }
        Quadric::Cone(s) => {
            let k = E::from(s.radius as f64 / s.height as f64);
            let k = k * k;
            let oz_h = oz - E::from(s.height as f64);
            (
                dx * dx + dy * dy - k * dz * dz,
                (dx * ox + dy * oy - k * dz * oz_h) * 2.0,
                ox * ox + oy * oy - k * oz_h * oz_h,
            )
        }
        Quadric::Paraboloid(s) => {
            let r = s.radius as f64;
            let k = E::from(s.z_max as f64) / E::from(r * r);
            (k * (dx * dx + dy * dy), k * (dx * ox + dy * oy) * 2.0 - dz, k * (ox * ox + oy * oy) - oz)
        }
        Quadric::Hyperboloid(h) => {
            let (al, be, ga, z1, dzl) = sweep(h);
            let (al, be, ga) = (E::from(al), E::from(be), E::from(ga));
            let v0 = (oz - E::from(z1)) / E::from(dzl);
            let vd = dz / E::from(dzl);
            (
                dx * dx + dy * dy - al * vd * vd,
                (dx * ox + dy * oy - al * v0 * vd) * 2.0 - be * vd,
                ox * ox + oy * oy - al * v0 * v0 - be * v0 - ga,
            )
        }
        Quadric::Disk(_) => (E::from(0.0), E::from(0.0), E::from(1.0)),
    }
}

/// Moves a hit onto the surface: radial re-projection for spheres and cylinders, one
/// Newton step on the implicit function for the others.
fn refine(q: &Quadric, p: DVec3) -> DVec3 {
    match q {
        Quadric::Sphere(s) => {
            let mut p = p * (s.radius as f64 / p.length());
            if p.x == 0.0 && p.y == 0.0 {
                p.x = 1e-5 * s.radius as f64;
            }
            p
        }
        Quadric::Cylinder(s) => {
            let k = s.radius as f64 / (p.x * p.x + p.y * p.y).sqrt();
            DVec3::new(p.x * k, p.y * k, p.z)
        }
        _ => {
            // Newton steps along the gradient; flat or narrow shapes need a few.
            let mut p = p;
            for _ in 0..8 {
                let (f, g) = implicit(q, p);
                let g2 = g.length_squared();
                if g2 == 0.0 || f * f / g2 <= (1e-15 * p.length()).powi(2) {
                    break;
                }
                p -= g * (f / g2);
            }
            p
        }
    }
}

/// An upper bound on the distance from an object-space point to the surface.
fn residual(q: &Quadric, p: DVec3) -> f64 {
    match q {
        Quadric::Sphere(s) => (p.length() - s.radius as f64).abs(),
        Quadric::Cylinder(s) => ((p.x * p.x + p.y * p.y).sqrt() - s.radius as f64).abs(),
        Quadric::Disk(k) => (p.z - k.height as f64).abs(),
        _ => {
            // |F|/|grad F| is the distance to first order; double it for the rest.
            let (f, g) = implicit(q, p);
            let g = g.length();
            if g > 0.0 { 2.0 * f.abs() / g } else { 0.0 }
        }
    }
}

/// The implicit function and its gradient.
fn implicit(q: &Quadric, p: DVec3) -> (f64, DVec3) {
    match q {
        Quadric::Cone(s) => {
            let k = (s.radius as f64 / s.height as f64).powi(2);
            let zh = p.z - s.height as f64;
            (p.x * p.x + p.y * p.y - k * zh * zh, DVec3::new(2.0 * p.x, 2.0 * p.y, -2.0 * k * zh))
        }
        Quadric::Paraboloid(s) => {
            let k = s.z_max as f64 / (s.radius as f64).powi(2);
            (k * (p.x * p.x + p.y * p.y) - p.z, DVec3::new(2.0 * k * p.x, 2.0 * k * p.y, -1.0))
        }
        Quadric::Hyperboloid(h) => {
            let (al, be, ga, z1, dzl) = sweep(h);
            let v = (p.z - z1) / dzl;
            let f = p.x * p.x + p.y * p.y - (al * v * v + be * v + ga);
            (f, DVec3::new(2.0 * p.x, 2.0 * p.y, -(2.0 * al * v + be) / dzl))
        }
        _ => (0.0, DVec3::ZERO),
    }
}

/// φ if the (refined) point lies in the shape's z range and φ range.
fn accept(q: &Quadric, p: DVec3) -> Option<f64> {
    let (phi, phi_max) = match q {
        Quadric::Hyperboloid(h) => {
            let (z0, z1) = (h.z_min as f64, h.z_max as f64);
            if p.z < z0 || p.z > z1 {
                return None;
            }
            let v = (p.z - h.p1.z as f64) / (h.p2.z as f64 - h.p1.z as f64);
            let pr = h.p1.as_dvec3().lerp(h.p2.as_dvec3(), v);
            (phi_of(pr.x * p.x + pr.y * p.y, pr.x * p.y - pr.y * p.x), h.phi_max)
        }
        _ => {
            let (z0, z1, phi_max) = match q {
                Quadric::Sphere(s) => (s.z_min, s.z_max, s.phi_max),
                Quadric::Cylinder(s) => (s.z_min, s.z_max, s.phi_max),
                Quadric::Cone(s) => (s.height.min(0.0), s.height.max(0.0), s.phi_max),
                Quadric::Paraboloid(s) => (s.z_min, s.z_max, s.phi_max),
                _ => return None,
            };
            if p.z < z0 as f64 || p.z > z1 as f64 {
                return None;
            }
            (phi_of(p.x, p.y), phi_max)
        }
    };
    (phi <= phi_max as f64).then_some(phi)
}

/// (u, v) and derivatives at an object-space hit (pbrt-v3's formulas; the hyperboloid
/// measures φ from the profile point p_r(v)).
fn local(q: &Quadric, p: DVec3, phi: f64) -> Local {
    let zero = DVec3::ZERO;
    match q {
        Quadric::Sphere(s) => {
            let (r, pm) = (s.radius as f64, s.phi_max as f64);
            let ta = (s.z_min as f64 / r).clamp(-1.0, 1.0).acos();
            let tb = (s.z_max as f64 / r).clamp(-1.0, 1.0).acos();
            let theta = (p.z / r).clamp(-1.0, 1.0).acos();
            let zr = (p.x * p.x + p.y * p.y).sqrt();
            let (cos_phi, sin_phi) = (p.x / zr, p.y / zr);
            let dt = tb - ta;
            Local {
                uv: [phi / pm, (theta - ta) / dt],
                dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
                dpdv: dt * DVec3::new(p.z * cos_phi, p.z * sin_phi, -r * theta.sin()),
                d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
                d2_uv: dt * p.z * pm * DVec3::new(-sin_phi, cos_phi, 0.0),
                d2_vv: -dt * dt * p,
            }
        }
        Quadric::Cylinder(s) => {
            let pm = s.phi_max as f64;
            let dz = s.z_max as f64 - s.z_min as f64;
            Local {
                uv: [phi / pm, (p.z - s.z_min as f64) / dz],
                dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
                dpdv: DVec3::new(0.0, 0.0, dz),
                d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
                d2_uv: zero,
                d2_vv: zero,
            }
        }
        Quadric::Disk(k) => {
            let (pm, r, ri) = (k.phi_max as f64, k.radius as f64, k.inner_radius as f64);
            let rho = (p.x * p.x + p.y * p.y).sqrt();
            let dpdv =
                if rho > 0.0 { DVec3::new(p.x, p.y, 0.0) * ((ri - r) / rho) } else { DVec3::new(ri - r, 0.0, 0.0) };
            Local {
                uv: [phi / pm, (r - rho) / (r - ri)],
                dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
                dpdv,
                d2_uu: zero,
                d2_uv: zero,
                d2_vv: zero,
            }
        }
        Quadric::Cone(s) => {
            let (pm, h) = (s.phi_max as f64, s.height as f64);
            let v = p.z / h;
            Local {
                uv: [phi / pm, v],
                dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
                dpdv: DVec3::new(-p.x / (1.0 - v), -p.y / (1.0 - v), h),
                d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
                d2_uv: pm / (1.0 - v) * DVec3::new(p.y, -p.x, 0.0),
                d2_vv: zero,
            }
        }
        Quadric::Paraboloid(s) => {
            let (pm, z0, z1) = (s.phi_max as f64, s.z_min as f64, s.z_max as f64);
            let dz = z1 - z0;
            Local {
                uv: [phi / pm, (p.z - z0) / dz],
                dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
                dpdv: dz * DVec3::new(p.x / (2.0 * p.z), p.y / (2.0 * p.z), 1.0),
                d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
                d2_uv: dz * pm * DVec3::new(-p.y / (2.0 * p.z), p.x / (2.0 * p.z), 0.0),
                d2_vv: -dz * dz * DVec3::new(p.x / (4.0 * p.z * p.z), p.y / (4.0 * p.z * p.z), 0.0),
            }
        }
        Quadric::Hyperboloid(h) => {
            let pm = h.phi_max as f64;
            let (p1, p2) = (h.p1.as_dvec3(), h.p2.as_dvec3());
            let v = (p.z - p1.z) / (p2.z - p1.z);
            let (sin_phi, cos_phi) = phi.sin_cos();
            let dl = p2 - p1;
            let dpdv = DVec3::new(dl.x * cos_phi - dl.y * sin_phi, dl.x * sin_phi + dl.y * cos_phi, dl.z);
            Local {
                uv: [phi / pm, v],
                dpdu: DVec3::new(-pm * p.y, pm * p.x, 0.0),
                dpdv,
                d2_uu: -pm * pm * DVec3::new(p.x, p.y, 0.0),
                d2_uv: pm * DVec3::new(-dpdv.y, dpdv.x, 0.0),
                d2_vv: zero,
            }
        }
    }
}

/// ∂n/∂u and ∂n/∂v from the Weingarten equations (object space).
fn weingarten(l: &Local) -> (DVec3, DVec3) {
    let n = l.dpdu.cross(l.dpdv).normalize_or_zero();
    let (e1, f1, g1) = (l.dpdu.dot(l.dpdu), l.dpdu.dot(l.dpdv), l.dpdv.dot(l.dpdv));
    let (e2, f2, g2) = (n.dot(l.d2_uu), n.dot(l.d2_uv), n.dot(l.d2_vv));
    let det = e1 * g1 - f1 * f1;
    if det == 0.0 || !det.is_finite() {
        return (DVec3::ZERO, DVec3::ZERO);
    }
    let inv = 1.0 / det;
    let dndu = (f2 * f1 - e2 * g1) * inv * l.dpdu + (e2 * f1 - f2 * e1) * inv * l.dpdv;
    let dndv = (g2 * f1 - f2 * g1) * inv * l.dpdu + (f2 * f1 - g2 * e1) * inv * l.dpdv;
    (dndu, dndv)
}
