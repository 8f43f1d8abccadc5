//! The graphics state: statements in, [`SceneDescription`] out.
//!
//! ```text
//! AttributeBegin                       # saves CTM, material, area light, orientation,
//!   CoordSysTransform "camera"         #   and (v3 scoping) named materials/textures
//!   ReverseOrientation
//!   MakeNamedMaterial "gold" "string type" "metal"
//!   NamedMaterial "gold"               # v4: may also name a material defined later
//!   ObjectBegin "tree"  Shape "plymesh" "string filename" "tree.ply"  ObjectEnd
//! AttributeEnd
//! ObjectInstance "tree"                # world-from-object = CTM here · CTM at the Shape
//! ```
//! Transforms post-multiply the CTM (`CTM ← CTM·X`); `ActiveTransform` picks which of the
//! start/end pair they change (shapes use the start transform; motion is warned once).
//! Named materials and textures are scoped by `AttributeBegin` as in v3, and a name not
//! in scope falls back to the last definition anywhere in the file (v4 forward
//! references). Object definitions, materials, textures and area lights are built
//! only when something uses them.

mod bugs;
mod checks;
mod instances;
mod media;
mod typed;

use super::entities;
use super::names::Family;
use super::options::RenderOptions;
use super::shapes::{AlphaParams, alpha_params};
use super::{Approximated, Geometry, Instances, ObjectDesc, SceneDescription, ShapeDesc, Skipped};
use crate::approx::Approx;
use crate::imageio::RgbImage;
use crate::limits::{FileBytes, Files, Limits};
use crate::materials::MaterialDesc;
use crate::math::animated::AnimatedTransform;
use crate::memory::{MemoryBudget, MemoryNeed};
use crate::parser::Syntax;
use crate::parser::error::{Diagnostic, LoadError, Located};
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::parser::stmt::{ActiveTransform, Entity, StatementReader, Stmt, StmtKind, read_scene_bytes};
use crate::shapes::read_ahead::ReadAhead;
use crate::shapes::{self, Built, ShapeContext, mesh_params as mesh, plymesh};
use crate::spectrum::transport::Colour;
use crate::textures::TextureDesc;
use glam::{DMat4, DVec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

/// How to load a scene.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Overrides syntax detection (`--syntax v3|v4`).
    pub syntax: Option<Syntax>,
    pub limits: Limits,
    /// Files `Include`/`Import` read from memory instead of disk, by the name the scene
    /// gives (for fuzzing and tests).
    pub in_memory: HashMap<String, Arc<[u8]>>,
    /// The pbrt bugs to fix (`--fix`); by default the file renders as its pbrt renders it.
    pub fixes: crate::fixes::Fixes,
    /// What paths carry (`--colour`); by default as the file's pbrt: wavelengths for
    /// pbrt-v4, RGB for pbrt-v3.
    pub colour: Option<Colour>,
    /// Leaves the files read unhashed (their [`crate::limits::InputFile`] hashes 0), for
    /// commands that make no render fingerprint.
    pub skip_input_hashes: bool,
}

/// Reads, parses and builds a scene file.
pub fn load_scene(path: &Path, opts: &LoadOptions) -> Result<SceneDescription, LoadError> {
    let files = files_for(opts);
    let bytes = read_scene_bytes(path, &files).map_err(|e| {
        // A file that exists but cannot be used (UTF-16, corrupt gzip, too large) is
        // blamed at its start; a missing one has no line to point at.
        let name = path.display().to_string();
        match path.is_file() {
            true => LoadError::at_start(name, e),
            false => LoadError::in_file(name, e),
        }
    })?;
    load(path, bytes, opts, files)
}

/// As [`load_scene`], with the top-level file's bytes given (its path still anchors
/// relative file names, and names it in the list of files read).
pub fn load_scene_from_bytes(path: &Path, bytes: Vec<u8>, opts: &LoadOptions) -> Result<SceneDescription, LoadError> {
    let files = files_for(opts);
    files.note(path, &bytes);
    load(path, bytes.into(), opts, files)
}

fn files_for(opts: &LoadOptions) -> Files {
    match opts.skip_input_hashes {
        true => Files::without_hashes(opts.limits),
        false => Files::new(opts.limits),
    }
}

fn load(path: &Path, bytes: FileBytes, opts: &LoadOptions, files: Files) -> Result<SceneDescription, LoadError> {
    let mut reader =
        StatementReader::new(path, bytes, files).map_err(|e| LoadError::in_file(path.display().to_string(), e))?;
    reader.in_memory = opts.in_memory.clone();
    let mut b = Builder::new(reader, opts.clone());
    match b.run() {
        Ok(scene) => Ok(scene),
        Err(d) => Err(LoadError::from_diagnostic(&b.reader.sources, &d)),
    }
}

type Res<T> = Result<T, Diagnostic>;

/// Named materials and textures visible in a scope (v3 semantics).
#[derive(Clone, Default)]
struct Scope {
    materials: HashMap<String, u32>,
    float_textures: HashMap<String, u32>,
    spectrum_textures: HashMap<String, u32>,
}

#[derive(Clone, Copy, Debug)]
enum MaterialRef {
    Pending(u32),
    /// A `NamedMaterial` not in scope at its statement: its index in `named_refs`.
    Named(u32),
}

/// A `NamedMaterial` statement whose name was not in scope there.
struct NamedRef {
    name: String,
    span: Span,
    /// The material current before it: what pbrt-v3 keeps when the name is defined
    /// nowhere.
    before: MaterialRef,
    /// The definition it stands for, once resolved.
    resolved: Option<u32>,
}

