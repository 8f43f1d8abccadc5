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

/// A thin pane's shares reflected and passed through at `cos_o` (|cos θ| of the direction the
/// light leaves by): each face's Fresnel reflectance R, then the geometric series of
/// bounces between the two faces, R + T²R/(1 − R²).
pub fn fr_thin_dielectric(cos_o: f32, eta: f32) -> (f32, f32) {
    let r = fr_dielectric(cos_o.abs(), 1.0, eta);
    if r >= 1.0 {
        return (1.0, 0.0);
    }
    let t = 1.0 - r;
    let r = r + t * t * r / (1.0 - r * r);
    (r, 1.0 - r)
}

/// (1 − cos θ)⁵, the weight of Schlick's approximation.
pub fn schlick_weight(cos: f32) -> f32 {
    (1.0 - cos).clamp(0.0, 1.0).powi(5)
}

/// The Disney specular lobe's Fresnel term: the dielectric's, blended towards Schlick's
/// from `r0` by `metallic`.
pub fn fr_disney(r0: Rgb, metallic: f32, eta: f32, cos_i: f32) -> Rgb {
    let w = schlick_weight(cos_i);
    let schlick = r0 * (1.0 - w) + Vec3::splat(w);
    Vec3::splat(fr_dielectric(cos_i, 1.0, eta)) * (1.0 - metallic) + schlick * metallic
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
    /// The coat of an opaque material: light always arrives through air (pbrt-v3's
    /// plastic with `--fix plastic-fresnel`).
    Coat {
        eta: f32,
    },
    /// pbrt-v3's plastic: `FresnelDielectric(eta, 1)`, the indices swapped, so light
    /// from the normal's side sees a dielectric of index 1/η and reflects totally past
    /// a 41.8° half-angle (pbrt-v3 #210, left so there to keep old images the same).
    // DEVIATION(pbrt): appearance, `--fix plastic-fresnel` uses `Coat` instead.
    SwappedCoat {
        eta: f32,
    },
    /// pbrt-v3's `DisneyFresnel`: the dielectric's term blended towards Schlick's from
    /// `r0` by `metallic` ([`fr_disney`]).
    Disney {
        r0: Rgb,
        metallic: f32,
        eta: f32,
    },
}

impl Fresnel {
    /// Whether F is zero at every angle: a dielectric interface between equal indices
    /// (`uber`'s `index` 1). pbrt's formula leaves rounding there: at most 5·10⁻⁸
    /// where |cos θ| is above 0.01, more below, and 1 below 2·10⁻⁴ (sin θ rounds to 1,
    /// so it reflects totally): a microfacet seen within 0.01° of edge-on.
    pub fn joins_equal_indices(self) -> bool {
        matches!(self, Fresnel::Dielectric { eta } | Fresnel::Coat { eta } | Fresnel::SwappedCoat { eta } if eta == 1.0)
    }

    /// F for the cosine between the incident direction and the (micro)normal.
    pub fn eval(self, cos_i: f32) -> Rgb {
        match self {
            Fresnel::One => Vec3::ONE,
            Fresnel::Conductor { eta, k } => fr_conductor(cos_i, eta, k),
            Fresnel::Dielectric { eta } => Vec3::splat(fr_dielectric(cos_i, 1.0, eta)),
            Fresnel::Coat { eta } => Vec3::splat(fr_dielectric(cos_i.abs(), 1.0, eta)),
            Fresnel::SwappedCoat { eta } => Vec3::splat(fr_dielectric(cos_i, eta, 1.0)),
            Fresnel::Disney { r0, metallic, eta } => fr_disney(r0, metallic, eta, cos_i),
        }
    }
}

