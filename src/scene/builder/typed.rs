//! The builder's second half: lights, area lights, materials and textures become typed
//! descriptions once the whole file is read (the syntax version decides some
//! meanings), and only those something uses. Texture references follow v3 scoping,
//! then v4 forward references; a texture that refers to itself is an error.

use super::{Builder, Res, Scope};
use crate::approx::Approx;
use crate::imageio::{EightBit, Format, Grey, RgbImage, Texels};
use crate::lights::{self, LightContext, LightDesc};
use crate::materials::params::{bump_map, normal_map};
use crate::materials::{self, MaterialDesc, MaterialKind, Resolver, TexValue};
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::{FloatValue, ParamList};
use crate::parser::source::Span;
use crate::parser::stmt::Entity;
use crate::scene::names::Family;
use crate::scene::shapes::AlphaParams;
use crate::scene::{AlphaRule, ShapeAlpha};
use crate::shapes;
use crate::textures::{self, TextureDesc, TextureKind, TextureSite};
use crate::values::SpectrumContext;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;

/// Textures may refer to textures this deep (a chain of definitions), no deeper.
const TEXTURE_DEPTH: usize = 64;
/// Texture lookups one evaluation may make (a texture used twice by another counts
/// twice), so a few shared definitions cannot make shading exponentially slow.
const TEXTURE_LOOKUPS: u64 = 100_000;

/// The builder as a [`Resolver`] for one material's or texture's scope.
struct Scoped<'b> {
    b: &'b mut Builder,
    scope: Rc<Scope>,
    depth: usize,
}

impl Builder {
    pub(super) fn syntax(&self) -> Syntax {
        self.syntax.unwrap_or(Syntax::V4)
    }

