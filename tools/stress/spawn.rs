//! `pbrt-bench stress spawn`: self-intersections of spawned rays per shape family, over
//! scales 1e-6…1e6 and distances from the origin 0, 1e6 and 1e7, under plain, mirrored
//! and sheared, and nearly singular transforms.
//!
//! ```text
//! pbrt-bench stress spawn [--shapes 500] [--rays 500]
//! ```
//! For each case, random shapes of the family are placed by Translate(distance · a
//! random direction) · Rotate(random) · X · Scale(scale), X the transform kind. A ray
//! from ten sizes away finds a point on each; from that point, rays are spawned in
//! random directions. A failure is a spawned ray that hits the shape again where it
//! cannot: anywhere, for rays leaving a convex shape outward or leaving a planar one;
//! within 2 p_error of the start (the surface it left) for rays going inward or leaving
//! the saddle-shaped hyperboloid; for a straight cylinder curve (width 0.1, 8 pieces),
//! anywhere, for rays leaving on the side the first ray came from. Inward rays are checked only where p_error is below
//! 1e-4 of the shape's smallest size and of the point's distance from the axis, and
//! only at least 1e-2 from tangent.
//!
//! "hit" is the share of shapes the first ray found: below f32's resolution where the
//! shape stands (a shape of 1e-6 at 1e7, where f32's spacing is 1), nothing can be hit,
//! and the summary gives the largest scale where under half the shapes were found.

use super::{DISTANCES, FAMILIES, KINDS, cases, dir, to_ray, transform};
use glam::{DMat4, DVec3, Vec3};
use pbrt_sppm::math::{Ray, Vector3};
use pbrt_sppm::sampling::{Rng, hash};
use pbrt_sppm::shapes::curve::{CurveShape, CurveType, Curves, Segment};
use pbrt_sppm::shapes::sphere::Sphere;
use pbrt_sppm::shapes::triangle::TriangleMesh;
use pbrt_sppm::shapes::{Cone, Cylinder, Disk, Hyperboloid, MeshFlags, Paraboloid, Quadric, QuadricShape};
use rayon::prelude::*;

/// A shape under test: a quadric, or one triangle in world space.
// One per case on the stack: boxing would only add an allocation.
#[allow(clippy::large_enum_variant)]
enum Shape {
    Quadric(QuadricShape, Quadric, DMat4),
    Triangle(TriangleMesh),
    Curve(CurveShape),
}

impl Shape {
    fn intersect(&self, r: &Ray) -> Option<pbrt_sppm::interaction::SurfaceInteraction> {
        match self {
            Shape::Quadric(s, ..) => s.intersect_t(r, f32::INFINITY).map(|h| s.interaction(&h)),
            Shape::Triangle(m) => {
                m.intersect_triangle(0, r, f32::INFINITY).map(|h| m.interaction(0, &h, MeshFlags::default()))
            }
            Shape::Curve(c) => {
                let hits = (0..c.piece_count()).filter_map(|k| c.intersect(k, r, f32::INFINITY));
                hits.min_by(|a, b| a.t.total_cmp(&b.t)).map(|h| c.interaction(&h))
            }
        }
    }

    fn hits(&self, r: &Ray) -> Option<f32> {
        match self {
            Shape::Quadric(s, ..) => s.intersect_t(r, f32::INFINITY).map(|h| h.t),
            Shape::Triangle(m) => m.intersect_triangle(0, r, f32::INFINITY).map(|h| h.t),
            Shape::Curve(c) => {
                (0..c.piece_count()).filter_map(|k| c.intersect(k, r, f32::INFINITY)).map(|h| h.t).reduce(f32::min)
            }
        }
    }

