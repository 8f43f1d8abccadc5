//! One registry per family: every name a registry lists is read by its own module and
//! renders as itself (nothing skipped or approximated), and the names are unique. A
//! type added to a registry without a working reader fails here.

use crate::common::root;
use pbrt_sppm::scene::SceneDescription;
use std::collections::BTreeSet;

fn unique(family: &str, names: &[&str]) {
    let set: BTreeSet<&str> = names.iter().copied().collect();
    assert_eq!(set.len(), names.len(), "{family}: a name is registered twice: {names:?}");
}

/// Loads `world` under a camera, as a file in pbrt-scenes/verify (so its geometry and
/// textures resolve), and checks nothing was skipped or approximated.
fn loads_as_itself(what: &str, world: &str) -> SceneDescription {
    let text = format!("LookAt 0 0 -5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n{world}\n");
    let path = root().join("pbrt-scenes/verify/registry.pbrt");
    let opts = pbrt_sppm::scene::LoadOptions::default();
    let s = pbrt_sppm::scene::load_scene_from_bytes(&path, text.into_bytes(), &opts)
        .unwrap_or_else(|e| panic!("{what} does not load: {e}"));
    assert!(s.skipped.is_empty(), "{what}: skipped {:?}", s.skipped.iter().map(|k| &k.what).collect::<Vec<_>>());
    assert!(
        s.approximated.is_empty(),
        "{what}: approximated {:?}",
        s.approximated.iter().map(|a| &a.how).collect::<Vec<_>>()
    );
    s
}

/// The name of an enum value's variant, from its `Debug` form.
fn variant(v: &impl std::fmt::Debug) -> String {
    format!("{v:?}").chars().take_while(|c| c.is_alphanumeric()).collect()
}

/// The description each material type reads into; a type registered without an entry
/// here fails.
fn material_variant(name: &str) -> &'static str {
    match name {
        "matte" | "diffuse" => "Diffuse",
        "mirror" => "Mirror",
        "glass" | "dielectric" => "Dielectric",
        "thindielectric" => "ThinDielectric",
        "metal" | "conductor" => "Conductor",
        "plastic" => "Plastic",
        "uber" => "Uber",
        "translucent" => "Translucent",
        "substrate" => "Substrate",
        "disney" => "Disney",
        "coateddiffuse" | "coatedconductor" => "Coated",
        "diffusetransmission" => "DiffuseTransmission",
        "interface" | "none" | "" => "Interface",
        "mix" => "Mix",
        "hair" => "Hair",
        "fourier" => "Fourier",
        "measured" => "Measured",
        "subsurface" | "kdsubsurface" => "Subsurface",
        other => panic!("material {other:?} is registered but this test does not know it"),
    }
}

#[test]
fn every_registered_light_type_reads_as_itself() {
    let names: Vec<&str> = pbrt_sppm::lights::REGISTRY.iter().map(|t| t.name).collect();
    unique("lights", &names);
    for name in names {
        // pbrt-v4 (the default syntax) requires a projection light's slide.
        let params = if name == "projection" { "\"string filename\" \"textures/slide.exr\"" } else { "" };
        let s = loads_as_itself(name, &format!("LightSource \"{name}\" {params}\nShape \"sphere\""));
        assert_eq!(s.lights.iter().map(|l| l.name()).collect::<Vec<_>>(), [name]);
    }
    for name in pbrt_sppm::lights::diffuse::NAMES {
        let s = loads_as_itself(name, &format!("AreaLightSource \"{name}\"\nShape \"sphere\""));
        assert_eq!(s.area_lights.len(), 1, "{name}");
    }
}