#[derive(Clone)]
struct GraphicsState {
    ctm: [DMat4; 2],
    active: [bool; 2],
    reverse_orientation: bool,
    material: MaterialRef,
    area_light: Option<u32>,
    scope: Rc<Scope>,
    /// v4 `Attribute` statements in effect: (target, index into `Builder::attributes`).
    attributes: Rc<Vec<(String, u32)>>,
    /// `MediumInterface`: the media inside and outside what comes next.
    media: media::MediaPair,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum PushKind {
    Attribute,
    Transform,
    Object,
    Import,
}

struct PendingMaterial {
    ty: String,
    name: Option<String>,
    params: ParamList,
    span: Option<Span>,
    scope: Rc<Scope>,
    built: Option<u32>,
    /// Being built: a `mix` that reaches it again is a cycle.
    building: bool,
}

struct PendingTexture {
    name: String,
    ty: String,
    class: String,
    params: ParamList,
    span: Span,
    scope: Rc<Scope>,
    /// The CTM at the statement (texture space for 3D textures and mappings).
    ctm: DMat4,
    /// `Some(None)`: tried and skipped; `Some(Some(i))`: built as texture i.
    built: Option<Option<u32>>,
}

struct PendingShape {
    entity: Entity,
    ctm: DMat4,
    reverse_orientation: bool,
    material: MaterialRef,
    /// The names in scope at the statement (for an alpha texture).
    scope: Rc<Scope>,
    media: media::MediaPair,
}

/// A world `plymesh` shape built at the end of the world: read before the file's
/// version was known (how its quads are read depends on it), or with its file read
/// ahead (`ahead`) so that the main thread goes on reading the scene meanwhile.
struct Deferred {
    /// Where its shapes go in `shapes`.
    at: usize,
    pending: PendingShape,
    area_light: Option<u32>,
    ahead: bool,
}

struct PendingObject {
    name: String,
    span: Span,
    shapes: Vec<PendingShape>,
    used: bool,
}

struct Builder {
    reader: StatementReader,
    opts: LoadOptions,
    gs: GraphicsState,
    stack: Vec<(PushKind, GraphicsState, Span)>,
    named_coords: HashMap<String, [DMat4; 2]>,
    in_world: bool,
    /// The `WorldBegin` statement, if read.
    world_begin: Option<Span>,
    /// Whether a `WorldEnd` was read (pbrt-v3 renders nothing without one).
    world_ended: bool,
    /// Type names neither pbrt knows, read before the file's version was settled.
    unknown_names: Vec<(Family, String, Span)>,
    /// `LookAt` statements whose up vector lies along the view, read before the
    /// file's version was settled.
    up_along_view: Vec<Span>,
    render: RenderOptions,
    shapes: Vec<ShapeDesc>,
    /// Per world shape: its `Shape` statement's type name.
    shape_spans: Vec<Span>,
    shape_materials: Vec<MaterialRef>,
    /// Per world shape: its alpha parameters and the scope to resolve them in.
    shape_alphas: Vec<Option<(AlphaParams, Rc<Scope>)>>,
    /// World `plymesh` shapes built at the end of the world, each in its place.
    deferred_shapes: Vec<Deferred>,
    /// PLY files being read on the thread pool meanwhile.
    read_ahead: ReadAhead,
    meshes: Vec<crate::shapes::TriangleMesh>,
    patches: Vec<crate::shapes::PatchMesh>,
    objects: Vec<PendingObject>,
    object_names: HashMap<String, u32>,
    current_object: Option<u32>,
    instance_uses: instances::InstanceUses,
    /// Moving world shapes, each alone in an object placed by its start and end
    /// transforms (as pbrt wraps them).
    moving_shapes: Vec<(u32, [DMat4; 2])>,
    /// `TransformTimes`: when the start and end transforms hold.
    transform_times: [f64; 2],
    /// The first statement that makes something move (a shape, an instance, the camera).
    first_motion: Option<Span>,
    /// `LightSource` statements (inside object definitions too) and the CTM at each.
    pending_lights: Vec<(Entity, DMat4)>,
    area_light_entities: Vec<(Entity, Option<u32>)>,
    /// Indices into `area_light_entities` of the area lights shapes use, by built index.
    area_lights_used: Vec<u32>,
    materials: Vec<PendingMaterial>,
    global_materials: HashMap<String, u32>,
    /// `NamedMaterial` statements whose name was not in scope there, each resolved
    /// (and warned about) once.
    named_refs: Vec<NamedRef>,
    built_materials: Vec<MaterialDesc>,
    textures: Vec<PendingTexture>,
    global_textures: [HashMap<String, u32>; 2],
    built_textures: Vec<TextureDesc>,
    /// Texture lookups one evaluation of each built texture makes.
    texture_lookups: Vec<u64>,
    images: HashMap<PathBuf, Arc<crate::imageio::Texels>>,
    light_images: HashMap<PathBuf, Arc<RgbImage>>,
    grey_images: HashMap<(PathBuf, crate::imageio::Grey), Arc<crate::imageio::Texels>>,
    /// Decided when the whole file is read.
    syntax: Option<Syntax>,
    approximated: Vec<(Span, String, Approx)>,
    attributes: Vec<Entity>,
    options: Vec<(String, String)>,
    warnings: Vec<Diagnostic>,
    skipped: Vec<(Option<Span>, String, String)>,
    motion_warned: bool,
    medium_slots: Vec<media::MediumSlot>,
    medium_names: HashMap<String, u32>,
    /// The media current at `Camera` (pbrt puts the camera in the outside one).
    camera_media: media::MediaPair,
    /// Per pending light: the outside medium current at its statement.
    pending_light_media: Vec<Option<u32>>,
    /// What the scene read so far will need in memory, and the limit it must stay under.
    memory: MemoryBudget,
}

impl Builder {
    fn new(reader: StatementReader, opts: LoadOptions) -> Builder {
        let default_material = PendingMaterial {
            ty: String::new(), // "matte" or "diffuse", decided with the syntax
            name: None,
            params: ParamList::default(),
            span: None,
            scope: Rc::default(),
            built: None,
            building: false,
        };
        Builder {
            memory: opts.limits.memory_budget(),
            reader,
            opts,
            gs: GraphicsState {
                ctm: [DMat4::IDENTITY; 2],
                active: [true; 2],
                reverse_orientation: false,
                material: MaterialRef::Pending(0),
                area_light: None,
                scope: Rc::default(),
                attributes: Rc::default(),
                media: (None, None),
            },
            stack: Vec::new(),
            named_coords: HashMap::new(),
            in_world: false,
            world_begin: None,
            world_ended: false,
            unknown_names: Vec::new(),
            up_along_view: Vec::new(),
            render: RenderOptions::default(),
            shapes: Vec::new(),
            shape_spans: Vec::new(),
            shape_materials: Vec::new(),
            shape_alphas: Vec::new(),
            deferred_shapes: Vec::new(),
            read_ahead: ReadAhead::default(),
            meshes: Vec::new(),
            patches: Vec::new(),
            objects: Vec::new(),
            object_names: HashMap::new(),
            current_object: None,
            instance_uses: Default::default(),
            moving_shapes: Vec::new(),
            transform_times: [0.0, 1.0],
            first_motion: None,
            pending_lights: Vec::new(),
            area_light_entities: Vec::new(),
            area_lights_used: Vec::new(),
            materials: vec![default_material],
            global_materials: HashMap::new(),
            named_refs: Vec::new(),
            built_materials: Vec::new(),
            textures: Vec::new(),
            global_textures: [HashMap::new(), HashMap::new()],
            built_textures: Vec::new(),
            texture_lookups: Vec::new(),
            images: HashMap::new(),
            light_images: HashMap::new(),
            grey_images: HashMap::new(),
            syntax: None,
            approximated: Vec::new(),
            attributes: Vec::new(),
            options: Vec::new(),
            warnings: Vec::new(),
            skipped: Vec::new(),
            motion_warned: false,
            medium_slots: Vec::new(),
            medium_names: HashMap::new(),
            camera_media: (None, None),
            pending_light_media: Vec::new(),
        }
    }

    fn run(&mut self) -> Res<SceneDescription> {
        if let Err(e) = self.read_statements() {
            // Shapes read ahead stand before the failing statement: their errors first.
            self.build_deferred_shapes(true)?;
            return Err(e);
        }
        for (kind, _, span) in self.stack.iter().rev() {
            let what = match kind {
                PushKind::Attribute => "AttributeBegin",
                PushKind::Transform => "TransformBegin",
                PushKind::Object => "ObjectBegin",
                PushKind::Import => continue,
            };
            self.warnings.push(Diagnostic::warning(*span, format!("{what} is never closed")));
        }
        self.finish()
    }

    fn read_statements(&mut self) -> Res<()> {
        while let Some(stmt) = self.reader.next_stmt()? {
            if !self.check_placement(&stmt)? {
                continue;
            }
            if matches!(stmt.kind, StmtKind::WorldEnd) {
                self.world_ended = true;
                if let Some(next) = self.reader.next_stmt()? {
                    let msg = "statements after WorldEnd are ignored (only the first frame of a file is rendered)";
                    self.warnings.push(Diagnostic::warning(next.span, msg));
                }
                break;
            }
            self.apply(stmt)?;
        }
        Ok(())
    }

    /// Whether a statement is where its pbrt takes it (before or after `WorldBegin`):
    /// `true` to apply it. Misplaced, it is an error, but in a v3 file, where pbrt-v3
    /// says so and ignores it: a warning, and `false`.
    fn check_placement(&mut self, stmt: &Stmt) -> Res<bool> {
        use StmtKind as K;
        let options_only = matches!(
            stmt.kind,
            K::Camera(_)
                | K::Sampler(_)
                | K::Film(_)
                | K::PixelFilter(_)
                | K::Integrator(_)
                | K::Accelerator(_)
                | K::TransformTimes(_)
                | K::WorldBegin
        );
        let world_only = matches!(
            stmt.kind,
            K::ReverseOrientation
                | K::AttributeBegin
                | K::AttributeEnd
                | K::TransformBegin
                | K::TransformEnd
                | K::Attribute(_)
                | K::Shape(_)
                | K::ObjectBegin(_)
                | K::ObjectEnd
                | K::ObjectInstance(_)
                | K::LightSource(_)
                | K::AreaLightSource(_)
                | K::Material(_)
                | K::MakeNamedMaterial(_)
                | K::NamedMaterial(_)
                | K::Texture { .. }
                | K::ImportBegin(_)
                | K::WorldEnd
        );
        let when = match (options_only && self.in_world, world_only && !self.in_world) {
            (true, _) => "before",
            (_, true) => "after",
            _ => return Ok(true),
        };
        let word = self.reader.sources.snippet(stmt.span);
        let what = match stmt.kind {
            K::WorldBegin => "WorldBegin is allowed only once".to_string(),
            _ => format!("{word} is allowed only {when} WorldBegin"),
        };
        // A file whose version is not yet known gets the error: ignoring the statement
        // could turn a v4 file's error into a later, puzzling one.
        self.v3_goes_on(self.known_syntax(), stmt.span, what, "ignored, as pbrt-v3 ignores it")?;
        Ok(false)
    }

    pub(super) fn evidence(&mut self, directive: &str, ty: &str, span: Span) {
        if let Some(s) = entities::evidence(directive, ty) {
            self.reader.note_evidence(s, span, format!("{directive} \"{ty}\""));
        }
    }

