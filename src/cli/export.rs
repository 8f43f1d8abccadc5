//! `pbrt-sppm export --mitsuba SCENE.pbrt`: the loaded scene as one flat JSON document
//! that `tools/mitsuba_reference.py` turns into a Mitsuba 3 scene.
//!
//! Everything is resolved before it is written, so the other side needs no pbrt
//! knowledge: transforms are applied, v3/v4 spectrum and `power` rules are evaluated to
//! RGB, named materials and textures are looked up. Instanced objects go out once, in
//! their own space, with one `to_world` per instance (Mitsuba's shape groups), so a
//! scene of 25,000 instances stays small. What goes out is what pbrt-sppm renders:
//!
//! ```text
//! { "format": "pbrt-sppm-export", "version": 1, "source": "scene.pbrt",
//!   "camera": { "kind": "perspective", "world_from_camera": [16, row-major], "fov": 40,
//!               "lens_radius": 0, "focal_distance": 1e6, "check_rays": [...] },
//!   "film": { "width": 64, "height": 48, "crop": [x0, x1, y0, y1], "scale": 1 },
//!   "max_depth": 5,
//!   "materials": [ { "type": "diffuse", "reflectance": [r, g, b] }, ... ],
//!   "shapes": [ { "type": "sphere", "center": [...], "radius": 1, "flip_normals": false,
//!                 "material": 0, "emission": { "radiance": [...], "two_sided": false } },
//!               { "type": "mesh", "positions": [...], "normals": null, "indices": [...], ... } ],
//!   "objects": [ { "name": "tree", "shapes": [ ...as above, without emission... ] } ],
//!   "instances": [ { "object": 0, "to_world": [16, row-major], "first_shape_index": 7 } ],
//!   "lights": [ { "type": "point", "position": [...], "intensity": [...] },
//!               { "type": "env_map", "filename": "/abs/sky.exr", "to_world": [16], "scale": 1 }, ... ],
//!   "unsupported": [ { "where": "file:line:col", "what": "...", "why": "..." } ] }
//! ```
//! Camera space is pbrt's (left-handed: +x right, +y up, +z forward). Cylinders and
//! disks carry `to_world` for Mitsuba's canonical shapes (unit radius, z ∈ [0, 1] /
//! z = 0). Partial or non-similar quadrics, cones, paraboloids and hyperboloids become
//! meshes whose winding puts the front face (Mitsuba's emitting side) where our normal
//! points. Both renderers map an instance's normals with the inverse transpose and no
//! handedness flip, so object shapes need no correction for mirrored instances. `check_rays` are camera rays at film positions relative to the crop window,
//! so the reader can verify its camera reproduces ours.

use crate::camera::Camera;
use crate::materials::{TexCtx, Textures};
use crate::math::transform::row_major;
use crate::scene::{CameraKind, Geometry, MaterialDesc, PlacedShape, SceneDescription, ShapeDesc, TexValue};
use crate::shapes::{Quadric, TriangleMesh};
use crate::spectrum::Rgb;
use glam::{DMat4, DVec3, Vec3};
use serde::Serialize;

#[derive(Serialize)]
pub struct Export {
    pub format: &'static str,
    pub version: u32,
    pub source: String,
    pub camera: CameraOut,
    pub film: FilmOut,
    /// pbrt's `maxdepth`: the most bounces a path may take.
    pub max_depth: u32,
    pub materials: Vec<MaterialOut>,
    /// World shapes, in world space.
    pub shapes: Vec<ShapeOut>,
    /// Instanced objects, their shapes in object space (`shape_index` counts within the
    /// object).
    pub objects: Vec<ObjectOut>,
    pub instances: Vec<InstanceOut>,
    pub lights: Vec<LightOut>,
    pub unsupported: Vec<Unsupported>,
}

#[derive(Serialize)]
pub struct CameraOut {
    pub kind: &'static str,
    pub world_from_camera: [f64; 16],
    /// Full angle of the shorter image axis, degrees.
    pub fov: f32,
    pub lens_radius: f32,
    pub focal_distance: f32,
    pub check_rays: Vec<CheckRay>,
}

/// A camera ray through `film_uv` (relative to the crop window, y down) and the lens
/// centre.
#[derive(Serialize)]
pub struct CheckRay {
    pub film_uv: [f32; 2],
    pub o: [f32; 3],
    pub d: [f32; 3],
}

#[derive(Serialize)]
pub struct FilmOut {
    pub width: u32,
    pub height: u32,
    /// Pixel bounds [x0, x1, y0, y1], half open.
    pub crop: [u32; 4],
    pub scale: f32,
}