    /// A point on the surface, world space.
    fn point(&self, rng: &mut Rng) -> DVec3 {
        match self {
            Shape::Quadric(_, q, m) => m.transform_point3(q.point(rng.uniform() as f64, rng.uniform() as f64)),
            Shape::Triangle(m) => {
                let [a, b, c] = m.vertices(0);
                let (u, v) = (rng.uniform() as f64, rng.uniform() as f64);
                let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                a + u * (b - a) + v * (c - a)
            }
            Shape::Curve(c) => {
                c.render_from_object.transform_point3(DVec3::new(rng.uniform() as f64 * 2.0 - 1.0, 0.0, 0.0))
            }
        }
    }
}

fn unit_quadric(family: usize) -> Quadric {
    match family {
        0 => Quadric::Sphere(Sphere::new(1.0, -1.0, 1.0, 360.0)),
        1 => Quadric::Cylinder(Cylinder::new(1.0, -1.0, 1.0, 360.0)),
        2 => Quadric::Disk(Disk::new(0.0, 1.0, 0.3, 360.0)),
        3 => Quadric::Cone(Cone::new(1.0, 1.0, 360.0)),
        4 => Quadric::Paraboloid(Paraboloid::new(1.0, 0.0, 1.0, 360.0)),
        _ => match Hyperboloid::new(Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 1.0, 1.0), 360.0) {
            Ok(h) => Quadric::Hyperboloid(h),
            Err(e) => unreachable!("a fixed hyperboloid: {e}"),
        },
    }
}

fn make(family: usize, m: DMat4) -> Shape {
    if family == 7 {
        let cp = [-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0].map(|x| Vec3::new(x, 0.0, 0.0));
        let segments = vec![Segment { cp, width: [0.1, 0.1], normals: None }];
        let pieces = (0..8).map(|i| (0, i as f32 / 8.0, (i + 1) as f32 / 8.0)).collect();
        let curves = Curves { kind: CurveType::Cylinder, segments, pieces };
        return Shape::Curve(CurveShape::new(std::sync::Arc::new(curves), m, false));
    }
    if family == 6 {
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y].map(|v| m.transform_point3(v).as_vec3().to_array());
        return Shape::Triangle(TriangleMesh { p: p.to_vec(), indices: vec![0, 1, 2], ..Default::default() });
    }
    let q = unit_quadric(family);
    Shape::Quadric(QuadricShape::new(q.clone(), m, false), q, m)
}

/// (found, rays spawned, failures) for one random shape.
fn one_shape(family: usize, kind: usize, scale: f64, distance: f64, rays: usize, seed: u64) -> (bool, u64, u64) {
    let mut rng = Rng::new(seed);
    let (m, smallest) = transform(kind, scale, distance, &mut rng);
    let shape = make(family, m);
    let target = shape.point(&mut rng);
    let o = target + dir(&mut rng) * 10.0 * scale;
    let Some(si) = shape.intersect(&to_ray(o, target - o)) else { return (false, 0, 0) };
    let n = si.n.0.as_dvec3();
    // Which side is out, for the convex quadrics: away from the middle of the axis
    // segment (the sphere's centre; the cone's and paraboloid's mid-height), judged in
    // object space, where n·(p − c) is |p|², x² + y², (1 − z)/2 and z + 1/2.
    let outward = match &shape {
        Shape::Quadric(..) => {
            let c = DVec3::new(0.0, 0.0, if matches!(family, 3 | 4) { 0.5 } else { 0.0 });
            let n_obj = m.transpose().transform_vector3(n);
            if (m.inverse().transform_point3(si.p.0.as_dvec3()) - c).dot(n_obj) >= 0.0 { n } else { -n }
        }
        // The side the first ray came from.
        Shape::Triangle(_) | Shape::Curve(_) => n,
    };
    let planar = matches!(family, 2 | 6);
    let curve = family == 7;
    let outward = if curve && outward.dot(o - target) < 0.0 { -outward } else { outward };
    let convex = family != 5;
    let err = si.p_error.length() as f64;
    // Inward rays may meet the far side close by where the shape narrows (a cone's
    // apex): judge them only where both the shape and its distance from the axis at the
    // point are ten thousand times p_error.
    let p_obj = m.inverse().transform_point3(si.p.0.as_dvec3());
    let to_axis = (si.p.0.as_dvec3() - m.transform_point3(p_obj * DVec3::Z)).length();
    let resolvable = err < 1e-4 * smallest.min(to_axis);
    let mut fails = 0;
    for _ in 0..rays {
        let w = dir(&mut rng);
        let cos = w.dot(outward);
        let r = si.spawn_ray(Vector3(w.as_vec3()));
        let Some(t) = shape.hits(&r) else { continue };
        let near = (r.at(t).0 - si.p.0).length() as f64 <= 2.0 * err;
        let fail = if curve {
            cos > 0.0
        } else if planar || (convex && cos > 0.0) {
            true
        } else {
            resolvable && cos.abs() >= 1e-2 && near
        };
        fails += fail as u64;
    }
    (true, rays as u64, fails)
}