    fn skip(&mut self, span: Span, what: String, why: String) {
        self.warnings.push(Diagnostic::warning(span, format!("{what}: {why}")));
        self.skipped.push((Some(span), what, why));
    }

    fn apply(&mut self, mut stmt: Stmt) -> Res<()> {
        use StmtKind as K;
        let span = stmt.span;
        self.check_type_name(&stmt.kind)?;
        self.v3_spectrum_files(&mut stmt.kind);
        match stmt.kind {
            K::Identity => self.transform(span, |_| DMat4::IDENTITY),
            K::Translate(d) => self.concat(span, DMat4::from_translation(DVec3::from(d))),
            K::Scale(s) => self.concat(span, DMat4::from_scale(DVec3::from(s))),
            K::Rotate(r) => self.rotate(r, span),
            K::LookAt(v) => self.look_at(&v, span),
            K::Transform(m) => self.transform(span, |_| DMat4::from_cols_array(&m)),
            K::ConcatTransform(m) => self.concat(span, DMat4::from_cols_array(&m)),
            K::CoordinateSystem(name) => self.coordinate_system(name),
            K::CoordSysTransform(name) => self.coord_sys_transform(&name, span),
            K::TransformTimes(t) => {
                self.transform_times = t;
                Ok(())
            }
            K::ActiveTransform(a) => self.active_transform(a),
            K::ReverseOrientation => self.reverse_orientation(),
            K::Option { name, value } => self.option(name, value, span),
            K::ColorSpace(name) => self.color_space(&name, span),
            K::Camera(e) => self.camera(e, span),
            K::Film(e) => self.film(e),
            K::Sampler(e) => self.sampler(e),
            K::Integrator(e) => self.integrator(e),
            K::PixelFilter(e) => self.set(|b| b.render.filter = Some(e)),
            K::Accelerator(e) => self.set(|b| b.render.accelerator = Some(e)),
            K::MakeNamedMedium(e) => self.named_medium(e),
            K::MediumInterface { inside, outside } => self.medium_interface(&inside, &outside, span),
            K::WorldBegin => self.world_begin(span),
            K::WorldEnd => Ok(()),
            K::AttributeBegin => self.push(PushKind::Attribute, span),
            K::TransformBegin => self.push(PushKind::Transform, span),
            K::AttributeEnd => self.pop(PushKind::Attribute, span),
            K::TransformEnd => self.pop(PushKind::Transform, span),
            K::ImportBegin(_) => self.push(PushKind::Import, span),
            K::ImportEnd => self.end_import(span),
            K::Attribute(e) => self.attribute(e),
            K::Shape(e) => self.shape(e, span),
            K::ObjectBegin(name) => self.object_begin(name, span),
            K::ObjectEnd => self.object_end(span),
            K::ObjectInstance(name) => self.object_instance(name, span),
            K::LightSource(e) => self.light(e),
            K::AreaLightSource(e) => self.area_light(e),
            K::Material(e) => self.material(e),
            K::MakeNamedMaterial(e) => self.make_named_material(e),
            K::NamedMaterial(name) => self.named_material(name, span),
            K::Texture { name, ty, class } => self.texture(name, ty, *class),
        }
    }

    // ---- statements -------------------------------------------------------------

    /// A statement that only records something.
    fn set(&mut self, f: impl FnOnce(&mut Self)) -> Res<()> {
        f(self);
        Ok(())
    }

    fn coordinate_system(&mut self, name: String) -> Res<()> {
        self.named_coords.insert(name, self.gs.ctm);
        Ok(())
    }

    fn reverse_orientation(&mut self) -> Res<()> {
        self.gs.reverse_orientation = !self.gs.reverse_orientation;
        Ok(())
    }

    fn rotate(&mut self, [angle, x, y, z]: [f64; 4], span: Span) -> Res<()> {
        let axis = DVec3::new(x, y, z);
        if axis.length_squared() == 0.0 {
            return Err(Diagnostic::error(span, "Rotate: the axis is the zero vector"));
        }
        self.concat(span, DMat4::from_axis_angle(axis.normalize(), angle.to_radians()))
    }

    fn look_at(&mut self, v: &[f64; 9], span: Span) -> Res<()> {
        match look_at(v) {
            Ok(m) => self.concat(span, m),
            // pbrt-v3 goes on with the identity, pbrt-v4 stops: decided with the version.
            Err(LookAtError::UpAlongView) => self.up_along_view(span),
            // DEVIATION(pbrt): robustness. pbrt builds the camera from NaNs here (a
            // NaN image); an error says why.
            Err(LookAtError::EyeAtLook) => {
                Err(Diagnostic::error(span, "LookAt: the eye and the look-at point are the same"))
            }
            Err(LookAtError::ZeroUp) => Err(Diagnostic::error(span, "LookAt: the up vector is zero")),
        }
    }

    fn coord_sys_transform(&mut self, name: &str, span: Span) -> Res<()> {
        match self.named_coords.get(name) {
            Some(&m) => self.transform(span, |i| m[i]),
            None => {
                let why = format!("coordinate system \"{name}\" is not defined; CTM unchanged");
                self.warnings.push(Diagnostic::warning(span, why));
                Ok(())
            }
        }
    }

    fn active_transform(&mut self, a: ActiveTransform) -> Res<()> {
        self.gs.active = match a {
            ActiveTransform::StartTime => [true, false],
            ActiveTransform::EndTime => [false, true],
            ActiveTransform::All => [true, true],
        };
        Ok(())
    }

    fn option(&mut self, name: String, value: String, span: Span) -> Res<()> {
        let key = name.to_ascii_lowercase().replace(['-', '_'], "");
        if key == "seed" {
            let seed = value
                .parse()
                .map_err(|_| Diagnostic::error(span, format!("Option \"seed\": \"{value}\" is not a whole number")))?;
            self.render.seed_option = Some(seed);
        }
        self.options.push((key, value));
        Ok(())
    }

    /// pbrt-v4's `ColorSpace`. One space serves the whole scene: the first one named
    /// (a later, different one is noted); an unknown name is pbrt-v4's error message,
    /// and the space stays.
    fn color_space(&mut self, name: &str, span: Span) -> Res<()> {
        use crate::spectrum::colorspace::ColorSpaceName;
        let Some(space) = ColorSpaceName::from_name(name) else {
            let known: Vec<&str> = ColorSpaceName::ALL.iter().map(|c| c.name()).collect();
            let msg = super::names::unknown("ColorSpace", name, &known);
            self.warnings.push(Diagnostic::warning(span, format!("{msg}; the colour space stays")));
            return Ok(());
        };
        match self.render.color_space {
            None => self.render.color_space = Some(space),
            Some(first) if first != space => {
                self.note(span, format!("ColorSpace \"{name}\" after \"{}\"", first.name()), Approx::ColorSpace)
            }
            Some(_) => {}
        }
        Ok(())
    }

    /// The scene's colour space.
    pub(super) fn space(&self) -> crate::spectrum::colorspace::ColorSpaceName {
        self.render.color_space.unwrap_or(crate::spectrum::colorspace::ColorSpaceName::Srgb)
    }

    fn film(&mut self, e: Entity) -> Res<()> {
        self.evidence("Film", &e.name.clone(), e.name_span);
        self.render.film = Some(e);
        Ok(())
    }

    fn sampler(&mut self, e: Entity) -> Res<()> {
        self.evidence("Sampler", &e.name.clone(), e.name_span);
        self.render.sampler = Some(e);
        Ok(())
    }

    fn integrator(&mut self, e: Entity) -> Res<()> {
        self.evidence("Integrator", &e.name.clone(), e.name_span);
        if let Some(p) = e.params.named("numiterations") {
            self.reader.note_evidence(Syntax::V3, p.span, "\"numiterations\"");
        }
        self.render.integrator = Some(e);
        Ok(())
    }

    fn world_begin(&mut self, span: Span) -> Res<()> {
        self.in_world = true;
        self.world_begin = Some(span);
        self.gs.ctm = [DMat4::IDENTITY; 2];
        self.gs.active = [true; 2];
        self.named_coords.insert("world".into(), self.gs.ctm);
        Ok(())
    }

    fn object_instance(&mut self, name: String, span: Span) -> Res<()> {
        if self.current_object.is_some() {
            let what = "ObjectInstance is not allowed inside an object definition".to_string();
            return self.v3_goes_on(self.known_syntax(), span, what, "ignored, as pbrt-v3 ignores it");
        }
        if self.gs.ctm[0] != self.gs.ctm[1] {
            self.first_motion.get_or_insert(span);
        }
        self.one_more_instance(span)?;
        if self.instance_uses.wants_room() {
            // This statement's and those ahead (the reader is past this one's word).
            self.instance_uses.reserve(1 + self.reader.instance_words_ahead());
        }
        self.instance_uses.push(name, span, self.gs.ctm);
        Ok(())
    }

