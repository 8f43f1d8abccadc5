//! Materials and textures (RGB) and the BSDFs they produce at a hit.
//!
//! ```text
//! Material "matte" "rgb Kd" [.5 .5 .5]        Material "diffuse" "texture reflectance" "checks"
//! Material "glass" "float index" 1.5          Material "metal" "spectrum eta" "metal-Au-eta"
//! Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "rgb tex1" [1 0 0]
//! ```
//! Every parameter is settled by the scene description (`scene::materials`); this module
//! turns typed materials into BSDFs. Textures live in one array and refer to each other
//! by index, so shared definitions are stored once. `imagemap` lookups are bilinear with
//! t = 0 at the image's bottom row (as pbrt), `wrap` repeat/clamp/black, `scale`,
//! `invert`.

mod bsdf;
pub mod lobes;
pub mod microfacet;

pub use bsdf::{Bsdf, BsdfSample, TransportMode};
use lobes::{Lobe, MAX_LOBES, oren_nayar_ab};
use microfacet::{Fresnel, TrowbridgeReitz};

use crate::imageio::RgbImage;
use crate::scene::{MaterialDesc, MaterialKind, RoughnessRemap, TexValue, TextureDesc, TextureKind, UvMapping, Wrap};
use crate::spectrum::Rgb;
use glam::Vec3;
use std::sync::Arc;

/// Bilinear lookup at (s, t) with t = 0 at the bottom row unless `top_down`.
pub fn lookup(img: &RgbImage, s: f32, t: f32, wrap: Wrap, top_down: bool) -> Rgb {
    let (w, h) = (img.width as i64, img.height as i64);
    if w == 0 || h == 0 {
        return Vec3::ZERO;
    }
    let y = if top_down { t } else { 1.0 - t };
    let (x, y) = (s * w as f32 - 0.5, y * h as f32 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |xi: i64, yi: i64| -> Rgb {
        let (xi, yi) = match wrap {
            Wrap::Repeat => (xi.rem_euclid(w), yi.rem_euclid(h)),
            Wrap::Clamp => (xi.clamp(0, w - 1), yi.clamp(0, h - 1)),
            Wrap::Black if xi < 0 || yi < 0 || xi >= w || yi >= h => return Vec3::ZERO,
            Wrap::Black => (xi, yi),
        };
        Vec3::from(img.pixels[(yi * w + xi) as usize])
    };
    let (x0, y0) = (x0 as i64, y0 as i64);
    (1.0 - fx) * (1.0 - fy) * texel(x0, y0)
        + fx * (1.0 - fy) * texel(x0 + 1, y0)
        + (1.0 - fx) * fy * texel(x0, y0 + 1)
        + fx * fy * texel(x0 + 1, y0 + 1)
}

/// An RGB texture over (u, v); inputs refer to other textures by index.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Const(Rgb),
    Checker { tex1: TexValue, tex2: TexValue, map: UvMapping },
    Scale(TexValue, TexValue),
    Mix(TexValue, TexValue, TexValue),
    Image { img: Arc<RgbImage>, map: UvMapping, wrap: Wrap, scale: f32, invert: bool },
}

/// Every texture of a scene, by the indices [`TexValue::Texture`] names.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Textures(pub Vec<Texture>);

impl Textures {
    pub fn new(descs: &[TextureDesc]) -> Textures {
        Textures(descs.iter().map(|t| Texture::from_kind(&t.kind)).collect())
    }

    pub fn eval(&self, v: TexValue, uv: [f32; 2]) -> Rgb {
        match v {
            TexValue::Const(c) => c,
            TexValue::Texture(t) => self.0.get(t as usize).map_or(Vec3::ZERO, |t| t.eval(self, uv)),
        }
    }
}

impl Texture {
    fn from_kind(k: &TextureKind) -> Texture {
        match k {
            TextureKind::Constant(TexValue::Const(c)) => Texture::Const(*c),
            TextureKind::Constant(v) => Texture::Scale(*v, TexValue::Const(Vec3::ONE)),
            TextureKind::Checkerboard { tex1, tex2, map } => Texture::Checker { tex1: *tex1, tex2: *tex2, map: *map },
            TextureKind::Scale { tex, scale } => Texture::Scale(*tex, *scale),
            TextureKind::Mix { tex1, tex2, amount } => Texture::Mix(*tex1, *tex2, *amount),
            TextureKind::Image { image, map, wrap, scale, invert } => {
                Texture::Image { img: image.clone(), map: *map, wrap: *wrap, scale: *scale, invert: *invert }
            }
        }
    }

