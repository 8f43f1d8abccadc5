//! `Shape "hyperboloid" "point p1" [0 0 0] "point p2" [1 1 1] "float phimax" 360`
//! (pbrt-v3 only)
//!
//! The surface swept by the segment p1→p2 around the z axis:
//! p_r(v) = (1 − v)·p1 + v·p2, p(u, v) = rotate_z(u·φmax) · p_r(v).
//! pbrt also fits the implicit form a_h(x² + y²) − c_h z² = 1 and intersects that
//! (rendering's default here too; `--fix hyperboloid-surface` intersects the swept
//! surface). Its refit loop never ends when the segment's line meets the axis,
//! including for the default parameters, so such input is rejected here. Sampling (an
//! emitting hyperboloid, which pbrt cannot sample) always uses the swept surface.

use super::Quadric;
use super::params::f;
use super::quadric::{Local, QuadricSurface};
use super::{integrate_unit_interval, phi_max_radians};
use crate::math::bounded::Interval;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::{DVec3, Vec3};

#[derive(Clone, Debug, PartialEq)]
pub struct Hyperboloid {
    pub p1: Vec3,
    pub p2: Vec3,
    pub z_min: f32,
    pub z_max: f32,
    pub r_max: f32,
    pub ah: f32,
    pub ch: f32,
    pub phi_max: f32,
    /// Intersect pbrt-v3's implicit fit a_h(x² + y²) − c_h z² = 1 instead of the swept
    /// surface (the render's default; `--fix hyperboloid-surface` clears it).
    pub implicit_fit: bool,
}

impl Hyperboloid {
    /// Follows pbrt-v3's constructor (swap when p2.z = 0, extrapolate until the implicit
    /// fit is finite), but with a bounded loop.
    // DEVIATION(pbrt): robustness. pbrt-v3 loops forever for lines through the z axis (e.g. the
    // default p1/p2) and for flat segments in z = 0; we report an error instead.
    pub fn new(p1: Vec3, p2: Vec3, phi_max_deg: f32) -> Result<Hyperboloid, String> {
        let cross = p1.x * p2.y - p1.y * p2.x;
        let vertical = p1.x == p2.x && p1.y == p2.y;
        if cross == 0.0 && !(vertical && (p1.x != 0.0 || p1.y != 0.0)) {
            return Err(format!(
                "hyperboloid: the line through p1 {p1:?} and p2 {p2:?} meets the z axis, which \
                 the hyperboloid's implicit form cannot represent (pbrt-v3 hangs on it); use a cone"
            ));
        }
        if p1.z == p2.z {
            return Err(format!(
                "hyperboloid: p1 {p1:?} and p2 {p2:?} have the same z, which sweeps a flat annulus; use a disk"
            ));
        }
        let r_max = (p1.x * p1.x + p1.y * p1.y).sqrt().max((p2.x * p2.x + p2.y * p2.y).sqrt());
        let (mut a, b) = if p2.z == 0.0 { (p2, p1) } else { (p1, p2) };
        let (mut ah, mut ch) = (f32::NAN, f32::NAN);
        for _ in 0..64 {
            a += 2.0 * (b - a);
            let xy1 = a.x * a.x + a.y * a.y;
            let xy2 = b.x * b.x + b.y * b.y;
            ah = (1.0 / xy1 - (a.z * a.z) / (xy1 * b.z * b.z)) / (1.0 - (xy2 * a.z * a.z) / (xy1 * b.z * b.z));
            ch = (ah * xy2 - 1.0) / (b.z * b.z);
            if ah.is_finite() && ch.is_finite() {
                break;
            }
        }
        if !(ah.is_finite() && ch.is_finite()) {
            return Err(format!(
                "hyperboloid: no implicit surface fits the segment p1 {p1:?} to p2 {p2:?} \
                 (pbrt-v3 hangs on it)"
            ));
        }
        Ok(Hyperboloid {
            p1,
            p2,
            z_min: p1.z.min(p2.z),
            z_max: p1.z.max(p2.z),
            r_max,
            ah,
            ch,
            phi_max: phi_max_radians(phi_max_deg),
            implicit_fit: false,
        })
    }

