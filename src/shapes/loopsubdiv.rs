//! Loop subdivision surfaces, refined once at load into a triangle mesh.
//!
//! ```text
//! Shape "loopsubdiv" "integer levels" 3 "integer indices" [0 1 2  0 2 3 ...] "point3 P" [...]
//! # v3 also accepts "integer nlevels"; both versions default to 3 levels
//! ```
//! The scheme is pbrt's: each level splits every triangle in four; interior vertices
//! move by Loop's β weights (1/16 when regular, valence 6), boundary vertices and edge
//! points by the 1-6-1 and ½-½ boundary rules (so open edges stay curves of their own,
//! pbrt's only crease). After the last level every vertex is pushed to its limit
//! position (γ weights; 1/5 on boundaries) and given the limit surface's normal from
//! the tangents of its one-ring. Vertices and triangles come out in pbrt's order, and
//! the arithmetic is pbrt's, in `f32`.
//!
//! pbrt assumes a consistently oriented 2-manifold and crashes or loops otherwise; here
//! such a mesh is an error naming the vertex where the walk around it fails.

use crate::limits::Limits;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::values::Res;
use glam::Vec3;

const NONE: u32 = u32::MAX;

fn next(i: usize) -> usize {
    (i + 1) % 3
}

fn prev(i: usize) -> usize {
    (i + 2) % 3
}

#[derive(Clone, Copy, Debug)]
struct Vertex {
    p: Vec3,
    start_face: u32,
    regular: bool,
    boundary: bool,
}

#[derive(Clone, Copy, Debug)]
struct Face {
    v: [u32; 3],
    /// The neighbour across edge (v[i], v[i+1]), or [`NONE`].
    f: [u32; 3],
}

/// A subdivision mesh at one level, with adjacency.
struct Mesh {
    verts: Vec<Vertex>,
    faces: Vec<Face>,
}

/// The limit mesh: positions, per-vertex normals (not normalised, as pbrt's) and indices.
#[derive(Clone, Debug, PartialEq)]
pub struct Subdivided {
    pub p: Vec<[f32; 3]>,
    pub n: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
}

fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl Face {
    fn vnum(&self, v: u32) -> Option<usize> {
        self.v.iter().position(|&x| x == v)
    }

    fn other_vert(&self, a: u32, b: u32) -> Option<u32> {
        self.v.iter().copied().find(|&x| x != a && x != b)
    }
}

/// Why the mesh cannot be subdivided.
fn broken(v: u32) -> String {
    format!(
        "loopsubdiv: the faces around vertex {v} do not form a consistently oriented surface \
         (Loop subdivision needs a manifold triangle mesh)"
    )
}

impl Mesh {
    /// Adjacency from shared edges, as pbrt pairs them: the first face to use an edge
    /// waits for the second, which links both and closes the edge.
    fn new(p: &[Vec3], indices: &[u32]) -> Result<Mesh, String> {
        let mut verts: Vec<Vertex> =
            p.iter().map(|&p| Vertex { p, start_face: NONE, regular: false, boundary: false }).collect();
        let mut faces: Vec<Face> =
            indices.chunks_exact(3).map(|c| Face { v: [c[0], c[1], c[2]], f: [NONE; 3] }).collect();
        for (i, face) in faces.iter().enumerate() {
            for &v in &face.v {
                verts[v as usize].start_face = i as u32;
            }
        }
        let mut open: std::collections::HashMap<(u32, u32), (u32, usize)> = Default::default();
        let mut closed: std::collections::HashSet<(u32, u32)> = Default::default();
        for i in 0..faces.len() {
            for e in 0..3 {
                let key = edge_key(faces[i].v[e], faces[i].v[next(e)]);
                if closed.contains(&key) {
                    return Err(format!(
                        "loopsubdiv: the edge between vertices {} and {} belongs to more than two triangles",
                        key.0, key.1
                    ));
                }
                match open.remove(&key) {
                    None => {
                        open.insert(key, (i as u32, e));
                    }
                    Some((f0, e0)) => {
                        // A shared edge runs the opposite way in its two faces.
                        if faces[f0 as usize].v[e0] == faces[i].v[e] {
                            return Err(broken(faces[i].v[e]));
                        }
                        closed.insert(key);
                        faces[f0 as usize].f[e0] = i as u32;
                        faces[i].f[e] = f0;
                    }
                }
            }
        }
        Ok(Mesh { verts, faces })
    }

