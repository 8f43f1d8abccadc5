//! `Shape "objmesh" "string filename" "model.obj"` — an extension of ours (pbrt has no
//! OBJ support): every object and group of the file becomes one triangle mesh, with
//! normals and texture coordinates when every part has them. Read through tobj.

use super::{Built, ShapeContext};
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::shapes::TriangleMesh;
use crate::values::Res;

pub fn load(path: &std::path::Path, files: &crate::limits::Files) -> Result<TriangleMesh, String> {
    let opts = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let bytes = files.read(path)?;
    // Materials (.mtl) are not used: the scene gives the material.
    let (models, _materials) = tobj::load_obj_buf(&mut &bytes[..], &opts, |_| Ok(Default::default()))
        .map_err(|e| format!("cannot read OBJ \"{}\": {e}", path.display()))?;
    let mut mesh = TriangleMesh::default();
    let all_normals = models.iter().all(|m| !m.mesh.normals.is_empty());
    let all_uvs = models.iter().all(|m| !m.mesh.texcoords.is_empty());
    let (mut n, mut uv) = (Vec::new(), Vec::new());
    for m in &models {
        let base = mesh.p.len() as u32;
        mesh.p.extend(m.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        mesh.indices.extend(m.mesh.indices.iter().map(|i| i + base));
        if all_normals {
            n.extend(m.mesh.normals.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        }
        if all_uvs {
            uv.extend(m.mesh.texcoords.chunks_exact(2).map(|c| [c[0], c[1]]));
        }
    }
    if let Some(&bad) = mesh.indices.iter().find(|&&i| i as usize >= mesh.p.len()) {
        return Err(format!("OBJ index {bad} is out of range ({} vertices)", mesh.p.len()));
    }
    mesh.n = (all_normals && n.len() == mesh.p.len()).then_some(n);
    mesh.uv = (all_uvs && uv.len() == mesh.p.len()).then_some(uv);
    Ok(mesh)
}

pub const NAME: &str = "objmesh";

pub fn read(ctx: &mut ShapeContext, p: &ParamList, span: Span) -> Res<Built> {
    let (name, at, path) = super::mesh_file(ctx, NAME, p, span)?;
    let mesh = load(&path, ctx.files).map_err(|e| Diagnostic::error(at, e))?;
    // Displaced as pbrt-v4 displaces a PLY mesh.
    super::displaced(mesh, NAME, name, p)
}
