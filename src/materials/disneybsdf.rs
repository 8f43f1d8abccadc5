//! The lobes of pbrt-v3's Disney BSDF ([`super::disney`] makes them): diffuse with
//! Fresnel, fake subsurface, retro-reflection and sheen (all sampled by the cosine, as
//! pbrt-v3's default `Sample_f`), and the GTR1 clearcoat with its own sampling. Their
//! specular lobe's Fresnel term is [`super::microfacet::fr_disney`].

use super::microfacet::schlick_weight;
use crate::spectrum::Rgb;
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// pbrt-v3's `Lerp(t, a, b)`.
pub fn lerp<T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>>(t: f32, a: T, b: T) -> T {
    a * (1.0 - t) + b * t
}

/// The half vector of a reflection pair and cos θd (ωi·ωh); `None` when they cancel.
fn half(o: Vec3, i: Vec3) -> Option<(Vec3, f32)> {
    let h = o + i;
    (h != Vec3::ZERO).then(|| {
        let h = h.normalize();
        (h, i.dot(h))
    })
}

/// Diffuse with Fresnel: 1 at normal incidence, ½ at grazing (Burley 2015, eq. 4).
pub fn diffuse(o: Vec3, i: Vec3, r: Rgb) -> Rgb {
    let (fo, fi) = (schlick_weight(o.z.abs()), schlick_weight(i.z.abs()));
    r * FRAC_1_PI * (1.0 - fo / 2.0) * (1.0 - fi / 2.0)
}

/// Hanrahan–Krueger's approximation of subsurface light, flattened by roughness.
pub fn fake_ss(o: Vec3, i: Vec3, r: Rgb, roughness: f32) -> Rgb {
    let Some((_, cos_d)) = half(o, i) else { return Vec3::ZERO };
    let fss90 = cos_d * cos_d * roughness;
    let (fo, fi) = (schlick_weight(o.z.abs()), schlick_weight(i.z.abs()));
    let fss = lerp(fo, 1.0, fss90) * lerp(fi, 1.0, fss90);
    // 1.25 keeps the albedo roughly as it was.
    let ss = 1.25 * (fss * (1.0 / (o.z.abs() + i.z.abs()) - 0.5) + 0.5);
    r * FRAC_1_PI * ss
}

/// Retro-reflection at grazing angles on rough surfaces.
pub fn retro(o: Vec3, i: Vec3, r: Rgb, roughness: f32) -> Rgb {
    let Some((_, cos_d)) = half(o, i) else { return Vec3::ZERO };
    let (fo, fi) = (schlick_weight(o.z.abs()), schlick_weight(i.z.abs()));
    let rr = 2.0 * roughness * cos_d * cos_d;
    r * FRAC_1_PI * rr * (fo + fi + fo * fi * (rr - 1.0))
}

/// Sheen: a grazing rim (pbrt-v3 leaves out the 1/π).
pub fn sheen(o: Vec3, i: Vec3, r: Rgb) -> Rgb {
    half(o, i).map_or(Vec3::ZERO, |(_, cos_d)| r * schlick_weight(cos_d))
}

/// Burley's GTR1 distribution of α = `alpha` at cos θh.
fn gtr1(cos: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    // DEVIATION(pbrt): robustness. At α = 1 pbrt-v3 divides 0 by log 1 (NaN); the
    // limit is uniform in cos²θh.
    if a2 == 1.0 {
        return FRAC_1_PI;
    }
    (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * cos * cos))
}

/// Smith's GGX masking in the form that folds in 1/(4 cos θ), as pbrt-v3's clearcoat
/// uses it.
fn smith_g_ggx(cos: f32, alpha: f32) -> f32 {
    let (a2, c2) = (alpha * alpha, cos * cos);
    1.0 / (cos + (a2 + c2 - a2 * c2).sqrt())
}

/// The clearcoat: index 1.5 (R(0) = 0.04), GTR1 of α = `gloss`, masking at α = 0.25.
pub fn clearcoat(o: Vec3, i: Vec3, weight: Rgb, gloss: f32) -> Rgb {
    let Some((h, _)) = half(o, i) else { return Vec3::ZERO };
    let dr = gtr1(h.z.abs(), gloss);
    let fr = lerp(schlick_weight(o.dot(h)), 0.04, 1.0);
    let gr = smith_g_ggx(o.z.abs(), 0.25) * smith_g_ggx(i.z.abs(), 0.25);
    weight * gr * fr * dr / 4.0
}