    fn next_face(&self, f: u32, v: u32) -> Result<u32, String> {
        let face = &self.faces[f as usize];
        face.vnum(v).map(|i| face.f[i]).ok_or_else(|| broken(v))
    }

    fn prev_face(&self, f: u32, v: u32) -> Result<u32, String> {
        let face = &self.faces[f as usize];
        face.vnum(v).map(|i| face.f[prev(i)]).ok_or_else(|| broken(v))
    }

    fn next_vert(&self, f: u32, v: u32) -> Result<u32, String> {
        let face = &self.faces[f as usize];
        face.vnum(v).map(|i| face.v[next(i)]).ok_or_else(|| broken(v))
    }

    fn prev_vert(&self, f: u32, v: u32) -> Result<u32, String> {
        let face = &self.faces[f as usize];
        face.vnum(v).map(|i| face.v[prev(i)]).ok_or_else(|| broken(v))
    }

    /// Walks the faces around `v` from its start face: whether the walk came back to
    /// it (an interior vertex) and how many faces it passed.
    fn walk_forward(&self, v: u32) -> Result<(bool, usize), String> {
        let start = self.verts[v as usize].start_face;
        let (mut f, mut n) = (start, 1);
        loop {
            f = self.next_face(f, v)?;
            if f == NONE || f == start {
                return Ok((f == start, n));
            }
            n += 1;
            if n > self.faces.len() {
                return Err(broken(v));
            }
        }
    }

    /// Marks boundary and regular vertices (pbrt: valence 6 inside, 4 on a boundary).
    fn classify(&mut self) -> Result<(), String> {
        for v in 0..self.verts.len() as u32 {
            let (closed, _) = self.walk_forward(v)?;
            self.verts[v as usize].boundary = !closed;
            let valence = self.valence(v)?;
            let vx = &mut self.verts[v as usize];
            vx.regular = if vx.boundary { valence == 4 } else { valence == 6 };
        }
        Ok(())
    }

    /// The number of one-ring neighbours.
    fn valence(&self, v: u32) -> Result<usize, String> {
        let (closed, forward) = self.walk_forward(v)?;
        if closed {
            return Ok(forward);
        }
        let (mut f, mut n) = (self.verts[v as usize].start_face, forward);
        loop {
            f = self.prev_face(f, v)?;
            if f == NONE {
                return Ok(n + 1);
            }
            n += 1;
            if n > self.faces.len() {
                return Err(broken(v));
            }
        }
    }

    /// The one-ring positions in pbrt's order (for a boundary vertex, from one open
    /// edge around to the other).
    fn one_ring(&self, v: u32) -> Result<Vec<Vec3>, String> {
        let vx = &self.verts[v as usize];
        let limit = self.faces.len() + 2;
        let mut ring = Vec::new();
        let mut face = vx.start_face;
        if !vx.boundary {
            loop {
                ring.push(self.verts[self.next_vert(face, v)? as usize].p);
                face = self.next_face(face, v)?;
                if face == vx.start_face {
                    return Ok(ring);
                }
                if face == NONE || ring.len() > limit {
                    return Err(broken(v));
                }
            }
        }
        let mut steps = 0;
        while let f2 = self.next_face(face, v)?
            && f2 != NONE
        {
            face = f2;
            steps += 1;
            if steps > limit {
                return Err(broken(v));
            }
        }
        ring.push(self.verts[self.next_vert(face, v)? as usize].p);
        while face != NONE {
            ring.push(self.verts[self.prev_vert(face, v)? as usize].p);
            face = self.prev_face(face, v)?;
            if ring.len() > limit {
                return Err(broken(v));
            }
        }
        Ok(ring)
    }

    fn weight_one_ring(&self, v: u32, beta: f32) -> Result<Vec3, String> {
        let ring = self.one_ring(v)?;
        let mut p = (1.0 - ring.len() as f32 * beta) * self.verts[v as usize].p;
        for q in ring {
            p += beta * q;
        }
        Ok(p)
    }

    fn weight_boundary(&self, v: u32, beta: f32) -> Result<Vec3, String> {
        let ring = self.one_ring(v)?;
        let (first, last) = (ring[0], ring[ring.len() - 1]);
        Ok((1.0 - 2.0 * beta) * self.verts[v as usize].p + beta * first + beta * last)
    }

