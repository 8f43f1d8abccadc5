//! Shapes with pbrt's parameters: the six quadrics (each with its defaults, clamps and
//! swaps applied in `new`), triangle meshes and bilinear patch meshes, and the shapes
//! pbrt turns into triangle meshes at load (loop subdivision; pbrt-v3's height fields
//! and NURBS). [`set`] is where the renderer dispatches on a shape's family.
//!
//! ```text
//! Shape "sphere"      "float radius" 1 "float zmin" -1 "float zmax" 1 "float phimax" 360
//! Shape "cylinder"    "float radius" 1 "float zmin" -1 "float zmax" 1 "float phimax" 360
//! Shape "disk"        "float height" 0 "float radius" 1 "float innerradius" 0 "float phimax" 360
//! Shape "cone"        "float height" 1 "float radius" 1 "float phimax" 360            # v3
//! Shape "paraboloid"  "float radius" 1 "float zmin" 0 "float zmax" 1 "float phimax" 360 # v3
//! Shape "hyperboloid" "point p1" [0 0 0] "point p2" [1 1 1] "float phimax" 360        # v3
//! Shape "bilinearmesh" "point3 P" [...] "integer indices" [...]                        # v4
//! Shape "curve" "point3 P" [...] "string type" "flat" "float width" 1
//! Shape "heightfield" "integer nu" 2 "integer nv" 2 "float Pz" [...]                   # v3
//! Shape "nurbs" "integer nu" 4 "integer uorder" 3 "float uknots" [...] ... "point P" [...] # v3
//! ```
//! Every quadric is described by a parametric map p(u, v) on [0,1]² with z as its axis,
//! φ = u·φmax. [`Quadric::point`], [`Quadric::dpdu`] and [`Quadric::dpdv`] evaluate it in
//! `f64`; areas of transformed shapes integrate |dp/du × dp/dv| in world space.

/// `match` on a [`Quadric`], binding each kind's shape to the same name: the one place
/// that turns a quadric into its own file's code.
macro_rules! dispatch_quadric {
    ($q:expr, $s:ident => $e:expr) => {
        match $q {
            $crate::shapes::Quadric::Sphere($s) => $e,
            $crate::shapes::Quadric::Cylinder($s) => $e,
            $crate::shapes::Quadric::Disk($s) => $e,
            $crate::shapes::Quadric::Cone($s) => $e,
            $crate::shapes::Quadric::Paraboloid($s) => $e,
            $crate::shapes::Quadric::Hyperboloid($s) => $e,
        }
    };
}

pub mod bilinear;
pub mod cone;
pub mod curve;
pub mod cylinder;
pub mod disk;
pub mod displace;
pub mod heightfield;
pub mod hyperboloid;
pub mod loopsubdiv;
pub mod mesh_params;
pub mod nurbs;
pub mod objmesh;
pub mod paraboloid;
pub mod params;
mod pbrt_sampling;
pub mod plymesh;
pub mod quadric;
pub mod read_ahead;
pub mod sampling;
pub mod set;
pub mod sphere;
pub mod triangle;

pub use bilinear::{PatchHit, PatchMesh};
pub use cone::Cone;
pub use cylinder::Cylinder;
pub use disk::Disk;
pub use hyperboloid::Hyperboloid;
pub use paraboloid::Paraboloid;
pub use quadric::{QuadricHit, QuadricShape};
pub use sampling::{QuadricSampler, ShapeSample};
pub use set::{LocalHit, Piece, ShapeRef, ShapeSet};
pub use sphere::Sphere;
#[cfg(target_arch = "x86_64")]
pub use triangle::edge_candidates8;
pub use triangle::{MeshFlags, TriangleHit, TriangleMesh, WatertightRay, corner_lanes_of, edge_candidates, watertight};

use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::values::Res;
use glam::{DMat3, DMat4, DVec3};

/// `phimax` in degrees, clamped to [0, 360], as radians (pbrt: `Radians(Clamp(phiMax, 0, 360))`).
pub fn phi_max_radians(degrees: f32) -> f32 {
    degrees.clamp(0.0, 360.0).to_radians()
}

/// The six quadric shapes.
#[derive(Clone, Debug, PartialEq)]
pub enum Quadric {
    Sphere(Sphere),
    Cylinder(Cylinder),
    Disk(Disk),
    Cone(Cone),
    Paraboloid(Paraboloid),
    Hyperboloid(Hyperboloid),
}

