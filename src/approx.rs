//! What we render differently from what a scene file says: one kind per way, with the
//! text `check`, the renderer and the README all use (a test holds the README to it).
//!
//! ```text
//! Material "mix" "string namedmaterial1" "coated" ...     # approximated: the coat's base only
//! Texture "t" "float" "ptex" "string filename" "gone.ptx"   # approximated: black
//! ```

/// One way of rendering something other than as written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Approx {
    CoatInBlend,
    HairInBlend,
    UnsupportedTexture,
    MissingImage,
    UnreadablePtex,
    UnreadableBsdfFile,
    Motion,
    FilmType,
    ColorSpace,
    Sensor,
}

impl Approx {
    pub const ALL: [Approx; 10] = [
        Approx::CoatInBlend,
        Approx::HairInBlend,
        Approx::UnsupportedTexture,
        Approx::MissingImage,
        Approx::UnreadablePtex,
        Approx::UnreadableBsdfFile,
        Approx::Motion,
        Approx::FilmType,
        Approx::ColorSpace,
        Approx::Sensor,
    ];

    /// How it is rendered instead (the README lists these texts).
    pub fn how(self) -> &'static str {
        match self {
            Approx::CoatInBlend => "a pbrt-v3 mix blends lobes: its coated part adds only the base under the coat",
            Approx::HairInBlend => {
                "a pbrt-v3 mix blends lobes: its hair part adds nothing (a fibre is not kept as lobes)"
            }
            Approx::UnsupportedTexture => "this texture class is not supported; a constant 0.5 is used",
            Approx::MissingImage => {
                "the image cannot be read; as in pbrt-v3, an image texture is a grey texel of 0.5 (sRGB-decoded where `gamma` is on, as it is for PNG and TGA) times `scale`, an environment map a constant sky, a normal map a smooth surface"
            }
            Approx::UnreadablePtex => {
                "the Ptex file cannot be read, or has other than 1 or 3 channels; black, as pbrt renders it"
            }
            Approx::UnreadableBsdfFile => "the BSDF file cannot be read; black, as pbrt-v3 renders it",
            Approx::Motion => {
                "a moving shape inside an object definition keeps its start transform (motion nests there in pbrt)"
            }
            Approx::FilmType => "written as an RGB film (R, G, B channels only)",
            Approx::ColorSpace => {
                "one colour space serves a scene: the first `ColorSpace` named, for every RGB value and the film"
            }
            Approx::Sensor => {
                "rendered in RGB (`--colour rgb`), the camera's measured curves cannot apply: seen as the CIE 1931 observer, white-balanced as pbrt-v4 balances that camera (6500 K unless `whitebalance` is given)"
            }
        }
    }
}
