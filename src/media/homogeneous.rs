//! A medium of the same density everywhere.
//!
//! ```text
//! MakeNamedMedium "fog" "string type" "homogeneous"
//!     "rgb sigma_a" [0.05 0.05 0.05] "rgb sigma_s" [0.5 0.5 0.5] "float scale" 2 "float g" 0.3
//! MakeNamedMedium "milk" "string type" "homogeneous" "string preset" "Wholemilk"
//! ```
//!
//! | parameter | pbrt-v3 | pbrt-v4 |
//! |---|---|---|
//! | `sigma_a`, `sigma_s` (per unit length) | default whole milk's (0.0011, 0.0024, 0.014), (2.55, 3.21, 3.77); given values replace a preset's | default 1; a found preset wins over them |
//! | `preset` | [`super::presets`]; unknown: a warning, the defaults | the same |
//! | `scale` | multiplies σa and σs | the same |
//! | `g` | Henyey–Greenstein asymmetry | the same (clamped to ±0.99) |
//! | `Le`, `Lescale` | — | emission σa·`Le`·`Lescale` per unit length (`Le` an illuminant, as lights') |

use super::lanes::{Emitted, Lanes, Sigma};
use super::phase::HenyeyGreenstein;
use super::{MediumContext, presets};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::values::{self, Range, Res};
use glam::Vec3;

pub const NAME: &str = "homogeneous";

/// σa and σs (per unit of world length), the phase function and the emission.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    pub sigma_a: Sigma,
    pub sigma_s: Sigma,
    pub phase: HenyeyGreenstein,
    /// Le times `Lescale` (pbrt-v4); the medium emits σa·Le per unit length.
    pub le: Emitted,
}

/// A homogeneous medium's σa, σs and Le at the wavelengths (or in the channels) a
/// path carries: what transmittance, emission and free flight are computed from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    pub sigma_a: Vec3,
    pub sigma_s: Vec3,
    pub le: Vec3,
}

/// What free-flight sampling along a segment found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Flight {
    /// A scattering point at ray parameter `t`; `weight` is Tr/pdf (times `sigma_s`,
    /// the scattering coefficient there, for a path that scatters; photons deposit
    /// with it as it is); `sigma_t` the attenuation there (bidirectional weights read
    /// it as the point's density).
    Scatter { t: f32, weight: Vec3, sigma_s: Vec3, sigma_t: Vec3 },
    /// No interaction before the segment's end: Tr/pdf of reaching it.
    Through { weight: Vec3 },
}

impl Homogeneous {
    /// Reads the parameters by the rules of the file's version.
    pub fn read(p: &ParamList, ctx: &mut MediumContext) -> Res<Homogeneous> {
        let m = Homogeneous::coefficients(p, ctx, true)?;
        let le = if ctx.syntax == Syntax::V4 { emission(p, ctx, m.sigma_a.rgb)? } else { Vec3::ZERO };
        Ok(Homogeneous { le: Emitted::new(le, ctx.spectral), ..m })
    }

    /// The coefficients at the lanes' wavelengths.
    #[inline]
    pub fn at(&self, lanes: Lanes) -> Coefficients {
        Coefficients { sigma_a: self.sigma_a.at(lanes), sigma_s: self.sigma_s.at(lanes), le: self.le.at(lanes) }
    }

    /// σa, σs (scaled) and g as every medium type reads them; `presets`: whether
    /// `preset` is read (pbrt-v4's grids ignore it).
    pub fn coefficients(p: &ParamList, ctx: &mut MediumContext, presets: bool) -> Res<Homogeneous> {
        let (mut sigma_a, mut sigma_s) = match ctx.syntax {
            Syntax::V3 => (Vec3::new(0.0011, 0.0024, 0.014), Vec3::new(2.55, 3.21, 3.77)),
            Syntax::V4 => (Vec3::ONE, Vec3::ONE),
        };
        let preset = if presets { preset(p, ctx)? } else { None };
        if let Some((a, s)) = preset {
            (sigma_a, sigma_s) = (a, s);
        }
        // pbrt-v3 lets given coefficients replace a preset's; pbrt-v4 keeps the preset.
        if preset.is_none() || ctx.syntax == Syntax::V3 {
            sigma_a = values::rgb(p, "sigma_a", &ctx.spectra, Range::NonNegative)?.unwrap_or(sigma_a);
            sigma_s = values::rgb(p, "sigma_s", &ctx.spectra, Range::NonNegative)?.unwrap_or(sigma_s);
        }
        let scale = values::float(p, "scale", 1.0, Range::NonNegative)?;
        let g = super::asymmetry(p)?;
        let (sigma_a, sigma_s) = (sigma_a * scale, sigma_s * scale);
        // DEVIATION(pbrt): robustness. pbrt lets σ·scale overflow to Inf, and then
        // distances of 0 times Inf make NaN pixels.
        if !(sigma_a + sigma_s).is_finite() {
            let at = values::span_of(p, "scale").or(values::span_of(p, "sigma_s")).unwrap_or_default();
            return Err(Diagnostic::error(at, "σa + σs times \"scale\" is beyond the range of 32-bit floats"));
        }
        let (sigma_a, sigma_s) = (Sigma::new(sigma_a, ctx.spectral), Sigma::new(sigma_s, ctx.spectral));
        Ok(Homogeneous { sigma_a, sigma_s, phase: HenyeyGreenstein::new(g), le: Emitted::NONE })
    }
}

