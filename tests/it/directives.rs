//! Every directive of pbrt-v3 and pbrt-v4, each checked for its effect.

use crate::common::{close, load, load_file, matrix, num, report, root, scene, warnings, world_shapes};
use pbrt_sppm::integrators::Algorithm;
use pbrt_sppm::parser::Syntax;
use pbrt_sppm::scene::{Geometry, LoadOptions, load_scene};

/// object_to_world (row-major) of the only shape in a world block.
fn m(world: &str) -> [f64; 16] {
    let shapes = world_shapes(world);
    assert_eq!(shapes.len(), 1, "{world}");
    matrix(&shapes[0]["object_to_world"])
}

const I: [f64; 16] = [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.];

fn approx(a: [f64; 16], b: [f64; 16]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
}

#[test]
fn translate_scale_rotate_identity() {
    assert_eq!(
        m(r#"Translate 1 2 3 Shape "sphere""#),
        [1., 0., 0., 1., 0., 1., 0., 2., 0., 0., 1., 3., 0., 0., 0., 1.]
    );
    assert_eq!(m(r#"Scale 2 3 -4 Shape "sphere""#), [2., 0., 0., 0., 0., 3., 0., 0., 0., 0., -4., 0., 0., 0., 0., 1.]);
    // Rotate 90 about z maps +x to +y: column 0 is (0, 1, 0).
    let r = m(r#"Rotate 90 0 0 1 Shape "sphere""#);
    assert!(approx(r, [0., -1., 0., 0., 1., 0., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]), "{r:?}");
    assert_eq!(m(r#"Translate 5 5 5 Identity Shape "sphere""#), I);
    // The statement nearest the shape acts first: T(1,0,0)·S(2) maps x=1 to 3.
    let ts = m(r#"Translate 1 0 0 Scale 2 2 2 Shape "sphere""#);
    assert_eq!((ts[0], ts[3]), (2.0, 1.0));
}

#[test]
fn transform_and_concat_transform_are_column_major() {
    assert_eq!(
        m(r#"Translate 9 9 9 Transform [1 0 0 0 0 1 0 0 0 0 1 0 7 8 9 1] Shape "sphere""#),
        [1., 0., 0., 7., 0., 1., 0., 8., 0., 0., 1., 9., 0., 0., 0., 1.]
    );
    let c = m(r#"Translate 1 0 0 ConcatTransform [2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1] Shape "sphere""#);
    assert_eq!((c[0], c[3], c[5]), (2.0, 1.0, 2.0));
}

#[test]
fn look_at_follows_pbrt_handedness() {
    let r = report("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n");
    let cfw = matrix(&r["camera"]["camera_from_world"]);
    // dir = -z, right = up × dir = -x: world +x appears on the image's left.
    assert!(approx(cfw, [-1., 0., 0., 0., 0., 1., 0., 0., 0., 0., -1., 5., 0., 0., 0., 1.]), "{cfw:?}");
}

#[test]
fn look_at_with_up_along_the_view_is_the_identity_in_v3_and_an_error_in_v4() {
    // pbrt-v3 says so and goes on with the CTM unchanged; the version is settled by a
    // v3-only statement after the LookAt, so the decision waits for it.
    let v3 = "Translate 1 2 3\nLookAt 0 0 0  0 0 1  0 0 2\nCamera \"perspective\"\nWorldBegin\nMaterial \"uber\"\n";
    let s = scene(v3);
    assert!(warnings(&s).iter().any(|w| w.contains("parallel") && w.contains("left unchanged")), "{:?}", warnings(&s));
    let cfw = matrix(&pbrt_sppm::cli::check::report(&s, false)["camera"]["camera_from_world"]);
    assert!(approx(cfw, [1., 0., 0., 1., 0., 1., 0., 2., 0., 0., 1., 3., 0., 0., 0., 1.]), "{cfw:?}");
    let v4 = v3.replace("uber", "coateddiffuse");
    let e = load(&v4).expect_err("pbrt-v4 stops at the LookAt").to_string();
    assert!(e.contains(":2:1: error: LookAt: the up vector and the viewing direction are parallel"), "{e}");
    // No viewing direction, or no up vector: an error for both (pbrt's camera is NaN).
    for bad in ["LookAt 1 1 1  1 1 1  0 1 0", "LookAt 0 0 0  0 0 1  0 0 0"] {
        let e = load(&format!("{bad}\nCamera \"perspective\"\nWorldBegin\nMaterial \"uber\"\n")).err();
        assert!(e.is_some_and(|e| e.to_string().contains(":1:1: error: LookAt: the")), "{bad}");
    }
}

#[test]
fn named_coordinate_systems_including_camera_and_world() {
    assert_eq!(m(r#"Translate 1 2 3 CoordinateSystem "a" Identity CoordSysTransform "a" Shape "sphere""#)[3], 1.0);
    let r = report(
        "LookAt 1 2 3  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nCoordSysTransform \"camera\"\nShape \"sphere\"\n",
    );
    let w = matrix(&r["shapes"][0]["object_to_world"]);
    assert!(close(w[3], 1.0, 1e-12) && close(w[7], 2.0, 1e-12) && close(w[11], 3.0, 1e-12), "{w:?}");
    assert_eq!(m(r#"Translate 4 4 4 CoordSysTransform "world" Shape "sphere""#), I);
    let s = scene(r#"WorldBegin CoordSysTransform "nowhere" Shape "sphere""#);
    assert!(warnings(&s)[0].contains("\"nowhere\" is not defined"));
}

#[test]
fn active_transform_and_transform_times() {
    // A moving world shape is made with the identity and placed by a moving instance,
    // as pbrt wraps it (pbrt-v3 interpolates in world space).
    let s = scene(
        "TransformTimes 0 2\nWorldBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\nShape \"sphere\"\n",
    );
    assert!(s.shapes.is_empty(), "the moving sphere is not a world shape");
    let i = s.instances.get(0);
    assert_eq!(i.world_from_instance(), glam::DMat4::IDENTITY, "placed at its start transform");
    assert_eq!(s.objects[i.object() as usize].shapes[0].object_to_world, glam::DMat4::IDENTITY);
    let motion = i.motion().expect("it moves");
    assert_eq!(motion.times, [0.0, 2.0]);
    assert!((motion.at(1.0).w_axis.x - 0.5).abs() < 1e-12, "halfway through TransformTimes, halfway there");
    assert!(warnings(&s).is_empty(), "{:?}", warnings(&s));
    // Inside an object definition motion would nest: the start transform, noted.
    let s = scene(
        "WorldBegin\nObjectBegin \"o\"\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\nShape \"sphere\"\nObjectEnd\nObjectInstance \"o\"\n",
    );
    assert!(warnings(&s).iter().any(|w| w.contains("keeps its start transform")), "{:?}", warnings(&s));
    assert!(s.instances.get(0).motion().is_none());
    // StartTime alone changes only the start: the shape moves back to where it was.
    let s = scene("WorldBegin\nActiveTransform StartTime Translate 2 0 0\nActiveTransform All\nShape \"sphere\"\n");
    assert_eq!(s.instances.get(0).world_from_instance().w_axis.x, 2.0);
    assert_eq!(s.instances.get(0).motion().map(|m| m.end.w_axis.x), Some(0.0));
}

#[test]
fn reverse_orientation_toggles_and_is_scoped() {
    let shapes = world_shapes(
        r#"ReverseOrientation Shape "sphere"
           AttributeBegin ReverseOrientation Shape "sphere" AttributeEnd
           Shape "disk""#,
    );
    let ro: Vec<bool> = shapes.iter().map(|s| s["reverse_orientation"].as_bool().unwrap()).collect();
    assert_eq!(ro, [true, false, true]);
    let sw = world_shapes(r#"Scale -1 1 1 Shape "sphere""#);
    assert_eq!(sw[0]["swaps_handedness"], true);
}

#[test]
fn option_and_color_space() {
    let s =
        scene("Option \"seed\" 42\nOption \"bool disablepixeljitter\" true\nColorSpace \"aces2065-1\"\nWorldBegin\n");
    assert_eq!(s.integrator.seed, 42);
    assert!(s.options.contains(&("disablepixeljitter".into(), "true".into())));
    // The scene's colour space, used whole; a second, different one is noted, an
    // unknown one is a warning and changes nothing.
    assert_eq!(s.color_space.name(), "aces2065-1");
    assert!(warnings(&s).is_empty(), "{:?}", warnings(&s));
    let two = scene("ColorSpace \"rec2020\" Film \"rgb\" WorldBegin AttributeBegin ColorSpace \"srgb\" AttributeEnd");
    assert_eq!(two.color_space.name(), "rec2020");
    assert!(
        two.approximated.iter().any(|a| a.what.contains("ColorSpace \"srgb\" after \"rec2020\"")),
        "{:?}",
        two.approximated
    );
    let bad = scene("ColorSpace \"adobergb\" Film \"rgb\" WorldBegin");
    assert_eq!(bad.color_space.name(), "srgb");
    assert!(warnings(&bad).iter().any(|w| w.contains("adobergb")), "{:?}", warnings(&bad));
    assert_eq!(s.syntax, Syntax::V4);
}

#[test]
fn camera_parameters_and_defaults() {
    let r = report(
        "Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100\nCamera \"perspective\" \"float fov\" 30 \"float lensradius\" 0.1 \"float focaldistance\" 4\nWorldBegin\n",
    );
    let c = &r["camera"];
    assert_eq!((num(&c["fov"]), num(&c["lensradius"]), num(&c["focaldistance"])), (30.0, 0.1, 4.0));
    assert_eq!(c["screenwindow"], serde_json::json!([-2.0, 2.0, -1.0, 1.0]));
    let r = report(
        "Film \"image\" \"integer xresolution\" 100 \"integer yresolution\" 200\nCamera \"orthographic\"\nWorldBegin\n",
    );
    assert_eq!(r["camera"]["type"], "orthographic");
    assert_eq!(r["camera"]["screenwindow"], serde_json::json!([-1.0, 1.0, -2.0, 2.0]));
    let r = report("Camera \"perspective\" \"float halffov\" 20\nWorldBegin\n");
    assert_eq!(num(&r["camera"]["fov"]), 40.0);
    let r = report("WorldBegin\n");
    assert_eq!((num(&r["camera"]["fov"]), r["film"]["xresolution"].as_u64()), (90.0, Some(1280)));
}

#[test]
fn film_crop_window_pixel_bounds_and_scale() {
    let r = report(
        "Film \"image\" \"integer xresolution\" 10 \"integer yresolution\" 10 \"float cropwindow\" [0.75 0.25 0.05 1.2] \"float scale\" 1.5\nWorldBegin\n",
    );
    let f = &r["film"];
    assert_eq!(f["cropwindow"], serde_json::json!([0.25, 0.75, 0.05, 1.0]));
    assert_eq!(f["pixelbounds"], serde_json::json!([3, 8, 1, 10]));
    assert_eq!(num(&f["scale"]), 1.5);
    let r = report(
        "Film \"rgb\" \"integer pixelbounds\" [2 6 1 3] \"float iso\" 200 \"string filename\" \"out.exr\"\nWorldBegin\n",
    );
    assert_eq!(r["film"]["pixelbounds"], serde_json::json!([2, 6, 1, 3]));
    assert_eq!((num(&r["film"]["scale"]), r["film"]["filename"].as_str()), (2.0, Some("out.exr")));
    assert_eq!(r["integrator"]["photonsperiteration"], 8, "default photons = pixels in the crop");
    // No Integrator line: pbrt-v4's default, volpath, which vcm renders.
    let i = &r["integrator"];
    assert_eq!((&i["requested"], &i["implied"], &i["rendered_with"]), (&"volpath".into(), &true.into(), &"vcm".into()));
    assert!(r["warnings"].as_array().unwrap().is_empty(), "a valid, silent file gets no warning");
    let path = report("Integrator \"path\"\nWorldBegin\n");
    assert_eq!(
        (&path["integrator"]["requested"], &path["integrator"]["rendered_with"]),
        (&"path".into(), &"vcm".into())
    );
    assert_eq!(path["integrator"]["implied"], false);
    let summary = pbrt_sppm::cli::check::summary(&scene("Integrator \"path\"\nWorldBegin\n"));
    assert!(summary.contains("integrator  \"path\", rendered with vcm"), "{summary}");
}

#[test]
fn without_an_integrator_line_pbrt_path_traces_and_vcm_renders() {
    use pbrt_sppm::cli::check::{implied_integrator, summary};
    let v3 = scene("Film \"image\"\nWorldBegin\n");
    let (i, s) = (&v3.integrator, summary(&v3));
    assert_eq!((i.requested.as_str(), i.implied, i.iterations), ("path", true, 16));
    assert!(s.contains("integrator  \"path\" (pbrt-v3's default: no Integrator line), rendered with vcm"), "{s}");
    let note = implied_integrator(&v3).expect("a note");
    assert!(note.contains("pbrt-v3 would render with \"path\"; rendering with vcm"), "{note}");
    let v4 = scene("Film \"rgb\"\nSampler \"zsobol\" \"integer pixelsamples\" 8\nWorldBegin\n");
    assert_eq!((v4.integrator.requested.as_str(), v4.integrator.iterations), ("volpath", 8));
    let sppm = scene("Film \"rgb\"\nIntegrator \"sppm\"\nWorldBegin\n");
    assert!(!sppm.integrator.implied && implied_integrator(&sppm).is_none());
    assert_eq!(Algorithm::by_default(&sppm.integrator), Algorithm::Sppm);
    assert_eq!(Algorithm::by_default(&v4.integrator).name(), "vcm");
}

#[test]
fn integrator_iterations_per_syntax_version() {
    let v3 = scene("Integrator \"sppm\" \"integer numiterations\" 10 \"float radius\" 0.025\nWorldBegin\n");
    assert_eq!((v3.syntax, v3.integrator.iterations, v3.integrator.radius), (Syntax::V3, 10, 0.025));
    let v3_default =
        scene("Film \"image\"\nIntegrator \"sppm\"\nSampler \"halton\" \"integer pixelsamples\" 4\nWorldBegin\n");
    assert_eq!(v3_default.integrator.iterations, 64, "v3 ignores the sampler");
    let v4 = scene(
        "Film \"rgb\"\nSampler \"zsobol\" \"integer pixelsamples\" 4\nIntegrator \"sppm\" \"integer maxdepth\" 7 \"integer photonsperiteration\" 1000 \"integer seed\" 9\nWorldBegin\n",
    );
    let i = &v4.integrator;
    assert_eq!((i.iterations, i.max_depth, i.photons_per_iteration, i.seed), (4, 7, 1000, 9));
    let strat =
        scene("Film \"rgb\"\nSampler \"stratified\" \"integer xsamples\" 3 \"integer ysamples\" 5\nWorldBegin\n");
    assert_eq!(strat.integrator.iterations, 15);
    assert_eq!(scene("Film \"rgb\"\nWorldBegin\n").integrator.iterations, 16);
    let explicit =
        scene("Integrator \"sppm\" \"integer iterations\" 3 \"integer imagewritefrequency\" 1\nWorldBegin\n");
    assert_eq!(explicit.integrator.iterations, 3);
    assert!(explicit.warnings.is_empty(), "{:?}", explicit.warnings);
    let path = scene("Integrator \"path\" \"integer maxdepth\" 3\nWorldBegin\n");
    assert!(warnings(&path)[0].contains("\"path\" is rendered with vcm"), "{:?}", warnings(&path));
    let bdpt = scene("Integrator \"bdpt\"\nSampler \"halton\" \"integer pixelsamples\" 8\nWorldBegin\n");
    assert!(warnings(&bdpt)[0].contains("\"bdpt\" is rendered with bdpt"), "{:?}", warnings(&bdpt));
    assert_eq!(bdpt.integrator.iterations, 8, "a bdpt file's passes are its pixel samples");
}

#[test]
fn sampler_filter_and_accelerator_are_accepted_quietly() {
    let s = scene(
        "Sampler \"halton\" \"integer pixelsamples\" 8\nPixelFilter \"gaussian\" \"float xwidth\" 2\nAccelerator \"kdtree\" \"integer maxprims\" 4\nWorldBegin\n",
    );
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn world_begin_resets_and_world_end_ends() {
    assert_eq!(m(r#"Shape "sphere""#), I);
    let s = scene("Translate 1 0 0\nWorldBegin\nShape \"sphere\"\nWorldEnd\nWorldBegin\nShape \"disk\"\n");
    assert_eq!(s.shapes.len(), 1);
    assert_eq!(s.shapes[0].object_to_world, glam::DMat4::IDENTITY);
    assert!(warnings(&s).iter().any(|w| w.contains("after WorldEnd")));
    assert_eq!(s.syntax, Syntax::V3);
}

/// pbrt-v3 renders at `WorldEnd` and renders nothing from a file that ends without
/// one; we render it, with a warning at the file's end. pbrt-v4 needs no `WorldEnd`.
#[test]
fn a_v3_file_without_world_end_renders_with_a_warning_at_its_end() {
    let text = "WorldBegin\nMaterial \"matte\"\nShape \"sphere\"\n";
    let s = scene(text);
    assert_eq!((s.syntax, s.shapes.len()), (Syntax::V3, 1));
    let w: Vec<_> = s.warnings.iter().filter(|w| w.message.contains("without WorldEnd")).collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    assert_eq!((w[0].line, w[0].column), (4, 1), "at the file's end");
    assert!(warnings(&scene(&format!("{text}WorldEnd\n"))).is_empty());
    assert!(warnings(&scene("WorldBegin\nMaterial \"diffuse\"\nShape \"sphere\"\n")).is_empty(), "v4");
}

#[test]
fn attribute_block_restores_everything_transform_block_only_the_ctm() {
    let s = scene(
        r#"WorldBegin
        AttributeBegin Translate 1 0 0 Material "mirror" ReverseOrientation AreaLightSource "diffuse" AttributeEnd
        Shape "sphere"
        TransformBegin Translate 2 0 0 Material "mirror" TransformEnd
        Shape "sphere""#,
    );
    let (a, b) = (&s.shapes[0], &s.shapes[1]);
    assert_eq!(a.object_to_world, glam::DMat4::IDENTITY);
    assert!(!a.reverse_orientation && a.area_light.is_none());
    assert_eq!(s.materials[a.material as usize].ty, "matte");
    assert_eq!(b.object_to_world, glam::DMat4::IDENTITY);
    assert_eq!(s.materials[b.material as usize].ty, "mirror", "v3 TransformEnd keeps the material");
}

#[test]
fn unbalanced_blocks_warn() {
    let s = scene("WorldBegin\nAttributeEnd\nAttributeBegin\nTransformEnd\nAttributeBegin\n");
    let w = warnings(&s);
    assert!(w[0].contains("without a matching AttributeBegin"), "{w:?}");
    assert!(w[1].contains("closes an AttributeBegin"), "{w:?}");
    assert!(w[2].contains("never closed"), "{w:?}");
}

#[test]
fn attribute_gives_lower_priority_defaults() {
    let shapes = world_shapes(
        r#"AttributeBegin Attribute "shape" "float radius" 2
             Shape "sphere" Shape "sphere" "float radius" 3
           AttributeEnd
           Shape "sphere""#,
    );
    let r: Vec<f64> = shapes.iter().map(|s| num(&s["params"]["radius"])).collect();
    assert_eq!(r, [2.0, 3.0, 1.0]);
}

#[test]
fn objects_share_geometry_and_compose_transforms() {
    let s = scene(
        r#"WorldBegin
        ObjectInstance "later"
        ObjectBegin "later"
          Translate 0 1 0
          Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2]
        ObjectEnd
        Translate 5 0 0
        ObjectInstance "later""#,
    );
    assert_eq!(s.meshes.len(), 1, "geometry is never copied");
    assert_eq!(s.instances.len(), 2);
    let r = pbrt_sppm::cli::check::report(&s, true);
    let w = matrix(&r["shapes"][1]["object_to_world"]);
    assert_eq!((w[3], w[7]), (5.0, 1.0), "instance · definition");
    assert_eq!(r["shapes"][1]["bounds"], serde_json::json!([[5.0, 1.0, 0.0], [6.0, 2.0, 0.0]]));
    assert_eq!(r["counts"]["instances"], 2);
}

#[test]
fn lights_and_area_lights() {
    // A v3 file (`Film "image"`): pbrt-v3 leaves unknown light types out with a
    // warning, where pbrt-v4 stops (tests/it/messages.rs).
    let s = scene(
        r#"Film "image" WorldBegin
        LightSource "point" "rgb I" [1 1 1] "float bogus" 1
        LightSource "laser" "string filename" "x.exr"
        AttributeBegin AreaLightSource "diffuse" "rgb L" [1 1 1] Shape "sphere" Shape "disk" AttributeEnd
        AttributeBegin AreaLightSource "projection" Shape "sphere" AttributeEnd
        Shape "sphere""#,
    );
    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.area_lights.len(), 1, "one AreaLightSource, shared by two shapes");
    let lit: Vec<bool> = s.shapes.iter().map(|x| x.area_light.is_some()).collect();
    assert_eq!(lit, [true, true, false, false]);
    assert_eq!(
        s.skipped.iter().map(|k| k.what.as_str()).collect::<Vec<_>>(),
        ["LightSource \"laser\"", "AreaLightSource \"projection\""]
    );
    let why: Vec<&str> = s.skipped.iter().map(|k| k.why.as_str()).collect();
    assert!(why[0].starts_with("unknown light type \"laser\""), "{why:?}");
    assert!(why[1].starts_with("unknown area light type \"projection\""), "{why:?}");
    let unused = s.warnings.iter().find(|w| w.message.contains("bogus")).expect("unused-parameter warning");
    assert_eq!((unused.line, unused.column), (2, 45));
    assert_eq!(pbrt_sppm::cli::check::report(&s, false)["counts"]["lights"], 3);
}

#[test]
fn named_materials_are_scoped_like_v3_and_resolve_forward_like_v4() {
    let s = scene(
        r#"WorldBegin
        MakeNamedMaterial "m" "string type" "matte" "rgb Kd" [1 0 0]
        AttributeBegin
          MakeNamedMaterial "m" "string type" "mirror"
          NamedMaterial "m" Shape "sphere"
        AttributeEnd
        NamedMaterial "m" Shape "sphere"
        NamedMaterial "fwd" Shape "sphere"
        MakeNamedMaterial "fwd" "string type" "glass"
        MakeNamedMaterial "unused" "string type" "metal"
        Material "disney" Shape "disk"
        WorldEnd"#,
    );
    let tys: Vec<&str> = s.shapes.iter().map(|x| s.materials[x.material as usize].ty.as_str()).collect();
    assert_eq!(tys, ["mirror", "matte", "glass", "disney"]);
    let what: Vec<&str> = s.skipped.iter().map(|k| k.what.as_str()).collect();
    assert!(what.contains(&"MakeNamedMaterial \"unused\""), "{what:?}");
    assert!(matches!(s.materials[3].kind, pbrt_sppm::scene::MaterialKind::Disney(_)), "{:?}", s.materials[3]);
    assert!(s.approximated.is_empty(), "{:?}", s.approximated);
    assert_eq!(s.materials.len(), 4, "only used materials are built");
}

/// pbrt-v3 forgets a named texture at the end of its `AttributeBegin` block (a later
/// reference gets the parameter's default, with an error); we use the definition and
/// say so. pbrt-v4's names are global: no warning there.
#[test]
fn a_v3_texture_used_after_its_attribute_block_is_named_in_a_warning() {
    let body = |film: &str, open: &str, close: &str| {
        let material = match film.contains("rgb") {
            true => "Material \"diffuse\" \"texture reflectance\" \"t\"",
            false => "Material \"matte\" \"texture Kd\" \"t\"",
        };
        format!(
            "{film}\nWorldBegin\n{open}\nTexture \"t\" \"spectrum\" \"constant\" \"rgb value\" [1 0 0]\n{close}\n\
             {material}\nShape \"sphere\"\nWorldEnd"
        )
    };
    let out_of_scope =
        |w: &Vec<String>| w.iter().filter(|m| m.contains("inside an AttributeBegin that has ended")).count();
    let v3 = scene(&body("Film \"image\"", "AttributeBegin", "AttributeEnd"));
    let w = warnings(&v3);
    assert_eq!(out_of_scope(&w), 1, "{w:?}");
    assert!(w.iter().any(|m| m.contains("texture \"t\"") && m.contains(":4:")), "names the definition: {w:?}");
    for (film, open, close) in
        [("Film \"image\"", "TransformBegin", "TransformEnd"), ("Film \"rgb\"", "AttributeBegin", "AttributeEnd")]
    {
        let w = warnings(&scene(&body(film, open, close)));
        assert_eq!(out_of_scope(&w), 0, "{film} {open}: {w:?}");
    }
}

/// pbrt-v3 forgets a named material at the end of its `AttributeBegin` block and has no
/// forward references: `NamedMaterial` is then an error there and the current material
/// stays. We use the definition and say so, once per statement; pbrt-v4's names are
/// global.
#[test]
fn a_v3_named_material_out_of_scope_is_named_in_a_warning() {
    let body = |film: &str, ty: &str| {
        format!(
            "{film}\nWorldBegin\nAttributeBegin\nMakeNamedMaterial \"red\" \"string type\" \"{ty}\"\nAttributeEnd\n\
             NamedMaterial \"red\"\nShape \"sphere\"\nShape \"sphere\" \"float radius\" 2\n\
             NamedMaterial \"blue\"\nShape \"sphere\"\n\
             MakeNamedMaterial \"blue\" \"string type\" \"{ty}\"\nWorldEnd"
        )
    };
    let flagged =
        |w: &Vec<String>| w.iter().filter(|m| m.contains("is not in scope here")).cloned().collect::<Vec<_>>();
    let v3 = scene(&body("Film \"image\"", "matte"));
    assert_eq!(v3.shapes.len(), 3);
    let w = flagged(&warnings(&v3));
    assert_eq!(w.len(), 2, "one per statement: {w:?}");
    assert!(w[0].contains("\"red\"") && w[0].contains(":4:"), "names the definition: {w:?}");
    assert!(w[1].contains("\"blue\"") && w[1].contains(":11:"), "a forward reference: {w:?}");
    let v4 = scene(&body("Film \"rgb\"", "diffuse"));
    assert!(flagged(&warnings(&v4)).is_empty(), "{:?}", warnings(&v4));
    // A v3 mix naming materials out of scope (pbrt-v3 takes matte for each).
    let mix = "WorldBegin\nAttributeBegin\nMakeNamedMaterial \"a\" \"string type\" \"matte\"\n\
               MakeNamedMaterial \"b\" \"string type\" \"plastic\"\nAttributeEnd\n\
               Material \"mix\" \"string namedmaterial1\" \"a\" \"string namedmaterial2\" \"b\"\nShape \"sphere\"\nWorldEnd";
    let w = flagged(&warnings(&scene(mix)));
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(w.iter().all(|m| m.contains("mix uses matte")), "{w:?}");
}

#[test]
fn a_v3_named_material_defined_nowhere_keeps_the_current_material() {
    // pbrt-v3 reports an error and keeps the current material; pbrt-v4 stops.
    let body = |film: &str| {
        format!(
            "{film}\nWorldBegin\nMaterial \"plastic\"\nNamedMaterial \"nope\"\nShape \"sphere\"\n\
             NamedMaterial \"nope\"\nNamedMaterial \"gone\"\nShape \"sphere\"\nShape \"disk\"\nWorldEnd"
        )
    };
    let v3 = scene(&body("Film \"image\""));
    let tys: Vec<&str> = v3.shapes.iter().map(|s| v3.materials[s.material as usize].ty.as_str()).collect();
    assert_eq!(tys, ["plastic"; 3]);
    let w: Vec<String> = warnings(&v3).into_iter().filter(|m| m.contains("is not defined")).collect();
    assert_eq!(w.len(), 3, "one per statement: {w:?}");
    assert!(w[0].contains("\"nope\"") && w[0].contains("current material is kept"), "{w:?}");
    let e = load(&body("Film \"rgb\"")).expect_err("pbrt-v4 stops").to_string();
    assert!(e.contains(":4:1: error: named material \"nope\" is not defined"), "{e}");
}

#[test]
fn a_v3_texture_defined_nowhere_leaves_the_parameter_its_default() {
    // pbrt-v3 reports it and uses the parameter's default (matte's Kd 0.5); pbrt-v4 stops.
    let body = |film: &str, material: &str| {
        format!(
            "LookAt 0 0 -4  0 0 0  0 1 0\nCamera \"perspective\"\n{film} \"integer xresolution\" 8 \"integer yresolution\" 8\n\
             Integrator \"sppm\" \"integer numiterations\" 1\nWorldBegin\n\
             AttributeBegin\nTranslate 0 3 0\nRotate 90 1 0 0\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nShape \"disk\"\nAttributeEnd\n\
             {material}\nShape \"sphere\"\nWorldEnd\n"
        )
    };
    let named = scene(&body("Film \"image\"", "Material \"matte\" \"texture Kd\" \"nowhere\""));
    let w: Vec<String> = warnings(&named).into_iter().filter(|m| m.contains("\"nowhere\" is not defined")).collect();
    assert!(w.len() == 1 && w[0].contains("takes its default"), "{w:?}");
    let plain = scene(&body("Film \"image\"", "Material \"matte\""));
    let settings = pbrt_sppm::integrators::RenderSettings { photons: Some(2000), ..Default::default() };
    let image = |s: &pbrt_sppm::scene::SceneDescription| {
        let rs = pbrt_sppm::render::RenderScene::new(s);
        pbrt_sppm::integrators::render(&rs, &settings).expect("renders").image.pixels
    };
    let (a, b) = (image(&named), image(&plain));
    assert!(a.iter().flatten().any(|&c| c > 0.0), "the scene is lit");
    assert_eq!(a, b, "the default Kd, as with no Kd at all");
    let e = load(&body("Film \"rgb\"", "Material \"diffuse\" \"texture reflectance\" \"nowhere\""))
        .expect_err("pbrt-v4 stops")
        .to_string();
    assert!(e.contains("error: spectrum texture \"nowhere\" is not defined"), "{e}");
}

#[test]
fn a_v3_statement_on_the_wrong_side_of_world_begin_is_ignored_with_a_warning() {
    // pbrt-v3: "must be inside world block" / "Options cannot be set inside world
    // block", each statement ignored. A file not yet known as v3 gets the error.
    let text = "Film \"image\" \"integer xresolution\" 8\nMaterial \"plastic\"\nWorldEnd\nWorldBegin\n\
                Camera \"orthographic\"\nWorldBegin\nShape \"sphere\"\nWorldEnd\n";
    let s = scene(text);
    let w: Vec<String> = warnings(&s).into_iter().filter(|m| m.contains("ignored, as pbrt-v3")).collect();
    assert_eq!(w.len(), 4, "{w:?}");
    assert!(w[0].contains("Material is allowed only after WorldBegin") && w[3].contains("allowed only once"), "{w:?}");
    assert_eq!(s.materials[s.shapes[0].material as usize].ty, "matte", "the Material was ignored");
    assert_eq!(report(text)["camera"]["type"], "perspective", "so was the Camera");
    assert_eq!(s.shapes.len(), 1);
    let e = load(&text.replace("Film \"image\" \"integer xresolution\" 8\n", "")).expect_err("not known as v3");
    assert!(e.to_string().contains(":1:1: error: Material is allowed only after WorldBegin"), "{e}");
}

#[test]
fn textures_are_built_only_when_a_used_material_needs_them() {
    let s = scene(
        r#"WorldBegin
        Texture "checks" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "texture tex2" "inner"
        Texture "inner" "spectrum" "constant" "rgb value" [0 0 1]
        Texture "lonely" "float" "constant" "float value" 1
        Texture "odd" "float" "wrinkled"
        Material "diffuse" "texture reflectance" "checks" "texture displacement" "odd"
        Shape "sphere""#,
    );
    let names: Vec<&str> = s.textures.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["inner", "checks", "odd"]);
    use pbrt_sppm::scene::{MaterialKind, TexValue};
    assert_eq!(s.materials[0].kind, MaterialKind::Diffuse { reflectance: TexValue::Texture(1) });
    assert_eq!(s.materials[0].bump, Some(TexValue::Texture(2)), "the displacement is the bump map");
    let what: Vec<&str> = s.skipped.iter().map(|k| k.what.as_str()).collect();
    assert_eq!(what, ["Texture \"lonely\""]);
    assert!(s.approximated.is_empty());
    let e = crate::common::load("WorldBegin Material \"diffuse\" \"texture reflectance\" \"missing\" Shape \"sphere\"")
        .unwrap_err()
        .one_line();
    assert!(e.ends_with("error: spectrum texture \"missing\" is not defined"), "{e}");
}

#[test]
fn include_continues_a_parameter_list_across_the_file_end() {
    let s = load_file(&root().join("tests/data/good/continue-main.pbrt")).expect("loads");
    let r = pbrt_sppm::cli::check::report(&s, true);
    let p = &r["shapes"][0]["params"];
    assert_eq!((num(&p["radius"]), num(&p["zmax"])), (3.0, 1.0));
    assert_eq!(matrix(&r["shapes"][0]["object_to_world"])[11], 1.0);
    assert_eq!(matrix(&r["shapes"][1]["object_to_world"]), I, "the include's AttributeBegin closed in the parent");
}

#[test]
fn include_paths_are_relative_to_the_top_level_file() {
    let s = load_file(&root().join("tests/data/good/nested-main.pbrt")).expect("loads");
    let r = pbrt_sppm::cli::check::report(&s, true);
    assert_eq!(num(&r["shapes"][0]["params"]["radius"]), 2.0);
}

#[test]
fn import_does_not_leak_state_back() {
    let s = load_file(&root().join("pbrt-scenes/v4/features.pbrt")).expect("loads");
    let mesh = s.shapes.iter().find(|x| matches!(x.geometry, Geometry::Mesh { .. })).expect("imported mesh");
    assert!(mesh.reverse_orientation);
    assert!(mesh.area_light.is_some());
    // features.pbrt's last shapes come after the Import: no leaked ReverseOrientation.
    assert!(s.shapes.iter().filter(|x| !matches!(x.geometry, Geometry::Mesh { .. })).all(|x| !x.reverse_orientation));
}

#[test]
fn gzip_scene_files_are_read() {
    use std::io::Write;
    let dir = crate::common::Scratch::new("gz");
    let path = dir.join("scene.pbrt.gz");
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(b"WorldBegin\nShape \"sphere\" \"float radius\" 4\n").unwrap();
    std::fs::write(&path, gz.finish().unwrap()).unwrap();
    let s = load_scene(&path, &LoadOptions::default()).expect("gzip scene");
    assert_eq!(s.shapes.len(), 1);
}

#[test]
fn syntax_detection_and_override() {
    let cases = [
        ("WorldBegin\nShape \"sphere\"\n", Syntax::V4),
        ("WorldBegin\nAreaLightSource \"diffuse\" \"bool twosided\" \"true\"\n", Syntax::V3),
        ("WorldBegin\nAreaLightSource \"diffuse\" \"bool twosided\" true\n", Syntax::V4),
        ("WorldBegin\nLightSource \"point\" \"blackbody I\" [5500 1]\n", Syntax::V3),
        ("WorldBegin\nLightSource \"point\" \"blackbody I\" [5500]\n", Syntax::V4),
        ("WorldBegin\nShape \"sphere\" \"point p\" [0 0 0]\n", Syntax::V3),
        ("Film \"image\"\nWorldBegin\n", Syntax::V3),
        ("Film \"rgb\"\nWorldBegin\n", Syntax::V4),
        ("WorldBegin\nMaterial \"dielectric\"\n", Syntax::V4),
        ("WorldBegin\nShape \"cone\"\n", Syntax::V3),
        // pbrt-v3 has volpath too: a v3 media scene names it before its Film.
        ("Integrator \"volpath\"\nFilm \"image\"\nWorldBegin\nWorldEnd\n", Syntax::V3),
        ("Integrator \"simplevolpath\"\nWorldBegin\n", Syntax::V4),
        ("MakeNamedMedium \"m\" \"string type\" \"heterogeneous\" \"float density\" [1]\nWorldBegin\n", Syntax::V3),
        ("MakeNamedMedium \"m\" \"string type\" \"uniformgrid\" \"float density\" [1]\nWorldBegin\n", Syntax::V4),
    ];
    for (text, want) in cases {
        assert_eq!(scene(text).syntax, want, "{text}");
    }
    let e = scene("WorldBegin\nTransformBegin\nTransformEnd\n").syntax_evidence.unwrap();
    assert!(e.contains("inline.pbrt:2:1: TransformBegin"), "{e}");
    let forced = pbrt_sppm::scene::load_scene_from_bytes(
        std::path::Path::new("x.pbrt"),
        b"Film \"image\"\nWorldBegin\n".to_vec(),
        &LoadOptions { syntax: Some(Syntax::V4), ..Default::default() },
    )
    .unwrap();
    assert_eq!((forced.syntax, forced.integrator.iterations), (Syntax::V4, 16));
}

#[test]
fn unused_parameters_are_warned_at_their_own_location() {
    let s = scene("WorldBegin\nShape \"sphere\" \"float radius\" 2\n  \"float radiuss\" 3 \"rgb Kd\" [1 0 0]\n");
    let w: Vec<(u32, u32, &str)> = s.warnings.iter().map(|w| (w.line, w.column, w.message.as_str())).collect();
    assert_eq!(w, [(3, 3, "parameter \"float radiuss\" is not used"), (3, 21, "parameter \"rgb Kd\" is not used")]);
    // A parameter a lookup asked for with another type is an error, not a warning.
    let e = crate::common::load("WorldBegin\nShape \"sphere\" \"integer zmin\" 0\n").unwrap_err().one_line();
    assert!(e.ends_with("2:16: error: parameter \"integer zmin\" has the wrong type: expected \"float\""), "{e}");
    let e = crate::common::load("WorldBegin\nMaterial \"matte\" \"float Kd\" 0.5 Shape \"disk\"\n").unwrap_err();
    assert!(e.one_line().contains("\"float Kd\" has the wrong type: expected \"rgb\""), "{}", e.one_line());
}

#[test]
fn v3_and_v4_spellings_of_one_scene_give_the_same_description() {
    let load = |v: &str| {
        let s = load_file(&root().join(format!("pbrt-scenes/{v}/cornell-glass.pbrt"))).expect("loads");
        assert!(s.warnings.is_empty(), "{v}: {:?}", s.warnings);
        pbrt_sppm::cli::check::report(&s, true)
    };
    let (v3, v4) = (load("v3"), load("v4"));
    assert_eq!((v3["syntax"].as_str(), v4["syntax"].as_str()), (Some("v3"), Some("v4")));
    for key in ["camera", "counts", "world_bounds", "shapes"] {
        assert_eq!(v3[key], v4[key], "{key}");
    }
    for key in ["xresolution", "yresolution", "filename", "cropwindow", "pixelbounds", "scale"] {
        assert_eq!(v3["film"][key], v4["film"][key], "film {key}");
    }
    for key in ["iterations", "maxdepth", "photonsperiteration", "radius", "seed"] {
        assert_eq!(v3["integrator"][key], v4["integrator"][key], "integrator {key}");
    }
}

#[test]
fn every_bundled_scene_loads_without_errors() {
    for v in ["v3", "v4"] {
        for e in std::fs::read_dir(root().join("pbrt-scenes").join(v)).unwrap().flatten() {
            let p = e.path();
            // Fragments for Include/Import live in include/ and are not scenes.
            if p.extension().is_some_and(|x| x == "pbrt") {
                load_file(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            }
        }
    }
    assert!(load("WorldBegin").is_ok());
}

#[test]
fn an_import_that_leaves_a_block_open_is_closed_at_its_end() {
    let s = load_file(&root().join("tests/data/good/import-open.pbrt")).expect("loads");
    assert_eq!(s.shapes.len(), 2);
    assert!(s.shapes[0].reverse_orientation);
    assert!(!s.shapes[1].reverse_orientation, "state from the import does not leak");
    assert_eq!(s.shapes[1].object_to_world, glam::DMat4::IDENTITY);
    assert!(warnings(&s).iter().any(|w| w.contains("never closed in the imported file")), "{:?}", s.warnings);
}

#[test]
fn mix_names_its_materials_and_may_not_mix_itself() {
    use pbrt_sppm::scene::{MaterialKind, MixRule};
    let s = scene(
        r#"WorldBegin
        MakeNamedMaterial "a" "string type" "diffuse"
        MakeNamedMaterial "b" "string type" "conductor"
        MakeNamedMaterial "m" "string type" "mix" "string materials" ["a" "b"] "float amount" 0.25
        NamedMaterial "m"
        Shape "sphere""#,
    );
    let m = &s.materials[s.shapes[0].material as usize];
    let MaterialKind::Mix { materials, rule, .. } = &m.kind else { panic!("{:?}", m.kind) };
    assert_eq!(*rule, MixRule::Choose);
    let tys: Vec<&str> = materials.iter().map(|&i| s.materials[i as usize].ty.as_str()).collect();
    assert_eq!(tys, ["diffuse", "conductor"]);
    let e = crate::common::load(
        "WorldBegin\nMakeNamedMaterial \"m\" \"string type\" \"mix\" \"string materials\" [\"m\" \"m\"]\n\
         NamedMaterial \"m\"\nShape \"sphere\"",
    )
    .unwrap_err()
    .one_line();
    assert!(e.contains(":2:") && e.ends_with("error: material \"m\" mixes itself"), "{e}");
    let e = crate::common::load(
        "WorldBegin\nMaterial \"mix\" \"string namedmaterial1\" \"nope\" \"string namedmaterial2\" \"nope\"\nShape \"sphere\"",
    )
    .unwrap_err()
    .one_line();
    assert!(e.ends_with("error: named material \"nope\" is not defined"), "{e}");
}

#[test]
fn v3_glass_ignores_roughness_as_pbrt_v3_does_and_v4_dielectric_reads_it() {
    use pbrt_sppm::scene::{MaterialKind, TexValue};
    let s = scene(
        "WorldBegin\nMaterial \"glass\" \"float roughness\" .3 \"float vroughness\" .2\nShape \"disk\"\nWorldEnd\n",
    );
    let w: Vec<&str> = s.warnings.iter().map(|w| w.message.as_str()).collect();
    assert_eq!(w, ["parameter \"float roughness\" is not used"]);
    let MaterialKind::Dielectric { roughness, .. } = &s.materials[0].kind else { panic!("{:?}", s.materials[0]) };
    assert_eq!(*roughness, [TexValue::Const(glam::Vec3::ZERO), TexValue::Const(glam::Vec3::splat(0.2))]);
    let s = scene("WorldBegin\nMaterial \"dielectric\" \"float roughness\" .3\nShape \"disk\"\n");
    assert!(s.warnings.is_empty());
    let MaterialKind::Dielectric { roughness, .. } = &s.materials[0].kind else { panic!("{:?}", s.materials[0]) };
    assert_eq!(*roughness, [TexValue::Const(glam::Vec3::splat(0.3)); 2]);
}

#[test]
fn a_realistic_camera_reads_its_lens_and_reports_it() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("realistic");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("lens.dat"), "# r t eta d\n0 2 1 20\n50 5 1.5 20\n-50 45 1 20\n").unwrap();
    let scene = |camera: &str, film: &str| {
        let end = if film.contains("\"image\"") { "WorldEnd\n" } else { "" };
        let text = format!("Camera \"realistic\" \"string lensfile\" \"lens.dat\" {camera}\n{film}\nWorldBegin\n{end}");
        std::fs::write(dir.join("s.pbrt"), text).unwrap();
        load_file(&dir.join("s.pbrt")).unwrap()
    };
    let s = scene("\"float aperturediameter\" 6 \"float focusdistance\" 3", "Film \"image\" \"float diagonal\" 50");
    let r = pbrt_sppm::cli::check::report(&s, false);
    assert_eq!(r["camera"]["type"], "realistic");
    assert_eq!(r["camera"]["lens"]["interfaces"], 3);
    assert_eq!((num(&r["camera"]["lens"]["aperturediameter"]), num(&r["camera"]["lens"]["focusdistance"])), (6.0, 3.0));
    assert_eq!(num(&r["camera"]["lens"]["filmdiagonal"]), 50.0);
    assert!(s.approximated.is_empty() && s.warnings.is_empty(), "{:?} {:?}", s.approximated, s.warnings);
    // pbrt-v4's built-in aperture shapes are read (no approximation, no unused
    // parameter); an unknown name is an image file that must exist.
    let s = scene("\"string aperture\" \"pentagon\"", "Film \"rgb\"");
    assert!(s.approximated.is_empty() && s.warnings.is_empty(), "{:?} {:?}", s.approximated, s.warnings);
    assert!(s.camera.lens.as_ref().is_some_and(|l| l.aperture.is_some()));
    std::fs::write(
        dir.join("s.pbrt"),
        "Camera \"realistic\" \"string lensfile\" \"lens.dat\" \"string aperture\" \"hex.exr\"\nWorldBegin\n",
    )
    .unwrap();
    let e = load_file(&dir.join("s.pbrt")).unwrap_err().to_string();
    assert!(e.contains("aperture \"hex.exr\""), "{e}");
}

#[test]
fn every_named_glass_of_pbrt_v4_is_read_with_its_index() {
    // pbrt-v4 names seven glasses; each renders (in RGB) with its luminance-weighted
    // mean index, near its catalogue n at 560 nm. (glass-F11 was read as 1.62, and
    // four of the seven were refused as unknown files.)
    let want = [("BK7", 1.5180), ("BAF10", 1.6722), ("FK51A", 1.4874), ("LASF9", 1.8542)];
    let more = [("F5", 1.6758), ("F10", 1.7321), ("F11", 1.7893)];
    for (name, n) in want.into_iter().chain(more) {
        let s = scene(&format!(
            "WorldBegin\nMaterial \"dielectric\" \"spectrum eta\" \"glass-{name}\"\nShape \"sphere\"\n"
        ));
        let pbrt_sppm::scene::MaterialKind::Dielectric { eta: pbrt_sppm::scene::TexValue::Const(c), .. } =
            s.materials[s.shapes[0].material as usize].kind
        else {
            panic!("glass-{name}: not a dielectric of constant index");
        };
        assert!((c.x - n).abs() < 1.5e-3, "glass-{name}: {}", c.x);
    }
}

/// The intensity of the file's one point light.
fn point_intensity(text: &str) -> glam::Vec3 {
    let s = scene(text);
    let pbrt_sppm::lights::LightKind::Point(p) = &s.lights[0].kind else { panic!("not a point light") };
    p.i
}

#[test]
fn pbrt_v4_lights_emit_their_spectrum_at_luminance_one_and_v3_lights_as_given() {
    use pbrt_sppm::spectrum::luminance;
    // pbrt-v4 divides a light's spectrum by its luminance (SpectrumToPhotometric):
    // a flat 5 and a flat 1 emit alike, as does a named illuminant; RGB is as given
    // (its white has luminance 1 already). pbrt-v3 takes the spectrum as it is.
    let v4 = |i: &str| point_intensity(&format!("WorldBegin LightSource \"point\" {i}"));
    let flat5 = v4("\"spectrum I\" [300 5 800 5]");
    assert!((luminance(flat5) - 1.0).abs() < 1e-5, "{flat5}");
    assert!((flat5 - v4("\"spectrum I\" [300 1 800 1]")).abs().max_element() < 1e-5);
    assert!((luminance(v4("\"spectrum I\" \"stdillum-F2\" \"float scale\" 3")) - 3.0).abs() < 1e-4);
    assert_eq!(v4("\"rgb I\" [2 0 0]"), glam::Vec3::new(2.0, 0.0, 0.0));
    let v3 = point_intensity("WorldBegin LightSource \"point\" \"spectrum I\" [300 5 800 5] WorldEnd");
    assert!((luminance(v3) - 5.0).abs() < 0.05, "{v3}");
}

/// A v4 `portal` must be a rectangle (pbrt-v4 warns where it is not, and renders); a
/// v3 file's is unknown to pbrt-v3; a latitude-longitude map (`mapname`) has none.
#[test]
fn infinite_light_portals_are_read_as_each_pbrt_reads_them() {
    let light = |film: &str, extra: &str, corners: &str| {
        format!(
            "{film}\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1] {extra}\n  \"point3 portal\" [{corners}]\n\
             Shape \"sphere\"\nWorldEnd"
        )
    };
    let square = "0 0 0  0 1 0  1 1 0  1 0 0";
    let portal_warnings = |w: Vec<String>| w.into_iter().filter(|m| m.contains("portal")).collect::<Vec<_>>();
    assert!(portal_warnings(warnings(&scene(&light("Film \"rgb\"", "", square)))).is_empty());
    let skewed = portal_warnings(warnings(&scene(&light("Film \"rgb\"", "", "0 0 0  0 1 0  1.5 1 0  1 0 0"))));
    assert!(skewed.len() == 1 && skewed[0].contains("not a planar rectangle"), "{skewed:?}");
    let v3 = portal_warnings(warnings(&scene(&light("Film \"image\"", "", square).replace("rgb L", "color L"))));
    assert!(v3.len() == 1 && v3[0].contains("pbrt-v3 has no portals"), "{v3:?}");
    let map = "\"string mapname\" \"../../../pbrt-scenes/verify/textures/gonio-latlong.exr\"";
    let latlong = portal_warnings(warnings(&scene(&light("Film \"rgb\"", map, square))));
    assert!(latlong.len() == 1 && latlong[0].contains("equal-area map"), "{latlong:?}");
    // Beside a portal, pbrt-v4 reads the map and leaves `L` out (without one, `L` and a
    // map are an error: tests/data/bad/infinite-l-and-map.pbrt).
    let map = "\"string filename\" \"../../../pbrt-scenes/verify/textures/sky-equalarea.exr\" \"float scale\" 2";
    let s = scene(&light("Film \"rgb\"", map, square).replace("[1 1 1]", "[3 5 7]"));
    let ignored: Vec<String> = warnings(&s).into_iter().filter(|m| m.contains("\"L\" is ignored")).collect();
    assert_eq!(ignored.len(), 1, "{:?}", warnings(&s));
    let pbrt_sppm::lights::LightKind::Infinite(sky) = &s.lights[0].kind else { panic!("not an infinite light") };
    assert_eq!(sky.l, glam::Vec3::splat(2.0));
}

/// A `LightSource` inside an object definition is one light, placed by the CTM there,
/// as both pbrts create it: not dropped, and not copied by the object's instances.
#[test]
fn a_light_in_an_object_definition_is_one_light_where_it_is_defined() {
    for (film, world_end) in [("Film \"image\"", "WorldEnd"), ("Film \"rgb\"", "")] {
        let s = scene(&format!(
            "{film}\nWorldBegin\nAttributeBegin\nTranslate 0 2 0\nObjectBegin \"lamp\"\n\
             LightSource \"point\" \"rgb I\" [5 5 5]\nShape \"sphere\" \"float radius\" 0.1\nObjectEnd\n\
             AttributeEnd\nAttributeBegin\nTranslate 3 0 0\nObjectInstance \"lamp\"\nAttributeEnd\n\
             ObjectInstance \"lamp\"\nShape \"sphere\"\n{world_end}"
        ));
        assert_eq!(s.lights.len(), 1, "{film}");
        let pbrt_sppm::lights::LightKind::Point(p) = &s.lights[0].kind else { panic!("not a point light") };
        assert_eq!(p.position, glam::DVec3::new(0.0, 2.0, 0.0), "{film}");
        assert!(!warnings(&s).iter().any(|w| w.contains("LightSource")), "{film}: {:?}", warnings(&s));
    }
}

#[test]
fn v3_materials_and_textures_pbrt_v3_cannot_make_fall_back_as_pbrt_v3_does() {
    // pbrt-v3 reports each and goes on; pbrt-v4 stops at each.
    let v3 = |world: &str| scene(&format!("Film \"image\"\nWorldBegin\n{world}\nShape \"sphere\"\nWorldEnd\n"));
    let v4 = |world: &str| load(&format!("Film \"rgb\"\nWorldBegin\n{world}\nShape \"sphere\"\n")).expect_err(world);
    let kind = |s: &pbrt_sppm::scene::SceneDescription| s.materials[s.shapes[0].material as usize].kind.clone();
    let flagged = |s: &pbrt_sppm::scene::SceneDescription, what: &str| {
        warnings(s).into_iter().filter(|m| m.contains(what)).collect::<Vec<_>>()
    };
    // A mix naming a material defined nowhere mixes in pbrt-v3's default matte.
    let s = v3("MakeNamedMaterial \"red\" \"string type\" \"plastic\"\n\
                Material \"mix\" \"string namedmaterial1\" \"red\" \"string namedmaterial2\" \"nope\"");
    let pbrt_sppm::materials::MaterialKind::Mix { materials: [a, b], .. } = kind(&s) else { panic!("{:?}", kind(&s)) };
    let tys = [a, b].map(|m| s.materials[m as usize].ty.as_str());
    assert_eq!(tys, ["plastic", "matte"]);
    assert_eq!(s.materials[b as usize].kind, scene("Film \"image\" WorldBegin Shape \"sphere\"").materials[0].kind);
    assert_eq!(flagged(&s, "\"nope\" is not defined; pbrt-v3's mix uses matte").len(), 1);
    let e = v4("MakeNamedMaterial \"red\" \"string type\" \"diffuse\"\n\
                Material \"mix\" \"string materials\" [\"red\" \"nope\"]");
    assert!(e.to_string().contains(":4:35: error: named material \"nope\" is not defined"), "{e}");
    // A named material without a type: pbrt-v3's material "", which it takes as "none".
    let s = v3("MakeNamedMaterial \"m\" \"rgb Kd\" [1 0 0]\nNamedMaterial \"m\"");
    assert_eq!(kind(&s), pbrt_sppm::materials::MaterialKind::Interface);
    assert_eq!(flagged(&s, "needs a \"string type\"; what uses it has no surface").len(), 1);
    let e = v4("MakeNamedMaterial \"m\" \"rgb reflectance\" [1 0 0]\nNamedMaterial \"m\"");
    assert!(e.to_string().contains(":3:19: error: MakeNamedMaterial \"m\" needs a \"string type\""), "{e}");
    // A texture of an unknown class or type is not defined: Ks takes its default.
    let plain = kind(&v3("Material \"plastic\""));
    for (texture, what) in [
        ("Texture \"t\" \"spectrum\" \"plaid\" \"rgb tex1\" [1 0 0]", "has unknown texture class \"plaid\""),
        ("Texture \"t\" \"vector\" \"constant\" \"rgb value\" [1 0 0]", "texture type \"vector\" is not"),
    ] {
        let s = v3(&format!("{texture}\nMaterial \"plastic\" \"texture Ks\" \"t\""));
        assert_eq!(kind(&s), plain, "{texture}");
        assert_eq!(flagged(&s, what).len(), 1, "{texture}: {:?}", warnings(&s));
        let e = v4(&format!("{texture}\nMaterial \"coateddiffuse\" \"texture reflectance\" \"t\""));
        assert!(e.to_string().contains(":3:"), "{texture}: {e}");
    }
}

#[test]
fn a_v3_include_that_cannot_be_read_is_skipped_with_a_warning() {
    // pbrt-v3 reports it and reads on; pbrt-v4 stops, and so does a file whose
    // version is not known by the Include.
    let body = |film: &str| format!("{film}\nWorldBegin\nInclude \"nowhere.pbrt\"\nShape \"sphere\"\n");
    let s = scene(&format!("{}WorldEnd\n", body("Film \"image\"")));
    assert_eq!(s.shapes.len(), 1);
    let w: Vec<String> = warnings(&s).into_iter().filter(|m| m.contains("nowhere.pbrt")).collect();
    assert!(w.len() == 1 && w[0].contains("skipped, as pbrt-v3 skips it"), "{w:?}");
    for film in ["Film \"rgb\"", ""] {
        let e = load(&body(film)).expect_err(film).to_string();
        assert!(e.contains(":3:9: error: cannot read") && e.contains("nowhere.pbrt"), "{film}: {e}");
    }
}

/// pbrt-v3 reads a `spectrum` parameter's SPD file with a lenient scanner: a file it
/// cannot open is black, characters that are not numbers are skipped, a number the
/// file ends in without a line end is lost, and an odd count loses its last number.
/// Each is a located warning in a v3 file, with the spectrum pbrt-v3 makes (checked
/// against pbrt-v3's images); pbrt-v4 stops, and so does a file of unknown version.
#[test]
fn v3_spectrum_files_are_read_as_pbrt_v3_reads_them() {
    let files = [
        ("odd.spd", "400 0.5\n700 0.25 0.9\n"),
        ("junk.spd", "400 0.5 abc\n700 0.25\n"),
        ("cut.spd", "400 0.5\n700 0.25\n800 1"),
        ("good.spd", "# fine\n400 0.5\n700 0.25\n"),
    ];
    let dir = crate::common::scratch("spd", "v3", &files);
    let load = |film: &str, kds: &[&str]| {
        let mut text = format!("{film}WorldBegin\n");
        for kd in kds {
            text += &format!("Material \"matte\" \"spectrum Kd\" {kd}\nShape \"sphere\"\n");
        }
        text += if film.contains("image") { "WorldEnd\n" } else { "" };
        std::fs::write(dir.join("scene.pbrt"), text).unwrap();
        crate::common::load_file(&dir.join("scene.pbrt"))
    };
    let named = ["\"nope.spd\"", "\"odd.spd\"", "\"junk.spd\"", "\"cut.spd\"", "\"good.spd\""];
    let s = load("Film \"image\"\n", &named).unwrap_or_else(|e| panic!("{e}"));
    let pairs = "[400 0.5 700 0.25]";
    let inline = load("Film \"image\"\n", &["[360 0 830 0]", pairs, pairs, pairs, pairs]).expect("inline");
    for (k, (a, b)) in s.shapes.iter().zip(&inline.shapes).enumerate() {
        assert_eq!(s.materials[a.material as usize].kind, inline.materials[b.material as usize].kind, "{}", named[k]);
    }
    let w: Vec<_> = s.warnings.iter().filter(|w| w.message.contains("pbrt-v3")).collect();
    let lines: Vec<u32> = w.iter().map(|w| w.line).collect();
    assert_eq!(lines, [3, 5, 7, 9], "{w:?}");
    for (w, why) in w.iter().zip(["cannot read", "odd count", "3 characters", "no line end"]) {
        assert!(w.message.contains(why), "{w:?} lacks {why}");
    }
    for kd in &named[..3] {
        let e = load("Film \"rgb\"\n", &[kd]).expect_err("pbrt-v4 stops").to_string();
        assert!(e.contains("scene.pbrt:3:"), "{kd}: {e}");
        assert!(load("", &[kd]).is_err(), "{kd}: version not known");
    }
    // Outside pbrt-v3's scanner the last number is read: three pairs, no warning.
    assert!(load("Film \"rgb\"\n", &[named[3]]).expect("three pairs").warnings.is_empty());
}

/// A `screenwindow` of other than four values: both pbrts report it and render with
/// the default window (checked against both), so it is a warning in either version.
/// A non-finite one stays an error.
#[test]
fn a_screenwindow_of_three_values_is_ignored_with_a_warning_as_pbrt_ignores_it() {
    for film in ["Film \"image\"", "Film \"rgb\""] {
        let s = scene(&format!(
            "{film} \"integer xresolution\" 200 \"integer yresolution\" 100\nCamera \"perspective\" \"float screenwindow\" [-1 1 -1]\nWorldBegin\n"
        ));
        assert_eq!(s.camera.screen_window, [-2.0, 2.0, -1.0, 1.0], "{film}: the default window");
        let w = warnings(&s);
        assert!(w.iter().any(|m| m.contains("\"screenwindow\" needs 4 values, found 3; ignored")), "{film}: {w:?}");
    }
    let e = crate::common::load("Camera \"perspective\" \"float screenwindow\" [-1 inf -1 1]\nWorldBegin\n");
    assert!(e.expect_err("not finite").to_string().contains("must be finite"));
}

/// Parameters both pbrts report and render past: a texture mapping of another name is
/// (u, v) unscaled in either version; a v4 film's `cropwindow` or `pixelbounds` of
/// other than four values is ignored (pbrt-v4 renders the whole film; pbrt-v3 leaves
/// its crop window unset and renders nothing, so a v3 film's stays an error); an
/// unknown v4 `imagemap` filter is the default one. Each checked against its pbrt.
#[test]
fn slips_both_pbrts_render_past_are_warnings() {
    use pbrt_sppm::textures::TextureKind;
    for (film, kd) in
        [("Film \"image\"", "\"matte\" \"texture Kd\""), ("Film \"rgb\"", "\"diffuse\" \"texture reflectance\"")]
    {
        let s = scene(&format!(
            "{film}\nWorldBegin\nTexture \"t\" \"spectrum\" \"checkerboard\" \"string mapping\" \"toroidal\" \
             \"float uscale\" 4\nTexture \"u\" \"spectrum\" \"checkerboard\"\nMaterial {kd} \"t\" Shape \"sphere\"\n\
             Material {kd} \"u\" Shape \"sphere\"\n"
        ));
        let [a, b] = [&s.textures[0].kind, &s.textures[1].kind];
        let map = |k: &TextureKind| match k {
            TextureKind::Checkerboard { map, .. } => *map,
            other => panic!("{other:?}"),
        };
        assert_eq!(map(a), map(b), "{film}: unscaled (u, v)");
        assert!(warnings(&s).iter().any(|w| w.contains("unknown texture mapping \"toroidal\"")), "{film}");
    }
    for (param, value) in [("float cropwindow", "[0 0.5 0]"), ("integer pixelbounds", "[0 16 0]")] {
        let s = scene(&format!(
            "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32 \"{param}\" {value}\nWorldBegin\n"
        ));
        assert_eq!(s.film.pixel_bounds, [0, 32, 0, 32], "{param}: the whole film");
        assert!(warnings(&s).iter().any(|w| w.contains("needs 4 values, found 3; ignored")), "{param}");
        let v3 = crate::common::load(&format!("Film \"image\" \"{param}\" {value}\nWorldBegin\n"));
        assert!(v3.expect_err("pbrt-v3 renders nothing").to_string().contains("4"), "{param}");
    }
    let s = scene(
        "Film \"rgb\"\nWorldBegin\nTexture \"i\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \"string filter\" \"gauss\"\n\
         Material \"diffuse\" \"texture reflectance\" \"i\" Shape \"sphere\"\n",
    );
    assert!(warnings(&s).iter().any(|w| w.contains("unknown filter \"gauss\"")), "{:?}", warnings(&s));
}

/// An imagemap `wrap` of another name: pbrt-v3 repeats without a word (its image of
/// `"mirror"` equals its image of the default, checked), pbrt-v4 stops. A v3 file gets
/// repeat and a warning; a v4 file the error.
#[test]
fn a_v3_imagemap_wrap_of_another_name_repeats_as_pbrt_v3_does() {
    let body = |film: &str, kd: &str, wrap: &str| {
        format!(
            "{film}\nWorldBegin\nTexture \"i\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" {wrap}\n\
             Material {kd} \"i\" Shape \"sphere\"\n"
        )
    };
    let v3 = |wrap: &str| scene(&body("Film \"image\"", "\"matte\" \"texture Kd\"", wrap));
    let (mirror, plain) = (v3("\"string wrap\" \"mirror\""), v3(""));
    assert_eq!(mirror.textures, plain.textures, "repeat, the default");
    assert!(warnings(&mirror).iter().any(|w| w.contains("unknown wrap mode \"mirror\"; repeat")));
    let v4 =
        crate::common::load(&body("Film \"rgb\"", "\"diffuse\" \"texture reflectance\"", "\"string wrap\" \"mirror\""));
    assert!(v4.expect_err("pbrt-v4 stops").to_string().contains("\"wrap\" must be one of"));
}
