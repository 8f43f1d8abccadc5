//! `pbrt-sppm trace SCENE [--rays FILE]`: ray queries against a scene's geometry.
//!
//! Each input line is `ox oy oz dx dy dz [tmax]` in world space (`#` comments and blank
//! lines are skipped). t is in units of the given direction, which is not normalised.
//! Each ray gives one JSON line: `{"hit": false}` or the hit's `t`, `p`, `p_error`, `n`
//! (unit geometric normal oriented by pbrt's rules, never turned toward the ray), `ns`,
//! `uv`, `dpdu`, `dpdv`, `shape`, `shape_index` (as in `check --shapes`) and `triangle`
//! for meshes.

use crate::accel::{Geometry, LocalHit};
use crate::cli::check::f32_json;
use crate::math::{Point3, Ray, Vector3};
use crate::scene::SceneDescription;
use serde_json::{Value, json};
use std::io::{BufRead, Write};

/// Why the answers stopped: a line that is not a ray, or an output that cannot be
/// written.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    #[error("line {line}: {message}")]
    Line { line: usize, message: String },
    #[error("cannot write: {0}")]
    Write(std::io::Error),
}

/// The geometry plus the shape names, in `check --shapes` order.
pub struct Tracer {
    pub geometry: Geometry,
    kinds: Vec<&'static str>,
}

impl Tracer {
    pub fn new(scene: &SceneDescription) -> Tracer {
        let kinds = scene.placed_shapes().map(|p| p.shape.kind()).collect();
        Tracer { geometry: Geometry::new(scene), kinds }
    }

    /// Answers every line of `input` on `out`, stopping at the first malformed line.
    pub fn answer(&self, input: impl BufRead, out: &mut impl Write) -> Result<(), TraceError> {
        for (i, line) in input.lines().enumerate() {
            let located = |message: String| TraceError::Line { line: i + 1, message };
            let text = line.map_err(|e| located(e.to_string()))?;
            if let Some(v) = self.line(&text).map_err(located)? {
                writeln!(out, "{v}").map_err(TraceError::Write)?;
            }
        }
        out.flush().map_err(TraceError::Write)
    }

    /// One input line: `Ok(None)` for blank lines and comments.
    pub fn line(&self, text: &str) -> Result<Option<Value>, String> {
        let text = text.split('#').next().unwrap_or_default().trim();
        if text.is_empty() {
            return Ok(None);
        }
        let nums: Vec<f32> = text
            .split_whitespace()
            .map(|w| w.parse::<f32>().map_err(|_| format!("'{w}' is not a number")))
            .collect::<Result<_, _>>()?;
        let (o, d, t_max) = match nums.as_slice() {
            [ox, oy, oz, dx, dy, dz] => ([*ox, *oy, *oz], [*dx, *dy, *dz], f32::INFINITY),
            [ox, oy, oz, dx, dy, dz, t] => ([*ox, *oy, *oz], [*dx, *dy, *dz], *t),
            _ => return Err(format!("expected 6 or 7 numbers (ox oy oz dx dy dz [tmax]), found {}", nums.len())),
        };
        Ok(Some(self.trace(&query(o, d, t_max)?)))
    }

    /// One ray's answer as the contract's JSON object.
    pub fn trace(&self, ray: &Ray) -> Value {
        let Some(h) = self.hit(ray) else { return json!({"hit": false}) };
        let v = |a: [f32; 3]| a.map(f32_json);
        let mut out = json!({
            "hit": true,
            "t": f32_json(h.t),
            "p": v(h.p),
            "p_error": v(h.p_error),
            "n": v(h.n),
            "ns": v(h.ns),
            "uv": h.uv.map(f32_json),
            "dpdu": v(h.dpdu),
            "dpdv": v(h.dpdv),
            "shape": h.shape,
            "shape_index": h.shape_index,
        });
        if let Some(k) = h.triangle {
            out["triangle"] = json!(k);
        }
        if let Some(k) = h.patch {
            out["patch"] = json!(k);
        }
        out
    }

    /// One ray's first hit, with the fields of the `trace` contract.
    pub fn hit(&self, ray: &Ray) -> Option<TraceHit> {
        let hit = self.geometry.intersect(ray)?;
        let si = self.geometry.interaction(&hit);
        let (triangle, patch) = match hit.local {
            LocalHit::Triangle { mesh, tri, .. } => (Some(self.geometry.triangle_id(mesh, tri)), None),
            LocalHit::Patch { patch, .. } => (None, Some(patch)),
            LocalHit::Quadric(..) | LocalHit::Curve { .. } => (None, None),
        };
        Some(TraceHit {
            t: hit.t,
            p: si.p.to_array(),
            p_error: si.p_error.to_array(),
            n: si.n.to_array(),
            ns: si.shading.n.to_array(),
            uv: si.uv,
            dpdu: si.dpdu.to_array(),
            dpdv: si.dpdv.to_array(),
            shape: self.kinds.get(hit.shape_index as usize).copied().unwrap_or("?"),
            shape_index: hit.shape_index,
            triangle,
            patch,
        })
    }
}

/// A query's ray: the origin and direction finite, the direction nonzero, tmax not NaN.
pub fn query(o: [f32; 3], d: [f32; 3], t_max: f32) -> Result<Ray, String> {
    if d == [0.0; 3] || !o.iter().chain(&d).all(|x| x.is_finite()) || t_max.is_nan() {
        return Err("the origin and direction must be finite and the direction nonzero".into());
    }
    Ok(Ray { o: Point3::new(o[0], o[1], o[2]), d: Vector3::new(d[0], d[1], d[2]), t_max, time: 0.0 })
}

/// A ray's first hit as `trace` reports it (see the module docs for each field).
#[derive(Clone, Debug, PartialEq)]
pub struct TraceHit {
    pub t: f32,
    pub p: [f32; 3],
    pub p_error: [f32; 3],
    pub n: [f32; 3],
    pub ns: [f32; 3],
    pub uv: [f32; 2],
    pub dpdu: [f32; 3],
    pub dpdv: [f32; 3],
    pub shape: &'static str,
    pub shape_index: u32,
    /// The triangle's index in its mesh as the file gave it (meshes only).
    pub triangle: Option<u32>,
    /// The patch's index in its bilinear mesh (`bilinearmesh` only).
    pub patch: Option<u32>,
}