    /// One level: every vertex moves, every edge gains a vertex, every face splits in
    /// four (children 0–2 at the corners, 3 in the middle), in pbrt's order.
    fn refine(&self) -> Result<Mesh, String> {
        let mut verts = Vec::with_capacity(self.verts.len() + self.faces.len() * 3 / 2 + 3);
        for (i, v) in self.verts.iter().enumerate() {
            let i = i as u32;
            let p = match (v.boundary, v.regular) {
                (true, _) => self.weight_boundary(i, 1.0 / 8.0)?,
                (false, true) => self.weight_one_ring(i, 1.0 / 16.0)?,
                (false, false) => self.weight_one_ring(i, beta(self.valence(i)?))?,
            };
            let start = v.start_face;
            let child_face = 4 * start + self.faces[start as usize].vnum(i).ok_or_else(|| broken(i))? as u32;
            verts.push(Vertex { p, start_face: child_face, regular: v.regular, boundary: v.boundary });
        }
        let mut edge_verts: std::collections::HashMap<(u32, u32), u32> = Default::default();
        for (fi, face) in self.faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (face.v[k], face.v[next(k)]);
                let key = edge_key(a, b);
                if edge_verts.contains_key(&key) {
                    continue;
                }
                let (pa, pb) = (self.verts[key.0 as usize].p, self.verts[key.1 as usize].p);
                let boundary = face.f[k] == NONE;
                let p = if boundary {
                    0.5 * pa + 0.5 * pb
                } else {
                    let c = face.other_vert(a, b).ok_or_else(|| broken(a))?;
                    let d = self.faces[face.f[k] as usize].other_vert(a, b).ok_or_else(|| broken(a))?;
                    3.0 / 8.0 * pa
                        + 3.0 / 8.0 * pb
                        + 1.0 / 8.0 * self.verts[c as usize].p
                        + 1.0 / 8.0 * self.verts[d as usize].p
                };
                edge_verts.insert(key, verts.len() as u32);
                verts.push(Vertex { p, start_face: 4 * fi as u32 + 3, regular: true, boundary });
            }
        }
        let mut faces = vec![Face { v: [NONE; 3], f: [NONE; 3] }; 4 * self.faces.len()];
        for (fi, face) in self.faces.iter().enumerate() {
            let child = |k: usize| 4 * fi + k;
            for j in 0..3 {
                faces[child(3)].f[j] = child(next(j)) as u32;
                faces[child(j)].f[next(j)] = child(3) as u32;
                let across = |n: u32| -> Result<u32, String> {
                    if n == NONE {
                        return Ok(NONE);
                    }
                    let k = self.faces[n as usize].vnum(face.v[j]).ok_or_else(|| broken(face.v[j]))?;
                    Ok(4 * n + k as u32)
                };
                faces[child(j)].f[j] = across(face.f[j])?;
                faces[child(j)].f[prev(j)] = across(face.f[prev(j)])?;
                faces[child(j)].v[j] = face.v[j];
                let e = edge_verts[&edge_key(face.v[j], face.v[next(j)])];
                faces[child(j)].v[next(j)] = e;
                faces[child(next(j))].v[j] = e;
                faces[child(3)].v[j] = e;
            }
        }
        Ok(Mesh { verts, faces })
    }

    /// The limit position of every vertex.
    fn limit_positions(&self) -> Result<Vec<Vec3>, String> {
        (0..self.verts.len() as u32)
            .map(|v| {
                if self.verts[v as usize].boundary {
                    self.weight_boundary(v, 1.0 / 5.0)
                } else {
                    self.weight_one_ring(v, loop_gamma(self.valence(v)?))
                }
            })
            .collect()
    }

    /// The limit surface's normal at `v` (pbrt's tangent masks; `v` already at its limit).
    fn limit_normal(&self, v: u32) -> Result<Vec3, String> {
        let ring = self.one_ring(v)?;
        let n = ring.len();
        let p = self.verts[v as usize].p;
        let (s, t) = if !self.verts[v as usize].boundary {
            let (mut s, mut t) = (Vec3::ZERO, Vec3::ZERO);
            for (j, q) in ring.iter().enumerate() {
                let a = 2.0 * std::f32::consts::PI * j as f32 / n as f32;
                s += a.cos() * *q;
                t += a.sin() * *q;
            }
            (s, t)
        } else {
            let s = ring[n - 1] - ring[0];
            let t = match n {
                2 => ring[0] + ring[1] - 2.0 * p,
                3 => ring[1] - p,
                4 => -ring[0] + 2.0 * ring[1] + 2.0 * ring[2] - ring[3] - 2.0 * p,
                _ => {
                    let theta = std::f32::consts::PI / (n - 1) as f32;
                    let mut t = theta.sin() * (ring[0] + ring[n - 1]);
                    for (k, q) in ring.iter().enumerate().take(n - 1).skip(1) {
                        t += (2.0 * theta.cos() - 2.0) * (k as f32 * theta).sin() * *q;
                    }
                    -t
                }
            };
            (s, t)
        };
        Ok(s.cross(t))
    }
}