    fn material(&mut self, e: Entity) -> Res<()> {
        self.evidence("Material", &e.name.clone(), e.name_span);
        let idx = self.add_material(e.name, None, e.params, e.name_span);
        self.gs.material = MaterialRef::Pending(idx);
        Ok(())
    }

    fn named_material(&mut self, name: String, span: Span) -> Res<()> {
        self.gs.material = match self.gs.scope.materials.get(&name) {
            Some(&i) => MaterialRef::Pending(i),
            None => {
                self.named_refs.push(NamedRef { name, span, before: self.gs.material, resolved: None });
                MaterialRef::Named(self.named_refs.len() as u32 - 1)
            }
        };
        Ok(())
    }

    // ---- transforms -------------------------------------------------------------

    // DEVIATION(pbrt): robustness. pbrt composes the CTM in f32; we compose in f64 and round once
    // where geometry is stored, so long transform chains and far-away origins lose less.
    fn transform(&mut self, span: Span, f: impl Fn(usize) -> DMat4) -> Res<()> {
        for i in 0..2 {
            if self.gs.active[i] {
                self.gs.ctm[i] = f(i);
            }
        }
        let m = &self.gs.ctm;
        if !(m[0].is_finite() && m[1].is_finite()) {
            return Err(Diagnostic::error(span, "the transform has non-finite entries"));
        }
        Ok(())
    }

    fn concat(&mut self, span: Span, m: DMat4) -> Res<()> {
        let ctm = self.gs.ctm;
        self.transform(span, |i| ctm[i] * m)
    }

    /// A moving shape inside an object definition (pbrt nests its motion inside the
    /// instance's; here it keeps its start transform).
    fn warn_motion(&mut self, span: Span) {
        if self.current_object.is_some() && self.gs.ctm[0] != self.gs.ctm[1] && !self.motion_warned {
            self.motion_warned = true;
            self.note(span, "ActiveTransform".into(), Approx::Motion);
        }
    }

    fn camera(&mut self, e: Entity, span: Span) -> Res<()> {
        let ctm = self.gs.ctm;
        let inv = [ctm[0].inverse(), ctm[1].inverse()];
        if !(inv[0].is_finite() && ctm[0].determinant() != 0.0) {
            return Err(Diagnostic::error(span, "the camera transform is not invertible"));
        }
        if !(inv[1].is_finite() && ctm[1].determinant() != 0.0) {
            return Err(Diagnostic::error(
                span,
                "the camera's end transform (ActiveTransform EndTime) is not invertible",
            ));
        }
        self.named_coords.insert("camera".into(), inv);
        (self.render.lens_data, self.render.lens_aperture) = match e.name.as_str() {
            "realistic" => (Some(self.lens_file(&e)?), self.lens_aperture(&e)?),
            _ => (None, None),
        };
        self.render.camera = Some((e, ctm[0]));
        self.render.camera_end = (ctm[1] != ctm[0]).then_some((ctm[1], self.transform_times));
        if self.render.camera_end.is_some() {
            self.first_motion.get_or_insert(span);
        }
        self.camera_media = self.gs.media;
        Ok(())
    }

    /// A realistic camera's lens file, read where `lensfile` names it (relative to the
    /// scene file); pbrt stops without one, and so do we.
    fn lens_file(&self, e: &Entity) -> Res<Vec<f64>> {
        let Some(name) = e.params.string("lensfile")? else {
            return Err(Diagnostic::error(e.name_span, "a realistic camera needs a \"lensfile\""));
        };
        let at = e.params.named("lensfile").map_or(e.name_span, |p| p.value_span);
        let path = self.reader.resolve_path(&name);
        let bytes = self.reader.files.read(&path).map_err(|why| Diagnostic::error(at, as_named(why, &path, &name)))?;
        let text = String::from_utf8_lossy(&bytes);
        crate::camera::realistic::read_lens_file(&text)
            .map_err(|why| Diagnostic::error(at, format!("lens file \"{name}\": {why}")))
    }

    /// pbrt-v4's `aperture` for a realistic camera: a built-in shape (`gaussian`,
    /// `square`, `pentagon`, `star`) or an image whose channels are averaged.
    fn lens_aperture(&self, e: &Entity) -> Res<Option<crate::camera::realistic::Aperture>> {
        use crate::camera::realistic::Aperture;
        let Some(name) = e.params.string("aperture")? else { return Ok(None) };
        if let Some(a) = Aperture::builtin(&name) {
            return Ok(Some(a));
        }
        let at = e.params.named("aperture").map_or(e.name_span, |p| p.value_span);
        let path = self.reader.resolve_path(&name);
        let image = crate::imageio::read_image_within(&path, &self.reader.files, crate::imageio::EightBit::Srgb)
            .map_err(|why| Diagnostic::error(at, format!("aperture \"{name}\": {}", as_named(why, &path, &name))))?;
        let mean = image.pixels.iter().map(|p| (p[0] + p[1] + p[2]) / 3.0).collect();
        Aperture::from_rows(image.width, image.height, mean)
            .map(Some)
            .ok_or_else(|| Diagnostic::error(at, format!("aperture \"{name}\": the image lets no light through")))
    }

    // ---- attribute stack --------------------------------------------------------

    fn push(&mut self, kind: PushKind, span: Span) -> Res<()> {
        self.stack.push((kind, self.gs.clone(), span));
        Ok(())
    }

    fn pop(&mut self, kind: PushKind, span: Span) -> Res<()> {
        let name = |k| match k {
            PushKind::Attribute => "AttributeBegin",
            PushKind::Transform => "TransformBegin",
            PushKind::Object => "ObjectBegin",
            PushKind::Import => "Import",
        };
        let Some(&(top, _, _)) = self.stack.last() else {
            let word = self.reader.sources.snippet(span);
            self.warnings.push(Diagnostic::warning(span, format!("{word} without a matching {}; ignored", name(kind))));
            return Ok(());
        };
        if top != kind && kind != PushKind::Import {
            // An ObjectBegin whose definition has ended (by a v3 file's nested
            // ObjectBegin) is an attribute block like any other.
            if top == PushKind::Import || (top == PushKind::Object && self.current_object.is_some()) {
                let word = self.reader.sources.snippet(span);
                let msg = format!("{word} closes a block opened outside the current {}", name(top));
                return Err(Diagnostic::error(span, msg));
            }
            let (word, opened) = (self.reader.sources.snippet(span), name(top));
            let article = if top == PushKind::Transform { "a" } else { "an" };
            self.warnings.push(Diagnostic::warning(span, format!("{word} closes {article} {opened}")));
        }
        let Some((top, saved, _)) = self.stack.last_mut() else { return Ok(()) };
        if *top == PushKind::Transform {
            (self.gs.ctm, self.gs.active) = (saved.ctm, saved.active);
        } else {
            std::mem::swap(&mut self.gs, saved);
        }
        // The state replaced is dropped where it lies.
        self.stack.truncate(self.stack.len() - 1);
        Ok(())
    }

    /// The end of an imported file: blocks it left open are closed (with a warning) and
    /// the state from before the `Import` comes back.
    fn end_import(&mut self, span: Span) -> Res<()> {
        while let Some((kind, saved, open)) = self.stack.pop() {
            if kind == PushKind::Import {
                self.gs = saved;
                if self.current_object.is_some_and(|o| self.objects[o as usize].span.file == span.file) {
                    return Err(Diagnostic::error(span, "an ObjectBegin in an imported file is never closed"));
                }
                return Ok(());
            }
            let word = self.reader.sources.snippet(open);
            self.warnings.push(Diagnostic::warning(open, format!("{word} is never closed in the imported file")));
            if kind == PushKind::Object {
                self.current_object = None;
            }
        }
        Ok(())
    }

    fn attribute(&mut self, e: Entity) -> Res<()> {
        const TARGETS: [&str; 5] = ["shape", "light", "material", "medium", "texture"];
        if !TARGETS.contains(&e.name.as_str()) {
            return Err(Diagnostic::error(
                e.name_span,
                format!("Attribute target \"{}\" is not one of {TARGETS:?}", e.name),
            ));
        }
        let idx = self.attributes.len() as u32;
        let target = e.name.clone();
        e.params.mark_all_used();
        self.attributes.push(e);
        Rc::make_mut(&mut self.gs.attributes).push((target, idx));
        Ok(())
    }