    pub fn object_bounds(&self) -> [DVec3; 2] {
        let r = self.r_max as f64;
        [DVec3::new(-r, -r, self.z_min as f64), DVec3::new(r, r, self.z_max as f64)]
    }

    /// φmax ∫₀¹ sqrt(Δz²(x² + y²) + (xΔx + yΔy)²) dv with (x, y) on the segment.
    // DEVIATION(pbrt): no image difference (only `check --shapes` shows it). pbrt-v3's
    // closed form is wrong in general (26.18 instead of 10.77 for p1 = (1,0,−1),
    // p2 = (0,1,1)); we integrate the exact surface-of-revolution area. pbrt-v3 cannot
    // sample a hyperboloid (it aborts on an emitting one), so no image uses its area.
    pub fn area(&self) -> f64 {
        let (p1, d) = (self.p1.as_dvec3(), (self.p2 - self.p1).as_dvec3());
        self.phi_max as f64
            * integrate_unit_interval(|v| {
                let p = p1 + v * d;
                (d.z * d.z * (p.x * p.x + p.y * p.y) + (p.x * d.x + p.y * d.y).powi(2)).sqrt()
            })
    }

    fn profile(&self, v: f64) -> DVec3 {
        self.p1.as_dvec3().lerp(self.p2.as_dvec3(), v)
    }

    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        let (pr, phi) = (self.profile(v), u * self.phi_max as f64);
        let (s, c) = phi.sin_cos();
        DVec3::new(pr.x * c - pr.y * s, pr.x * s + pr.y * c, pr.z)
    }

    pub fn dpdv(&self, u: f64, _v: f64) -> DVec3 {
        let (d, phi) = ((self.p2 - self.p1).as_dvec3(), u * self.phi_max as f64);
        let (s, c) = phi.sin_cos();
        DVec3::new(d.x * c - d.y * s, d.x * s + d.y * c, d.z)
    }
}

impl Hyperboloid {
    /// The swept surface as ρ²(v) = α v² + β v + γ with v = (z − z1)/Δz: returns
    /// (α, β, γ, z1, Δz).
    fn sweep(&self) -> (f64, f64, f64, f64, f64) {
        let (p1, p2) = (self.p1.as_dvec3(), self.p2.as_dvec3());
        let dl = p2 - p1;
        (dl.x * dl.x + dl.y * dl.y, 2.0 * (p1.x * dl.x + p1.y * dl.y), p1.x * p1.x + p1.y * p1.y, p1.z, dl.z)
    }
}

/// Whether the swept surface and pbrt-v3's implicit fit differ: the fit's residual at
/// the segment's ends and middle, relative to its size.
pub fn fit_differs(h: &Hyperboloid) -> bool {
    let implicit = Hyperboloid { implicit_fit: true, ..h.clone() };
    [0.0, 0.5, 1.0].iter().any(|&v| {
        let p = h.point(0.0, v);
        implicit.residual(p) > 1e-4 * (h.r_max as f64).max((h.z_max - h.z_min) as f64)
    })
}

/// Intersected as the surface the segment sweeps (F = x² + y² − ρ²(v)), or as pbrt-v3's
/// implicit fit (`implicit_fit`): see the module notes of `quadric`.
// DEVIATION(pbrt): appearance, `--fix hyperboloid-surface`. pbrt-v3 intersects its
// implicit fit, whose waist is at z = 0: it is the swept surface only when the
// segment's closest approach to the axis is at z = 0 (pbrt-v3 #168), and elsewhere
// pbrt's (u, v), normals and area describe a surface other than the one it hits.
impl QuadricSurface for Hyperboloid {
    fn coefficients<N: Interval>(&self, [ox, oy, oz]: [N; 3], [dx, dy, dz]: [N; 3]) -> (N, N, N) {
        if self.implicit_fit {
            let (ah, ch) = (N::from(self.ah as f64), N::from(self.ch as f64));
            return (
                ah * (dx * dx + dy * dy) - ch * dz * dz,
                (ah * (dx * ox + dy * oy) - ch * dz * oz) * 2.0,
                ah * (ox * ox + oy * oy) - ch * oz * oz - N::from(1.0),
            );
        }
        let (al, be, ga, z1, dzl) = self.sweep();
        let (al, be, ga) = (N::from(al), N::from(be), N::from(ga));
        let v0 = (oz - N::from(z1)) / N::from(dzl);
        let vd = dz / N::from(dzl);
        (
            dx * dx + dy * dy - al * vd * vd,
            (dx * ox + dy * oy - al * v0 * vd) * 2.0 - be * vd,
            ox * ox + oy * oy - al * v0 * v0 - be * v0 - ga,
        )
    }

