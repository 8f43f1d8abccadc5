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

use super::{Builder, Res};
use crate::fixes::Fix;
use crate::media::{self, MediumContext, MediumDesc, MediumInterface};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
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
}

/// Slots of the media on either side of what comes next (`None`: vacuum).
pub(super) type MediaPair = (Option<u32>, Option<u32>);

impl Builder {
    fn medium_slot(&mut self, name: &str) -> u32 {
        if let Some(&i) = self.medium_names.get(name) {
            return i;
        }
        self.medium_slots.push(MediumSlot { name: name.to_string(), definition: None, first_use: None });
        let i = self.medium_slots.len() as u32 - 1;
        self.medium_names.insert(name.to_string(), i);
        i
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
        for i in 0..self.medium_slots.len() {
            let slot = &mut self.medium_slots[i];
            // The medium's own transform (the CTM at its statement) matters to grids only.
            let Some((e, ctm)) = slot.definition.take() else {
                let at = slot.first_use.unwrap_or_default();
                return Err(Diagnostic::error(
                    at,
                    format!("medium \"{}\" is not defined (MakeNamedMedium)", slot.name),
                ));
            };
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
    // DEVIATION(pbrt): input leniency. pbrt-v3 warns and leaves the medium undefined
    // (its uses then fall back to vacuum); an error names the typo instead.
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
