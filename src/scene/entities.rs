//! Which pbrt version a type name proves, for syntax detection.
//!
//! ```text
//! Film "image" ...                 # v3 (v4 writes Film "rgb")
//! Material "dielectric" ...        # v4 (v3 writes Material "glass")
//! Shape "cone" ...                 # v3 (v4 removed the cone)
//! MakeNamedMedium "m" "string type" "uniformgrid"   # v4 (v3 writes "heterogeneous")
//! ```

use crate::parser::Syntax;

/// The pbrt version a type name belongs to, for syntax detection.
pub fn evidence(directive: &str, ty: &str) -> Option<Syntax> {
    use Syntax::*;
    match (directive, ty) {
        ("Film", "image") => Some(V3),
        ("Film", "rgb" | "gbuffer" | "spectral") => Some(V4),
        ("Material" | "MakeNamedMaterial", t) => crate::materials::evidence(t),
        ("Shape", t) => crate::shapes::evidence(t),
        ("AreaLightSource", t) => crate::lights::diffuse::evidence(t),
        ("Sampler", "lowdiscrepancy" | "02sequence" | "maxmindist" | "random") => Some(V3),
        ("Sampler", "zsobol" | "pmj02bn" | "paddedsobol" | "independent") => Some(V4),
        ("Integrator", "directlighting" | "whitted") => Some(V3),
        // Both versions have `volpath` (and `path`, `bdpt`, `mlt`, `sppm`,
        // `ambientocclusion`): no evidence.
        ("Integrator", "simplepath" | "lightpath" | "simplevolpath" | "randomwalk" | "aov" | "function") => Some(V4),
        ("MakeNamedMedium", "heterogeneous") => Some(V3),
        ("MakeNamedMedium", "uniformgrid" | "rgbgrid" | "cloud" | "nanovdb") => Some(V4),
        _ => None,
    }
}
