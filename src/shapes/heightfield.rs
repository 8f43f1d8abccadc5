//! pbrt-v3's height field: a grid of heights over the unit square, built at load into
//! a triangle mesh as pbrt-v3 builds it.
//!
//! ```text
//! Shape "heightfield" "integer nu" 3 "integer nv" 2 "float Pz" [0 .5 0  .2 1 .2]   # v3
//! ```
//! Vertex (x, y) of the `nu × nv` grid (x fastest) sits at (x/(nu−1), y/(nv−1), Pz)
//! with that point as its (u, v); each cell is split along its (x, y)–(x+1, y+1)
//! diagonal, with pbrt's vertex order, and there are no shading normals.
//!
//! pbrt-v3 stops with a failed assertion when `Pz` does not hold `nu·nv` heights and
//! divides by zero for a grid one vertex wide; here both are located errors.

use super::{Built, ShapeContext, TriangleMesh};
use crate::limits::Limits;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::values::Res;

pub const NAME: &str = "heightfield";

pub fn read(ctx: &mut ShapeContext, p: &ParamList, span: Span) -> Res<Built> {
    let count = |name: &str| -> Res<u32> {
        let at = p.named(name).map_or(span, |q| q.value_span);
        match p.int(name)? {
            Some(n) if n >= 2 => Ok(n as u32),
            Some(n) => Err(Diagnostic::error(at, format!("heightfield: \"{name}\" is {n}; a grid needs at least 2"))),
            None => Err(Diagnostic::error(span, format!("heightfield needs \"integer {name}\""))),
        }
    };
    let (nu, nv) = (count("nu")?, count("nv")?);
    let z =
        p.array("Pz", ParamType::Float)?.ok_or_else(|| Diagnostic::error(span, "heightfield needs \"float Pz\""))?;
    let cells = u64::from(nu) * u64::from(nv);
    if z.floats().len() as u64 != cells {
        let msg = format!("heightfield: \"Pz\" has {} heights; nu × nv = {nu} × {nv} needs {cells}", z.floats().len());
        return Err(Diagnostic::error(z.value_span, msg));
    }
    let tris = 2 * u64::from(nu - 1) * u64::from(nv - 1);
    if tris > ctx.files.limits.triangles {
        let what = format!("heightfield: {nu} × {nv} heights make {tris} triangles, which");
        return Err(Diagnostic::error(z.value_span, Limits::over(what, "triangles", ctx.files.limits.triangles)));
    }
    Ok(Built::Mesh { mesh: grid(nu, nv, |x, y| z.floats()[(x + y * nu) as usize]), kind: NAME, filename: None })
}

/// The mesh of an `nu × nv` grid over the unit square with heights `z(x, y)`, in
/// pbrt-v3's vertex and triangle order (the `nurbs` shape dices the same way).
pub fn grid(nu: u32, nv: u32, z: impl Fn(u32, u32) -> f32) -> TriangleMesh {
    let mut p = Vec::with_capacity((nu * nv) as usize);
    let mut uv = Vec::with_capacity(p.capacity());
    for y in 0..nv {
        for x in 0..nu {
            // pbrt divides in single precision.
            let (u, v) = (x as f32 / (nu - 1) as f32, y as f32 / (nv - 1) as f32);
            p.push([u, v, z(x, y)]);
            uv.push([u, v]);
        }
    }
    TriangleMesh { p, uv: Some(uv), indices: grid_indices(nu, nv), ..Default::default() }
}

/// Two triangles per cell, (x,y)(x+1,y)(x+1,y+1) and (x,y)(x+1,y+1)(x,y+1), as pbrt-v3.
pub fn grid_indices(nu: u32, nv: u32) -> Vec<u32> {
    let vert = |x: u32, y: u32| x + y * nu;
    let mut out = Vec::with_capacity(6 * ((nu - 1) * (nv - 1)) as usize);
    for y in 0..nv - 1 {
        for x in 0..nu - 1 {
            out.extend([vert(x, y), vert(x + 1, y), vert(x + 1, y + 1)]);
            out.extend([vert(x, y), vert(x + 1, y + 1), vert(x, y + 1)]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_has_pbrts_vertices_and_triangles() {
        let m = grid(3, 2, |x, y| (x + 10 * y) as f32);
        assert_eq!(m.p.len(), 6);
        assert_eq!(m.p[4], [0.5, 1.0, 11.0]);
        assert_eq!(m.uv.as_ref().unwrap()[5], [1.0, 1.0]);
        assert_eq!(m.indices, vec![0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4]);
        // Every triangle faces +z over a flat grid (counter-clockwise seen from above).
        let flat = grid(4, 3, |_, _| 0.0);
        for t in 0..flat.triangle_count() {
            let [a, b, c] = flat.vertices(t);
            assert!((b - a).cross(c - a).z > 0.0);
        }
        assert!((flat.area() - 1.0).abs() < 1e-12);
    }
}