    pub fn eval(&self, all: &Textures, uv: [f32; 2]) -> Rgb {
        let st = |m: &UvMapping| (uv[0] * m.su + m.du, uv[1] * m.sv + m.dv);
        match self {
            Texture::Const(c) => *c,
            Texture::Checker { tex1, tex2, map } => {
                let (s, t) = st(map);
                if (s.floor() as i64 + t.floor() as i64) % 2 == 0 { all.eval(*tex1, uv) } else { all.eval(*tex2, uv) }
            }
            Texture::Scale(a, b) => all.eval(*a, uv) * all.eval(*b, uv),
            Texture::Mix(a, b, t) => {
                let t = all.eval(*t, uv);
                all.eval(*a, uv) * (Vec3::ONE - t) + all.eval(*b, uv) * t
            }
            Texture::Image { img, map, wrap, scale, invert } => {
                let (s, t) = st(map);
                let v = lookup(img, s, t, *wrap, false) * *scale;
                if *invert { (Vec3::ONE - v).max(Vec3::ZERO) } else { v }
            }
        }
    }
}

/// A material ready to shade: the scene's description, its inputs evaluated at each hit.
#[derive(Clone, Debug, PartialEq)]
pub struct Material(MaterialKind);

/// Clamps to [0, 1] as pbrt's `Spectrum::Clamp()` does for reflectances.
fn unit(c: Rgb) -> Rgb {
    c.clamp(Vec3::ZERO, Vec3::ONE)
}

impl Material {
    pub fn from_desc(m: &MaterialDesc) -> Material {
        Material(m.kind.clone())
    }

    pub fn kind(&self) -> &MaterialKind {
        &self.0
    }

    /// The BSDF at a hit (`None` for interfaces).
    pub fn bsdf(&self, textures: &Textures, uv: [f32; 2], frame: [Vec3; 3], ng: Vec3) -> Option<Bsdf> {
        if let MaterialKind::Diffuse { reflectance } = &self.0 {
            // The common case, without the lobe list's set-up.
            let lambert = lambert(unit(textures.eval(*reflectance, uv)));
            return Some(Bsdf::new(frame, ng, lambert.as_slice()));
        }
        let mut lobes = Lobes::default();
        self.lobes(&Inputs { textures, uv }, &mut lobes)?;
        Some(Bsdf::new(frame, ng, &lobes.list[..lobes.n]))
    }

    fn lobes(&self, i: &Inputs, out: &mut Lobes) -> Option<()> {
        match &self.0 {
            MaterialKind::Diffuse { reflectance } => {
                lambert(unit(i.rgb(*reflectance))).into_iter().for_each(|l| out.push(l))
            }
            MaterialKind::OrenNayar { reflectance, sigma } => {
                let r = unit(i.rgb(*reflectance));
                match oren_nayar_ab(i.float(*sigma)) {
                    (_, 0.0) => out.push_nonzero(r, Lobe::Lambert),
                    (a, b) => out.push_nonzero(r, |r| Lobe::OrenNayar { r, a, b }),
                }
            }
            MaterialKind::Mirror { reflectance } => {
                out.push(Lobe::SpecularReflection { r: i.rgb(*reflectance), fresnel: Fresnel::One })
            }
            MaterialKind::Dielectric { eta, kr, kt, roughness, remap } => {
                // Smooth when the roughness as written is 0 (pbrt-v3: v3's remapping
                // takes 0 to α ≈ 0.047) or α is below 10⁻³ (pbrt-v4's test).
                let raw = roughness.map(|r| i.float(r));
                let alpha = if raw == [0.0; 2] { raw } else { raw.map(|r| remap.alpha(r)) };
                let alpha = if alpha.iter().all(|a| *a < 1e-3) { [0.0; 2] } else { alpha };
                dielectric(i.float(*eta), unit(i.rgb(*kr)), unit(i.rgb(*kt)), alpha, out)
            }
            MaterialKind::Conductor { eta, k, roughness, remap } => {
                let fresnel = Fresnel::Conductor { eta: *eta, k: *k };
                let alpha = i.alpha(roughness, *remap);
                if alpha[0] < 1e-3 && alpha[1] < 1e-3 {
                    out.push(Lobe::SpecularReflection { r: Vec3::ONE, fresnel });
                } else {
                    out.push(Lobe::MicrofacetReflection { r: Vec3::ONE, dist: TrowbridgeReitz::new(alpha), fresnel });
                }
            }
            MaterialKind::Plastic { kd, ks, roughness, remap } => {
                out.push_nonzero(unit(i.rgb(*kd)), Lobe::Lambert);
                let a = remap.alpha(i.float(*roughness));
                let (dist, fresnel) = (TrowbridgeReitz::new([a, a]), Fresnel::Coat { eta: 1.5 });
                out.push_nonzero(unit(i.rgb(*ks)), |r| Lobe::MicrofacetReflection { r, dist, fresnel });
            }
            MaterialKind::Uber { kd, ks, kr, kt, roughness, eta, opacity, remap } => {
                // pbrt-v3: a pass-through of 1 − opacity, then each layer scaled by it.
                let op = unit(i.rgb(*opacity));
                out.push_nonzero(unit(Vec3::ONE - op), |t| Lobe::SpecularTransmission { t, eta: 1.0 });
                let eta = i.float(*eta);
                out.push_nonzero(op * unit(i.rgb(*kd)), Lobe::Lambert);
                let (dist, fresnel) = (TrowbridgeReitz::new(i.alpha(roughness, *remap)), Fresnel::Dielectric { eta });
                out.push_nonzero(op * unit(i.rgb(*ks)), |r| Lobe::MicrofacetReflection { r, dist, fresnel });
                out.push_nonzero(op * unit(i.rgb(*kr)), |r| Lobe::SpecularReflection { r, fresnel });
                out.push_nonzero(op * unit(i.rgb(*kt)), |t| Lobe::SpecularTransmission { t, eta });
            }
            MaterialKind::Translucent { kd, ks, reflect, transmit, roughness, remap } => {
                let (r, t) = (unit(i.rgb(*reflect)), unit(i.rgb(*transmit)));
                let (kd, ks) = (unit(i.rgb(*kd)), unit(i.rgb(*ks)));
                out.push_nonzero(r * kd, Lobe::Lambert);
                out.push_nonzero(t * kd, Lobe::LambertTransmission);
                let a = remap.alpha(i.float(*roughness));
                let (dist, eta) = (TrowbridgeReitz::new([a, a]), 1.5);
                let fresnel = Fresnel::Dielectric { eta };
                out.push_nonzero(r * ks, |r| Lobe::MicrofacetReflection { r, dist, fresnel });
                out.push_nonzero(t * ks, |t| Lobe::MicrofacetTransmission { t, dist, eta });
            }
            MaterialKind::Substrate { kd, ks, roughness, remap } => {
                let (rd, rs) = (unit(i.rgb(*kd)), unit(i.rgb(*ks)));
                if rd != Vec3::ZERO || rs != Vec3::ZERO {
                    let dist = TrowbridgeReitz::new(i.alpha(roughness, *remap));
                    out.push(Lobe::FresnelBlend { rd, rs, dist });
                }
            }
            MaterialKind::Interface => return None,
        }
        Some(())
    }
}

