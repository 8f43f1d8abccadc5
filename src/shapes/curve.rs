//! Curves (pbrt-v3 and v4): cubic Bézier segments swept with a width, intersected as
//! pbrt intersects them, by recursive subdivision against the ray.
//!
//! ```text
//! Shape "curve" "point3 P" [p0 p1 p2 p3 ...]
//!     "string basis" "bezier"      # or "bspline" (uniform); converted to Bézier segments
//!     "integer degree" 3           # or 2 (elevated to cubic)
//!     "string type" "flat"         # "ribbon" (needs "normal N", one per segment end) or "cylinder"
//!     "float width" 1  "float width0" 1  "float width1" 1   # width0/width1 default to width
//!     "integer splitdepth" 3       # each segment is 2^splitdepth primitives
//! ```
//! A `flat` curve always faces the ray; a `cylinder` is flat too, but its normal turns
//! across the width so it shades as a tube; a `ribbon`'s width follows the normals
//! given at the segment ends, interpolated by slerp. The hit's (u, v) are pbrt's: u
//! along the whole statement's segment, v across the width; the error bound is twice
//! the width, as pbrt's, so rays leaving a curve start clear of it. Curves cannot be
//! area lights (pbrt cannot sample them and stops).

use super::mesh_params::MAX_COORDINATE;
use super::{Built, ShapeContext};
use crate::interaction::{Shading, SurfaceInteraction};
use crate::limits::Limits;
use crate::math::{Bounds3, Normal3, Point3, Ray, Vector3};
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::values::Res;
use glam::{DMat3, DMat4, DVec3, Vec3};
use std::sync::Arc;

pub const NAME: &str = "curve";

/// How a curve is shaped across its width.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveType {
    Flat,
    Cylinder,
    Ribbon,
}

/// One cubic Bézier segment of a statement (pbrt's `CurveCommon`), in object space.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    pub cp: [Vec3; 4],
    pub width: [f32; 2],
    /// A ribbon's unit normals at the two ends, the angle between them and 1/sin of it.
    pub normals: Option<([Vec3; 2], f32, f32)>,
}

/// The curves of one `Shape "curve"` statement: its Bézier segments and the pieces
/// (u ranges of a segment) the BVH holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Curves {
    pub kind: CurveType,
    pub segments: Vec<Segment>,
    /// (segment, u_min, u_max) per primitive.
    pub pieces: Vec<(u32, f32, f32)>,
}

/// Curves with their transform, ready to intersect.
#[derive(Clone, Debug)]
pub struct CurveShape {
    pub curves: Arc<Curves>,
    pub render_from_object: DMat4,
    pub object_from_render: DMat4,
    pub reverse_orientation: bool,
    /// The error bound in widths at the hit: 2 in pbrt-v3, 1 in pbrt-v4.
    pub error_widths: f32,
}

/// The cheap result of a ray–curve test, in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveHit {
    pub t: f32,
    pub uv: [f32; 2],
    pub p: Vec3,
    pub dpdu: Vec3,
    pub dpdv: Vec3,
    pub width: f32,
}

fn lerp(t: f32, a: Vec3, b: Vec3) -> Vec3 {
    (1.0 - t) * a + t * b
}