    fn spectrum_context(&self, lights: bool) -> SpectrumContext<'_> {
        SpectrumContext {
            base_dir: self.reader.base_dir(),
            normalize_emission: lights && self.syntax() == Syntax::V4,
            files: &self.reader.files,
            space: self.space(),
        }
    }

    /// An image for a texture or normal map by scene-relative name, read once, its size
    /// checked before decoding.
    pub(super) fn image(&mut self, name: &str) -> Result<Arc<Texels>, String> {
        let path = self.reader.resolve_path(name);
        self.readable(&path)?;
        let files = &self.reader.files;
        read_once(&mut self.images, path.clone(), &path, |p| crate::imageio::read_texels_within(p, files))
    }

    /// [`Builder::image`] for float textures: one value a texel, as `grey` says.
    pub(super) fn grey_image(&mut self, name: &str, grey: Grey) -> Result<Arc<Texels>, String> {
        let path = self.reader.resolve_path(name);
        self.readable(&path)?;
        let files = &self.reader.files;
        let read = |p: &Path| crate::imageio::read_grey_texels_within(p, files, grey);
        read_once(&mut self.grey_images, (path.clone(), grey), &path, read)
    }

    /// [`Builder::image`] for lights, which keep every value as `f32`. pbrt-v3's lights
    /// take an 8-bit image's values as stored; pbrt-v4's decode sRGB.
    fn light_image(&mut self, name: &str) -> Result<Arc<RgbImage>, String> {
        let path = self.reader.resolve_path(name);
        self.readable(&path)?;
        let files = &self.reader.files;
        let eight_bit = if self.syntax() == Syntax::V3 { EightBit::Raw } else { EightBit::Srgb };
        read_once(&mut self.light_images, path.clone(), &path, |p| {
            crate::imageio::read_image_within(p, files, eight_bit)
        })
    }

    /// Refuses an image format the file's pbrt cannot read, as that pbrt does (pbrt-v3
    /// reads EXR, PNG, TGA and PFM).
    fn readable(&self, path: &Path) -> Result<(), String> {
        match Format::of(path) {
            Some(f) if self.syntax() == Syntax::V3 && !f.read_by_pbrt_v3() => {
                Err(format!("\"{}\": pbrt-v3 does not read {} images", path.display(), f.name()))
            }
            _ => Ok(()),
        }
    }

    /// Every `LightSource` of a supported type, typed.
    pub(super) fn build_lights(&mut self) -> Res<Vec<LightDesc>> {
        let pending = std::mem::take(&mut self.pending_lights);
        let media = std::mem::take(&mut self.pending_light_media);
        let mut out = Vec::new();
        for ((e, ctm), medium) in pending.into_iter().zip(media) {
            let (files, base) = (self.reader.files.clone(), self.reader.base_dir().to_path_buf());
            let mut warnings = Vec::new();
            let mut missing = Vec::new();
            let kind = {
                let (syntax, space) = (self.syntax(), self.space());
                let mut note_missing = |at: Span, what: String| missing.push((at, what));
                let mut images = |n: &str| self.light_image(n);
                let mut ctx = LightContext {
                    syntax,
                    spectra: SpectrumContext {
                        base_dir: &base,
                        normalize_emission: syntax == Syntax::V4,
                        files: &files,
                        space,
                    },
                    image: &mut images,
                    warnings: &mut warnings,
                    missing: &mut note_missing,
                };
                lights::read(&e.name, &e.params, &ctm, e.name_span, &mut ctx).and_then(|k| {
                    let spectrum = lights::emission_spectrum(&e.name, &e.params, &ctx.spectra)?;
                    Ok(k.map(|kind| (kind, spectrum)))
                })
            };
            self.warnings.append(&mut warnings);
            for (at, what) in missing {
                self.note(at, what, Approx::MissingImage);
            }
            let kind = kind?;
            match kind {
                Some((kind, spectrum)) => {
                    finish_params(&e.params, &mut self.warnings)?;
                    out.push(LightDesc { kind, spectrum, world_from_light: ctm, medium });
                }
                None => {
                    let what = format!("LightSource \"{}\"", e.name);
                    self.skip(e.name_span, what, super::checks::why_left_out(Family::Light, &e.name));
                }
            }
        }
        Ok(out)
    }

    /// pbrt-v4 ignores an area light on a shape whose material is `interface` (or
    /// `none`, `""`), with a warning; pbrt-v3 lets it emit.
    pub(super) fn drop_interface_emitters(&mut self) {
        if self.syntax() != Syntax::V4 {
            return;
        }
        let interface = |m: u32| matches!(self.built_materials[m as usize].kind, MaterialKind::Interface);
        let dropped: Vec<usize> = (0..self.shapes.len())
            .filter(|&i| self.shapes[i].area_light.is_some() && interface(self.shapes[i].material))
            .collect();
        for i in dropped {
            let Some(a) = self.shapes[i].area_light.take() else { continue };
            let at = self.area_light_entities[self.area_lights_used[a as usize] as usize].0.name_span;
            let why = "ignored on a shape with the \"interface\" material, as pbrt-v4 ignores it";
            self.warnings.push(Diagnostic::warning(at, format!("AreaLightSource: {why}")));
        }
    }

    /// The area lights some world shape used, in the order of their indices.
    pub(super) fn build_area_lights(&mut self) -> Res<Vec<lights::AreaLightDesc>> {
        let used = std::mem::take(&mut self.area_lights_used);
        let mut out = Vec::with_capacity(used.len());
        for i in used {
            let e = std::mem::replace(&mut self.area_light_entities[i as usize].0, Entity::default_named(""));
            let mut warnings = Vec::new();
            let (files, base, syntax) =
                (self.reader.files.clone(), self.reader.base_dir().to_path_buf(), self.syntax());
            let space = self.space();
            let spectra =
                SpectrumContext { base_dir: &base, normalize_emission: syntax == Syntax::V4, files: &files, space };
            let mut images = |n: &str| self.light_image(n);
            let desc =
                lights::diffuse::read(&e.name, &e.params, (syntax, &spectra), &mut images, &mut warnings, e.name_span);
            self.warnings.append(&mut warnings);
            let desc = desc?.ok_or_else(|| Diagnostic::error(e.name_span, "unsupported area light"))?;
            finish_params(&e.params, &mut self.warnings)?;
            out.push(desc);
        }
        Ok(out)
    }

    pub(super) fn note(&mut self, at: Span, what: String, how: Approx) {
        self.warnings.push(Diagnostic::warning(at, format!("{what}: {}", how.how())));
        self.approximated.push((at, what, how));
    }

    /// Builds material `i` on first use; its index among the built materials.
    pub(super) fn build_material(&mut self, i: u32) -> Res<u32> {
        let m = &mut self.materials[i as usize];
        if let Some(b) = m.built {
            return Ok(b);
        }
        m.building = true;
        let params = std::mem::take(&mut m.params);
        let (name, span, scope, ty) = (m.name.clone(), m.span, m.scope.clone(), m.ty.clone());
        params.mark_known(&["type"]);
        let at = span.unwrap_or_default();
        let kind = {
            let mut r = Scoped { b: self, scope, depth: 0 };
            // pbrt-v3 renders an unknown material as matte with its parameters (pbrt-v4
            // stops at it: see `checks`).
            let read_as = if Family::Material.knows(&ty) { ty.as_str() } else { crate::materials::matte::NAME };
            let kind = materials::read(read_as, &params, at, &mut r)?;
            (kind, bump_map(&params, &mut r)?, normal_map(&ty, &params, &mut r)?)
        };
        let (kind, bump, normal_map) = kind;
        finish_params(&params, &mut self.warnings)?;
        self.built_materials.push(MaterialDesc { ty, name, kind, bump, normal_map });
        let b = self.built_materials.len() as u32 - 1;
        self.materials[i as usize].built = Some(b);
        self.materials[i as usize].building = false;
        Ok(b)
    }

    /// Builds texture `i` (and what it refers to) on first use.
    fn build_texture(&mut self, i: u32, depth: usize, at: Span) -> Res<u32> {
        let t = &mut self.textures[i as usize];
        match t.built {
            Some(Some(b)) => return Ok(b),
            Some(None) => {
                return Err(Diagnostic::error(at, format!("texture \"{}\" refers to itself", t.name)));
            }
            None => {}
        }
        if depth >= TEXTURE_DEPTH {
            return Err(Diagnostic::error(at, format!("textures refer to textures more than {TEXTURE_DEPTH} deep")));
        }
        t.built = Some(None); // being built: a reference back to it is a cycle
        let params = std::mem::take(&mut t.params);
        let (class, span, scope, is_float) = (t.class.clone(), t.span, t.scope.clone(), t.ty == "float");
        let site = TextureSite { world_from_texture: t.ctm, syntax: self.syntax() };
        let kind = {
            let mut r = Scoped { b: self, scope, depth: depth + 1 };
            textures::read(&class, is_float, &params, span, &site, &mut r)?
        };
        let kind = kind.unwrap_or_else(|| {
            params.mark_all_used();
            let what = format!("texture \"{}\" of class \"{class}\"", self.textures[i as usize].name);
            if !Family::Texture.knows(&class) {
                self.warnings.push(Diagnostic::warning(span, Family::Texture.unknown(&class)));
            }
            self.note(span, what, Approx::UnsupportedTexture);
            TextureKind::Constant(TexValue::Const(Vec3::splat(0.5)))
        });
        finish_params(&params, &mut self.warnings)?;
        let lookups = 1 + children(&kind).map(|c| self.texture_lookups[c as usize]).sum::<u64>();
        if lookups > TEXTURE_LOOKUPS {
            let msg = format!("texture needs {lookups} lookups per evaluation, more than {TEXTURE_LOOKUPS}");
            return Err(Diagnostic::error(span, msg));
        }
        let name = self.textures[i as usize].name.clone();
        self.built_textures.push(TextureDesc { name, kind });
        self.texture_lookups.push(lookups);
        let b = self.built_textures.len() as u32 - 1;
        self.textures[i as usize].built = Some(Some(b));
        Ok(b)
    }
}