    /// The entity's own parameters, after the `Attribute` defaults for `target`
    /// (lookups find the last occurrence, so the entity's own win).
    fn with_attributes(&self, target: &str, params: ParamList) -> ParamList {
        let inherited: Vec<_> = self
            .gs
            .attributes
            .iter()
            .filter(|(t, _)| t == target)
            .flat_map(|(_, i)| self.attributes[*i as usize].params.params.iter().cloned())
            .collect();
        if inherited.is_empty() {
            return params;
        }
        inherited.iter().for_each(|p| p.mark_used());
        ParamList { params: inherited.into_iter().chain(params.params).collect() }
    }

    // ---- shapes and objects -----------------------------------------------------

    fn shape(&mut self, e: Entity, span: Span) -> Res<()> {
        self.evidence("Shape", &e.name.clone(), e.name_span);
        self.warn_motion(span);
        let params = self.with_attributes("shape", e.params);
        let e = Entity { params, ..e };
        let media = self.media_here(e.name_span);
        let mut pending = PendingShape {
            entity: e,
            ctm: self.gs.ctm[0],
            reverse_orientation: self.gs.reverse_orientation,
            material: self.gs.material,
            scope: self.gs.scope.clone(),
            media,
        };
        if self.current_object.is_none() && self.gs.ctm[0] != self.gs.ctm[1] {
            return self.moving_shape(pending, span);
        }
        match self.current_object {
            Some(obj) => {
                if self.gs.area_light.is_some() {
                    self.warnings.push(Diagnostic::warning(
                        span,
                        "area lights inside object definitions are ignored (as in pbrt)",
                    ));
                }
                self.objects[obj as usize].shapes.push(pending);
            }
            None => {
                let area_light = self.gs.area_light;
                let ply = pending.entity.name == crate::shapes::plymesh::NAME;
                // World shapes only: an object's files are read when it is built, at
                // the end, and only if an instance uses it.
                let ahead = ply && self.read_ply_ahead(&pending.entity.params);
                let unknown_quads = ply && self.known_syntax().is_none();
                // An emitting shape is built in turn: area lights are numbered by first use.
                if unknown_quads || (ahead && area_light.is_none()) {
                    let at = self.shapes.len();
                    self.deferred_shapes.push(Deferred { at, pending, area_light, ahead: !unknown_quads });
                    return Ok(());
                }
                for (shape, alpha) in self.build_shape(&mut pending, area_light)? {
                    self.shapes.push(shape);
                    self.shape_spans.push(pending.entity.name_span);
                    self.shape_materials.push(pending.material);
                    self.shape_alphas.push(alpha.map(|a| (a, pending.scope.clone())));
                }
            }
        }
        Ok(())
    }

    /// Starts reading a `plymesh` shape's file on the thread pool, if its name and the
    /// file's version (how quads are read) are known; whether it started.
    fn read_ply_ahead(&self, p: &ParamList) -> bool {
        // The same parameter `plymesh` reads, looked at without marking it used.
        let name = p.named("filename").filter(|f| f.ty == ParamType::String).map(|f| f.strings());
        let (Some(syntax), Some([name])) = (self.known_syntax(), name) else {
            return false;
        };
        // A displaced v4 mesh has its quads split, as pbrt-v4 splits them to displace.
        let split = syntax == Syntax::V3 || shapes::displaces(p);
        let quads = if split { plymesh::Quads::Split } else { plymesh::Quads::Patches };
        self.read_ahead.start(self.reader.resolve_path(name), quads, &self.reader.files);
        true
    }

    /// A world shape whose transform moves: alone in an object of its own, made with the
    /// identity and placed by an instance with the two transforms, as pbrt does.
    fn moving_shape(&mut self, mut pending: PendingShape, span: Span) -> Res<()> {
        if self.gs.area_light.is_some() {
            // DEVIATION(pbrt): input leniency. pbrt-v4 stops on an animated area light;
            // pbrt-v3 drops the light with a warning, as here for both.
            let why = "an area light on a moving shape is ignored (pbrt-v3 drops it, pbrt-v4 stops)";
            self.warnings.push(Diagnostic::warning(span, why));
        }
        pending.ctm = DMat4::IDENTITY;
        self.first_motion.get_or_insert(span);
        self.one_more_instance(span)?;
        let idx = self.objects.len() as u32;
        let name = format!("moving {} {idx}", pending.entity.name);
        self.objects.push(PendingObject { name, span, shapes: vec![pending], used: true });
        self.moving_shapes.push((idx, self.gs.ctm));
        Ok(())
    }

    /// Where motion is interpolated: pbrt-v3 in world space (the identity); pbrt-v4 in
    /// its rendering space, world moved by the camera's position at mid-shutter
    /// (returned as world-from-render). Fixes the camera's motion times: pbrt-v3 takes
    /// the last `TransformTimes`, pbrt-v4 those current at `Camera`.
    fn motion_frame(&mut self, syntax: Syntax) -> DMat4 {
        if let Some((_, times)) = &mut self.render.camera_end
            && syntax == Syntax::V3
        {
            *times = self.transform_times;
        }
        if syntax == Syntax::V3 {
            return DMat4::IDENTITY;
        }
        let start = self.render.camera.as_ref().map_or(DMat4::IDENTITY, |c| c.1).inverse();
        let eye = match &self.render.camera_end {
            Some((end, times)) => {
                let world_from_camera = AnimatedTransform::new(start, end.inverse(), *times);
                world_from_camera.at((times[0] + times[1]) / 2.0).w_axis.truncate()
            }
            None => start.w_axis.truncate(),
        };
        self.render.world_from_render = DMat4::from_translation(eye);
        self.render.world_from_render
    }

    /// The file's pbrt version, if known yet: given on the command line, or settled by
    /// what has been read so far.
    fn known_syntax(&self) -> Option<Syntax> {
        self.opts.syntax.or(self.syntax).or(self.reader.evidence.as_ref().map(|e| e.0))
    }

    /// Builds the deferred world shapes read ahead (`ahead`) or the others, each in its
    /// place. They are built in file order, so the first error is the one reading them
    /// in turn meets first; the ones read ahead come before the end of the world's
    /// other checks, as their errors did when they were built at their statements.
    fn build_deferred_shapes(&mut self, ahead: bool) -> Res<()> {
        let (now, later) = std::mem::take(&mut self.deferred_shapes).into_iter().partition(|d| d.ahead == ahead);
        self.deferred_shapes = later;
        let mut built = Vec::with_capacity(now.len());
        for mut d in now {
            let shapes = self.build_shape(&mut d.pending, d.area_light)?;
            built.push((d, shapes));
        }
        // From the last, so that each earlier place stays where it was.
        for (d, shapes) in built.into_iter().rev() {
            for (k, (shape, alpha)) in shapes.into_iter().enumerate() {
                self.shapes.insert(d.at + k, shape);
                self.shape_spans.insert(d.at + k, d.pending.entity.name_span);
                self.shape_materials.insert(d.at + k, d.pending.material);
                self.shape_alphas.insert(d.at + k, alpha.map(|a| (a, d.pending.scope.clone())));
            }
        }
        Ok(())
    }

    /// Geometry, transform and flags, and the alpha parameters, one entry per shape made
    /// (a pbrt-v4 PLY file of triangles and quads makes two); the material and alpha are
    /// resolved later. Empty when the shape type is unsupported (warned and listed as
    /// skipped).
    fn build_shape(
        &mut self,
        s: &mut PendingShape,
        area_light: Option<u32>,
    ) -> Res<Vec<(ShapeDesc, Option<AlphaParams>)>> {
        let at = s.entity.name_span;
        let resolve = |n: &str| self.reader.resolve_path(n);
        let quads = match self.known_syntax() {
            Some(Syntax::V3) => plymesh::Quads::Split,
            _ => plymesh::Quads::Patches,
        };
        let mut warn = Vec::new();
        let (files, ahead) = (&self.reader.files, &self.read_ahead);
        let syntax = self.known_syntax();
        let mut ctx = ShapeContext { resolve: &resolve, quads, files, ahead, warn: &mut warn, syntax };
        let built = shapes::read(&s.entity.name, &mut s.entity.params, at, &mut ctx);
        self.warnings.append(&mut warn);
        let p = &s.entity.params;
        let Some(built) = built? else {
            let what = format!("Shape \"{}\"", s.entity.name);
            self.skip(at, what, checks::why_left_out(Family::Shape, &s.entity.name));
            return Ok(Vec::new());
        };
        if built.is_nothing() {
            return Ok(Vec::new()); // left out as pbrt-v3 leaves it out (warned)
        }
        let alpha = alpha_params(p)?;
        typed::finish_params(p, &mut self.warnings)?;
        let area_light = match built {
            Built::Curves(_) if area_light.is_some() => {
                let why = "pbrt cannot sample curves and stops; the curve is rendered without emission";
                self.skip(at, "an area light on a curve".into(), why.into());
                None
            }
            _ => area_light,
        };
        let mut geometries = Vec::new();
        self.add_geometry(built, s, &mut geometries)?;
        let area_light = area_light.map(|a| self.use_area_light(a));
        let shape = |geometry| ShapeDesc {
            geometry,
            object_to_world: s.ctm,
            reverse_orientation: s.reverse_orientation,
            material: 0,
            area_light,
            alpha: None,
            media: crate::media::MediumInterface { inside: s.media.0, outside: s.media.1 },
        };
        Ok(geometries.into_iter().map(|g| (shape(g), alpha.clone())).collect())
    }

