//! The scene description: what a pbrt file says, after the graphics state has been
//! applied, defaults filled in, names resolved and the unused left out.
//!
//! [`load_scene`] runs the parser and the [`builder`]; the result is plain data that the
//! renderer turns into render-ready structures. Only what the scene references is
//! built: never-instanced objects, never-used named materials and textures are listed
//! in [`SceneDescription::skipped`] and their files are never opened.

pub mod builder;
pub mod entities;
pub mod instances;
pub mod names;
pub mod options;
pub mod shapes;

use crate::math::bounds::transform_bounds;
use crate::parser::Syntax;
use crate::parser::error::Located;
use crate::shapes::{PatchMesh, Quadric, TriangleMesh};
use glam::{DMat4, DVec3};

pub use crate::approx::Approx;
pub use crate::lights::{AreaLightDesc, EnvMapDesc, LightDesc, LightKind};
pub use crate::materials::{CoatBase, Coated, MaterialDesc, MaterialKind, Metal, MixRule, RoughnessRemap, TexValue};
pub use crate::textures::{Mapping2D, Octaves, TextureDesc, TextureKind, TextureSite, UvMapping, Wrap};
pub use builder::{LoadOptions, load_scene, load_scene_from_bytes};
pub use instances::{Instances, Placed};
pub use options::{Camera, CameraKind, Film, Integrator};

/// A shape's geometry: a quadric, a triangle mesh stored in [`SceneDescription::meshes`]
/// or a bilinear patch mesh stored in [`SceneDescription::patches`].
#[derive(Clone, Debug, PartialEq)]
pub enum Geometry {
    Quadric(Quadric),
    /// `kind` is the scene's shape name: `trianglemesh`, `plymesh` or `objmesh`.
    Mesh {
        mesh: u32,
        kind: &'static str,
        filename: Option<String>,
    },
    /// Bilinear patches; `kind` is `bilinearmesh`, or `plymesh` for a pbrt-v4 PLY
    /// file's quads.
    Patches {
        mesh: u32,
        kind: &'static str,
        filename: Option<String>,
    },
    /// A `curve` statement's Bézier segments, in object space.
    Curves {
        curves: std::sync::Arc<crate::shapes::curve::Curves>,
    },
}

/// One created shape.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeDesc {
    pub geometry: Geometry,
    /// The CTM at the `Shape` statement: world-from-object for world shapes,
    /// instance-from-object inside an `ObjectBegin` definition. Mesh vertices are stored
    /// with it already applied, as pbrt does.
    pub object_to_world: DMat4,
    pub reverse_orientation: bool,
    /// Index into [`SceneDescription::materials`].
    pub material: u32,
    /// Index into [`SceneDescription::area_lights`].
    pub area_light: Option<u32>,
    /// Where the shape is cut away, if anywhere.
    pub alpha: Option<ShapeAlpha>,
    /// The media on its two sides (`MediumInterface`), indices into
    /// [`SceneDescription::media`]. Only a transition changes a ray's medium; an area
    /// light emits into these either way.
    pub media: crate::media::MediumInterface,
}

/// A shape's alpha mask: rays pass through where it cuts the surface away.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeAlpha {
    /// Tested by every ray.
    pub alpha: TexValue,
    /// v3 `shadowalpha`: tested by shadow rays only, as well as `alpha`.
    pub shadow: Option<TexValue>,
    pub rule: AlphaRule,
}

/// What an alpha value means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlphaRule {
    /// pbrt-v3: 0 cuts, anything else is opaque.
    ZeroCuts,
    /// pbrt-v4: a ray passes with probability 1 − α (decided by a hash of the ray, so
    /// the same ray always gets the same answer).
    Stochastic,
}

impl ShapeDesc {
    pub fn kind(&self) -> &'static str {
        match &self.geometry {
            Geometry::Quadric(q) => q.name(),
            Geometry::Mesh { kind, .. } | Geometry::Patches { kind, .. } => kind,
            Geometry::Curves { .. } => crate::shapes::curve::NAME,
        }
    }

    /// det of the upper 3×3 of object-to-world < 0.
    pub fn swaps_handedness(&self) -> bool {
        glam::DMat3::from_mat4(self.object_to_world).determinant() < 0.0
    }
}

