//! `Shape` statements to geometry: quadric parameters with defaults, and the three mesh
//! sources. Unsupported shape types return `None` (the caller skips them with a warning).
//!
//! ```text
//! Shape "sphere" "float radius" 2 "float zmax" 1        # zmin defaults to -radius
//! Shape "plymesh" "string filename" "geometry/mesh.ply"
//! Shape "objmesh" "string filename" "model.obj"          # extension: OBJ through tobj
//! Shape "bilinearmesh" "point3 P" [...] "integer indices" [...]   # v4
//! ```

use super::{mesh, obj, ply};
use crate::limits::{Files, Limits};
use crate::parser::error::Diagnostic;
use crate::parser::params::{FloatValue, ParamList, ParamType};
use crate::parser::source::Span;
use crate::shapes::{
    Cone, Cylinder, Disk, Hyperboloid, Paraboloid, PatchMesh, Quadric, Sphere, TriangleMesh, loopsubdiv,
};
use glam::Vec3;
use std::path::PathBuf;

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
    /// A pbrt-v4 PLY file of triangles and quads: two shapes, as in pbrt-v4.
    Several(Vec<Built>),
}

type Res<T> = Result<T, Diagnostic>;

/// Builds a shape's geometry in object space; `resolve` maps scene-relative file names;
/// `quads` says how a PLY file's quads are read (the file's pbrt version decides).
pub fn build(
    ty: &str,
    p: &ParamList,
    span: Span,
    resolve: &dyn Fn(&str) -> PathBuf,
    quads: ply::Quads,
    files: &Files,
    warn: &mut Vec<Diagnostic>,
) -> Res<Option<Built>> {
    let q = |q| Ok(Some(Built::Quadric(q)));
    match ty {
        "sphere" => {
            let r = positive(p, "radius", 1.0, span)?;
            q(Quadric::Sphere(Sphere::new(r, f(p, "zmin", -r)?, f(p, "zmax", r)?, f(p, "phimax", 360.0)?)))
        }
        "cylinder" => {
            let r = positive(p, "radius", 1.0, span)?;
            q(Quadric::Cylinder(Cylinder::new(r, f(p, "zmin", -1.0)?, f(p, "zmax", 1.0)?, f(p, "phimax", 360.0)?)))
        }
        "disk" => {
            let r = positive(p, "radius", 1.0, span)?;
            let ri = f(p, "innerradius", 0.0)?;
            if !(0.0..=r).contains(&ri) {
                return Err(Diagnostic::error(span, format!("disk: innerradius {ri} must lie in [0, radius {r}]")));
            }
            q(Quadric::Disk(Disk::new(f(p, "height", 0.0)?, r, ri, f(p, "phimax", 360.0)?)))
        }
        "cone" => {
            let r = positive(p, "radius", 1.0, span)?;
            let h = f(p, "height", 1.0)?;
            if h == 0.0 {
                return Err(Diagnostic::error(span, "cone: height must be nonzero"));
            }
            q(Quadric::Cone(Cone::new(h, r, f(p, "phimax", 360.0)?)))
        }
        "paraboloid" => {
            let r = positive(p, "radius", 1.0, span)?;
            let (z0, z1) = (f(p, "zmin", 0.0)?, f(p, "zmax", 1.0)?);
            if z0.max(z1) == 0.0 {
                return Err(Diagnostic::error(span, "paraboloid: zmax must be nonzero"));
            }
            q(Quadric::Paraboloid(Paraboloid::new(r, z0, z1, f(p, "phimax", 360.0)?)))
        }
        "hyperboloid" => {
            let p1 = Vec3::from(p.point3("p1")?.unwrap_or([0.0; 3]));
            let p2 = Vec3::from(p.point3("p2")?.unwrap_or([1.0; 3]));
            if !(p1.is_finite() && p2.is_finite()) {
                return Err(Diagnostic::error(span, "hyperboloid: p1 and p2 must be finite"));
            }
            let h = Hyperboloid::new(p1, p2, f(p, "phimax", 360.0)?).map_err(|e| Diagnostic::error(span, e))?;
            q(Quadric::Hyperboloid(h))
        }
        "trianglemesh" => {
            let m = mesh::from_params(p, span, warn)?;
            Ok(Some(Built::Mesh { mesh: m, kind: "trianglemesh", filename: None }))
        }
        "bilinearmesh" => {
            let m = mesh::patches_from_params(p, span, warn)?;
            Ok(Some(Built::Patches { mesh: m, kind: "bilinearmesh", filename: None }))
        }
        "loopsubdiv" => loop_subdiv(p, span, &files.limits, warn).map(Some),
        "plymesh" | "objmesh" => file_mesh(ty, p, span, resolve, quads, files, warn).map(Some),
        _ => Ok(None),
    }
}