    fn implicit(&self, p: DVec3) -> (f64, DVec3) {
        if self.implicit_fit {
            let (ah, ch) = (self.ah as f64, self.ch as f64);
            let f = ah * (p.x * p.x + p.y * p.y) - ch * p.z * p.z - 1.0;
            return (f, DVec3::new(2.0 * ah * p.x, 2.0 * ah * p.y, -2.0 * ch * p.z));
        }
        let (al, be, ga, z1, dzl) = self.sweep();
        let v = (p.z - z1) / dzl;
        let f = p.x * p.x + p.y * p.y - (al * v * v + be * v + ga);
        (f, DVec3::new(2.0 * p.x, 2.0 * p.y, -(2.0 * al * v + be) / dzl))
    }

    fn ranges(&self) -> (f64, f64, f64) {
        (self.z_min as f64, self.z_max as f64, self.phi_max as f64)
    }

    /// φ is measured from the profile point p_r(v) at the hit's height.
    fn phi_frame(&self, p: DVec3) -> (f64, f64) {
        let pr = self.profile((p.z - self.p1.z as f64) / (self.p2.z as f64 - self.p1.z as f64));
        (pr.x * p.x + pr.y * p.y, pr.x * p.y - pr.y * p.x)
    }

    fn local(&self, p: DVec3, phi: f64) -> Local {
        let pm = self.phi_max as f64;
        let (p1, p2) = (self.p1.as_dvec3(), self.p2.as_dvec3());
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
            d2_vv: DVec3::ZERO,
        }
    }
}

impl Hyperboloid {
    /// Its parameters after defaults and clamps, for `check --shapes`.
    pub fn params(&self) -> Vec<(&'static str, super::ShapeParam)> {
        use super::ShapeParam::*;
        vec![
            ("p1", Point(self.p1.to_array())),
            ("p2", Point(self.p2.to_array())),
            ("phimax", Angle(self.phi_max)),
            ("zmin", Float(self.z_min)),
            ("zmax", Float(self.z_max)),
            ("rmax", Float(self.r_max)),
        ]
    }
}

pub const NAME: &str = "hyperboloid";

/// `Shape "hyperboloid"` (v3): `p1` (0,0,0), `p2` (1,1,1), `phimax` 360; a line that
/// meets the z axis is an error (pbrt-v3 never returns from it).
pub fn read(p: &ParamList, span: Span) -> Res<Quadric> {
    let p1 = Vec3::from(p.point3("p1")?.unwrap_or([0.0; 3]));
    let p2 = Vec3::from(p.point3("p2")?.unwrap_or([1.0; 3]));
    if !(p1.is_finite() && p2.is_finite()) {
        return Err(Diagnostic::error(span, "hyperboloid: p1 and p2 must be finite"));
    }
    let h = Hyperboloid::new(p1, p2, f(p, "phimax", 360.0)?).map_err(|e| Diagnostic::error(span, e))?;
    Ok(Quadric::Hyperboloid(h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_of_the_reference_case() {
        let h = Hyperboloid::new(Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 1.0, 1.0), 360.0);
        let area = h.map(|h| h.area()).unwrap_or(f64::NAN);
        assert!((area - 10.77).abs() < 0.01, "{area}");
    }

    #[test]
    fn lines_through_the_axis_are_rejected() {
        assert!(Hyperboloid::new(Vec3::ZERO, Vec3::ONE, 360.0).is_err());
        assert!(Hyperboloid::new(Vec3::new(1.0, 1.0, 0.0), Vec3::new(2.0, 2.0, 1.0), 360.0).is_err());
        // A vertical segment off the axis is a cylinder: fine.
        assert!(Hyperboloid::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 1.0), 360.0).is_ok());
    }
}
