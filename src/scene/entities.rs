//! What each light, material, texture and shape type accepts, and which pbrt version
//! a type name proves. Parameters not listed for a type are warned as unused.
//!
//! ```text
//! LightSource "point" "rgb I" [1 1 1] "point3 from" [0 4 0]
//! AreaLightSource "diffuse" "blackbody L" [6500] "bool twosided" true
//! Material "glass" "float index" 1.5          # v3;  v4: Material "dielectric" "float eta" 1.5
//! Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "rgb tex1" [1 0 0]
//! ```

use crate::parser::Syntax;

/// Supported light types and their parameters (the union of v3 and v4).
pub fn light_params(ty: &str) -> Option<&'static [&'static str]> {
    Some(match ty {
        "point" => &["I", "scale", "from", "power"],
        "spot" => &["I", "scale", "coneangle", "conedeltaangle", "from", "to", "power"],
        "distant" => &["L", "scale", "from", "to", "illuminance"],
        "infinite" => &["L", "scale", "mapname", "filename", "samples", "nsamples", "illuminance"],
        _ => return None,
    })
}

/// Supported area light types and their parameters.
pub fn area_light_params(ty: &str) -> Option<&'static [&'static str]> {
    Some(match ty {
        "diffuse" | "area" => &["L", "scale", "twosided", "samples", "nsamples", "power"],
        _ => return None,
    })
}

/// Supported material types and their parameters.
pub fn material_params(ty: &str) -> Option<&'static [&'static str]> {
    Some(match ty {
        "matte" => &["Kd", "sigma", "bumpmap"],
        "diffuse" => &["reflectance", "displacement", "normalmap"],
        "mirror" => &["Kr", "bumpmap"],
        "glass" => &["Kr", "Kt", "eta", "index", "uroughness", "vroughness", "remaproughness", "bumpmap"],
        "dielectric" => {
            &["eta", "roughness", "uroughness", "vroughness", "remaproughness", "displacement", "normalmap"]
        }
        "metal" => &["eta", "k", "roughness", "uroughness", "vroughness", "remaproughness", "bumpmap"],
        "conductor" => &[
            "eta",
            "k",
            "reflectance",
            "roughness",
            "uroughness",
            "vroughness",
            "remaproughness",
            "displacement",
            "normalmap",
        ],
        "plastic" => &["Kd", "Ks", "roughness", "remaproughness", "bumpmap"],
        "coateddiffuse" => &[
            "reflectance",
            "roughness",
            "uroughness",
            "vroughness",
            "thickness",
            "eta",
            "albedo",
            "g",
            "maxdepth",
            "nsamples",
            "remaproughness",
            "displacement",
            "normalmap",
        ],
        "uber" => &[
            "Kd",
            "Ks",
            "Kr",
            "Kt",
            "roughness",
            "uroughness",
            "vroughness",
            "eta",
            "index",
            "opacity",
            "remaproughness",
            "bumpmap",
        ],
        "" | "none" | "interface" => &[],
        _ => return None,
    })
}

/// Supported texture classes and their parameters (mapping parameters included).
pub fn texture_params(class: &str) -> Option<&'static [&'static str]> {
    Some(match class {
        "constant" => &["value"],
        "checkerboard" => {
            &["tex1", "tex2", "dimension", "aamode", "mapping", "uscale", "vscale", "udelta", "vdelta", "v1", "v2"]
        }
        "imagemap" => &[
            "filename",
            "wrap",
            "maxanisotropy",
            "trilinear",
            "filter",
            "gamma",
            "encoding",
            "scale",
            "invert",
            "mapping",
            "uscale",
            "vscale",
            "udelta",
            "vdelta",
            "v1",
            "v2",
        ],
        "scale" => &["tex1", "tex2", "tex", "scale"],
        "mix" => &["tex1", "tex2", "amount"],
        _ => return None,
    })
}

/// Parameters that name float textures (the rest name spectrum textures).
pub fn is_float_texture_param(name: &str) -> bool {
    matches!(
        name,
        "bumpmap"
            | "displacement"
            | "roughness"
            | "uroughness"
            | "vroughness"
            | "sigma"
            | "amount"
            | "index"
            | "thickness"
            | "g"
            | "opacity"
            | "alpha"
            | "shadowalpha"
    )
}

/// The pbrt version a type name belongs to, for syntax detection.
pub fn evidence(directive: &str, ty: &str) -> Option<Syntax> {
    use Syntax::*;
    match (directive, ty) {
        ("Film", "image") => Some(V3),
        ("Film", "rgb" | "gbuffer" | "spectral") => Some(V4),
        ("Material" | "MakeNamedMaterial", t) => match t {
            "matte" | "plastic" | "glass" | "metal" | "mirror" | "uber" | "substrate" | "translucent"
            | "kdsubsurface" | "fourier" | "disney" | "none" | "" => Some(V3),
            "diffuse"
            | "dielectric"
            | "conductor"
            | "coateddiffuse"
            | "coatedconductor"
            | "thindielectric"
            | "diffusetransmission"
            | "measured"
            | "interface" => Some(V4),
            _ => None,
        },
        ("Shape", "cone" | "paraboloid" | "hyperboloid" | "heightfield" | "nurbs") => Some(V3),
        ("Shape", "bilinearmesh") => Some(V4),
        ("AreaLightSource", "area") => Some(V3),
        ("Sampler", "lowdiscrepancy" | "02sequence" | "maxmindist" | "random") => Some(V3),
        ("Sampler", "zsobol" | "pmj02bn" | "paddedsobol" | "independent") => Some(V4),
        ("Integrator", "directlighting" | "whitted") => Some(V3),
        ("Integrator", "volpath" | "simplepath" | "lightpath" | "simplevolpath" | "randomwalk") => Some(V4),
        _ => None,
    }
}
