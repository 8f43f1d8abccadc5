//! Media whose density varies over a grid: pbrt-v3's `heterogeneous` and pbrt-v4's
//! `uniformgrid`, sampled by delta tracking and attenuated by ratio tracking against
//! the grid's largest density (pbrt-v3's `GridDensityMedium`).
//!
//! ```text
//! MakeNamedMedium "smoke" "string type" "heterogeneous"        # v3 (v4: "uniformgrid")
//!     "integer nx" 2 "integer ny" 1 "integer nz" 1 "float density" [0.5 2]
//!     "point p0" [-1 0 -1] "point p1" [1 2 1] "rgb sigma_s" [1 1 1] "rgb sigma_a" [.1 .1 .1]
//! ```
//!
//! The density at a point is the trilinear interpolation of the samples, which sit at
//! voxel centres of the box `p0`–`p1` in the medium's space (the CTM at its statement);
//! outside the samples it falls to 0. σa and σs (with each version's defaults, `scale`,
//! and v3's presets) multiply it; `g` is the phase function's. `nx·ny·nz` must match
//! the number of densities. One σt is tracked: pbrt-v3 requires σa + σs equal in every
//! channel and otherwise uses the first (so do we, with a warning); for pbrt-v4 the
//! channels' mean stands in (noted as an approximation). v4's `temperature`, `Le` and
//! `Lescale` (emission) are read and listed as approximated.

use super::phase::HenyeyGreenstein;
use super::{Flight, MediumContext};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::sampling::Sampler;
use crate::scene::approx::Approx;
use crate::scene::values::{self, Res};
use glam::{DMat4, DVec3, Vec3};
use std::sync::Arc;

pub const NAMES: [&str; 2] = ["heterogeneous", "uniformgrid"];

/// Tracking steps one ray segment may take before it stops (Tr = 0, no scattering).
const MAX_STEPS: u32 = 1 << 20;

#[derive(Clone, Debug, PartialEq)]
pub struct GridMedium {
    pub sigma_a: Vec3,
    pub sigma_s: Vec3,
    /// The σt tracked (pbrt-v3's single value): σa + σs where it is the same in every
    /// channel.
    sigma_t: f32,
    pub phase: HenyeyGreenstein,
    /// World to the unit cube of the samples.
    world_to_grid: DMat4,
    n: [usize; 3],
    density: Arc<[f32]>,
    max_density: f32,
}

impl GridMedium {
    /// Reads a grid medium, placed by the CTM at its statement (`ctx.medium_to_world`).
    pub fn read(p: &ParamList, ctx: &mut MediumContext) -> Res<GridMedium> {
        let homogeneous = super::Homogeneous::coefficients(p, ctx, ctx.syntax == Syntax::V3)?;
        let density = densities(p, ctx.at)?;
        let n = [p.int("nx")?.unwrap_or(1), p.int("ny")?.unwrap_or(1), p.int("nz")?.unwrap_or(1)];
        let count = n.iter().map(|&k| k.max(0) as i64).product::<i64>();
        if n.iter().any(|&k| k < 1) || count != density.1.len() as i64 {
            let msg = format!(
                "the grid has {} density values; nx·ny·nz = {}·{}·{} = {} are needed",
                density.1.len(),
                n[0],
                n[1],
                n[2],
                count
            );
            return Err(Diagnostic::error(density.0, msg));
        }
        let p0 = p.point3("p0")?.unwrap_or([0.0; 3]);
        let p1 = p.point3("p1")?.unwrap_or([1.0; 3]);
        let (lo, hi) = (DVec3::from(p0.map(f64::from)), DVec3::from(p1.map(f64::from)));
        let extent = hi - lo;
        if extent.min_element() <= 0.0 {
            let at = values::span_of(p, "p1").or(values::span_of(p, "p0")).unwrap_or(density.0);
            return Err(Diagnostic::error(at, "\"p1\" must exceed \"p0\" in x, y and z"));
        }
        let grid_to_world = ctx.medium_to_world * DMat4::from_translation(lo) * DMat4::from_scale(extent);
        let st = homogeneous.sigma_a + homogeneous.sigma_s;
        let sigma_t = tracked_sigma_t(p, st, ctx, density.0);
        if ctx.syntax == Syntax::V4 {
            emission(p, ctx)?;
        }
        let max_density = density.1.iter().fold(0f32, |m, &d| m.max(d));
        if !(sigma_t * max_density).is_finite() {
            return Err(Diagnostic::error(
                density.0,
                "σt times the largest density is beyond the range of 32-bit floats",
            ));
        }
        Ok(GridMedium {
            sigma_a: homogeneous.sigma_a,
            sigma_s: homogeneous.sigma_s,
            sigma_t,
            phase: homogeneous.phase,
            world_to_grid: grid_to_world.inverse(),
            n: n.map(|k| k as usize),
            density: density.1.into(),
            max_density,
        })
    }