/// A Lambertian lobe, or none for a black reflectance (pbrt adds no lobe then).
fn lambert(r: Rgb) -> Option<Lobe> {
    (r != Vec3::ZERO).then_some(Lobe::Lambert(r))
}

/// Smooth glass is one Fresnel-weighted lobe; rough glass is pbrt-v3's pair of
/// microfacet reflection and transmission lobes.
fn dielectric(eta: f32, r: Rgb, t: Rgb, alpha: [f32; 2], out: &mut Lobes) {
    if r == Vec3::ZERO && t == Vec3::ZERO {
        return;
    }
    if alpha == [0.0, 0.0] {
        out.push(Lobe::FresnelSpecular { r, t, eta });
        return;
    }
    let dist = TrowbridgeReitz::new(alpha);
    out.push_nonzero(r, |r| Lobe::MicrofacetReflection { r, dist, fresnel: Fresnel::Dielectric { eta } });
    out.push_nonzero(t, |t| Lobe::MicrofacetTransmission { t, dist, eta });
}

/// Texture inputs at one hit.
struct Inputs<'a> {
    textures: &'a Textures,
    uv: [f32; 2],
}

impl Inputs<'_> {
    fn rgb(&self, v: TexValue) -> Rgb {
        self.textures.eval(v, self.uv)
    }

    fn float(&self, v: TexValue) -> f32 {
        self.rgb(v).x
    }

    fn alpha(&self, roughness: &[TexValue; 2], remap: RoughnessRemap) -> [f32; 2] {
        roughness.map(|r| remap.alpha(self.float(r)))
    }
}

impl RoughnessRemap {
    /// The microfacet α of a roughness as written.
    pub fn alpha(self, r: f32) -> f32 {
        match self {
            RoughnessRemap::None => r.max(0.0),
            RoughnessRemap::V3 => microfacet::roughness_to_alpha_v3(r),
            RoughnessRemap::V4 => r.max(0.0).sqrt(),
        }
    }
}

/// The lobes one hit's material makes.
#[derive(Default)]
struct Lobes {
    list: [Lobe; MAX_LOBES],
    n: usize,
}

impl Default for Lobe {
    fn default() -> Lobe {
        Lobe::Lambert(Vec3::ZERO)
    }
}

impl Lobes {
    fn push(&mut self, l: Lobe) {
        if self.n < MAX_LOBES {
            self.list[self.n] = l;
            self.n += 1;
        }
    }

    /// Adds `make(c)` unless `c` is black (pbrt adds no lobe for a black input).
    fn push_nonzero(&mut self, c: Rgb, make: impl FnOnce(Rgb) -> Lobe) {
        if c != Vec3::ZERO {
            self.push(make(c));
        }
    }
}