impl Quadric {
    /// The shape's name in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            Quadric::Sphere(_) => sphere::NAME,
            Quadric::Cylinder(_) => cylinder::NAME,
            Quadric::Disk(_) => disk::NAME,
            Quadric::Cone(_) => cone::NAME,
            Quadric::Paraboloid(_) => paraboloid::NAME,
            Quadric::Hyperboloid(_) => hyperboloid::NAME,
        }
    }

    /// The quadric as Mitsuba's own shape under `m`, where it has one (full spheres,
    /// cylinders and disks under similarity transforms); `None`: tessellate it.
    pub fn mitsuba(&self, m: &DMat4, reverse: bool) -> Option<crate::mitsuba::GeometryOut> {
        match self {
            Quadric::Sphere(s) => s.mitsuba(m, reverse),
            Quadric::Cylinder(s) => s.mitsuba(m, reverse),
            Quadric::Disk(s) => s.mitsuba(m, reverse),
            Quadric::Cone(_) | Quadric::Paraboloid(_) | Quadric::Hyperboloid(_) => None,
        }
    }

    /// Its parameters after defaults and clamps, for `check --shapes`.
    pub fn params(&self) -> Vec<(&'static str, ShapeParam)> {
        dispatch_quadric!(self, s => s.params())
    }

    pub fn phi_max(&self) -> f64 {
        dispatch_quadric!(self, s => s.phi_max as f64)
    }

    /// Object-space bounds, pbrt's (not tightened for φmax < 360°).
    pub fn object_bounds(&self) -> [DVec3; 2] {
        dispatch_quadric!(self, s => s.object_bounds())
    }

    /// Object-space surface area.
    pub fn area(&self) -> f64 {
        dispatch_quadric!(self, s => s.area())
    }

    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        dispatch_quadric!(self, s => s.point(u, v))
    }

    /// ∂p/∂u = φmax · (−y, x, 0) for every quadric.
    pub fn dpdu(&self, u: f64, v: f64) -> DVec3 {
        let p = self.point(u, v);
        self.phi_max() * DVec3::new(-p.y, p.x, 0.0)
    }

    pub fn dpdv(&self, u: f64, v: f64) -> DVec3 {
        dispatch_quadric!(self, s => s.dpdv(u, v))
    }

    /// Surface area after the linear map `m` (the upper 3×3 of object-to-world).
    /// Similarity maps scale the closed form; any other map integrates
    /// |m·dp/du × m·dp/dv| over (u, v) by Gauss–Legendre quadrature.
    // DEVIATION(pbrt): no image difference. pbrt reports object-space areas even under scales; `check`
    // reports the true world-space area, and so does exact light sampling (pbrt's
    // object-space one is the default: `--fix shape-sampling`, `pbrt_sampling`).
    pub fn world_area(&self, m: DMat3) -> f64 {
        match similarity_scale(m) {
            Some(s2) => s2 * self.area(),
            None => integrate_unit_square(|u, v| (m * self.dpdu(u, v)).cross(m * self.dpdv(u, v)).length()),
        }
    }
}

/// s² when `m` = s·(rotation or reflection), else `None`.
pub(crate) fn similarity_scale(m: DMat3) -> Option<f64> {
    let g = m.transpose() * m;
    let s2 = (g.x_axis.x + g.y_axis.y + g.z_axis.z) / 3.0;
    let off = g - DMat3::from_diagonal(DVec3::splat(s2));
    let err = off.x_axis.abs().max_element().max(off.y_axis.abs().max_element()).max(off.z_axis.abs().max_element());
    (err <= 1e-12 * s2.abs()).then_some(s2)
}

/// 8-point Gauss–Legendre nodes and weights on [-1, 1].
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_2, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_2, 0.101_228_536_290_376_26),
];

/// ∫∫ f over [0,1]² by composite Gauss–Legendre (8 panels × 8 points per axis).
pub fn integrate_unit_square(f: impl Fn(f64, f64) -> f64) -> f64 {
    const PANELS: usize = 8;
    let nodes: Vec<(f64, f64)> = (0..PANELS)
        .flat_map(|p| {
            GL8.iter().map(move |&(x, w)| {
                let h = 1.0 / PANELS as f64;
                (h * (p as f64 + 0.5 * (x + 1.0)), 0.5 * h * w)
            })
        })
        .collect();
    let mut sum = 0.0;
    for &(v, wv) in &nodes {
        for &(u, wu) in &nodes {
            sum += wu * wv * f(u, v);
        }
    }
    sum
}

/// ∫ f over [0,1] by the same rule (for areas of surfaces of revolution).
pub fn integrate_unit_interval(f: impl Fn(f64) -> f64) -> f64 {
    integrate_unit_square(|_, v| f(v))
}