    /// The interpolated density at a point of the unit cube.
    fn density_at(&self, p: Vec3) -> f32 {
        let s = Vec3::new(p.x * self.n[0] as f32 - 0.5, p.y * self.n[1] as f32 - 0.5, p.z * self.n[2] as f32 - 0.5);
        let i = s.floor();
        let d = s - i;
        let (x, y, z) = (i.x as i64, i.y as i64, i.z as i64);
        let at = |dx: i64, dy: i64, dz: i64| self.sample(x + dx, y + dy, z + dz);
        let lerp = |t: f32, a: f32, b: f32| a + t * (b - a);
        let d00 = lerp(d.x, at(0, 0, 0), at(1, 0, 0));
        let d10 = lerp(d.x, at(0, 1, 0), at(1, 1, 0));
        let d01 = lerp(d.x, at(0, 0, 1), at(1, 0, 1));
        let d11 = lerp(d.x, at(0, 1, 1), at(1, 1, 1));
        lerp(d.z, lerp(d.y, d00, d10), lerp(d.y, d01, d11))
    }

    fn sample(&self, x: i64, y: i64, z: i64) -> f32 {
        let [nx, ny, nz] = self.n.map(|k| k as i64);
        if x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz {
            return 0.0;
        }
        self.density[((z * ny + y) * nx + x) as usize]
    }

    /// The segment of the world ray (origin, unit direction, length) inside the grid's
    /// box: the ray in grid space and its [t0, t1] in world units.
    fn clip(&self, o: Vec3, d: Vec3, len: f32) -> Option<(Vec3, Vec3, f32, f32)> {
        let og = self.world_to_grid.transform_point3(o.as_dvec3()).as_vec3();
        let dg = self.world_to_grid.transform_vector3(d.as_dvec3()).as_vec3();
        let (mut t0, mut t1) = (0f32, len);
        for a in 0..3 {
            let inv = 1.0 / dg[a];
            let (mut near, mut far) = ((0.0 - og[a]) * inv, (1.0 - og[a]) * inv);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            // NaN (a zero direction component on a slab's plane) keeps the old bound.
            t0 = if near > t0 { near } else { t0 };
            t1 = if far < t1 { far } else { t1 };
            if t0 > t1 {
                return None;
            }
        }
        Some((og, dg, t0, t1))
    }

    /// Delta tracking along a segment of parameter length `t_max` of a ray `o + t·d`
    /// (`|d|` = `dlen`): where it scatters, weight 1/σt(x) and σs(x).
    pub fn sample_flight(&self, o: Vec3, d: Vec3, t_max: f32, sampler: &mut impl Sampler) -> Flight {
        let dlen = d.length();
        let Some((og, dg, t0, t1)) = self.clip(o, d / dlen, t_max * dlen) else {
            return Flight::Through { weight: Vec3::ONE };
        };
        let majorant = self.sigma_t * self.max_density;
        if majorant <= 0.0 {
            return Flight::Through { weight: Vec3::ONE };
        }
        let mut t = t0;
        for _ in 0..MAX_STEPS {
            t -= (1.0 - sampler.get1d()).max(f32::MIN_POSITIVE).ln() / majorant;
            if t >= t1 {
                return Flight::Through { weight: Vec3::ONE };
            }
            let density = self.density_at(og + dg * t);
            if density / self.max_density > sampler.get1d() {
                let sigma_t = self.sigma_t * density;
                return Flight::Scatter {
                    t: t / dlen,
                    weight: Vec3::splat(1.0 / sigma_t),
                    sigma_s: self.sigma_s * density,
                };
            }
        }
        Flight::Through { weight: Vec3::ZERO }
    }

    /// Ratio tracking: an unbiased estimate of the transmittance over `dist` world
    /// units from `o` along unit direction `d`, with pbrt-v3's Russian roulette below 0.1.
    pub fn transmittance(&self, o: Vec3, d: Vec3, dist: f32, sampler: &mut impl Sampler) -> Vec3 {
        let Some((og, dg, t0, t1)) = self.clip(o, d, dist) else { return Vec3::ONE };
        let majorant = self.sigma_t * self.max_density;
        if majorant <= 0.0 {
            return Vec3::ONE;
        }
        let (mut tr, mut t) = (1f32, t0);
        for _ in 0..MAX_STEPS {
            t -= (1.0 - sampler.get1d()).max(f32::MIN_POSITIVE).ln() / majorant;
            if t >= t1 {
                return Vec3::splat(tr);
            }
            tr *= 1.0 - (self.density_at(og + dg * t) / self.max_density).max(0.0);
            if tr < 0.1 {
                let q = (1.0 - tr).max(0.05);
                if sampler.get1d() < q {
                    return Vec3::ZERO;
                }
                tr /= 1.0 - q;
            }
        }
        Vec3::ZERO
    }
}

