//! Textures, one module per class, each owning its parameters, its evaluation at a hit
//! and its name; [`REGISTRY`] is the one list of `Texture` classes. Float textures are
//! stored as grey RGB. Textures live in one array and refer to each other by index, so
//! shared definitions are stored once ([`Textures`]).
//!
//! ```text
//! Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "rgb tex1" [1 0 0]
//! Texture "s" "spectrum" "scale" "texture tex" "checks" "float scale" 0.5
//! Texture "img" "spectrum" "imagemap" "string filename" "wood.png"
//! Texture "n" "float" "fbm" "integer octaves" 8 "float roughness" .5
//! ```
//! 2D textures map the hit through `"string mapping"` ([`mapping`]); 3D textures
//! (`fbm`, `wrinkled`, `windy`, `marble`, 3D `checkerboard`) work in texture space, as
//! each version defines it. Textures are point-sampled: SPPM's many samples per pixel
//! do the filtering that pbrt's ray differentials do for the first hit; `ptex` filters
//! as the Ptex library does, over the first hit's footprint.
//!
//! Adding a texture class: a module here with `NAME`, `read` and `eval`; a variant in
//! [`TextureKind`]; a line in [`REGISTRY`]; then the `match` in [`Textures`]' evaluation.

pub mod bilerp;
pub mod checkerboard;
pub mod constant;
pub mod directionmix;
pub mod dots;
pub mod fbm;
pub mod imagemap;
pub mod mapping;
pub mod marble;
pub mod mix;
pub mod noise;
pub mod ptex;
pub mod scale;
pub mod uv;
pub mod windy;
pub mod wrinkled;

pub use crate::imageio::Wrap;
pub use mapping::{Mapping2D, TextureSite, UvMapping};
pub use noise::Octaves;

use crate::fixes::{Fix, Fixes};
use crate::imageio::Texels;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::spectrum::Rgb;
use crate::values::{self, Range, Res, Resolver, TexValue, float_input, spectrum_input};
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// What a texture class's reader is given besides its parameters.
pub struct Input<'a> {
    /// A `"float"` texture (else `"spectrum"`).
    pub is_float: bool,
    pub r: &'a mut dyn Resolver,
}

impl Input<'_> {
    /// A texture input of the texture's own kind (float or spectrum).
    pub fn input(&mut self, p: &ParamList, name: &str, default: f32) -> Res<TexValue> {
        if self.is_float {
            float_input(p, name, default, Range::Any, self.r)
        } else {
            spectrum_input(p, name, default, self.r)
        }
    }

    /// A float input (constant or float texture).
    pub fn float(&mut self, p: &ParamList, name: &str, default: f32, range: Range) -> Res<TexValue> {
        float_input(p, name, default, range, self.r)
    }

    /// A constant input (`bilerp`'s corners): a float, or a spectrum as RGB.
    pub fn constant(&mut self, p: &ParamList, name: &str, default: f32) -> Res<Rgb> {
        Ok(if self.is_float {
            Vec3::splat(values::float(p, name, default, Range::Any)?)
        } else {
            values::rgb(p, name, &self.r.spectra(), Range::Any)?.unwrap_or(Vec3::splat(default))
        })
    }
}

/// A `Texture` class: its name and its reader (`None` from the reader: not for this
/// kind, float or spectrum).
pub struct TextureClass {
    pub name: &'static str,
    pub read: fn(&mut Input, &ParamList, Span, &TextureSite) -> Res<Option<TextureKind>>,
}

const fn class(
    name: &'static str,
    read: fn(&mut Input, &ParamList, Span, &TextureSite) -> Res<Option<TextureKind>>,
) -> TextureClass {
    TextureClass { name, read }
}

/// Every `Texture` class we render.
pub const REGISTRY: [TextureClass; 14] = [
    class(constant::NAME, constant::read),
    class(checkerboard::NAME, checkerboard::read),
    class(scale::NAME, scale::read),
    class(mix::NAME, mix::read),
    class(directionmix::NAME, directionmix::read),
    class(bilerp::NAME, bilerp::read),
    class(imagemap::NAME, imagemap::read),
    class(dots::NAME, dots::read),
    class(fbm::NAME, fbm::read),
    class(wrinkled::NAME, wrinkled::read),
    class(windy::NAME, windy::read),
    class(marble::NAME, marble::read),
    class(uv::NAME, uv::read),
    class(ptex::NAME, ptex::read),
];