impl Builder {
    /// A shape's alpha mask as the file's version reads it; `None` when it never cuts.
    pub(super) fn resolve_alpha(&mut self, a: &AlphaParams, scope: Rc<Scope>) -> Res<Option<ShapeAlpha>> {
        let rule = if self.syntax() == Syntax::V3 { AlphaRule::ZeroCuts } else { AlphaRule::Stochastic };
        let mut r = Scoped { b: self, scope, depth: 0 };
        let mut value = |v: &Option<(FloatValue, Span)>| -> Res<Option<TexValue>> {
            Ok(match v {
                None => None,
                Some((FloatValue::Texture(name), at)) => r.texture(name, true, *at)?.map(TexValue::Texture),
                // A constant that never cuts is no mask at all.
                Some((FloatValue::Const(c), _)) => match rule {
                    AlphaRule::ZeroCuts => (*c == 0.0).then_some(TexValue::Const(Vec3::ZERO)),
                    AlphaRule::Stochastic => (*c < 1.0).then_some(TexValue::Const(Vec3::splat(*c))),
                },
            })
        };
        let (alpha, shadow) = (value(&a.alpha)?, value(&a.shadow)?);
        Ok(match (alpha, shadow) {
            (None, None) => None,
            (alpha, shadow) => Some(ShapeAlpha { alpha: alpha.unwrap_or(TexValue::Const(Vec3::ONE)), shadow, rule }),
        })
    }
}

