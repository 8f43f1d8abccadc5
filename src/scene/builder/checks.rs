//! Checks of a whole file that need its version settled: type names neither pbrt knows
//! ([`Family`]), a `LookAt` with its up vector along the view, and a file that never
//! reaches `WorldBegin`.
//!
//! ```text
//! Shape "sphre"      # v4: error, unknown shape type "sphre" (did you mean "sphere"?)
//!                    # v3: warning, left out as pbrt-v3 leaves it out
//! Camera "pinhole"   # an error for both: pbrt renders nothing without a camera
//! LookAt 0 0 0  0 0 1  0 0 1   # v4: error; v3: warning, the CTM left unchanged
//! ```

use super::{Builder, Res};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamType, Values};
use crate::parser::source::{FileId, Span};
use crate::parser::stmt::StmtKind;
use crate::scene::names::Family;

/// The wavelengths (nm) of the black spectrum pbrt-v3 uses for an SPD file it cannot
/// read: two zero samples span the visible range.
const BLACK_FROM: f32 = 360.0;
const BLACK_TO: f32 = 830.0;

/// Why a statement of a type we do not render is left out: a name pbrt knows and we
/// do not render, or an unknown one (with the nearest known name).
pub(super) fn why_left_out(family: Family, name: &str) -> String {
    if family.knows(name) {
        format!("this {} is not supported", family.noun())
    } else {
        format!("{}; left out, as pbrt-v3 leaves it out", family.unknown(name))
    }
}

impl Builder {
    /// A type name neither pbrt knows is an error where the file's pbrt stops at it, as
    /// soon as the version is known; until then it waits for [`Builder::settle_unknown_names`].
    pub(super) fn check_type_name(&mut self, kind: &StmtKind) -> Res<()> {
        let named_type;
        let (family, name, at) = match kind {
            StmtKind::Shape(e) => (Family::Shape, e.name.as_str(), e.name_span),
            StmtKind::Material(e) => (Family::Material, e.name.as_str(), e.name_span),
            StmtKind::MakeNamedMaterial(e) => match e.params.string("type") {
                Ok(Some(ty)) => {
                    named_type = ty;
                    let at = crate::values::span_of(&e.params, "type").unwrap_or(e.name_span);
                    (Family::Material, named_type.as_str(), at)
                }
                _ => return Ok(()),
            },
            StmtKind::Texture { class, .. } => (Family::Texture, class.name.as_str(), class.name_span),
            StmtKind::LightSource(e) => (Family::Light, e.name.as_str(), e.name_span),
            StmtKind::AreaLightSource(e) => (Family::AreaLight, e.name.as_str(), e.name_span),
            StmtKind::Camera(e) => (Family::Camera, e.name.as_str(), e.name_span),
            StmtKind::Sampler(e) => (Family::Sampler, e.name.as_str(), e.name_span),
            StmtKind::PixelFilter(e) => (Family::Filter, e.name.as_str(), e.name_span),
            StmtKind::Film(e) => (Family::Film, e.name.as_str(), e.name_span),
            StmtKind::Integrator(e) => (Family::Integrator, e.name.as_str(), e.name_span),
            _ => return Ok(()),
        };
        // Names are compared borrowed: only an unknown one is copied.
        if family.knows(name) {
            return Ok(());
        }
        match self.known_syntax() {
            Some(syntax) if family.stops(syntax) => Err(unknown_error(family, name, at, syntax)),
            None if !family.v3_goes_on() => Err(unknown_error(family, name, at, Syntax::V3)),
            _ => {
                self.unknown_names.push((family, name.to_string(), at));
                Ok(())
            }
        }
    }

    /// With the version settled: the first unknown name where the file's pbrt stops is
    /// an error; pbrt-v3's unknown materials are rendered as matte, with a warning (the
    /// other families warn where the statement is left out).
    pub(super) fn settle_unknown_names(&mut self, syntax: Syntax) -> Res<()> {
        for (family, name, at) in std::mem::take(&mut self.unknown_names) {
            if family.stops(syntax) {
                return Err(unknown_error(family, &name, at, syntax));
            }
            if family == Family::Material {
                let msg = format!("{}; rendered as matte with its parameters, as pbrt-v3 does", family.unknown(&name));
                self.warnings.push(Diagnostic::warning(at, msg));
            }
        }
        Ok(())
    }

    /// pbrt-v3 reads a `spectrum` parameter's SPD file as it parses the statement. One
    /// it cannot read, or whose text is not numbers, is black with a warning, and one
    /// with an odd count loses its last number; the render goes on. pbrt-v4 stops. In a
    /// file known as v3 such a parameter's value becomes those pairs here; elsewhere the
    /// parameter's reader reports the error.
    pub(super) fn v3_spectrum_files(&mut self, kind: &mut StmtKind) {
        if self.known_syntax() != Some(Syntax::V3) {
            return;
        }
        let Some(params) = kind.params_mut() else { return };
        for p in params.params.iter_mut().filter(|p| p.ty == ParamType::Spectrum) {
            let Values::Strings(names) = &p.values else { continue };
            let [name] = names.as_slice() else { continue };
            let Some((values, why)) = self.v3_spd_slip(name) else { continue };
            let msg = format!("\"spectrum {}\" \"{name}\": {why}", p.name);
            self.warnings.push(Diagnostic::warning(p.value_span, msg));
            p.values = Values::Floats(if values.is_empty() { vec![BLACK_FROM, 0.0, BLACK_TO, 0.0] } else { values });
        }
    }

