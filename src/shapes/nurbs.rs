//! pbrt-v3's NURBS patch, evaluated and diced at load into a 30 × 30 grid of vertices
//! (two triangles per cell, shading normals from the surface's derivatives, (u, v) the
//! surface parameters), as pbrt-v3 does, so images agree.
//!
//! ```text
//! Shape "nurbs" "integer nu" 4 "integer nv" 4 "integer uorder" 3 "integer vorder" 3
//!     "float uknots" [0 0 0 .5 1 1 1] "float vknots" [0 0 0 .5 1 1 1]
//!     "float u0" 0 "float u1" 1 "float v0" 0 "float v1" 1      # default: the knots' valid range
//!     "point P" [...]            # nu·nv control points, u fastest
//!   # or "float Pw" [x y z w ...]: homogeneous points (x, y, z already multiplied by w)
//! ```
//! The evaluation is pbrt-v3's de Boor recurrence in single precision. pbrt-v3 reads
//! out of bounds or stops with a failed assertion for orders below 2, fewer control
//! points than the order, decreasing knots and parameter ranges outside the knots, and
//! writes NaN vertices where a weight is 0; each of those is a located error here.

use super::heightfield::grid_indices;
use super::{Built, ShapeContext, TriangleMesh};
use crate::parser::error::Diagnostic;
use crate::parser::params::{Param, ParamList, ParamType};
use crate::parser::source::Span;
use crate::values::Res;
use glam::{Vec3, Vec4};

pub const NAME: &str = "nurbs";

/// pbrt-v3's fixed dicing rate in each direction.
const DICE: u32 = 30;

/// One direction of the patch: order, knots and the parameter range to dice.
struct Direction {
    order: usize,
    count: usize,
    knots: Vec<f32>,
    range: [f32; 2],
}

pub fn read(ctx: &mut ShapeContext, p: &ParamList, span: Span) -> Res<Built> {
    let Arrays { u, v, points, arity } = match arrays(p, span)? {
        Ok(arrays) => arrays,
        Err((at, why)) => return ctx.left_out_by_v3(p, at, why),
    };
    let (u, v) = (direction(p, "u", u)?, direction(p, "v", v)?);
    let cp = control_points(points, arity);
    let mut mesh = TriangleMesh { indices: grid_indices(DICE, DICE), ..Default::default() };
    let (mut n, mut uv) = (Vec::new(), Vec::new());
    let at = |d: &Direction, i: u32| lerp(i as f32 / (DICE - 1) as f32, d.range[0], d.range[1]);
    for j in 0..DICE {
        for i in 0..DICE {
            let (s, t) = (at(&u, i), at(&v, j));
            let (point, dpdu, dpdv) = surface(&u, &v, &cp, s, t);
            if !point.is_finite() {
                let msg = format!(
                    "nurbs: the surface is not defined at (u, v) = ({s}, {t}) (a weight of 0 or a repeated knot)"
                );
                return Err(Diagnostic::error(p.named("Pw").or(p.named("P")).map_or(span, |q| q.value_span), msg));
            }
            mesh.p.push(point.to_array());
            n.push(dpdu.cross(dpdv).normalize());
            uv.push([s, t]);
        }
    }
    mend_normals(&mut n);
    (mesh.n, mesh.uv) = (Some(n.iter().map(|v| v.to_array()).collect()), Some(uv));
    Ok(Built::Mesh { mesh, kind: NAME, filename: None })
}

/// Gives each vertex where the surface has no normal (a collapsed edge, as at the poles
/// of a NURBS sphere, where ∂p/∂u × ∂p/∂v = 0) the mean of its grid neighbours'.
// DEVIATION(pbrt): robustness. pbrt-v3 normalises the zero vector there: NaN shading
// normals in every triangle at the pole.
fn mend_normals(n: &mut [Vec3]) {
    let at = |i: i64, j: i64| (0..DICE as i64).contains(&i) && (0..DICE as i64).contains(&j);
    for k in 0..n.len() {
        if n[k].is_finite() {
            continue;
        }
        let (i, j) = ((k as u32 % DICE) as i64, (k as u32 / DICE) as i64);
        let mut sum = Vec3::ZERO;
        for (di, dj) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
            let (a, b) = (i + di, j + dj);
            let m = n.get((a + b * DICE as i64) as usize).copied().filter(|m| at(a, b) && m.is_finite());
            sum += m.unwrap_or(Vec3::ZERO);
        }
        n[k] = sum.try_normalize().unwrap_or(Vec3::Z);
    }
}

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// One direction's `n`, `order` and `knots`, as given.
#[derive(Clone, Copy)]
struct Given<'a> {
    count: i32,
    order: i32,
    knots: &'a Param,
}

