//! Render-ready quadrics: intersection, interaction and bounds of the six quadrics
//! under their transform.
//!
//! Each quadric's own file (`sphere.rs`, …) implements [`QuadricSurface`]: its implicit
//! form, ranges and (u, v) derivatives, and where it needs one its own root finder
//! (the disk) or refinement (sphere, cylinder). This file holds what they share: the
//! object-space ray with rounding bounds, the default quadratic solve, and the move
//! from object-space derivatives to a render-space [`SurfaceInteraction`].
//!
//! Intersection is two-stage, as in pbrt-v4: [`QuadricShape::intersect_t`] finds the hit
//! parameter and object-space point (used during traversal and for shadow rays);
//! [`QuadricShape::interaction`] builds the full differential geometry for the closest
//! hit only.
//!
//! DEVIATION(pbrt): robustness. The ray is taken to object space and the quadratic solved with
//! [`EFloat64`] intervals (pbrt uses f32 `EFloat`, which fails pbrt's own reintersection
//! test for cones and paraboloids, pbrt-v3 #44). Hits are refined onto the surface in
//! f64, so the stored f32 point is within about one ulp of the true surface; `p_error`
//! bounds that, and spawned rays clear it.
//! The hyperboloid is intersected as pbrt-v3 does, as its implicit fit, by default,
//! and as the surface its segment sweeps with `--fix hyperboloid-surface` (see
//! `hyperboloid`).

use super::Quadric;
use crate::interaction::{Shading, SurfaceInteraction};
use crate::math::float::{gamma, gamma64};
use crate::math::{Bounds3, EFloat64, Normal3, Point3, Ray, Vector3};
use glam::{DMat3, DMat4, DVec3, Vec3};
use std::f64::consts::TAU;

pub(super) type E = EFloat64;

/// A quadric with its transform and orientation, ready to intersect.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadricShape {
    pub quadric: Quadric,
    pub render_from_object: DMat4,
    pub object_from_render: DMat4,
    pub reverse_orientation: bool,
    /// ∂n/∂u and ∂n/∂v as pbrt makes them (see [`QuadricShape::interaction`]).
    pub pbrt_normal_derivatives: bool,
}

/// The cheap result of a ray–quadric test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricHit {
    pub t: f32,
    pub p_obj: DVec3,
    pub phi: f64,
}

/// Object-space derivatives at a hit: (u, v), ∂p/∂u, ∂p/∂v and the second derivatives
/// (for ∂n/∂u and ∂n/∂v by the Weingarten equations).
pub struct Local {
    pub uv: [f64; 2],
    pub dpdu: DVec3,
    pub dpdv: DVec3,
    pub d2_uu: DVec3,
    pub d2_uv: DVec3,
    pub d2_vv: DVec3,
}

impl QuadricShape {
    pub fn new(quadric: Quadric, render_from_object: DMat4, reverse_orientation: bool) -> QuadricShape {
        QuadricShape {
            quadric,
            object_from_render: render_from_object.inverse(),
            render_from_object,
            reverse_orientation,
            pbrt_normal_derivatives: false,
        }
    }

    /// Render-space bounds of the object bounds' corners, widened by a few ulps.
    pub fn bounds(&self) -> Bounds3 {
        crate::math::bounds::transform_bounds_widened(&self.render_from_object, self.quadric.object_bounds())
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
        let (t, p_obj, phi) = dispatch_quadric!(&self.quadric, s => s.hit(o, d, t_max))?;
        Some(QuadricHit { t: t as f32, p_obj, phi })
    }

    /// Any hit before t_max (shadow rays).
    pub fn intersect_p(&self, r: &Ray, t_max: f32) -> bool {
        self.intersect_t(r, t_max).is_some()
    }

    /// (u, v) of a hit in f64 (the interaction stores them rounded to f32).
    pub fn uv_of(&self, hit: &QuadricHit) -> [f64; 2] {
        dispatch_quadric!(&self.quadric, s => s.local(hit.p_obj, hit.phi).uv)
    }

    /// (u, v) of an object-space point on the surface.
    pub fn uv_of_object_point(&self, p_obj: DVec3) -> [f64; 2] {
        dispatch_quadric!(&self.quadric, s => s.local(p_obj, phi_of(p_obj.x, p_obj.y)).uv)
    }

