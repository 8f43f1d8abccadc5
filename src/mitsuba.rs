//! The scene as `pbrt-sppm export --mitsuba` writes it for Mitsuba 3: plain data that
//! `tools/mitsuba_reference.py` reads. Each light type writes its own entry (its module's
//! `mitsuba`); `cli::export` assembles the whole.

use crate::values::TexValue;
use serde::Serialize;

/// A light, in world space (area lights go with their shapes).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum LightOut {
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        up: [f32; 3],
        intensity: [f32; 3],
        cutoff_angle: f32,
        beam_width: f32,
    },
    /// `direction` is the way the light travels.
    Distant {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
    Constant {
        radiance: [f32; 3],
    },
    /// An equirectangular map (absolute path); `to_world` maps Mitsuba's map axes to
    /// the world.
    EnvMap {
        filename: String,
        to_world: [f64; 16],
        scale: f32,
    },
}

/// What an export could not carry over alike, where in the scene, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Unsupported {
    #[serde(rename = "where")]
    pub location: String,
    pub what: String,
    pub why: String,
}

impl Unsupported {
    pub fn new(location: &str, what: &str, why: impl Into<String>) -> Unsupported {
        Unsupported { location: location.to_string(), what: what.to_string(), why: why.into() }
    }
}

/// A material (pbrt's types map to the nearest Mitsuba BSDF; what does not is noted).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum MaterialOut {
    Diffuse {
        reflectance: [f32; 3],
    },
    /// A perfect mirror scaled by `reflectance`.
    Mirror {
        reflectance: [f32; 3],
    },
    Dielectric {
        eta: f32,
        reflectance: [f32; 3],
        transmittance: [f32; 3],
    },
    /// A pane that reflects or passes light straight on (Mitsuba's `thindielectric`).
    ThinDielectric {
        eta: f32,
    },
    Conductor {
        eta: [f32; 3],
        k: [f32; 3],
    },
    /// GGX, α along the shading tangents.
    RoughConductor {
        eta: [f32; 3],
        k: [f32; 3],
        alpha: [f32; 2],
    },
    /// No surface: rays pass straight through.
    None,
}

/// What a material's export needs from the exporter: its inputs as constants (a
/// texture's mean, noted), and a place to note what does not go over alike.
pub trait MaterialExport {
    fn rgb(&mut self, t: TexValue) -> [f32; 3];
    fn note(&mut self, why: &str);

    /// A material exported as its diffuse part (noted).
    fn diffuse_part(&mut self, reflectance: TexValue) -> MaterialOut {
        self.note("no Mitsuba equivalent is exported yet; exported as its diffuse part");
        MaterialOut::Diffuse { reflectance: self.rgb(reflectance) }
    }
}

/// A shape's geometry.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum GeometryOut {
    Sphere {
        center: [f64; 3],
        radius: f64,
        flip_normals: bool,
    },
    Cylinder {
        to_world: [f64; 16],
        flip_normals: bool,
    },
    Disk {
        to_world: [f64; 16],
        flip_normals: bool,
    },
    /// `face_normals`: shade with the flat triangle normal (pbrt meshes without `N`);
    /// false for tessellated quadrics, whose smooth normals the reader interpolates.
    Mesh {
        positions: Vec<f32>,
        normals: Option<Vec<f32>>,
        indices: Vec<u32>,
        face_normals: bool,
    },
}
