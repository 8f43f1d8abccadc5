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
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::scene::values::Res;
use crate::textures::TexCtx;
use glam::Vec3;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

pub const NAME: &str = "measured";

/// Tables already read, by their bytes' hash (lobes are `Copy` and refer to them).
fn loaded() -> &'static Mutex<HashMap<u64, &'static MeasuredTable>> {
    static TABLES: OnceLock<Mutex<HashMap<u64, &'static MeasuredTable>>> = OnceLock::new();
    TABLES.get_or_init(Mutex::default)
}

/// The table in `bytes`, shared with every other material that read the same bytes.
fn table(bytes: &[u8]) -> Result<&'static MeasuredTable, String> {
    let key = xxhash_rust::xxh3::xxh3_64(bytes);
    if let Some(t) = loaded().lock().ok().and_then(|m| m.get(&key).copied()) {
        return Ok(t);
    }
    let t: &'static MeasuredTable = Box::leak(Box::new(MeasuredTable::read(bytes).map_err(|e| e.to_string())?));
    if let Ok(mut m) = loaded().lock() {
        m.insert(key, t);
    }
    Ok(t)
}

pub fn read(_ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let name = p
        .string("filename")?
        .ok_or_else(|| p.wrong_type().unwrap_or_else(|| Diagnostic::error(at, "measured needs \"string filename\"")))?;
    let name_at = crate::scene::values::span_of(p, "filename").unwrap_or(at);
    let spectra = r.spectra();
    let path = spectra.base_dir.join(&name);
    match spectra.files.read(&path).and_then(|b| table(&b)) {
        Ok(t) => Ok(MaterialKind::Measured { table: Table(t) }),
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
