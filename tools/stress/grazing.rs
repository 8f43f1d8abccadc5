//! `pbrt-bench stress grazing`: rays tangent to the quadrics, through their rims and
//! through their poles and apexes, against an f64 reference.
//!
//! ```text
//! pbrt-bench stress grazing [--shapes 100] [--rays 400]
//! ```
//! Each family is tried whole (φmax 360°, with its pole or apex where it has one) and
//! cut (φmax 270°, and a z range or inner radius that leaves rims), placed by the sweep's
//! transforms. The rays, built in object space and rounded to f32 in world space:
//! - **tangent**: along a random tangent at a random point, pushed off the surface by
//!   ±10^U(−7, −1) along the normal (the disk's are parallel to its plane);
//! - **rim**: through a random point of the φmax seam or of a z (radius) edge, in a
//!   random direction;
//! - **pole**: through the pole or apex (else a random point) along the axis, tilted by
//!   10^U(−9, −2), or in a random direction.
//!
//! The reference takes the f32 world ray back to object space in f64 and solves the
//! surface x² + y² = ρ²(z) (every family but the disk, where ρ² is a quadratic in z) or
//! the disk's plane exactly, then applies the z and φ ranges. A ray is **judged** when
//! moving its origin by ε = max(10^-5 of the shape's smallest size, 64 f32 spacings)
//! along each world axis changes neither the reference's hit-or-miss nor its hit point
//! by more than 10^-2 of the shape, and its hit is not within the ray's rounding of a
//! cut shape's φ seams; rays closer to tangent than that, or hits that close to a seam
//! (near the axis every hit is), have no answer at f32's resolution. Failures:
//! - **invalid**: a hit with a non-finite or non-positive t, a non-finite point, normal,
//!   (u, v), ∂p/∂u, ∂p/∂v or error bound, or a normal not of unit length (any ray);
//! - **off**: a hit farther from the surface or its ranges than the world ray's own
//!   rounding allows (any ray);
//! - **wrong**: a judged ray that ours misses and the reference hits, or that ours
//!   hits farther than 10^-3 of the shape from the reference's hit, or that ours hits
//!   where the reference misses, unless our point is within the ray's rounding of the
//!   ray (a touch at f32's resolution: a ray grazing a cone's apex).

use super::{DISTANCES, KINDS, cases, dir, per_1e7, resolvable, to_ray, transform, ulp32};
use glam::{DMat3, DVec3, Vec3};
use pbrt_sppm::sampling::{Rng, hash};
use pbrt_sppm::shapes::sphere::Sphere;
use pbrt_sppm::shapes::{Cone, Cylinder, Disk, Hyperboloid, Paraboloid, Quadric, QuadricShape};
use rayon::prelude::*;

const FAMILIES: [&str; 6] = ["sphere", "cylinder", "disk", "cone", "paraboloid", "hyperboloid"];
const TYPES: [&str; 3] = ["tangent", "rim", "pole"];

/// The family whole (`cut` false) or cut to leave rims.
fn shape(family: usize, cut: bool) -> Quadric {
    let phi = if cut { 270.0 } else { 360.0 };
    match family {
        0 if cut => Quadric::Sphere(Sphere::new(1.0, -0.5, 0.8, phi)),
        0 => Quadric::Sphere(Sphere::new(1.0, -1.0, 1.0, phi)),
        1 => Quadric::Cylinder(Cylinder::new(1.0, -1.0, 1.0, phi)),
        2 => Quadric::Disk(Disk::new(0.0, 1.0, if cut { 0.3 } else { 0.0 }, phi)),
        3 => Quadric::Cone(Cone::new(1.0, 1.0, phi)),
        4 => Quadric::Paraboloid(Paraboloid::new(1.0, if cut { 0.3 } else { 0.0 }, 1.0, phi)),
        _ => match Hyperboloid::new(Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 1.0, 1.0), phi) {
            Ok(h) => Quadric::Hyperboloid(h),
            Err(e) => unreachable!("a fixed hyperboloid: {e}"),
        },
    }
}

/// The reference surface in object space: x² + y² = c2 z² + c1 z + c0 (or the disk's
/// plane z = c0 with ρ in [ρmin, ρmax]), z in [zmin, zmax], φ ≤ φmax.
struct Reference {
    disk: bool,
    /// The hyperboloid's profile ends (x, y, z): φ is measured from the profile's own
    /// azimuth at the point's height.
    profile: Option<(DVec3, DVec3)>,
    c: [f64; 3],
    rho: [f64; 2],
    z: [f64; 2],
    phi_max: f64,
}

