//! The builder's media: `MakeNamedMedium` definitions, the `MediumInterface` in the
//! graphics state, and the names shapes, lights and the camera refer to, resolved to
//! built media once the file's version is known.
//!
//! ```text
//! MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_s" [0.2 0.2 0.2]
//! MediumInterface "fog" ""            # inside, outside; one name means both
//! ```
//!
//! A name may be used before its definition (pbrt-v4 resolves names at the end too);
//! one never defined is an error at its first use. Types that are not rendered are
//! skipped with a warning, and what refers to them is in vacuum.
//!
//! pbrt-v3 looks a name up when a shape or light is made, and where it finds nothing
//! it says so and goes on in vacuum: a v3 file's shapes and lights made before the
//! name's definition, or with no definition at all, are in vacuum (with a warning), as
//! are uses of a definition pbrt-v3 could not make (no type, an unknown type, a grid
//! without its density values). pbrt-v4 stops at each.

use super::{Builder, Res};
use crate::fixes::Fix;
use crate::media::{self, MediumContext, MediumDesc, MediumInterface};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamType;
use crate::parser::source::Span;
use crate::parser::stmt::Entity;
use crate::spectrum::transport::Colour;
use crate::values::SpectrumContext;
use glam::DMat4;

/// A medium name as the file uses it: its definition, if read, and its first use.
pub(super) struct MediumSlot {
    name: String,
    definition: Option<(Entity, DMat4)>,
    first_use: Option<Span>,
    /// For a stand-in: the slot whose name a shape or light used before any
    /// definition of it was read (pbrt-v4 takes the definition, pbrt-v3 vacuum).
    early_use_of: Option<u32>,
    /// The stand-in for this slot's uses before its definition.
    early: Option<u32>,
}

/// Slots of the media on either side of what comes next (`None`: vacuum).
pub(super) type MediaPair = (Option<u32>, Option<u32>);

impl Builder {
    fn medium_slot(&mut self, name: &str) -> u32 {
        if let Some(&i) = self.medium_names.get(name) {
            return i;
        }
        let i = self.new_slot(name, None);
        self.medium_names.insert(name.to_string(), i);
        i
    }

    fn new_slot(&mut self, name: &str, early_use_of: Option<u32>) -> u32 {
        let (definition, first_use, early) = (None, None, None);
        self.medium_slots.push(MediumSlot { name: name.to_string(), definition, first_use, early_use_of, early });
        self.medium_slots.len() as u32 - 1
    }

    /// The media of a shape or light made here (at `at`): the graphics state's, with a
    /// name not yet defined replaced by its stand-in, which the version settles.
    pub(super) fn media_here(&mut self, at: Span) -> MediaPair {
        let (inside, outside) = self.gs.media;
        (inside.map(|s| self.defined_by_now(s, at)), outside.map(|s| self.defined_by_now(s, at)))
    }

    fn defined_by_now(&mut self, slot: u32, at: Span) -> u32 {
        let s = &self.medium_slots[slot as usize];
        if s.definition.is_some() {
            return slot;
        }
        if let Some(early) = s.early {
            return early;
        }
        let name = s.name.clone();
        let early = self.new_slot(&name, Some(slot));
        self.medium_slots[early as usize].first_use = Some(at);
        self.medium_slots[slot as usize].early = Some(early);
        early
    }

    pub(super) fn named_medium(&mut self, e: Entity) -> Res<()> {
        if let Some(ty) = medium_type(&e) {
            let at = crate::values::span_of(&e.params, "type").unwrap_or(e.name_span);
            self.evidence("MakeNamedMedium", &ty, at);
        }
        let i = self.medium_slot(&e.name) as usize;
        if self.medium_slots[i].definition.is_some() {
            // DEVIATION(pbrt): robustness. pbrt-v4 refuses a file that redefines a
            // medium; pbrt-v3 takes the last definition, as we do for both, with a warning.
            let msg = format!("medium \"{}\" is defined again; this definition replaces the earlier one", e.name);
            self.warnings.push(Diagnostic::warning(e.name_span, msg));
        }
        self.medium_slots[i].definition = Some((e, self.gs.ctm[0]));
        Ok(())
    }

    pub(super) fn medium_interface(&mut self, inside: &str, outside: &str, span: Span) -> Res<()> {
        let mut slot = |name: &str| -> Option<u32> {
            if name.is_empty() {
                return None;
            }
            let i = self.medium_slot(name);
            self.medium_slots[i as usize].first_use.get_or_insert(span);
            Some(i)
        };
        self.gs.media = (slot(inside), slot(outside));
        Ok(())
    }

