//! `Shape "trianglemesh"` parameters to a [`TriangleMesh`] and v4's `"bilinearmesh"` to a
//! [`PatchMesh`], with pbrt's validity checks.
//!
//! ```text
//! Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  1 1 0  0 1 0] "integer indices" [0 1 2 0 2 3]
//!       "normal N" [...] "vector3 S" [...] "point2 uv" [...] "integer faceIndices" [0 0]
//! # v3 also: "float uv" [...], "point2 st" / "float st" [...]
//! Shape "bilinearmesh" "point3 P" [0 0 0  1 0 0  0 1 0  1 1 0] "integer indices" [0 1 2 3]
//!       "normal N" [...] "point2 uv" [...] "integer faceIndices" [0]
//! ```
//! `indices` may be left out when there are exactly three points (four for a patch). A
//! count that is not a multiple of 3 (4) drops the extras (warning); an index out of
//! range is an error. `N`/`S` with the wrong count are ignored (warning); `uv` with too
//! few entries is ignored, with too many the extras are dropped (warnings).

use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType, Values};
use crate::parser::source::Span;
use crate::shapes::{PatchMesh, TriangleMesh};
use glam::{DMat3, DMat4, DVec3};
use rayon::prelude::*;

/// Arrays longer than this are copied and checked on all threads.
const PARALLEL_VALUES: usize = 1 << 16;

/// Reads the mesh arrays of a `trianglemesh` statement, moving the long ones out of
/// the list (a 50 MB inline mesh copied its points and indices in 8 ms).
/// `ty` names the shape in messages.
pub fn from_params(
    p: &mut ParamList,
    ty: &str,
    span: Span,
    warn: &mut Vec<Diagnostic>,
) -> Result<TriangleMesh, Diagnostic> {
    let (positions, indices) = points_and_indices(p, ty, 3, span, warn)?;
    let n_p = positions.len();
    let mut mesh = TriangleMesh { p: positions, indices, ..Default::default() };
    mesh.n = per_vertex(p, "N", ParamType::Normal3, n_p, warn)?;
    mesh.s = per_vertex(p, "S", ParamType::Vector3, n_p, warn)?;
    mesh.uv = uvs(p, n_p, warn)?;
    mesh.face_indices = face_indices(p, mesh.triangle_count(), "triangles", warn)?;
    p.mark_known(&["discarddegenerateUVs"]);
    Ok(mesh)
}

/// Reads the arrays of a v4 `bilinearmesh` statement, moving them out of the list.
/// `ty` names the shape in messages.
pub fn patches_from_params(
    p: &mut ParamList,
    ty: &str,
    span: Span,
    warn: &mut Vec<Diagnostic>,
) -> Result<PatchMesh, Diagnostic> {
    let (positions, indices) = points_and_indices(p, ty, 4, span, warn)?;
    let n_p = positions.len();
    let mut mesh = PatchMesh { p: positions, indices, ..Default::default() };
    mesh.n = per_vertex(p, "N", ParamType::Normal3, n_p, warn)?;
    mesh.uv = uvs(p, n_p, warn)?;
    mesh.face_indices = face_indices(p, mesh.patch_count(), "patches", warn)?;
    // pbrt-v4 draws emission from this image's distribution; that changes only the
    // sampling density, not the image, so it is read past.
    p.mark_known(&["emissionfilename"]);
    Ok(mesh)
}

/// `P` and `indices` (`arity` per face; may be left out for a single face).
fn points_and_indices(
    p: &mut ParamList,
    shape: &str,
    arity: usize,
    span: Span,
    warn: &mut Vec<Diagnostic>,
) -> Result<(Vec<[f32; 3]>, Vec<u32>), Diagnostic> {
    let positions = p
        .array("P", ParamType::Point3)?
        .ok_or_else(|| Diagnostic::error(span, format!("{shape} needs \"point3 P\"")))?;
    let n_p = positions.values.len() / 3;
    let indices_span = p.find("indices", &[ParamType::Integer]).map(|i| i.value_span);
    let kept = match p.array("indices", ParamType::Integer)? {
        Some(i) => Some(check_face_indices(i.ints(), arity, n_p, indices_span.unwrap_or(span), warn)?),
        None if n_p == arity => None,
        None => {
            let face = if arity == 3 { "triangle" } else { "patch" };
            let msg = format!(
                "{shape} needs \"integer indices\" (only a single {face} of {arity} points may leave them out)"
            );
            return Err(Diagnostic::error(span, msg));
        }
    };
    let indices = match kept {
        Some(kept) => {
            // Checked: none is negative.
            bytemuck::allocation::cast_vec(take_ints(p, "indices", kept))
        }
        None => (0..arity as u32).collect(),
    };
    Ok((take_arrays(p, "P", n_p), indices))
}