/// Prints the sweep and its summary; the summary follows the line naming "under 50% hit at".
pub fn run(shapes: usize, rays: usize) {
    let scales: Vec<f64> = (-6..=6).map(|e| 10f64.powi(e)).collect();
    println!("{shapes} shapes a case, {rays} rays spawned from each; failures per 10^7 spawned rays");
    println!(
        "{:<12} {:>9} {:<14} {:>7} {:>6} {:>11} {:>9} {:>12}",
        "family", "distance", "transform", "scale", "hit", "rays", "failures", "per 10^7"
    );
    let mut summary = Vec::new();
    for (f, family) in FAMILIES.iter().enumerate() {
        let (mut total_rays, mut total_fails) = (0u64, 0u64);
        let (mut failing, mut unresolved) = (Vec::new(), Vec::new());
        for &d in &DISTANCES {
            for &s in &scales {
                let (mut case_ok, mut resolved) = (true, true);
                for (k, kind) in KINDS.iter().enumerate() {
                    let seed = |i: usize| hash(&[i as u64, f as u64, k as u64, s.to_bits(), d.to_bits()]);
                    let res: Vec<(bool, u64, u64)> =
                        (0..shapes).into_par_iter().map(|i| one_shape(f, k, s, d, rays, seed(i))).collect();
                    let hit = res.iter().filter(|r| r.0).count();
                    let (n, fails) = res.iter().fold((0, 0), |a, r| (a.0 + r.1, a.1 + r.2));
                    (total_rays, total_fails) = (total_rays + n, total_fails + fails);
                    let per = if n > 0 { fails as f64 * 1e7 / n as f64 } else { 0.0 };
                    let hit_share = hit as f64 / shapes as f64;
                    case_ok &= fails == 0;
                    resolved &= hit_share >= 0.5;
                    println!(
                        "{family:<12} {d:>9.0e} {kind:<14} {s:>7.0e} {:>5.0}% {n:>11} {fails:>9} {per:>12.1}",
                        100.0 * hit_share
                    );
                }
                if !case_ok {
                    failing.push(format!("{s:.0e}@{d:.0e}"));
                }
                if !resolved {
                    unresolved.push(s);
                }
            }
        }
        let per = total_fails as f64 * 1e7 / total_rays.max(1) as f64;
        let below = unresolved.iter().fold(0.0f64, |a, &s| a.max(s));
        summary.push((family, total_rays, total_fails, per, failing, below));
    }
    println!(
        "\n{:<12} {:>11} {:>9} {:>10} {:>16}   scale@distance cases with failures",
        "family", "rays", "failures", "per 10^7", "under 50% hit at"
    );
    for (family, n, fails, per, failing, below) in summary {
        let cases = cases(&failing);
        let below = if below > 0.0 { format!("scale ≤ {below:.0e}") } else { "-".into() };
        println!("{family:<12} {n:>11} {fails:>9} {per:>10.2} {below:>16}   {cases}");
    }
}