    /// The object-space derivatives at a hit. On the axis ∂p/∂u vanishes (a sphere's
    /// pole, a cone's apex, a paraboloid's vertex, a disk's centre) and ∂p/∂v may be
    /// infinite, so there they are those of the surface point 2^-20 away in v, at the
    /// hit's φ: the limit of the frame along that meridian. (u, v) stay the hit's.
    // DEVIATION(pbrt): robustness. pbrt moves only the sphere's pole hits (x = 1e-5 r); its cone,
    // paraboloid and disk give a NaN normal there.
    fn local_at(&self, hit: &QuadricHit) -> Local {
        let l = dispatch_quadric!(&self.quadric, s => s.local(hit.p_obj, hit.phi));
        let n = l.dpdu.cross(l.dpdv);
        if n.is_finite() && n.length_squared() > 0.0 {
            return l;
        }
        let [u, v] = l.uv;
        let near = self.quadric.point(u, if v > 0.5 { v - 2f64.powi(-20) } else { v + 2f64.powi(-20) });
        let moved = dispatch_quadric!(&self.quadric, s => s.local(near, hit.phi));
        Local { uv: l.uv, ..moved }
    }

    /// What maps object-space normals to render space: the inverse transpose of the
    /// linear part of render-from-object.
    pub(super) fn normal_matrix(&self) -> DMat3 {
        DMat3::from_mat4(self.object_from_render).transpose()
    }

    /// The geometric normal at an object-space hit: `n`, the normal of the (u, v)
    /// parametrisation, unless the surface intersected is another one (pbrt-v3's
    /// implicit hyperboloid), whose own normal, on `n`'s side, rays are spawned from.
    // DEVIATION(pbrt): robustness. pbrt-v3 offsets rays from its hyperboloid along the
    // parametrisation's normal, which is not the implicit surface's: rays leave on the
    // wrong side of it and re-hit it. Its shading normal stays pbrt's.
    fn geometric_normal(&self, p_obj: DVec3, n: DVec3) -> DVec3 {
        let Quadric::Hyperboloid(h) = &self.quadric else { return n };
        if !h.implicit_fit {
            return n;
        }
        let (_, g) = h.implicit(p_obj);
        let g = (self.normal_matrix() * g).normalize_or_zero();
        match g.dot(n) {
            d if g == DVec3::ZERO || !d.is_finite() => n,
            d if d < 0.0 => -g,
            _ => g,
        }
    }

    /// Full differential geometry at a hit found by [`QuadricShape::intersect_t`].
    pub fn interaction(&self, hit: &QuadricHit) -> SurfaceInteraction {
        let l = self.local_at(hit);
        let m = self.render_from_object;
        let m3 = DMat3::from_mat4(m);
        // The map is affine, so world derivatives of every order are m3 times the
        // object ones; Weingarten on those gives the derivatives of the world normal.
        let world = Local {
            uv: l.uv,
            dpdu: m3 * l.dpdu,
            dpdv: m3 * l.dpdv,
            d2_uu: m3 * l.d2_uu,
            d2_uv: m3 * l.d2_uv,
            d2_vv: m3 * l.d2_vv,
        };
        let (dpdu, dpdv) = (world.dpdu, world.dpdv);
        let n = dpdu.cross(dpdv).normalize_or_zero();
        let n = if self.reverse_orientation { -n } else { n };
        // DEVIATION(pbrt): appearance, `--fix normal-derivatives`. pbrt transforms the
        // object-space ∂n/∂u and ∂n/∂v as normals (off by the scale under scaling) and
        // does not flip them with ReverseOrientation, which bump maps then use; the fix
        // uses the derivatives of the normal reported.
        let (dndu, dndv) = if self.pbrt_normal_derivatives {
            let ((du, dv), normals) = (weingarten(&l), self.normal_matrix());
            (normals * du, normals * dv)
        } else {
            let (du, dv) = weingarten(&world);
            if self.reverse_orientation { (-du, -dv) } else { (du, dv) }
        };
        let p = m.transform_point3(hit.p_obj);
        let p32 = p.as_vec3();
        // The f32 rounding of p, the f64 work before it, and any distance left between
        // the refined point and the surface (mapped by the largest column of m).
        let off_surface = dispatch_quadric!(&self.quadric, s => s.residual(hit.p_obj)) * (m3.abs() * DVec3::ONE);
        let f64_slop = gamma64(16) * (m3.abs() * hit.p_obj.abs() + m.w_axis.truncate().abs() + p.abs()) + off_surface;
        let p_error = gamma(2) * p32.abs() + f64_slop.as_vec3() + Vec3::splat(f32::MIN_POSITIVE);
        let nv = Normal3(n.as_vec3());
        let ng = Normal3(self.geometric_normal(hit.p_obj, n).as_vec3());
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
            n: ng,
            dpdu: shading.dpdu,
            dpdv: shading.dpdv,
            dndu: shading.dndu,
            dndv: shading.dndv,
            shading,
            time: 0.0,
            face: 0,
        }
    }
}