    /// Where media that a `MediumInterface` names emit what pbrt-v4 leaves unnormalised
    /// (a `temperature` grid, an `rgbgrid`'s `Le`): the `medium-emission` bug.
    pub(super) fn unnormalized_emitters(&self) -> impl Iterator<Item = Span> + '_ {
        let used = self.medium_slots.iter().filter(|s| s.first_use.is_some());
        used.filter_map(|s| s.definition.as_ref()).filter_map(|(e, _)| {
            let ty = medium_type(e).unwrap_or_default();
            let param = match ty.as_str() {
                "uniformgrid" => "temperature",
                media::rgbgrid::NAME => "Le",
                _ => return None,
            };
            e.params.named(param).map(|p| p.span)
        })
    }

    /// Builds the defined media in slot order; returns each slot's index among them
    /// (`None` for a type that is not rendered, or a medium nothing names).
    pub(super) fn build_media(&mut self) -> Res<(Vec<MediumDesc>, Vec<Option<u32>>)> {
        let mut built = Vec::new();
        let (mut remap, syntax) = (Vec::new(), self.syntax());
        let mut defined = Vec::with_capacity(self.medium_slots.len());
        for i in 0..self.medium_slots.len() {
            let slot = &mut self.medium_slots[i];
            defined.push(slot.definition.is_some());
            if let Some(of) = slot.early_use_of {
                // Its slot comes first: `remap` and `defined` hold it already.
                let (of, at) = (of as usize, slot.first_use.unwrap_or_default());
                remap.push(self.early_use(of, at, defined[of], syntax, &remap));
                continue;
            }
            // The medium's own transform (the CTM at its statement) matters to grids only.
            let Some((e, ctm)) = slot.definition.take() else {
                let what = format!("medium \"{}\" is not defined (MakeNamedMedium)", slot.name);
                let at = slot.first_use.unwrap_or_default();
                self.v3_goes_on(Some(syntax), at, what, "what it names is vacuum, as in pbrt-v3")?;
                remap.push(None);
                continue;
            };
            if syntax == Syntax::V3
                && let Some((at, why)) = left_out_by_v3(&e)?
            {
                let what = format!("MakeNamedMedium \"{}\": {why}", e.name);
                self.v3_goes_on(Some(syntax), at, what, "pbrt-v3 leaves it out: what it names is vacuum")?;
                remap.push(None);
                continue;
            }
            checked_type(&e, syntax)?;
            // Never named by a MediumInterface: nothing is in it (listed, not built).
            if slot.first_use.is_none() {
                let what = format!("MakeNamedMedium \"{}\"", e.name);
                self.skipped.push((Some(e.name_span), what, "never used".into()));
                remap.push(None);
                continue;
            }
            let kind = self.build_medium(&e, ctm)?;
            remap.push(kind.map(|kind| {
                built.push(MediumDesc { name: e.name.clone(), kind });
                built.len() as u32 - 1
            }));
        }
        Ok((built, remap))
    }

    /// What a shape or light made before slot `of` had a definition (first at `at`)
    /// is in: pbrt-v4 takes the definition; pbrt-v3 vacuum, with a warning where a
    /// definition comes later (where none does, the slot's own warning says so).
    fn early_use(&mut self, of: usize, at: Span, defined: bool, syntax: Syntax, remap: &[Option<u32>]) -> Option<u32> {
        if syntax == Syntax::V4 {
            return remap[of];
        }
        if defined {
            let name = &self.medium_slots[of].name;
            let msg = format!("medium \"{name}\" is used before its MakeNamedMedium; here it is vacuum, as in pbrt-v3");
            self.warnings.push(Diagnostic::warning(at, msg));
        }
        None
    }

    fn build_medium(&mut self, e: &Entity, medium_to_world: DMat4) -> Res<Option<media::Medium>> {
        let (ty, at) = checked_type(e, self.syntax())?;
        let syntax = self.syntax();
        if syntax == Syntax::V3 && ty != "homogeneous" && ty != "heterogeneous" {
            // pbrt-v3 warns that it does not know the type and leaves the medium out:
            // what it would fill is vacuum.
            e.params.params.iter().for_each(crate::parser::params::Param::mark_used);
            let why = "pbrt-v3 has no such medium type (a pbrt-v4 one): what it fills is vacuum, as in pbrt-v3";
            self.skipped.push((Some(at), format!("MakeNamedMedium \"{}\" (\"{ty}\")", e.name), why.into()));
            return Ok(None);
        }
        if ty != "homogeneous" && !invertible(&medium_to_world) {
            // DEVIATION(pbrt): robustness. pbrt-v4 fills such a transform's inverse
            // with NaN and renders garbage; our tracking then took 2^20 steps a ray.
            let msg = format!("medium \"{}\": its transform cannot be inverted (scaled to nothing?)", e.name);
            return Err(Diagnostic::error(e.name_span, msg));
        }
        let (files, base) = (self.reader.files.clone(), self.reader.base_dir().to_path_buf());
        let fixes = self.opts.fixes;
        let mut warnings = Vec::new();
        let built = {
            let space = self.space();
            let spectra = SpectrumContext { base_dir: &base, normalize_emission: false, files: &files, space };
            // DEVIATION(pbrt): appearance, `--fix medium-emission` (see Fix).
            let raw_emission = if fixes.has(Fix::MediumEmission) { 1.0 } else { crate::spectrum::CIE_Y_INTEGRAL };
            let mut ctx = MediumContext {
                syntax,
                spectra,
                warnings: &mut warnings,
                medium_to_world,
                at: e.name_span,
                raw_emission,
                spectral: (Colour::chosen(self.opts.colour, syntax) == Colour::Spectral).then_some(space),
            };
            media::read(&ty, &e.params, &mut ctx)
        };
        self.warnings.append(&mut warnings);
        let m = built?;
        super::typed::finish_params(&e.params, &mut self.warnings)?;
        Ok(Some(m))
    }
}

