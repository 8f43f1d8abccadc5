//! pbrt-v4's displaced PLY meshes.
//!
//! ```text
//! Texture "bumps" "float" "bilerp" "float v00" 0 "float v11" .2
//! Shape "plymesh" "string filename" "rock.ply" "texture displacement" "bumps" "float edgelength" .05
//! ```
//! As pbrt-v4's `TriQuadMesh::Displace`: quads become two triangles; a triangle with an
//! edge of `edgelength` or more (measured in world space) is split at the midpoint of
//! its longest edge, again and again (an edge's midpoint is shared by the triangles on
//! both sides); then each vertex moves along its normal (the file's, or the mean of
//! its triangles') by the texture's value there, and the normals are made anew from
//! the displaced triangles.

use super::triangle::TriangleMesh;
use glam::{DMat4, DVec3, Vec3};
use std::collections::HashMap;

/// The most triangles a displaced mesh may have (pbrt-v4 refines until memory runs
/// out): a smaller `edgelength` than this allows is an error.
pub const MAX_TRIANGLES: usize = 1 << 25;

/// Refines and displaces `mesh` (object space, triangles only) in place. `height` is
/// the texture at an object-space point, normal and (u, v).
pub fn displace(
    mesh: &mut TriangleMesh,
    world_from_object: &DMat4,
    edge_length: f32,
    height: impl Fn([f32; 3], [f32; 3], [f32; 2]) -> f32,
) -> Result<(), String> {
    if !(edge_length > 0.0 && edge_length.is_finite()) {
        return Err(format!("\"edgelength\" must be a positive number, not {edge_length}"));
    }
    let Some(uv) = mesh.uv.take() else {
        return Err("displacement needs the mesh's (u, v) coordinates, as in pbrt-v4".into());
    };
    let n = mesh.n.take().unwrap_or_else(|| normals(&mesh.p, &mesh.indices));
    let mut r = Refiner { p: std::mem::take(&mut mesh.p), n, uv, indices: Vec::new(), split: HashMap::new() };
    let mut world: Vec<DVec3> =
        r.p.iter().map(|p| world_from_object.transform_point3(DVec3::from(p.map(f64::from)))).collect();
    if !world.iter().all(|p| p.is_finite()) {
        // A NaN edge is never short enough: it would split forever.
        return Err("a vertex that is not a finite point cannot be displaced".into());
    }
    let old = std::mem::take(&mut mesh.indices);
    // Refined triangles have about half an edge's square of area each at least: refuse
    // up front what would pass the limit, rather than find out at the limit.
    let area: f64 = old
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| world[i as usize]);
            (b - a).cross(c - a).length() / 2.0
        })
        .sum();
    if 2.0 * area / (edge_length as f64).powi(2) > MAX_TRIANGLES as f64 {
        return Err(too_many());
    }
    for t in old.chunks_exact(3) {
        r.refine([t[0], t[1], t[2]], edge_length, world_from_object, &mut world)?;
    }
    for i in 0..r.p.len() {
        let d = height(r.p[i], r.n[i], r.uv[i]);
        r.p[i] = (Vec3::from(r.p[i]) + d * Vec3::from(r.n[i])).to_array();
    }
    mesh.n = Some(normals(&r.p, &r.indices));
    (mesh.p, mesh.uv, mesh.indices) = (r.p, Some(r.uv), r.indices);
    // The file's tangents and face indices no longer fit the new triangles.
    (mesh.s, mesh.face_indices) = (None, None);
    Ok(())
}

fn too_many() -> String {
    format!("displacement at this \"edgelength\" makes more than {MAX_TRIANGLES} triangles")
}

struct Refiner {
    p: Vec<[f32; 3]>,
    n: Vec<[f32; 3]>,
    uv: Vec<[f32; 2]>,
    indices: Vec<u32>,
    /// Each split edge's midpoint vertex, by its two ends (lower first).
    split: HashMap<(u32, u32), u32>,
}

impl Refiner {
    /// Splits triangle `v` until no edge is `max` long or more, in pbrt-v4's order: the
    /// longest edge's half with the first vertex, then the other half.
    fn refine(&mut self, v: [u32; 3], max: f32, m: &DMat4, world: &mut Vec<DVec3>) -> Result<(), String> {
        let mut stack = vec![v];
        while let Some([v0, v1, v2]) = stack.pop() {
            let d = |a: u32, b: u32| world[a as usize].distance(world[b as usize]) as f32;
            let (d01, d12, d20) = (d(v0, v1), d(v1, v2), d(v2, v0));
            if d01 < max && d12 < max && d20 < max {
                if self.indices.len() >= 3 * MAX_TRIANGLES {
                    return Err(too_many());
                }
                self.indices.extend([v0, v1, v2]);
                continue;
            }
            // The longest edge first (ties as pbrt-v4 breaks them).
            let [a, b, c] = match (d01 > d12, d01 > d20, d12 > d20) {
                (true, true, _) => [v0, v1, v2],
                (true, false, _) => [v2, v0, v1],
                (false, _, true) => [v1, v2, v0],
                (false, _, false) => [v2, v0, v1],
            };
            let mid = self.midpoint(a, b, m, world);
            stack.push([mid, b, c]);
            stack.push([a, mid, c]);
        }
        Ok(())
    }

