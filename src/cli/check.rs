//! `pbrt-sppm check SCENE --json [--shapes]`: the loaded scene as one JSON object.
//!
//! The layout is a contract (README, "Command line"; extended, never broken): `syntax`,
//! `camera`, `film`, `integrator`, `counts`, `world_bounds`, `warnings`, `skipped`,
//! `approximated`, `pbrt_bugs` (each pbrt bug the scene triggers, where, and whether
//! `--fix` fixes it), and with `--shapes` one entry per
//! created shape (world shapes in creation order, then each instance's shapes) with its
//! parameters after defaults and clamps, row-major `object_to_world`, orientation flags,
//! world-space area and bounds.

use crate::scene::{CameraKind, Geometry, PlacedShape, SceneDescription};
use crate::shapes::Quadric;
use crate::shapes::{QUADRIC_NAMES, ShapeParam};
use glam::{DMat3, DMat4, DVec3};
use serde_json::{Value, json};

/// A float printed with the shortest decimal that round-trips through `f32`
/// (so 0.1 prints as 0.1, not 0.10000000149011612); non-finite values become null.
pub fn f32_json(x: f32) -> Value {
    if !x.is_finite() {
        return Value::Null;
    }
    x.to_string().parse::<f64>().map_or(Value::Null, |v| json!(v))
}

