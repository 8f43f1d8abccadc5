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
use super::shared::Loaded;
use crate::approx::Approx;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::Vec3;

pub const NAME: &str = "fourier";

/// Tables already read (lobes are `Copy` and refer to them).
static TABLES: Loaded<FourierTable> = Loaded::new();

pub fn read(_ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    // A missing parameter is a mistake in the file, as for `imagemap` and `ptex`; a
    // file named but unreadable is what pbrt-v3 renders black.
    let name = p.string("bsdffile")?.ok_or_else(|| {
        p.wrong_type()
            .unwrap_or_else(|| crate::parser::error::Diagnostic::error(at, "fourier needs \"string bsdffile\""))
    })?;
    let name_at = crate::values::span_of(p, "bsdffile").unwrap_or(at);
    let table = {
        let spectra = r.spectra();
        let read = |b: &[u8]| FourierTable::read(b).map_err(|e| e.to_string());
        spectra.files.read(&spectra.base_dir.join(&name)).and_then(|b| TABLES.get(&b, read))
    };
    match table {
        Ok(table) => Ok(MaterialKind::Fourier { table }),
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
