//! The type names pbrt-v3 and pbrt-v4 know, per family, so that a typo is told apart
//! from a known type we do not render, and answered the way the file's pbrt answers it.
//!
//! ```text
//! Shape "sphre"                  # unknown shape type "sphre" (did you mean "sphere"?)
//! Material "fourier" ...         # known to pbrt-v3, not rendered here: approximated
//! ```
//!
//! pbrt-v4 stops at any unknown type name. pbrt-v3 warns and goes on for shapes,
//! lights, area lights, textures and media (leaving the statement out) and materials
//! (using `matte` with the statement's parameters); an unknown camera, sampler, film,
//! filter or integrator leaves it with nothing to render, so that is an error for both.

use crate::parser::Syntax;

/// A family of types, named by its directive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    Shape,
    Material,
    Texture,
    Light,
    AreaLight,
    Medium,
    Camera,
    Sampler,
    Filter,
    Film,
    Integrator,
}

impl Family {
    /// "shape type", "texture class", ...: what a message calls the name.
    pub fn noun(self) -> &'static str {
        match self {
            Family::Shape => "shape type",
            Family::Material => "material type",
            Family::Texture => "texture class",
            Family::Light => "light type",
            Family::AreaLight => "area light type",
            Family::Medium => "medium type",
            Family::Camera => "camera type",
            Family::Sampler => "sampler type",
            Family::Filter => "filter type",
            Family::Film => "film type",
            Family::Integrator => "integrator",
        }
    }

    /// Every name pbrt-v3 or pbrt-v4 (or this renderer) knows in the family.
    pub fn known(self) -> &'static [&'static str] {
        match self {
            Family::Shape => SHAPES,
            Family::Material => MATERIALS,
            Family::Texture => TEXTURES,
            Family::Light => LIGHTS,
            Family::AreaLight => AREA_LIGHTS,
            Family::Medium => MEDIA,
            Family::Camera => CAMERAS,
            Family::Sampler => SAMPLERS,
            Family::Filter => FILTERS,
            Family::Film => FILMS,
            Family::Integrator => INTEGRATORS,
        }
    }

    pub fn knows(self, name: &str) -> bool {
        self.known().contains(&name)
    }

    /// Whether pbrt-v3 renders on past an unknown name of this family (warning and
    /// leaving the statement out, or a matte material).
    pub fn v3_goes_on(self) -> bool {
        matches!(
            self,
            Family::Shape | Family::Material | Family::Texture | Family::Light | Family::AreaLight | Family::Medium
        )
    }

    /// Whether the file's pbrt stops at an unknown name of this family.
    pub fn stops(self, syntax: Syntax) -> bool {
        syntax == Syntax::V4 || !self.v3_goes_on()
    }

    /// `unknown shape type "sphre" (did you mean "sphere"?)`.
    pub fn unknown(self, name: &str) -> String {
        unknown(self.noun(), name, self.known())
    }
}

/// `unknown {noun} "name"`, with the nearest of `known` suggested when one is close.
pub fn unknown(noun: &str, name: &str, known: &[&str]) -> String {
    match nearest(name, known) {
        Some(n) => format!("unknown {noun} \"{name}\" (did you mean \"{n}\"?)"),
        None => format!("unknown {noun} \"{name}\""),
    }
}

