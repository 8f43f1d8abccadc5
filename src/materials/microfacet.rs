//! Fresnel terms and pbrt's Trowbridge–Reitz (GGX) microfacet distribution.

use crate::spectrum::Rgb;
use glam::Vec3;
use std::f32::consts::PI;

/// pbrt-v3's `TrowbridgeReitzDistribution::RoughnessToAlpha` (`remaproughness true` in
/// v3 materials).
pub fn roughness_to_alpha_v3(r: f32) -> f32 {
    let x = r.max(1e-3).ln();
    1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x
}

/// Fresnel reflectance of a dielectric interface (pbrt `FrDielectric`): a negative
/// cosine means the light arrives from inside (η swapped).
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

/// What a microfacet or specular reflection lobe multiplies by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    /// Always 1 (`mirror`).
    One,
    Conductor {
        eta: Rgb,
        k: Rgb,
    },
    /// Air over a dielectric of index `eta` (pbrt `FresnelDielectric(1, eta)`): light
    /// from below the shading normal is taken to come from inside.
    Dielectric {
        eta: f32,
    },
    /// The coat of an opaque material: light always arrives through air.
    // DEVIATION(pbrt): pbrt-v3's plastic builds `FresnelDielectric(1.5, 1)`, indices
    // swapped, so its highlights turn totally reflecting past a 41.8° half-angle
    // (pbrt-v3 #210, left unfixed there so old images stay the same).
    Coat {
        eta: f32,
    },
}

impl Fresnel {
    /// F for the cosine between the incident direction and the (micro)normal.
    pub fn eval(self, cos_i: f32) -> Rgb {
        match self {
            Fresnel::One => Vec3::ONE,
            Fresnel::Conductor { eta, k } => fr_conductor(cos_i, eta, k),
            Fresnel::Dielectric { eta } => Vec3::splat(fr_dielectric(cos_i, 1.0, eta)),
            Fresnel::Coat { eta } => Vec3::splat(fr_dielectric(cos_i.abs(), 1.0, eta)),
        }
    }
}

/// Trowbridge–Reitz microfacet distribution with α along the shading tangents.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    pub ax: f32,
    pub ay: f32,
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
    /// α below 10⁻³ is raised to it (pbrt-v3 clamps the same way in its sampling).
    pub fn new(alpha: [f32; 2]) -> TrowbridgeReitz {
        TrowbridgeReitz { ax: alpha[0].max(1e-3), ay: alpha[1].max(1e-3) }
    }

    pub fn d(&self, wh: Vec3) -> f32 {
        let Some((cos2, tan2, cos_phi2, sin_phi2)) = slope_terms(wh) else { return 0.0 };
        if !tan2.is_finite() {
            return 0.0;
        }
        let e = (cos_phi2 / (self.ax * self.ax) + sin_phi2 / (self.ay * self.ay)) * tan2;
        1.0 / (PI * self.ax * self.ay * cos2 * cos2 * (1.0 + e) * (1.0 + e))
    }

    fn lambda(&self, w: Vec3) -> f32 {
        let Some((_, tan2, cos_phi2, sin_phi2)) = slope_terms(w) else { return 0.0 };
        if !tan2.is_finite() {
            return 0.0;
        }
        let alpha2 = cos_phi2 * self.ax * self.ax + sin_phi2 * self.ay * self.ay;
        (-1.0 + (1.0 + alpha2 * tan2).sqrt()) / 2.0
    }

    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// A microfacet normal in the hemisphere of `wo`, with density D·|cos θh|.
    // DEVIATION(pbrt): pbrt-v3 samples visible normals by default; sampling all
    // normals is unbiased with the matching pdf, only noisier at grazing angles.
    pub fn sample_wh(&self, wo: Vec3, u: [f32; 2]) -> Vec3 {
        let phi = if self.ax == self.ay {
            2.0 * PI * u[1]
        } else {
            (self.ay / self.ax * (2.0 * PI * u[1] + 0.5 * PI).tan()).atan() + if u[1] > 0.5 { PI } else { 0.0 }
        };
        let (sp, cp) = phi.sin_cos();
        let alpha2 = 1.0 / (cp * cp / (self.ax * self.ax) + sp * sp / (self.ay * self.ay));
        let tan2 = alpha2 * u[0] / (1.0 - u[0]).max(1e-7);
        let cos_t = 1.0 / (1.0 + tan2).sqrt();
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let wh = Vec3::new(sin_t * cp, sin_t * sp, cos_t);
        if wh.z * wo.z < 0.0 { -wh } else { wh }
    }

    /// The density of [`TrowbridgeReitz::sample_wh`] (over microfacet normals).
    pub fn pdf_wh(&self, wh: Vec3) -> f32 {
        self.d(wh) * wh.z.abs()
    }
}
