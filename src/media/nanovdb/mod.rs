//! pbrt-v4's `nanovdb` medium: density (and optionally temperature) read from a
//! NanoVDB file ([`file`]), tracked against a 64³ majorant grid.
//!
//! ```text
//! MakeNamedMedium "smoke" "string type" "nanovdb" "string filename" "smoke.nvdb"
//!     "rgb sigma_a" [1 1 1] "rgb sigma_s" [4 4 4] "float scale" 2 "float g" 0.3
//!     "string gridname" "density"                  # the default
//!     "string temperaturename" "temperature"       # emits where that grid exists:
//!     "float Lescale" 0.01 "float temperatureoffset" 0 "float temperaturescale" 1
//! ```
//!
//! As pbrt-v4: the density is the trilinear interpolation of the grid's voxels
//! (NanoVDB's first-order sampler, voxel centres at integer index points) at the point
//! mapped by the grid's own transform, times σa and σs (each 1 by default) and
//! `scale`. The medium fills the union of the grids' world boxes, in the medium's space
//! (the CTM at the statement). Where the file holds a grid named `temperaturename`,
//! the medium emits σa·`Lescale`·B(T) with B the peak-normalised blackbody at T =
//! (value − `temperatureoffset`) · `temperaturescale` (`temperaturecutoff` is the old
//! name of the offset), none at or below 100 K, unnormalised as in [`super::grid`].
//! Grids must hold floats and be fog volumes (or unclassified); uncompressed and ZIP
//! grids are read, BLOSC ones are refused with a located error.

pub mod file;

use super::MediumContext;
use super::grid::Blackbody;
use super::lanes::{Lanes, Sigma, sigma_t_bound};
use super::tracking::{Field, Props, Tracked};
use crate::limits::FileBytes;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::values::{self, Range, Res};
use file::FloatGrid;
use glam::{DMat4, DVec3, Vec3};
use std::sync::Arc;

pub const NAME: &str = "nanovdb";

/// pbrt-v4's majorant grid for NanoVDB media: 64 voxels along each axis.
const MAJORANT_RES: usize = 64;

/// The density grid, its coefficients and its emission.
#[derive(Debug)]
pub struct NanoVdb {
    sigma_a: Sigma,
    sigma_s: Sigma,
    density: FloatGrid,
    emission: Option<Temperature>,
    /// The medium's box in its own space (the union of the grids' world boxes).
    lo: DVec3,
    extent: DVec3,
}

/// The temperature grid and its scaling.
#[derive(Debug)]
struct Temperature {
    grid: FloatGrid,
    offset: f32,
    scale: f32,
    le_scale: f32,
    table: Blackbody,
}

impl NanoVdb {
    /// A point of the box's unit cube in the medium's space.
    fn point(&self, u: Vec3) -> Vec3 {
        (self.lo + u.as_dvec3() * self.extent).as_vec3()
    }
}

impl Temperature {
    fn le(&self, p: Vec3, lanes: Lanes) -> Vec3 {
        let kelvin = (self.grid.sample(self.grid.to_index(p)) - self.offset) * self.scale;
        let b = match lanes {
            Some(l) => self.table.at_lanes(kelvin, l),
            None => self.table.at(kelvin),
        };
        b * self.le_scale
    }
}

impl Field for NanoVdb {
    fn at(&self, u: Vec3, emission: bool, lanes: Lanes) -> Props {
        let p = self.point(u);
        let d = self.density.sample(self.density.to_index(p));
        let (sigma_a, sigma_s) = (self.sigma_a.at(lanes), self.sigma_s.at(lanes));
        let emitted = match (&self.emission, emission) {
            (Some(t), true) => sigma_a * d * t.le(p, lanes),
            _ => Vec3::ZERO,
        };
        Props { sigma_t: (sigma_a + sigma_s) * d, sigma_s: sigma_s * d, emitted }
    }

    /// pbrt-v4's bound: the largest voxel value whose interpolation reaches the box,
    /// times the largest σt.
    // DEVIATION(pbrt): robustness. pbrt-v4 maps two corners of the box to index space,
    // which bounds too little under a rotating or mirroring grid transform; all eight
    // are mapped here (the same voxels where pbrt's is right).
    fn majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
        let (mut a, mut b) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for k in 0..8 {
            let u = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let i = self.density.to_index(self.point(u));
            (a, b) = (a.min(i), b.max(i));
        }
        let first = a.floor().as_ivec3().to_array();
        let last = (b.floor() + 1.0).as_ivec3().to_array();
        self.density.max_over(first, last).max(0.0) * sigma_t_bound(&self.sigma_a, &self.sigma_s)
    }

    fn emissive(&self) -> bool {
        self.emission.is_some()
    }

    fn emission_bound(&self) -> f32 {
        let Some(t) = &self.emission else { return 0.0 };
        self.sigma_a.rgb.max_element() * self.density.max_value().max(0.0) * t.table.max() * t.le_scale
    }

    fn majorant_res(&self) -> usize {
        MAJORANT_RES
    }
}

