//! Transforms in `f32` with pbrt-v3's rounding-error propagation, written as explicit
//! scalar code in pbrt's order of operations.

use super::bounds::Bounds3;
use super::float::gamma;
use super::ray::Ray;
use super::vector::{Normal3, Point3, Vector3};
use glam::{DMat4, Vec3};

/// A matrix and its inverse, row-major (`m[row][col]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub m: [[f32; 4]; 4],
    pub m_inv: [[f32; 4]; 4],
}

/// The 16 entries of `m` row by row, as scene files, `check` and exports write them.
pub fn row_major(m: &DMat4) -> [f64; 16] {
    m.transpose().to_cols_array()
}

fn rows(m: DMat4) -> [[f32; 4]; 4] {
    let t = m.transpose().to_cols_array_2d(); // columns of the transpose are rows
    t.map(|r| r.map(|x| x as f32))
}

impl Transform {
    pub const IDENTITY: Transform = Transform {
        m: [[1., 0., 0., 0.], [0., 1., 0., 0.], [0., 0., 1., 0.], [0., 0., 0., 1.]],
        m_inv: [[1., 0., 0., 0.], [0., 1., 0., 0.], [0., 0., 1., 0.], [0., 0., 0., 1.]],
    };

    /// From an f64 matrix (the scene description's), inverting in f64.
    pub fn from_dmat4(m: DMat4) -> Transform {
        Transform { m: rows(m), m_inv: rows(m.inverse()) }
    }

    pub fn inverse(&self) -> Transform {
        Transform { m: self.m_inv, m_inv: self.m }
    }

    /// det of the upper 3×3 < 0.
    pub fn swaps_handedness(&self) -> bool {
        let m = &self.m;
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        det < 0.0
    }

    pub fn point(&self, p: Point3) -> Point3 {
        self.point_with_error(p).0
    }

    /// The transformed point and a bound on its rounding error.
    pub fn point_with_error(&self, p: Point3) -> (Point3, Vec3) {
        let m = &self.m;
        let [x, y, z] = p.to_array();
        let r = |i: usize| m[i][0] * x + m[i][1] * y + m[i][2] * z + m[i][3];
        let e = |i: usize| (m[i][0] * x).abs() + (m[i][1] * y).abs() + (m[i][2] * z).abs() + m[i][3].abs();
        let err = gamma(3) * Vec3::new(e(0), e(1), e(2));
        let w = r(3);
        let q = Vec3::new(r(0), r(1), r(2));
        (Point3(if w == 1.0 { q } else { q / w }), err)
    }

    /// As [`Transform::point_with_error`] for a point that already carries `p_error`.
    pub fn point_with_error_prop(&self, p: Point3, p_error: Vec3) -> (Point3, Vec3) {
        let m = &self.m;
        let (q, err) = self.point_with_error(p);
        let pe = p_error.to_array();
        let prop = |i: usize| m[i][0].abs() * pe[0] + m[i][1].abs() * pe[1] + m[i][2].abs() * pe[2];
        (q, err + (gamma(3) + 1.0) * Vec3::new(prop(0), prop(1), prop(2)))
    }

    pub fn vector(&self, v: Vector3) -> Vector3 {
        let m = &self.m;
        let [x, y, z] = v.to_array();
        let r = |i: usize| m[i][0] * x + m[i][1] * y + m[i][2] * z;
        Vector3::new(r(0), r(1), r(2))
    }

    /// Normals transform by the inverse transpose.
    pub fn normal(&self, n: Normal3) -> Normal3 {
        let mi = &self.m_inv;
        let [x, y, z] = n.to_array();
        let r = |i: usize| mi[0][i] * x + mi[1][i] * y + mi[2][i] * z;
        Normal3::new(r(0), r(1), r(2))
    }

    /// pbrt-v3's ray transform: the origin is moved forward along the ray by its error
    /// bound, so that a ray leaving a surface never starts behind it. Returns the ray
    /// and that shift `dt` (t on the new ray + dt = t on the old one).
    pub fn ray(&self, r: &Ray) -> (Ray, f32) {
        let (mut o, o_err) = self.point_with_error(r.o);
        let d = self.vector(r.d);
        let mut t_max = r.t_max;
        let mut dt = 0.0;
        let len2 = d.0.length_squared();
        if len2 > 0.0 {
            dt = d.0.abs().dot(o_err) / len2;
            o = o + d * dt;
            t_max -= dt;
        }
        (Ray { o, d, t_max, time: r.time }, dt)
    }

    /// Bounds of the 8 transformed corners.
    pub fn bounds(&self, b: Bounds3) -> Bounds3 {
        let c = [b.min, b.max];
        (0..8).fold(Bounds3::default(), |acc, i| {
            let p = Point3::new(c[i & 1].x, c[(i >> 1) & 1].y, c[(i >> 2) & 1].z);
            acc.union_point(self.point(p).0)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_error_bounds_hold() {
        let t = Transform::from_dmat4(
            DMat4::from_translation(glam::DVec3::new(1e3, -2.5, 0.1))
                * DMat4::from_axis_angle(glam::DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7)
                * DMat4::from_scale(glam::DVec3::new(3.0, -0.2, 7.0)),
        );
        for p in [Point3::new(0.3, -7.0, 2e2), Point3::new(-1e-3, 5.0, 1.0)] {
            let (q, err) = t.point_with_error(p);
            for i in 0..3 {
                let exact: f64 = (0..3).map(|j| t.m[i][j] as f64 * p.0[j] as f64).sum::<f64>() + t.m[i][3] as f64;
                assert!((q.0[i] as f64 - exact).abs() <= err[i] as f64, "{i}");
            }
        }
        assert!(t.swaps_handedness(), "the scale has one negative factor");
    }

    #[test]
    fn ray_origin_moves_forward_by_its_error_and_keeps_t() {
        let t = Transform::from_dmat4(DMat4::from_translation(glam::DVec3::new(1e4, 0.0, 0.0)));
        let r = Ray { o: Point3::new(0.5, 0.0, 0.0), d: Vector3::new(2.0, 0.0, 0.0), t_max: 10.0, time: 0.0 };
        let (tr, dt) = t.ray(&r);
        assert!(dt > 0.0, "the origin has rounding error at x = 1e4");
        assert_eq!(tr.t_max, 10.0 - dt);
        // The same point at the same t, up to the transform's rounding.
        let p = t.point(r.at(3.0));
        assert!((tr.at(3.0 - dt).0 - p.0).length() <= 2e-3, "{:?} vs {p:?}", tr.at(3.0 - dt));
    }

    #[test]
    fn normals_stay_perpendicular_under_nonuniform_scale() {
        let t = Transform::from_dmat4(DMat4::from_scale(glam::DVec3::new(1.0, 4.0, 1.0)));
        let (n, v) = (Normal3::new(1.0, 1.0, 0.0), Vector3::new(1.0, -1.0, 0.0));
        assert!(t.normal(n).dot(t.vector(v)).abs() < 1e-6);
    }
}
