//! Texture evaluation at a hit (the statements are read by `scene::textures`).
//!
//! `imagemap` lookups are bilinear with t = 0 at the image's bottom row (as pbrt),
//! `wrap` repeat/clamp/black, `scale`, `invert`. Float textures are stored as grey RGB.
//! Textures are point-sampled: SPPM's many samples per pixel do the filtering that
//! pbrt's ray differentials do for the first hit.

use super::noise::{fbm, noise2, turbulence};
use crate::fixes::{Fix, Fixes};

use super::params::TexValue;
use crate::imageio::lookup;
use crate::scene::textures::{Mapping2D, TextureDesc, TextureKind};
use crate::spectrum::Rgb;
use glam::{Mat4, Vec3};
use std::f32::consts::PI;

/// Where a texture is looked up: the world-space point, the geometric normal, (u, v),
/// and the point's change across a pixel (zero without ray differentials).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexCtx {
    pub p: Vec3,
    pub n: Vec3,
    pub uv: [f32; 2],
    pub dpdx: Vec3,
    pub dpdy: Vec3,
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

    /// Whether some texture reads the footprint (`dpdx`, `dpdy`): the noise textures.
    pub fn use_footprint(&self) -> bool {
        use TextureKind as K;
        self.0.iter().any(|t| matches!(t, K::Fbm { .. } | K::Wrinkled { .. } | K::Windy { .. } | K::Marble { .. }))
    }

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

    fn eval_kind(&self, k: &TextureKind, ctx: &TexCtx) -> Rgb {
        let get = |v: TexValue| self.eval(v, ctx);
        match k {
            TextureKind::Constant(v) => get(*v),
            TextureKind::Checkerboard { tex1, tex2, map } => {
                let [s, t] = map_2d(map, ctx);
                get(if (s.floor() as i64 + t.floor() as i64) % 2 == 0 { *tex1 } else { *tex2 })
            }
            TextureKind::Checkerboard3D { tex1, tex2, map } => {
                let p = map.transform_point3(ctx.p).floor();
                get(if (p.x as i64 + p.y as i64 + p.z as i64) % 2 == 0 { *tex1 } else { *tex2 })
            }
            TextureKind::Scale { tex, scale } => get(*tex) * get(*scale),
            TextureKind::Mix { tex1, tex2, amount } => {
                let t = get(*amount);
                get(*tex1) * (Vec3::ONE - t) + get(*tex2) * t
            }
            TextureKind::DirectionMix { tex1, tex2, dir } => {
                let a = ctx.n.dot(*dir).abs();
                a * get(*tex1) + (1.0 - a) * get(*tex2)
            }
            TextureKind::Bilerp { v, map } => {
                let [s, t] = map_2d(map, ctx);
                (1.0 - s) * (1.0 - t) * v[0] + s * (1.0 - t) * v[1] + (1.0 - s) * t * v[2] + s * t * v[3]
            }
            TextureKind::Image { image, map, wrap, scale, invert } => {
                let [s, t] = map_2d(map, ctx);
                let v = lookup(image, s, t, *wrap, false) * *scale;
                if *invert { (Vec3::ONE - v).max(Vec3::ZERO) } else { v }
            }
            TextureKind::Dots { dot, background, map } => {
                get(if inside_dot(map_2d(map, ctx)) { *dot } else { *background })
            }
            TextureKind::Fbm { map, octaves: o } => {
                let (p, dx, dy) = map_3d(map, ctx);
                Vec3::splat(fbm(p, dx, dy, o.omega, o.octaves))
            }
            TextureKind::Wrinkled { map, octaves: o } => {
                let (p, dx, dy) = map_3d(map, ctx);
                Vec3::splat(turbulence(p, dx, dy, o.omega, o.octaves))
            }
            TextureKind::Windy { map } => {
                let (p, dx, dy) = map_3d(map, ctx);
                Vec3::splat(fbm(0.1 * p, 0.1 * dx, 0.1 * dy, 0.5, 3).abs() * fbm(p, dx, dy, 0.5, 6))
            }
            TextureKind::Marble { map, octaves: o, scale, variation, v3_segments } => {
                let (p, dx, dy) = map_3d(map, ctx);
                let m = p.y * *scale + *variation * fbm(p * *scale, dx * *scale, dy * *scale, o.omega, o.octaves);
                marble(0.5 + 0.5 * m.sin(), *v3_segments)
            }
            TextureKind::Uv { map } => {
                let [s, t] = map_2d(map, ctx);
                Vec3::new(s - s.floor(), t - t.floor(), 0.0)
            }
        }
    }
}

