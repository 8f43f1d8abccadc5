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
use crate::math::bounded::{Bounded64, Interval};
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
    /// ∂n/∂u and ∂n/∂v as pbrt makes them (see [`QuadricShape::normal_derivatives`]).
    pub pbrt_normal_derivatives: bool,
    /// ∂n/∂u and ∂n/∂v left at zero: only bump maps read them, and the scene has none.
    pub skip_normal_derivatives: bool,
}

/// The cheap result of a ray–quadric test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricHit {
    pub t: f32,
    pub p_obj: DVec3,
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
            skip_normal_derivatives: false,
        }
    }

    /// Render-space bounds of the object bounds' corners, widened by a few ulps.
    pub fn bounds(&self) -> Bounds3 {
        crate::math::bounds::transform_bounds_widened(&self.render_from_object, self.quadric.object_bounds())
    }

    /// The ray in object space, each coordinate with its f64 rounding bound.
    fn object_ray(&self, r: &Ray) -> ObjectRay {
        let m = self.object_from_render;
        let (o, d) = (r.o.0.as_dvec3(), r.d.0.as_dvec3());
        let row = |i: usize| m.row(i);
        let op = |i: usize| {
            let w = row(i);
            let v = w.x * o.x + w.y * o.y + w.z * o.z + w.w;
            (v, gamma64(4) * ((w.x * o.x).abs() + (w.y * o.y).abs() + (w.z * o.z).abs() + w.w.abs()))
        };
        let dp = |i: usize| {
            let w = row(i);
            let v = w.x * d.x + w.y * d.y + w.z * d.z;
            (v, gamma64(3) * ((w.x * d.x).abs() + (w.y * d.y).abs() + (w.z * d.z).abs()))
        };
        ObjectRay { o: [op(0), op(1), op(2)], d: [dp(0), dp(1), dp(2)] }
    }

    /// The first hit with 0 < t < t_max, if any.
    pub fn intersect_t(&self, r: &Ray, t_max: f32) -> Option<QuadricHit> {
        let ray = self.object_ray(r);
        let t_max = t_max as f64;
        let (t, p_obj) = dispatch_quadric!(&self.quadric, s => s.hit(&ray, t_max))?;
        Some(QuadricHit { t: t as f32, p_obj })
    }

    /// Any hit before t_max (shadow rays).
    pub fn intersect_p(&self, r: &Ray, t_max: f32) -> bool {
        self.intersect_t(r, t_max).is_some()
    }

    /// (u, v) of a hit in f64 (the interaction stores them rounded to f32).
    pub fn uv_of(&self, hit: &QuadricHit) -> [f64; 2] {
        dispatch_quadric!(&self.quadric, s => s.local(hit.p_obj, s.phi(hit.p_obj)).uv)
    }

    /// (u, v) of an object-space point on the surface.
    pub fn uv_of_object_point(&self, p_obj: DVec3) -> [f64; 2] {
        dispatch_quadric!(&self.quadric, s => s.local(p_obj, s.phi(p_obj)).uv)
    }

    /// The object-space derivatives at a hit. On the axis ∂p/∂u vanishes (a sphere's
    /// pole, a cone's apex, a paraboloid's vertex, a disk's centre) and ∂p/∂v may be
    /// infinite, so there they are those of the surface point 2^-20 away in v, at the
    /// hit's φ: the limit of the frame along that meridian. (u, v) stay the hit's.
    // DEVIATION(pbrt): robustness. pbrt moves only the sphere's pole hits (x = 1e-5 r); its cone,
    // paraboloid and disk give a NaN normal there.
    fn local_at(&self, hit: &QuadricHit) -> Local {
        let phi = dispatch_quadric!(&self.quadric, s => s.phi(hit.p_obj));
        let l = dispatch_quadric!(&self.quadric, s => s.local(hit.p_obj, phi));
        let n = l.dpdu.cross(l.dpdv);
        if n.is_finite() && n.length_squared() > 0.0 {
            return l;
        }
        let [u, v] = l.uv;
        let near = self.quadric.point(u, if v > 0.5 { v - 2f64.powi(-20) } else { v + 2f64.powi(-20) });
        let moved = dispatch_quadric!(&self.quadric, s => s.local(near, phi));
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

    /// ∂n/∂u and ∂n/∂v in render space from the object-space derivatives `l`, `m3`
    /// being render-from-object's linear part.
    fn normal_derivatives(&self, l: &Local, m3: DMat3) -> (DVec3, DVec3) {
        // DEVIATION(pbrt): appearance, `--fix normal-derivatives`. pbrt transforms the
        // object-space ∂n/∂u and ∂n/∂v as normals (off by the scale under scaling) and
        // does not flip them with ReverseOrientation, which bump maps then use; the fix
        // uses the derivatives of the normal reported.
        if self.pbrt_normal_derivatives {
            let ((du, dv), normals) = (weingarten(l), self.normal_matrix());
            return (normals * du, normals * dv);
        }
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
        let (du, dv) = weingarten(&world);
        if self.reverse_orientation { (-du, -dv) } else { (du, dv) }
    }

    /// Full differential geometry at a hit found by [`QuadricShape::intersect_t`].
    pub fn interaction(&self, hit: &QuadricHit) -> SurfaceInteraction {
        let l = self.local_at(hit);
        let m = self.render_from_object;
        let m3 = DMat3::from_mat4(m);
        let (dpdu, dpdv) = (m3 * l.dpdu, m3 * l.dpdv);
        let n = dpdu.cross(dpdv).normalize_or_zero();
        let n = if self.reverse_orientation { -n } else { n };
        let (dndu, dndv) = match self.skip_normal_derivatives {
            true => (DVec3::ZERO, DVec3::ZERO),
            false => self.normal_derivatives(&l, m3),
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

/// A ray in object space: each coordinate of its origin and direction as an f64 value
/// and a bound on that value's rounding error. Tests decide on plain values and a
/// bound ([`Bounded64`]) where they can, and build the intervals ([`E`]) only where
/// the bound leaves a doubt: stepping their ends out was 30% of a quadric test's
/// instructions on `sppm-bench`.
#[derive(Clone, Copy, Debug)]
pub struct ObjectRay {
    pub o: [(f64, f64); 3],
    pub d: [(f64, f64); 3],
}

impl ObjectRay {
    /// Origin and direction as intervals: each value ± its bound.
    pub fn intervals(&self) -> ([E; 3], [E; 3]) {
        (self.o.map(|(v, e)| E::new(v, e)), self.d.map(|(v, e)| E::new(v, e)))
    }

    /// Origin and direction as values with radii that hold the ends of
    /// [`ObjectRay::intervals`].
    // Written out: `[_; 3].map` kept copies this form does not (28 instructions a test).
    #[inline(always)]
    pub fn bounded(&self) -> ([Bounded64; 3], [Bounded64; 3]) {
        let b = |(v, e): (f64, f64)| Bounded64::around(v, e);
        let (o, d) = (&self.o, &self.d);
        ([b(o[0]), b(o[1]), b(o[2])], [b(d[0]), b(d[1]), b(d[2])])
    }

    /// The point at parameter t (in plain values, as the intervals' values give it).
    pub fn at(&self, t: f64) -> DVec3 {
        let (o, d) = (self.o, self.d);
        DVec3::new(o[0].0 + t * d[0].0, o[1].0 + t * d[1].0, o[2].0 + t * d[2].0)
    }
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
    /// a t² + b t + c = F(o + t d), F the implicit function, with rounding bounds
    /// (exact interval ends, or a bound on them: [`Interval`]).
    fn coefficients<N: Interval>(&self, o: [N; 3], d: [N; 3]) -> (N, N, N);

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

    /// The (x, y) whose angle is a point's φ (its own x and y about the axis).
    fn phi_frame(&self, p: DVec3) -> (f64, f64) {
        (p.x, p.y)
    }

    /// φ at a point, in [0, 2π].
    fn phi(&self, p: DVec3) -> f64 {
        let (x, y) = self.phi_frame(p);
        phi_of(x, y)
    }

    /// Whether the (refined) point lies in the z range and the φ range.
    fn accept(&self, p: DVec3) -> bool {
        let (z0, z1, phi_max) = self.ranges();
        if p.z < z0 || p.z > z1 {
            return false;
        }
        let (x, y) = self.phi_frame(p);
        // A full turn takes every φ (at most 2π) but NaN's, and the arctangent waits
        // for the hit that is kept: a sphere's candidates cost an atan2 each.
        if phi_max >= TAU {
            return !(x.is_nan() || y.is_nan());
        }
        phi_of(x, y) <= phi_max
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

    /// The first hit (t, object-space point) with 0 < t < t_max. Decided from the
    /// roots' values and a bound on their intervals ([`quick_roots`]) where that bound
    /// leaves no doubt, from the intervals otherwise: the same decisions either way.
    fn hit(&self, ray: &ObjectRay, t_max: f64) -> Option<(f64, DVec3)> {
        match quick_roots(self, ray) {
            Some(None) => return None,
            Some(Some(roots)) => {
                if let Some(hit) = first_hit(self, roots, ray, t_max) {
                    return hit;
                }
            }
            None => {}
        }
        interval_hit(self, ray, t_max)
    }
}

/// [`QuadricSurface::hit`] decided from the roots' intervals alone.
fn interval_hit<S: QuadricSurface + ?Sized>(s: &S, ray: &ObjectRay, t_max: f64) -> Option<(f64, DVec3)> {
    let (o, d) = ray.intervals();
    let (t0, t1) = s.roots(o, d)?;
    first_hit(s, (RootEnds::exact(t0), RootEnds::exact(t1)), ray, t_max).flatten()
}

/// The first of the roots (t0 ≤ t1) in (0, t_max) that lies on the shape, as
/// pbrt-v3 decides it from their intervals; `None` when the ends known cannot
/// settle one of its comparisons (never for exact ends).
fn first_hit<S: QuadricSurface + ?Sized>(
    s: &S,
    (t0, t1): (RootEnds, RootEnds),
    ray: &ObjectRay,
    t_max: f64,
) -> Option<Option<(f64, DVec3)>> {
    match (settled(t0.high, |h| h > t_max), settled(t1.low, |l| l <= 0.0)) {
        (Some(true), _) | (_, Some(true)) => return Some(None),
        (Some(false), Some(false)) => {}
        _ => return None,
    }
    let try_root = |t: f64| {
        let p = s.refine(ray.at(t));
        s.accept(p).then_some((t, p))
    };
    if settled(t0.low, |l| l > 0.0)?
        && let Some(hit) = try_root(t0.v)
    {
        return Some(Some(hit));
    }
    if settled(t1.high, |h| h > t_max)? {
        return Some(None);
    }
    Some(try_root(t1.v))
}

/// What a hit test knows of a root: its value, and the least and most each end of its
/// interval can be (both the end itself for an interval root).
#[derive(Clone, Copy, Debug)]
struct RootEnds {
    v: f64,
    low: [f64; 2],
    high: [f64; 2],
}

impl RootEnds {
    fn exact(t: E) -> RootEnds {
        RootEnds { v: t.value(), low: [t.lower(); 2], high: [t.upper(); 2] }
    }

    fn bounded(t: Bounded64) -> RootEnds {
        RootEnds { v: t.v, low: [t.low_least(), t.v], high: [t.v, t.high_most()] }
    }
}

/// Whether the interval of t lies in (0, t_max), as its ends decide it (low > 0, high
/// < t_max), from its value and radius: `None` where they leave a doubt.
pub(super) fn within(t: Bounded64, t_max: f64) -> Option<bool> {
    if !t.is_known() {
        return None;
    }
    let (low, high) = ([t.low_least(), t.v], [t.v, t.high_most()]);
    Some(settled(low, |l| l > 0.0)? && settled(high, |h| h < t_max)?)
}

/// `test` of an interval end known to lie in `end` (least, most), where the two give
/// the same answer: `test` compares with a fixed value, so the end's answer is theirs.
/// Exact ends always settle, as the comparison itself (NaN included).
fn settled(end: [f64; 2], test: impl Fn(f64) -> bool) -> Option<bool> {
    let (least, most) = (test(end[0]), test(end[1]));
    (least == most).then_some(least)
}

/// The roots as [`QuadricSurface::roots`] gives them (ordered by their low ends), from
/// the plain values and a bound on the ends: `Some(None)` for a clear miss (a negative
/// discriminant whose interval is surely below 0), `None` where the bound cannot settle
/// the order or the miss, or a radius is unknown.
#[inline]
fn quick_roots<S: QuadricSurface + ?Sized>(s: &S, ray: &ObjectRay) -> Option<Option<(RootEnds, RootEnds)>> {
    let (o, d) = ray.bounded();
    let (a, b, c) = s.coefficients(o, d);
    let disc = b.v * b.v - 4.0 * a.v * c.v;
    if disc.is_nan() {
        return None;
    }
    if disc < 0.0 {
        let wide = b * b - a * c * 4.0;
        return (wide.is_known() && wide.high_most() < 0.0).then_some(None);
    }
    // As `EFloat64::quadratic`: the root of the discriminant within half an ulp.
    let root = disc.sqrt();
    let float_root = Bounded64::of(E::new(root, (f64::EPSILON * 0.5) * root));
    let q = if b.v < 0.0 { (b - float_root) * -0.5 } else { (b + float_root) * -0.5 };
    let (t0, t1) = (q / a, c / q);
    if !(t0.is_known() && t1.is_known()) {
        return None;
    }
    let (t0, t1) = (RootEnds::bounded(t0), RootEnds::bounded(t1));
    // Swapped where t0's low end is surely above t1's, kept where surely not.
    if t0.low[0] > t1.low[1] {
        Some(Some((t1, t0)))
    } else if t0.low[1] <= t1.low[0] {
        Some(Some((t0, t1)))
    } else {
        None
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::sphere::Sphere;
    use crate::shapes::{Cone, Cylinder, Disk, Hyperboloid, Paraboloid};
    use glam::Vec3;

    /// A ray toward `s`'s surface that starts on it, near it, inside or far off, and
    /// grazes it or ends at or near its hit: where a decision comes closest to a
    /// bound's doubt. Returns the ray and its t_max.
    fn ray_at<S: QuadricSurface>(s: &S, rng: &mut Rng, scale: f64) -> (ObjectRay, f64) {
        let on = s.refine(uniform_sphere(rng.uniform2()).as_dvec3() * scale);
        let d = uniform_sphere(rng.uniform2()).as_dvec3();
        let kind = (rng.uniform() * 4.0) as u32;
        let o = match kind {
            0 => on,
            1 => on + d * 1e-9 * scale * (rng.uniform() as f64 - 0.5),
            2 => on * (0.2 + rng.uniform() as f64),
            _ => on - d * scale * 10.0 * rng.uniform() as f64,
        };
        // Grazing: the direction turned into the tangent plane at `on`.
        let (_, g) = s.implicit(on);
        let d = if rng.uniform() < 0.25 && g.length() > 0.0 {
            let n = g.normalize();
            (d - n * d.dot(n) + n * 1e-12 * (rng.uniform() as f64 - 0.5)).normalize()
        } else {
            d
        };
        let ray = ObjectRay {
            o: o.to_array().map(|v| (v, gamma64(4) * v.abs())),
            d: d.to_array().map(|v| (v, gamma64(3) * v.abs())),
        };
        let t_hit = interval_hit(s, &ray, f64::INFINITY).map_or(1.0, |h| h.0);
        let t_max = match (rng.uniform() * 3.0) as u32 {
            0 => f64::INFINITY,
            1 => t_hit * (1.0 + 1e-15 * (rng.uniform() as f64 - 0.5)),
            _ => t_hit * 2.0 * rng.uniform() as f64,
        };
        (ray, t_max)
    }

    /// The quick decisions are the intervals' on every kind of quadric and ray, with
    /// the same hit bit for bit, and they settle nearly every test.
    fn same_hits<S: QuadricSurface>(s: &S, scale: f64) {
        let (mut rng, mut quick) = (Rng::new(5), 0);
        let n = 200_000;
        for _ in 0..n {
            let (ray, t_max) = ray_at(s, &mut rng, scale);
            let exact = interval_hit(s, &ray, t_max);
            let fast = match quick_roots(s, &ray) {
                Some(None) => Some(None),
                Some(Some(roots)) => first_hit(s, roots, &ray, t_max),
                None => None,
            };
            if let Some(fast) = fast {
                quick += 1;
                let bits = |h: Option<(f64, DVec3)>| h.map(|(t, p)| (t.to_bits(), p.to_array().map(f64::to_bits)));
                assert_eq!(bits(fast), bits(exact), "{ray:?} t_max {t_max}");
            }
            assert_eq!(s.hit(&ray, t_max).map(|h| h.0.to_bits()), exact.map(|h| h.0.to_bits()));
        }
        eprintln!("settled quickly: {quick} of {n}");
        assert!(quick > n / 2, "settled quickly: {quick} of {n}");
    }

    /// What `accept` decided when it computed φ at every candidate: the z range, then
    /// φ ≤ φmax (false for a NaN φ).
    fn accepted_by_phi<S: QuadricSurface>(s: &S, p: DVec3) -> bool {
        let (z0, z1, phi_max) = s.ranges();
        !(p.z < z0 || p.z > z1) && s.phi(p) <= phi_max
    }

    /// A full turn skips the arctangent, and accepts exactly the points it accepted:
    /// on and off the surface, on the axis, at the z limits, and with NaN or infinite
    /// coordinates.
    fn same_acceptance<S: QuadricSurface>(s: &S) {
        let mut rng = Rng::new(11);
        let odd = [0.0, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e-300];
        let (z0, z1, _) = s.ranges();
        for k in 0..20_000 {
            let mut p = s.refine(uniform_sphere(rng.uniform2()).as_dvec3() * 2.0);
            match k % 4 {
                0 => p[(rng.uniform() * 3.0) as usize % 3] = odd[(rng.uniform() * 6.0) as usize % 6],
                1 => p.z = if rng.uniform() < 0.5 { z0 } else { z1 },
                2 => (p.x, p.y) = (0.0, 0.0),
                _ => {}
            }
            assert_eq!(s.accept(p), accepted_by_phi(s, p), "{p:?}");
        }
    }

    #[test]
    fn full_turns_accept_what_phi_accepts() {
        same_acceptance(&Sphere::new(1.0, -1.0, 1.0, 360.0));
        same_acceptance(&Sphere::new(1.0, -0.5, 0.7, 250.0));
        same_acceptance(&Cylinder::new(0.7, -1.0, 2.0, 360.0));
        same_acceptance(&Cone::new(1.5, 0.8, 360.0));
        same_acceptance(&Paraboloid::new(1.0, 0.1, 2.0, 360.0));
        let h = Hyperboloid::new(Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.5, 0.8, 1.0), 360.0).expect("a hyperboloid");
        same_acceptance(&h);
    }

    /// A sampled point's (u, v) are those of the surface's parametrisation, as a hit's
    /// are: the hyperboloid's φ is measured from its profile point (pbrt-v3's hit), not
    /// from the x axis, which put a sampled point's u up to 0.19 away on this one.
    #[test]
    fn sampled_points_have_their_parameters() {
        let h = Hyperboloid::new(Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.5, 0.8, 1.0), 300.0).expect("a hyperboloid");
        let shape = QuadricShape::new(Quadric::Hyperboloid(h.clone()), DMat4::IDENTITY, false);
        for (u, v) in [(0.1, 0.2), (0.5, 0.9), (0.8, 0.5), (0.3, 1.0)] {
            let [su, sv] = shape.uv_of_object_point(h.point(u, v));
            assert!((su - u).abs() < 1e-9 && (sv - v).abs() < 1e-9, "({u}, {v}) gave ({su}, {sv})");
        }
    }

    /// The disk's hit as it was decided from intervals alone.
    fn disk_by_intervals(k: &Disk, ray: &ObjectRay, t_max: f64) -> Option<(f64, DVec3)> {
        let (o, d) = ray.intervals();
        let h = k.height as f64;
        if d[2].value() == 0.0 {
            return None;
        }
        let t = (E::from(h) - o[2]) / d[2];
        if t.lower() <= 0.0 || t.upper() >= t_max {
            return None;
        }
        let mut p = ray.at(t.value());
        let dist2 = p.x * p.x + p.y * p.y;
        let (r, ri) = (k.radius as f64, k.inner_radius as f64);
        if dist2 > r * r || dist2 < ri * ri {
            return None;
        }
        p.z = h;
        k.accept(p).then_some((t.value(), p))
    }

    /// The disk's quick decision of t's range is the intervals', bit for bit, on rays
    /// that start on the plane or end at their hit.
    #[test]
    fn disk_decisions_are_the_intervals() {
        for k in [Disk::new(0.3, 1.2, 0.0, 360.0), Disk::new(-2e3, 4e3, 1e3, 250.0)] {
            let (mut rng, mut hits) = (Rng::new(3), 0);
            for _ in 0..200_000 {
                let (ray, t_max) = ray_at(&k, &mut rng, k.radius as f64);
                let bits = |h: Option<(f64, DVec3)>| h.map(|(t, p)| (t.to_bits(), p.to_array().map(f64::to_bits)));
                let exact = disk_by_intervals(&k, &ray, t_max);
                assert_eq!(bits(k.hit(&ray, t_max)), bits(exact), "{ray:?} t_max {t_max}");
                hits += exact.is_some() as u32;
            }
            assert!(hits > 10_000, "{hits} hits");
        }
    }

    #[test]
    fn quick_decisions_are_the_intervals() {
        same_hits(&Sphere::new(1.3, -0.9, 1.1, 300.0), 1.3);
        same_hits(&Sphere::new(2e3, -2e3, 2e3, 360.0), 2e3);
        same_hits(&Cylinder::new(0.7, -1.0, 2.0, 360.0), 1.0);
        same_hits(&Cone::new(1.5, 0.8, 270.0), 1.0);
        same_hits(&Paraboloid::new(1.0, 0.1, 2.0, 360.0), 1.0);
        let mut h =
            Hyperboloid::new(Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.5, 0.8, 1.0), 360.0).expect("a hyperboloid");
        for fit in [true, false] {
            h.implicit_fit = fit;
            same_hits(&h, 1.0);
        }
    }
}