/// The floats of parameter `name` (looked up and checked) in groups of `N`, moved out
/// of the list; past `len` groups dropped. The vector is cut to its length (in place:
/// a list read by pushes has room to spare, which the mesh would keep), so its room is
/// whole groups and nothing is copied.
fn take_arrays<const N: usize>(p: &mut ParamList, name: &str, len: usize) -> Vec<[f32; N]> {
    let mut floats = match p.take_values(name) {
        Some(Values::Floats(v)) => v,
        _ => Vec::new(),
    };
    floats.truncate(N * len);
    floats.shrink_to_fit();
    bytemuck::allocation::try_cast_vec(floats).unwrap_or_else(|(_, v)| v.as_chunks::<N>().0.to_vec())
}

/// The integers of parameter `name` (looked up and checked), moved out of the list and
/// cut to `len` (in place).
fn take_ints(p: &mut ParamList, name: &str, len: usize) -> Vec<i32> {
    let mut ints = match p.take_values(name) {
        Some(Values::Ints(v)) => v,
        _ => Vec::new(),
    };
    ints.truncate(len);
    ints.shrink_to_fit();
    ints
}

/// A per-vertex array of triples, ignored (warning) when its count is not `n_p`.
fn per_vertex(
    p: &mut ParamList,
    name: &str,
    ty: ParamType,
    n_p: usize,
    warn: &mut Vec<Diagnostic>,
) -> Result<Option<Vec<[f32; 3]>>, Diagnostic> {
    let Some(a) = p.array(name, ty)? else { return Ok(None) };
    if a.values.len() / 3 != n_p {
        let msg = format!("\"{name}\" has {} entries but there are {n_p} vertices; ignored", a.values.len() / 3);
        warn.push(Diagnostic::warning(a.span, msg));
        return Ok(None);
    }
    Ok(Some(take_arrays(p, name, n_p)))
}

/// `faceIndices`, ignored (warning) unless there is one per face.
fn face_indices(
    p: &mut ParamList,
    faces: usize,
    what: &str,
    warn: &mut Vec<Diagnostic>,
) -> Result<Option<Vec<i32>>, Diagnostic> {
    let Some(f) = p.array("faceIndices", ParamType::Integer)? else { return Ok(None) };
    if f.ints().len() == faces {
        return Ok(Some(take_ints(p, "faceIndices", faces)));
    }
    let msg = format!("\"faceIndices\" has {} entries for {faces} {what}; ignored", f.ints().len());
    warn.push(Diagnostic::warning(f.span, msg));
    Ok(None)
}

/// `uv` as point2 (both versions), or v3's `float uv`, `point2 st`, `float st`.
fn uvs(p: &mut ParamList, n_p: usize, warn: &mut Vec<Diagnostic>) -> Result<Option<Vec<[f32; 2]>>, Diagnostic> {
    let Some(a) = ["uv", "st"].iter().find_map(|n| p.find(n, &[ParamType::Point2, ParamType::Float])) else {
        return Ok(None);
    };
    let f = a.floats();
    if f.len() % 2 != 0 {
        return Err(Diagnostic::error(a.span, format!("\"{}\" needs an even number of values", a.name)));
    }
    let n = f.len() / 2;
    if n < n_p {
        warn.push(Diagnostic::warning(a.span, format!("\"{}\" has {n} entries for {n_p} vertices; ignored", a.name)));
        return Ok(None);
    }
    if n > n_p {
        warn.push(Diagnostic::warning(
            a.span,
            format!("\"{}\" has {n} entries for {n_p} vertices; extras ignored", a.name),
        ));
    }
    let name = a.name.clone();
    Ok(Some(take_arrays(p, &name, n_p)))
}

/// Drops a trailing partial triangle (warning) and rejects out-of-range indices.
pub fn check_indices(
    idx: &[i32],
    n_vertices: usize,
    span: Span,
    warn: &mut Vec<Diagnostic>,
) -> Result<Vec<u32>, Diagnostic> {
    let kept = check_face_indices(idx, 3, n_vertices, span, warn)?;
    Ok(map_values(&idx[..kept], |i| i as u32))
}

