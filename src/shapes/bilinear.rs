//! Bilinear patch meshes (pbrt-v4):
//!
//! ```text
//! Shape "bilinearmesh" "point3 P" [0 0 0  1 0 0  0 1 0  1 1 1]   # p00 p10 p01 p11
//!       "integer indices" [0 1 2 3]   # four per patch; may be left out for one patch
//!       "normal N" [...] "point2 uv" [...] "integer faceIndices" [...]
//! ```
//! Patch k is p(u, v) = lerp(u, lerp(v, p00, p01), lerp(v, p10, p11)) over the corners
//! `indices[4k..4k+4]` = (p00, p10, p01, p11). Rays meet it exactly, by pbrt-v4's
//! ray–patch quadratic in u; nothing is tessellated. As for triangle meshes, positions
//! and normals are stored already transformed.

use super::sampling::ShapeSample;
use super::{Built, ShapeContext};
use super::{MeshFlags, integrate_unit_square};
use crate::interaction::{Shading, SurfaceInteraction};
use crate::math::float::gamma;
use crate::math::{Bounds3, Normal3, Point3, Ray, Vector3};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::{DVec3, Quat, Vec2, Vec3};

/// One bilinear patch mesh's vertex data (already in the space of its transform).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PatchMesh {
    pub p: Vec<[f32; 3]>,
    /// Four per patch: p00, p10, p01, p11.
    pub indices: Vec<u32>,
    pub n: Option<Vec<[f32; 3]>>,
    pub uv: Option<Vec<[f32; 2]>>,
    pub face_indices: Option<Vec<i32>>,
}

/// Where a ray met a patch: its ray parameter and the patch's (u, v).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchHit {
    pub t: f32,
    pub uv: [f32; 2],
}

fn lerp3(t: f32, a: Vec3, b: Vec3) -> Vec3 {
    a + t * (b - a)
}

impl PatchMesh {
    pub fn patch_count(&self) -> usize {
        self.indices.len() / 4
    }

    /// p00, p10, p01, p11.
    pub fn corners(&self, patch: usize) -> [Vec3; 4] {
        let i = &self.indices[4 * patch..4 * patch + 4];
        [0, 1, 2, 3].map(|k| Vec3::from(self.p[i[k] as usize]))
    }

    fn corners64(&self, patch: usize) -> [DVec3; 4] {
        self.corners(patch).map(|c| c.as_dvec3())
    }

    /// ∂p/∂u and ∂p/∂v at (u, v), before any `uv` reparameterisation.
    fn derivatives(c: [Vec3; 4], u: f32, v: f32) -> (Vec3, Vec3) {
        let [p00, p10, p01, p11] = c;
        (lerp3(v, p10, p11) - lerp3(v, p00, p01), lerp3(u, p01, p11) - lerp3(u, p00, p10))
    }

    /// pbrt-v4's test for a planar rectangle, which is then sampled uniformly in (u, v).
    fn is_rectangle(c: [Vec3; 4]) -> bool {
        let [p00, p10, p01, p11] = c;
        if p00 == p01 || p01 == p11 || p11 == p10 || p10 == p00 {
            return false;
        }
        let n = (p10 - p00).cross(p01 - p00).normalize();
        if (p11 - p00).normalize().dot(n).abs() > 1e-5 {
            return false;
        }
        let center = (p00 + p01 + p10 + p11) / 4.0;
        let d2 = [p00, p01, p10, p11].map(|p| p.distance_squared(center));
        d2[1..].iter().all(|d| (d - d2[0]).abs() / d2[0] <= 1e-4)
    }

    /// The patch's area, |∂p/∂u × ∂p/∂v| integrated over (u, v).
    // pbrt-v4 approximates it with a 3×3 grid of quads; only the choice of light by
    // power depends on it, the density of points on the patch does not.
    pub fn patch_area(&self, patch: usize) -> f64 {
        Self::area_of(self.corners64(patch))
    }

    fn area_of([p00, p10, p01, p11]: [DVec3; 4]) -> f64 {
        let twist = p00 - p01 - p10 + p11;
        let (e_u, e_v) = (p10 - p00, p01 - p00);
        // ∂p/∂u = e_u + v·twist, ∂p/∂v = e_v + u·twist.
        if twist.length_squared() == 0.0 {
            return e_u.cross(e_v).length();
        }
        integrate_unit_square(|u, v| (e_u + v * twist).cross(e_v + u * twist).length())
    }

