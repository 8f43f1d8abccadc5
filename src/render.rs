//! The render-ready scene: geometry and BVHs, camera, materials per shape, lights (area
//! lights one per quadric or triangle), the photon-source distribution, and the world's
//! bounding sphere. Built once from a [`SceneDescription`].

use crate::accel::{Geometry, Hit, LocalHit};
use crate::camera::Camera;
use crate::interaction::SurfaceInteraction;
use crate::lights::{Emitter, Light, WorldSphere, quadric_area};
use crate::materials::{Bsdf, Material, Textures};
use crate::math::frame::coordinate_system;
use crate::parser::Syntax;
use crate::sampling::Distribution1D;
use crate::scene::{AreaLightDesc, Film, Geometry as ShapeGeometry, Integrator, SceneDescription};
use crate::shapes::MeshFlags;
use crate::spectrum::{Rgb, luminance};
use glam::Vec3;

/// An emitting world shape: its radiance and where its lights start.
#[derive(Clone, Copy, Debug)]
pub struct EmitterInfo {
    pub l: Rgb,
    pub two_sided: bool,
    /// Index of its (first) light; meshes have one light per stored triangle after it.
    pub first_light: u32,
}

pub struct RenderScene {
    pub geometry: Geometry,
    pub camera: Camera,
    pub film: Film,
    pub integrator: Integrator,
    pub syntax: Syntax,
    pub materials: Vec<Material>,
    pub textures: Textures,
    world_shape_material: Vec<u32>,
    object_shape_material: Vec<Vec<u32>>,
    /// Per world shape (by `check --shapes` index): its emission, if it emits.
    pub emitters: Vec<Option<EmitterInfo>>,
    pub lights: Vec<Light>,
    pub light_power: Distribution1D,
    pub world: WorldSphere,
    /// Row-major world-to-camera, for image metadata.
    pub world_to_camera: [f32; 16],
}

impl RenderScene {
    pub fn new(mut scene: SceneDescription) -> RenderScene {
        let camera = Camera::new(&scene.camera, &scene.film);
        let textures = Textures::new(&scene.textures);
        let materials: Vec<Material> = scene.materials.iter().map(|m| Material::from_desc(m, &textures)).collect();
        let world_shape_material = scene.shapes.iter().map(|s| s.material).collect();
        let object_shape_material =
            scene.objects.iter().map(|o| o.shapes.iter().map(|s| s.material).collect()).collect();
        let bounds = scene.world_bounds();
        let world = match bounds {
            Some([lo, hi]) => {
                let c = (lo + hi) * 0.5;
                WorldSphere { center: c.as_vec3(), radius: ((hi - c).length() as f32).max(1e-6) }
            }
            None => WorldSphere { center: Vec3::ZERO, radius: 1.0 },
        };
        let mut lights: Vec<Light> = scene.lights.iter().map(Light::from_desc).collect();
        let shape_info: Vec<(ShapeGeometry, Option<u32>, bool, bool)> = scene
            .shapes
            .iter()
            .map(|s| (s.geometry.clone(), s.area_light, s.reverse_orientation, s.swaps_handedness()))
            .collect();
        let area_params = scene.area_lights.clone();
        let syntax = scene.syntax;
        let film = scene.film.clone();
        let integrator = scene.integrator.clone();
        let m = crate::math::transform::row_major(&scene.camera.camera_from_world).map(|x| x as f32);
        let geometry = Geometry::new(&mut scene);
        let emitters = area_lights(&geometry, &shape_info, &area_params, &mut lights);
        let light_power = Distribution1D::new(&lights.iter().map(|l| l.power(world) as f64).collect::<Vec<_>>());
        RenderScene {
            geometry,
            camera,
            film,
            integrator,
            syntax,
            materials,
            textures,
            world_shape_material,
            object_shape_material,
            emitters,
            lights,
            light_power,
            world,
            world_to_camera: m,
        }
    }

    /// The material of a hit shape.
    pub fn material(&self, hit: &Hit) -> &Material {
        let idx = match self.geometry.shape_of(hit) {
            (None, s) => self.world_shape_material[s as usize],
            (Some(o), s) => self.object_shape_material[o as usize][s as usize],
        };
        &self.materials[idx as usize]
    }

    /// The BSDF at a hit (`None` for interfaces), in the shading frame.
    pub fn bsdf(&self, hit: &Hit, si: &SurfaceInteraction) -> Option<Bsdf> {
        let ns = si.shading.n.0;
        let dpdu = si.shading.dpdu.0;
        let mut ss = (dpdu - ns * ns.dot(dpdu)).normalize_or_zero();
        if ss == Vec3::ZERO {
            ss = coordinate_system(ns).0;
        }
        let ts = ns.cross(ss);
        self.material(hit).bsdf(&self.textures, si.uv, [ss, ts, ns], si.n.0)
    }

