//! How 2D textures find (s, t) at a hit (`"string mapping"`), and how 3D textures take
//! the hit to texture space.
//!
//! ```text
//! Texture "t" "spectrum" "checkerboard" "string mapping" "uv" "float uscale" 8 "float vdelta" .5
//! Texture "t" "spectrum" "checkerboard" "string mapping" "planar" "vector v1" [1 0 0] "vector v2" [0 0 1]
//! Texture "t" "spectrum" "imagemap" "string mapping" "spherical"       # also "cylindrical"
//! ```
//! `spherical`, `cylindrical` and `planar` work in the space the CTM at the `Texture`
//! statement defines. 3D textures take the hit point to texture space as each version
//! does: pbrt-v4 by the inverse of the CTM, pbrt-v3 by the CTM itself (it hands the
//! texture-to-world transform to a mapping that expects world-to-texture; v3 files were
//! made to look right under that rule). v3's `planar` takes world-space points.

use super::TexCtx;
use crate::parser::Syntax;
use crate::parser::params::{ParamList, ParamType};
use crate::values::{self, Range, Res, Resolver};
use glam::{DMat4, Mat4, Vec3};
use std::f32::consts::PI;

/// (s, t) = (su·u + du, sv·v + dv).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMapping {
    pub su: f32,
    pub sv: f32,
    pub du: f32,
    pub dv: f32,
}

/// How a 2D texture finds (s, t) at a hit. `texture_from_world` takes world-space
/// points to texture space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mapping2D {
    Uv(UvMapping),
    /// s = θ/π, t = φ/2π of the direction from the texture-space origin.
    Spherical {
        texture_from_world: Mat4,
    },
    /// s = (π + atan2(y, x))/2π, t = z.
    Cylindrical {
        texture_from_world: Mat4,
    },
    /// s = ds + p·vs, t = dt + p·vt.
    Planar {
        texture_from_world: Mat4,
        vs: Vec3,
        vt: Vec3,
        ds: f32,
        dt: f32,
    },
}

/// Where a `Texture` statement stands: its CTM and the file's syntax version.
#[derive(Clone, Copy, Debug)]
pub struct TextureSite {
    pub world_from_texture: DMat4,
    pub syntax: Syntax,
}

impl TextureSite {
    /// World to texture space for 3D textures (see the module notes on v3).
    pub fn map3d(&self) -> Mat4 {
        match self.syntax {
            Syntax::V3 => self.world_from_texture.as_mat4(),
            Syntax::V4 => self.world_from_texture.inverse().as_mat4(),
        }
    }
}

/// `"string mapping"` and its parameters. An unknown mapping is (u, v) unscaled, with a
/// warning: both pbrts report it and render so.
pub fn read(p: &ParamList, site: &TextureSite, r: &mut dyn Resolver) -> Res<Mapping2D> {
    let kind = p.string("mapping")?.unwrap_or_else(|| "uv".into());
    if !["uv", "spherical", "cylindrical", "planar"].contains(&kind.as_str()) {
        let at = values::span_of(p, "mapping").unwrap_or_default();
        r.warn(at, format!("unknown texture mapping \"{kind}\"; (u, v) unscaled, as pbrt maps it"));
        return Ok(Mapping2D::Uv(UvMapping { su: 1.0, sv: 1.0, du: 0.0, dv: 0.0 }));
    }
    let f = |name: &str, d: f32| values::float(p, name, d, Range::Any);
    let texture_from_world = site.world_from_texture.inverse().as_mat4();
    Ok(match kind.as_str() {
        "spherical" => Mapping2D::Spherical { texture_from_world },
        "cylindrical" => Mapping2D::Cylindrical { texture_from_world },
        "planar" => {
            let v = |name: &str, d: Vec3| -> Res<Vec3> {
                Ok(p.fixed::<3>(name, &[ParamType::Vector3])?.map_or(d, Vec3::from))
            };
            Mapping2D::Planar {
                // pbrt-v3 maps world-space points (see the module notes).
                texture_from_world: if site.syntax == Syntax::V3 { Mat4::IDENTITY } else { texture_from_world },
                vs: v("v1", Vec3::X)?,
                vt: v("v2", Vec3::Y)?,
                ds: f("udelta", 0.0)?,
                dt: f("vdelta", 0.0)?,
            }
        }
        _ => Mapping2D::Uv(UvMapping {
            su: f("uscale", 1.0)?,
            sv: f("vscale", 1.0)?,
            du: f("udelta", 0.0)?,
            dv: f("vdelta", 0.0)?,
        }),
    })
}

/// The point and its footprint in texture space.
pub fn map_3d(m: &Mat4, ctx: &TexCtx) -> (Vec3, Vec3, Vec3) {
    (m.transform_point3(ctx.p), m.transform_vector3(ctx.dpdx), m.transform_vector3(ctx.dpdy))
}

/// (s, t) at a hit.
pub fn map_2d(m: &Mapping2D, ctx: &TexCtx) -> [f32; 2] {
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