/// The arrays a patch needs, each present and of its count: each direction's, and the
/// control points' values with their arity (3 for `P`, 4 for `Pw`).
struct Arrays<'a> {
    u: Given<'a>,
    v: Given<'a>,
    points: &'a [f32],
    arity: usize,
}

/// The patch's arrays; or where and why pbrt-v3 reports it and leaves it out, in its
/// order: a count, order or knot vector missing, or knots other than count + order in
/// number, in u and then in v; no control points, or not count_u · count_v of them.
/// (What it cannot survive, [`direction`] reports as errors.)
fn arrays(p: &ParamList, span: Span) -> Res<Result<Arrays<'_>, (Span, String)>> {
    let mut given = Vec::with_capacity(2);
    for d in ["u", "v"] {
        let (count, order) = (p.int(&format!("n{d}"))?, p.int(&format!("{d}order"))?);
        let knots = p.array(&format!("{d}knots"), ParamType::Float)?;
        let (count, order, knots) = match (count, order, knots) {
            (None, ..) => return Ok(Err((span, format!("nurbs needs \"integer n{d}\"")))),
            (_, None, _) => return Ok(Err((span, format!("nurbs needs \"integer {d}order\"")))),
            (.., None) => return Ok(Err((span, format!("nurbs needs \"float {d}knots\"")))),
            (Some(c), Some(o), Some(k)) => (c, o, k),
        };
        let sum = count as i64 + order as i64;
        if knots.floats().len() as i64 != sum {
            return Ok(Err((
                knots.value_span,
                format!("nurbs: {} {d} knots; n{d} + {d}order = {sum}", knots.floats().len()),
            )));
        }
        given.push(Given { count, order, knots });
    }
    let (values, at, arity) = match (p.array("P", ParamType::Point3)?, p.array("Pw", ParamType::Float)?) {
        (Some(q), _) => (q.floats(), q.value_span, 3),
        (None, Some(q)) => (q.floats(), q.value_span, 4),
        (None, None) => return Ok(Err((span, "nurbs needs its control points as \"point P\" or \"float Pw\"".into()))),
    };
    let points = given.iter().map(|g| g.count as i64).product::<i64>();
    if values.len() % arity != 0 || (values.len() / arity) as i64 != points {
        let msg = format!("nurbs: {} values for {points} control points of {arity} values", values.len());
        return Ok(Err((at, msg)));
    }
    Ok(Ok(Arrays { u: given[0], v: given[1], points: values, arity }))
}

/// Direction `d`'s arrays checked, and its `{d}0`/`{d}1`.
fn direction(p: &ParamList, d: &str, Given { count, order, knots }: Given) -> Res<Direction> {
    let located = |name: &str| p.named(name).map_or(knots.value_span, |q| q.value_span);
    if order < 2 || count < order {
        let msg = format!("nurbs: {d}order {order} with n{d} {count}; the order must be at least 2 and at most n{d}");
        return Err(Diagnostic::error(located(&format!("{d}order")), msg));
    }
    let (count, order) = (count as usize, order as usize);
    let k = knots.floats().to_vec();
    if k.iter().any(|x| !x.is_finite()) || !k.is_sorted() {
        return Err(Diagnostic::error(knots.value_span, format!("nurbs: the {d} knots decrease or are not finite")));
    }
    let (lo, hi) = (k[order - 1], k[count]);
    let range = [p.float(&format!("{d}0"))?.unwrap_or(lo), p.float(&format!("{d}1"))?.unwrap_or(hi)];
    if lo >= hi {
        return Err(Diagnostic::error(knots.value_span, format!("nurbs: the {d} knots span nothing ([{lo}, {hi}])")));
    }
    if let Some(k) = (0..2).find(|&k| !(lo..=hi).contains(&range[k])) {
        let msg = format!("nurbs: {d}{k} is {}, outside the knots' range [{lo}, {hi}]", range[k]);
        return Err(Diagnostic::error(located(&format!("{d}{k}")), msg));
    }
    Ok(Direction { order, count, knots: k, range })
}

/// The control points as homogeneous points: `P` with weight 1, or `Pw` as given.
fn control_points(values: &[f32], arity: usize) -> Vec<Vec4> {
    values.chunks_exact(arity).map(|c| Vec4::new(c[0], c[1], c[2], if arity == 4 { c[3] } else { 1.0 })).collect()
}

/// The first knot span holding `t` (pbrt-v3's `KnotOffset`).
fn knot_offset(knots: &[f32], order: usize, t: f32) -> usize {
    let mut k = order - 1;
    while k + 2 < knots.len() && t > knots[k + 1] {
        k += 1;
    }
    k
}