fn lerp1(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// The Bézier control points of the part of `cp` between `u0` and `u1` (by blossoming).
fn blossom_segment(cp: &[Vec3; 4], u0: f32, u1: f32) -> [Vec3; 4] {
    let blossom = |a: f32, b: f32, c: f32| {
        let l = [lerp(a, cp[0], cp[1]), lerp(a, cp[1], cp[2]), lerp(a, cp[2], cp[3])];
        lerp(c, lerp(b, l[0], l[1]), lerp(b, l[1], l[2]))
    };
    [blossom(u0, u0, u0), blossom(u0, u0, u1), blossom(u0, u1, u1), blossom(u1, u1, u1)]
}

/// The point at `u` and the derivative (pbrt's fallback where it vanishes).
fn eval_bezier(cp: &[Vec3; 4], u: f32) -> (Vec3, Vec3) {
    let c1 = [lerp(u, cp[0], cp[1]), lerp(u, cp[1], cp[2]), lerp(u, cp[2], cp[3])];
    let c2 = [lerp(u, c1[0], c1[1]), lerp(u, c1[1], c1[2])];
    let d = if (c2[1] - c2[0]).length_squared() > 0.0 { 3.0 * (c2[1] - c2[0]) } else { cp[3] - cp[0] };
    (lerp(u, c2[0], c2[1]), d)
}

fn subdivide(cp: &[Vec3; 4]) -> [Vec3; 7] {
    [
        cp[0],
        (cp[0] + cp[1]) / 2.0,
        (cp[0] + 2.0 * cp[1] + cp[2]) / 4.0,
        (cp[0] + 3.0 * cp[1] + 3.0 * cp[2] + cp[3]) / 8.0,
        (cp[1] + 2.0 * cp[2] + cp[3]) / 4.0,
        (cp[2] + cp[3]) / 2.0,
        cp[3],
    ]
}

/// pbrt's integer log2, rounded to nearest, 0 below 1.
fn log2_int(v: f32) -> i32 {
    if v < 1.0 {
        return 0;
    }
    let bits = v.to_bits();
    (bits >> 23) as i32 - 127 + i32::from(bits & (1 << 22) != 0)
}

/// The ray's frame: x along `up` × d, z along d (pbrt's `LookAt` from the origin).
struct RayFrame {
    o: Vec3,
    axes: [Vec3; 3],
}

impl RayFrame {
    fn new(o: Vec3, d: Vec3, up: Vec3) -> RayFrame {
        let dir = d.normalize();
        let right = up.normalize().cross(dir).normalize();
        RayFrame { o, axes: [right, dir.cross(right), dir] }
    }
    fn point(&self, p: Vec3) -> Vec3 {
        let q = p - self.o;
        Vec3::new(self.axes[0].dot(q), self.axes[1].dot(q), self.axes[2].dot(q))
    }
    fn vector(&self, v: Vec3) -> Vec3 {
        Vec3::new(self.axes[0].dot(v), self.axes[1].dot(v), self.axes[2].dot(v))
    }
    fn to_object(&self, v: Vec3) -> Vec3 {
        v.x * self.axes[0] + v.y * self.axes[1] + v.z * self.axes[2]
    }
}

/// Whether the control points' box, grown by half of `width`, misses the ray (the z
/// axis in the ray frame) between 0 and `z_max`.
fn box_misses(cp: &[Vec3], width: f32, z_max: f32) -> bool {
    let (lo, hi) = cp.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let h = 0.5 * width;
    hi.y + h < 0.0 || lo.y - h > 0.0 || hi.x + h < 0.0 || lo.x - h > 0.0 || hi.z + h < 0.0 || lo.z - h > z_max
}

/// What the recursion needs besides the control points.
struct Query<'a> {
    seg: &'a Segment,
    kind: CurveType,
    frame: RayFrame,
    ray_d: Vec3,
    ray_length: f32,
    z_max: f32,
}

impl Segment {
    /// The width at `u`.
    fn width_at(&self, u: f32) -> f32 {
        lerp1(u, self.width[0], self.width[1])
    }

    /// The larger width at the two ends of [u0, u1] (widths are linear in u).
    fn max_width(&self, u0: f32, u1: f32) -> f32 {
        self.width_at(u0).max(self.width_at(u1))
    }
}

impl Curves {
    /// The pieces' object-space box, each grown by half its width.
    pub fn object_bounds(&self) -> [DVec3; 2] {
        let mut b = [DVec3::INFINITY, DVec3::NEG_INFINITY];
        for seg in &self.segments {
            let h = 0.5 * seg.width[0].max(seg.width[1]) as f64;
            for p in seg.cp {
                b = [b[0].min(p.as_dvec3() - h), b[1].max(p.as_dvec3() + h)];
            }
        }
        b
    }

    /// pbrt's area estimate (each piece's control polygon length times its mean width)
    /// under the linear map `m`: lengths mapped, widths scaled by |det m|^(1/3).
    pub fn area_under(&self, m: DMat3) -> f64 {
        let scale = m.determinant().abs().cbrt();
        self.pieces
            .iter()
            .map(|&(s, u0, u1)| {
                let seg = &self.segments[s as usize];
                let cp = blossom_segment(&seg.cp, u0, u1).map(|p| m * p.as_dvec3());
                let length: f64 = cp.windows(2).map(|w| w[0].distance(w[1])).sum();
                let width = 0.5 * (seg.width_at(u0) + seg.width_at(u1));
                length * width as f64 * scale
            })
            .sum()
    }