    /// Transforms and checks built geometry, stores its meshes, and appends what shapes
    /// refer to.
    fn add_geometry(&mut self, built: Built, s: &PendingShape, out: &mut Vec<Geometry>) -> Res<()> {
        let (p, at) = (&s.entity.params, s.entity.name_span);
        let where_ = p.named("P").or(p.named("filename")).map_or(at, |x| x.span);
        let geometry = match built {
            Built::Quadric(q) => Geometry::Quadric(q),
            Built::Mesh { mesh: mut m, kind, filename } => {
                mesh::transform(&mut m, &s.ctm);
                self.check_mesh(where_, mesh::validate(&m), mesh::degenerate_warning(&m))?;
                self.need_memory(where_, |n| {
                    n.triangles += m.triangle_count() as u64;
                    n.vertices += m.p.len() as u64;
                })?;
                self.meshes.push(m);
                Geometry::Mesh { mesh: self.meshes.len() as u32 - 1, kind, filename }
            }
            Built::Patches { mesh: mut m, kind, filename } => {
                mesh::transform_patches(&mut m, &s.ctm);
                self.check_mesh(where_, mesh::validate_patches(&m), mesh::degenerate_patches_warning(&m))?;
                self.need_memory(where_, |n| {
                    n.triangles += 2 * m.patch_count() as u64;
                    n.vertices += m.p.len() as u64;
                })?;
                self.patches.push(m);
                Geometry::Patches { mesh: self.patches.len() as u32 - 1, kind, filename }
            }
            Built::Curves(c) => Geometry::Curves { curves: std::sync::Arc::new(c) },
            Built::Several(parts) => {
                return parts.into_iter().try_for_each(|b| self.add_geometry(b, s, out));
            }
            Built::Displaced(d) => {
                let mesh = self.displace(*d, s.scope.clone(), &s.ctm)?;
                return self.add_geometry(mesh, s, out);
            }
        };
        out.push(geometry);
        Ok(())
    }

    /// Counts an instance (an `ObjectInstance`, or a moving shape, which is rendered as
    /// one) against the memory budget and the most a scene can hold.
    fn one_more_instance(&mut self, at: Span) -> Res<()> {
        if self.instance_uses.len() + self.moving_shapes.len() >= super::instances::MAX_INSTANCES {
            let most = super::instances::MAX_INSTANCES;
            return Err(Diagnostic::error(at, format!("a scene holds at most {most} instances")));
        }
        self.need_memory(at, |n| n.instances += 1)
    }

    /// Adds to what the scene needs in memory; an error at `at` once that is over the
    /// limit.
    fn need_memory(&mut self, at: Span, add: impl FnOnce(&mut MemoryNeed)) -> Res<()> {
        self.memory.add(add).map_err(|e| Diagnostic::error(at, e))
    }

    /// Adds the film's pixels to what the scene needs, at the `Film` statement (or
    /// `WorldBegin` where the film is the default one).
    fn need_film_memory(&mut self, film: &super::Film) -> Res<()> {
        let pixels = film.pixel_count();
        let Some(at) = self.render.film.as_ref().map(|e| e.name_span).or(self.world_begin) else { return Ok(()) };
        self.need_memory(at, |n| n.pixels = pixels)
    }

    /// An invalid mesh is a located error; a degenerate one a located warning.
    fn check_mesh(&mut self, at: Span, valid: Result<(), String>, degenerate: Option<String>) -> Res<()> {
        valid.map_err(|e| Diagnostic::error(at, e))?;
        self.warnings.extend(degenerate.map(|w| Diagnostic::warning(at, w)));
        Ok(())
    }

    fn object_begin(&mut self, name: String, span: Span) -> Res<()> {
        if self.current_object.is_some() {
            // pbrt-v3 goes on: the first definition gets nothing more, this one begins.
            let what = "ObjectBegin inside another object definition".to_string();
            self.v3_goes_on(self.known_syntax(), span, what, "that definition ends here, as in pbrt-v3")?;
        }
        self.push(PushKind::Object, span)?;
        let idx = self.objects.len() as u32;
        if self.object_names.insert(name.clone(), idx).is_some() {
            self.warnings.push(Diagnostic::warning(
                span,
                format!("object \"{name}\" is redefined; later instances use this definition"),
            ));
        }
        self.objects.push(PendingObject { name, span, shapes: Vec::new(), used: false });
        self.current_object = Some(idx);
        Ok(())
    }

    fn object_end(&mut self, span: Span) -> Res<()> {
        if self.current_object.is_none() {
            // pbrt-v3 goes on to the AttributeEnd its ObjectEnd includes.
            let what = "ObjectEnd without ObjectBegin".to_string();
            if self.stack.is_empty() {
                return self.v3_goes_on(self.known_syntax(), span, what, "ignored, as pbrt-v3 ignores it");
            }
            self.v3_goes_on(self.known_syntax(), span, what, "it ends an attribute block, as in pbrt-v3")?;
            return self.pop(PushKind::Object, span);
        }
        if self.stack.last().map(|s| s.0) != Some(PushKind::Object) {
            // pbrt-v3 ends the definition and pops the open block as its ObjectEnd's
            // AttributeEnd; the ObjectBegin's entry stays, for a later AttributeEnd.
            let what = "ObjectEnd inside an unclosed AttributeBegin or TransformBegin".to_string();
            let v3_does = "the definition ends and the block is closed, as in pbrt-v3";
            self.v3_goes_on(self.known_syntax(), span, what, v3_does)?;
            self.current_object = None;
            return self.pop(PushKind::Attribute, span);
        }
        self.pop(PushKind::Object, span)?;
        self.current_object = None;
        Ok(())
    }

    // ---- lights -----------------------------------------------------------------

    /// A `LightSource`. Inside an object definition too, as both pbrts take it: one
    /// light, placed by the CTM there, whether or how often the object is instanced.
    fn light(&mut self, e: Entity) -> Res<()> {
        if let Some(p) = e.params.named("mapname") {
            self.reader.note_evidence(Syntax::V3, p.span, "\"mapname\"");
        }
        if self.gs.ctm[0] != self.gs.ctm[1] {
            let why = "lights do not move (as in pbrt): the start transform is used";
            self.warnings.push(Diagnostic::warning(e.name_span, why));
        }
        let params = self.with_attributes("light", e.params);
        self.pending_lights.push((Entity { params, ..e }, self.gs.ctm[0]));
        let medium = self.media_here(e.name_span).1;
        self.pending_light_media.push(medium);
        Ok(())
    }

    fn area_light(&mut self, e: Entity) -> Res<()> {
        self.evidence("AreaLightSource", &e.name.clone(), e.name_span);
        if !crate::lights::diffuse::NAMES.contains(&e.name.as_str()) {
            let what = format!("AreaLightSource \"{}\"", e.name);
            self.skip(e.name_span, what, checks::why_left_out(Family::AreaLight, &e.name));
            self.gs.area_light = None;
            return Ok(());
        }
        let params = self.with_attributes("light", e.params);
        self.area_light_entities.push((Entity { params, ..e }, None));
        self.gs.area_light = Some(self.area_light_entities.len() as u32 - 1);
        Ok(())
    }

    /// The built index of area light `i`, given on its first use by a shape.
    fn use_area_light(&mut self, i: u32) -> u32 {
        let (_, built) = &mut self.area_light_entities[i as usize];
        if let Some(b) = built {
            return *b;
        }
        self.area_lights_used.push(i);
        let idx = self.area_lights_used.len() as u32 - 1;
        *built = Some(idx);
        idx
    }

    // ---- materials and textures -------------------------------------------------