/// An `ObjectBegin` definition that is instanced at least once.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectDesc {
    pub name: String,
    pub shapes: Vec<ShapeDesc>,
}

/// Something the scene asked for that is not built, and why.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Skipped {
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub what: String,
    pub why: String,
}

/// Something rendered other than as the file says, and how ([`Approx::how`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Approximated {
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub what: String,
    pub how: String,
}

/// The loaded scene.
#[derive(Debug)]
pub struct SceneDescription {
    pub syntax: Syntax,
    /// Whether paths carry sampled wavelengths (`spectrum::transport`), as pbrt-v4's
    /// do, rather than RGB, as pbrt-v3's do.
    pub spectral: bool,
    /// pbrt-v4's `ColorSpace`: what RGB values mean, what spectra reduce to, what the
    /// film writes (sRGB unless the file names another).
    pub color_space: crate::spectrum::colorspace::ColorSpaceName,
    /// Where the syntax was decided from (`file:line:col: what`), if not defaulted.
    pub syntax_evidence: Option<String>,
    pub camera: Camera,
    pub film: Film,
    pub integrator: Integrator,
    /// World shapes (not inside object definitions), in creation order.
    pub shapes: Vec<ShapeDesc>,
    pub objects: Vec<ObjectDesc>,
    /// Shared with the accelerator, which keeps only what rays need beside it.
    pub instances: std::sync::Arc<Instances>,
    /// Shared with the render scene, which reads them and keeps its own reordered
    /// copies of the triangle meshes.
    pub meshes: Vec<std::sync::Arc<TriangleMesh>>,
    pub patches: Vec<std::sync::Arc<PatchMesh>>,
    pub lights: Vec<LightDesc>,
    pub area_lights: Vec<AreaLightDesc>,
    /// The named media that are rendered (`MakeNamedMedium`), in order of first mention.
    pub media: Vec<crate::media::MediumDesc>,
    /// The medium the camera sits in.
    pub camera_medium: Option<u32>,
    pub materials: Vec<MaterialDesc>,
    pub textures: Vec<TextureDesc>,
    /// `Option` statements (v4), name → raw value.
    pub options: Vec<(String, String)>,
    /// The top-level file's directory, against which texture and map names resolve.
    pub base_dir: std::path::PathBuf,
    pub warnings: Vec<Located>,
    pub skipped: Vec<Skipped>,
    pub approximated: Vec<Approximated>,
    /// The pbrt bugs this scene would show, at the statements that trigger them.
    pub pbrt_bugs: Vec<crate::fixes::PbrtBug>,
    /// The pbrt bugs the render fixes (`--fix`): none by default.
    pub fixes: crate::fixes::Fixes,
    /// The limits the scene was loaded under (the renderer checks its overrides too).
    pub limits: crate::limits::Limits,
    /// Its estimated peak memory and the limit it was held to ([`crate::memory`]).
    pub memory: crate::memory::MemoryBudget,
    /// Every file the scene was made from (the top-level file, Includes, meshes,
    /// images, SPD files), sorted by path: what a checkpoint's fingerprint hashes.
    pub inputs: Vec<crate::limits::InputFile>,
}

/// A shape placed in the world: instances expanded, with world-from-object.
pub struct PlacedShape<'a> {
    pub shape: &'a ShapeDesc,
    pub object_to_world: DMat4,
    pub instance: Option<u32>,
}