/// The point and its footprint in texture space.
fn map_3d(m: &Mat4, ctx: &TexCtx) -> (Vec3, Vec3, Vec3) {
    (m.transform_point3(ctx.p), m.transform_vector3(ctx.dpdx), m.transform_vector3(ctx.dpdy))
}

/// (s, t) at a hit.
fn map_2d(m: &Mapping2D, ctx: &TexCtx) -> [f32; 2] {
    let tex = |m: &Mat4| m.transform_point3(ctx.p);
    match m {
        Mapping2D::Uv(m) => [ctx.uv[0] * m.su + m.du, ctx.uv[1] * m.sv + m.dv],
        Mapping2D::Spherical { texture_from_world } => {
            let v = tex(texture_from_world).normalize_or_zero();
            let theta = v.z.clamp(-1.0, 1.0).acos();
            let phi = v.y.atan2(v.x);
            let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
            [theta / PI, phi / (2.0 * PI)]
        }
        Mapping2D::Cylindrical { texture_from_world } => {
            let p = tex(texture_from_world);
            [(PI + p.y.atan2(p.x)) / (2.0 * PI), p.z]
        }
        Mapping2D::Planar { texture_from_world, vs, vt, ds, dt } => {
            let p = tex(texture_from_world);
            [ds + p.dot(*vs), dt + p.dot(*vt)]
        }
    }
}

/// pbrt's polka dots: one dot of radius .35 in half the unit cells, jittered by noise.
fn inside_dot([s, t]: [f32; 2]) -> bool {
    let (sc, tc) = ((s + 0.5).floor(), (t + 0.5).floor());
    if noise2(sc + 0.5, tc + 0.5) <= 0.0 {
        return false;
    }
    const RADIUS: f32 = 0.35;
    let shift = 0.5 - RADIUS;
    let centre = (sc + shift * noise2(sc + 1.5, tc + 2.8), tc + shift * noise2(sc + 4.5, tc + 9.8));
    let (ds, dt) = (s - centre.0, t - centre.1);
    ds * ds + dt * dt < RADIUS * RADIUS
}

/// pbrt's marble colour at `t` = ½ + ½ sin(y + variation · fBm): a cubic Bézier colour
/// spline of six segments.
// DEVIATION(pbrt): appearance, `--fix marble-palette`. pbrt-v3 picks the segment with
// `min(1, ⌊6t⌋)` (`v3_segments`), which evaluates the Bézier far outside [0, 1]
// (colours beyond 10, or negative); the fix, and pbrt-v4, use `min(⌊6t⌋, 5)`.
fn marble(t: f32, v3_segments: bool) -> Rgb {
    const C: [[f32; 3]; 9] = [
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.5, 0.5, 0.5],
        [0.6, 0.59, 0.58],
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.2, 0.2, 0.33],
        [0.58, 0.58, 0.6],
    ];
    let segments = C.len() - 3;
    let last = if v3_segments { 1 } else { segments - 1 };
    let first = ((t * segments as f32).floor().max(0.0) as usize).min(last);
    let t = t * segments as f32 - first as f32;
    let c: Vec<Vec3> = C[first..first + 4].iter().map(|c| Vec3::from(*c)).collect();
    let l = |a: Vec3, b: Vec3| (1.0 - t) * a + t * b;
    let (s0, s1, s2) = (l(c[0], c[1]), l(c[1], c[2]), l(c[2], c[3]));
    let (s0, s1) = (l(s0, s1), l(s1, s2));
    1.5 * l(s0, s1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::textures::{Octaves, UvMapping};

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
