//! `Material "subsurface"` (both versions) and `"kdsubsurface"` (pbrt-v3): a smooth or
//! rough dielectric boundary over a translucent interior whose light leaves near where
//! it entered, by pbrt's tabulated BSSRDF ([`super::bssrdf`]).
//!
//! ```text
//! Material "subsurface" "string name" "Skin1" "float scale" 10          # measured media
//! Material "subsurface" "rgb sigma_a" [.0011 .0024 .014] "rgb sigma_s" [2.55 3.21 3.77]
//! Material "subsurface" "rgb reflectance" [.8 .5 .4] "rgb mfp" [.5 .3 .2]   # pbrt-v4
//! Material "kdsubsurface" "rgb Kd" [.8 .5 .4] "rgb mfp" [.5 .5 .5]          # pbrt-v3
//! ```
//! The coefficients come from a measured medium's name (then g = 0: the table holds
//! reduced scattering; in pbrt-v3 `sigma_a` and `sigma_s` override it), from `sigma_a`
//! and `sigma_s`, or from a diffuse reflectance and a mean free path, as pbrt's
//! `SubsurfaceFromDiffuse` inverts the profile's albedo. `scale` multiplies them (the
//! scene's unit against the table's mm⁻¹). `--fix subsurface-walk` walks the interior
//! as a homogeneous medium of them instead ([`walk_medium`]).
//!
//! The boundary is pbrt's glass of index `eta` (pbrt-v3: `Kr`, `Kt`, `uroughness`,
//! `vroughness`; pbrt-v4: `roughness` or its two parts). What lies under it depends on
//! the integrator, as in pbrt: its path tracers (pbrt-v3 `path` and `volpath`, pbrt-v4
//! `volpath`) take light that crosses the boundary through the BSSRDF, while its SPPM,
//! bdpt and pbrt-v4's `path` see only the boundary, a clear glass object.

use super::MaterialKind;
use super::bssrdf::{BssrdfTable, Profile, table};
use super::dielectric;
use super::inputs::{Inputs, Lobes};
use super::params::{Resolver, RoughnessRemap, TexValue, remap_v3, remap_v4, roughness, spectrum, uv_roughness};
use crate::media::lanes::{Emitted, Sigma};
use crate::media::{HenyeyGreenstein, Homogeneous, Medium};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::colorspace::ColorSpaceName;
use crate::textures::TexCtx;
use crate::values::{Res, span_of};
use glam::Vec3;
use std::sync::{Arc, OnceLock};

pub const NAMES: [&str; 2] = ["subsurface", "kdsubsurface"];

/// pbrt's defaults when no coefficients are given: skim-milk-like σa and σs (mm⁻¹).
const SIGMA_A: Vec3 = Vec3::new(0.0011, 0.0024, 0.014);
const SIGMA_S: Vec3 = Vec3::new(2.55, 3.21, 3.77);

/// How the interior's coefficients are given.
#[derive(Clone, Debug, PartialEq)]
pub enum Coefficients {
    /// σa and σs (a measured medium's, or the file's).
    Sigma { sigma_a: TexValue, sigma_s: TexValue },
    /// A diffuse reflectance and a mean free path (`kdsubsurface`, pbrt-v4's
    /// `reflectance`).
    Diffuse { reflectance: TexValue, mfp: TexValue },
}

/// A subsurface material's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Subsurface {
    pub coefficients: Coefficients,
    pub scale: f32,
    pub eta: f32,
    pub kr: TexValue,
    pub kt: TexValue,
    pub roughness: [TexValue; 2],
    pub remap: RoughnessRemap,
    /// The phase function's asymmetry (0 for a measured medium).
    pub g: f32,
    /// The profile table of (g, η), shared with every material of the same pair and
    /// made on first use ([`Subsurface::table`]): integrators that see only the
    /// boundary never need it.
    table: OnceLock<Arc<BssrdfTable>>,
    /// Read as pbrt-v4 reads it (its BSDF follows pbrt-v4's conventions).
    pub v4: bool,
}