/// The textures a texture reads.
fn children(k: &TextureKind) -> impl Iterator<Item = u32> {
    k.inputs().into_iter().filter_map(|v| if let TexValue::Texture(t) = v { Some(t) } else { None })
}

/// After a typed build: a parameter some lookup wanted with another type is an error;
/// the rest nobody looked up are warned as unused.
pub(super) fn finish_params(p: &ParamList, warnings: &mut Vec<Diagnostic>) -> Res<()> {
    if let Some(e) = p.wrong_type() {
        return Err(e);
    }
    p.report_unused(warnings);
    Ok(())
}

impl Builder {
    /// A pbrt-v4 displaced PLY mesh made a mesh: its float texture found in the shape's
    /// scope and looked up at each refined vertex. pbrt-v4 looks it up at the vertex's
    /// object-space point taken as a point of its rendering space (world moved by the
    /// camera's position): so do we, for 3D textures to land where pbrt-v4's do.
    pub(super) fn displace(&mut self, d: shapes::Displaced, scope: Rc<Scope>, ctm: &glam::DMat4) -> Res<shapes::Built> {
        let texture = Scoped { b: self, scope, depth: 0 }.texture(&d.texture, true, d.at)?;
        // Displacement is pbrt-v4's: a texture defined nowhere stays an error, v3 file or not.
        let texture = texture
            .ok_or_else(|| Diagnostic::error(d.at, format!("float texture \"{}\" is not defined", d.texture)))?;
        let textures = textures::Textures::new(&self.built_textures, self.opts.fixes);
        let camera = self.render.camera.as_ref().map_or(glam::DMat4::IDENTITY, |c| c.1);
        let eye = camera.inverse().w_axis.truncate().as_vec3();
        let height = |p: [f32; 3], n: [f32; 3], uv: [f32; 2]| {
            let ctx = textures::TexCtx { p: Vec3::from(p) + eye, n: Vec3::from(n), uv, ..Default::default() };
            textures.float(TexValue::Texture(texture), &ctx)
        };
        let mut mesh = d.mesh;
        shapes::displace::displace(&mut mesh, ctm, d.edge_length, height)
            .map_err(|e| Diagnostic::error(d.at, format!("{}: {e}", d.filename)))?;
        Ok(shapes::Built::Mesh { mesh, kind: shapes::plymesh::NAME, filename: Some(d.filename) })
    }
}

