//! `Material "disney"` (v3): pbrt-v3's Disney BSDF (Burley 2015), which exporters
//! write for Blender's Principled BSDF.
//!
//! ```text
//! Material "disney" "rgb color" [.8 .2 .1] "float metallic" 0 "float roughness" .4
//!     "float speculartint" .2 "float sheen" .5 "float clearcoat" .3 "float spectrans" 0
//! Material "disney" "bool thin" "true" "float difftrans" 1.2 "float flatness" .5
//! ```
//! The lobes are pbrt-v3's, weighted as it weighs them: a Fresnel-modified diffuse
//! lobe (blended with a fake-subsurface lobe by `flatness` on a `thin` surface),
//! retro-reflection and sheen, all scaled by (1 − `metallic`)(1 − `spectrans`); a
//! Trowbridge–Reitz specular lobe with separable masking and a Fresnel term between a
//! dielectric's and Schlick's; a GTR1 clearcoat; rough transmission tinted by
//! √`color`; and, on a thin surface, Lambertian transmission by `difftrans`/2.
//! A `scatterdistance` on a surface that is not `thin` puts a smooth boundary in place
//! of the diffuse lobe and Burley's BSSRDF under it ([`super::disneybssrdf`]). As for
//! the `subsurface` materials, light goes through the BSSRDF for files whose pbrt-v3
//! integrator takes it (`path`, `volpath`); pbrt-v3's SPPM and bdpt see the boundary
//! alone, and so do ours for their files.

use super::MaterialKind;
use super::bssrdf::Profile;
use super::disneybsdf::lerp;
use super::disneybssrdf::Burley;
use super::inputs::{Inputs, Lobes};
use super::lobes::Lobe;
use super::microfacet::{Fresnel, TrowbridgeReitz};
use super::params::{Resolver, TexValue, float, spectrum};
use crate::fixes::Fix;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::textures::TexCtx;
use crate::values::{Range, Res};
use glam::Vec3;

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
    /// diffuse lobe.
    pub scatter_distance: TexValue,
    pub thin: bool,
    pub flatness: TexValue,
    pub diff_trans: TexValue,
}

pub fn read(_ty: &str, p: &ParamList, _at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let any = |name: &str, default: f32, r: &mut dyn Resolver| float(p, name, default, Range::Any, r);
    let scatter_distance = spectrum(p, "scatterdistance", 0.0, r)?;
    let thin = p.bool("thin")?.unwrap_or(false);
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

impl Disney {
    /// Whether some hit may have a BSSRDF: not thin, and a `scatterdistance` that is
    /// not the constant 0.
    pub fn may_scatter_below(&self) -> bool {
        !self.thin && self.scatter_distance != TexValue::Const(Vec3::ZERO)
    }
}

/// The BSSRDF under the boundary at a hit, and the boundary's index: `None` where
/// pbrt-v3 makes none (thin, no `scatterdistance` there, or no diffuse weight).
pub fn bssrdf(d: &Disney, i: &Inputs<impl Fn() -> TexCtx>) -> Option<(Profile, f32)> {
    if d.thin {
        return None;
    }
    let sd = i.rgb(d.scatter_distance);
    let diffuse_weight = (1.0 - i.float(d.metallic)) * (1.0 - i.float(d.spec_trans));
    if sd == Vec3::ZERO || diffuse_weight <= 0.0 {
        return None;
    }
    let c = i.rgb(d.color).max(Vec3::ZERO);
    let r = i.lanes_unbounded(diffuse_weight * c);
    Some((Profile::Burley(Burley::new(r, i.lanes_unbounded(sd))), i.float(d.eta)))
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
        let facing_only = i.fixes.has(Fix::RoughTransmission);
        out.push(Lobe::MicrofacetTransmission { t, dist, eta: e, facing_only });
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

pub fn mitsuba(d: &Disney, e: &mut dyn MaterialExport) -> MaterialOut {
    e.diffuse_part(d.color)
}