/// Newton steps along ∇F onto the surface F = 0.
pub(super) fn newton<S: QuadricSurface + ?Sized>(s: &S, p: DVec3) -> DVec3 {
    let mut p = p;
    for _ in 0..8 {
        let (f, g) = s.implicit(p);
        let g2 = g.length_squared();
        if g2 == 0.0 || f * f / g2 <= (1e-15 * p.length()).powi(2) {
            break;
        }
        p -= g * (f / g2);
    }
    p
}

/// The point at parameter t along an object-space ray.
pub(super) fn at(o: [E; 3], d: [E; 3], t: f64) -> DVec3 {
    DVec3::new(o[0].value() + t * d[0].value(), o[1].value() + t * d[1].value(), o[2].value() + t * d[2].value())
}

/// φ in [0, 2π).
pub(super) fn phi_of(x: f64, y: f64) -> f64 {
    let phi = y.atan2(x);
    if phi < 0.0 { phi + TAU } else { phi }
}

/// What each quadric's own file supplies for intersection and differential geometry,
/// all in object space and f64. The defaults are the shared method: solve the quadratic
/// with rounding bounds, move each root onto the surface by Newton steps on the
/// implicit function, and keep the first that lies in the z range and under φmax.
pub trait QuadricSurface {
    /// a t² + b t + c = F(o + t d), F the implicit function, with rounding bounds.
    fn coefficients(&self, o: [E; 3], d: [E; 3]) -> (E, E, E);

    /// F(p) and ∇F(p); F = 0 on the surface.
    fn implicit(&self, p: DVec3) -> (f64, DVec3);

    /// zmin, zmax and φmax, which a hit must respect.
    fn ranges(&self) -> (f64, f64, f64);

    /// (u, v) and the derivatives of p at an object-space hit with azimuth φ.
    fn local(&self, p: DVec3, phi: f64) -> Local;

    /// Moves a point near the surface onto it: Newton steps along ∇F (flat or narrow
    /// shapes need a few).
    fn refine(&self, p: DVec3) -> DVec3 {
        newton(self, p)
    }

    /// An upper bound on the distance from p to the surface: |F|/|∇F| is the distance
    /// to first order; doubled for the rest.
    fn residual(&self, p: DVec3) -> f64 {
        let (f, g) = self.implicit(p);
        let g = g.length();
        if g > 0.0 { 2.0 * f.abs() / g } else { 0.0 }
    }

    /// φ if the (refined) point lies in the z range and the φ range.
    fn accept(&self, p: DVec3) -> Option<f64> {
        let (z0, z1, phi_max) = self.ranges();
        if p.z < z0 || p.z > z1 {
            return None;
        }
        let phi = phi_of(p.x, p.y);
        (phi <= phi_max).then_some(phi)
    }

    /// The roots of F(o + t d) = 0. A negative discriminant that rounding could have
    /// made negative is tried again from the point midway between the roots, where a,
    /// b and c no longer cancel.
    // DEVIATION(pbrt): robustness. Where two roots nearly meet without tangency (a ray through a
    // cone's apex enters one nappe and leaves the other), b² − 4ac computed from the
    // ray's origin cancels to a negative number and pbrt reports a miss.
    fn roots(&self, o: [E; 3], d: [E; 3]) -> Option<(E, E)> {
        let (a, b, c) = self.coefficients(o, d);
        if let Some(roots) = E::quadratic(a, b, c) {
            return Some(roots);
        }
        // Clear misses (most rays that reach a quadric's bounds) stop here.
        if (b * b - a * c * 4.0).upper() < 0.0 {
            return None;
        }
        let mid = -b.value() / (2.0 * a.value());
        if !mid.is_finite() {
            return None;
        }
        let m = E::from(mid);
        let (a, b, c) = self.coefficients([o[0] + d[0] * m, o[1] + d[1] * m, o[2] + d[2] * m], d);
        let (t0, t1) = E::quadratic(a, b, c)?;
        Some((t0 + m, t1 + m))
    }

    /// The first hit (t, object-space point, φ) with 0 < t < t_max.
    fn hit(&self, o: [E; 3], d: [E; 3], t_max: f64) -> Option<(f64, DVec3, f64)> {
        let (t0, t1) = self.roots(o, d)?;
        if t0.upper() > t_max || t1.lower() <= 0.0 {
            return None;
        }
        let try_root = |t: E| {
            let p = self.refine(at(o, d, t.value()));
            self.accept(p).map(|phi| (t.value(), p, phi))
        };
        if t0.lower() > 0.0
            && let Some(hit) = try_root(t0)
        {
            return Some(hit);
        }
        if t1.upper() > t_max {
            return None;
        }
        try_root(t1)
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