    /// The emitting world shape hit, and which of its lights (for MIS).
    pub fn emitter(&self, hit: &Hit) -> Option<(EmitterInfo, u32)> {
        if hit.instance.is_some() {
            return None; // area lights inside object definitions are ignored, as in pbrt
        }
        let info = (*self.emitters.get(hit.shape_index as usize)?)?;
        let light = match hit.local {
            LocalHit::Triangle { tri, .. } => info.first_light + tri,
            LocalHit::Quadric(..) => info.first_light,
        };
        Some((info, light))
    }

    /// Radiance leaving a hit surface toward `w` (area lights).
    pub fn emitted(&self, hit: &Hit, si: &SurfaceInteraction, w: Vec3) -> Rgb {
        match self.emitter(hit) {
            Some((e, _)) if e.two_sided || si.n.0.dot(w) > 0.0 => e.l,
            _ => Vec3::ZERO,
        }
    }
}

/// One light per emitting quadric and per non-degenerate triangle of emitting meshes
/// (world shapes).
fn area_lights(
    g: &Geometry,
    shapes: &[(ShapeGeometry, Option<u32>, bool, bool)],
    params: &[AreaLightDesc],
    lights: &mut Vec<Light>,
) -> Vec<Option<EmitterInfo>> {
    let mut emitters = vec![None; shapes.len()];
    let mut quadric = 0u32;
    for (i, (geom, area, ro, swaps)) in shapes.iter().enumerate() {
        let this_quadric = quadric;
        if let ShapeGeometry::Quadric(_) = geom {
            quadric += 1;
        }
        let Some(a) = area else { continue };
        let desc = &params[*a as usize];
        let first_light = lights.len() as u32;
        let mut shape_lights = Vec::new();
        match geom {
            ShapeGeometry::Quadric(_) => {
                let sampler = g.quadrics[this_quadric as usize].sampler();
                let area = quadric_area(g, this_quadric);
                let emitter = Emitter::Quadric { index: this_quadric, sampler };
                shape_lights.push((emitter, area));
            }
            ShapeGeometry::Mesh { mesh, .. } => {
                let m = &g.meshes[*mesh as usize];
                let flags = MeshFlags { reverse_orientation: *ro, swaps_handedness: *swaps };
                for t in 0..m.triangle_count() {
                    let [a, b, c] = m.vertices(t);
                    let area = (0.5 * (b - a).cross(c - a).length()) as f32;
                    // Zero-area triangles keep their slot (lights are found by triangle
                    // number) but emit nothing.
                    shape_lights.push((Emitter::Triangle { mesh: *mesh, tri: t as u32, flags }, area));
                }
            }
        }
        let l = area_emission(desc, shape_lights.iter().map(|(_, a)| *a as f64).sum());
        for (emitter, area) in shape_lights {
            let l = if area > 0.0 { l } else { Vec3::ZERO };
            lights.push(Light::Area { emitter, l, two_sided: desc.two_sided, area });
        }
        emitters[i] = Some(EmitterInfo { l, two_sided: desc.two_sided, first_light });
    }
    emitters
}

/// An area light's radiance on a shape of total area `area`, after v4's `power`.
// DEVIATION(pbrt): pbrt-v4 applies `power` to each triangle of a mesh on its own, so a
// mesh of n triangles emits n times the power asked for; we spread it over the shape.
pub fn area_emission(a: &AreaLightDesc, area: f64) -> Rgb {
    match a.power {
        Some(w) if area > 0.0 => {
            let sides = if a.two_sided { 2.0 } else { 1.0 };
            a.l * (w as f64 / (std::f64::consts::PI * sides * area * luminance(a.l).max(1e-9) as f64)) as f32
        }
        _ => a.l,
    }
}

/// Command-line overrides and reporting for a render.
#[derive(Clone, Debug, Default)]
pub struct RenderSettings {
    /// SPPM iterations (`--spp`/`--iterations`).
    pub iterations: Option<u32>,
    pub photons: Option<u64>,
    pub radius: Option<f32>,
    pub seed: Option<u64>,
    /// Divide the iteration count by 16 (pbrt-v3's `--quick`).
    pub quick: bool,
    /// Stop after the iteration that passes this many seconds.
    pub time_limit: Option<f64>,
    /// Compare against this image after every iteration (`--mse-reference-image`).
    pub reference: Option<crate::imageio::RgbImage>,
    /// Print a progress bar with ETA on stderr.
    pub progress: bool,
}