fn beta(valence: usize) -> f32 {
    if valence == 3 { 3.0 / 16.0 } else { 3.0 / (8.0 * valence as f32) }
}

fn loop_gamma(valence: usize) -> f32 {
    1.0 / (valence as f32 + 3.0 / (8.0 * beta(valence)))
}

/// Subdivides `levels` times and moves the result to the limit surface. `indices` must
/// be in range and a multiple of 3. Vertices no triangle uses are dropped first, and so
/// are triangles that repeat a vertex (pbrt would crash on either).
pub fn subdivide(p: &[[f32; 3]], indices: &[u32], levels: u32) -> Result<Subdivided, String> {
    let (p, indices) = compact(p, indices);
    let mut mesh = Mesh::new(&p, &indices)?;
    mesh.classify()?;
    for _ in 0..levels {
        mesh = mesh.refine()?;
    }
    let limit = mesh.limit_positions()?;
    for (v, p) in mesh.verts.iter_mut().zip(&limit) {
        v.p = *p;
    }
    let n =
        (0..mesh.verts.len() as u32).map(|v| mesh.limit_normal(v).map(|n| n.to_array())).collect::<Result<_, _>>()?;
    Ok(Subdivided {
        p: limit.iter().map(|p| p.to_array()).collect(),
        n,
        indices: mesh.faces.iter().flat_map(|f| f.v).collect(),
    })
}

/// Drops triangles that repeat a vertex and vertices no triangle uses.
fn compact(p: &[[f32; 3]], indices: &[u32]) -> (Vec<Vec3>, Vec<u32>) {
    let tris: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    let mut new_index = vec![NONE; p.len()];
    let mut kept = Vec::new();
    let mut out = Vec::with_capacity(tris.len() * 3);
    for t in &tris {
        for &v in t {
            if new_index[v as usize] == NONE {
                new_index[v as usize] = kept.len() as u32;
                kept.push(Vec3::from(p[v as usize]));
            }
            out.push(new_index[v as usize]);
        }
    }
    // Keep the file's vertex order when every vertex is used (pbrt's numbering).
    if kept.len() == p.len() {
        return (p.iter().map(|&q| Vec3::from(q)).collect(), tris.concat());
    }
    (kept, out)
}

/// Triangles after `levels` levels, or `None` past `u64`.
pub fn triangle_count(base: usize, levels: u32) -> Option<u64> {
    4u64.checked_pow(levels)?.checked_mul(base as u64)
}

/// `Shape "loopsubdiv"`: the control mesh refined to its limit surface at load, so the
/// renderer sees an ordinary triangle mesh with normals.
///
/// ```text
/// Shape "loopsubdiv" "integer levels" 3 "point3 P" [...] "integer indices" [...]   # v3 also "nlevels"
/// ```
pub const NAME: &str = "loopsubdiv";