/// How many indices are kept: a trailing partial face of `arity` corners is dropped
/// (warning). Out-of-range indices are rejected.
fn check_face_indices(
    idx: &[i32],
    arity: usize,
    n_vertices: usize,
    span: Span,
    warn: &mut Vec<Diagnostic>,
) -> Result<usize, Diagnostic> {
    let faces = idx.len() / arity;
    if faces * arity != idx.len() {
        let (n, extra) = (idx.len(), idx.len() % arity);
        let msg = format!("{n} vertex indices is not a multiple of {arity}; the last {extra} are ignored");
        warn.push(Diagnostic::warning(span, msg));
    }
    let idx = &idx[..faces * arity];
    let out_of_range = |&i: &i32| i < 0 || i as usize >= n_vertices;
    let bad = match idx.len() < PARALLEL_VALUES {
        true => idx.iter().find(|i| out_of_range(i)),
        false => idx.par_chunks(PARALLEL_VALUES).find_map_first(|c| c.iter().find(|i| out_of_range(i))),
    };
    if let Some(bad) = bad {
        return Err(Diagnostic::error(
            span,
            format!("vertex index {bad} is out of range: the mesh has {n_vertices} vertices"),
        ));
    }
    Ok(idx.len())
}

/// The first of a mesh's face indices (`arity` a face) at or past its vertex count,
/// if none is negative: what pbrt-v3 leaves a mesh out for. Only read on the way to an
/// error: reading the mesh finds the first bad index without it.
pub fn index_past_the_end(p: &ParamList, arity: usize) -> Option<i32> {
    let n_p = p.find("P", &[ParamType::Point3])?.floats().len() / 3;
    let idx = p.find("indices", &[ParamType::Integer])?.ints();
    let idx = &idx[..idx.len() / arity * arity];
    if idx.iter().any(|&i| i < 0) {
        return None;
    }
    idx.iter().copied().find(|&i| i as usize >= n_p)
}

/// `f` of each value, on all threads for long arrays (a small mesh would wait longer
/// for the pool than for its copy).
fn map_values<T: Copy + Sync, U: Send>(values: &[T], f: impl Fn(T) -> U + Sync) -> Vec<U> {
    if values.len() < PARALLEL_VALUES {
        return values.iter().map(|&v| f(v)).collect();
    }
    let mut out = Vec::with_capacity(values.len());
    let chunk = PARALLEL_VALUES.max(values.len().div_ceil(64));
    out.spare_capacity_mut()[..values.len()]
        .par_chunks_mut(chunk)
        .zip(values.par_chunks(chunk))
        .for_each(|(o, v)| o.iter_mut().zip(v).for_each(|(o, &v)| _ = o.write(f(v))));
    // SAFETY: the chunks of the first `len` places were each written in full.
    unsafe { out.set_len(values.len()) };
    out
}

/// Applies the shape's transform: points by `m`, tangents by its linear part, normals by
/// the inverse transpose (as pbrt stores meshes, already transformed).
pub fn transform(mesh: &mut TriangleMesh, m: &DMat4) {
    transform_vertices(&mut mesh.p, mesh.s.as_deref_mut(), mesh.n.as_deref_mut(), m);
}

/// [`transform`] for a patch mesh.
pub fn transform_patches(mesh: &mut PatchMesh, m: &DMat4) {
    transform_vertices(&mut mesh.p, None, mesh.n.as_deref_mut(), m);
}