    fn add_material(&mut self, ty: String, name: Option<String>, params: ParamList, span: Span) -> u32 {
        let params = self.with_attributes("material", params);
        self.materials.push(PendingMaterial {
            ty,
            name,
            params,
            span: Some(span),
            scope: self.gs.scope.clone(),
            built: None,
            building: false,
        });
        self.materials.len() as u32 - 1
    }

    fn make_named_material(&mut self, e: Entity) -> Res<()> {
        let ty = match e.params.string("type")? {
            Some(ty) => ty,
            None => {
                // pbrt-v3 says so and makes a material of type "", which it takes as "none".
                let what = format!("MakeNamedMaterial \"{}\" needs a \"string type\"", e.name);
                let v3_does = "what uses it has no surface (material \"none\"), as in pbrt-v3";
                self.v3_goes_on(self.known_syntax(), e.name_span, what, v3_does)?;
                String::new()
            }
        };
        self.evidence("MakeNamedMaterial", &ty, e.name_span);
        if self.global_materials.contains_key(&e.name) {
            self.warnings.push(Diagnostic::warning(e.name_span, format!("named material \"{}\" is redefined", e.name)));
        }
        let idx = self.add_material(ty, Some(e.name.clone()), e.params, e.name_span);
        Rc::make_mut(&mut self.gs.scope).materials.insert(e.name.clone(), idx);
        self.global_materials.insert(e.name, idx);
        Ok(())
    }

    fn texture(&mut self, name: String, ty: String, class: Entity) -> Res<()> {
        let kind = match ty.as_str() {
            "float" => 0,
            "spectrum" => 1,
            "color" => {
                self.reader.note_evidence(Syntax::V3, class.name_span, "Texture type \"color\"");
                1
            }
            other => {
                // pbrt-v3 says so and defines no texture.
                let what = format!("texture type \"{other}\" is not \"float\" or \"spectrum\"");
                class.params.mark_all_used();
                let v3_does = "no texture is defined, as in pbrt-v3";
                return self.v3_goes_on(self.known_syntax(), class.name_span, what, v3_does);
            }
        };
        let params = self.with_attributes("texture", class.params);
        let idx = self.textures.len() as u32;
        self.textures.push(PendingTexture {
            name: name.clone(),
            ty: if kind == 0 { "float" } else { "spectrum" }.into(),
            class: class.name,
            params,
            span: class.name_span,
            scope: self.gs.scope.clone(),
            ctm: self.gs.ctm[0],
            built: None,
        });
        let scope = Rc::make_mut(&mut self.gs.scope);
        if kind == 0 { &mut scope.float_textures } else { &mut scope.spectrum_textures }.insert(name.clone(), idx);
        self.global_textures[kind].insert(name, idx);
        Ok(())
    }

    // DEVIATION(pbrt): input leniency (no valid scene renders differently). pbrt-v3 scopes names and has no forward
    // references; pbrt-v4 has forward references and no scoping. Real scenes of each version need their rule, so a name
    // is looked up in scope first and then among all definitions.
    fn resolve_material(&mut self, r: &MaterialRef) -> Res<u32> {
        let idx = self.material_definition(*r)?;
        self.build_material(idx)
    }

    /// The material definition a reference stands for. A v3 name defined nowhere
    /// stands for the material before its statement (pbrt-v3 reports an error and
    /// keeps that one). Each statement is resolved and warned about once, so a run of
    /// such statements costs its length, not its length per shape.
    fn material_definition(&mut self, r: MaterialRef) -> Res<u32> {
        let (mut at, mut walked) = (r, Vec::new());
        let idx = loop {
            let k = match at {
                MaterialRef::Pending(i) => break i,
                MaterialRef::Named(k) => k as usize,
            };
            if let Some(i) = self.named_refs[k].resolved {
                break i;
            }
            walked.push(k);
            let NamedRef { ref name, span, before, .. } = self.named_refs[k];
            match self.global_materials.get(name).copied() {
                Some(i) => {
                    if self.syntax() == Syntax::V3 {
                        let (name, pbrt) = (name.clone(), "pbrt-v3 reports an error and keeps the current material");
                        self.warn_material_out_of_scope(&name, span, i, pbrt);
                    }
                    break i;
                }
                None => {
                    let what = format!("named material \"{name}\" is not defined");
                    let v3_does = "the current material is kept, as pbrt-v3 keeps it";
                    self.v3_goes_on(Some(self.syntax()), span, what, v3_does)?;
                    at = before;
                }
            }
        };
        walked.into_iter().for_each(|k| self.named_refs[k].resolved = Some(idx));
        Ok(idx)
    }

    /// The warning for a v3 reference to named material `material` that pbrt-v3 does
    /// not find at `at`; `pbrt` says what pbrt-v3 does instead.
    pub(super) fn warn_material_out_of_scope(&mut self, name: &str, at: Span, material: u32, pbrt: &str) {
        let defined = self.materials[material as usize].span.map(|d| self.reader.sources.location(d).to_string());
        let msg = format!(
            "named material \"{name}\" is not in scope here (defined at {}, inside an AttributeBegin that has ended or later in the file); {pbrt}, this renderer uses that definition",
            defined.unwrap_or_default()
        );
        self.warnings.push(Diagnostic::warning(at, msg));
    }

    // ---- the end ----------------------------------------------------------------

    fn finish(&mut self) -> Res<SceneDescription> {
        let syntax = self.opts.syntax.or(self.reader.evidence.as_ref().map(|e| e.0)).unwrap_or(Syntax::V4);
        self.syntax = Some(syntax);
        self.build_deferred_shapes(true)?;
        self.settle_unknown_names(syntax)?;
        self.settle_up_along_view(syntax)?;
        self.build_deferred_shapes(false)?;
        self.materials[0].ty =
            if syntax == Syntax::V3 { crate::materials::matte::NAME } else { crate::materials::diffuse::NAME }.into();
        let object_of_name = self.resolve_instances(syntax)?;
        let (mut objects, remap) = self.build_objects()?;
        let frame = self.motion_frame(syntax);
        let instances = self.instances(&object_of_name, &remap, frame);
        self.resolve_world_shapes()?;
        self.drop_interface_emitters();
        let bugs = self.pbrt_bugs(syntax, &objects);
        let mut lights = self.build_lights()?;
        let area_lights = self.build_area_lights()?;
        let (media, camera_medium) = self.resolve_media(&mut objects, &mut lights)?;
        self.render.emitting_media = media.iter().any(|m| m.kind.emissive());
        let r = self.resolve_options(syntax)?;
        self.need_film_memory(&r.film)?;
        self.report_left_out();
        // In file order, whatever the order they were found in.
        self.skipped.sort_by_key(|(span, _, _)| span.map(|s| (s.file.0, s.start)));
        self.approximated.sort_by_key(|(span, _, _)| (span.file.0, span.start));
        // Last: every other error comes first, in file order, as the file is read.
        self.check_world_begin()?;
        self.check_world_end(syntax);
        let warnings = self.warnings_in_file_order();
        let sources = &self.reader.sources;
        let mut film = r.film;
        let filename_param = self.render.film.as_ref().and_then(|e| e.params.named("filename"));
        film.filename_location = filename_param.map(|p| sources.location(p.value_span).to_string());
        film.location = self.render.film.as_ref().map(|e| sources.location(e.name_span).to_string());
        let evidence = self
            .reader
            .evidence
            .as_ref()
            .map(|(s, span, what)| format!("{}: {what} ({})", sources.location(*span), s.name()));
        Ok(SceneDescription {
            spectral: self.render.spectral,
            color_space: self.space(),
            syntax,
            syntax_evidence: if self.opts.syntax.is_some() { Some("--syntax".into()) } else { evidence },
            camera: r.camera,
            film,
            integrator: r.integrator,
            shapes: std::mem::take(&mut self.shapes),
            objects,
            instances: Arc::new(instances),
            meshes: std::mem::take(&mut self.meshes).into_iter().map(Arc::new).collect(),
            patches: std::mem::take(&mut self.patches).into_iter().map(Arc::new).collect(),
            lights,
            area_lights,
            media,
            camera_medium,
            materials: std::mem::take(&mut self.built_materials),
            textures: std::mem::take(&mut self.built_textures),
            options: std::mem::take(&mut self.options),
            base_dir: self.reader.base_dir().to_path_buf(),
            warnings: warnings.iter().map(|d| Located::resolve(sources, d.span, &d.message)).collect(),
            skipped: self.located_skipped(),
            approximated: self.located_approximated(),
            pbrt_bugs: bugs::located(&bugs, self.opts.fixes, sources),
            fixes: self.opts.fixes,
            limits: self.opts.limits,
            memory: self.memory,
            inputs: self.reader.files.list(),
        })
    }