pub fn read(ctx: &mut super::ShapeContext, p: &ParamList, span: Span) -> Res<super::Built> {
    // pbrt-v3 reports a missing array and leaves the shape out; pbrt-v4 stops.
    let need = |what: &str| format!("loopsubdiv needs {what}");
    let Some(positions) = p.array("P", ParamType::Point3)? else {
        return ctx.left_out_by_v3(p, span, need("\"point3 P\""));
    };
    let Some(indices) = p.array("indices", ParamType::Integer)? else {
        return ctx.left_out_by_v3(p, span, need("\"integer indices\""));
    };
    let n_p = positions.values.len() / 3;
    let indices = super::mesh_params::check_indices(indices.ints(), n_p, indices.value_span, ctx.warn)?;
    // v3 also reads "nlevels"; both default to 3.
    let levels_at = p.find("levels", &[ParamType::Integer]).or(p.find("nlevels", &[ParamType::Integer]));
    let levels = p.int("levels")?.or(p.int("nlevels")?).unwrap_or(3).max(0) as u32;
    let at = levels_at.map_or(span, |l| l.value_span);
    let tris = triangle_count(indices.len() / 3, levels).unwrap_or(u64::MAX);
    let limits = &ctx.files.limits;
    if tris > limits.triangles {
        let what = format!("loopsubdiv: {levels} levels make {tris} triangles, which");
        return Err(Diagnostic::error(at, Limits::over(what, "triangles", limits.triangles)));
    }
    let points: Vec<[f32; 3]> = positions.floats().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let s = subdivide(&points, &indices, levels)
        .map_err(|e| Diagnostic::error(p.named("indices").map_or(span, |i| i.value_span), e))?;
    p.mark_known(&["scheme"]);
    let mesh = super::TriangleMesh { p: s.p, indices: s.indices, n: Some(s.n), ..Default::default() };
    Ok(super::Built::Mesh { mesh, kind: NAME, filename: None })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> (Vec<[f32; 3]>, Vec<u32>) {
        let p = vec![[1.0, 1.0, 1.0], [-1.0, -1.0, 1.0], [-1.0, 1.0, -1.0], [1.0, -1.0, -1.0]];
        (p, vec![0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2])
    }

    #[test]
    fn counts_grow_by_four_per_level() {
        let (p, i) = tetrahedron();
        for levels in 0..4 {
            let s = subdivide(&p, &i, levels).unwrap();
            assert_eq!(s.indices.len() / 3, 4 * 4usize.pow(levels));
            // Closed surface: V − E + F = 2 with E = 3F/2.
            let f = s.indices.len() / 3;
            assert_eq!(s.p.len() + f - 3 * f / 2, 2);
        }
    }

    #[test]
    fn limit_of_a_regular_tetrahedron_is_symmetric_and_shrinks() {
        let (p, i) = tetrahedron();
        let s = subdivide(&p, &i, 3).unwrap();
        let centroid: Vec3 = s.p.iter().map(|&q| Vec3::from(q)).sum::<Vec3>() / s.p.len() as f32;
        assert!(centroid.length() < 1e-5, "{centroid}");
        for (q, n) in s.p.iter().zip(&s.n) {
            let (q, n) = (Vec3::from(*q), Vec3::from(*n));
            assert!(q.length() < 3f32.sqrt(), "inside the control hull");
            assert!(n.normalize().dot(q.normalize()) > 0.8, "normals point outward: {q} {n}");
        }
        // A corner's limit position (valence 3, γ = 1/(3 + 3/(8·3/16)) = 1/5):
        // after 0 levels p·(1 − 3γ) + γ·Σring = (1,1,1)·(2/5) − (1,1,1)/5.
        let s0 = subdivide(&p, &i, 0).unwrap();
        assert!((Vec3::from(s0.p[0]) - Vec3::splat(0.2)).length() < 1e-6, "{:?}", s0.p[0]);
    }

    #[test]
    fn a_flat_open_patch_stays_flat_with_boundary_curves() {
        // Two triangles of a square: every vertex is on the boundary.
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let s = subdivide(&p, &[0, 1, 2, 0, 2, 3], 2).unwrap();
        for (q, n) in s.p.iter().zip(&s.n) {
            assert_eq!(q[2], 0.0);
            let n = Vec3::from(*n);
            assert!(n.z.abs() > 0.0 && n.x.abs() + n.y.abs() < 1e-5 * n.z.abs(), "{n}");
        }
    }

    #[test]
    fn non_manifold_input_is_an_error() {
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.5, 0.5, 1.0]];
        // The second triangle runs along edge 0→1 the same way as the first.
        let e = subdivide(&p, &[0, 1, 2, 0, 1, 3], 1).unwrap_err();
        assert!(e.contains("consistently oriented"), "{e}");
        // Three triangles on one edge.
        let e = subdivide(&p, &[0, 1, 2, 1, 0, 3, 0, 1, 4], 1).unwrap_err();
        assert!(e.contains("more than two"), "{e}");
        // Two triangles wound against each other on all three edges close a valid pillow.
        let s = subdivide(&p, &[0, 1, 2, 2, 1, 0], 1).unwrap();
        assert_eq!(s.indices.len(), 24);
    }

    #[test]
    fn unused_vertices_and_repeated_corners_are_dropped() {
        let p = vec![[0.0, 0.0, 0.0], [9.0, 9.0, 9.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let s = subdivide(&p, &[0, 2, 3, 0, 0, 2], 1).unwrap();
        assert_eq!(s.indices.len(), 12);
        assert!(s.p.iter().all(|q| q[0] <= 1.0));
    }
}