// pbrt-v3's and pbrt-v4's names (and `objmesh`, which we read too).
const SHAPES: &[&str] = &[
    "sphere",
    "cylinder",
    "disk",
    "cone",
    "paraboloid",
    "hyperboloid",
    "curve",
    "trianglemesh",
    "plymesh",
    "objmesh",
    "heightfield",
    "loopsubdiv",
    "nurbs",
    "bilinearmesh",
];
const MATERIALS: &[&str] = &[
    "matte",
    "plastic",
    "translucent",
    "glass",
    "mirror",
    "hair",
    "mix",
    "metal",
    "substrate",
    "uber",
    "subsurface",
    "kdsubsurface",
    "fourier",
    "disney",
    "none",
    "",
    "coateddiffuse",
    "coatedconductor",
    "conductor",
    "dielectric",
    "thindielectric",
    "diffuse",
    "diffusetransmission",
    "interface",
    "measured",
];
const TEXTURES: &[&str] = &[
    "constant",
    "scale",
    "mix",
    "directionmix",
    "bilerp",
    "imagemap",
    "uv",
    "checkerboard",
    "dots",
    "fbm",
    "wrinkled",
    "windy",
    "marble",
    "ptex",
];
const LIGHTS: &[&str] = &["point", "spot", "goniometric", "projection", "distant", "infinite", "exinfinite"];
const AREA_LIGHTS: &[&str] = &["area", "diffuse"];
const MEDIA: &[&str] = &["homogeneous", "heterogeneous", "uniformgrid", "rgbgrid", "cloud", "nanovdb"];
const CAMERAS: &[&str] = &["perspective", "orthographic", "realistic", "environment", "spherical"];
const SAMPLERS: &[&str] = &[
    "lowdiscrepancy",
    "02sequence",
    "maxmindist",
    "halton",
    "sobol",
    "random",
    "stratified",
    "independent",
    "paddedsobol",
    "pmj02bn",
    "zsobol",
];
const FILTERS: &[&str] = &["box", "gaussian", "mitchell", "sinc", "triangle"];
const FILMS: &[&str] = &["image", "rgb", "gbuffer", "spectral"];
const INTEGRATORS: &[&str] = &[
    "whitted",
    "directlighting",
    "path",
    "volpath",
    "bdpt",
    "mlt",
    "ambientocclusion",
    "sppm",
    "aov",
    "lightpath",
    "randomwalk",
    "simplepath",
    "simplevolpath",
    "function",
];

/// The known name closest to `name` by edit distance (case ignored), if close enough
/// to be a typo: at most a third of its letters, and at least one, changed.
pub fn nearest<'a>(name: &str, known: &[&'a str]) -> Option<&'a str> {
    let lower = name.to_ascii_lowercase();
    let reach = (lower.chars().count() / 3).max(1);
    known
        .iter()
        .filter(|k| !k.is_empty())
        .map(|k| (distance(&lower, k), *k))
        .filter(|(d, _)| *d <= reach)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// Levenshtein distance, with a swap of two neighbours counted as one edit.
fn distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut rows = vec![(0..=b.len()).collect::<Vec<_>>(); a.len() + 1];
    for (i, row) in rows.iter_mut().enumerate() {
        row[0] = i;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut d = (rows[i - 1][j] + 1).min(rows[i][j - 1] + 1).min(rows[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d = d.min(rows[i - 2][j - 2] + 1);
            }
            rows[i][j] = d;
        }
    }
    rows[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typos_suggest_the_nearest_known_name() {
        assert_eq!(Family::Shape.unknown("sphre"), "unknown shape type \"sphre\" (did you mean \"sphere\"?)");
        assert_eq!(nearest("mattte", Family::Material.known()), Some("matte"));
        assert_eq!(nearest("gausian", Family::Filter.known()), Some("gaussian"));
        assert_eq!(nearest("Sphere", Family::Shape.known()), Some("sphere"));
        assert_eq!(nearest("homogenous", Family::Medium.known()), Some("homogeneous"));
        assert_eq!(nearest("pont", Family::Light.known()), Some("point"));
        assert_eq!(nearest("halotn", Family::Sampler.known()), Some("halton"), "a swap is one edit");
        assert_eq!(nearest("teapot", Family::Shape.known()), None);
        assert_eq!(Family::Integrator.unknown("xyz"), "unknown integrator \"xyz\"");
    }

    #[test]
    fn pbrt_v3_goes_on_past_unknown_scene_content_and_stops_at_unknown_options() {
        assert!(!Family::Shape.stops(Syntax::V3) && Family::Shape.stops(Syntax::V4));
        assert!(Family::Camera.stops(Syntax::V3) && Family::Integrator.stops(Syntax::V3));
    }
}