fn transform_vertices(p: &mut [[f32; 3]], s: Option<&mut [[f32; 3]]>, n: Option<&mut [[f32; 3]]>, m: &DMat4) {
    if *m == DMat4::IDENTITY {
        return;
    }
    let to = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
    let from = |a: &[f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    for p in p {
        *p = to(m.transform_point3(from(p)));
    }
    let linear = DMat3::from_mat4(*m);
    if let Some(s) = s {
        s.iter_mut().for_each(|v| *v = to(linear * from(v)));
    }
    let normal = linear.inverse().transpose();
    if let Some(n) = n {
        n.iter_mut().for_each(|v| *v = to(normal * from(v)));
    }
}

/// Coordinates beyond this overflow f32 arithmetic (squared lengths, areas).
pub(crate) const MAX_COORDINATE: f32 = 1e18;

/// Rejects non-finite or overflowing vertex data, naming the first bad vertex.
pub fn validate(mesh: &TriangleMesh) -> Result<(), String> {
    validate_vertices(&mesh.p, mesh.n.as_deref(), mesh.s.as_deref(), mesh.uv.as_deref())
}

/// [`validate`] for a patch mesh.
pub fn validate_patches(mesh: &PatchMesh) -> Result<(), String> {
    validate_vertices(&mesh.p, mesh.n.as_deref(), None, mesh.uv.as_deref())
}

fn validate_vertices(
    p: &[[f32; 3]],
    n: Option<&[[f32; 3]]>,
    s: Option<&[[f32; 3]]>,
    uv: Option<&[[f32; 2]]>,
) -> Result<(), String> {
    let bad = |v: &[f32; 3]| v.iter().any(|x| !x.is_finite() || x.abs() > MAX_COORDINATE);
    if let Some(i) = first_where(p, bad) {
        let [x, y, z] = p[i];
        return Err(format!(
            "vertex {i} is at ({x:?}, {y:?}, {z:?}): positions must be finite and within ±{MAX_COORDINATE:e}"
        ));
    }
    let not_finite = |v: &[f32]| v.iter().any(|x| !x.is_finite());
    let firsts = [
        ("normal", n.and_then(|a| first_where(a, |v| not_finite(v)))),
        ("tangent", s.and_then(|a| first_where(a, |v| not_finite(v)))),
        ("uv", uv.and_then(|a| first_where(a, |v| not_finite(v)))),
    ];
    match firsts.into_iter().find_map(|(what, i)| Some((what, i?))) {
        Some((what, i)) => Err(format!("the {what} of vertex {i} is not finite")),
        None => Ok(()),
    }
}

/// The first index whose value is `bad`, looked for on all threads in long arrays (by
/// runs: rayon's search item by item took five times as long as one thread).
fn first_where<T: Sync>(values: &[T], bad: impl Fn(&T) -> bool + Sync + Send) -> Option<usize> {
    if values.len() < PARALLEL_VALUES {
        return values.iter().position(bad);
    }
    let runs = values.par_chunks(PARALLEL_VALUES).enumerate();
    runs.find_map_first(|(k, run)| run.iter().position(&bad).map(|i| k * PARALLEL_VALUES + i))
}

/// One warning counting zero-area patches, which the renderer drops.
pub fn degenerate_patches_warning(mesh: &PatchMesh) -> Option<String> {
    let n = (0..mesh.patch_count()).filter(|&k| mesh.is_degenerate(k)).count();
    (n > 0).then(|| format!("{n} of {} patches have zero area and are dropped", mesh.patch_count()))
}

/// One warning counting zero-area triangles, which the renderer drops.
pub fn degenerate_warning(mesh: &TriangleMesh) -> Option<String> {
    let n = mesh.degenerate_count();
    (n > 0).then(|| format!("{n} of {} triangles have zero area and are dropped", mesh.triangle_count()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn param(ty: ParamType, name: &str, values: Values) -> crate::parser::params::Param {
        let type_name = if ty == ParamType::Integer { "integer" } else { "point3" };
        crate::parser::params::Param::new(ty, type_name.into(), name.into(), values, Span::default(), Span::default())
    }

    #[test]
    fn long_arrays_move_into_the_mesh_without_a_copy() {
        let mut p: Vec<f32> = Vec::with_capacity(12);
        p.extend([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0]);
        let indices = vec![0, 1, 2, 0, 2, 3, 3];
        let (p_at, indices_at) = (p.as_ptr() as usize, indices.as_ptr() as usize);
        let mut list = ParamList {
            params: vec![
                param(ParamType::Point3, "P", Values::Floats(p)),
                param(ParamType::Integer, "indices", Values::Ints(indices)),
            ],
        };
        let mut warn = Vec::new();
        let mesh = from_params(&mut list, "trianglemesh", Span::default(), &mut warn).unwrap();
        assert_eq!(mesh.p, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]);
        assert_eq!(mesh.indices, [0, 1, 2, 0, 2, 3], "the partial triangle is dropped");
        assert_eq!(warn.len(), 1);
        assert_eq!((mesh.p.as_ptr() as usize, mesh.indices.as_ptr() as usize), (p_at, indices_at));
        // The parameters stay, named and located, without their values.
        assert!(list.named("P").is_some_and(|p| p.values.is_empty() && p.is_used()));

        // Room to spare (a list read by pushes) is given back, not kept by the mesh.
        let mut p: Vec<f32> = Vec::with_capacity(100);
        p.extend([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
        let mut list = ParamList { params: vec![param(ParamType::Point3, "P", Values::Floats(p))] };
        let mesh = from_params(&mut list, "trianglemesh", Span::default(), &mut warn).unwrap();
        assert_eq!(mesh.p.capacity(), 3);
        assert_eq!((mesh.p, mesh.indices), (vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]], vec![0, 1, 2]));
    }
}