#[derive(Serialize)]
pub struct Emission {
    pub radiance: [f32; 3],
    pub two_sided: bool,
}

#[derive(Serialize)]
pub struct ShapeOut {
    #[serde(flatten)]
    pub geometry: GeometryOut,
    pub material: u32,
    pub emission: Option<Emission>,
    /// `check --shapes` index of the shape this came from.
    pub shape_index: u32,
}

#[derive(Serialize)]
pub struct ObjectOut {
    pub name: String,
    pub shapes: Vec<ShapeOut>,
}

#[derive(Serialize)]
pub struct InstanceOut {
    pub object: u32,
    pub to_world: [f64; 16],
    /// `check --shapes` index of the instance's first shape.
    pub first_shape_index: u32,
}

use crate::mitsuba::MaterialExport;
pub use crate::mitsuba::{GeometryOut, LightOut, MaterialOut, Unsupported};

/// Quadric tessellation: cells around the full φ range and along v.
const PHI_CELLS: u32 = 96;
const V_CELLS: u32 = 48;

/// The scene as it goes to Mitsuba, with everything that cannot go noted.
pub fn mitsuba(scene: &SceneDescription, source: &str) -> Export {
    let mut notes: Vec<Unsupported> = scene
        .skipped
        .iter()
        .map(|s| Unsupported {
            location: format!("{}:{}:{}", s.file, s.line, s.column),
            what: s.what.clone(),
            why: format!("skipped on load: {}", s.why),
        })
        .collect();
    notes.extend(scene.approximated.iter().map(|a| Unsupported {
        location: format!("{}:{}:{}", a.file, a.line, a.column),
        what: a.what.clone(),
        why: format!("approximated by pbrt-sppm too: {}", a.how),
    }));
    notes.extend(scene.media.iter().map(|m| Unsupported {
        location: source.to_string(),
        what: format!("MakeNamedMedium \"{}\"", m.name),
        why: "media are not exported: Mitsuba renders the scene in vacuum".into(),
    }));
    if scene.film.white_balance.is_some() {
        let why = "white balance is not exported: Mitsuba's image keeps the colours as rendered";
        notes.push(note(source, "Film \"whitebalance\"", why));
    }
    let moving = scene.instances.iter().filter(|i| i.motion().is_some()).count();
    if moving > 0 || scene.camera.camera_from_world_end.is_some() {
        let why = "motion is not exported: moving shapes, instances and the camera stand at their start";
        notes.push(note(source, &format!("ActiveTransform ({moving} moving instances)"), why));
    }
    let textures = Textures::new(&scene.textures, scene.fixes);
    let materials = scene.materials.iter().enumerate().map(|(i, m)| material(m, &textures, i, &mut notes)).collect();
    let shapes = scene.shapes.iter().enumerate().map(|(i, s)| shape(scene, s, true, i as u32, &mut notes)).collect();
    let objects = scene
        .objects
        .iter()
        .map(|o| ObjectOut {
            name: o.name.clone(),
            shapes: o.shapes.iter().enumerate().map(|(i, s)| shape(scene, s, false, i as u32, &mut notes)).collect(),
        })
        .collect();
    let mut first_shape_index = scene.shapes.len() as u32;
    let instances = scene
        .instances
        .iter()
        .map(|i| {
            let out =
                InstanceOut { object: i.object(), to_world: row_major(&i.world_from_instance()), first_shape_index };
            first_shape_index += scene.objects[i.object() as usize].shapes.len() as u32;
            out
        })
        .collect();
    let lights = scene.lights.iter().map(|d| d.mitsuba(&mut notes)).collect();
    Export {
        format: "pbrt-sppm-export",
        version: 1,
        source: source.to_string(),
        camera: camera(scene, &mut notes),
        film: FilmOut {
            width: scene.film.x_resolution,
            height: scene.film.y_resolution,
            crop: scene.film.pixel_bounds,
            scale: scene.film.scale,
        },
        max_depth: scene.integrator.max_depth,
        materials,
        shapes,
        objects,
        instances,
        lights,
        unsupported: notes,
    }
}

fn note(location: &str, what: &str, why: impl Into<String>) -> Unsupported {
    Unsupported::new(location, what, why)
}