/// The density of [`clearcoat_sample`]: GTR1 over half vectors, moved to ωi.
pub fn clearcoat_pdf(o: Vec3, i: Vec3, gloss: f32) -> f32 {
    if o.z * i.z <= 0.0 {
        return 0.0;
    }
    let Some((h, _)) = half(o, i) else { return 0.0 };
    gtr1(h.z.abs(), gloss) * h.z.abs() / (4.0 * o.dot(h))
}

/// A clearcoat direction: a half vector drawn from GTR1, ωo mirrored about it; `None`
/// when that leaves the other side.
pub fn clearcoat_sample(o: Vec3, u: [f32; 2], gloss: f32) -> Option<Vec3> {
    let a2 = gloss * gloss;
    let cos2 = if a2 == 1.0 { u[0] } else { ((1.0 - a2.powf(1.0 - u[0])) / (1.0 - a2)).max(0.0) };
    let cos = cos2.sqrt();
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let mut h = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
    if h.z * o.z < 0.0 {
        h = -h;
    }
    let i = -o + 2.0 * o.dot(h) * h;
    (i.z * o.z > 0.0).then_some(i)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ pdf dω over the sphere, by a fine midpoint rule in (cos θ, φ).
    fn integral(pdf: impl Fn(Vec3) -> f32) -> f64 {
        let n = 800;
        let mut sum = 0.0;
        for a in 0..n {
            let z = -1.0 + 2.0 * (a as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            for b in 0..n {
                let phi = 2.0 * std::f64::consts::PI * (b as f64 + 0.5) / n as f64;
                let w = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                sum += pdf(w) as f64;
            }
        }
        sum * 4.0 * std::f64::consts::PI / (n * n) as f64
    }

    #[test]
    fn the_clearcoat_samples_follow_the_clearcoat_density() {
        let o = Vec3::new(0.3, -0.2, 0.9).normalize();
        for gloss in [0.1, 0.05] {
            // Less than 1 by what mirrors below the horizon (GTR1's tails are long):
            // the share of samples kept must be that integral.
            let total = integral(|i| clearcoat_pdf(o, i, gloss));
            let n = 200_000;
            let (mut sum, mut kept) = (0.0, 0);
            for k in 0..n {
                let u = [(k as f32 + 0.5) / n as f32, (k as f64 * 0.618_033_988_749_895).fract() as f32];
                if let Some(i) = clearcoat_sample(o, u, gloss) {
                    let p = clearcoat_pdf(o, i, gloss);
                    assert!(p > 0.0 && p.is_finite(), "gloss {gloss}: pdf {p} at a sample");
                    kept += 1;
                    sum += if i.z > 0.5 { 1.0 / p as f64 } else { 0.0 };
                }
            }
            let share = kept as f64 / n as f64;
            assert!(total > 0.5 && (share / total - 1.0).abs() < 0.01, "gloss {gloss}: kept {share}, ∫pdf {total}");
            let cap = sum / n as f64;
            assert!((cap / std::f64::consts::PI - 1.0).abs() < 0.03, "gloss {gloss}: {cap}");
        }
    }

    #[test]
    fn the_fresnel_term_is_the_dielectrics_or_schlicks_by_metallic() {
        use super::super::microfacet::{fr_dielectric, fr_disney};
        let r0 = Vec3::new(0.9, 0.5, 0.1);
        assert_eq!(fr_disney(r0, 0.0, 1.5, 0.7), Vec3::splat(fr_dielectric(0.7, 1.0, 1.5)));
        assert_eq!(fr_disney(r0, 1.0, 1.5, 1.0), r0);
        assert_eq!(fr_disney(r0, 1.0, 1.5, 0.0), Vec3::ONE);
        // Head-on, a diffuse lobe passes all it is given; at grazing, half each way.
        let n = Vec3::Z;
        assert!((diffuse(n, n, Vec3::ONE).x - FRAC_1_PI).abs() < 1e-7);
        let graze = Vec3::new(1.0, 0.0, 0.0);
        assert!((diffuse(graze, n, Vec3::ONE).x - 0.5 * FRAC_1_PI).abs() < 1e-7);
        assert_eq!(gtr1(0.3, 1.0), FRAC_1_PI);
    }
}