fn f64_json(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

fn vec3(v: DVec3) -> Value {
    json!([f64_json(v.x), f64_json(v.y), f64_json(v.z)])
}

fn row_major(m: &DMat4) -> Value {
    Value::Array(crate::math::transform::row_major(m).iter().map(|&x| f64_json(x)).collect())
}

fn bounds(b: Option<[DVec3; 2]>) -> Value {
    b.map_or(Value::Null, |[lo, hi]| json!([vec3(lo), vec3(hi)]))
}

/// The whole report.
pub fn report(scene: &SceneDescription, with_shapes: bool) -> Value {
    let c = &scene.camera;
    let f = &scene.film;
    let i = &scene.integrator;
    let mut out = json!({
        "syntax": scene.syntax.name(),
        "syntax_evidence": scene.syntax_evidence,
        "colour": if scene.spectral { "spectral" } else { "rgb" },
        "colour_space": scene.color_space.name(),
        "camera": {
            "type": c.kind.name(),
            "fov": f32_json(c.fov),
            "lensradius": f32_json(c.lens_radius),
            "focaldistance": f32_json(c.focal_distance),
            "frameaspectratio": f32_json(c.frame_aspect_ratio),
            "screenwindow": c.screen_window.map(f32_json),
            "shutteropen": f32_json(c.shutter_open),
            "shutterclose": f32_json(c.shutter_close),
            "camera_from_world": row_major(&c.camera_from_world),
            "camera_from_world_end": c.camera_from_world_end.map(|(m, _)| row_major(&m)),
            "transformtimes": c.camera_from_world_end.map(|(_, t)| t),
        },
        "film": film(f),
        "integrator": {
            "type": "sppm",
            "requested": i.requested,
            // No Integrator line: `requested` is pbrt's default for the version.
            "implied": i.implied,
            // What renders it by default (the warnings say why).
            "rendered_with": crate::integrators::Algorithm::by_default(i).name(),
            "iterations": i.iterations,
            "maxdepth": i.max_depth,
            "photonsperiteration": i.photons_per_iteration,
            "radius": f32_json(i.radius),
            "seed": i.seed,
        },
        "counts": counts(scene),
        "memory": memory(scene),
        "world_bounds": bounds(scene.world_bounds()),
        "warnings": scene.warnings,
        "skipped": scene.skipped,
        "approximated": scene.approximated,
        "pbrt_bugs": scene.pbrt_bugs,
        "fixes": scene.fixes.names(),
    });
    if let CameraKind::Spherical(m) = c.kind {
        out["camera"]["mapping"] = json!(match m {
            crate::scene::options::SphericalMapping::EqualArea => "equalarea",
            crate::scene::options::SphericalMapping::Equirectangular => "equirectangular",
        });
    }
    if let Some(l) = &c.lens {
        out["camera"]["lens"] = json!({
            "interfaces": l.data.len() / 4,
            "aperturediameter": l.aperture_diameter,
            "focusdistance": l.focus_distance,
            "filmdiagonal": f32_json(f.diagonal_mm),
        });
    }
    if with_shapes {
        let shapes: Vec<Value> = scene.placed_shapes().enumerate().map(|(k, p)| shape(scene, k, &p)).collect();
        out["shapes"] = Value::Array(shapes);
    }
    out
}

/// The estimated peak memory and the limit it was checked against (`null`: none).
fn memory(scene: &SceneDescription) -> Value {
    let m = &scene.memory;
    json!({
        "estimate_bytes": m.need.bytes(),
        "limit_bytes": (m.limit != u64::MAX).then_some(m.limit),
        "limit_is_free_memory": m.free_memory,
    })
}

/// The film's part of the report.
fn film(f: &crate::scene::Film) -> Value {
    json!({
        "type": f.ty,
        "xresolution": f.x_resolution,
        "yresolution": f.y_resolution,
        "filename": f.filename,
        "cropwindow": f.crop_window.map(f32_json),
        "pixelbounds": f.pixel_bounds,
        "scale": f32_json(f.scale),
        // Extensions: the named camera whose curves film the wavelengths, the
        // pixel filter camera rays follow, the sample clamp, and a spectral film's
        // buckets when they are written (pbrt-v4; null: none).
        "sensor": f.sensor.as_ref().map(|s| s.name),
        // The bound on each sample, by the parameter that sets it (null: none).
        "clamp": f.clamp.map(|c| json!({ c.param().0: c.param().1 })),
        "filter": f.filter.as_ref().map(|p| p.name.clone()),
        "buckets": f.buckets.map(|b| json!({
            "nbuckets": b.count,
            "lambdamin": f32_json(b.lambda_min),
            "lambdamax": f32_json(b.lambda_max),
        })),
    })
}

fn counts(scene: &SceneDescription) -> Value {
    let mut n = [0u64; 6];
    let (mut meshes, mut triangles, mut emitters) = (0u64, 0u64, 0u64);
    let (mut patch_meshes, mut patches, mut curves) = (0u64, 0u64, 0u64);
    for p in scene.placed_shapes() {
        let tris = scene.triangle_count(p.shape) as u64;
        match &p.shape.geometry {
            Geometry::Quadric(q) => n[quadric_slot(q)] += 1,
            Geometry::Mesh { .. } => {
                meshes += 1;
                triangles += tris;
            }
            Geometry::Patches { .. } => {
                patch_meshes += 1;
                patches += scene.prim_count(p.shape) as u64;
            }
            Geometry::Curves { .. } => curves += 1,
        }
        // pbrt makes one light per emissive shape (one per triangle or patch for
        // meshes); area lights inside object definitions are ignored.
        if p.shape.area_light.is_some() && p.instance.is_none() {
            emitters += scene.prim_count(p.shape) as u64;
        }
    }
    let mut counts: serde_json::Map<String, Value> =
        QUADRIC_NAMES.iter().zip(n).map(|(name, k)| (name.to_string(), k.into())).collect();
    counts.insert(crate::shapes::triangle::NAME.into(), meshes.into());
    counts.insert("triangles".into(), triangles.into());
    counts.insert(crate::shapes::bilinear::NAME.into(), patch_meshes.into());
    counts.insert("patches".into(), patches.into());
    counts.insert(crate::shapes::curve::NAME.into(), curves.into());
    counts.insert("instances".into(), scene.instances.len().into());
    counts.insert("moving_instances".into(), scene.instances.iter().filter(|i| i.motion().is_some()).count().into());
    counts.insert("lights".into(), (scene.lights.len() as u64 + emitters).into());
    counts.insert("materials".into(), scene.materials.len().into());
    counts.insert("media".into(), scene.media.len().into());
    Value::Object(counts)
}

fn quadric_slot(q: &Quadric) -> usize {
    QUADRIC_NAMES.iter().position(|n| *n == q.name()).unwrap_or(0)
}

fn shape(scene: &SceneDescription, index: usize, p: &PlacedShape) -> Value {
    let s = p.shape;
    let linear = DMat3::from_mat4(p.object_to_world);
    let params = match &s.geometry {
        Geometry::Quadric(q) => quadric_params(q),
        Geometry::Mesh { mesh, filename, .. } => {
            let m = &scene.meshes[*mesh as usize];
            json!({
                "filename": filename,
                "vertices": m.p.len(),
                "normals": m.n.is_some(),
                "tangents": m.s.is_some(),
                "uv": m.uv.is_some(),
            })
        }
        Geometry::Patches { mesh, filename, .. } => {
            let m = &scene.patches[*mesh as usize];
            json!({ "filename": filename, "vertices": m.p.len(), "normals": m.n.is_some(), "uv": m.uv.is_some() })
        }
        Geometry::Curves { curves } => curves.params(),
    };
    let area = scene.placed_area(p);
    let mut v = json!({
        "index": index,
        "kind": s.kind(),
        "params": params,
        "object_to_world": row_major(&p.object_to_world),
        "reverse_orientation": s.reverse_orientation,
        "swaps_handedness": linear.determinant() < 0.0,
        "area": f64_json(area),
        "bounds": bounds(scene.world_bounds_of(p)),
        "material": s.material,
        "area_light": s.area_light,
    });
    match &s.geometry {
        Geometry::Mesh { .. } => v["triangles"] = json!(scene.prim_count(s)),
        Geometry::Patches { .. } => v["patches"] = json!(scene.prim_count(s)),
        Geometry::Curves { .. } => v["pieces"] = json!(scene.prim_count(s)),
        Geometry::Quadric(_) => {}
    }
    if let Some(i) = p.instance {
        v["instance"] = json!(i);
    }
    v
}

fn quadric_params(q: &Quadric) -> Value {
    let value = |v: ShapeParam| match v {
        ShapeParam::Float(x) => f32_json(x),
        ShapeParam::Angle(r) => f32_json((r as f64).to_degrees() as f32),
        ShapeParam::Point(p) => json!(p.map(f32_json)),
    };
    Value::Object(q.params().into_iter().map(|(name, v)| (name.to_string(), value(v))).collect())
}

/// For a file without an Integrator line, the notice a render prints: what the file's
/// pbrt would use and what renders it here.
pub fn implied_integrator(s: &SceneDescription) -> Option<String> {
    let i = &s.integrator;
    i.implied.then(|| {
        let with = crate::integrators::Algorithm::by_default(i).name();
        format!(
            "note: no Integrator line, so {} would render with \"{}\"; rendering with {with}, which converges \
             to the same image (--integrator, or Integrator \"sppm\" in the file, picks another)",
            s.syntax.pbrt(),
            i.requested
        )
    })
}

/// The scene's nonzero counts on one line ("sphere 2, trianglemesh 1, triangles 12, …").
pub fn counts_line(s: &SceneDescription) -> String {
    let c = counts(s);
    let parts: Vec<String> = c
        .as_object()
        .map(|c| c.iter().filter(|(_, v)| v.as_u64() != Some(0)).map(|(k, v)| format!("{k} {v}")).collect())
        .unwrap_or_default();
    parts.join(", ")
}

/// The text `check` prints: the scene in a few lines, then every skipped, approximated
/// and pbrt-bug statement at its location.
pub fn summary(s: &SceneDescription) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(out, "syntax      {}", s.syntax.name());
    let colour = if s.spectral { "spectral (3 wavelengths per path)" } else { "RGB" };
    let _ = writeln!(out, "colour      {colour}, colour space {}", s.color_space.name());
    let f = &s.film;
    let sensor = f.sensor.as_ref().map(|c| format!(", sensor {}", c.name)).unwrap_or_default();
    let filter = f.filter.as_ref().map(|p| format!(", filter {}", p.name)).unwrap_or_default();
    let buckets = f.buckets.map(|b| format!(", {} buckets {}–{} nm", b.count, b.lambda_min, b.lambda_max));
    let clamp = f.clamp.map(|c| format!(", {} {} (not in SPPM)", c.param().0, c.param().1));
    let filter = filter + &buckets.unwrap_or_default() + &clamp.unwrap_or_default();
    let _ = writeln!(out, "film        {}x{} -> {}{sensor}{filter}", f.x_resolution, f.y_resolution, f.filename);
    let i = &s.integrator;
    let method = crate::integrators::Algorithm::by_default(i).name();
    let implied =
        if i.implied { format!(" ({}'s default: no Integrator line)", s.syntax.pbrt()) } else { String::new() };
    let _ = writeln!(
        out,
        "integrator  \"{}\"{implied}, rendered with {method}: {} iterations, maxdepth {}, {} photons/iteration, radius {}",
        i.requested, i.iterations, i.max_depth, i.photons_per_iteration, i.radius
    );
    let _ = writeln!(out, "counts      {}", counts_line(s));
    let _ = writeln!(out, "memory      {}", s.memory.summary());
    for k in &s.skipped {
        let _ = writeln!(out, "skipped     {}:{}:{}: {} ({})", k.file, k.line, k.column, k.what, k.why);
    }
    for a in &s.approximated {
        let _ = writeln!(out, "approximated {}:{}:{}: {} ({})", a.file, a.line, a.column, a.what, a.how);
    }
    for b in &s.pbrt_bugs {
        let how = if b.fixed { "fixed (--fix)" } else { "rendered as pbrt does" };
        let _ = writeln!(out, "pbrt bug    {}:{}:{}: {} ({how})", b.file, b.line, b.column, b.name);
    }
    if s.pbrt_bugs.iter().any(|b| !b.fixed) {
        let _ = writeln!(
            out,
            "            (`--fix NAME` renders the physically right image; `--fix help` says what each changes)"
        );
    }
    out
}