impl SceneDescription {
    /// Every shape in creation order, world shapes first, then each instance's shapes.
    pub fn placed_shapes(&self) -> impl Iterator<Item = PlacedShape<'_>> {
        let world =
            self.shapes.iter().map(|s| PlacedShape { shape: s, object_to_world: s.object_to_world, instance: None });
        let inst = self.instances.iter().enumerate().flat_map(move |(i, inst)| {
            self.objects[inst.object() as usize].shapes.iter().map(move |s| PlacedShape {
                shape: s,
                object_to_world: inst.world_from_instance() * s.object_to_world,
                instance: Some(i as u32),
            })
        });
        world.chain(inst)
    }

    /// Bounds of a shape in its own stored space (meshes: the stored vertices).
    pub fn local_bounds(&self, s: &ShapeDesc) -> Option<[DVec3; 2]> {
        match &s.geometry {
            Geometry::Quadric(q) => Some(transform_bounds(&s.object_to_world, q.object_bounds())),
            Geometry::Mesh { mesh, .. } => self.meshes[*mesh as usize].bounds(),
            Geometry::Patches { mesh, .. } => self.patches[*mesh as usize].bounds(),
            Geometry::Curves { curves } => Some(transform_bounds(&s.object_to_world, curves.object_bounds())),
        }
    }

    /// World area of one placed shape.
    pub fn placed_area(&self, p: &PlacedShape) -> f64 {
        let s = p.shape;
        // Mesh vertices are stored transformed by the shape's own CTM already: an
        // instance adds the map from there to the world.
        let extra = || glam::DMat3::from_mat4(p.object_to_world * s.object_to_world.inverse());
        match &s.geometry {
            Geometry::Quadric(q) => q.world_area(glam::DMat3::from_mat4(p.object_to_world)),
            Geometry::Mesh { mesh, .. } if p.instance.is_some() => self.meshes[*mesh as usize].area_under(extra()),
            Geometry::Mesh { mesh, .. } => self.meshes[*mesh as usize].area(),
            Geometry::Patches { mesh, .. } if p.instance.is_some() => self.patches[*mesh as usize].area_under(extra()),
            Geometry::Patches { mesh, .. } => self.patches[*mesh as usize].area(),
            Geometry::Curves { curves } => curves.area_under(glam::DMat3::from_mat4(p.object_to_world)),
        }
    }

    /// World bounds of one placed shape.
    pub fn world_bounds_of(&self, p: &PlacedShape) -> Option<[DVec3; 2]> {
        let local = self.local_bounds(p.shape)?;
        match p.instance {
            None => Some(local),
            Some(i) => Some(transform_bounds(&self.instances.get(i as usize).world_from_instance(), local)),
        }
    }

    /// Union of all shapes' world bounds (`None` for an empty scene). On all threads:
    /// a large scene's meshes and instances took a tenth of a second on one (unions are
    /// exact, so the result does not depend on how the work is split).
    pub fn world_bounds(&self) -> Option<[DVec3; 2]> {
        use rayon::prelude::*;
        let object_bounds: Vec<Option<[DVec3; 2]>> = self
            .objects
            .par_iter()
            .map(|o| o.shapes.iter().filter_map(|s| self.local_bounds(s)).reduce(union))
            .collect();
        let world = self.shapes.par_iter().filter_map(|s| self.local_bounds(s));
        let inst = self
            .instances
            .par_iter()
            .filter_map(|i| object_bounds[i.object() as usize].map(|b| transform_bounds(&i.world_from_instance(), b)));
        world.chain(inst).reduce_with(union)
    }

    /// Shapes whose geometry is a triangle mesh count their triangles.
    pub fn triangle_count(&self, s: &ShapeDesc) -> usize {
        match &s.geometry {
            Geometry::Mesh { mesh, .. } => self.meshes[*mesh as usize].triangle_count(),
            Geometry::Quadric(_) | Geometry::Patches { .. } | Geometry::Curves { .. } => 0,
        }
    }

    /// Primitives of a shape: one per triangle or patch, one for a quadric, one per curve
    /// piece. An emitting
    /// shape is that many lights.
    pub fn prim_count(&self, s: &ShapeDesc) -> usize {
        match &s.geometry {
            Geometry::Mesh { mesh, .. } => self.meshes[*mesh as usize].triangle_count(),
            Geometry::Patches { mesh, .. } => self.patches[*mesh as usize].patch_count(),
            Geometry::Quadric(_) => 1,
            Geometry::Curves { curves } => curves.pieces.len(),
        }
    }
}

/// The box holding both boxes.
pub fn union(a: [DVec3; 2], b: [DVec3; 2]) -> [DVec3; 2] {
    [a[0].min(b[0]), a[1].max(b[1])]
}