/// A texture of class `class`, or `None` for classes (or kinds) we do not support.
pub fn read(
    class: &str,
    is_float: bool,
    p: &ParamList,
    at: Span,
    site: &TextureSite,
    r: &mut dyn Resolver,
) -> Res<Option<TextureKind>> {
    let Some(c) = REGISTRY.iter().find(|c| c.name == class) else { return Ok(None) };
    (c.read)(&mut Input { is_float, r }, p, at, site)
}

#[derive(Clone, Debug, PartialEq)]
pub enum TextureKind {
    Constant(TexValue),
    Checkerboard {
        tex1: TexValue,
        tex2: TexValue,
        map: Mapping2D,
    },
    Checkerboard3D {
        tex1: TexValue,
        tex2: TexValue,
        map: Mat4,
    },
    Scale {
        tex: TexValue,
        scale: TexValue,
    },
    Mix {
        tex1: TexValue,
        tex2: TexValue,
        amount: TexValue,
    },
    /// `tex1` where the geometric normal is along `dir` (world space), `tex2` across it.
    DirectionMix {
        tex1: TexValue,
        tex2: TexValue,
        dir: Vec3,
    },
    /// Corner values at (s, t) = (0,0), (1,0), (0,1), (1,1).
    Bilerp {
        v: [Rgb; 4],
        map: Mapping2D,
    },
    Image {
        image: Arc<Texels>,
        map: Mapping2D,
        wrap: Wrap,
        scale: f32,
        invert: bool,
    },
    /// Polka dots: `dot` inside them, `background` around them.
    Dots {
        dot: TexValue,
        background: TexValue,
        map: Mapping2D,
    },
    Fbm {
        map: Mat4,
        octaves: Octaves,
    },
    Wrinkled {
        map: Mat4,
        octaves: Octaves,
    },
    Windy {
        map: Mat4,
    },
    Marble {
        map: Mat4,
        octaves: Octaves,
        scale: f32,
        variation: f32,
        /// pbrt-v3's colour spline segments (see [`marble::colour`]).
        v3_segments: bool,
    },
    /// (s, t) modulo 1 as red and green.
    Uv {
        map: Mapping2D,
    },
    Ptex(Arc<ptex::PtexTexture>),
}

/// A texture some used material (or texture) refers to.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureDesc {
    pub name: String,
    pub kind: TextureKind,
}

impl TextureKind {
    /// The textures this one reads.
    pub fn inputs(&self) -> Vec<TexValue> {
        use TextureKind as K;
        match self {
            K::Constant(v) => vec![*v],
            K::Checkerboard { tex1, tex2, .. } | K::Checkerboard3D { tex1, tex2, .. } => vec![*tex1, *tex2],
            K::DirectionMix { tex1, tex2, .. } => vec![*tex1, *tex2],
            K::Scale { tex, scale } => vec![*tex, *scale],
            K::Mix { tex1, tex2, amount } => vec![*tex1, *tex2, *amount],
            K::Dots { dot, background, .. } => vec![*dot, *background],
            K::Bilerp { .. } | K::Image { .. } | K::Fbm { .. } | K::Wrinkled { .. } => vec![],
            K::Windy { .. } | K::Marble { .. } | K::Uv { .. } | K::Ptex(_) => vec![],
        }
    }
}

/// Where a texture is looked up: the world-space point, the geometric normal, (u, v),
/// the point's change across a pixel (zero without ray differentials), the same in
/// (u, v) as (∂u/∂x, ∂v/∂x, ∂u/∂y, ∂v/∂y), and the mesh face's index (`faceIndices`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexCtx {
    pub p: Vec3,
    pub n: Vec3,
    pub uv: [f32; 2],
    pub dpdx: Vec3,
    pub dpdy: Vec3,
    pub duv: [f32; 4],
    pub face: i32,
}

/// Every texture of a scene, by the indices [`TexValue::Texture`] names.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Textures(pub Vec<TextureKind>);

impl Textures {
    /// The scene's textures, with the pbrt bugs in `fixes` fixed.
    pub fn new(descs: &[TextureDesc], fixes: Fixes) -> Textures {
        let fixed = |t: &TextureDesc| {
            let mut k = t.kind.clone();
            if let TextureKind::Marble { v3_segments, .. } = &mut k {
                *v3_segments &= !fixes.has(Fix::MarblePalette);
            }
            k
        };
        Textures(descs.iter().map(fixed).collect())
    }