#[test]
fn every_registered_material_type_reads_as_itself() {
    let names: Vec<&str> = pbrt_sppm::materials::REGISTRY.iter().map(|t| t.name).collect();
    unique("materials", &names);
    let named = "MakeNamedMaterial \"a\" \"string type\" \"matte\"\nMakeNamedMaterial \"b\" \"string type\" \"mirror\"";
    for name in names {
        let (named, params) = match name {
            "mix" => (named, "\"string namedmaterial1\" \"a\" \"string namedmaterial2\" \"b\""),
            "fourier" => ("", "\"string bsdffile\" \"bsdfs/glazed.bsdf\""),
            "measured" => ("", "\"string filename\" \"bsdfs/rosegold.bsdf\""),
            _ => ("", ""),
        };
        let world = format!("{named}\nMaterial \"{name}\" {params}\nShape \"sphere\"");
        let s = loads_as_itself(&format!("material {name:?}"), &world);
        let used = &s.materials[s.shapes[0].material as usize];
        assert_eq!(used.ty, name);
        assert_eq!(variant(&used.kind), material_variant(name), "material {name:?} is read by another type's reader");
        assert_eq!(
            pbrt_sppm::materials::evidence(name),
            pbrt_sppm::materials::REGISTRY.iter().find(|t| t.name == name).unwrap().syntax
        );
    }
    // Every type pbrt-v3 or pbrt-v4 knows is rendered: none is left to approximate.
    for name in pbrt_sppm::scene::names::Family::Material.known() {
        assert!(pbrt_sppm::materials::REGISTRY.iter().any(|t| t.name == *name), "material {name:?} is not rendered");
    }
}

#[test]
fn every_registered_texture_class_reads_as_itself() {
    let names: Vec<&str> = pbrt_sppm::textures::REGISTRY.iter().map(|c| c.name).collect();
    unique("textures", &names);
    for name in names {
        let params = match name {
            "imagemap" => "\"string filename\" \"textures/domes-normal.png\"",
            "ptex" => "\"string filename\" \"textures/ptex-grid.ptx\"",
            _ => "",
        };
        let world = format!(
            "Texture \"t\" \"spectrum\" \"{name}\" {params}\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\nShape \"sphere\""
        );
        let s = loads_as_itself(&format!("texture {name:?}"), &world);
        assert_eq!(s.textures.len(), 1, "{name}");
        let expected = match name {
            "imagemap" => "Image",
            "directionmix" => "DirectionMix",
            other => &format!("{}{}", other[..1].to_uppercase(), &other[1..]),
        };
        assert_eq!(variant(&s.textures[0].kind), expected, "texture {name:?} is read by another class's reader");
    }
}

#[test]
fn every_registered_shape_type_reads_as_itself() {
    // The parameters each type needs; a type registered without an entry here fails.
    let params = |name: &str| match name {
        "trianglemesh" => "\"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]",
        "bilinearmesh" => "\"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0]",
        "loopsubdiv" => "\"point3 P\" [0 0 0 1 0 0 0 1 0 0 0 1] \"integer indices\" [0 2 1 0 1 3 0 3 2 1 2 3]",
        "plymesh" => "\"string filename\" \"geometry/twisted-quads.ply\"",
        "objmesh" => "\"string filename\" \"../v3/geometry/cube.obj\"",
        // The default p1, p2 meet the z axis, where pbrt-v3 hangs (an error here).
        "hyperboloid" => "\"point3 p1\" [1 0 -1] \"point3 p2\" [0 1 1]",
        "heightfield" => "\"integer nu\" 2 \"integer nv\" 2 \"float Pz\" [0 1 1 0]",
        "nurbs" => {
            "\"integer nu\" 2 \"integer nv\" 2 \"integer uorder\" 2 \"integer vorder\" 2 \
             \"float uknots\" [0 0 1 1] \"float vknots\" [0 0 1 1] \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 1]"
        }
        "curve" => "\"point3 P\" [0 0 0 1 1 0 2 -1 0 3 0 0]",
        "sphere" | "cylinder" | "disk" | "cone" | "paraboloid" => "",
        other => panic!("shape {other:?} is registered but this test does not know its parameters"),
    };
    let names: Vec<&str> = pbrt_sppm::shapes::REGISTRY.iter().map(|t| t.name).collect();
    unique("shapes", &names);
    for name in names {
        let s = loads_as_itself(&format!("shape {name:?}"), &format!("Shape \"{name}\" {}", params(name)));
        assert!(!s.shapes.is_empty(), "{name}");
        assert!(s.shapes.iter().all(|sh| sh.kind() == name), "{name}");
    }
}