/// A MakeNamedMedium's `type` and where it is written, checked as the file's pbrt
/// checks it, used or not: required, known to pbrt, and for pbrt-v4 not pbrt-v3's
/// `heterogeneous` (pbrt-v4 creates every named medium, and stops at that one).
fn checked_type(e: &Entity, syntax: Syntax) -> Res<(String, Span)> {
    let ty = e.params.string("type")?.unwrap_or_default();
    let at = crate::values::span_of(&e.params, "type").unwrap_or(e.name_span);
    if ty.is_empty() {
        return Err(Diagnostic::error(e.name_span, "MakeNamedMedium needs a \"string type\""));
    }
    // pbrt-v3 leaves the medium out instead (`left_out_by_v3`, checked first).
    if !media::known(&ty) {
        return Err(Diagnostic::error(at, crate::scene::names::Family::Medium.unknown(&ty)));
    }
    if syntax == Syntax::V4 && ty == "heterogeneous" {
        return Err(Diagnostic::error(
            at,
            "pbrt-v4 has no medium type \"heterogeneous\" (its grid is \"uniformgrid\")",
        ));
    }
    Ok((ty, at))
}

/// Why pbrt-v3 makes no medium of a definition (it says so and goes on; what names
/// the medium is then in vacuum): no type, a type it does not know, or a grid whose
/// density values are missing or do not fill nx·ny·nz. `None`: it makes one.
fn left_out_by_v3(e: &Entity) -> Res<Option<(Span, String)>> {
    let Some(ty) = e.params.string("type")?.filter(|t| !t.is_empty()) else {
        return Ok(Some((e.name_span, "no \"string type\"".into())));
    };
    let at = crate::values::span_of(&e.params, "type").unwrap_or(e.name_span);
    if !media::known(&ty) {
        return Ok(Some((at, crate::scene::names::Family::Medium.unknown(&ty))));
    }
    if ty != "heterogeneous" {
        return Ok(None);
    }
    let Some((values_at, values)) = media::grid::grid_values(&e.params, "density", ParamType::Float)? else {
        return Ok(Some((e.name_span, "a grid without \"float density\" values".into())));
    };
    let n = [e.params.int("nx")?, e.params.int("ny")?, e.params.int("nz")?].map(|k| i128::from(k.unwrap_or(1)));
    let want: i128 = n.iter().product();
    // A zero or negative count stays an error (pbrt-v3 would index a grid of nothing).
    if n.iter().all(|&k| k >= 1) && want != values.len() as i128 {
        let why = format!("the grid has {} density values, not nx·ny·nz = {want}", values.len());
        return Ok(Some((values_at, why)));
    }
    Ok(None)
}

impl Builder {
    /// Builds the media and turns every slot index (shapes, lights, the camera) into
    /// an index among them; returns the media and the camera's.
    pub(super) fn resolve_media(
        &mut self,
        objects: &mut [crate::scene::ObjectDesc],
        lights: &mut [crate::lights::LightDesc],
    ) -> Res<(Vec<MediumDesc>, Option<u32>)> {
        let (built, remap) = self.build_media()?;
        let pair = |m: &MediumInterface| (m.inside, m.outside);
        let shapes = self.shapes.iter_mut().chain(objects.iter_mut().flat_map(|o| o.shapes.iter_mut()));
        for s in shapes {
            s.media = resolve(pair(&s.media), &remap);
        }
        for l in lights {
            l.medium = resolve((None, l.medium), &remap).outside;
        }
        // DEVIATION(pbrt): appearance, `--fix camera-medium` (pbrt-v3 only; see Fix).
        let camera = match self.syntax() {
            crate::parser::Syntax::V3 if !self.opts.fixes.has(crate::fixes::Fix::CameraMedium) => self.gs.media.1,
            _ => self.camera_media.1,
        };
        Ok((built, resolve((None, camera), &remap).outside))
    }
}

/// A `MakeNamedMedium`'s `"string type"` as written (before the version is known).
fn medium_type(e: &Entity) -> Option<String> {
    e.params.named("type").and_then(|p| p.strings().first().cloned())
}

/// A pair of slots as built media.
pub(super) fn resolve(pair: MediaPair, remap: &[Option<u32>]) -> MediumInterface {
    let get = |s: Option<u32>| s.and_then(|s| remap[s as usize]);
    MediumInterface { inside: get(pair.0), outside: get(pair.1) }
}

/// Whether a grid's placement can be undone: rays are taken into the grid's space.
fn invertible(m: &DMat4) -> bool {
    let det = m.determinant();
    det.is_normal() && m.inverse().is_finite()
}
