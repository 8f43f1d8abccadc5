//! Which pbrt bugs ([`crate::fixes`]) a scene would show, each at the statement that
//! triggers it, for `check`. Read from the built materials, textures and shapes, so
//! only what the scene uses is reported.

use super::Builder;
use crate::fixes::{Fix, Fixes, PbrtBug};
use crate::materials::{CoatBase, MaterialDesc, MaterialKind, TexValue};
use crate::parser::Syntax;
use crate::parser::error::Located;
use crate::parser::source::Span;
use crate::scene::{Geometry, ObjectDesc, ShapeDesc};
use crate::shapes::Quadric;
use crate::textures::TextureKind;
use glam::DMat3;

impl Builder {
    /// The bugs the scene triggers, in file order, one per (statement, fix). Called
    /// once materials, textures and world shapes are built, before the lights are.
    pub(super) fn pbrt_bugs(&self, syntax: Syntax, objects: &[ObjectDesc]) -> Vec<(Span, Fix)> {
        let mut found = Vec::new();
        for m in &self.materials {
            let (Some(b), Some(at)) = (m.built, m.span) else { continue };
            match &self.built_materials[b as usize].kind {
                MaterialKind::Plastic { .. } if syntax == Syntax::V3 => found.push((at, Fix::PlasticFresnel)),
                MaterialKind::Coated(c) if syntax == Syntax::V4 && rough(&c.coat_roughness) && rough_base(&c.base) => {
                    found.push((at, Fix::LayeredWeights))
                }
                MaterialKind::Subsurface(_) if self.takes_bssrdf(syntax) => found.push((at, Fix::SubsurfaceWalk)),
                _ => {}
            }
            if syntax == Syntax::V3 && rough_transmission(&self.built_materials[b as usize].kind) {
                found.push((at, Fix::RoughTransmission));
            }
        }
        for t in &self.textures {
            let Some(Some(b)) = t.built else { continue };
            if syntax == Syntax::V3 && matches!(self.built_textures[b as usize].kind, TextureKind::Marble { .. }) {
                found.push((t.span, Fix::MarblePalette));
            }
        }
        if syntax == Syntax::V3 && self.built_materials.iter().any(|m| glossy(&m.kind)) {
            let skies = self.pending_lights.iter().filter(|(e, _)| e.name == crate::lights::infinite::NAME);
            found.extend(skies.map(|(e, _)| (e.name_span, Fix::SkyAfterGlossy)));
        }
        for s in self.shapes.iter().filter(|s| s.area_light.is_some()) {
            self.area_light_bugs(s, syntax, &mut found);
        }
        for (s, at) in self.shapes.iter().zip(&self.shape_spans) {
            if let Geometry::Quadric(Quadric::Hyperboloid(h)) = &s.geometry
                && crate::shapes::hyperboloid::fit_differs(h)
            {
                found.push((*at, Fix::HyperboloidSurface));
            }
        }
        let shapes = self.shapes.iter().chain(objects.iter().flat_map(|o| o.shapes.iter()));
        for s in shapes.filter(|s| bumped_quadric_pbrt_tilts(s, &self.built_materials)) {
            let material = self.materials.iter().find(|m| m.built == Some(s.material)).and_then(|m| m.span);
            found.extend(material.map(|at| (at, Fix::NormalDerivatives)));
        }
        if let Some(at) = self.photon_statement() {
            found.push((at, Fix::PhotonsBehind));
        }
        if syntax == Syntax::V4 {
            found.extend(self.unnormalized_emitters().map(|at| (at, Fix::MediumEmission)));
            found.extend(self.illuminated_maps().map(|at| (at, Fix::MapIlluminance)));
            if self.photon_statement().is_some() {
                found.extend(self.portals().map(|at| (at, Fix::PortalPhotons)));
            }
        }
        if syntax == Syntax::V3
            && let Some(at) = self.first_motion
        {
            found.push((at, Fix::MotionTime));
        }
        if syntax == Syntax::V3 && self.camera_media.1 != self.gs.media.1 {
            found.extend(self.render.camera.as_ref().map(|(e, _)| (e.name_span, Fix::CameraMedium)));
        }
        found.sort_by_key(|(span, fix)| (span.file.0, span.start, *fix));
        found.dedup();
        found
    }