    /// For spectrum `name`, a file pbrt-v3 does not take whole: the numbers it keeps
    /// (none: black) and why. `None` for a named spectrum or a well-formed file.
    fn v3_spd_slip(&self, name: &str) -> Option<(Vec<f32>, String)> {
        if crate::spectrum::named_spectrum(name).is_some() {
            return None;
        }
        let path = crate::parser::stmt::resolve_relative(self.reader.base_dir(), name);
        let bytes = match self.reader.files.read(&path) {
            Ok(bytes) => bytes,
            Err(e) => return Some((Vec::new(), format!("{e}; black, as pbrt-v3 renders it"))),
        };
        let well_formed = crate::values::spd_numbers(&bytes, name).is_ok_and(|v| !v.is_empty() && v.len() % 2 == 0);
        let v3 = crate::values::pbrt_v3_float_file(&bytes);
        if well_formed && !v3.cut_off {
            return None;
        }
        let mut why = vec![];
        if v3.skipped > 0 {
            why.push(format!("{} characters that are not numbers skipped", v3.skipped));
        }
        if v3.cut_off {
            why.push("the number at its end, with no line end after it, lost".to_string());
        }
        let mut values = v3.values;
        if values.len() % 2 == 1 {
            values.pop();
            why.push("an odd count: the last number dropped".to_string());
        }
        if values.is_empty() {
            why.push("no pairs: black".to_string());
        }
        Some((values, format!("read as pbrt-v3 reads it ({})", why.join("; "))))
    }

    /// What pbrt-v3 reports and goes on past, where pbrt-v4 stops: an error (`what`),
    /// but in a file known as v3 (`syntax`) a warning that adds what pbrt-v3 does
    /// instead (`v3_does`), and `Ok` for the caller to do the same.
    pub(super) fn v3_goes_on(&mut self, syntax: Option<Syntax>, at: Span, what: String, v3_does: &str) -> Res<()> {
        if syntax != Some(Syntax::V3) {
            return Err(Diagnostic::error(at, what));
        }
        self.warnings.push(Diagnostic::warning(at, format!("{what}; {v3_does}")));
        Ok(())
    }

    /// A `LookAt` whose up vector lies along the view: pbrt-v3 says so and leaves the
    /// CTM unchanged (its identity), pbrt-v4 stops. Until the version is known the CTM
    /// is left unchanged and [`Builder::settle_up_along_view`] decides.
    pub(super) fn up_along_view(&mut self, at: Span) -> Res<()> {
        match self.known_syntax() {
            Some(syntax) => self.up_along_view_in(syntax, at),
            None => {
                self.up_along_view.push(at);
                Ok(())
            }
        }
    }

    /// With the version settled: the `LookAt` statements [`Builder::up_along_view`]
    /// left waiting.
    pub(super) fn settle_up_along_view(&mut self, syntax: Syntax) -> Res<()> {
        std::mem::take(&mut self.up_along_view).into_iter().try_for_each(|at| self.up_along_view_in(syntax, at))
    }

    fn up_along_view_in(&mut self, syntax: Syntax, at: Span) -> Res<()> {
        const WHAT: &str = "LookAt: the up vector and the viewing direction are parallel";
        match syntax {
            Syntax::V4 => Err(Diagnostic::error(at, format!("{WHAT} (pbrt-v4 stops here too)"))),
            Syntax::V3 => {
                let msg = format!("{WHAT}; the transformation is left unchanged, as pbrt-v3 leaves it");
                self.warnings.push(Diagnostic::warning(at, msg));
                Ok(())
            }
        }
    }

    /// A file (with its includes) that ends before `WorldBegin` has nothing to render:
    /// an error at its end, as pbrt-v4 says.
    pub(super) fn check_world_begin(&self) -> Res<()> {
        if self.world_begin.is_some() {
            return Ok(());
        }
        let main = FileId(0);
        let end = self.reader.sources.file(main).text.len();
        let what = if end == 0 || self.reader.sources.file(main).text.iter().all(u8::is_ascii_whitespace) {
            "the file is empty"
        } else {
            "the file ends before WorldBegin"
        };
        Err(Diagnostic::error(Span::new(main, end, end), format!("{what}: there is no scene to render")))
    }

    /// pbrt-v3 renders a scene at its `WorldEnd`; a v3 file that ends without one
    /// renders nothing there ("pbrtCleanup() called while inside world block"). We
    /// render it, as pbrt-v4 would, and say so at the file's end.
    pub(super) fn check_world_end(&mut self, syntax: Syntax) {
        // DEVIATION(pbrt): robustness. The scene is complete; pbrt-v3 drops it.
        if syntax != Syntax::V3 || self.world_ended || self.world_begin.is_none() {
            return;
        }
        let main = FileId(0);
        let end = self.reader.sources.file(main).text.len();
        let msg = "the file ends without WorldEnd: pbrt-v3 renders nothing (\"pbrtCleanup() called while inside world block\"); rendered as if it were there";
        self.warnings.push(Diagnostic::warning(Span::new(main, end, end), msg));
    }
}

fn unknown_error(family: Family, name: &str, at: Span, syntax: Syntax) -> Diagnostic {
    let why = match syntax {
        _ if !family.v3_goes_on() => "pbrt renders nothing without a known one",
        Syntax::V4 => "pbrt-v4 stops here too",
        Syntax::V3 => "pbrt-v3 stops here too",
    };
    Diagnostic::error(at, format!("{}; {why}", family.unknown(name)))
}