    /// Whether some texture reads the footprint (`dpdx`, `dpdy`, `duv`): the noise
    /// textures and `ptex`.
    pub fn use_footprint(&self) -> bool {
        use TextureKind as K;
        self.0
            .iter()
            .any(|t| matches!(t, K::Fbm { .. } | K::Wrinkled { .. } | K::Windy { .. } | K::Marble { .. } | K::Ptex(_)))
    }

    /// Whether some texture reads `duv` (then the caller fills it in).
    pub fn use_duv(&self) -> bool {
        self.0.iter().any(|t| matches!(t, TextureKind::Ptex(_)))
    }

    #[inline]
    pub fn eval(&self, v: TexValue, ctx: &TexCtx) -> Rgb {
        match v {
            TexValue::Const(c) => c,
            TexValue::Texture(t) => self.0.get(t as usize).map_or(Vec3::ZERO, |t| self.eval_kind(t, ctx)),
        }
    }

    /// A float input (the red channel of its grey).
    pub fn float(&self, v: TexValue, ctx: &TexCtx) -> f32 {
        self.eval(v, ctx).x
    }

    /// One texture at a hit, by its class's module.
    fn eval_kind(&self, k: &TextureKind, ctx: &TexCtx) -> Rgb {
        use TextureKind as K;
        let get = |v: TexValue| self.eval(v, ctx);
        match k {
            K::Constant(v) => constant::eval(*v, get),
            K::Checkerboard { tex1, tex2, map } => checkerboard::eval_2d([*tex1, *tex2], map, ctx, get),
            K::Checkerboard3D { tex1, tex2, map } => checkerboard::eval_3d([*tex1, *tex2], map, ctx, get),
            K::Scale { tex, scale } => scale::eval(*tex, *scale, get),
            K::Mix { tex1, tex2, amount } => mix::eval([*tex1, *tex2, *amount], get),
            K::DirectionMix { tex1, tex2, dir } => directionmix::eval([*tex1, *tex2], *dir, ctx, get),
            K::Bilerp { v, map } => bilerp::eval(v, map, ctx),
            K::Image { image, map, wrap, scale, invert } => imagemap::eval(image, map, (*wrap, *scale, *invert), ctx),
            K::Dots { dot, background, map } => dots::eval([*dot, *background], map, ctx, get),
            K::Fbm { map, octaves } => fbm::eval(map, octaves, ctx),
            K::Wrinkled { map, octaves } => wrinkled::eval(map, octaves, ctx),
            K::Windy { map } => windy::eval(map, ctx),
            K::Marble { map, octaves, scale, variation, v3_segments } => {
                marble::eval(map, octaves, [*scale, *variation], *v3_segments, ctx)
            }
            K::Uv { map } => uv::eval(map, ctx),
            K::Ptex(t) => ptex::eval(t, ctx),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::mapping::map_2d;
    use super::*;

    fn at(p: Vec3, uv: [f32; 2]) -> TexCtx {
        TexCtx { p, n: Vec3::Z, uv, ..TexCtx::default() }
    }

    fn c(v: f32) -> TexValue {
        TexValue::Const(Vec3::splat(v))
    }

    #[test]
    fn mappings_follow_pbrt() {
        let id = Mat4::IDENTITY;
        let ctx = at(Vec3::new(0.0, 2.0, 0.0), [0.0; 2]);
        let [s, t] = map_2d(&Mapping2D::Spherical { texture_from_world: id }, &ctx);
        assert!((s - 0.5).abs() < 1e-6 && (t - 0.25).abs() < 1e-6, "{s} {t}");
        let [s, t] =
            map_2d(&Mapping2D::Cylindrical { texture_from_world: id }, &at(Vec3::new(-1.0, 0.0, 3.0), [0.0; 2]));
        assert!((s - 1.0).abs() < 1e-6 && t == 3.0, "{s} {t}");
        let planar = Mapping2D::Planar { texture_from_world: id, vs: Vec3::X, vt: Vec3::Z, ds: 0.5, dt: -1.0 };
        assert_eq!(map_2d(&planar, &at(Vec3::new(2.0, 7.0, 3.0), [0.0; 2])), [2.5, 2.0]);
        let uv = Mapping2D::Uv(UvMapping { su: 2.0, sv: 3.0, du: 0.5, dv: 0.0 });
        assert_eq!(map_2d(&uv, &at(Vec3::ZERO, [0.25, 0.5])), [1.0, 1.5]);
    }

    #[test]
    fn checkerboards_alternate_in_2d_and_3d() {
        let t = Textures(vec![
            TextureKind::Checkerboard3D { tex1: c(1.0), tex2: c(0.0), map: Mat4::IDENTITY },
            TextureKind::Bilerp {
                v: [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
                map: Mapping2D::Uv(UvMapping { su: 1.0, sv: 1.0, du: 0.0, dv: 0.0 }),
            },
        ]);
        let v = |p: Vec3| t.float(TexValue::Texture(0), &at(p, [0.0; 2]));
        assert_eq!(v(Vec3::new(0.5, 0.5, 0.5)), 1.0);
        assert_eq!(v(Vec3::new(1.5, 0.5, 0.5)), 0.0);
        assert_eq!(v(Vec3::new(-0.5, 0.5, 0.5)), 0.0);
        assert_eq!(v(Vec3::new(-0.5, -0.5, 0.5)), 1.0);
        let b = t.eval(TexValue::Texture(1), &at(Vec3::ZERO, [0.25, 0.75]));
        assert!((b - Vec3::new(0.25 * 0.25, 0.75 * 0.75, 0.25 * 0.75)).length() < 1e-6, "{b}");
    }

    #[test]
    fn dots_cover_about_a_fifth_of_the_plane() {
        // Half the cells hold a dot of area π·0.35² ≈ 0.385: about 19% covered.
        let map = Mapping2D::Uv(UvMapping { su: 1.0, sv: 1.0, du: 0.0, dv: 0.0 });
        let t = Textures(vec![TextureKind::Dots { dot: c(1.0), background: c(0.0), map }]);
        let n = 200;
        let mut inside = 0.0;
        for i in 0..n * n {
            let uv = [(i % n) as f32 * 0.173 + 0.01, (i / n) as f32 * 0.131 + 0.02];
            inside += t.float(TexValue::Texture(0), &at(Vec3::ZERO, uv));
        }
        let frac = inside / (n * n) as f32;
        assert!((0.12..0.27).contains(&frac), "{frac}");
    }

    /// The smallest and largest channel of a marble over 2000 points.
    fn marble_range(v3_segments: bool, fixes: Fixes) -> (f32, f32) {
        let o = Octaves { octaves: 8, omega: 0.5 };
        let kind = TextureKind::Marble { map: Mat4::IDENTITY, octaves: o, scale: 3.0, variation: 0.6, v3_segments };
        let t = Textures::new(&[TextureDesc { name: "m".into(), kind }], fixes);
        (0..2000).fold((f32::MAX, f32::MIN), |(lo, hi), i| {
            let p = Vec3::new(i as f32 * 0.013, (i as f32 * 0.37).sin(), 0.2);
            let v = t.eval(TexValue::Texture(0), &at(p, [0.0; 2]));
            (lo.min(v.min_element()), hi.max(v.max_element()))
        })
    }

    #[test]
    fn marble_stays_within_its_palette_in_v4_and_with_the_fix() {
        for (v3, fixes) in [(false, Fixes::NONE), (true, Fixes::NONE.with(Fix::MarblePalette))] {
            let (lo, hi) = marble_range(v3, fixes);
            assert!(lo >= 0.29 && hi <= 0.91, "v3 spline {v3}: {lo}..{hi}");
        }
    }

    #[test]
    fn pbrt_v3s_marble_leaves_its_palette() {
        let (lo, hi) = marble_range(true, Fixes::NONE);
        assert!(hi > 2.0, "{lo}..{hi}");
    }

    #[test]
    fn direction_mix_weighs_by_the_normal() {
        let t = Textures(vec![TextureKind::DirectionMix { tex1: c(1.0), tex2: c(0.0), dir: Vec3::Z }]);
        let v = |n: Vec3| t.float(TexValue::Texture(0), &TexCtx { n, ..TexCtx::default() });
        assert_eq!(v(Vec3::Z), 1.0);
        assert_eq!(v(-Vec3::Z), 1.0);
        assert!((v(Vec3::new(0.6, 0.0, 0.8)) - 0.8).abs() < 1e-6);
    }
}