fn camera(scene: &SceneDescription, notes: &mut Vec<Unsupported>) -> CameraOut {
    let c = &scene.camera;
    let cam = Camera::new(c, &scene.film);
    let [x0, x1, y0, y1] = scene.film.pixel_bounds.map(|v| v as f32);
    let check_rays = [[0.5, 0.5], [0.1, 0.2], [0.9, 0.3], [0.25, 0.85], [0.0, 0.0], [1.0, 1.0]]
        .into_iter()
        .map(|film_uv: [f32; 2]| {
            let raster = [x0 + film_uv[0] * (x1 - x0), y0 + film_uv[1] * (y1 - y0)];
            let r = cam.generate_ray(raster, [0.5, 0.5]);
            CheckRay { film_uv, o: r.o.0.to_array(), d: r.d.0.to_array() }
        })
        .collect();
    let aspect = scene.film.x_resolution as f32 / scene.film.y_resolution as f32;
    let default_window =
        if aspect > 1.0 { [-aspect, aspect, -1.0, 1.0] } else { [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect] };
    if c.screen_window.iter().zip(default_window).any(|(a, b)| (a - b).abs() > 1e-5 * b.abs().max(1.0)) {
        notes.push(note("", "camera screenwindow", "a non-default screen window has no Mitsuba equivalent"));
    }
    CameraOut {
        kind: match c.kind {
            CameraKind::Orthographic => "orthographic",
            CameraKind::Perspective => "perspective",
            CameraKind::Environment | CameraKind::Spherical(_) => {
                let why = "Mitsuba 3 has no camera that sees every direction; exported as a perspective one";
                notes.push(note("", &format!("camera \"{}\"", c.kind.name()), why));
                "perspective"
            }
            CameraKind::Realistic => {
                let why = "Mitsuba 3 has no lens-system camera; exported as a pinhole perspective one";
                notes.push(note("", "camera \"realistic\"", why));
                "perspective"
            }
        },
        world_from_camera: row_major(&c.camera_from_world.inverse()),
        fov: c.fov,
        lens_radius: c.lens_radius,
        focal_distance: c.focal_distance,
        check_rays,
    }
}

/// A texture as one colour: itself if constant, else its mean over (u, v) (noted).
fn flat(t: TexValue, textures: &Textures, what: &str, notes: &mut Vec<Unsupported>) -> [f32; 3] {
    if let TexValue::Const(c) = t {
        return c.to_array();
    }
    notes.push(note("", what, "textured; exported as its mean over (u, v) ∈ [0, 1]²"));
    const N: u32 = 32;
    let sum: Rgb = (0..N * N)
        .map(|k| {
            let uv = [((k % N) as f32 + 0.5) / N as f32, ((k / N) as f32 + 0.5) / N as f32];
            textures.eval(t, &TexCtx { uv, ..TexCtx::default() })
        })
        .fold(Vec3::ZERO, |a, b| a + b);
    (sum / (N * N) as f32).to_array()
}

/// What a material's export reads and notes: its inputs flattened to constants.
struct Flatten<'a> {
    textures: &'a Textures,
    what: String,
    notes: &'a mut Vec<Unsupported>,
}

impl MaterialExport for Flatten<'_> {
    fn rgb(&mut self, t: TexValue) -> [f32; 3] {
        flat(t, self.textures, &self.what, self.notes)
    }

    fn note(&mut self, why: &str) {
        self.notes.push(note("", &self.what, why));
    }
}

fn material(m: &MaterialDesc, textures: &Textures, index: usize, notes: &mut Vec<Unsupported>) -> MaterialOut {
    let what = format!("material {index} (\"{}\")", m.ty);
    m.mitsuba(&mut Flatten { textures, what, notes })
}

/// One shape in its own space: the world for world shapes, its object's for object
/// shapes (which cannot emit, in pbrt-sppm as in Mitsuba).
fn shape(scene: &SceneDescription, s: &ShapeDesc, world: bool, index: u32, notes: &mut Vec<Unsupported>) -> ShapeOut {
    let emission = s.area_light.filter(|_| world).map(|a| {
        let a = &scene.area_lights[a as usize];
        if a.two_sided {
            notes.push(note("", &format!("shape {index}"), "two-sided area light: Mitsuba's emit on one side"));
        }
        if a.image.is_some() {
            notes.push(note("", &format!("shape {index}"), "image area light: exported as its scale, uniform"));
        }
        let area = scene.placed_area(&PlacedShape { shape: s, object_to_world: s.object_to_world, instance: None });
        Emission { radiance: a.emission(area).to_array(), two_sided: a.two_sided }
    });
    let geometry = match &s.geometry {
        Geometry::Quadric(q) => quadric(q, &s.object_to_world, s.reverse_orientation),
        Geometry::Mesh { mesh, .. } => {
            mesh_out(&scene.meshes[*mesh as usize], s.reverse_orientation, s.swaps_handedness())
        }
        Geometry::Patches { mesh, .. } => {
            let m = &scene.patches[*mesh as usize];
            mesh_out(&m.to_triangles(PATCH_CELLS), s.reverse_orientation, s.swaps_handedness())
        }
        Geometry::Curves { curves } => {
            let what = format!("shape {index} (curve)");
            notes.push(note("", &what, "exported as round tubes of its width (Mitsuba's curves need files)"));
            mesh_out(&curves.tubes(&s.object_to_world), s.reverse_orientation, false)
        }
    };
    ShapeOut { geometry, material: s.material, emission, shape_index: index }
}

