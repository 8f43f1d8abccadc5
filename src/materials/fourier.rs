//! `Material "fourier"` (v3): a BSDF tabulated in a `SCATFUN` file, as pbrt-v3's
//! `FourierMaterial` (the table and its evaluation: [`super::fourierbsdf`]).
//!
//! ```text
//! Material "fourier" "string bsdffile" "bsdfs/coated-copper.bsdf"
//! ```
//! Materials naming one file share its table. A file that cannot be read is black, as
//! in pbrt-v3 (noted).

use super::MaterialKind;
use super::fourierbsdf::{FourierTable, Table};
use super::lobes::Lobe;
use super::params::{Resolver, TexValue};
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::scene::approx::Approx;
use crate::scene::values::Res;
use glam::Vec3;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

pub const NAME: &str = "fourier";

/// Tables already read, by their bytes' hash: materials naming one file share its
/// table for the process's life (lobes are `Copy` and refer to it), and a file that
/// changes on disk is read again.
fn loaded() -> &'static Mutex<HashMap<u64, &'static FourierTable>> {
    static TABLES: OnceLock<Mutex<HashMap<u64, &'static FourierTable>>> = OnceLock::new();
    TABLES.get_or_init(Mutex::default)
}

/// The table in `bytes`, shared with every other material that read the same bytes.
fn table(bytes: &[u8]) -> Result<&'static FourierTable, String> {
    let key = xxhash_rust::xxh3::xxh3_64(bytes);
    if let Some(t) = loaded().lock().ok().and_then(|m| m.get(&key).copied()) {
        return Ok(t);
    }
    let t: &'static FourierTable = Box::leak(Box::new(FourierTable::read(bytes).map_err(|e| e.to_string())?));
    if let Ok(mut m) = loaded().lock() {
        m.insert(key, t);
    }
    Ok(t)
}

pub fn read(_ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    // A missing parameter is a mistake in the file, as for `imagemap` and `ptex`; a
    // file named but unreadable is what pbrt-v3 renders black.
    let name = p.string("bsdffile")?.ok_or_else(|| {
        p.wrong_type()
            .unwrap_or_else(|| crate::parser::error::Diagnostic::error(at, "fourier needs \"string bsdffile\""))
    })?;
    let name_at = crate::scene::values::span_of(p, "bsdffile").unwrap_or(at);
    let table = {
        let spectra = r.spectra();
        spectra.files.read(&spectra.base_dir.join(&name)).and_then(|b| table(&b))
    };
    match table {
        Ok(table) => Ok(MaterialKind::Fourier { table: Table(table) }),
        Err(why) => {
            r.approximate(name_at, format!("fourier \"{name}\" ({why})"), Approx::UnreadableBsdfFile);
            Ok(MaterialKind::Diffuse { reflectance: TexValue::Const(Vec3::ZERO) })
        }
    }
}

pub fn lobe(table: Table) -> Lobe {
    Lobe::Fourier { table, scale: Vec3::ONE }
}

pub fn mitsuba(e: &mut dyn MaterialExport) -> MaterialOut {
    e.note("fourier: the tabulated BSDF is not exported; exported as a grey diffuse");
    MaterialOut::Diffuse { reflectance: [0.5, 0.5, 0.5] }
}