    /// For `check --shapes`.
    pub fn params(&self) -> serde_json::Value {
        let kind = match self.kind {
            CurveType::Flat => "flat",
            CurveType::Cylinder => "cylinder",
            CurveType::Ribbon => "ribbon",
        };
        serde_json::json!({ "type": kind, "segments": self.segments.len(), "pieces": self.pieces.len() })
    }

    /// Round tubes of the curves' widths in the space of `m`, for exporters without
    /// curves: 8 steps along each segment, 6 around.
    pub fn tubes(&self, m: &DMat4) -> super::TriangleMesh {
        const ALONG: u32 = 8;
        const AROUND: u32 = 6;
        let mut mesh = super::TriangleMesh::default();
        for seg in &self.segments {
            let base = mesh.p.len() as u32;
            for i in 0..=ALONG {
                let u = i as f32 / ALONG as f32;
                let (p, d) = eval_bezier(&seg.cp, u);
                let (a, b) = d.normalize_or_zero().any_orthonormal_pair();
                let r = 0.5 * seg.width_at(u);
                for k in 0..AROUND {
                    let phi = std::f32::consts::TAU * k as f32 / AROUND as f32;
                    let q = p + r * (phi.cos() * a + phi.sin() * b);
                    mesh.p.push(m.transform_point3(q.as_dvec3()).as_vec3().to_array());
                }
            }
            for i in 0..ALONG {
                for k in 0..AROUND {
                    let v = |i: u32, k: u32| base + i * AROUND + k % AROUND;
                    mesh.indices.extend([v(i, k), v(i + 1, k), v(i + 1, k + 1), v(i, k), v(i + 1, k + 1), v(i, k + 1)]);
                }
            }
        }
        mesh
    }
}

impl CurveShape {
    /// Curves with pbrt-v3's error bound (see [`CurveShape::error_widths`]).
    pub fn new(curves: Arc<Curves>, render_from_object: DMat4, reverse_orientation: bool) -> CurveShape {
        let object_from_render = render_from_object.inverse();
        CurveShape { curves, object_from_render, render_from_object, reverse_orientation, error_widths: 2.0 }
    }

    pub fn piece_count(&self) -> usize {
        self.curves.pieces.len()
    }

    /// A piece's render-space bounds: its control points' box grown by half its width.
    pub fn bounds(&self, piece: usize) -> Bounds3 {
        let (s, u0, u1) = self.curves.pieces[piece];
        let seg = &self.curves.segments[s as usize];
        let cp = blossom_segment(&seg.cp, u0, u1);
        let h = 0.5 * seg.max_width(u0, u1);
        let lo = cp.iter().fold(Vec3::INFINITY, |a, &p| a.min(p)) - Vec3::splat(h);
        let hi = cp.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p)) + Vec3::splat(h);
        crate::math::bounds::transform_bounds_widened(&self.render_from_object, [lo.as_dvec3(), hi.as_dvec3()])
    }

    /// The hit of a piece before `t_max` (pbrt's `Curve::Intersect`).
    pub fn intersect(&self, piece: usize, ray: &Ray, t_max: f32) -> Option<CurveHit> {
        let (s, u0, u1) = self.curves.pieces[piece];
        let seg = &self.curves.segments[s as usize];
        let o = self.object_from_render.transform_point3(ray.o.0.as_dvec3()).as_vec3();
        let d = self.object_from_render.transform_vector3(ray.d.0.as_dvec3()).as_vec3();
        let cp_obj = blossom_segment(&seg.cp, u0, u1);
        let mut up = d.cross(cp_obj[3] - cp_obj[0]);
        if up.length_squared() == 0.0 {
            up = d.any_orthonormal_vector();
        }
        let frame = RayFrame::new(o, d, up);
        let cp = cp_obj.map(|p| frame.point(p));
        let ray_length = d.length();
        let z_max = ray_length * t_max;
        if box_misses(&cp, seg.max_width(u0, u1), z_max) {
            return None;
        }
        let mut l0 = 0.0f32;
        for i in 0..2 {
            l0 = l0.max((cp[i] - 2.0 * cp[i + 1] + cp[i + 2]).abs().max_element());
        }
        let eps = seg.width[0].max(seg.width[1]) * 0.05;
        let depth = (log2_int(std::f32::consts::SQRT_2 * 6.0 * l0 / (8.0 * eps)) / 2).clamp(0, 10);
        let q = Query { seg, kind: self.curves.kind, frame, ray_d: d, ray_length, z_max };
        let mut best = None;
        recurse(&q, &cp, [u0, u1], depth, &mut best);
        best
    }

    /// The full interaction of a hit, in render space.
    pub fn interaction(&self, hit: &CurveHit) -> SurfaceInteraction {
        let m = self.render_from_object;
        let m3 = DMat3::from_mat4(m);
        let dpdu = m3 * hit.dpdu.as_dvec3();
        let dpdv = m3 * hit.dpdv.as_dvec3();
        let n = dpdu.cross(dpdv).normalize_or_zero();
        let n = Normal3(if self.reverse_orientation { -n } else { n }.as_vec3());
        let p = m.transform_point3(hit.p.as_dvec3());
        // pbrt's bound: the width (v4) or twice it (v3) in object space, mapped to render
        // space.
        let p_error = (m3.abs() * DVec3::splat((self.error_widths * hit.width) as f64)).as_vec3()
            + crate::math::float::gamma(3) * p.abs().as_vec3()
            + Vec3::splat(f32::MIN_POSITIVE);
        let (dpdu, dpdv) = (Vector3(dpdu.as_vec3()), Vector3(dpdv.as_vec3()));
        let shading = Shading { n, dpdu, dpdv, dndu: Normal3(Vec3::ZERO), dndv: Normal3(Vec3::ZERO) };
        SurfaceInteraction {
            p: Point3(p.as_vec3()),
            p_error,
            t: hit.t,
            uv: hit.uv,
            n,
            dpdu,
            dpdv,
            dndu: shading.dndu,
            dndv: shading.dndv,
            shading,
            time: 0.0,
            face: 0,
        }
    }
}