/// Trowbridge–Reitz microfacet distribution with α along the shading tangents.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    pub ax: f32,
    pub ay: f32,
    /// Masking and shadowing as G1(ωo)·G1(ωi), as pbrt-v3's Disney distribution has
    /// them, rather than Smith's correlated 1/(1 + Λ(ωo) + Λ(ωi)).
    pub separable: bool,
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
        TrowbridgeReitz { ax: alpha[0].max(1e-3), ay: alpha[1].max(1e-3), separable: false }
    }

    /// pbrt-v3's `DisneyMicrofacetDistribution`: the same, with separable masking.
    pub fn separable(alpha: [f32; 2]) -> TrowbridgeReitz {
        TrowbridgeReitz { separable: true, ..TrowbridgeReitz::new(alpha) }
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
        if self.separable {
            return self.g1(wo) * self.g1(wi);
        }
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Smith's masking of one direction.
    fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// A microfacet normal visible from `wo`, in its hemisphere, with density
    /// [`TrowbridgeReitz::pdf_wh`] (pbrt-v4's `Sample_wm`: visible normals, which pbrt-v3
    /// samples too, so few samples carry large weights at grazing angles).
    pub fn sample_wh(&self, wo: Vec3, u: [f32; 2]) -> Vec3 {
        let w = if wo.z < 0.0 { -wo } else { wo };
        let wh = Vec3::new(self.ax * w.x, self.ay * w.y, w.z).normalize_or_zero();
        let t1 = if wh.z < 0.99999 { Vec3::Z.cross(wh).normalize() } else { Vec3::X };
        let t2 = wh.cross(t1);
        let (r, phi) = (u[0].sqrt(), 2.0 * PI * u[1]);
        let (px, py) = (r * phi.cos(), r * phi.sin());
        let h = (1.0 - px * px).max(0.0).sqrt();
        let s = 0.5 * (1.0 + wh.z);
        let py = (1.0 - s) * h + s * py;
        let pz = (1.0 - px * px - py * py).max(0.0).sqrt();
        let nh = px * t1 + py * t2 + pz * wh;
        let wm = Vec3::new(self.ax * nh.x, self.ay * nh.y, nh.z.max(1e-6)).normalize();
        if wo.z < 0.0 { -wm } else { wm }
    }

    /// The density of [`TrowbridgeReitz::sample_wh`] for `wo` (over microfacet normals):
    /// G1(ωo) · D(ωh) · max(0, ωo·ωh) / |cos θo|, with ωh taken on ωo's side (either
    /// orientation is the same facet). Facets facing away from ωo are never sampled.
    pub fn pdf_wh(&self, wo: Vec3, wh: Vec3) -> f32 {
        let wh = if wh.z * wo.z < 0.0 { -wh } else { wh };
        // A facet facing away (or a NaN) has no density.
        if wo.dot(wh).max(0.0) == 0.0 {
            return 0.0;
        }
        self.pdf_wh_either_side(wo, wh)
    }

    /// pbrt-v3's `MicrofacetDistribution::Pdf`: [`TrowbridgeReitz::pdf_wh`] with |ωo·ωh|,
    /// so facets facing away from ωo, which are never sampled, have a density too.
    pub fn pdf_wh_either_side(&self, wo: Vec3, wh: Vec3) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        self.g1(wo) / wo.z.abs() * self.d(wh) * wo.dot(wh).abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pane_reflects_both_faces_and_passes_the_rest_straight() {
        let shares = fr_thin_dielectric;
        // Head-on through glass of 1.5: 4% a face, 2R/(1 + R) ≈ 7.7% for the pane.
        let (r, t) = shares(1.0, 1.5);
        assert!((r - 0.08 / 1.04).abs() < 1e-6, "{r}");
        assert!((r + t - 1.0).abs() < 1e-6);
        // Either side, the same shares; at grazing, all reflected.
        assert_eq!(shares(-0.3, 1.5), shares(0.3, 1.5));
        assert!(shares(1e-6, 1.5).0 > 0.999);
        // An index of 1 is no surface at all; below 1, light from outside can be
        // reflected whole.
        assert_eq!(shares(0.7, 1.0), (0.0, 1.0));
        assert_eq!(shares(0.1, 0.5), (1.0, 0.0));
    }

    /// E[h(ωh)] over `sample_wh`'s samples, and ∫ h·pdf_wh by quadrature.
    fn sampled_and_integrated(d: TrowbridgeReitz, wo: Vec3, h: impl Fn(Vec3) -> f32) -> (f64, f64) {
        let mut rng = crate::sampling::Rng::new(17);
        let n = 400_000;
        let sampled = (0..n).map(|_| h(d.sample_wh(wo, rng.uniform2())) as f64).sum::<f64>() / n as f64;
        let (nt, np) = (600, 1200);
        let mut integral = 0.0;
        for a in 0..nt {
            let theta = (a as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
            for b in 0..np {
                let phi = (b as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                let z = if wo.z < 0.0 { -theta.cos() } else { theta.cos() };
                let w = Vec3::new((theta.sin() * phi.cos()) as f32, (theta.sin() * phi.sin()) as f32, z as f32);
                let dw = theta.sin() * (std::f64::consts::FRAC_PI_2 / nt as f64) * (std::f64::consts::TAU / np as f64);
                integral += (h(w) * d.pdf_wh(wo, w)) as f64 * dw;
            }
        }
        (sampled, integral)
    }

    #[test]
    fn visible_normals_are_sampled_with_the_stated_density() {
        let d = TrowbridgeReitz::new([0.15, 0.5]);
        for wo in [Vec3::new(0.6, 0.3, 0.74).normalize(), Vec3::new(-0.2, 0.9, -0.4).normalize()] {
            for (name, h) in [
                ("1", &(|_: Vec3| 1.0f32) as &dyn Fn(Vec3) -> f32),
                ("x²", &|w: Vec3| w.x * w.x),
                ("y > 0", &|w: Vec3| (w.y > 0.0) as u8 as f32),
                ("|z|³", &|w: Vec3| w.z.abs().powi(3)),
            ] {
                let (s, i) = sampled_and_integrated(d, wo, h);
                assert!((s - i).abs() < 0.01 * i.abs().max(0.05), "{name} for {wo}: sampled {s}, integrated {i}");
            }
        }
    }
}
