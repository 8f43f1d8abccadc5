//! `Material "disney"` (v3): pbrt-v3's Disney BSDF (Burley 2015), which exporters
//! write for Blender's Principled BSDF.
//!
//! ```text
//! Material "disney" "rgb color" [.8 .2 .1] "float metallic" 0 "float roughness" .4
//!     "float speculartint" .2 "float sheen" .5 "float clearcoat" .3 "float spectrans" 0
//! Material "disney" "bool thin" true "float difftrans" 1.2 "float flatness" .5
//! ```
//! The lobes are pbrt-v3's, weighted as it weighs them: a Fresnel-modified diffuse
//! lobe (blended with a fake-subsurface lobe by `flatness` on a `thin` surface),
//! retro-reflection and sheen, all scaled by (1 − `metallic`)(1 − `spectrans`); a
//! Trowbridge–Reitz specular lobe with separable masking and a Fresnel term between a
//! dielectric's and Schlick's; a GTR1 clearcoat; rough transmission tinted by
//! √`color`; and, on a thin surface, Lambertian transmission by `difftrans`/2.
//! A `scatterdistance` makes pbrt-v3 add a BSSRDF under a smooth boundary: the
//! boundary is rendered (it is all pbrt-v3's SPPM and bdpt see), the BSSRDF is not
//! (an approximation, noted).

use super::MaterialKind;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::{Fresnel, TrowbridgeReitz, fr_dielectric};
use super::params::{Resolver, TexValue, float, spectrum};
use crate::approx::Approx;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::textures::TexCtx;
use crate::values::{Range, Res};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

pub const NAME: &str = "disney";

/// The material's inputs, as pbrt-v3's `CreateDisneyMaterial` reads them.
#[derive(Clone, Debug, PartialEq)]
pub struct Disney {
    pub color: TexValue,
    pub metallic: TexValue,
    pub eta: TexValue,
    pub roughness: TexValue,
    pub specular_tint: TexValue,
    pub anisotropic: TexValue,
    pub sheen: TexValue,
    pub sheen_tint: TexValue,
    pub clearcoat: TexValue,
    pub clearcoat_gloss: TexValue,
    pub spec_trans: TexValue,
    /// Not black: pbrt-v3 puts a BSSRDF under a smooth boundary in place of the
    /// diffuse lobe (only the boundary is rendered here).
    pub scatter_distance: TexValue,
    pub thin: bool,
    pub flatness: TexValue,
    pub diff_trans: TexValue,
}

pub fn read(_ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let any = |name: &str, default: f32, r: &mut dyn Resolver| float(p, name, default, Range::Any, r);
    let scatter_distance = spectrum(p, "scatterdistance", 0.0, r)?;
    let thin = p.bool("thin")?.unwrap_or(false);
    if scatter_distance != TexValue::Const(Vec3::ZERO) && !thin {
        r.approximate(at, "material \"disney\" with \"scatterdistance\"".into(), Approx::DisneyBssrdf);
    }
    Ok(MaterialKind::Disney(Box::new(Disney {
        color: spectrum(p, "color", 0.5, r)?,
        metallic: any("metallic", 0.0, r)?,
        eta: float(p, "eta", 1.5, Range::Positive, r)?,
        roughness: any("roughness", 0.5, r)?,
        specular_tint: any("speculartint", 0.0, r)?,
        anisotropic: any("anisotropic", 0.0, r)?,
        sheen: any("sheen", 0.0, r)?,
        sheen_tint: any("sheentint", 0.5, r)?,
        clearcoat: any("clearcoat", 0.0, r)?,
        clearcoat_gloss: any("clearcoatgloss", 1.0, r)?,
        spec_trans: any("spectrans", 0.0, r)?,
        scatter_distance,
        thin,
        flatness: any("flatness", 0.0, r)?,
        diff_trans: any("difftrans", 1.0, r)?,
    })))
}

/// pbrt-v3's `Lerp(t, a, b)`.
fn lerp<T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>>(t: f32, a: T, b: T) -> T {
    a * (1.0 - t) + b * t
}

/// The colours the lobes are made of, in RGB (then put in the path's lanes).
struct Colours {
    c: Rgb,
    /// `color` with its luminance divided out: hue and saturation alone.
    tint: Rgb,
}

impl Colours {
    fn of(c: Rgb) -> Colours {
        let lum = crate::spectrum::luminance(c);
        Colours { c, tint: if lum > 0.0 { c / lum } else { Vec3::ONE } }
    }
}

