//! Every shape's parameters: defaults, clamps, swaps, validity checks, mesh sources,
//! world-space areas and bounds.

use crate::common::{close, load, num, report, root, scene, warnings, world_shapes};
use serde_json::{Value, json};
use std::f64::consts::PI;

fn one(world: &str) -> Value {
    let s = world_shapes(world);
    assert_eq!(s.len(), 1, "{world}");
    s[0].clone()
}

fn params(world: &str) -> Value {
    one(world)["params"].clone()
}

#[test]
fn sphere_defaults_clamps_and_swaps() {
    assert_eq!(params(r#"Shape "sphere""#), json!({"radius": 1.0, "zmin": -1.0, "zmax": 1.0, "phimax": 360.0}));
    assert_eq!(params(r#"Shape "sphere" "float radius" 2"#)["zmin"], -2.0, "zmin defaults to -radius");
    let p = params(r#"Shape "sphere" "float radius" 2 "float zmin" 5 "float zmax" -0.5 "float phimax" 400"#);
    assert_eq!(p, json!({"radius": 2.0, "zmin": -0.5, "zmax": 2.0, "phimax": 360.0}));
    assert_eq!(params(r#"Shape "sphere" "float phimax" -10"#)["phimax"], 0.0);
    let s = one(r#"Shape "sphere" "float radius" 2 "float zmin" -1 "float zmax" 1.5 "float phimax" 90"#);
    assert!(close(num(&s["area"]), PI / 2.0 * 2.0 * 2.5, 1e-6), "{}", s["area"]);
}

#[test]
fn cylinder_disk_cone_paraboloid_defaults() {
    assert_eq!(params(r#"Shape "cylinder""#), json!({"radius": 1.0, "zmin": -1.0, "zmax": 1.0, "phimax": 360.0}));
    let p = params(r#"Shape "cylinder" "float radius" 0.5 "float zmin" 3 "float zmax" 2"#);
    assert_eq!((p["zmin"].clone(), p["zmax"].clone()), (json!(2.0), json!(3.0)), "swapped, not radius-relative");
    assert_eq!(params(r#"Shape "disk""#), json!({"height": 0.0, "radius": 1.0, "innerradius": 0.0, "phimax": 360.0}));
    assert_eq!(params(r#"Shape "cone""#), json!({"height": 1.0, "radius": 1.0, "phimax": 360.0}));
    assert_eq!(params(r#"Shape "paraboloid""#), json!({"radius": 1.0, "zmin": 0.0, "zmax": 1.0, "phimax": 360.0}));
    let p = params(r#"Shape "paraboloid" "float zmin" 2 "float zmax" 0.5"#);
    assert_eq!((p["zmin"].clone(), p["zmax"].clone()), (json!(0.5), json!(2.0)));
}

#[test]
fn closed_form_areas() {
    let cases = [
        (r#"Shape "cylinder" "float radius" 2 "float zmin" 0 "float zmax" 3 "float phimax" 180"#, PI * 2.0 * 3.0),
        (r#"Shape "disk" "float radius" 2 "float innerradius" 1 "float phimax" 180"#, PI / 2.0 * 3.0),
        (r#"Shape "cone" "float radius" 3 "float height" 4"#, PI * 3.0 * 5.0),
        // Paraboloid z = x² + y² up to z = 1: π/6 (5√5 − 1).
        (r#"Shape "paraboloid""#, PI / 6.0 * (5.0 * 5f64.sqrt() - 1.0)),
    ];
    for (shape, area) in cases {
        let got = num(&one(shape)["area"]);
        assert!(close(got, area, 1e-6), "{shape}: {got} vs {area}");
    }
}

#[test]
fn hyperboloid_parameters_and_true_area() {
    let s = one(r#"Shape "hyperboloid" "point p1" [1 0 -1] "point p2" [0 1 1]"#);
    assert_eq!(s["params"]["p1"], json!([1.0, 0.0, -1.0]));
    assert_eq!((s["params"]["zmin"].clone(), s["params"]["rmax"].clone()), (json!(-1.0), json!(1.0)));
    // pbrt-v3's formula gives 26.18 here; the surface of revolution has area ≈ 10.77.
    let numeric = 2.0
        * PI
        * integrate(|v: f64| {
            let (x, y) = (1.0 - v, v);
            (4.0 * (x * x + y * y) + (-x + y).powi(2)).sqrt()
        });
    assert!(close(num(&s["area"]), numeric, 1e-6), "{} vs {numeric}", s["area"]);
    assert!((numeric - 10.77).abs() < 0.01);
}

fn integrate(f: impl Fn(f64) -> f64) -> f64 {
    let n = 200_000;
    (0..n).map(|i| f((i as f64 + 0.5) / n as f64)).sum::<f64>() / n as f64
}

#[test]
fn world_areas_under_any_transform() {
    // A unit disk scaled by (2, 3, 7): an ellipse of area 6π.
    let s = one(r#"Scale 2 3 7 Shape "disk""#);
    assert!(close(num(&s["area"]), 6.0 * PI, 1e-6), "{}", s["area"]);
    // A unit sphere scaled by (1, 1, 2): a prolate spheroid, area 2π(1 + 2·asin(e)/e), e = √3/2.
    let e = 3f64.sqrt() / 2.0;
    let s = one(r#"Scale 1 1 2 Shape "sphere""#);
    assert!(close(num(&s["area"]), 2.0 * PI * (1.0 + 2.0 * e.asin() / e), 1e-6), "{}", s["area"]);
    // Mirrored and rotated: area unchanged, handedness flips.
    let s = one(r#"Rotate 33 1 2 3 Scale -1 1 1 Shape "cylinder""#);
    assert!(close(num(&s["area"]), 4.0 * PI, 1e-6));
    assert_eq!(s["swaps_handedness"], true);
    // Meshes under a shear.
    let s = one(
        r#"ConcatTransform [1 0 0 0  1 1 0 0  0 0 1 0  0 0 0 1] Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0]"#,
    );
    assert!(close(num(&s["area"]), 0.5, 1e-12));
}

#[test]
fn bounds_are_world_space() {
    let s = one(r#"Translate 1 2 3 Shape "sphere" "float radius" 2 "float zmax" 1"#);
    assert_eq!(s["bounds"], json!([[-1.0, 0.0, 1.0], [3.0, 4.0, 4.0]]));
}

#[test]
fn triangle_mesh_arrays_and_checks() {
    let s = scene(
        r#"WorldBegin
        Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 1 1 0 0 1 0] "integer indices" [0 1 2 0 2 3 0]
          "normal N" [0 0 1 0 0 1 0 0 1 0 0 1] "vector3 S" [1 0 0] "point2 uv" [0 0 1 0 1 1 0 1 5 5]
          "integer faceIndices" [7 8]
        Shape "trianglemesh" "point P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2] "float st" [0 0 1 0]
        WorldEnd"#,
    );
    let m = &s.meshes[0];
    assert_eq!(m.indices, [0, 1, 2, 0, 2, 3], "the partial triangle is dropped");
    assert!(m.n.is_some() && m.s.is_none(), "S with the wrong count is ignored");
    assert_eq!(m.uv.as_ref().map(Vec::len), Some(4), "extra uv dropped");
    assert_eq!(m.face_indices, Some(vec![7, 8]));
    let second = &s.meshes[1];
    assert!(second.uv.is_none(), "too few uv are ignored");
    let msgs: Vec<&str> = s.warnings.iter().map(|w| w.message.as_str()).collect();
    assert_eq!(msgs.len(), 4, "{msgs:?}");
}

#[test]
fn loopsubdiv_refines_to_a_closed_limit_mesh_with_normals() {
    let tetra = r#""point3 P" [1 1 1  -1 -1 1  -1 1 -1  1 -1 -1] "integer indices" [0 1 2 0 2 3 0 3 1 1 3 2]"#;
    // v4 defaults to 3 levels; v3 also reads "nlevels".
    let s = scene(&format!("WorldBegin Shape \"loopsubdiv\" {tetra}"));
    let m = &s.meshes[0];
    assert_eq!(m.triangle_count(), 4 * 64);
    assert_eq!(m.p.len(), 2 + m.triangle_count() / 2, "a closed surface: V = 2 + F/2");
    assert_eq!(m.n.as_ref().map(Vec::len), Some(m.p.len()));
    assert!(m.p.iter().all(|p| glam::Vec3::from(*p).length() < 3f32.sqrt()), "the limit lies inside the hull");
    let s = scene(&format!("WorldBegin Translate 0 0 10 Shape \"loopsubdiv\" \"integer nlevels\" 1 {tetra}"));
    assert_eq!(s.meshes[0].triangle_count(), 16);
    assert!(s.meshes[0].p.iter().all(|p| p[2] > 8.0), "stored in world space");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let r = report(&format!("WorldBegin Shape \"loopsubdiv\" \"integer levels\" 2 {tetra}"));
    assert_eq!(r["shapes"][0]["kind"], "loopsubdiv");
    assert_eq!(r["counts"]["triangles"], 64);
    // A level count past the triangle limit is a located error, before any work.
    let e = load(&format!("WorldBegin\nShape \"loopsubdiv\" \"integer levels\" 40 {tetra}")).unwrap_err();
    assert!(e.to_string().contains("inline.pbrt:2:37: error") && e.to_string().contains("--limit triangles"), "{e}");
}

#[test]
fn meshes_are_stored_transformed_like_pbrt() {
    let s = scene(
        r#"WorldBegin Translate 0 0 5 Scale 2 2 2 Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "normal N" [0 0 1 0 0 1 0 0 1]"#,
    );
    assert_eq!(s.meshes[0].p, [[0.0, 0.0, 5.0], [2.0, 0.0, 5.0], [0.0, 2.0, 5.0]]);
    assert_eq!(s.meshes[0].n.as_ref().unwrap()[0], [0.0, 0.0, 0.5]);
}

/// pbrt-v4 refines a PLY mesh with a `displacement` texture until its edges are
/// shorter than `edgelength` and moves each vertex along its normal by the texture;
/// pbrt-v3 has no displacement (the parameter is unused there).
#[test]
fn a_displaced_plymesh_is_refined_and_moved_along_its_normals() {
    let ply = "Shape \"plymesh\" \"string filename\" \"../../../pbrt-scenes/v3/geometry/icosphere.ply\"";
    let text = format!(
        "WorldBegin\nTexture \"d\" \"float\" \"constant\" \"float value\" 0.1\n\
         {ply} \"texture displacement\" \"d\" \"float edgelength\" 0.2\n"
    );
    let plain = &scene(&format!("WorldBegin\n{ply}\n")).meshes[0];
    let s = scene(&text);
    let m = &s.meshes[0];
    assert!(m.triangle_count() > 4 * plain.triangle_count(), "{} triangles", m.triangle_count());
    assert!(s.warnings.is_empty() && s.approximated.is_empty(), "{:?}", s.warnings);
    // The file's vertices (first in the list) move out by 0.1 along their unit normals.
    let r = |p: [f32; 3]| glam::Vec3::from(p).length();
    for (a, b) in plain.p.iter().zip(&m.p) {
        assert!((r(*b) - r(*a) - 0.1).abs() < 1e-4, "{a:?} -> {b:?}");
    }
    // No edge is 0.2 long or more before displacement: after, none is much more.
    let longest = m
        .indices
        .chunks_exact(3)
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .map(|(a, b)| glam::Vec3::from(m.p[a as usize]).distance(glam::Vec3::from(m.p[b as usize])))
        .fold(0.0f32, f32::max);
    assert!(longest < 0.2 * 1.2, "{longest}");
    // pbrt-v3 reads no displacement.
    let v3 = scene(&format!("{text}WorldEnd\n"));
    assert_eq!(v3.meshes[0].triangle_count(), plain.triangle_count());
    assert!(
        v3.warnings.iter().any(|w| w.message.contains("\"texture displacement\" is not used")),
        "{:?}",
        v3.warnings
    );
    // Only a texture displaces (pbrt-v4 reads no other type there): a v4 file's quads
    // stay patches.
    let slab = "Shape \"plymesh\" \"string filename\" \"../../../pbrt-scenes/v3/geometry/slab_be.ply\"";
    let s = scene(&format!("WorldBegin\n{slab} \"float displacement\" 0.1\n"));
    assert!(s.meshes.is_empty() && s.patches.len() == 1, "{} meshes", s.meshes.len());
    // Without (u, v) pbrt-v4 stops; so do we, at the texture parameter.
    let e = crate::common::load(
        "WorldBegin\nTexture \"d\" \"float\" \"constant\"\nShape \"plymesh\" \"string filename\" \
         \"../../../pbrt-scenes/v3/geometry/slab_be.ply\" \"texture displacement\" \"d\" \"float edgelength\" 0\n",
    )
    .unwrap_err()
    .one_line();
    assert!(e.contains("edgelength") && e.contains(":3:"), "{e}");
}

#[test]
fn plymesh_ascii_binary_quads_and_uv_names() {
    let s = scene(r#"WorldBegin Shape "plymesh" "string filename" "../../../pbrt-scenes/v3/geometry/icosphere.ply""#);
    let m = &s.meshes[0];
    assert_eq!((m.p.len(), m.triangle_count()), (42, 80));
    assert!(m.n.is_some() && m.uv.is_some());
    // Only the WorldEnd after the shape says this is a pbrt-v3 file: quads are split.
    let slab = r#"Shape "plymesh" "string filename" "../../../pbrt-scenes/v3/geometry/slab_be.ply""#;
    let s = scene(&format!("WorldBegin {slab} WorldEnd"));
    assert!(s.patches.is_empty());
    let m = &s.meshes[0];
    assert_eq!((m.p.len(), m.triangle_count()), (25, 32), "16 quads split in two");
    // Quad (a,b,c,d) = (0,1,6,5) becomes (0,1,6) and (5,0,6).
    assert_eq!(&m.indices[..6], [0, 1, 6, 5, 0, 6]);
    assert_eq!(m.uv.as_ref().unwrap()[6], [0.25, 0.25], "s t names");
    assert_eq!(&m.face_indices.as_ref().unwrap()[..4], [0, 0, 1, 1]);
    // pbrt-v4 keeps each quad as the bilinear patch (a, b, d, c).
    let s = scene(&format!("WorldBegin {slab}"));
    assert!(s.meshes.is_empty());
    let m = &s.patches[0];
    assert_eq!((m.p.len(), m.patch_count()), (25, 16));
    assert_eq!(&m.indices[..4], [0, 1, 5, 6]);
    assert_eq!(m.uv.as_ref().unwrap()[6], [0.25, 0.25]);
    assert_eq!(&m.face_indices.as_ref().unwrap()[..2], [0, 1]);
}

/// A PLY of one triangle and one non-planar quad, ASCII.
fn mixed_ply(dir: &std::path::Path) {
    std::fs::create_dir_all(dir).unwrap();
    let text = "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n\
                element face 2\nproperty list uchar int vertex_indices\nend_header\n\
                5 0 0\n6 0 0\n5 1 0\n0 0 0\n1 0 0\n1 1 1\n0 1 0\n3 0 1 2\n4 3 4 5 6\n";
    std::fs::write(dir.join("mixed.ply"), text).unwrap();
}

#[test]
fn v4_ply_of_triangles_and_quads_is_two_shapes_in_file_order() {
    let dir = crate::common::Scratch::new("mixed-ply");
    mixed_ply(&dir);
    let world = "WorldBegin\nShape \"sphere\"\nShape \"plymesh\" \"string filename\" \"mixed.ply\"\nShape \"disk\"\n";
    let report_of = |text: &str| {
        let path = dir.join("scene.pbrt");
        std::fs::write(&path, text).unwrap();
        let s = crate::common::load_file(&path).unwrap_or_else(|e| panic!("{e}"));
        pbrt_sppm::cli::check::report(&s, true)
    };
    // No version evidence before the shape: read at the end, as pbrt-v4 (the default).
    let r = report_of(world);
    let kinds: Vec<_> = r["shapes"].as_array().unwrap().iter().map(|s| s["kind"].clone()).collect();
    assert_eq!(kinds, [json!("sphere"), json!("plymesh"), json!("plymesh"), json!("disk")]);
    let shapes = r["shapes"].as_array().unwrap();
    assert_eq!((shapes[1]["triangles"].clone(), shapes[2]["patches"].clone()), (json!(1), json!(1)));
    assert_eq!(shapes[2]["params"]["filename"], "mixed.ply");
    assert_eq!((r["counts"]["triangles"].clone(), r["counts"]["patches"].clone()), (json!(1), json!(1)));
    // The quad (0,0,0) (1,0,0) (1,1,1) (0,1,0) is twisted: the patch z = uv is not the
    // two triangles, and its area (∫∫ sqrt(1 + u² + v²)) is smaller than theirs (√2).
    let patch_area = num(&shapes[2]["area"]);
    assert!(close(patch_area, 1.2808, 1e-4), "{patch_area}");
    // pbrt-v3 splits it.
    let r = report_of(&format!("{world}WorldEnd\n"));
    let shapes = r["shapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 3);
    assert_eq!(shapes[1]["triangles"], 3);
    let split_area = num(&shapes[1]["area"]) - 0.5;
    assert!(close(split_area, 2f64.sqrt(), 1e-6), "{split_area}");
}

/// World `plymesh` files are read on the thread pool while the scene is read on, and
/// built at the end of the world: the shapes, meshes and warnings are those of reading
/// them in turn, and a file's error still comes before the errors of later statements
/// and of the end of the world.
#[test]
fn plymesh_files_read_ahead_keep_order_and_first_errors() {
    let tri = |z: f32, degenerate: bool| {
        let far = if degenerate { 0 } else { 1 };
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 {z}\n1 0 {z}\n0 {far} {z}\n\
             3 0 1 2\n3 0 1 2\n"
        )
    };
    let bad = "ply\nformat ascii 1.0\nelement vertex 3\n";
    let (a, b) = (tri(1.0, false), tri(2.0, true));
    let dir = crate::common::scratch("read-ahead", "order", &[("a.ply", &a), ("b.ply", &b), ("bad.ply", bad)]);
    let load = |lines: &[&str]| {
        let text = format!("Film \"rgb\"\nWorldBegin\n{}\n", lines.join("\n"));
        std::fs::write(dir.join("scene.pbrt"), text).unwrap();
        crate::common::load_file(&dir.join("scene.pbrt"))
    };
    let ply = |f: &str| format!("Shape \"plymesh\" \"string filename\" \"{f}.ply\"");
    let (pa, pb, pbad) = (ply("a"), ply("b"), ply("bad"));
    let s = load(&["Shape \"sphere\"", &pa, "Shape \"disk\"", &pb, &pa]).unwrap_or_else(|e| panic!("{e}"));
    let r = pbrt_sppm::cli::check::report(&s, true);
    let shapes = r["shapes"].as_array().unwrap();
    let kinds: Vec<_> = shapes.iter().map(|s| s["kind"].clone()).collect();
    assert_eq!(kinds, [json!("sphere"), json!("plymesh"), json!("disk"), json!("plymesh"), json!("plymesh")]);
    let files: Vec<_> = shapes.iter().map(|s| s["params"]["filename"].clone()).collect();
    assert_eq!(files[1..], [json!("a.ply"), Value::Null, json!("b.ply"), json!("a.ply")]);
    // The meshes in their places: z = 1, 2, 1 (b's triangles have zero area).
    let z = |i: usize| match &s.shapes[i].geometry {
        pbrt_sppm::scene::Geometry::Mesh { mesh, .. } => s.meshes[*mesh as usize].p[0][2],
        _ => panic!("shape {i} is not a mesh"),
    };
    assert_eq!([z(1), z(3), z(4)], [1.0, 2.0, 1.0]);
    let degenerate: Vec<_> = s.warnings.iter().filter(|w| w.message.contains("zero area")).collect();
    assert_eq!(degenerate.len(), 1, "{:?}", s.warnings);
    assert_eq!(degenerate[0].line, 6, "b.ply's statement");
    // A broken file's error, located at its statement, beats what comes after it: a
    // bad statement, an undefined object at the end of the world, a second bad file.
    for after in ["Bogus 1 2 3", "ObjectInstance \"nowhere\"", &pbad] {
        let e = load(&[&pa, &pbad, "Shape \"disk\"", after]).expect_err("bad.ply").to_string();
        assert!(e.contains("scene.pbrt:4:") && e.contains("bad.ply"), "after {after:?}: {e}");
    }
}

/// Writes a PLY with the given format and texture-coordinate names and loads it.
fn ply_roundtrip(format: &str, uv: (&str, &str)) -> pbrt_sppm::shapes::TriangleMesh {
    let dir = crate::common::Scratch::new(&format!("ply-{format}-{}", uv.0));
    let head = format!(
        "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property float {}\nproperty float {}\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n",
        uv.0, uv.1
    );
    let verts = [[0.0f32, 0.0, 0.0, 0.1, 0.2], [1.0, 0.0, 0.0, 0.3, 0.4], [0.0, 1.0, 0.0, 0.5, 0.6]];
    let mut bytes = head.into_bytes();
    if format == "ascii" {
        for v in verts {
            bytes.extend(format!("{} {} {} {} {}\n", v[0], v[1], v[2], v[3], v[4]).bytes());
        }
        bytes.extend(b"3 0 1 2\n");
    } else {
        let big = format == "binary_big_endian";
        for x in verts.iter().flatten() {
            bytes.extend(if big { x.to_be_bytes() } else { x.to_le_bytes() });
        }
        bytes.push(3);
        for i in [0u32, 1, 2] {
            bytes.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
        }
    }
    std::fs::write(dir.join("t.ply"), bytes).unwrap();
    let path = dir.join("scene.pbrt");
    std::fs::write(&path, "WorldBegin\nShape \"plymesh\" \"string filename\" \"t.ply\"\n").unwrap();
    let s = crate::common::load_file(&path).unwrap_or_else(|e| panic!("{format}: {e}"));
    (*s.meshes[0]).clone()
}

#[test]
fn ply_every_encoding_and_texture_coordinate_name() {
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        for uv in [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")] {
            let m = ply_roundtrip(format, uv);
            assert_eq!(m.p, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], "{format} {uv:?}");
            assert_eq!(m.indices, [0, 1, 2]);
            assert_eq!(m.uv, Some(vec![[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]]), "{format} {uv:?}");
        }
    }
}

#[test]
fn objmesh_extension() {
    let s = scene(r#"WorldBegin Shape "objmesh" "string filename" "../../../pbrt-scenes/v3/geometry/cube.obj""#);
    let m = &s.meshes[0];
    assert_eq!((m.p.len(), m.triangle_count()), (8, 12));
    assert!(close(m.area(), 6.0, 1e-12));
}

#[test]
fn unknown_shapes_in_v3_files_are_skipped_with_one_warning() {
    // pbrt-v3 warns and goes on (pbrt-v4 stops: tests/it/messages.rs).
    let s = scene(
        "Film \"image\" WorldBegin\nShape \"blob\" \"point3 P\" [0 0 0 1 1 1 2 2 2 3 3 3]\nShape \"sphere\" \"float alpha\" 0.5\nWorldEnd\n",
    );
    assert_eq!(s.shapes.len(), 1);
    assert_eq!(s.skipped.len(), 1);
    assert_eq!((s.skipped[0].line, s.skipped[0].column, s.skipped[0].what.as_str()), (2, 7, "Shape \"blob\""));
    let msgs: Vec<&str> = s.warnings.iter().map(|w| w.message.as_str()).collect();
    assert_eq!(msgs, ["Shape \"blob\": unknown shape type \"blob\"; left out, as pbrt-v3 leaves it out"]);
    // The sphere's alpha of 0.5 is opaque in pbrt-v3 (only 0 cuts), nothing approximated.
    assert!(s.approximated.is_empty());
    assert_eq!(s.shapes[0].alpha.map(|a| a.alpha), None);
    assert!(root().exists());
}

/// Two saddle patches z = u·v side by side (the second shifted by 1 in x), sharing an
/// edge.
const SADDLES: &str = r#"Shape "bilinearmesh" "point3 P" [0 0 0  1 0 0  0 1 0  1 1 1  2 0 0  2 1 0]
    "integer indices" [0 1 2 3  1 4 3 5]"#;

#[test]
fn bilinear_meshes_report_patches_areas_and_lights() {
    // ∫∫ √(1 + u² + v²) over the unit square, per saddle (the second is a mirror image).
    let saddle = 1.280_789_261_6;
    let s = one(SADDLES);
    assert_eq!(s["kind"], "bilinearmesh");
    assert_eq!(s["patches"], 2);
    assert_eq!(s["params"]["vertices"], 6);
    assert!(close(num(&s["area"]), 2.0 * saddle, 1e-6), "{}", s["area"]);
    let scaled = one(&format!("Scale 2 2 2\n{SADDLES}"));
    assert!(close(num(&scaled["area"]), 8.0 * saddle, 1e-6), "{}", scaled["area"]);
    // Inside an instance, the instance's scale counts too.
    let r =
        report(&format!("WorldBegin\nObjectBegin \"s\"\n{SADDLES}\nObjectEnd\nScale 3 3 3\nObjectInstance \"s\"\n"));
    assert!(close(num(&r["shapes"][0]["area"]), 18.0 * saddle, 1e-6), "{}", r["shapes"][0]["area"]);
    // One light per patch, as in pbrt-v4.
    let r = report(&format!("WorldBegin\nAreaLightSource \"diffuse\"\n{SADDLES}\n"));
    assert_eq!((r["counts"]["bilinearmesh"].clone(), r["counts"]["patches"].clone()), (json!(1), json!(2)));
    assert_eq!(r["counts"]["lights"], 2);
}

#[test]
fn bilinear_mesh_inputs_are_checked_as_pbrt_v4_checks_them() {
    // One patch of four points may leave out its indices.
    let s = one(r#"Shape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0]"#);
    assert_eq!((s["patches"].clone(), num(&s["area"])), (json!(1), 1.0));
    // Extra indices are dropped with a warning; N of the wrong count is ignored.
    let sc = scene(
        "WorldBegin\nShape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"integer indices\" [0 1 2 3 0 1]\n\
         \"normal N\" [0 0 1]",
    );
    let msgs: Vec<&str> = sc.warnings.iter().map(|w| w.message.as_str()).collect();
    assert!(msgs.iter().any(|m| m.contains("not a multiple of 4; the last 2 are ignored")), "{msgs:?}");
    assert!(msgs.iter().any(|m| m.contains("\"N\" has 1 entries")), "{msgs:?}");
    assert_eq!(sc.patches[0].patch_count(), 1);
    assert!(sc.patches[0].n.is_none());
    // Errors, located.
    for (text, wanted, col) in [
        (
            r#"Shape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0] "integer indices" [0 1 2 4]"#,
            "vertex index 4 is out of range",
            77,
        ),
        (
            r#"Shape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0 2 2 2]"#,
            "bilinearmesh needs \"integer indices\"",
            7,
        ),
        (r#"Shape "bilinearmesh" "integer indices" [0 1 2 3]"#, "bilinearmesh needs \"point3 P\"", 7),
    ] {
        let e = load(&format!("WorldBegin\n{text}\n")).expect_err(text).to_string();
        assert!(e.contains(wanted) && e.contains(&format!(":2:{col}:")), "{e}");
    }
}

/// pbrt-v3 reports a PLY file it cannot open and renders without the shape (world or
/// instanced, emitting or not); pbrt-v4 stops.
#[test]
fn a_v3_ply_file_that_cannot_be_read_is_left_out_with_a_warning() {
    let body = |film: &str| {
        format!(
            "{film}\nWorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\"\n\
             Shape \"plymesh\" \"string filename\" \"nowhere.ply\"\nAttributeEnd\n\
             ObjectBegin \"o\"\nShape \"plymesh\" \"string filename\" \"nowhere.ply\"\nObjectEnd\n\
             ObjectInstance \"o\"\nShape \"sphere\"\n"
        )
    };
    let s = crate::common::scene(&body("Film \"image\""));
    assert_eq!((s.shapes.len(), s.area_lights.len()), (1, 0), "the sphere alone, no light");
    assert!(s.objects.iter().all(|o| o.shapes.is_empty()));
    let w: Vec<String> = warnings(&s).into_iter().filter(|m| m.contains("nowhere.ply")).collect();
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(w.iter().all(|m| m.contains("left out, as pbrt-v3")), "{w:?}");
    let e = crate::common::load(&body("Film \"rgb\"")).expect_err("pbrt-v4 stops").to_string();
    assert!(e.contains(":5:35: error: cannot read"), "{e}");
}

/// pbrt-v3 reports a `trianglemesh` without `P` or `indices` (even a single
/// triangle) or with an index past its last vertex, and leaves it out; pbrt-v4 stops,
/// or takes three points as one triangle.
#[test]
fn a_v3_trianglemesh_pbrt_v3_cannot_make_is_left_out_with_a_warning() {
    let quad = "\"point P\" [-1 -1 0 1 -1 0 1 1 0 -1 1 0]";
    let v3 =
        |mesh: &str| scene(&format!("Film \"image\"\nWorldBegin\nShape \"trianglemesh\" {mesh}\nShape \"sphere\"\n"));
    let v4 = |mesh: &str| load(&format!("Film \"rgb\"\nWorldBegin\nShape \"trianglemesh\" {mesh}\nShape \"sphere\"\n"));
    for (mesh, why) in [
        (quad.to_string(), "needs \"integer indices\""),
        ("\"point P\" [0 0 0 1 0 0 0 1 0]".to_string(), "needs \"integer indices\""),
        ("\"integer indices\" [0 1 2]".to_string(), "needs \"point3 P\""),
        (format!("{quad} \"integer indices\" [0 1 2 0 2 4]"), "vertex index 4 is out of range"),
    ] {
        let s = v3(&mesh);
        if !mesh.contains("[0 1 2 0 2 4]") {
            // So is a loopsubdiv without either array (pbrt-v3 checks no index).
            let loop_mesh = scene(&format!("Film \"image\"\nWorldBegin\nShape \"loopsubdiv\" {mesh}\n"));
            assert!(loop_mesh.shapes.is_empty(), "{mesh}");
            assert!(warnings(&loop_mesh).iter().any(|m| m.contains("loopsubdiv needs")), "{mesh}");
        }
        assert_eq!(s.shapes.len(), 1, "{mesh}: the sphere alone");
        let w: Vec<String> = warnings(&s).into_iter().filter(|m| m.contains("left out")).collect();
        assert!(w.len() == 1 && w[0].contains(why), "{mesh}: {w:?}");
    }
    let e = load(&format!("Film \"image\"\nWorldBegin\nShape \"trianglemesh\" {quad} \"integer indices\" [0 -1 2]"));
    assert!(e.expect_err("negative").to_string().contains(":3:"), "a negative index stays an error");
    assert_eq!(v4("\"point P\" [0 0 0 1 0 0 0 1 0]").expect("one triangle").shapes.len(), 2);
    for mesh in [quad.to_string(), format!("{quad} \"integer indices\" [0 1 2 0 2 4]")] {
        assert!(v4(&mesh).expect_err(&mesh).to_string().contains(":3:"), "{mesh}");
    }
}

/// pbrt-v3 reports a curve it cannot make (a degree or basis it lacks, control points
/// that make no segment or none at all, a ribbon without one normal per segment end)
/// and leaves it out; pbrt-v4 stops. Both images checked against pbrt-v3: the scene
/// without the curve.
#[test]
fn a_v3_curve_pbrt_v3_cannot_make_is_left_out_with_a_warning() {
    let four = "\"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]";
    let curve =
        |film: &str, curve: &str| format!("Film \"{film}\"\nWorldBegin\nShape \"curve\" {curve}\nShape \"sphere\"\n");
    for (c, why) in [
        (format!("{four} \"integer degree\" 4"), "degree 4"),
        (format!("{four} \"string basis\" \"hermite\""), "basis \"hermite\""),
        ("\"point P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]".to_string(), "5 control points"),
        ("\"float width\" 0.1".to_string(), "curve needs \"point3 P\""),
        (format!("{four} \"string type\" \"ribbon\""), "a ribbon needs \"normal N\""),
        (format!("{four} \"string type\" \"ribbon\" \"normal N\" [0 0 1]"), "1 normals"),
    ] {
        let s = scene(&curve("image", &c));
        assert_eq!(s.shapes.len(), 1, "{c}: the sphere alone");
        let w: Vec<String> = warnings(&s).into_iter().filter(|m| m.contains("left out")).collect();
        assert!(w.len() == 1 && w[0].contains(why), "{c}: {w:?}");
        assert!(!warnings(&s).iter().any(|m| m.contains("not used")), "{c}: its parameters are not reported unused");
        let e = load(&curve("rgb", &c)).expect_err("pbrt-v4 stops").to_string();
        assert!(e.contains(":3:") && e.contains(why), "{c}: {e}");
    }
    assert_eq!(scene(&curve("image", four)).shapes.len(), 2, "a curve pbrt-v3 makes");
}

/// pbrt-v3 reports a NURBS patch with a count, order or knot vector missing, knots
/// other than count + order in number, or control points missing or miscounted, and
/// leaves it out (checked against its image: the scene without the patch). `nurbs` is
/// pbrt-v3's alone, so its files are v3 files. What pbrt-v3 cannot survive (order 1,
/// decreasing knots) stays an error.
#[test]
fn a_nurbs_patch_pbrt_v3_cannot_make_is_left_out_with_a_warning() {
    let patch = |u_knots: &str, points: &str| {
        format!(
            "Shape \"nurbs\" \"integer nu\" 2 \"integer nv\" 2 \"integer uorder\" 2 \"integer vorder\" 2 \
             \"float uknots\" {u_knots} \"float vknots\" [0 0 1 1] {points}"
        )
    };
    let four = "\"point P\" [0 0 0 1 0 0 0 1 0 1 1 0]";
    let loaded = |shape: &str| scene(&format!("WorldBegin\n{shape}\nShape \"sphere\"\n"));
    for (shape, why) in [
        ("Shape \"nurbs\" \"integer nv\" 2".to_string(), "needs \"integer nu\""),
        (patch("[0 0 1]", four), "3 u knots; nu + uorder = 4"),
        (patch("[0 0 1 1]", ""), "needs its control points"),
        (patch("[0 0 1 1]", "\"point P\" [0 0 0 1 0 0 0 1 0]"), "9 values for 4 control points"),
        (patch("[0 0 1 1]", "\"float Pw\" [0 0 0 1 1 0 0 1 0 1 0 1 1 1 0]"), "15 values for 4 control points"),
    ] {
        let s = loaded(&shape);
        assert_eq!(s.shapes.len(), 1, "{shape}: the sphere alone");
        let w: Vec<String> = warnings(&s).into_iter().filter(|m| m.contains("left out")).collect();
        assert!(w.len() == 1 && w[0].contains(why), "{shape}: {w:?}");
    }
    assert_eq!(loaded(&patch("[0 0 1 1]", four)).shapes.len(), 2, "a patch pbrt-v3 makes");
    let order_1 = patch("[0 1 1]", four).replace("\"integer uorder\" 2", "\"integer uorder\" 1");
    let e = load(&format!("WorldBegin\n{order_1}\n")).expect_err("order 1").to_string();
    assert!(e.contains("the order must be at least 2"), "order 1 stays an error: {e}");
}