/// `loopsubdiv`: the control mesh refined to its limit surface now, so the renderer
/// sees an ordinary triangle mesh with normals.
fn loop_subdiv(p: &ParamList, span: Span, limits: &Limits, warn: &mut Vec<Diagnostic>) -> Res<Built> {
    let need = |what: &str| Diagnostic::error(span, format!("loopsubdiv needs {what}"));
    let positions = p.array("P", ParamType::Point3)?.ok_or_else(|| need("\"point3 P\""))?;
    let indices = p.array("indices", ParamType::Integer)?.ok_or_else(|| need("\"integer indices\""))?;
    let n_p = positions.values.len() / 3;
    let indices = mesh::check_indices(indices.ints().to_vec(), n_p, indices.value_span, warn)?;
    // v3 also reads "nlevels"; both default to 3.
    let levels_at = p.find("levels", &[ParamType::Integer]).or(p.find("nlevels", &[ParamType::Integer]));
    let levels = p.int("levels")?.or(p.int("nlevels")?).unwrap_or(3).max(0) as u32;
    let at = levels_at.map_or(span, |l| l.value_span);
    let tris = loopsubdiv::triangle_count(indices.len() / 3, levels).unwrap_or(u64::MAX);
    if tris > limits.triangles {
        let what = format!("loopsubdiv: {levels} levels make {tris} triangles, which");
        return Err(Diagnostic::error(at, Limits::over(what, "triangles", limits.triangles)));
    }
    let points: Vec<[f32; 3]> = positions.floats().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let s = loopsubdiv::subdivide(&points, &indices, levels)
        .map_err(|e| Diagnostic::error(p.named("indices").map_or(span, |i| i.value_span), e))?;
    p.mark_known(&["scheme"]);
    let mesh = TriangleMesh { p: s.p, indices: s.indices, n: Some(s.n), ..Default::default() };
    Ok(Built::Mesh { mesh, kind: "loopsubdiv", filename: None })
}

fn file_mesh(
    ty: &str,
    p: &ParamList,
    span: Span,
    resolve: &dyn Fn(&str) -> PathBuf,
    quads: ply::Quads,
    files: &Files,
    warn: &mut Vec<Diagnostic>,
) -> Res<Built> {
    let name =
        p.string("filename")?.ok_or_else(|| Diagnostic::error(span, format!("{ty} needs \"string filename\"")))?;
    let at = p.named("filename").map_or(span, |f| f.value_span);
    let path = resolve(&name);
    if let Some(d) = p.named("displacement") {
        d.mark_used();
        warn.push(Diagnostic::warning(d.span, "displacement is not supported; the mesh is used undisplaced"));
    }
    p.mark_known(&["edgelength"]);
    if ty == "objmesh" {
        let mesh = obj::load(&path, files).map_err(|e| Diagnostic::error(at, e))?;
        return Ok(Built::Mesh { mesh, kind: "objmesh", filename: Some(name) });
    }
    let m = ply::load(&path, quads, files).map_err(|e| {
        // Read errors name the file already; format errors get its name first.
        Diagnostic::error(at, if e.starts_with("cannot read") { e } else { format!("{name}: {e}") })
    })?;
    let has_triangles = !m.triangles.indices.is_empty();
    let tris = Built::Mesh { mesh: m.triangles, kind: "plymesh", filename: Some(name.clone()) };
    Ok(match m.patches {
        None => tris,
        Some(mesh) => {
            let patches = Built::Patches { mesh, kind: "plymesh", filename: Some(name) };
            if has_triangles { Built::Several(vec![tris, patches]) } else { patches }
        }
    })
}

fn f(p: &ParamList, name: &str, default: f32) -> Res<f32> {
    let v = p.float(name)?.unwrap_or(default);
    if !v.is_finite() {
        let span = p.named(name).map(|p| p.value_span).unwrap_or_default();
        return Err(Diagnostic::error(span, format!("\"{name}\" must be finite, not {v}")));
    }
    Ok(v)
}

fn positive(p: &ParamList, name: &str, default: f32, span: Span) -> Res<f32> {
    let v = f(p, name, default)?;
    if v <= 0.0 {
        let at = p.named(name).map_or(span, |p| p.value_span);
        return Err(Diagnostic::error(at, format!("\"{name}\" must be positive, not {v}")));
    }
    Ok(v)
}

/// A shape's `alpha` and (v3) `shadowalpha` as written: a constant or a float texture's
/// name, each with its span. Resolved once the file is read (`builder::typed`).
#[derive(Clone, Debug, Default)]
pub struct AlphaParams {
    pub alpha: Option<(FloatValue, Span)>,
    pub shadow: Option<(FloatValue, Span)>,
}

/// The shape's alpha parameters, `None` when neither is given.
pub fn alpha_params(p: &ParamList) -> Res<Option<AlphaParams>> {
    let get = |name: &str| -> Res<Option<(FloatValue, Span)>> {
        Ok(p.float_or_texture(name)?.map(|v| (v, p.named(name).map(|x| x.value_span).unwrap_or_default())))
    };
    let a = AlphaParams { alpha: get("alpha")?, shadow: get("shadowalpha")? };
    Ok((a.alpha.is_some() || a.shadow.is_some()).then_some(a))
}