/// pbrt's `recursiveIntersect`: halves the segment `depth` times, skipping halves whose
/// boxes miss the ray, and tests the leaves; keeps the nearest hit in `best`.
// DEVIATION(pbrt): robustness. pbrt-v3 keeps the last leaf hit it finds, which for a
// piece that folds back across the ray may be the farther one; this keeps the nearest.
fn recurse(q: &Query, cp: &[Vec3; 4], u: [f32; 2], depth: i32, best: &mut Option<CurveHit>) {
    if depth <= 0 {
        if let Some(h) = leaf(q, cp, u)
            && best.is_none_or(|b| h.t < b.t)
        {
            *best = Some(h);
        }
        return;
    }
    let split = subdivide(cp);
    let us = [u[0], (u[0] + u[1]) / 2.0, u[1]];
    for half in 0..2 {
        let cps: [Vec3; 4] = split[3 * half..3 * half + 4].try_into().unwrap();
        let z_max = best.map_or(q.z_max, |b| b.t * q.ray_length);
        if !box_misses(&cps, q.seg.max_width(us[half], us[half + 1]), z_max) {
            recurse(q, &cps, [us[half], us[half + 1]], depth - 1, best);
        }
    }
}

/// The leaf test of pbrt's `recursiveIntersect`, with (u, v), ∂p/∂u and ∂p/∂v.
fn leaf(q: &Query, cp: &[Vec3; 4], [u0, u1]: [f32; 2]) -> Option<CurveHit> {
    // The ray must pass between the perpendiculars at the two ends.
    if (cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x) < 0.0
        || (cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x) < 0.0
    {
        return None;
    }
    let dir = cp[3].truncate() - cp[0].truncate();
    let denom = dir.length_squared();
    if denom == 0.0 {
        return None;
    }
    let w = (-cp[0].truncate()).dot(dir) / denom;
    let u = lerp1(w, u0, u1).clamp(u0, u1);
    let seg = q.seg;
    let mut hit_width = seg.width_at(u);
    let mut n_hit = Vec3::ZERO;
    if let (CurveType::Ribbon, Some((n, angle, inv_sin))) = (q.kind, seg.normals) {
        // DEVIATION(pbrt): robustness. pbrt-v3 divides by sin 0 for a ribbon whose end
        // normals agree (NaN width and normal); pbrt-v4 takes the normal as it is.
        n_hit = if angle == 0.0 {
            n[0]
        } else {
            ((1.0 - u) * angle).sin() * inv_sin * n[0] + (u * angle).sin() * inv_sin * n[1]
        };
        hit_width *= n_hit.dot(q.ray_d).abs() / q.ray_length;
    }
    let (pc, dpcdw) = eval_bezier(cp, w.clamp(0.0, 1.0));
    let dist2 = pc.x * pc.x + pc.y * pc.y;
    // DEVIATION(pbrt): robustness. A width of 0 (a ribbon seen edge-on, a curve tapering
    // to nothing) is never hit: pbrt's v of 0/0 there gives NaN normals.
    if hit_width.is_nan() || hit_width <= 0.0 || dist2 > hit_width * hit_width * 0.25 || pc.z < 0.0 || pc.z > q.z_max {
        return None;
    }
    let dist = dist2.sqrt();
    let v = if dpcdw.x * -pc.y + pc.x * dpcdw.y > 0.0 { 0.5 + dist / hit_width } else { 0.5 - dist / hit_width };
    let t = pc.z / q.ray_length;
    let (_, dpdu) = eval_bezier(&seg.cp, u);
    let dpdv = match q.kind {
        CurveType::Ribbon => n_hit.cross(dpdu).normalize() * hit_width,
        CurveType::Flat | CurveType::Cylinder => {
            let along = q.frame.vector(dpdu);
            let mut across = Vec3::new(-along.y, along.x, 0.0).normalize() * hit_width;
            if q.kind == CurveType::Cylinder {
                // Turned about the curve by −θ, θ from −90° to 90° across the width.
                let theta = lerp1(v, -90.0, 90.0).to_radians();
                let a = along.normalize();
                across = across * (-theta).cos() + a.cross(across) * (-theta).sin();
            }
            q.frame.to_object(across)
        }
    };
    let p = q.frame.o + q.ray_d * t;
    Some(CurveHit { t, uv: [u, v], p, dpdu, dpdv, width: hit_width })
}