/// One `ERRORS.csv` row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorRow {
    pub iteration: u32,
    pub seconds: f64,
    pub photons: u64,
    pub mse: f64,
    pub rmse: f64,
    pub relmse: f64,
}

/// The header of `ERRORS.csv` (a fixed contract).
pub const ERRORS_HEADER: &str = "iteration,seconds,photons,mse,rmse,relmse";

pub struct RenderOutput {
    pub image: crate::imageio::RgbImage,
    pub stats: crate::integrators::sppm::Stats,
    pub errors: Vec<ErrorRow>,
    pub seconds: f64,
}

/// `ERRORS.csv` text.
pub fn errors_csv(rows: &[ErrorRow]) -> String {
    let mut s = format!("{ERRORS_HEADER}\n");
    for r in rows {
        s.push_str(&format!(
            "{},{:.6},{},{:e},{:e},{:e}\n",
            r.iteration, r.seconds, r.photons, r.mse, r.rmse, r.relmse
        ));
    }
    s
}

impl RenderScene {
    /// Renders with SPPM (scene loading excluded from the timings).
    pub fn render(&self, settings: &RenderSettings) -> Result<RenderOutput, String> {
        use crate::imageio::{ImageMeta, RgbImage, metrics};
        let start = std::time::Instant::now();
        let i = &self.integrator;
        let mut iterations = settings.iterations.unwrap_or(i.iterations);
        if settings.quick {
            iterations = (iterations / 16).max(1);
        }
        let photons = settings.photons.unwrap_or(i.photons_per_iteration).max(1);
        let radius = settings.radius.unwrap_or(i.radius);
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!("the radius must be positive, not {radius}"));
        }
        let mut sppm = crate::integrators::sppm::Sppm::new(self, photons, radius, settings.seed.unwrap_or(i.seed))?;
        let [x0, x1, y0, y1] = self.film.pixel_bounds;
        let (w, h) = ((x1 - x0) as usize, (y1 - y0) as usize);
        if let Some(r) = &settings.reference
            && (r.width, r.height) != (w, h)
            && (r.width, r.height) != (self.film.x_resolution as usize, self.film.y_resolution as usize)
        {
            return Err(format!("the reference image is {}x{}, the render {w}x{h}", r.width, r.height));
        }
        let mut errors = Vec::new();
        for it in 0..iterations {
            sppm.iterate();
            let seconds = start.elapsed().as_secs_f64();
            if let Some(r) = &settings.reference {
                let img = sppm.image();
                let refpx = crop_reference(r, self.film.pixel_bounds);
                let mse = metrics::mse(&img, &refpx);
                errors.push(ErrorRow {
                    iteration: it + 1,
                    seconds,
                    photons: sppm.stats.photon_paths,
                    mse,
                    rmse: mse.sqrt(),
                    relmse: metrics::relmse(&img, &refpx),
                });
            }
            if settings.progress {
                progress_bar(it + 1, iterations, seconds);
            }
            if settings.time_limit.is_some_and(|t| seconds >= t) {
                break;
            }
        }
        if settings.progress {
            eprintln!();
        }
        let seconds = start.elapsed().as_secs_f64();
        let image = RgbImage {
            width: w,
            height: h,
            pixels: sppm.image(),
            origin: (x0 as i32, y0 as i32),
            full: (self.film.x_resolution as usize, self.film.y_resolution as usize),
            meta: ImageMeta {
                render_time_seconds: Some(seconds as f32),
                samples_per_pixel: Some(sppm.iteration as i32),
                photons_per_iteration: Some(photons as i64),
                world_to_camera: Some(self.world_to_camera),
                software: Some(format!("pbrt-sppm {}", env!("CARGO_PKG_VERSION"))),
            },
        };
        Ok(RenderOutput { image, stats: sppm.stats.clone(), errors, seconds })
    }
}

/// The reference's pixels under the render's data window (the reference may be the
/// full image or already cropped).
fn crop_reference(r: &crate::imageio::RgbImage, bounds: [u32; 4]) -> Vec<[f32; 3]> {
    let [x0, x1, y0, y1] = bounds.map(|v| v as usize);
    if r.width == x1 - x0 && r.height == y1 - y0 {
        return r.pixels.clone();
    }
    (y0..y1).flat_map(|y| (x0..x1).map(move |x| r.pixels[y * r.width + x])).collect()
}

fn progress_bar(done: u32, total: u32, seconds: f64) {
    let width = 30;
    let filled = (done as usize * width) / total.max(1) as usize;
    let eta = seconds / done.max(1) as f64 * (total - done) as f64;
    eprint!(
        "\r[{}{}] {done}/{total} iterations, {seconds:.1} s, ETA {eta:.1} s   ",
        "#".repeat(filled),
        "-".repeat(width - filled)
    );
}