/// What a `Shape` statement produced.
pub enum Built {
    Quadric(Quadric),
    Mesh {
        mesh: TriangleMesh,
        kind: &'static str,
        filename: Option<String>,
    },
    Patches {
        mesh: PatchMesh,
        kind: &'static str,
        filename: Option<String>,
    },
    /// A pbrt-v4 PLY file of triangles and quads: two shapes, as in pbrt-v4. None at
    /// all ([`Built::NOTHING`]): a shape pbrt-v3 leaves out.
    Several(Vec<Built>),
    /// A mesh file (a v4 `plymesh`, its quads split, or an `objmesh`) that a float
    /// texture displaces: the scene resolves the texture and calls
    /// [`displace::displace`].
    Displaced(Box<Displaced>),
    /// Bézier curves, in object space.
    Curves(curve::Curves),
}

impl Built {
    pub const NOTHING: Built = Built::Several(Vec::new());

    pub fn is_nothing(&self) -> bool {
        matches!(self, Built::Several(parts) if parts.is_empty())
    }
}

/// A mesh to displace, as read: `texture` named at `at`, refined to `edge_length`.
pub struct Displaced {
    pub mesh: TriangleMesh,
    pub filename: String,
    pub texture: String,
    pub at: Span,
    pub edge_length: f32,
}

/// What reading a shape needs besides its parameters.
pub struct ShapeContext<'a> {
    /// Maps scene-relative file names to paths.
    pub resolve: &'a dyn Fn(&str) -> std::path::PathBuf,
    /// How a PLY file's quads are read (the file's pbrt version decides).
    pub quads: plymesh::Quads,
    pub files: &'a crate::limits::Files,
    /// PLY files already being read (see [`read_ahead`]).
    pub ahead: &'a read_ahead::ReadAhead,
    pub warn: &'a mut Vec<Diagnostic>,
    /// The file's pbrt version, where known by now.
    pub syntax: Option<crate::parser::Syntax>,
}

impl ShapeContext<'_> {
    /// A shape pbrt-v3 reports (`what`, at `at`) and leaves out, where pbrt-v4 stops:
    /// in a file known as v3 a warning and nothing to build, else the error.
    pub fn left_out_by_v3(&mut self, p: &ParamList, at: Span, what: String) -> Res<Built> {
        if self.syntax != Some(crate::parser::Syntax::V3) {
            return Err(Diagnostic::error(at, what));
        }
        p.mark_all_used();
        self.warn.push(Diagnostic::warning(at, format!("{what}; the shape is left out, as pbrt-v3 leaves it out")));
        Ok(Built::NOTHING)
    }
}

/// A `Shape` type: the name scenes use and its reader.
pub struct ShapeType {
    pub name: &'static str,
    /// Gets the list to itself: a reader may move long arrays out of it.
    pub read: fn(&mut ShapeContext, &mut ParamList, Span) -> Res<Built>,
}

/// A quadric's reader as a shape reader.
macro_rules! quadric_type {
    ($m:ident) => {
        ShapeType { name: $m::NAME, read: |_, p, span| $m::read(p, span).map(Built::Quadric) }
    };
}

/// Whether Mitsuba's own shapes can stand for a quadric under this linear part: a
/// similarity that keeps handedness.
fn native_in_mitsuba(m3: DMat3) -> bool {
    similarity_scale(m3).is_some() && m3.determinant() > 0.0
}

/// One parameter of a shape as it is after defaults and clamps (for reports).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShapeParam {
    Float(f32),
    /// An angle, stored in radians and reported in degrees as scenes write it.
    Angle(f32),
    Point([f32; 3]),
}

/// The quadrics' names, in the order `check` counts them.
pub const QUADRIC_NAMES: [&str; 6] =
    [sphere::NAME, cylinder::NAME, disk::NAME, cone::NAME, paraboloid::NAME, hyperboloid::NAME];

/// The pbrt version a shape type name proves, for syntax detection: pbrt-v4 dropped
/// the cone, paraboloid, hyperboloid, heightfield and nurbs and added the bilinear mesh.
pub fn evidence(ty: &str) -> Option<crate::parser::Syntax> {
    use crate::parser::Syntax::{V3, V4};
    match ty {
        cone::NAME | paraboloid::NAME | hyperboloid::NAME | heightfield::NAME | nurbs::NAME => Some(V3),
        bilinear::NAME => Some(V4),
        _ => None,
    }
}