/// The single σt tracked. pbrt-v3 takes the first channel's (with an error message
/// where the channels differ, and goes on); for pbrt-v4, which tracks each wavelength,
/// the channels' mean stands in (noted as an approximation).
fn tracked_sigma_t(p: &ParamList, st: Vec3, ctx: &mut MediumContext, fallback: crate::parser::source::Span) -> f32 {
    if st.max_element() - st.min_element() <= 1e-6 * st.max_element() {
        return st.x;
    }
    let at = values::span_of(p, "sigma_a").or(values::span_of(p, "sigma_s")).unwrap_or(fallback);
    match ctx.syntax {
        Syntax::V3 => {
            let msg = "a grid medium needs the same σa + σs in every channel; as pbrt-v3, the first channel's is used";
            ctx.warnings.push(Diagnostic::warning(at, msg));
            st.x
        }
        Syntax::V4 => {
            (ctx.approximate)(
                at,
                "a grid medium's σa + σs that differs between channels".into(),
                Approx::ColoredGridMedium,
            );
            st.element_sum() / 3.0
        }
    }
}

/// The `density` values and where they are written.
fn densities(p: &ParamList, at: crate::parser::source::Span) -> Res<(crate::parser::source::Span, Vec<f32>)> {
    match p.array("density", ParamType::Float)? {
        Some(param) => {
            param.mark_used();
            if let Some(v) = param.floats().iter().find(|v| !v.is_finite() || **v < 0.0) {
                return Err(Diagnostic::error(
                    param.value_span,
                    format!("densities must be finite and at least 0, not {v}"),
                ));
            }
            Ok((param.value_span, param.floats().to_vec()))
        }
        None => Err(Diagnostic::error(at, "a grid medium needs \"float density\" values")),
    }
}

/// v4's emission parameters: read, and listed as approximated where they would emit.
fn emission(p: &ParamList, ctx: &mut MediumContext) -> Res<()> {
    let temperature = p.array("temperature", ParamType::Float)?.map(|t| t.mark_used()).is_some();
    let _ = p.array("Lescale", ParamType::Float)?.map(|t| t.mark_used());
    values::no_effect(p, &["temperaturecutoff", "temperatureoffset", "temperaturescale"]);
    super::note_emission(p, ctx, "medium emission", true, temperature)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// A 3×1×1 grid of densities 0, 1, 4 over the unit cube, σt = 2.
    fn ramp() -> GridMedium {
        GridMedium {
            sigma_a: Vec3::splat(0.5),
            sigma_s: Vec3::splat(1.5),
            sigma_t: 2.0,
            phase: HenyeyGreenstein::new(0.0),
            world_to_grid: DMat4::IDENTITY,
            n: [3, 1, 1],
            density: vec![0.0, 1.0, 4.0].into(),
            max_density: 4.0,
        }
    }

    /// ∫ σt·density along x at y = z = 0.5 by the midpoint rule.
    fn optical_depth(g: &GridMedium) -> f64 {
        let n = 100_000;
        (0..n).map(|i| g.density_at(Vec3::new((i as f32 + 0.5) / n as f32, 0.5, 0.5)) as f64).sum::<f64>()
            * g.sigma_t as f64
            / n as f64
    }

    #[test]
    fn interpolates_between_voxel_centres_and_falls_to_zero_outside() {
        let g = ramp();
        assert_eq!(g.density_at(Vec3::new(0.5, 0.5, 0.5)), 1.0);
        assert!((g.density_at(Vec3::new(2.0 / 3.0, 0.5, 0.5)) - 2.5).abs() < 1e-5);
        // Past the last sample (x = 5/6) the density falls toward the zero beyond.
        assert!((g.density_at(Vec3::new(1.0, 0.5, 0.5)) - 2.0).abs() < 1e-5);
        assert!((g.density_at(Vec3::new(0.5, 1.0, 0.5)) - 0.5).abs() < 1e-5);
    }

    /// Delta tracking passes with probability exp(−τ) and ratio tracking averages to
    /// it, along a ray that starts outside the box and ends inside it; scattering
    /// points follow σt·density (their mean depth matches the integral's).
    #[test]
    fn tracking_is_unbiased_against_the_optical_depth() {
        let g = ramp();
        let want = (-optical_depth(&g)).exp();
        let (o, d) = (Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        let mut rng = Rng::new(7);
        let n = 200_000;
        let (mut passed, mut ratio) = (0.0f64, 0.0f64);
        for _ in 0..n {
            match g.sample_flight(o, d * 2.0, 1.0, &mut rng) {
                Flight::Through { weight } => passed += weight.x as f64,
                Flight::Scatter { t, weight, sigma_s } => {
                    let x = o.x + 2.0 * t;
                    assert!((0.0..=1.0).contains(&x), "scattered outside the box at x = {x}");
                    let density = g.density_at(Vec3::new(x, 0.5, 0.5));
                    assert!((weight.x * 2.0 * density - 1.0).abs() < 1e-4 && (sigma_s.x - 1.5 * density).abs() < 1e-4);
                }
            }
            ratio += g.transmittance(o, d, 2.0, &mut rng).x as f64;
        }
        let (passed, ratio) = (passed / n as f64, ratio / n as f64);
        assert!((passed - want).abs() < 4e-3, "delta tracking passes {passed}, want {want}");
        assert!((ratio - want).abs() < 4e-3, "ratio tracking {ratio}, want {want}");
    }
}