/// Cells per side when a curved bilinear patch is exported as triangles.
const PATCH_CELLS: usize = 8;

/// Mitsuba's sphere, cylinder and disk for full shapes under a rotation, uniform scale
/// and translation; a mesh otherwise.
/// A quadric as Mitsuba's own shape where it has one (each quadric's `mitsuba`), else
/// tessellated.
fn quadric(q: &Quadric, m: &DMat4, reverse: bool) -> GeometryOut {
    q.mitsuba(m, reverse).unwrap_or_else(|| tessellate(q, m, reverse))
}

/// A (u, v) grid over the quadric. Our normal is m·∂p/∂u × m·∂p/∂v (negated by
/// ReverseOrientation), so the grid's own winding faces it unless `flip`.
fn tessellate(q: &Quadric, m: &DMat4, flip: bool) -> GeometryOut {
    let nu = ((PHI_CELLS as f64 * q.phi_max() / std::f64::consts::TAU).ceil() as u32).max(4);
    let nv = V_CELLS;
    let mut positions = Vec::with_capacity(((nu + 1) * (nv + 1) * 3) as usize);
    for j in 0..=nv {
        for i in 0..=nu {
            let p = m.transform_point3(q.point(i as f64 / nu as f64, j as f64 / nv as f64));
            positions.extend(p.as_vec3().to_array());
        }
    }
    let at = |i: u32, j: u32| j * (nu + 1) + i;
    let vertex = |k: u32| Vec3::from_slice(&positions[3 * k as usize..3 * k as usize + 3]);
    let mut indices = Vec::with_capacity((nu * nv * 6) as usize);
    for j in 0..nv {
        for i in 0..nu {
            for t in [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]] {
                // Cells at poles and apexes collapse to slivers; leave them out.
                let [a, b, c] = t.map(vertex);
                if (b - a).cross(c - a).length_squared() > 0.0 {
                    indices.extend(if flip { [t[0], t[2], t[1]] } else { t });
                }
            }
        }
    }
    // Drop the vertices only slivers used (Mitsuba warns about normals it cannot make).
    let mut remap = vec![u32::MAX; positions.len() / 3];
    let mut kept = Vec::with_capacity(positions.len());
    for k in indices.iter_mut() {
        if remap[*k as usize] == u32::MAX {
            remap[*k as usize] = (kept.len() / 3) as u32;
            kept.extend_from_slice(&positions[3 * *k as usize..3 * *k as usize + 3]);
        }
        *k = remap[*k as usize];
    }
    GeometryOut::Mesh { positions: kept, normals: None, indices, face_normals: false }
}

/// A mesh as stored (its shape's transform applied). The front face is our normal's
/// side: the winding's, flipped by ReverseOrientation XOR a handedness swap, or with `N`
/// the side `N` is on (`N` is negated by ReverseOrientation, as our shading normal is).
fn mesh_out(m: &TriangleMesh, reverse: bool, swaps: bool) -> GeometryOut {
    let positions = m.p.iter().flatten().copied().collect();
    let sign = if reverse { -1.0 } else { 1.0 };
    let normals =
        m.n.as_ref().map(|ns| ns.iter().flat_map(|n| (sign * Vec3::from(*n)).normalize_or_zero().to_array()).collect());
    let mut indices = Vec::with_capacity(m.indices.len());
    for (t, tri) in m.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = m.vertices(t);
        let face = (b - a).cross(c - a);
        let front = match &m.n {
            Some(ns) => {
                let n: DVec3 = tri.iter().map(|&k| DVec3::from(ns[k as usize].map(f64::from))).sum();
                face.dot(sign as f64 * n) >= 0.0
            }
            None => !(reverse ^ swaps),
        };
        indices.extend(if front { [tri[0], tri[1], tri[2]] } else { [tri[0], tri[2], tri[1]] });
    }
    let face_normals = normals.is_none();
    GeometryOut::Mesh { positions, normals, indices, face_normals }
}