/// The lobes at a hit, in pbrt-v3's order (which decides nothing but is kept).
pub fn lobes<const N: usize>(d: &Disney, i: &Inputs<impl Fn() -> TexCtx>, out: &mut Lobes<N>) {
    let k = Colours::of(i.rgb(d.color).max(Vec3::ZERO));
    let lanes = |c: Rgb| i.lanes_unbounded(c);
    let metallic = i.float(d.metallic);
    let e = i.float(d.eta);
    let strans = i.float(d.spec_trans);
    let diffuse_weight = (1.0 - metallic) * (1.0 - strans);
    // 0: all the diffuse light is reflected; 1: all transmitted.
    let dt = i.float(d.diff_trans) / 2.0;
    let rough = i.float(d.roughness);
    if diffuse_weight > 0.0 {
        diffuse_lobes(d, &k, [diffuse_weight, dt, rough, e], i, out);
    }
    // DEVIATION(pbrt): robustness. pbrt-v3's √(1 − 0.9·anisotropic) is NaN past
    // anisotropic 1.11; the root is kept at or above its value at 1.
    let aspect = (1.0 - i.float(d.anisotropic) * 0.9).max(0.1).sqrt();
    let alpha = |r: f32| [(r * r / aspect).max(1e-3), (r * r * aspect).max(1e-3)];
    let dist = TrowbridgeReitz::separable(alpha(rough));
    let tinted = lerp(i.float(d.specular_tint), Vec3::ONE, k.tint);
    let r0 = lerp(metallic, schlick_r0(e) * tinted, k.c);
    let fresnel = Fresnel::Disney { r0: lanes(r0), metallic, eta: e };
    out.push(Lobe::MicrofacetReflection { r: Vec3::ONE, dist, fresnel });
    let cc = i.float(d.clearcoat);
    if cc > 0.0 {
        let gloss = lerp(i.float(d.clearcoat_gloss), 0.1, 0.001);
        out.push(Lobe::DisneyClearcoat { weight: Vec3::splat(cc), gloss });
    }
    if strans > 0.0 {
        // √colour, so that two refractions give the colour back.
        let t = lanes(strans * k.c.powf(0.5));
        let dist = match d.thin {
            // The roughness scaled by the index (Burley 2015, figure 15).
            true => TrowbridgeReitz::new(alpha((0.65 * e - 0.35) * rough)),
            false => dist,
        };
        out.push(Lobe::MicrofacetTransmission { t, dist, eta: e });
    }
    if d.thin {
        out.push(Lobe::LambertTransmission(lanes(dt * k.c)));
    }
}

/// The lobes (1 − metallic)(1 − spectrans) weighs: diffuse (or fake subsurface, or
/// the BSSRDF's boundary), retro-reflection and sheen. pbrt-v3 adds them whatever
/// their colour, so black ones still count among the lobes a sample picks from.
fn diffuse_lobes<const N: usize>(
    d: &Disney,
    k: &Colours,
    [weight, dt, rough, eta]: [f32; 4],
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let lanes = |c: Rgb| i.lanes_unbounded(c);
    let c = weight * k.c;
    if d.thin {
        let flat = i.float(d.flatness);
        out.push(Lobe::DisneyDiffuse(lanes((1.0 - flat) * (1.0 - dt) * c)));
        out.push(Lobe::DisneyFakeSs { r: lanes(flat * (1.0 - dt) * c), roughness: rough });
    } else if i.rgb(d.scatter_distance) == Vec3::ZERO {
        out.push(Lobe::DisneyDiffuse(lanes(c)));
    } else {
        out.push(Lobe::SpecularTransmission { t: Vec3::ONE, eta });
    }
    out.push(Lobe::DisneyRetro { r: lanes(c), roughness: rough });
    let sheen = i.float(d.sheen);
    if sheen > 0.0 {
        let tint = lerp(i.float(d.sheen_tint), Vec3::ONE, k.tint);
        out.push(Lobe::DisneySheen(lanes(weight * sheen * tint)));
    }
}

/// R(0) of a dielectric of index `eta` seen from air.
fn schlick_r0(eta: f32) -> f32 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

/// (1 − cos θ)⁵, the weight of Schlick's approximation.
pub fn schlick_weight(cos: f32) -> f32 {
    (1.0 - cos).clamp(0.0, 1.0).powi(5)
}

/// The Disney specular lobe's Fresnel term: the dielectric's, blended towards Schlick's
/// from `r0` by `metallic`.
pub fn fresnel(r0: Rgb, metallic: f32, eta: f32, cos_i: f32) -> Rgb {
    let schlick = lerp(schlick_weight(cos_i), r0, Vec3::ONE);
    lerp(metallic, Vec3::splat(fr_dielectric(cos_i, 1.0, eta)), schlick)
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

pub fn mitsuba(d: &Disney, e: &mut dyn MaterialExport) -> MaterialOut {
    e.diffuse_part(d.color)
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
        let r0 = Vec3::new(0.9, 0.5, 0.1);
        assert_eq!(fresnel(r0, 0.0, 1.5, 0.7), Vec3::splat(fr_dielectric(0.7, 1.0, 1.5)));
        assert_eq!(fresnel(r0, 1.0, 1.5, 1.0), r0);
        assert_eq!(fresnel(r0, 1.0, 1.5, 0.0), Vec3::ONE);
        // Head-on, a diffuse lobe passes all it is given; at grazing, half each way.
        let n = Vec3::Z;
        assert!((diffuse(n, n, Vec3::ONE).x - FRAC_1_PI).abs() < 1e-7);
        let graze = Vec3::new(1.0, 0.0, 0.0);
        assert!((diffuse(graze, n, Vec3::ONE).x - 0.5 * FRAC_1_PI).abs() < 1e-7);
        assert_eq!(gtr1(0.3, 1.0), FRAC_1_PI);
    }
}