/// Whether the file's pbrt integrator `name` takes light through the BSSRDF: pbrt-v3's
/// `path` and `volpath`, pbrt-v4's `volpath` (their SPPM, bdpt, MLT, Whitted and direct
/// lighting integrators, and pbrt-v4's `path`, see only the boundary).
pub fn follows_bssrdf(syntax: crate::parser::Syntax, name: &str) -> bool {
    match syntax {
        crate::parser::Syntax::V3 => matches!(name, "path" | "volpath"),
        crate::parser::Syntax::V4 => name == "volpath",
    }
}

impl Subsurface {
    /// The profile table of (g, η).
    pub fn table(&self) -> &Arc<BssrdfTable> {
        self.table.get_or_init(|| table(self.g, self.eta))
    }
}

pub fn read(ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let v4 = r.syntax() == crate::parser::Syntax::V4;
    // DEVIATION(pbrt): robustness. pbrt takes g as given; at |g| ≥ 1 the table's
    // reduced coefficients vanish or turn negative and every pixel of the material is
    // NaN. Kept within ±0.99, as pbrt-v4 keeps a medium's.
    let mut g = p.float("g")?.unwrap_or(0.0).clamp(-0.99, 0.99);
    let coefficients = if ty == NAMES[1] {
        Coefficients::Diffuse { reflectance: spectrum(p, "Kd", 0.5, r)?, mfp: spectrum(p, "mfp", 1.0, r)? }
    } else {
        match named(p, v4, at, &mut g, r)? {
            // pbrt-v4 takes the named medium alone.
            Some((a, s)) if v4 => Coefficients::Sigma { sigma_a: TexValue::Const(a), sigma_s: TexValue::Const(s) },
            // pbrt-v3 takes it as the defaults `sigma_a` and `sigma_s` override.
            found => given(p, v4, at, found.unwrap_or((SIGMA_A, SIGMA_S)), r)?,
        }
    };
    let eta = p.float("eta")?.unwrap_or(1.33);
    if !(eta > 0.0 && eta.is_finite()) {
        return Err(Diagnostic::error(span_of(p, "eta").unwrap_or(at), "\"eta\" must be positive"));
    }
    let scale = p.float("scale")?.unwrap_or(1.0);
    let one = TexValue::Const(Vec3::ONE);
    let (kr, kt) = if v4 { (one, one) } else { (spectrum(p, "Kr", 1.0, r)?, spectrum(p, "Kt", 1.0, r)?) };
    let roughness = if v4 { roughness(p, 0.0, r)? } else { uv_roughness(p, r)? };
    let remap = if v4 { remap_v4(p)? } else { remap_v3(p)? };
    let table = OnceLock::new();
    Ok(MaterialKind::Subsurface(Box::new(Subsurface {
        coefficients,
        scale,
        eta,
        kr,
        kt,
        roughness,
        remap,
        g,
        table,
        v4,
    })))
}

/// A measured medium named by `name`: its (σa, σs), with g = 0. An unknown name is
/// pbrt-v4's error and pbrt-v3's warning (which then keeps the defaults and g).
fn named(p: &ParamList, v4: bool, at: Span, g: &mut f32, r: &mut dyn Resolver) -> Res<Option<(Vec3, Vec3)>> {
    let Some(name) = p.string("name")?.filter(|n| !n.is_empty()) else { return Ok(None) };
    let at = span_of(p, "name").unwrap_or(at);
    let Some((a, s)) = crate::media::presets::lookup(&name) else {
        let msg = format!("named medium \"{name}\" not found");
        if v4 {
            return Err(Diagnostic::error(at, msg));
        }
        r.warn(at, format!("{msg}; the default coefficients are used"));
        return Ok(None);
    };
    if v4 && *g != 0.0 {
        r.warn(at, "a non-zero \"g\" is ignored with a named medium".into());
    }
    *g = 0.0;
    Ok(Some((a, s)))
}