/// Reads a `Shape "curve"` statement into Bézier segments split into pieces.
pub fn read(ctx: &mut ShapeContext, p: &ParamList, span: Span) -> Res<Built> {
    let at = |name: &str| p.named(name).map_or(span, |q| q.value_span);
    let width = p.float("width")?.unwrap_or(1.0);
    let widths = [p.float("width0")?.unwrap_or(width), p.float("width1")?.unwrap_or(width)];
    // Widths and points past ±1e18 overflow f32 arithmetic (a width of 1e30 gave vcm NaN).
    if let Some(k) = (0..2).find(|&k| !(widths[k] >= 0.0 && widths[k] <= MAX_COORDINATE)) {
        let name = if p.named(&format!("width{k}")).is_some() { format!("width{k}") } else { "width".into() };
        let msg = format!("curve: {name} must be a number from 0 to {MAX_COORDINATE:e}");
        return Err(Diagnostic::error(at(&name), msg));
    }
    // pbrt-v3 reports these and leaves the curve out; pbrt-v4 stops.
    let degree = p.int("degree")?.unwrap_or(3);
    if degree != 2 && degree != 3 {
        return ctx.left_out_by_v3(p, at("degree"), format!("curve: degree {degree}; only 2 and 3 are supported"));
    }
    let degree = degree as usize;
    let basis = p.string("basis")?.unwrap_or_else(|| "bezier".into());
    if basis != "bezier" && basis != "bspline" {
        let msg = format!("curve: basis \"{basis}\"; expected \"bezier\" or \"bspline\"");
        return ctx.left_out_by_v3(p, at("basis"), msg);
    }
    let Some(points) = p.array("P", ParamType::Point3)? else {
        return ctx.left_out_by_v3(p, span, "curve needs \"point3 P\"".into());
    };
    let cp: Vec<Vec3> = points.floats().chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
    if !cp.iter().all(|p| p.is_finite() && p.abs().max_element() <= MAX_COORDINATE) {
        let msg = format!("curve: control points must be finite and within ±{MAX_COORDINATE:e}");
        return Err(Diagnostic::error(points.value_span, msg));
    }
    let count = match segment_count(cp.len(), &basis, degree) {
        Ok(count) => count,
        Err(msg) => return ctx.left_out_by_v3(p, points.value_span, msg),
    };
    let kind = curve_type(ctx, p, at("type"))?;
    if let Some((at, msg)) = ribbon_mismatch(p, span, kind, count)? {
        return ctx.left_out_by_v3(p, at, msg);
    }
    let normals = ribbon_normals(ctx, p, kind)?;
    let split = split_depth(p, at("splitdepth"))?;
    let pieces_per = 1u64 << split;
    let total = count as u64 * pieces_per;
    if total > ctx.files.limits.triangles {
        let what = format!("curve: {count} segments split {pieces_per} ways make {total} pieces, which");
        return Err(Diagnostic::error(at("splitdepth"), Limits::over(what, "triangles", ctx.files.limits.triangles)));
    }
    let segments: Vec<Segment> = (0..count)
        .map(|s| Segment {
            cp: bezier_segment(&cp, &basis, degree, s),
            width: [
                lerp1(s as f32 / count as f32, widths[0], widths[1]),
                lerp1((s + 1) as f32 / count as f32, widths[0], widths[1]),
            ],
            normals: normals.as_ref().map(|n| ribbon_ends(n[s], n[s + 1])),
        })
        .collect();
    let pieces = (0..count as u32)
        .flat_map(|s| {
            (0..pieces_per).map(move |i| (s, i as f32 / pieces_per as f32, (i + 1) as f32 / pieces_per as f32))
        })
        .collect();
    Ok(Built::Curves(Curves { kind, segments, pieces }))
}

