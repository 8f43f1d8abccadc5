//! `Material "measured"` (pbrt-v4): a BRDF measured by the RGL gonio-photometer, read
//! from its tensor file as pbrt-v4's `MeasuredMaterial` (the tables and their
//! evaluation: [`super::measuredbsdf`]).
//!
//! ```text
//! Material "measured" "string filename" "bsdfs/rosegold.bsdf"
//! ```
//! Materials naming files with the same bytes share one table. A missing parameter, or
//! a file that cannot be read or is malformed, is an error at the parameter, as pbrt-v4
//! stops there too.

use super::MaterialKind;
use super::inputs::Inputs;
use super::lobes::Lobe;
use super::measuredbsdf::{Lanes, MeasuredTable, Table};
use super::params::Resolver;
use super::shared::Loaded;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::textures::TexCtx;
use crate::values::Res;
use glam::Vec3;

pub const NAME: &str = "measured";

/// Tables already read (lobes are `Copy` and refer to them).
static TABLES: Loaded<MeasuredTable> = Loaded::new();

pub fn read(_ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let name = p
        .string("filename")?
        .ok_or_else(|| p.wrong_type().unwrap_or_else(|| Diagnostic::error(at, "measured needs \"string filename\"")))?;
    let name_at = crate::values::span_of(p, "filename").unwrap_or(at);
    let spectra = r.spectra();
    let path = spectra.base_dir.join(&name);
    let read = |b: &[u8]| MeasuredTable::read(b).map_err(|e| e.to_string());
    match spectra.files.read(&path).and_then(|b| TABLES.get(&b, read)) {
        Ok(table) => Ok(MaterialKind::Measured { table }),
        Err(why) => Err(Diagnostic::error(name_at, format!("measured BSDF \"{name}\": {why}"))),
    }
}

/// The lobe at a hit: the table in the path's lanes.
pub fn lobe(table: Table, i: &Inputs<impl Fn() -> TexCtx>) -> Lobe {
    let lanes = i.spectral.map_or(Lanes::Rgb, |s| Lanes::Wavelengths(s.lambda));
    Lobe::Measured { table, lanes, scale: Vec3::ONE }
}

pub fn mitsuba(e: &mut dyn MaterialExport) -> MaterialOut {
    e.note("measured: the tabulated BSDF is not exported; exported as a grey diffuse");
    MaterialOut::Diffuse { reflectance: [0.5, 0.5, 0.5] }
}