    /// The vertex halfway along edge (a, b), made on the edge's first split.
    fn midpoint(&mut self, a: u32, b: u32, m: &DMat4, world: &mut Vec<DVec3>) -> u32 {
        let key = (a.min(b), a.max(b));
        if let Some(&v) = self.split.get(&key) {
            return v;
        }
        let (a, b) = (a as usize, b as usize);
        let p = (Vec3::from(self.p[a]) + Vec3::from(self.p[b])) / 2.0;
        let n = Vec3::from(self.n[a]) + Vec3::from(self.n[b]);
        let n = if n.length_squared() > 0.0 { n.normalize() } else { n };
        let uv = [(self.uv[a][0] + self.uv[b][0]) / 2.0, (self.uv[a][1] + self.uv[b][1]) / 2.0];
        let v = self.p.len() as u32;
        self.p.push(p.to_array());
        self.n.push(n.to_array());
        self.uv.push(uv);
        world.push(m.transform_point3(DVec3::from(p.to_array().map(f64::from))));
        self.split.insert(key, v);
        v
    }
}

/// Vertex normals as pbrt-v4's `ComputeNormals`: the sum of the unit normals of the
/// triangles about each vertex, normalised (zero where there are none).
fn normals(p: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut n = vec![Vec3::ZERO; p.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(p[i as usize]));
        let face = (b - a).cross(c - b);
        if face.length_squared() > 0.0 {
            let face = face.normalize();
            t.iter().for_each(|&i| n[i as usize] += face);
        }
    }
    n.into_iter().map(|v| if v.length_squared() > 0.0 { v.normalize() } else { v }.to_array()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> TriangleMesh {
        TriangleMesh {
            p: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            indices: vec![0, 1, 2, 0, 2, 3],
            n: None,
            s: None,
            uv: Some(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
            face_indices: None,
        }
    }

    #[test]
    fn refined_edges_are_shorter_than_the_limit_and_shared_midpoints_keep_it_closed() {
        let mut m = square();
        displace(&mut m, &DMat4::IDENTITY, 0.3, |_, _, _| 0.0).unwrap();
        for t in m.indices.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (Vec3::from(m.p[t[k] as usize]), Vec3::from(m.p[t[(k + 1) % 3] as usize]));
                assert!(a.distance(b) < 0.3, "edge {a} {b}");
            }
        }
        // Area kept, and no vertex twice: midpoints are shared, so the surface has no
        // cracks (a crack would leave a vertex on one side only).
        let area: f32 = m
            .indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(m.p[i as usize]));
                (b - a).cross(c - a).length() / 2.0
            })
            .sum();
        assert!((area - 1.0).abs() < 1e-5, "{area}");
        let mut seen: Vec<[u32; 3]> = m.p.iter().map(|p| p.map(f32::to_bits)).collect();
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), m.p.len());
        // Scaled up in world space by 2, the same limit needs more triangles.
        let mut big = square();
        displace(&mut big, &DMat4::from_scale(DVec3::splat(2.0)), 0.3, |_, _, _| 0.0).unwrap();
        assert!(big.triangle_count() > m.triangle_count());
    }

    #[test]
    fn vertices_move_along_their_normals_by_the_texture() {
        let mut m = square();
        displace(&mut m, &DMat4::IDENTITY, 0.5, |_, _, uv| 0.1 * uv[0]).unwrap();
        for (p, uv) in m.p.iter().zip(m.uv.as_ref().unwrap()) {
            assert!((p[2] - 0.1 * uv[0]).abs() < 1e-6, "{p:?} at {uv:?}");
        }
        // The new normals lean away from the rise in u.
        assert!(m.n.as_ref().unwrap().iter().all(|n| n[0] < 0.0 && n[2] > 0.9));
        let mut no_uv = square();
        no_uv.uv = None;
        assert!(displace(&mut no_uv, &DMat4::IDENTITY, 0.5, |_, _, _| 0.0).is_err());
        assert!(displace(&mut square(), &DMat4::IDENTITY, 0.0, |_, _, _| 0.0).is_err());
        assert!(displace(&mut square(), &DMat4::IDENTITY, 1e-6, |_, _, _| 0.0).unwrap_err().contains("more than"));
        let mut nan = square();
        nan.p[2][0] = f32::NAN;
        assert!(displace(&mut nan, &DMat4::IDENTITY, 0.5, |_, _, _| 0.0).unwrap_err().contains("finite"));
    }
}