/// `type`: flat, ribbon or cylinder; another name is a warning and a cylinder, as pbrt.
fn curve_type(ctx: &mut ShapeContext, p: &ParamList, at: Span) -> Res<CurveType> {
    Ok(match p.string("type")?.as_deref() {
        None | Some("flat") => CurveType::Flat,
        Some("ribbon") => CurveType::Ribbon,
        Some("cylinder") => CurveType::Cylinder,
        Some(other) => {
            ctx.warn.push(Diagnostic::warning(at, format!("curve: unknown type \"{other}\"; a cylinder, as in pbrt")));
            CurveType::Cylinder
        }
    })
}

/// The number of segments `n` control points make in `basis`, or why they make none.
fn segment_count(n: usize, basis: &str, degree: usize) -> Result<usize, String> {
    let count = if basis == "bezier" {
        (n > degree && (n - 1).is_multiple_of(degree)).then(|| (n - 1) / degree)
    } else {
        (n > degree).then(|| n - degree)
    };
    count.ok_or_else(|| {
        let need = if basis == "bezier" {
            format!("{} + n·{degree}", degree + 1)
        } else {
            format!("at least {}", degree + 1)
        };
        format!("curve: {n} control points; the degree-{degree} {basis} basis needs {need}")
    })
}

/// Where and why a ribbon's normals do not fit its `count` segments (missing, or not
/// one per segment end); `None` when they do or the curve is not a ribbon.
fn ribbon_mismatch(p: &ParamList, span: Span, kind: CurveType, count: usize) -> Res<Option<(Span, String)>> {
    if kind != CurveType::Ribbon {
        return Ok(None);
    }
    Ok(match p.array("N", ParamType::Normal3)? {
        None => Some((span, "curve: a ribbon needs \"normal N\" at its segment ends".into())),
        Some(n) if n.floats().len() != 3 * (count + 1) => {
            let given = n.floats().len() / 3;
            Some((n.value_span, format!("curve: {given} normals; a ribbon of {count} segments needs {}", count + 1)))
        }
        Some(_) => None,
    })
}

/// A ribbon's normals, one per segment end ([`ribbon_mismatch`] has checked their
/// count); ignored with a warning on other types.
fn ribbon_normals(ctx: &mut ShapeContext, p: &ParamList, kind: CurveType) -> Res<Option<Vec<Vec3>>> {
    let n = p.array("N", ParamType::Normal3)?;
    match (kind, n) {
        (CurveType::Ribbon, Some(n)) => {
            let normals: Vec<Vec3> = n.floats().chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
            // pbrt normalises them blindly: NaN widths and normals for a zero normal.
            if !normals.iter().all(|v| v.is_finite() && v.length_squared() > 0.0) {
                return Err(Diagnostic::error(n.value_span, "curve: a ribbon normal is zero or not finite"));
            }
            Ok(Some(normals))
        }
        (_, Some(n)) => {
            ctx.warn
                .push(Diagnostic::warning(n.span, "curve: normals are only used by \"ribbon\" curves (as in pbrt)"));
            Ok(None)
        }
        (_, None) => Ok(None),
    }
}