    /// Zero area (from the stored corners): never hit, never sampled. ∂p/∂u × ∂p/∂v is
    /// affine in (u, v), e_u×e_v + u·(e_u×twist) + v·(twist×e_v), so the area is zero
    /// exactly when those three vectors are.
    pub fn is_degenerate(&self, patch: usize) -> bool {
        let [p00, p10, p01, p11] = self.corners64(patch);
        let (e_u, e_v, twist) = (p10 - p00, p01 - p00, p00 - p01 - p10 + p11);
        [e_u.cross(e_v), e_u.cross(twist), twist.cross(e_v)].iter().all(|c| *c == DVec3::ZERO)
    }

    /// Total area.
    pub fn area(&self) -> f64 {
        (0..self.patch_count()).map(|k| self.patch_area(k)).sum()
    }

    /// Total area after the linear map `m` (instances).
    pub fn area_under(&self, m: glam::DMat3) -> f64 {
        (0..self.patch_count()).map(|k| Self::area_of(self.corners64(k).map(|c| m * c))).sum()
    }

    /// A patch lies inside the convex hull of its corners.
    pub fn patch_bounds(&self, patch: usize) -> Bounds3 {
        let c = self.corners(patch);
        let (lo, hi) = c.iter().fold((c[0], c[0]), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        Bounds3 { min: lo, max: hi }
    }

    /// Bounds of all vertices used, `None` for an empty mesh.
    pub fn bounds(&self) -> Option<[DVec3; 2]> {
        let mut used = self.indices.iter().map(|&i| DVec3::from(self.p[i as usize].map(f64::from)));
        let first = used.next()?;
        Some(used.fold([first, first], |[lo, hi], p| [lo.min(p), hi.max(p)]))
    }

    /// The patches as triangles, `cells`² quads per patch (one for parallelograms), with
    /// interpolated normals and texture coordinates (for export to other renderers).
    pub fn to_triangles(&self, cells: usize) -> super::TriangleMesh {
        let mut out =
            super::TriangleMesh { n: self.n.as_ref().map(|_| Vec::new()), uv: Some(Vec::new()), ..Default::default() };
        for k in 0..self.patch_count() {
            let c = self.corners(k);
            let flat = c[0] - c[1] - c[2] + c[3] == Vec3::ZERO;
            let n = if flat { 1 } else { cells };
            let first = out.p.len() as u32;
            for j in 0..=n {
                for i in 0..=n {
                    let uv = [i as f32 / n as f32, j as f32 / n as f32];
                    let [p00, p10, p01, p11] = c;
                    out.p.push(lerp3(uv[0], lerp3(uv[1], p00, p01), lerp3(uv[1], p10, p11)).to_array());
                    if let (Some(ns), Some(_)) = (&mut out.n, &self.n) {
                        ns.push(self.normal_at(k, uv).unwrap_or(Vec3::ZERO).to_array());
                    }
                    if let Some(st) = &mut out.uv {
                        st.push(self.st(k, uv).0.to_array());
                    }
                }
            }
            let at = |i: usize, j: usize| first + (j * (n + 1) + i) as u32;
            for j in 0..n {
                for i in 0..n {
                    // (u, v) order keeps the triangles' winding that of ∂p/∂u × ∂p/∂v.
                    out.indices.extend([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                    out.indices.extend([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
        }
        out
    }

    /// pbrt-v4's ray–patch intersection: the quadratic in u whose roots are the iso-lines
    /// u = const the ray meets, then v and t from the ray's closest approach to each.
    // Evaluated in f64 (pbrt: f32 with compensated products); pbrt's ε on t is kept.
    pub fn intersect(&self, patch: usize, ray: &Ray, t_max: f32) -> Option<PatchHit> {
        let c32 = self.corners(patch);
        let [p00, p10, p01, p11] = c32.map(|c| c.as_dvec3());
        let (o, d) = (ray.o.0.as_dvec3(), ray.d.0.as_dvec3());
        let a = (p10 - p00).cross(p01 - p11).dot(d);
        let c = (p00 - o).cross(d).dot(p01 - p00);
        let b = (p10 - o).cross(d).dot(p11 - p10) - (a + c);
        let (u1, u2) = quadratic(a, b, c)?;
        let max = |v: Vec3| v.abs().max_element();
        let eps = gamma(30) * (max(ray.o.0) + max(ray.d.0) + c32.iter().map(|&p| max(p)).sum::<f32>());
        let eps = eps as f64;
        let mut best: Option<(f64, f64, f64)> = None;
        for (k, u) in [u1, u2].into_iter().enumerate() {
            if !(0.0..=1.0).contains(&u) || (k == 1 && u == u1) {
                continue;
            }
            let uo = p00.lerp(p10, u);
            let ud = p01.lerp(p11, u) - uo;
            let delta = uo - o;
            let perp = d.cross(ud);
            let p2 = perp.length_squared();
            // det[δ, d, perp] and det[δ, ud, perp], both over |perp|².
            let v = delta.dot(d.cross(perp));
            let t = delta.dot(ud.cross(perp));
            if p2 > 0.0 && (0.0..=p2).contains(&v) && t > p2 * eps && best.is_none_or(|(bt, ..)| t / p2 < bt) {
                best = Some((t / p2, u, v / p2));
            }
        }
        let (t, u, v) = best?;
        let t = t as f32;
        (t < t_max).then_some(PatchHit { t, uv: [u as f32, v as f32] })
    }

    /// The texture (s, t) at patch (u, v), with ∂(u,v)/∂s and ∂(u,v)/∂t as pbrt-v4
    /// computes them (a near-zero derivative of s or t counts as none).
    fn st(&self, patch: usize, [u, v]: [f32; 2]) -> (Vec2, [f32; 4]) {
        let Some(uvs) = &self.uv else { return (Vec2::new(u, v), [1.0, 0.0, 0.0, 1.0]) };
        let i = &self.indices[4 * patch..4 * patch + 4];
        let [t00, t10, t01, t11] = [0, 1, 2, 3].map(|k| Vec2::from(uvs[i[k] as usize]));
        let st = (t00.lerp(t01, v)).lerp(t10.lerp(t11, v), u);
        let dst_du = t10.lerp(t11, v) - t00.lerp(t01, v);
        let dst_dv = t01.lerp(t11, u) - t00.lerp(t10, u);
        let inv = |x: f32| if x.abs() < 1e-8 { 0.0 } else { 1.0 / x };
        // (du/ds, du/dt, dv/ds, dv/dt)
        (st, [inv(dst_du.x), inv(dst_du.y), inv(dst_dv.x), inv(dst_dv.y)])
    }

    /// Differential geometry at a hit (pbrt-v4's `InteractionFromIntersection`).
    pub fn interaction(&self, patch: usize, hit: &PatchHit, flags: MeshFlags) -> SurfaceInteraction {
        let c = self.corners(patch);
        let [p00, p10, p01, p11] = c;
        let [u, v] = hit.uv;
        let p = lerp3(u, lerp3(v, p00, p01), lerp3(v, p10, p11));
        let (mut dpdu, mut dpdv) = Self::derivatives(c, u, v);
        let (st, [duds, dudt, dvds, dvdt]) = self.st(patch, hit.uv);
        if self.uv.is_some() {
            let dpds = dpdu * duds + dpdv * dvds;
            let mut dpdt = dpdu * dudt + dpdv * dvdt;
            if dpds.cross(dpdt) != Vec3::ZERO {
                if dpdu.cross(dpdv).dot(dpds.cross(dpdt)) < 0.0 {
                    dpdt = -dpdt;
                }
                (dpdu, dpdv) = (dpds, dpdt);
            }
        }
        // Only ∂²p/∂u∂v is nonzero on a bilinear patch.
        let d2p_duv = (p00 - p01) + (p11 - p10);
        // First fundamental form E, F, G; of the second, only f (e = g = 0).
        let (e1, f1, g1) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
        let n = dpdu.cross(dpdv).normalize_or_zero();
        let f2 = n.dot(d2p_duv);
        let egf2 = e1 * g1 - f1 * f1;
        let inv = if egf2 == 0.0 { 0.0 } else { 1.0 / egf2 };
        let dndu = (f2 * f1 * inv) * dpdu + (-f2 * e1 * inv) * dpdv;
        let dndv = (-f2 * g1 * inv) * dpdu + (f2 * f1 * inv) * dpdv;
        let (dndu, dndv) = (dndu * duds + dndv * dvds, dndu * dudt + dndv * dvdt);
        let p_error = gamma(6) * (p00.abs() + p01.abs() + p10.abs() + p11.abs());
        let n = if flags.reverse_orientation ^ flags.swaps_handedness { -n } else { n };
        let mut si = SurfaceInteraction {
            p: Point3(p),
            p_error,
            t: hit.t,
            uv: st.to_array(),
            n: Normal3(n),
            dpdu: Vector3(dpdu),
            dpdv: Vector3(dpdv),
            dndu: Normal3(dndu),
            dndv: Normal3(dndv),
            shading: Shading {
                n: Normal3(n),
                dpdu: Vector3(dpdu),
                dpdv: Vector3(dpdv),
                dndu: Normal3(dndu),
                dndv: Normal3(dndv),
            },
            time: 0.0,
            face: self.face_indices.as_ref().map_or(0, |f| f[patch]),
        };
        if let Some(ns) = self.normal_at(patch, hit.uv) {
            self.shading_geometry(patch, hit.uv, ns, [duds, dudt, dvds, dvdt], &mut si);
        }
        si
    }

    /// The interpolated vertex normal at (u, v), when the mesh has normals and it is
    /// not zero.
    fn normal_at(&self, patch: usize, [u, v]: [f32; 2]) -> Option<Vec3> {
        let [n00, n10, n01, n11] = self.corner_normals(patch)?;
        lerp3(u, lerp3(v, n00, n01), lerp3(v, n10, n11)).try_normalize()
    }

    /// The vertex normals at p00, p10, p01, p11, when the mesh has normals.
    fn corner_normals(&self, patch: usize) -> Option<[Vec3; 4]> {
        let ns = self.n.as_ref()?;
        let i = &self.indices[4 * patch..4 * patch + 4];
        Some([0, 1, 2, 3].map(|k| Vec3::from(ns[i[k] as usize])))
    }

    /// Vertex normals decide the front side and tilt the shading frame (pbrt-v4 rotates
    /// ∂p/∂u and ∂p/∂v from the geometric normal to the shading one).
    fn shading_geometry(&self, patch: usize, [u, v]: [f32; 2], ns: Vec3, d: [f32; 4], si: &mut SurfaceInteraction) {
        let Some([n00, n10, n01, n11]) = self.corner_normals(patch) else { return };
        let dndu = lerp3(v, n10, n11) - lerp3(v, n00, n01);
        let dndv = lerp3(u, n01, n11) - lerp3(u, n00, n10);
        let [duds, dudt, dvds, dvdt] = d;
        let (dnds, dndt) = (dndu * duds + dndv * dvds, dndu * dudt + dndv * dvdt);
        let r = Quat::from_rotation_arc(si.n.0, ns);
        si.n = si.n.face_forward(Vector3(ns));
        si.shading = Shading {
            n: Normal3(ns),
            dpdu: Vector3(r * si.dpdu.0),
            dpdv: Vector3(r * si.dpdv.0),
            dndu: Normal3(dnds),
            dndv: Normal3(dndt),
        };
    }

    /// The corner weights of pbrt-v4's approximately area-uniform (u, v) sampling:
    /// |∂p/∂u × ∂p/∂v| at the four corners.
    fn corner_weights([p00, p10, p01, p11]: [Vec3; 4]) -> [f32; 4] {
        [
            (p10 - p00).cross(p01 - p00).length(),
            (p10 - p00).cross(p11 - p10).length(),
            (p01 - p00).cross(p11 - p01).length(),
            (p11 - p10).cross(p11 - p01).length(),
        ]
    }

    /// The density over (u, v) that `sample` uses.
    fn uv_pdf(c: [Vec3; 4], uv: [f32; 2]) -> f32 {
        if Self::is_rectangle(c) { 1.0 } else { bilinear_pdf(uv, Self::corner_weights(c)) }
    }

    /// A point on one patch, by area (pbrt-v4's `BilinearPatch::Sample`): uniform in
    /// (u, v) for rectangles, otherwise bilinear in the corner area elements; the
    /// density is exact, p(u, v) / |∂p/∂u × ∂p/∂v|.
    pub fn sample(&self, patch: usize, u: [f32; 2], flags: MeshFlags) -> Option<ShapeSample> {
        let c = self.corners(patch);
        let [p00, p10, p01, p11] = c;
        let uv = if Self::is_rectangle(c) { u } else { sample_bilinear(u, Self::corner_weights(c)) };
        let (dpdu, dpdv) = Self::derivatives(c, uv[0], uv[1]);
        let jacobian = dpdu.cross(dpdv).length();
        if jacobian == 0.0 {
            return None;
        }
        let p = lerp3(uv[0], lerp3(uv[1], p00, p01), lerp3(uv[1], p10, p11));
        let mut n = dpdu.cross(dpdv) / jacobian;
        match self.normal_at(patch, uv) {
            Some(ns) if n.dot(ns) < 0.0 => n = -n,
            Some(_) => {}
            None if flags.reverse_orientation ^ flags.swaps_handedness => n = -n,
            None => {}
        }
        let st = self.st(patch, uv).0.to_array();
        Some(ShapeSample { p: Point3(p), n: Normal3(n), uv: st, pdf: Self::uv_pdf(c, uv) / jacobian })
    }

    /// The area density `sample` gives the point `p` of the patch (whose normal is
    /// `n`), found again by a short ray through `p` along the normal.
    pub fn pdf_area(&self, patch: usize, p: Point3, n: Vec3) -> f32 {
        let c = self.corners(patch);
        let size = c.iter().map(|q| (*q - c[0]).abs().max_element()).fold(0.0f32, f32::max).max(1e-30);
        let eps = 1e-3 * size + 1e-4 * p.0.abs().max_element();
        let Some(hit) = self.intersect(patch, &Ray::new(Point3(p.0 + n * eps), Vector3(-n)), 2.0 * eps) else {
            return 0.0;
        };
        let (dpdu, dpdv) = Self::derivatives(c, hit.uv[0], hit.uv[1]);
        let jacobian = dpdu.cross(dpdv).length();
        if jacobian == 0.0 { 0.0 } else { Self::uv_pdf(c, hit.uv) / jacobian }
    }

    /// Solid-angle density of `sample` (converted at `reference`) along `wi`.
    pub fn pdf_solid_angle(&self, patch: usize, reference: Point3, wi: Vector3) -> f32 {
        let Some(hit) = self.intersect(patch, &Ray::new(reference, wi), f32::INFINITY) else { return 0.0 };
        let c = self.corners(patch);
        let (dpdu, dpdv) = Self::derivatives(c, hit.uv[0], hit.uv[1]);
        let cross = dpdu.cross(dpdv);
        let jacobian = cross.length();
        let d = wi.0 * hit.t;
        let cos = (cross / jacobian).dot(wi.0.normalize()).abs();
        if jacobian == 0.0 || cos == 0.0 {
            return 0.0;
        }
        Self::uv_pdf(c, hit.uv) / jacobian * d.length_squared() / cos
    }
}

/// Roots of a·x² + b·x + c in increasing order (pbrt's `Quadratic`).
fn quadratic(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    if a == 0.0 {
        return (b != 0.0).then(|| (-c / b, -c / b));
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + disc.sqrt().copysign(b));
    let (t0, t1) = (q / a, c / q);
    Some(if t0 > t1 { (t1, t0) } else { (t0, t1) })
}

/// x in [0, 1) with density ∝ lerp(x, a, b) (pbrt-v4's `SampleLinear`).
fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if u == 0.0 && a == 0.0 {
        return 0.0;
    }
    let x = u * (a + b) / (a + (a * a + u * (b * b - a * a)).sqrt());
    x.min(1.0 - f32::EPSILON / 2.0)
}

/// A point of [0, 1]² with density ∝ the bilinear interpolation of corner weights `w`
/// (order (0,0), (1,0), (0,1), (1,1)).
fn sample_bilinear(u: [f32; 2], w: [f32; 4]) -> [f32; 2] {
    let y = sample_linear(u[1], w[0] + w[1], w[2] + w[3]);
    let x = sample_linear(u[0], w[0] + y * (w[2] - w[0]), w[1] + y * (w[3] - w[1]));
    [x, y]
}

fn bilinear_pdf([x, y]: [f32; 2], w: [f32; 4]) -> f32 {
    if !(0.0..=1.0).contains(&x) || !(0.0..=1.0).contains(&y) {
        return 0.0;
    }
    let sum = w.iter().sum::<f32>();
    if sum == 0.0 {
        return 1.0;
    }
    4.0 * ((1.0 - x) * (1.0 - y) * w[0] + x * (1.0 - y) * w[1] + (1.0 - x) * y * w[2] + x * y * w[3]) / sum
}

/// `Shape "bilinearmesh"` (v4; see [`super::mesh_params`] for its parameters).
pub const NAME: &str = "bilinearmesh";

pub fn read(ctx: &mut ShapeContext, p: &mut ParamList, span: Span) -> Res<Built> {
    let mesh = super::mesh_params::patches_from_params(p, NAME, span, ctx.warn)?;
    Ok(Built::Patches { mesh, kind: NAME, filename: None })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(c: [[f32; 3]; 4]) -> PatchMesh {
        PatchMesh { p: c.to_vec(), indices: vec![0, 1, 2, 3], ..Default::default() }
    }

    /// A saddle: z = u·v over the unit square.
    fn saddle() -> PatchMesh {
        one([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 1.0]])
    }

    #[test]
    fn rays_meet_the_saddle_where_z_is_uv() {
        let m = saddle();
        for (x, y) in [(0.25f32, 0.5f32), (0.9, 0.1), (0.6, 0.7)] {
            let ray = Ray::new(Point3(Vec3::new(x, y, 5.0)), Vector3(Vec3::new(0.0, 0.0, -1.0)));
            let hit = m.intersect(0, &ray, f32::INFINITY).expect("hit");
            assert!((hit.t - (5.0 - x * y)).abs() < 1e-5, "{hit:?}");
            assert!((hit.uv[0] - x).abs() < 1e-5 && (hit.uv[1] - y).abs() < 1e-5, "{hit:?}");
            let si = m.interaction(0, &hit, MeshFlags::default());
            assert!((si.p.0 - Vec3::new(x, y, x * y)).length() < 1e-5);
            // n ∝ (−v, −u, 1).
            let n = Vec3::new(-y, -x, 1.0).normalize();
            assert!(si.n.0.dot(n) > 0.9999, "{:?}", si.n);
        }
        let miss = Ray::new(Point3(Vec3::new(1.5, 0.5, 5.0)), Vector3(Vec3::new(0.0, 0.0, -1.0)));
        assert_eq!(m.intersect(0, &miss, f32::INFINITY), None);
        // t_max and hits behind the origin.
        let ray = Ray::new(Point3(Vec3::new(0.5, 0.5, 5.0)), Vector3(Vec3::new(0.0, 0.0, -1.0)));
        assert_eq!(m.intersect(0, &ray, 4.0), None);
        let back = Ray::new(Point3(Vec3::new(0.5, 0.5, -5.0)), Vector3(Vec3::new(0.0, 0.0, -1.0)));
        assert_eq!(m.intersect(0, &back, f32::INFINITY), None);
    }

    #[test]
    fn a_ray_through_the_saddle_twice_stops_at_the_nearer_crossing() {
        // Along (s, s, s − 0.1), z − xy = s − 0.1 − s² vanishes at s = (1 ± √0.6)/2.
        let m = saddle();
        let d = Vector3(Vec3::ONE);
        let (near, far) = ((1.0 - 0.6f32.sqrt()) / 2.0, (1.0 + 0.6f32.sqrt()) / 2.0);
        let ray = Ray::new(Point3(Vec3::new(0.0, 0.0, -0.1)), d);
        let hit = m.intersect(0, &ray, f32::INFINITY).expect("hit");
        assert!((hit.t - near).abs() < 1e-5, "{hit:?}, expected {near}");
        let from_between = Ray::new(Point3(Vec3::new(0.5, 0.5, 0.4)), d);
        let hit = m.intersect(0, &from_between, f32::INFINITY).expect("hit");
        assert!((hit.t - (far - 0.5)).abs() < 1e-5, "{hit:?}, expected {}", far - 0.5);
    }

    #[test]
    fn area_and_sampling_density_integrate_to_one() {
        let m = saddle();
        // Area of z = xy over the unit square: ∫∫ √(1 + x² + y²).
        let exact = integrate_unit_square(|x, y| (1.0 + x * x + y * y).sqrt());
        assert!((m.area() - exact).abs() < 1e-9, "{}", m.area());
        // E[1/pdf] over the sampler is the area.
        let n = 200_000;
        let mut sum = 0.0;
        let mut rng = crate::sampling::Rng::new(7);
        for _ in 0..n {
            let s = m.sample(0, [rng.uniform(), rng.uniform()], MeshFlags::default()).expect("sample");
            sum += 1.0 / s.pdf as f64;
            assert!((s.p.0.z - s.p.0.x * s.p.0.y).abs() < 1e-5);
        }
        let est = sum / n as f64;
        assert!((est - exact).abs() < 0.01 * exact, "{est} vs {exact}");
    }

    #[test]
    fn solid_angle_density_matches_sampling() {
        // A tilted non-rectangular planar quad seen from a point: ∫ pdf dω over the
        // sampled directions must be 1, i.e. E[1/pdf_ω] = solid angle, which we check
        // against pdf_solid_angle at the same directions.
        let m = one([[0.0, 0.0, 0.0], [2.0, 0.0, 0.2], [0.0, 1.0, 0.0], [1.5, 1.5, 0.5]]);
        let r = Point3(Vec3::new(0.3, 0.4, 3.0));
        let mut rng = crate::sampling::Rng::new(3);
        for _ in 0..200 {
            let s = m.sample(0, [rng.uniform(), rng.uniform()], MeshFlags::default()).expect("sample");
            let d = s.p.0 - r.0;
            let cos = s.n.0.dot(d.normalize()).abs();
            let pdf_w = s.pdf * d.length_squared() / cos;
            let pdf = m.pdf_solid_angle(0, r, Vector3(d.normalize()));
            assert!((pdf - pdf_w).abs() < 1e-3 * pdf_w, "{pdf} vs {pdf_w}");
        }
    }

    #[test]
    fn vertex_normals_and_orientation_decide_the_front() {
        let mut m = saddle();
        let flags = MeshFlags { reverse_orientation: true, ..MeshFlags::default() };
        let ray = Ray::new(Point3(Vec3::new(0.5, 0.5, 5.0)), Vector3(Vec3::new(0.0, 0.0, -1.0)));
        let hit = m.intersect(0, &ray, f32::INFINITY).expect("hit");
        assert!(m.interaction(0, &hit, flags).n.0.z < 0.0);
        m.n = Some(vec![[0.0, 0.0, 1.0]; 4]);
        let si = m.interaction(0, &hit, flags);
        assert!(si.n.0.z > 0.0 && si.shading.n.0.z > 0.999);
        assert!(si.shading.dpdu.0.dot(si.shading.n.0).abs() < 1e-5);
    }

    #[test]
    fn texture_coordinates_interpolate_bilinearly() {
        let mut m = saddle();
        m.uv = Some(vec![[0.0, 0.0], [2.0, 0.0], [0.0, 4.0], [2.0, 4.0]]);
        let ray = Ray::new(Point3(Vec3::new(0.25, 0.5, 5.0)), Vector3(Vec3::new(0.0, 0.0, -1.0)));
        let hit = m.intersect(0, &ray, f32::INFINITY).expect("hit");
        let si = m.interaction(0, &hit, MeshFlags::default());
        assert!((si.uv[0] - 0.5).abs() < 1e-5 && (si.uv[1] - 2.0).abs() < 1e-5, "{:?}", si.uv);
        // ∂p/∂s is ∂p/∂u / 2.
        let (dpdu, _) = PatchMesh::derivatives(m.corners(0), 0.25, 0.5);
        assert!((si.dpdu.0 - dpdu / 2.0).length() < 1e-5);
    }
}