    /// The world shapes' materials and alpha masks, resolved now that every name is
    /// known.
    /// The reader's and the builder's warnings, interleaved in file order (stable for
    /// equal spans).
    fn warnings_in_file_order(&mut self) -> Vec<Diagnostic> {
        let mut warnings: Vec<Diagnostic> = std::mem::take(&mut self.reader.warnings);
        warnings.append(&mut self.warnings);
        warnings.sort_by_key(|d| d.span.map(|s| (s.file.0, s.start)));
        warnings
    }

    fn resolve_world_shapes(&mut self) -> Res<()> {
        let world_materials = std::mem::take(&mut self.shape_materials);
        let resolved: Vec<u32> = world_materials.iter().map(|r| self.resolve_material(r)).collect::<Res<_>>()?;
        for (shape, m) in self.shapes.iter_mut().zip(resolved) {
            shape.material = m;
        }
        for (i, a) in std::mem::take(&mut self.shape_alphas).into_iter().enumerate() {
            if let Some((a, scope)) = a {
                self.shapes[i].alpha = self.resolve_alpha(&a, scope)?;
            }
        }
        Ok(())
    }

    /// Camera, film and integrator, with their approximations noted and their unused
    /// parameters warned.
    fn resolve_options(&mut self, syntax: Syntax) -> Res<super::options::Resolved> {
        let mut approx = Vec::new();
        self.render.spectral = Colour::chosen(self.opts.colour, syntax) == Colour::Spectral;
        let r = self.render.resolve(syntax, &self.opts.limits, &mut self.warnings, &mut approx)?;
        for (at, what, how) in approx {
            self.note(at, what, how);
        }
        if let Some((c, _)) = &self.render.camera {
            typed::finish_params(&c.params, &mut self.warnings)?;
        }
        for e in [&self.render.film, &self.render.integrator].into_iter().flatten() {
            typed::finish_params(&e.params, &mut self.warnings)?;
        }
        Ok(r)
    }

    fn located_skipped(&self) -> Vec<Skipped> {
        let sources = &self.reader.sources;
        let locate = |(span, what, why): &(Option<Span>, String, String)| {
            let l = Located::resolve(sources, *span, "");
            Skipped { file: l.file, line: l.line, column: l.column, what: what.clone(), why: why.clone() }
        };
        self.skipped.iter().map(locate).collect()
    }

    fn located_approximated(&self) -> Vec<Approximated> {
        let sources = &self.reader.sources;
        let locate = |(span, what, how): &(Span, String, Approx)| {
            let l = Located::resolve(sources, Some(*span), "");
            Approximated {
                file: l.file,
                line: l.line,
                column: l.column,
                what: what.clone(),
                how: how.how().to_string(),
            }
        };
        self.approximated.iter().map(locate).collect()
    }

    /// The instances the file names, then the moving world shapes' (as pbrt wraps
    /// them), objects numbered as built (`remap`); `frame` is the motion frame.
    fn instances(&mut self, object_of_name: &[u32], remap: &[u32], frame: DMat4) -> Instances {
        let times = self.transform_times;
        let mut instances = std::mem::take(&mut self.instance_uses).resolve(object_of_name, remap, frame, times);
        // Moving world shapes come after the instances the file names.
        for (obj, [m0, m1]) in std::mem::take(&mut self.moving_shapes) {
            // pbrt-v4 interpolates a shape from its own space in rendering space.
            let motion = (m0 != m1).then(|| AnimatedTransform::framed(m0, m1, times, frame, DMat4::IDENTITY));
            instances.push(remap[obj as usize], m0, motion);
        }
        instances
    }

    /// The object each name instances use stands for (the last defined by that name),
    /// by name index, and marks them used. Objects may be defined after their
    /// instances (v4); a name never defined is an error at its first use (in a v3
    /// file, an empty object and a warning).
    fn resolve_instances(&mut self, syntax: Syntax) -> Res<Vec<u32>> {
        let mut found: Vec<Option<u32>> =
            self.instance_uses.names().map(|n| self.object_names.get(n).copied()).collect();
        if syntax == Syntax::V3 {
            self.stand_in_for_undefined_objects(&mut found);
        }
        if let Some(e) = self.instance_uses.first_undefined(&found) {
            return Err(e);
        }
        let objects: Vec<u32> = found.into_iter().flatten().collect();
        for &obj in &objects {
            self.objects[obj as usize].used = true;
        }
        Ok(objects)
    }

    /// pbrt-v3 reports an error at an `ObjectInstance` of a name no `ObjectBegin`
    /// defines and goes on without it: each such name stands for an empty object here,
    /// with a warning at its first use.
    fn stand_in_for_undefined_objects(&mut self, found: &mut [Option<u32>]) {
        let missing: Vec<(String, Span)> =
            self.instance_uses.undefined(found).map(|(name, _, span)| (name.clone(), *span)).collect();
        let mut stand_ins = missing.into_iter().map(|(name, span)| {
            let why =
                format!("object \"{name}\" is not defined; its instances are left out, as pbrt-v3 leaves them out");
            self.warnings.push(Diagnostic::warning(span, why));
            self.objects.push(PendingObject { name, span, shapes: Vec::new(), used: true });
            self.objects.len() as u32 - 1
        });
        for slot in found.iter_mut().filter(|f| f.is_none()) {
            *slot = stand_ins.next();
        }
    }

    /// Builds the objects that are instanced (opening their mesh files); returns them
    /// and the map from definition index to built index.
    fn build_objects(&mut self) -> Res<(Vec<ObjectDesc>, Vec<u32>)> {
        let mut built = Vec::new();
        let mut remap = vec![u32::MAX; self.objects.len()];
        for (i, slot) in remap.iter_mut().enumerate() {
            if !self.objects[i].used {
                continue;
            }
            let mut pending = std::mem::take(&mut self.objects[i].shapes);
            let mut shapes = Vec::with_capacity(pending.len());
            for s in &mut pending {
                for (mut shape, alpha) in self.build_shape(s, None)? {
                    shape.material = self.resolve_material(&s.material)?;
                    if let Some(a) = alpha {
                        shape.alpha = self.resolve_alpha(&a, s.scope.clone())?;
                    }
                    shapes.push(shape);
                }
            }
            *slot = built.len() as u32;
            built.push(ObjectDesc { name: self.objects[i].name.clone(), shapes });
        }
        Ok((built, remap))
    }

    fn report_left_out(&mut self) {
        let mut left = Vec::new();
        for o in self.objects.iter().filter(|o| !o.used) {
            left.push((o.span, format!("ObjectBegin \"{}\"", o.name), "never instanced".to_string()));
        }
        for m in self.materials.iter().filter(|m| m.built.is_none() && m.name.is_some()) {
            let name = m.name.clone().unwrap_or_default();
            left.push((m.span.unwrap_or_default(), format!("MakeNamedMaterial \"{name}\""), "never used".to_string()));
        }
        for t in self.textures.iter().filter(|t| t.built.is_none()) {
            let why = "not used by any material that is built".to_string();
            left.push((t.span, format!("Texture \"{}\"", t.name), why));
        }
        self.skipped.extend(left.into_iter().map(|(s, what, why)| (Some(s), what, why)));
    }
}

/// A file error naming the file as the scene does, not by the path it resolved to, so
/// the message is the same wherever the scene is read from.
fn as_named(why: impl ToString, path: &std::path::Path, name: &str) -> String {
    why.to_string().replace(&path.display().to_string(), name)
}

/// Why `LookAt` has no camera frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LookAtError {
    /// The eye is the look-at point: no viewing direction.
    EyeAtLook,
    /// The up vector is zero.
    ZeroUp,
    /// The up vector lies along the viewing direction.
    UpAlongView,
}

/// pbrt's LookAt: camera-from-world for eye, look and up, or why there is none.
pub fn look_at(v: &[f64; 9]) -> Result<DMat4, LookAtError> {
    let (eye, look, up) = (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]), DVec3::new(v[6], v[7], v[8]));
    let dir = (look - eye).try_normalize().ok_or(LookAtError::EyeAtLook)?;
    let up = up.try_normalize().ok_or(LookAtError::ZeroUp)?;
    let right = up.cross(dir).try_normalize().ok_or(LookAtError::UpAlongView)?;
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(right.extend(0.0), new_up.extend(0.0), dir.extend(0.0), eye.extend(1.0));
    Ok(world_from_camera.inverse())
}