    /// `map-illuminance`: v4 infinite lights that scale a map (`filename`) to an
    /// `illuminance`, at the `illuminance` parameter.
    fn illuminated_maps(&self) -> impl Iterator<Item = Span> + '_ {
        let infinite = self.pending_lights.iter().map(|(e, _)| e).filter(|e| e.name == crate::lights::infinite::NAME);
        infinite.filter_map(|e| {
            let map = e.params.string("filename").ok().flatten().is_some_and(|f| !f.is_empty());
            let lux = crate::lights::params::illuminance(&e.params).ok().flatten().is_some();
            (map && lux).then(|| e.params.named("illuminance").map_or(e.name_span, |p| p.span))
        })
    }

    /// `portal-photons`: v4 infinite lights with a portal, at the `portal` parameter.
    fn portals(&self) -> impl Iterator<Item = Span> + '_ {
        let infinite = self.pending_lights.iter().map(|(e, _)| e).filter(|e| e.name == crate::lights::infinite::NAME);
        infinite.filter_map(|e| e.params.named("portal").map(|p| p.span))
    }

    /// `mesh-power` and `area-alpha` for one emitting world shape, at its
    /// `AreaLightSource` statement.
    fn area_light_bugs(&self, s: &ShapeDesc, syntax: Syntax, found: &mut Vec<(Span, Fix)>) {
        let Some(i) = s.area_light else { return };
        let Some(&entity) = self.area_lights_used.get(i as usize) else { return };
        let e = &self.area_light_entities[entity as usize].0;
        let pieces = match &s.geometry {
            Geometry::Quadric(_) => 1,
            Geometry::Mesh { mesh, .. } => self.meshes[*mesh as usize].triangle_count(),
            Geometry::Patches { mesh, .. } => self.patches[*mesh as usize].patch_count(),
            Geometry::Curves { curves } => curves.pieces.len(),
        };
        if syntax == Syntax::V4 && pieces > 1 && e.params.named("power").is_some() {
            found.push((e.name_span, Fix::MeshPower));
        }
        // pbrt-v4's second mask changes nothing where alpha is only 0 or 1.
        let fractional = |a: &TexValue| !matches!(a, TexValue::Const(c) if c.x <= 0.0 || c.x >= 1.0);
        if s.alpha.as_ref().is_some_and(|a| syntax == Syntax::V3 || fractional(&a.alpha)) {
            found.push((e.name_span, Fix::AreaAlpha));
        }
        let two_sided = e.params.bool("twosided").ok().flatten().unwrap_or(false);
        if let Geometry::Quadric(q) = &s.geometry
            && pbrt_samples_differently(q, s, two_sided)
        {
            found.push((e.name_span, Fix::ShapeSampling));
        }
    }

    /// Where SPPM is asked for: the `Integrator "sppm"` statement (`None` for another
    /// integrator, or a scene with nothing to render).
    /// `subsurface-walk`: whether the file's integrator takes light through BSSRDFs.
    fn takes_bssrdf(&self, syntax: Syntax) -> bool {
        let default = if syntax == Syntax::V3 { "path" } else { "volpath" };
        let name = self.render.integrator.as_ref().map_or(default, |e| e.name.as_str());
        crate::materials::subsurface::follows_bssrdf(syntax, name)
    }

    fn photon_statement(&self) -> Option<Span> {
        if self.shapes.is_empty() && self.objects.is_empty() {
            return None;
        }
        // Only pbrt's SPPM has it: without `Integrator "sppm"` pbrt path-traces.
        self.render.integrator.as_ref().filter(|e| e.name == "sppm").map(|e| e.name_span)
    }
}