/// Every `Shape` type we render.
pub const REGISTRY: [ShapeType; 14] = [
    quadric_type!(sphere),
    quadric_type!(cylinder),
    quadric_type!(disk),
    quadric_type!(cone),
    quadric_type!(paraboloid),
    quadric_type!(hyperboloid),
    ShapeType { name: triangle::NAME, read: triangle::read },
    ShapeType { name: bilinear::NAME, read: bilinear::read },
    ShapeType { name: loopsubdiv::NAME, read: |c, p, at| loopsubdiv::read(c, p, at) },
    ShapeType { name: plymesh::NAME, read: |c, p, at| plymesh::read(c, p, at) },
    ShapeType { name: objmesh::NAME, read: |c, p, at| objmesh::read(c, p, at) },
    ShapeType { name: heightfield::NAME, read: |c, p, at| heightfield::read(c, p, at) },
    ShapeType { name: nurbs::NAME, read: |c, p, at| nurbs::read(c, p, at) },
    ShapeType { name: curve::NAME, read: |c, p, at| curve::read(c, p, at) },
];

/// Builds a shape's geometry in object space, or `None` for a type we do not render
/// (the caller skips it with a warning).
pub fn read(ty: &str, p: &mut ParamList, span: Span, ctx: &mut ShapeContext) -> Res<Option<Built>> {
    let Some(t) = REGISTRY.iter().find(|t| t.name == ty) else { return Ok(None) };
    (t.read)(ctx, p, span).map(Some)
}

/// A mesh file's `filename` (required), where it was written, and its path.
fn mesh_file(ctx: &mut ShapeContext, ty: &str, p: &ParamList, span: Span) -> Res<(String, Span, std::path::PathBuf)> {
    let name =
        p.string("filename")?.ok_or_else(|| Diagnostic::error(span, format!("{ty} needs \"string filename\"")))?;
    let at = p.named("filename").map_or(span, |f| f.value_span);
    let path = (ctx.resolve)(&name);
    Ok((name, at, path))
}

/// Whether a mesh file names a `"texture displacement"` (pbrt-v4 reads only a texture
/// there: another type leaves the mesh as it is).
pub fn displaces(p: &ParamList) -> bool {
    p.named("displacement").is_some_and(|d| d.ty == crate::parser::params::ParamType::Texture)
}

/// A mesh file's `"texture displacement"` and `"float edgelength"` (pbrt-v4's default
/// 1): the mesh as read, to be displaced by the scene, or as it is without one.
fn displaced(mesh: TriangleMesh, kind: &'static str, filename: String, p: &ParamList) -> Res<Built> {
    let Some(d) = p.find("displacement", &[crate::parser::params::ParamType::Texture]) else {
        return Ok(Built::Mesh { mesh, kind, filename: Some(filename) });
    };
    let [texture] = <[String; 1]>::try_from(d.strings().to_vec())
        .map_err(|_| Diagnostic::error(d.span, "\"texture displacement\" needs exactly one name"))?;
    let edge_length = p.float("edgelength")?.unwrap_or(1.0);
    Ok(Built::Displaced(Box::new(Displaced { mesh, filename, texture, at: d.span, edge_length })))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadrature_is_exact_for_polynomials() {
        let i = integrate_unit_square(|u, v| u * u * v * v * v);
        assert!((i - 1.0 / 12.0).abs() < 1e-14);
    }

    #[test]
    fn closed_form_areas_match_quadrature_under_identity() {
        let shapes = [
            Quadric::Sphere(Sphere::new(2.0, -0.5, 1.5, 270.0)),
            Quadric::Cylinder(Cylinder::new(1.5, -1.0, 2.0, 200.0)),
            Quadric::Disk(Disk::new(0.5, 2.0, 0.5, 300.0)),
            Quadric::Cone(Cone::new(2.0, 0.75, 270.0)),
            Quadric::Paraboloid(Paraboloid::new(1.0, 0.25, 2.0, 360.0)),
        ];
        for s in shapes {
            let numeric = integrate_unit_square(|u, v| s.dpdu(u, v).cross(s.dpdv(u, v)).length());
            assert!((numeric - s.area()).abs() < 1e-12 * s.area(), "{}: {numeric} vs {}", s.name(), s.area());
        }
    }

    #[test]
    fn world_area_scales_by_square_and_integrates_otherwise() {
        let s = Quadric::Sphere(Sphere::new(1.0, -1.0, 1.0, 360.0));
        let a = s.world_area(DMat3::from_diagonal(DVec3::splat(-2.0)));
        assert!((a - 16.0 * std::f64::consts::PI).abs() < 1e-6 * a, "{a}");
        // A disk scaled by (2, 3, 5): area π·2·3.
        let d = Quadric::Disk(Disk::new(0.0, 1.0, 0.0, 360.0));
        let a = d.world_area(DMat3::from_diagonal(DVec3::new(2.0, 3.0, 5.0)));
        assert!((a - 6.0 * std::f64::consts::PI).abs() < 1e-6 * a, "{a}");
    }
}