impl Reference {
    fn new(q: &Quadric) -> Reference {
        let f = |x: f32| x as f64;
        let (mut disk, mut rho, mut profile) = (false, [0.0, 0.0], None);
        let (c, z) = match q {
            Quadric::Sphere(s) => ([-1.0, 0.0, f(s.radius).powi(2)], [f(s.z_min), f(s.z_max)]),
            Quadric::Cylinder(s) => ([0.0, 0.0, f(s.radius).powi(2)], [f(s.z_min), f(s.z_max)]),
            Quadric::Disk(s) => {
                (disk, rho) = (true, [f(s.inner_radius), f(s.radius)]);
                ([0.0, 0.0, f(s.height)], [f(s.height); 2])
            }
            Quadric::Cone(s) => {
                // (r/h)² (h − z)²
                let (h, k) = (f(s.height), (f(s.radius) / f(s.height)).powi(2));
                ([k, -2.0 * k * h, k * h * h], [h.min(0.0), h.max(0.0)])
            }
            Quadric::Paraboloid(s) => ([0.0, f(s.radius).powi(2) / f(s.z_max), 0.0], [f(s.z_min), f(s.z_max)]),
            Quadric::Hyperboloid(s) => {
                // |a + v (b − a)|² with v = (z − z1)/dz, a and b the ends' (x, y).
                profile = Some((s.p1.as_dvec3(), s.p2.as_dvec3()));
                let (a, b) = (s.p1.truncate().as_dvec2(), s.p2.truncate().as_dvec2());
                let (z1, dz) = (f(s.p1.z), f(s.p2.z) - f(s.p1.z));
                let (qa, qb, qc) = ((b - a).length_squared(), 2.0 * a.dot(b - a), a.length_squared());
                // qa v² + qb v + qc, v = (z − z1)/dz, as a polynomial in z.
                let c2 = qa / (dz * dz);
                let c1 = -2.0 * qa * z1 / (dz * dz) + qb / dz;
                let c0 = qa * z1 * z1 / (dz * dz) - qb * z1 / dz + qc;
                ([c2, c1, c0], [f(s.z_min), f(s.z_max)])
            }
        };
        Reference { disk, profile, c, rho, z, phi_max: q.phi_max() }
    }

    /// F (zero on the surface) and its gradient.
    fn implicit(&self, p: DVec3) -> (f64, DVec3) {
        if self.disk {
            return (p.z - self.c[2], DVec3::Z);
        }
        let [c2, c1, c0] = self.c;
        (
            p.x * p.x + p.y * p.y - (c2 * p.z * p.z + c1 * p.z + c0),
            DVec3::new(2.0 * p.x, 2.0 * p.y, -(2.0 * c2 * p.z + c1)),
        )
    }

    /// p's azimuth as the shape measures it, in [0, 2π): the hyperboloid's from its
    /// profile's own azimuth at p's height.
    fn phi(&self, p: DVec3) -> f64 {
        let mut phi = p.y.atan2(p.x);
        if let Some((a, b)) = self.profile {
            let pr = a.lerp(b, (p.z - a.z) / (b.z - a.z));
            phi -= pr.y.atan2(pr.x);
        }
        phi.rem_euclid(std::f64::consts::TAU)
    }

    /// How far p lies from the φ = 0 and φ = φmax seams of a cut shape, along its
    /// circle (infinite on a whole one): near the axis, which side p falls on is
    /// decided by rounding.
    fn seam_margin(&self, p: DVec3) -> f64 {
        if self.phi_max >= std::f64::consts::TAU {
            return f64::INFINITY;
        }
        let phi = self.phi(p);
        p.x.hypot(p.y) * phi.min((self.phi_max - phi).abs())
    }

    /// How far p lies outside the z, φ and (disk) ρ ranges; 0 inside.
    fn outside(&self, p: DVec3) -> f64 {
        let phi = self.phi(p);
        let rho = p.x.hypot(p.y);
        let mut out = (self.z[0] - p.z).max(p.z - self.z[1]).max(0.0);
        out = out.max(rho * (phi - self.phi_max).max(0.0));
        if self.disk {
            out = out.max(self.rho[0] - rho).max(rho - self.rho[1]);
        }
        out
    }

    /// The first hit with t > 0, object space.
    fn hit(&self, o: DVec3, d: DVec3) -> Option<DVec3> {
        let roots = if self.disk {
            vec![(self.c[2] - o.z) / d.z]
        } else {
            let [c2, c1, c0] = self.c;
            let a = d.x * d.x + d.y * d.y - c2 * d.z * d.z;
            let b = 2.0 * (o.x * d.x + o.y * d.y) - 2.0 * c2 * o.z * d.z - c1 * d.z;
            let c = o.x * o.x + o.y * o.y - c2 * o.z * o.z - c1 * o.z - c0;
            solve(a, b, c)
        };
        // Within 10^-9 of a range counts as inside: the f64 point's own rounding.
        let on = |t: f64| if self.disk { DVec3::new(o.x + t * d.x, o.y + t * d.y, self.c[2]) } else { o + t * d };
        roots.into_iter().filter(|t| t.is_finite() && *t > 0.0).map(on).find(|&p| self.outside(p) <= 1e-9)
    }
}