impl Coefficients {
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_a + self.sigma_s
    }

    /// Transmittance across `dist` units of world length (an infinite one too: 0
    /// where the channel attenuates at all, 1 where it does not).
    pub fn transmittance(&self, dist: f32) -> Vec3 {
        let st = self.sigma_t();
        let tr = |s: f32| if s == 0.0 { 1.0 } else { (-s * dist).exp() };
        Vec3::new(tr(st.x), tr(st.y), tr(st.z))
    }

    /// The emission reaching the start of a segment of `dist` world units (an infinite
    /// one too): ∫₀^dist exp(−σt·t)·σa·Le dt per channel.
    pub fn emission(&self, dist: f32) -> Vec3 {
        let (st, e) = (self.sigma_t(), self.sigma_a * self.le);
        let one = |s: f32, e: f32| if e == 0.0 { 0.0 } else { e * -(-s * dist).exp_m1() / s };
        Vec3::new(one(st.x, e.x), one(st.y, e.y), one(st.z, e.z))
    }

    /// Free-flight sampling over a segment of `len` world units (ray parameter `t_max`,
    /// direction length `dlen`): a channel chosen by `u_channel`, a distance by `u`,
    /// weighted by the density averaged over channels (pbrt's single-channel scheme,
    /// unbiased for colored media).
    pub fn sample(&self, t_max: f32, dlen: f32, u_channel: f32, u: f32) -> Flight {
        let st = self.sigma_t();
        let c = ((u_channel * 3.0) as usize).min(2);
        let dist = -(1.0 - u).max(f32::MIN_POSITIVE).ln() / st[c];
        let t = dist / dlen;
        if t < t_max {
            let tr = self.transmittance(dist);
            let pdf = (st * tr).element_sum() / 3.0;
            // A zero density can only come from a point the other channels cannot reach.
            let weight = if pdf > 0.0 { tr / pdf } else { Vec3::ZERO };
            return Flight::Scatter { t, weight, sigma_s: self.sigma_s, sigma_t: st };
        }
        let tr = self.transmittance(t_max * dlen);
        let pdf = tr.element_sum() / 3.0;
        Flight::Through { weight: if pdf > 0.0 { tr / pdf } else { Vec3::ZERO } }
    }
}

/// The preset's (σa, σs), `None` when none is given or it is unknown (a warning, as in
/// pbrt).
fn preset(p: &ParamList, ctx: &mut MediumContext) -> Res<Option<(Vec3, Vec3)>> {
    let Some(name) = p.string("preset")? else { return Ok(None) };
    let found = presets::lookup(&name);
    if found.is_none() {
        let at = values::span_of(p, "preset").unwrap_or_default();
        let known: Vec<&str> = presets::names().collect();
        let msg = format!("unknown medium preset \"{name}\"; the defaults are used (presets: {})", known.join(", "));
        ctx.warnings.push(Diagnostic::warning(at, msg));
    }
    Ok(found)
}

/// pbrt-v4's `Le` times `Lescale`, where σa times it stays finite.
fn emission(p: &ParamList, ctx: &mut MediumContext, sigma_a: Vec3) -> Res<Vec3> {
    let scale = values::float(p, "Lescale", 1.0, Range::NonNegative)?;
    let le = super::read_le(p, ctx)?.unwrap_or(Vec3::ZERO) * scale;
    // DEVIATION(pbrt): robustness, as for σ: an overflowing emission makes NaN pixels.
    if !(le * sigma_a).is_finite() {
        let at = values::span_of(p, "Lescale").or(values::span_of(p, "Le")).unwrap_or(ctx.at);
        return Err(Diagnostic::error(at, "σa times \"Le\" and \"Lescale\" is beyond the range of 32-bit floats"));
    }
    Ok(le)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fog() -> Coefficients {
        Coefficients { sigma_a: Vec3::new(0.1, 0.2, 0.3), sigma_s: Vec3::new(0.5, 0.4, 0.9), le: Vec3::ZERO }
    }

    #[test]
    fn transmittance_to_infinity_is_one_where_a_channel_does_not_attenuate() {
        let m = Coefficients { sigma_a: Vec3::new(0.0, 1.0, 0.0), sigma_s: Vec3::ZERO, le: Vec3::ZERO };
        assert_eq!(m.transmittance(f32::INFINITY), Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(m.sample(f32::INFINITY, 1.0, 0.1, 0.5), Flight::Through { weight: Vec3::new(1.5, 0.0, 1.5) });
    }

    /// E[weight · σs] over scatter events plus E[weight] over passes reproduce the two
    /// terms of the segment's transport: ∫ Tr σs dt and Tr(L), per channel.
    #[test]
    fn free_flight_weights_are_unbiased_per_channel() {
        let (m, len) = (fog(), 3.0);
        let n = 200_000;
        let (mut scattered, mut through) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            let uc = ((k * 7) % 3) as f32 / 3.0 + 0.1;
            match m.sample(len / 2.0, 2.0, uc, u) {
                Flight::Scatter { t, weight, .. } => {
                    assert!(t < len / 2.0);
                    scattered += (weight * m.sigma_s).as_dvec3();
                }
                Flight::Through { weight } => through += weight.as_dvec3(),
            }
        }
        let st = m.sigma_t();
        for c in 0..3 {
            let want_s = m.sigma_s[c] / st[c] * (1.0 - (-st[c] * len).exp());
            let want_t = (-st[c] * len).exp();
            assert!((scattered[c] / n as f64 - want_s as f64).abs() < 2e-3, "channel {c} scatter");
            assert!((through[c] / n as f64 - want_t as f64).abs() < 2e-3, "channel {c} through");
        }
    }
}