/// The end normals, normalised, the angle between them and 1/sin of it. pbrt-v3
/// clamps the cosine to [0, 1], so normals more than 90° apart turn by 90°.
fn ribbon_ends(a: Vec3, b: Vec3) -> ([Vec3; 2], f32, f32) {
    let n = [a.normalize(), b.normalize()];
    let angle = n[0].dot(n[1]).clamp(0.0, 1.0).acos();
    (n, angle, 1.0 / angle.sin())
}

/// `splitdepth`, an integer or (as pbrt-v3 also reads it) a float; 0 to 20.
fn split_depth(p: &ParamList, at: Span) -> Res<u32> {
    let d = match p.int("splitdepth")? {
        Some(d) => d,
        None => p.float("splitdepth")?.map_or(3, |f| f as i32),
    };
    if !(0..=20).contains(&d) {
        return Err(Diagnostic::error(at, format!("curve: splitdepth {d}; expected 0 to 20")));
    }
    Ok(d as u32)
}

/// Segment `s`'s cubic Bézier control points, converted as pbrt converts them.
fn bezier_segment(cp: &[Vec3], basis: &str, degree: usize, s: usize) -> [Vec3; 4] {
    match (basis, degree) {
        ("bezier", 3) => [cp[3 * s], cp[3 * s + 1], cp[3 * s + 2], cp[3 * s + 3]],
        ("bezier", _) => {
            let c = &cp[2 * s..2 * s + 3];
            [c[0], lerp(2.0 / 3.0, c[0], c[1]), lerp(1.0 / 3.0, c[1], c[2]), c[2]]
        }
        (_, 2) => {
            let c = &cp[s..s + 3];
            let (p11, p22) = (lerp(0.5, c[0], c[1]), lerp(0.5, c[1], c[2]));
            [p11, lerp(2.0 / 3.0, p11, c[1]), lerp(1.0 / 3.0, c[1], p22), p22]
        }
        _ => {
            let c = &cp[s..s + 4];
            let p122 = lerp(2.0 / 3.0, c[0], c[1]);
            let p223 = lerp(1.0 / 3.0, c[1], c[2]);
            let p233 = lerp(2.0 / 3.0, c[1], c[2]);
            let p334 = lerp(1.0 / 3.0, c[2], c[3]);
            [lerp(0.5, p122, p223), p223, p233, lerp(0.5, p233, p334)]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(kind: CurveType, width: f32) -> CurveShape {
        // Evenly spaced: u runs uniformly along the line.
        let cp = [-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0].map(|x| Vec3::new(x, 0.0, 0.0));
        let normals = (kind == CurveType::Ribbon).then(|| ribbon_ends(Vec3::Z, Vec3::Z));
        let curves = Curves {
            kind,
            segments: vec![Segment { cp, width: [width, width], normals }],
            pieces: vec![(0, 0.0, 0.5), (0, 0.5, 1.0)],
        };
        CurveShape::new(Arc::new(curves), DMat4::IDENTITY, false)
    }

    fn down(x: f32, y: f32) -> Ray {
        Ray::new(Point3(Vec3::new(x, y, 5.0)), Vector3(Vec3::new(0.0, 0.0, -2.0)))
    }

    #[test]
    fn a_straight_flat_curve_is_a_strip_of_its_width_facing_the_ray() {
        let c = straight(CurveType::Flat, 0.2);
        let h = c.intersect(1, &down(0.5, 0.05), f32::INFINITY).expect("hit");
        assert!((h.t - 2.5).abs() < 1e-5, "{h:?}");
        assert!((h.uv[0] - 0.75).abs() < 1e-4 && ((h.uv[1] - 0.5).abs() - 0.25).abs() < 1e-4, "{h:?}");
        assert_eq!(c.intersect(1, &down(0.5, 0.11), f32::INFINITY), None);
        assert_eq!(c.intersect(0, &down(0.5, 0.05), f32::INFINITY), None, "the other piece");
        assert_eq!(c.intersect(1, &down(0.5, 0.0), 2.4), None, "beyond t_max");
        let si = c.interaction(&h);
        assert!(si.n.0.z.abs() > 0.9999, "faces the ray: {:?}", si.n);
        assert!(si.p_error.min_element() >= 0.4, "twice the width");
    }

    #[test]
    fn a_cylinder_turns_its_normal_across_the_width() {
        let c = straight(CurveType::Cylinder, 0.2);
        let centre = c.interaction(&c.intersect(1, &down(0.5, 0.0), f32::INFINITY).unwrap());
        let edge = c.interaction(&c.intersect(1, &down(0.5, 0.095), f32::INFINITY).unwrap());
        assert!(centre.n.0.z.abs() > 0.999, "{:?}", centre.n);
        assert!(edge.n.0.y.abs() > 0.99, "{:?}", edge.n);
    }

    #[test]
    fn a_ribbon_narrows_as_it_turns_edge_on_and_equal_normals_stay_finite() {
        // Seen at 45°, a ribbon in the xy plane keeps the rays that cross it within
        // |y| ≤ 0.1 at z = 0; a flat curve always shows its full width to the ray.
        let slanted = |y: f32| Ray::new(Point3(Vec3::new(0.5, y - 5.0, 5.0)), Vector3(Vec3::new(0.0, 1.0, -1.0)));
        let (ribbon, flat) = (straight(CurveType::Ribbon, 0.2), straight(CurveType::Flat, 0.2));
        let h = ribbon.intersect(1, &slanted(0.095), f32::INFINITY).expect("inside the ribbon");
        assert!(ribbon.interaction(&h).n.0.is_finite() && ribbon.interaction(&h).n.0.z.abs() > 0.999);
        assert!(ribbon.intersect(1, &slanted(0.105), f32::INFINITY).is_none());
        assert!(flat.intersect(1, &slanted(0.105), f32::INFINITY).is_some());
    }

    #[test]
    fn rays_leaving_a_curve_toward_the_viewer_never_hit_it_again() {
        // A straight cylinder at scales 1e-4…1e4 and 1e5 from the origin: every ray
        // spawned back to the side the first ray came from must miss it.
        let mut rng = crate::sampling::Rng::new(7);
        let mut spawned = 0;
        for e in -4..=4 {
            let scale = 10f64.powi(e);
            let m = DMat4::from_translation(DVec3::new(1e5, -3e4, 2e4))
                * DMat4::from_rotation_y(0.7)
                * DMat4::from_scale(DVec3::splat(scale));
            let c = CurveShape::new(straight(CurveType::Cylinder, 0.1).curves, m, false);
            for _ in 0..200 {
                let x = 2.0 * rng.uniform() - 1.0;
                let target = m.transform_point3(DVec3::new(x as f64, 0.0, 0.0));
                let from = m.transform_point3(DVec3::new(x as f64, 3.0 * (rng.uniform() as f64 - 0.5), 5.0));
                let ray = Ray::new(Point3(from.as_vec3()), Vector3((target - from).as_vec3()));
                let hit = (0..c.piece_count())
                    .filter_map(|k| c.intersect(k, &ray, f32::INFINITY))
                    .min_by(|a, b| a.t.total_cmp(&b.t));
                let Some(hit) = hit else { continue };
                let si = c.interaction(&hit);
                let back = if si.n.0.dot(-ray.d.0) > 0.0 { si.n.0 } else { -si.n.0 };
                for _ in 0..50 {
                    let w = crate::sampling::uniform_sphere([rng.uniform(), rng.uniform()]);
                    let w = if w.dot(back) > 0.0 { w } else { -w };
                    let r = si.spawn_ray(Vector3(w));
                    spawned += 1;
                    assert!(
                        (0..c.piece_count()).all(|k| c.intersect(k, &r, f32::INFINITY).is_none()),
                        "scale {scale}: {si:?} {w}"
                    );
                }
            }
        }
        assert!(spawned > 50_000, "{spawned}");
    }

    #[test]
    fn bspline_and_quadratic_segments_convert_as_pbrt() {
        // A uniform cubic B-spline of collinear, evenly spaced points is the line itself.
        let pts: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let s = bezier_segment(&pts, "bspline", 3, 1);
        for (k, p) in s.iter().enumerate() {
            assert!((p.x - (2.0 + k as f32 / 3.0)).abs() < 1e-6, "{s:?}");
        }
        // Degree elevation keeps the curve: the midpoint of a quadratic.
        let q = [Vec3::ZERO, Vec3::new(1.0, 2.0, 0.0), Vec3::new(2.0, 0.0, 0.0)];
        let c = bezier_segment(&q, "bezier", 2, 0);
        assert!((eval_bezier(&c, 0.5).0 - Vec3::new(1.0, 1.0, 0.0)).length() < 1e-6);
    }
}