/// Real roots of a t² + b t + c, ascending; the linear root when a is negligible.
fn solve(a: f64, b: f64, c: f64) -> Vec<f64> {
    if a.abs() <= 1e-14 * (b.abs() + c.abs()) {
        return if b != 0.0 { vec![-c / b] } else { vec![] };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return vec![];
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
    vec![t0.min(t1), t0.max(t1)]
}

/// A ray of the given type, object space: (origin, direction).
fn object_ray(q: &Quadric, r: &Reference, ty: usize, cut: bool, rng: &mut Rng) -> (DVec3, DVec3) {
    let (u, v) = (rng.uniform() as f64, rng.uniform() as f64);
    let (p, d) = match ty {
        0 => {
            let p = q.point(u, v);
            let n = r.implicit(p).1.normalize();
            let t = dir(rng).reject_from_normalized(n).normalize();
            let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            (p + sign * 10f64.powf(-7.0 + 6.0 * rng.uniform() as f64) * n, t)
        }
        1 => {
            let edge = (rng.uniform() * 3.0) as usize;
            let p = match edge {
                0 if cut => q.point(1.0, v),
                0 | 1 => q.point(u, 0.0),
                _ => q.point(u, 1.0),
            };
            (p, dir(rng))
        }
        _ => {
            let pole = match q {
                Quadric::Sphere(_) if !cut => Some(q.point(u, (rng.uniform() < 0.5) as u8 as f64)),
                Quadric::Disk(_) | Quadric::Cone(_) if !cut => Some(q.point(u, 1.0)),
                Quadric::Paraboloid(_) if !cut => Some(q.point(u, 0.0)),
                _ => None,
            };
            let p = pole.unwrap_or_else(|| q.point(u, v));
            let d = if rng.uniform() < 0.5 {
                let tilt = 10f64.powf(-9.0 + 7.0 * rng.uniform() as f64);
                let axis = if rng.uniform() < 0.5 { DVec3::Z } else { -DVec3::Z };
                (axis + tilt * dir(rng).reject_from_normalized(axis).normalize()).normalize()
            } else {
                dir(rng)
            };
            (p, d)
        }
    };
    (p - 3.0 * d, d)
}

/// Counts for one group of rays.
#[derive(Clone, Copy, Default)]
struct Counts {
    rays: u64,
    judged: u64,
    invalid: u64,
    off: u64,
    wrong: u64,
}

impl Counts {
    fn add(self, o: Counts) -> Counts {
        Counts {
            rays: self.rays + o.rays,
            judged: self.judged + o.judged,
            invalid: self.invalid + o.invalid,
            off: self.off + o.off,
            wrong: self.wrong + o.wrong,
        }
    }

    fn failures(&self) -> u64 {
        self.invalid + self.off + self.wrong
    }
}

/// The rays of one random placement of a family.
/// Whether the reference's answer `base` for the world ray `(o, d)` stands: the same
/// (a hit within 10^-2) with the origin moved by `eps` and the direction by 10^-6
/// along each world axis, and a hit clear of a cut shape's seams by `tol`.
fn judged(
    reference: &Reference,
    to_object: &impl Fn(DVec3, DVec3) -> (DVec3, DVec3),
    (o, d): (DVec3, DVec3),
    base: Option<DVec3>,
    eps: f64,
    tol: f64,
) -> bool {
    base.is_none_or(|b| reference.seam_margin(b) > tol)
        && (0..12).all(|i| {
            let mut shift = DVec3::ZERO;
            shift[i / 2 % 3] = if i % 2 == 0 { 1.0 } else { -1.0 };
            let (po, pd) =
                if i < 6 { to_object(o + eps * shift, d) } else { to_object(o, d + 1e-6 * d.length() * shift) };
            match (reference.hit(po, pd), base) {
                (None, None) => true,
                (Some(a), Some(b)) => (a - b).length() <= 1e-2,
                _ => false,
            }
        })
}

/// One case of the sweep.
#[derive(Clone, Copy)]
struct Case {
    family: usize,
    cut: bool,
    ty: usize,
    kind: usize,
    scale: f64,
    distance: f64,
}

fn one_shape(case: Case, rays: usize, seed: u64) -> Counts {
    let Case { family, cut, ty, kind, scale, distance } = case;
    let mut rng = Rng::new(seed);
    let (m, smallest) = transform(kind, scale, distance, &mut rng);
    if !resolvable(smallest, distance) {
        return Counts::default();
    }
    let q = shape(family, cut);
    let reference = Reference::new(&q);
    let s = QuadricShape::new(q.clone(), m, false);
    let (inv, m3) = (m.inverse(), DMat3::from_mat4(m));
    let to_object = |o: DVec3, d: DVec3| (inv.transform_point3(o), inv.transform_vector3(d));
    let mut c = Counts::default();
    for _ in 0..rays {
        let (o, d) = object_ray(&q, &reference, ty, cut, &mut rng);
        let ray = to_ray(m.transform_point3(o), m3 * d);
        // The f32 world ray is the ray: the reference sees exactly what ours sees.
        let (ow, dw) = (ray.o.0.as_dvec3(), ray.d.0.as_dvec3());
        let (oo, od) = to_object(ow, dw);
        let base = reference.hit(oo, od);
        let eps = (1e-5 * smallest).max(64.0 * ulp32(ow.abs().max_element()));
        // What the f32 world point's rounding allows, in object units.
        let tol = 1e-6 + 1e2 * ulp32(ow.abs().max_element() + scale) / smallest;
        let judged = judged(&reference, &to_object, (ow, dw), base, eps, tol);
        let ours = s.intersect_t(&ray, f32::INFINITY);
        c.rays += 1;
        c.judged += judged as u64;
        let Some(hit) = ours else {
            c.wrong += (judged && base.is_some()) as u64;
            continue;
        };
        let si = s.interaction(&hit);
        let valid = hit.t.is_finite()
            && hit.t > 0.0
            && si.p.0.is_finite()
            && si.p_error.is_finite()
            && si.dpdu.0.is_finite()
            && si.dpdv.0.is_finite()
            && si.uv.iter().all(|x| x.is_finite())
            && (si.n.0.length() - 1.0).abs() < 1e-3;
        c.invalid += !valid as u64;
        let (f, g) = reference.implicit(hit.p_obj);
        let from_surface = f.abs() / g.length().max(1e-300);
        c.off += (from_surface > tol || reference.outside(hit.p_obj) > tol) as u64;
        // A hit on the surface within `tol` of the ray touches it at f32's
        // resolution, whatever the reference says.
        let touch = (hit.p_obj - oo).reject_from(od).length() <= tol;
        if judged {
            c.wrong += base.map_or(!touch, |b| (b - hit.p_obj).length() > 1e-3) as u64;
        }
    }
    c
}

/// Prints a line per family, variant and ray type, and a summary per family; the
/// summary follows the line naming "grazing failures per 10^7".
pub fn run(shapes: usize, rays: usize) {
    println!("\ngrazing rays: {shapes} shapes a case, {rays} rays each, every transform, scale 1e-6…1e6 and distance");
    println!(
        "{:<12} {:<6} {:<8} {:>10} {:>10} {:>8} {:>8} {:>8}",
        "family", "shape", "rays", "traced", "judged", "invalid", "off", "wrong"
    );
    let mut summary = Vec::new();
    for (f, family) in FAMILIES.iter().enumerate() {
        let mut total = Counts::default();
        let mut failing = Vec::new();
        for cut in [false, true] {
            for (ty, name) in TYPES.iter().enumerate() {
                let mut group = Counts::default();
                for (k, kind) in KINDS.iter().enumerate() {
                    for &d in &DISTANCES {
                        for e in (-6..=6).step_by(2) {
                            let s = 10f64.powi(e);
                            let case = Case { family: f, cut, ty, kind: k, scale: s, distance: d };
                            let seed = |i: usize| {
                                hash(&[i as u64, f as u64, cut as u64, ty as u64, k as u64, s.to_bits(), d.to_bits()])
                            };
                            let c = (0..shapes)
                                .into_par_iter()
                                .map(|i| one_shape(case, rays, seed(i)))
                                .reduce(Counts::default, Counts::add);
                            if c.failures() > 0 {
                                failing.push(format!(
                                    "{}/{name}/{kind}/{s:.0e}@{d:.0e}",
                                    if cut { "cut" } else { "whole" }
                                ));
                            }
                            group = group.add(c);
                        }
                    }
                }
                let variant = if cut { "cut" } else { "whole" };
                println!(
                    "{family:<12} {variant:<6} {name:<8} {:>10} {:>10} {:>8} {:>8} {:>8}",
                    group.rays, group.judged, group.invalid, group.off, group.wrong
                );
                total = total.add(group);
            }
        }
        summary.push((family, total, failing));
    }
    println!(
        "\n{:<12} {:>11} {:>11} {:>8} {:>8} {:>8} {:>26}   cases with failures",
        "family", "rays", "judged", "invalid", "off", "wrong", "grazing failures per 10^7"
    );
    for (family, c, failing) in summary {
        let cases = cases(&failing);
        println!(
            "{family:<12} {:>11} {:>11} {:>8} {:>8} {:>8} {:>26.2}   {cases}",
            c.rays,
            c.judged,
            c.invalid,
            c.off,
            c.wrong,
            per_1e7(c.failures(), c.rays)
        );
    }
}