/// A point of the curve with control points `cp(i)`, i < count, and its derivative
/// (of the projected point) when asked (pbrt-v3's `NURBSEvaluate`).
fn curve(d: &Direction, t: f32, cp: impl Fn(usize) -> Vec4, deriv: bool) -> (Vec4, Vec3) {
    let offset = knot_offset(&d.knots, d.order, t);
    let knot = &d.knots[offset + 1 - d.order..];
    let first = offset + 1 - d.order;
    let o = d.order - 1; // knot[o] is pbrt's knot[0]
    let mut work: Vec<Vec4> = (0..d.order).map(|i| cp(first + i)).collect();
    for i in 0..d.order.saturating_sub(2) {
        for j in 0..d.order - 1 - i {
            let alpha = (knot[o + 1 + j] - t) / (knot[o + 1 + j] - knot[j + 1 + i]);
            work[j] = work[j] * alpha + work[j + 1] * (1.0 - alpha);
        }
    }
    let alpha = (knot[o + 1] - t) / (knot[o + 1] - knot[o]);
    let val = work[0] * alpha + work[1] * (1.0 - alpha);
    if !deriv {
        return (val, Vec3::ZERO);
    }
    let delta = (work[1] - work[0]) * ((d.order - 1) as f32 / (knot[o + 1] - knot[o]));
    let w = val.w;
    (val, delta.truncate() / w - val.truncate() * delta.w / (w * w))
}

/// The surface point at (s, t) with ∂p/∂u and ∂p/∂v (pbrt-v3's `NURBSEvaluateSurface`).
fn surface(u: &Direction, v: &Direction, cp: &[Vec4], s: f32, t: f32) -> (Vec3, Vec3, Vec3) {
    let ucp = u.count;
    let u_first = knot_offset(&u.knots, u.order, s) + 1 - u.order;
    let iso: Vec<Vec4> = (0..u.order).map(|i| curve(v, t, |k| cp[u_first + i + k * ucp], false).0).collect();
    let (p, dpdu) = curve(u, s, |k| iso[k - u_first], true);
    let v_first = knot_offset(&v.knots, v.order, t) + 1 - v.order;
    let iso: Vec<Vec4> = (0..v.order).map(|i| curve(u, s, |k| cp[(v_first + i) * ucp + k], false).0).collect();
    let (_, dpdv) = curve(v, t, |k| iso[k - v_first], true);
    (p.truncate() / p.w, dpdu, dpdv)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(order: usize, knots: &[f32]) -> Direction {
        let count = knots.len() - order;
        Direction { order, count, knots: knots.to_vec(), range: [knots[order - 1], knots[count]] }
    }

    #[test]
    fn a_rational_quadratic_is_an_exact_quarter_circle() {
        // The classic quarter circle: control points (1,0) (1,1) (0,1), middle weight 1/√2.
        let d = dir(3, &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        let w = std::f32::consts::FRAC_1_SQRT_2;
        let cp = [Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(w, w, 0.0, w), Vec4::new(0.0, 1.0, 0.0, 1.0)];
        for k in 0..=10 {
            let t = k as f32 / 10.0;
            let (h, deriv) = curve(&d, t, |i| cp[i], true);
            let p = h.truncate() / h.w;
            assert!((p.length() - 1.0).abs() < 1e-6, "{t}: {p}");
            // The tangent is perpendicular to the radius.
            assert!(deriv.normalize().dot(p).abs() < 1e-5, "{t}: {deriv}");
        }
    }

    #[test]
    fn a_collapsed_edge_gets_its_neighbours_normal_not_nan() {
        // A cone-like patch: the whole v = 0 row of control points is one apex.
        let mut n = vec![Vec3::NAN; (DICE * DICE) as usize];
        for (k, v) in n.iter_mut().enumerate().skip(DICE as usize) {
            *v = Vec3::new(0.1 * (k % 7) as f32, 0.0, 1.0).normalize();
        }
        mend_normals(&mut n);
        assert!(n.iter().all(|v| v.is_finite() && (v.length() - 1.0).abs() < 1e-5));
        assert!(n[3].z > 0.9, "{}", n[3]);
    }

    #[test]
    fn a_bilinear_patch_of_order_two_is_its_own_surface() {
        let d = dir(2, &[0.0, 0.0, 1.0, 1.0]);
        let cp = [
            Vec4::new(0.0, 0.0, 0.0, 1.0),
            Vec4::new(2.0, 0.0, 0.0, 1.0),
            Vec4::new(0.0, 3.0, 1.0, 1.0),
            Vec4::new(2.0, 3.0, 1.0, 1.0),
        ];
        let (p, dpdu, dpdv) = surface(&d, &d, &cp, 0.25, 0.5);
        assert!((p - Vec3::new(0.5, 1.5, 0.5)).length() < 1e-6, "{p}");
        assert!((dpdu - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6 && (dpdv - Vec3::new(0.0, 3.0, 1.0)).length() < 1e-6);
    }
}