impl Resolver for Scoped<'_> {
    fn texture(&mut self, name: &str, float: bool, at: Span) -> Res<Option<u32>> {
        let (mine, other) = if float {
            (&self.scope.float_textures, &self.scope.spectrum_textures)
        } else {
            (&self.scope.spectrum_textures, &self.scope.float_textures)
        };
        let kind = if float { 0 } else { 1 };
        let in_scope = mine.get(name).or_else(|| other.get(name)).is_some();
        let found = mine
            .get(name)
            .or_else(|| self.b.global_textures[kind].get(name))
            .or_else(|| other.get(name))
            .or_else(|| self.b.global_textures[1 - kind].get(name))
            .copied();
        let want = if float { "float" } else { "spectrum" };
        let Some(i) = found else {
            let what = format!("{want} texture \"{name}\" is not defined");
            let v3_does = "the parameter takes its default, as pbrt-v3 takes it";
            return self.b.v3_goes_on(Some(self.b.syntax()), at, what, v3_does).map(|()| None);
        };
        let class = &self.b.textures[i as usize].class;
        if self.b.syntax() == Syntax::V3 && !Family::Texture.knows(class) {
            // pbrt-v3 makes no texture of a class it does not know.
            self.b.textures[i as usize].params.mark_all_used();
            let what = format!("{want} texture \"{name}\" has {}", Family::Texture.unknown(class));
            let v3_does = "it is not defined and the parameter takes its default, as in pbrt-v3";
            return self.b.v3_goes_on(Some(Syntax::V3), at, what, v3_does).map(|()| None);
        }
        // DEVIATION(pbrt): input leniency. pbrt-v3 forgets a texture at the end of its
        // block (an error, then the parameter's default); its definition is used, named.
        if !in_scope && self.b.syntax() == Syntax::V3 {
            let defined = self.b.textures[i as usize].span;
            let msg = format!(
                "texture \"{name}\" was defined inside an AttributeBegin that has ended ({}); pbrt-v3 does not find it here and uses the parameter's default, this renderer uses that definition",
                self.b.reader.sources.location(defined)
            );
            self.b.warnings.push(Diagnostic::warning(at, msg));
        }
        self.b.build_texture(i, self.depth, at).map(Some)
    }

    fn approximate(&mut self, at: Span, what: String, how: Approx) {
        self.b.note(at, what, how);
    }

    fn warn(&mut self, at: Span, message: String) {
        self.b.warnings.push(Diagnostic::warning(at, message));
    }

    fn syntax(&self) -> Syntax {
        self.b.syntax()
    }

    fn named_material(&mut self, name: &str, at: Span) -> Res<u32> {
        let in_scope = self.scope.materials.get(name).copied();
        let found = in_scope.or_else(|| self.b.global_materials.get(name).copied());
        let Some(i) = found else {
            // pbrt-v3 mixes in a matte for it; the default material (index 0) is
            // pbrt-v3's matte. DEVIATION(pbrt): appearance, too small for a fix: pbrt-v3's
            // matte takes the mix's own Kd, sigma and bumpmap, which a mix rarely has.
            let what = format!("named material \"{name}\" is not defined");
            self.b.v3_goes_on(Some(self.b.syntax()), at, what, "pbrt-v3's mix uses matte in its place")?;
            return self.b.build_material(0);
        };
        // DEVIATION(pbrt): input leniency. pbrt-v3's mix takes matte for a name out of
        // scope (with an error); its definition is used, named.
        if in_scope.is_none() && self.b.syntax() == Syntax::V3 {
            self.b.warn_material_out_of_scope(name, at, i, "pbrt-v3's mix uses matte in its place");
        }
        if self.b.materials[i as usize].building {
            return Err(Diagnostic::error(at, format!("material \"{name}\" mixes itself")));
        }
        self.b.build_material(i)
    }

    fn material_type(&self, built: u32) -> Option<&str> {
        self.b.built_materials.get(built as usize).map(|m| m.ty.as_str())
    }

    fn spectra(&self) -> SpectrumContext<'_> {
        self.b.spectrum_context(false)
    }

    fn image(&mut self, name: &str) -> Result<Arc<Texels>, String> {
        self.b.image(name)
    }

    fn grey_image(&mut self, name: &str, grey: Grey) -> Result<Arc<Texels>, String> {
        self.b.grey_image(name, grey)
    }
}

/// The image at `path` from `cache` (under `key`), or read by `read` and kept there.
fn read_once<K: std::hash::Hash + Eq, T, E: std::fmt::Display>(
    cache: &mut HashMap<K, Arc<T>>,
    key: K,
    path: &Path,
    read: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<Arc<T>, String> {
    if let Some(img) = cache.get(&key) {
        return Ok(img.clone());
    }
    let img = Arc::new(read(path).map_err(|e| e.to_string())?);
    cache.insert(key, img.clone());
    Ok(img)
}