/// Reads a `nanovdb` medium, placed by the CTM at its statement.
pub fn read(p: &ParamList, ctx: &mut MediumContext) -> Res<Tracked> {
    let coefficients = super::Homogeneous::coefficients(p, ctx, false)?;
    let (bytes, at, shown) = load(p, ctx)?;
    let limit = ctx.spectra.files.limits.file_bytes;
    let grid_name = p.string("gridname")?.unwrap_or_else(|| "density".into());
    let grid = |name: &str| {
        file::read_grid(&bytes, name, limit).map_err(|e| Diagnostic::error(at, format!("\"{shown}\": {e}")))
    };
    let density = grid(&grid_name)?.ok_or_else(|| {
        Diagnostic::error(at, format!("\"{shown}\" has no grid named \"{grid_name}\" (\"string gridname\")"))
    })?;
    // DEVIATION(pbrt): robustness. pbrt-v4 tracks whatever the grid holds: a NaN
    // density makes NaN pixels and a negative one a negative majorant.
    if density.values().any(|v| !(v >= 0.0 && v.is_finite())) {
        let msg = format!("\"{shown}\": grid \"{grid_name}\" holds a density that is negative or not finite");
        return Err(Diagnostic::error(at, msg));
    }
    let temperature_name = p.string("temperaturename")?.unwrap_or_else(|| "temperature".into());
    let emission = match grid(&temperature_name)? {
        Some(kelvin) => temperature(p, ctx, kelvin)?,
        None => None,
    };
    let (mut lo, mut hi) = (density.world_min, density.world_max);
    if let Some(t) = &emission {
        (lo, hi) = (lo.min(t.grid.world_min), hi.max(t.grid.world_max));
    }
    if (hi - lo).min_element() <= 0.0 {
        return Err(Diagnostic::error(at, "the grid holds no active voxels (its world box is empty)"));
    }
    let medium = NanoVdb {
        sigma_a: coefficients.sigma_a,
        sigma_s: coefficients.sigma_s,
        density,
        emission,
        lo,
        extent: hi - lo,
    };
    let box_to_world = ctx.medium_to_world * DMat4::from_translation(lo) * DMat4::from_scale(hi - lo);
    super::finite(Tracked::new(box_to_world, coefficients.phase, Arc::new(medium)), at)
}

/// The file's bytes, where its name is written, and the name.
fn load(p: &ParamList, ctx: &MediumContext) -> Res<(FileBytes, crate::parser::source::Span, String)> {
    let name = p.string("filename")?.unwrap_or_default();
    let at = values::span_of(p, "filename").unwrap_or(ctx.at);
    if name.is_empty() {
        return Err(Diagnostic::error(ctx.at, "a \"nanovdb\" medium needs a \"string filename\""));
    }
    let path = ctx.spectra.base_dir.join(&name);
    let bytes = ctx.spectra.files.read(&path).map_err(|why| Diagnostic::error(at, why))?;
    Ok((bytes, at, name))
}

/// The emission of a temperature grid, with pbrt-v4's parameters (none where
/// `Lescale` is not positive, as pbrt-v4's `IsEmissive`).
fn temperature(p: &ParamList, ctx: &MediumContext, grid: FloatGrid) -> Res<Option<Temperature>> {
    if grid.values().any(|v| !v.is_finite()) {
        let at = values::span_of(p, "filename").unwrap_or(ctx.at);
        return Err(Diagnostic::error(at, "the temperature grid holds a value that is not finite"));
    }
    let le_scale = values::float(p, "Lescale", 1.0, Range::Any)?;
    let (offset, scale) = super::grid::temperature_mapping(p)?;
    let hottest = ((grid.max_value() - offset) * scale).abs();
    let table = Blackbody::up_to(hottest, ctx.raw_emission);
    Ok((le_scale > 0.0).then_some(Temperature { grid, offset, scale, le_scale, table }))
}
