//! BSDFs in a shading frame (pbrt-v3's BxDFs, RGB): Lambertian reflection, specular
//! reflection, smooth dielectrics with Fresnel, smooth conductors, and rough
//! conductors with pbrt-v3's Trowbridge–Reitz microfacet distribution.

use crate::sampling::cosine_hemisphere;
use crate::spectrum::Rgb;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Which quantity a path carries: radiance (camera paths) or importance (photons).
/// Only refraction differs: radiance is scaled by (η_i/η_t)².
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BxDF {
    Lambert(Rgb),
    Specular(Rgb),
    Dielectric {
        eta: f32,
        kr: Rgb,
        kt: Rgb,
    },
    Conductor {
        eta: Rgb,
        k: Rgb,
    },
    /// Trowbridge–Reitz (GGX) microfacet reflection with conductor Fresnel.
    RoughConductor {
        eta: Rgb,
        k: Rgb,
        alpha: [f32; 2],
    },
}

/// pbrt-v3's `TrowbridgeReitzDistribution::RoughnessToAlpha` (used by `metal`).
pub fn roughness_to_alpha_v3(r: f32) -> f32 {
    let x = r.max(1e-3).ln();
    1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x
}

/// Trowbridge–Reitz microfacet distribution (pbrt-v3, sampling all normals).
#[derive(Clone, Copy, Debug)]
struct TrowbridgeReitz {
    ax: f32,
    ay: f32,
}

/// (cos²θ, tan²θ, cos²φ, sin²φ) of a local direction; `None` when it is tangent.
fn slope_terms(w: Vec3) -> Option<(f32, f32, f32, f32)> {
    let cos2 = w.z * w.z;
    let sin2 = (1.0 - cos2).max(0.0);
    if cos2 == 0.0 {
        return None;
    }
    let (cos_phi2, sin_phi2) = if sin2 > 0.0 { (w.x * w.x / sin2, w.y * w.y / sin2) } else { (1.0, 0.0) };
    Some((cos2, sin2 / cos2, cos_phi2, sin_phi2))
}

impl TrowbridgeReitz {
    fn d(&self, wh: Vec3) -> f32 {
        let Some((cos2, tan2, cos_phi2, sin_phi2)) = slope_terms(wh) else { return 0.0 };
        let e = (cos_phi2 / (self.ax * self.ax) + sin_phi2 / (self.ay * self.ay)) * tan2;
        1.0 / (std::f32::consts::PI * self.ax * self.ay * cos2 * cos2 * (1.0 + e) * (1.0 + e))
    }

    fn lambda(&self, w: Vec3) -> f32 {
        let Some((_, tan2, cos_phi2, sin_phi2)) = slope_terms(w) else { return 0.0 };
        let alpha2 = cos_phi2 * self.ax * self.ax + sin_phi2 * self.ay * self.ay;
        (-1.0 + (1.0 + alpha2 * tan2).sqrt()) / 2.0
    }

    fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// A microfacet normal in the hemisphere of `wo`, with density D·|cos θh|.
    fn sample_wh(&self, wo: Vec3, u: [f32; 2]) -> Vec3 {
        let phi = (self.ay / self.ax * (2.0 * std::f32::consts::PI * u[1] + 0.5 * std::f32::consts::PI).tan()).atan()
            + if u[1] > 0.5 { std::f32::consts::PI } else { 0.0 };
        let phi = if self.ax == self.ay { 2.0 * std::f32::consts::PI * u[1] } else { phi };
        let (sp, cp) = phi.sin_cos();
        let alpha2 = 1.0 / (cp * cp / (self.ax * self.ax) + sp * sp / (self.ay * self.ay));
        let tan2 = alpha2 * u[0] / (1.0 - u[0]).max(1e-7);
        let cos_t = 1.0 / (1.0 + tan2).sqrt();
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let wh = Vec3::new(sin_t * cp, sin_t * sp, cos_t);
        if wh.z * wo.z < 0.0 { -wh } else { wh }
    }

    fn pdf_wh(&self, wh: Vec3) -> f32 {
        self.d(wh) * wh.z.abs()
    }
}

/// A sampled direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3,
    pub f: Rgb,
    pub pdf: f32,
    pub specular: bool,
}

/// A BxDF with its shading frame and the geometric normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bsdf {
    ss: Vec3,
    ts: Vec3,
    ns: Vec3,
    ng: Vec3,
    pub bxdf: BxDF,
}

/// Fresnel reflectance of a dielectric interface (pbrt-v3 `FrDielectric`).
pub fn fr_dielectric(cos_i: f32, mut eta_i: f32, mut eta_t: f32) -> f32 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    if cos_i <= 0.0 {
        std::mem::swap(&mut eta_i, &mut eta_t);
        cos_i = cos_i.abs();
    }
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let sin_t = eta_i / eta_t * sin_i;
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let parl = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    let perp = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    (parl * parl + perp * perp) / 2.0
}