/// Whether pbrt's sampling of an emitting quadric differs from the exact one: a cut
/// sphere or disk, an area changed by the transform, or a mirrored one-sided light.
fn pbrt_samples_differently(q: &Quadric, s: &ShapeDesc, two_sided: bool) -> bool {
    let full = std::f32::consts::TAU * (1.0 - 1e-6);
    let cut = match q {
        Quadric::Sphere(sp) => sp.z_min > -sp.radius || sp.z_max < sp.radius || sp.phi_max < full,
        Quadric::Disk(d) => d.inner_radius > 0.0 || d.phi_max < full,
        Quadric::Cylinder(_) => false,
        _ => return false,
    };
    let (object, world) = (q.world_area(DMat3::IDENTITY), q.world_area(DMat3::from_mat4(s.object_to_world)));
    cut || (world - object).abs() > 1e-6 * object || (s.swaps_handedness() && !two_sided)
}

/// Whether a bump-mapped quadric's ∂n/∂u differs in pbrt: under a transform that is
/// not rigid, or reversed.
fn bumped_quadric_pbrt_tilts(s: &ShapeDesc, materials: &[MaterialDesc]) -> bool {
    let bumped = materials.get(s.material as usize).is_some_and(|m| m.bump.is_some());
    let rigid =
        crate::shapes::similarity_scale(DMat3::from_mat4(s.object_to_world)).is_some_and(|k| (k - 1.0).abs() < 1e-9);
    matches!(s.geometry, Geometry::Quadric(_)) && bumped && (s.reverse_orientation || !rigid)
}

/// Whether a material may scatter glossily (where pbrt-v3 counts the sky twice).
fn glossy(k: &MaterialKind) -> bool {
    match k {
        MaterialKind::Diffuse { .. } | MaterialKind::OrenNayar { .. } | MaterialKind::Mirror { .. } => false,
        MaterialKind::Interface | MaterialKind::DiffuseTransmission { .. } => false,
        MaterialKind::Dielectric { roughness, .. } => rough(roughness),
        _ => true,
    }
}

/// Whether a coat's roughness may be above pbrt-v4's smoothness threshold.
/// Whether a v3 material's lobes may include pbrt-v3's `MicrofacetTransmission`.
fn rough_transmission(kind: &MaterialKind) -> bool {
    let on = |v: &TexValue| !matches!(v, TexValue::Const(c) if *c == glam::Vec3::ZERO);
    match kind {
        MaterialKind::Dielectric { kt, roughness, .. } => on(kt) && rough(roughness),
        MaterialKind::Subsurface(s) => on(&s.kt) && rough(&s.roughness),
        MaterialKind::Translucent { ks, transmit, .. } => on(ks) && on(transmit),
        MaterialKind::Disney(d) => on(&d.spec_trans),
        _ => false,
    }
}

fn rough(r: &[TexValue; 2]) -> bool {
    r.iter().any(|v| !matches!(v, TexValue::Const(c) if c.x <= 0.0))
}

/// Whether the layer under a coat scatters other than specularly.
fn rough_base(b: &CoatBase) -> bool {
    match b {
        CoatBase::Diffuse { .. } => true,
        CoatBase::Conductor { roughness, .. } => rough(roughness),
    }
}

/// The bugs found, located, each saying whether this run fixes it.
pub(super) fn located(found: &[(Span, Fix)], fixes: Fixes, sources: &crate::parser::source::SourceMap) -> Vec<PbrtBug> {
    found
        .iter()
        .map(|(span, fix)| {
            let l = Located::resolve(sources, Some(*span), "");
            PbrtBug {
                file: l.file,
                line: l.line,
                column: l.column,
                name: fix.name().into(),
                effect: fix.info().effect.into(),
                fixed: fixes.has(*fix),
            }
        })
        .collect()
}