/// `sigma_a` and `sigma_s`, or (pbrt-v4) `reflectance` and `mfp`, or `defaults`.
fn given(p: &ParamList, v4: bool, at: Span, defaults: (Vec3, Vec3), r: &mut dyn Resolver) -> Res<Coefficients> {
    let (has_a, has_s) = (p.named("sigma_a").is_some(), p.named("sigma_s").is_some());
    if v4 && has_a != has_s {
        let (have, lack) = if has_a { ("sigma_a", "sigma_s") } else { ("sigma_s", "sigma_a") };
        let at = span_of(p, have).unwrap_or(at);
        return Err(Diagnostic::error(at, format!("\"{have}\" is given without \"{lack}\"")));
    }
    if v4 && !has_a && p.named("reflectance").is_some() {
        let reflectance = spectrum(p, "reflectance", 0.0, r)?;
        return Ok(Coefficients::Diffuse { reflectance, mfp: spectrum(p, "mfp", 1.0, r)? });
    }
    let sigma = |name: &str, default: Vec3, r: &mut dyn Resolver| -> Res<TexValue> {
        Ok(match spectrum(p, name, 0.0, r)? {
            v if p.named(name).is_some() => v,
            _ => TexValue::Const(default),
        })
    };
    Ok(Coefficients::Sigma { sigma_a: sigma("sigma_a", defaults.0, r)?, sigma_s: sigma("sigma_s", defaults.1, r)? })
}

/// The boundary's lobes at a hit: pbrt's glass of index η.
pub fn lobes<const N: usize>(
    s: &Subsurface,
    convention: super::Convention,
    i: &Inputs<impl Fn() -> TexCtx>,
    out: &mut Lobes<N>,
) {
    let eta = dielectric::Eta { mean: TexValue::Const(Vec3::splat(s.eta)), dispersion: None };
    dielectric::lobes(eta, [s.kr, s.kt], &s.roughness, s.remap, convention, i, out)
}

/// The BSSRDF's profile at a hit: σa and σs there (scaled, clamped at 0), in the path's
/// lanes.
pub fn profile(s: &Subsurface, i: &Inputs<impl Fn() -> TexCtx>) -> Profile {
    let (sigma_a, sigma_s) = match s.coefficients {
        Coefficients::Sigma { sigma_a, sigma_s } => {
            ((s.scale * i.unbounded(sigma_a)).max(Vec3::ZERO), (s.scale * i.unbounded(sigma_s)).max(Vec3::ZERO))
        }
        Coefficients::Diffuse { reflectance, mfp } => {
            let mfree = (s.scale * i.unbounded(mfp)).max(Vec3::ZERO);
            s.table().from_diffuse(i.albedo(reflectance), mfree)
        }
    };
    Profile::new(s.table().clone(), sigma_a, sigma_s)
}

/// The interior as a homogeneous medium (`--fix subsurface-walk`), where the
/// coefficients are constants (textured ones keep the BSSRDF). A reflectance and mean
/// free path are turned into σa and σs in RGB, by the same inversion.
pub fn walk_medium(s: &Subsurface, space: Option<ColorSpaceName>) -> Option<Medium> {
    let (sigma_a, sigma_s) = match s.coefficients {
        Coefficients::Sigma { sigma_a: TexValue::Const(a), sigma_s: TexValue::Const(sc) } => (a, sc),
        Coefficients::Diffuse { reflectance: TexValue::Const(r), mfp: TexValue::Const(m) } => {
            s.table().from_diffuse(r.clamp(Vec3::ZERO, Vec3::ONE), m.max(Vec3::ZERO))
        }
        _ => return None,
    };
    let (sigma_a, sigma_s) = ((s.scale * sigma_a).max(Vec3::ZERO), (s.scale * sigma_s).max(Vec3::ZERO));
    Some(Medium::Homogeneous(Homogeneous {
        sigma_a: Sigma::new(sigma_a, space),
        sigma_s: Sigma::new(sigma_s, space),
        phase: HenyeyGreenstein::new(s.g),
        le: Emitted::new(Vec3::ZERO, None),
    }))
}

pub fn mitsuba(s: &Subsurface, e: &mut dyn MaterialExport) -> MaterialOut {
    e.note("subsurface: exported as its dielectric boundary; the BSSRDF is not exported");
    dielectric::mitsuba([TexValue::Const(Vec3::splat(s.eta)), s.kr, s.kt], &s.roughness, e)
}