/// Fresnel reflectance of a conductor, per channel (pbrt-v3 `FrConductor`, η_i = 1).
pub fn fr_conductor(cos_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    let c = cos_i.clamp(-1.0, 1.0).abs();
    let (c2, s2) = (c * c, 1.0 - c * c);
    let (e2, k2) = (eta * eta, k * k);
    let t0 = e2 - k2 - Vec3::splat(s2);
    let a2b2 = (t0 * t0 + 4.0 * e2 * k2).powf(0.5);
    let t1 = a2b2 + Vec3::splat(c2);
    let a = (0.5 * (a2b2 + t0)).max(Vec3::ZERO).powf(0.5);
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2b2 + Vec3::splat(s2 * s2);
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    0.5 * (rp + rs)
}

/// Refraction of `wi` about `n` (same side) with relative index `eta` = η_i/η_t.
fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = n.dot(wi);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * -wi + (eta * cos_i - cos_t) * n)
}

impl Bsdf {
    pub fn new(frame: [Vec3; 3], ng: Vec3, bxdf: BxDF) -> Bsdf {
        Bsdf { ss: frame[0], ts: frame[1], ns: frame[2], ng, bxdf }
    }

    pub fn shading_normal(&self) -> Vec3 {
        self.ns
    }

    fn local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.ss), v.dot(self.ts), v.dot(self.ns))
    }

    fn world(&self, v: Vec3) -> Vec3 {
        self.ss * v.x + self.ts * v.y + self.ns * v.z
    }

    /// Whether the BSDF has a diffuse part (SPPM stores visible points there).
    pub fn is_diffuse(&self) -> bool {
        matches!(self.bxdf, BxDF::Lambert(_))
    }

    /// Whether it is glossy (SPPM stores a visible point there only at the last depth).
    pub fn is_glossy(&self) -> bool {
        matches!(self.bxdf, BxDF::RoughConductor { .. })
    }

    fn rough_f(o: Vec3, i: Vec3, eta: Rgb, k: Rgb, alpha: [f32; 2]) -> Rgb {
        let (co, ci) = (o.z.abs(), i.z.abs());
        if co == 0.0 || ci == 0.0 || o.z * i.z <= 0.0 {
            return Vec3::ZERO;
        }
        let wh = o + i;
        if wh == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let wh = wh.normalize();
        let dist = TrowbridgeReitz { ax: alpha[0], ay: alpha[1] };
        fr_conductor(i.dot(wh), eta, k) * dist.d(wh) * dist.g(o, i) / (4.0 * ci * co)
    }

    /// f(ωo, ωi); reflection only counts when both lie on the same side of the geometric
    /// normal (pbrt's rule, which stops light leaking through shading normals).
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.dot(self.ng) * wi.dot(self.ng) <= 0.0 {
            return Vec3::ZERO;
        }
        match self.bxdf {
            BxDF::Lambert(r) => r * FRAC_1_PI,
            BxDF::RoughConductor { eta, k, alpha } => Self::rough_f(self.local(wo), self.local(wi), eta, k, alpha),
            _ => Vec3::ZERO,
        }
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self.bxdf {
            BxDF::Lambert(_) => {
                let (o, i) = (self.local(wo), self.local(wi));
                if o.z * i.z > 0.0 { i.z.abs() * FRAC_1_PI } else { 0.0 }
            }
            BxDF::RoughConductor { alpha, .. } => {
                let (o, i) = (self.local(wo), self.local(wi));
                if o.z * i.z <= 0.0 {
                    return 0.0;
                }
                let wh = (o + i).normalize_or_zero();
                let d = o.dot(wh);
                if d == 0.0 { 0.0 } else { TrowbridgeReitz { ax: alpha[0], ay: alpha[1] }.pdf_wh(wh) / (4.0 * d.abs()) }
            }
            _ => 0.0,
        }
    }

    /// Samples ωi for ωo; `u_lobe` chooses reflection or refraction for dielectrics.
    pub fn sample_f(&self, wo: Vec3, u: [f32; 2], u_lobe: f32, mode: TransportMode) -> Option<BsdfSample> {
        let o = self.local(wo);
        if o.z == 0.0 {
            return None;
        }
        let reflect = Vec3::new(-o.x, -o.y, o.z);
        let specular = |wi_l: Vec3, f: Rgb, pdf: f32| {
            let cos = wi_l.z.abs();
            (cos > 0.0).then(|| BsdfSample { wi: self.world(wi_l), f: f / cos, pdf, specular: true })
        };
        match self.bxdf {
            BxDF::Lambert(_) => {
                let mut i = cosine_hemisphere(u);
                if o.z < 0.0 {
                    i.z = -i.z;
                }
                let wi = self.world(i);
                let pdf = i.z.abs() * FRAC_1_PI;
                (pdf > 0.0).then(|| BsdfSample { wi, f: self.f(wo, wi), pdf, specular: false })
            }
            BxDF::Specular(r) => specular(reflect, r, 1.0),
            BxDF::Conductor { eta, k } => specular(reflect, fr_conductor(o.z, eta, k), 1.0),
            BxDF::RoughConductor { alpha, .. } => {
                let wh = TrowbridgeReitz { ax: alpha[0], ay: alpha[1] }.sample_wh(o, u);
                let i = 2.0 * o.dot(wh) * wh - o;
                if o.z * i.z <= 0.0 {
                    return None;
                }
                let wi = self.world(i);
                let pdf = self.pdf(wo, wi);
                (pdf > 0.0).then(|| BsdfSample { wi, f: self.f(wo, wi), pdf, specular: false })
            }
            BxDF::Dielectric { eta, kr, kt } => {
                let fr = fr_dielectric(o.z, 1.0, eta);
                if u_lobe < fr {
                    return specular(reflect, fr * kr, fr);
                }
                let entering = o.z > 0.0;
                let (eta_i, eta_t) = if entering { (1.0, eta) } else { (eta, 1.0) };
                let n = if entering { Vec3::Z } else { -Vec3::Z };
                let t = refract(o, n, eta_i / eta_t)?;
                let mut ft = kt * (1.0 - fr);
                if mode == TransportMode::Radiance {
                    ft *= (eta_i / eta_t) * (eta_i / eta_t);
                }
                specular(t, ft, 1.0 - fr)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> [Vec3; 3] {
        [Vec3::X, Vec3::Y, Vec3::Z]
    }

    #[test]
    fn fresnel_limits() {
        assert!((fr_dielectric(1.0, 1.0, 1.5) - 0.04).abs() < 1e-6);
        assert_eq!(fr_dielectric(0.1, 1.5, 1.0).max(fr_dielectric(-0.1, 1.0, 1.5)), 1.0, "total internal reflection");
        let c = fr_conductor(1.0, Vec3::splat(0.2), Vec3::splat(3.9));
        assert!(c.x > 0.9 && c.x < 1.0, "{c}");
    }

    #[test]
    fn dielectric_sampling_conserves_energy_at_normal_incidence() {
        let b = Bsdf::new(frame(), Vec3::Z, BxDF::Dielectric { eta: 1.5, kr: Vec3::ONE, kt: Vec3::ONE });
        let wo = Vec3::Z;
        let r = b.sample_f(wo, [0.5, 0.5], 0.0, TransportMode::Importance).unwrap();
        let t = b.sample_f(wo, [0.5, 0.5], 0.99, TransportMode::Importance).unwrap();
        assert!(r.wi.z > 0.99 && t.wi.z < -0.99);
        // Weighted by probability, reflection and transmission throughputs add to 1.
        let total = r.f.x * r.wi.z.abs() + t.f.x * t.wi.z.abs();
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        let tr = b.sample_f(wo, [0.5, 0.5], 0.99, TransportMode::Radiance).unwrap();
        assert!((tr.f.x / t.f.x - 1.0 / 2.25).abs() < 1e-5, "radiance scales by (1/η)²");
    }

    #[test]
    fn rough_conductor_sampling_matches_its_pdf_and_conserves_energy() {
        let b = Bsdf::new(
            frame(),
            Vec3::Z,
            BxDF::RoughConductor { eta: Vec3::splat(0.2), k: Vec3::splat(3.9), alpha: [0.3, 0.3] },
        );
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let mut rng = crate::sampling::Rng::new(11);
        let (mut albedo, mut n) = (0.0, 0);
        for _ in 0..100_000 {
            if let Some(s) = b.sample_f(wo, rng.uniform2(), 0.0, TransportMode::Radiance) {
                assert!((b.pdf(wo, s.wi) - s.pdf).abs() <= 1e-3 * s.pdf);
                albedo += (s.f.x * s.wi.z.abs() / s.pdf) as f64;
            }
            n += 1;
        }
        let albedo = albedo / n as f64;
        assert!(albedo > 0.8 && albedo <= 1.0, "directional albedo {albedo}");
    }

    #[test]
    fn lambert_reflects_only_on_the_geometric_side() {
        let b = Bsdf::new(frame(), Vec3::Z, BxDF::Lambert(Vec3::splat(0.5)));
        assert_eq!(b.f(Vec3::Z, Vec3::new(0.0, 0.6, 0.8)).x, 0.5 * FRAC_1_PI);
        assert_eq!(b.f(Vec3::Z, Vec3::new(0.0, 0.6, -0.8)).x, 0.0);
        let s = b.sample_f(Vec3::new(0.0, 0.0, -1.0), [0.3, 0.7], 0.0, TransportMode::Radiance).unwrap();
        assert!(s.wi.z < 0.0 && s.pdf > 0.0);
    }
}
