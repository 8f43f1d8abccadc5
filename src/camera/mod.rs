//! Perspective, orthographic and spherical cameras with pbrt's conventions.
//!
//! ```text
//! LookAt 0 1 5  0 1 0  0 1 0
//! Camera "perspective" "float fov" 40 "float lensradius" 0.05 "float focaldistance" 5
//! Camera "orthographic" "float screenwindow" [-2 2 -1.5 1.5]
//! Camera "environment"                                   # v3: latitude-longitude
//! Camera "spherical" "string mapping" "equalarea"        # v4; or "equirectangular"
//! Camera "realistic" "string lensfile" "lens.dat"        # see [`realistic`]
//! ```
//! The spherical cameras see every direction from their position: the film's (u, v)
//! in [0, 1]² is laid on the sphere (pbrt-v3's environment camera and pbrt-v4's
//! equirectangular mapping alike, or pbrt-v4's equal-area square), +y up.
//! Camera space is left-handed: +x is image right, +y up, +z the viewing direction. The
//! screen window spans [−1, 1] on the image's shorter axis, so `fov` is the full angle
//! of the shorter axis. Raster (0, 0) is the top-left pixel corner and y grows
//! downward. With `LookAt`, world +x appears on the image's left (pbrt's orientation).
//!
//! For light paths that reach the lens (bidirectional methods), a perspective camera
//! also gives its importance `we` for a ray leaving the lens, the densities `pdf_we`
//! with which `generate_ray` makes it, and `sample_wi`, a lens point seen from a scene
//! point, as pbrt-v3's `PerspectiveCamera` does. An orthographic camera cannot be
//! reached by chance (its rays are parallel), so it has none, as in pbrt; nor have the
//! spherical ones (pbrt has no importance for them either), so light paths never end
//! on them.

pub mod clamp;
pub mod desc;
pub mod realistic;

use crate::math::animated::AnimatedTransform;
use crate::math::equal_area;
use crate::math::ray::RayDifferential;
use crate::math::{Point3, Ray, Vector3};
use desc::{Camera as CameraDesc, CameraKind, Film, SphericalMapping};
use glam::Vec3;
use glam::{DMat4, DVec3};

/// A camera ready to generate rays.
#[derive(Clone, Debug)]
pub struct Camera {
    kind: CameraKind,
    /// At the start of the shutter; `motion` has it over time when the camera moves.
    world_from_camera: DMat4,
    /// Its inverse, kept because light tracing asks for it at every light vertex.
    camera_from_world: DMat4,
    motion: Option<AnimatedTransform>,
    shutter: [f32; 2],
    /// A realistic camera's lens system.
    lens: Option<std::sync::Arc<realistic::Lens>>,
    /// Screen window [x0, x1, y0, y1] and the full film resolution.
    window: [f32; 4],
    resolution: [f32; 2],
    /// How far past the film's edge a ray may start (a pixel filter's radius less half
    /// a pixel), so that light tracing reaches what the edge pixels' rays see.
    margin: [f64; 2],
    tan_half_fov: f32,
    lens_radius: f32,
    focal_distance: f32,
    /// A still pinhole's rays in world space, for [`Camera::generate_ray_at`].
    pinhole: Option<Pinhole>,
}

/// A still pinhole camera's rays, set up once: the origin, and the world direction
/// (before normalising) of raster point (x, y) as `corner + x·per_x + y·per_y`. Each
/// ray then costs a few multiply-adds and a normalisation in `f32`, as pbrt's do,
/// where a transform in `f64` per ray took 3.6% of `sppm-bench`'s time.
#[derive(Clone, Copy, Debug)]
struct Pinhole {
    origin: Vec3,
    corner: Vec3,
    per_x: Vec3,
    per_y: Vec3,
}

impl Pinhole {
    fn new(c: &Camera) -> Option<Pinhole> {
        let still_pinhole = c.kind == CameraKind::Perspective && c.lens_radius <= 0.0 && c.motion.is_none();
        if !still_pinhole || c.lens.is_some() {
            return None;
        }
        let ([x0, x1, y0, y1], t, m) = (c.window.map(|v| v as f64), c.tan_half_fov as f64, c.world_from_camera);
        let [w, h] = c.resolution.map(|v| v as f64);
        let along = |v: DVec3| m.transform_vector3(v).as_vec3();
        Some(Pinhole {
            origin: m.transform_point3(DVec3::ZERO).as_vec3(),
            corner: along(DVec3::new(x0 * t, y1 * t, 1.0)),
            per_x: along(DVec3::new((x1 - x0) / w * t, 0.0, 0.0)),
            per_y: along(DVec3::new(0.0, -(y1 - y0) / h * t, 0.0)),
        })
    }

    fn ray(&self, [x, y]: [f32; 2], time: f32) -> Ray {
        let d = (self.corner + self.per_x * x + self.per_y * y).normalize();
        Ray::new(Point3(self.origin), Vector3(d)).at_time(time)
    }
}

impl Camera {
    pub fn new(desc: &CameraDesc, film: &Film) -> Camera {
        let world_from_camera = desc.camera_from_world.inverse();
        let camera = Camera {
            kind: desc.kind,
            world_from_camera,
            camera_from_world: world_from_camera.inverse(),
            motion: desc.camera_from_world_end.map(|(end, times)| {
                let frame = desc.world_from_render;
                AnimatedTransform::framed(
                    desc.camera_from_world.inverse(),
                    end.inverse(),
                    times,
                    frame,
                    DMat4::IDENTITY,
                )
            }),
            shutter: [desc.shutter_open, desc.shutter_close],
            lens: desc.lens.as_ref().and_then(|l| {
                let lens = realistic::Lens::new(l, [film.x_resolution, film.y_resolution], film.diagonal_mm as f64);
                lens.ok().map(std::sync::Arc::new)
            }),
            window: desc.screen_window,
            resolution: [film.x_resolution as f32, film.y_resolution as f32],
            margin: film.filter.as_ref().map_or([0.0; 2], |f| f.radius().map(|r| (r as f64 - 0.5).max(0.0))),
            tan_half_fov: (desc.fov.to_radians() / 2.0).tan(),
            lens_radius: desc.lens_radius,
            focal_distance: desc.focal_distance,
            pinhole: None,
        };
        Camera { pinhole: Pinhole::new(&camera), ..camera }
    }

    /// Whether the camera moves while the shutter is open.
    pub fn moves(&self) -> bool {
        self.motion.is_some()
    }

    /// A ray's time for a sample `u` in [0, 1): within the shutter (pbrt's lerp).
    pub fn time(&self, u: f32) -> f32 {
        self.shutter[0] + (self.shutter[1] - self.shutter[0]) * u
    }

    /// World-from-camera at `time`.
    fn world_from_camera_at(&self, time: f32) -> DMat4 {
        self.motion.as_ref().map_or(self.world_from_camera, |m| m.at(time as f64))
    }

    /// Camera-from-world at `time`.
    fn camera_from_world_at(&self, time: f32) -> DMat4 {
        self.motion.as_ref().map_or(self.camera_from_world, |m| m.at(time as f64).inverse())
    }

    /// The screen-space point of a raster position.
    fn screen(&self, p_raster: [f32; 2]) -> [f32; 2] {
        let [x0, x1, y0, y1] = self.window;
        [x0 + p_raster[0] / self.resolution[0] * (x1 - x0), y1 - p_raster[1] / self.resolution[1] * (y1 - y0)]
    }

    /// The differentials of `ray` (made for `p_raster`, `u_lens`): the rays through the
    /// same lens point from one pixel over in x and in y, their offsets scaled by
    /// `scale` (the ray itself where the lens stops one, as pbrt has none then).
    pub fn differentials(&self, ray: &Ray, p_raster: [f32; 2], u_lens: [f32; 2], scale: f32) -> RayDifferential {
        let shifted = |dx: f32, dy: f32| {
            self.generate_ray_weighted([p_raster[0] + dx, p_raster[1] + dy], u_lens, ray.time).map_or(*ray, |r| r.0)
        };
        RayDifferential { rx: shifted(1.0, 0.0), ry: shifted(0.0, 1.0) }.scaled(ray, scale)
    }

    /// Whether rays read their lens sample: a realistic camera's, or a perspective or
    /// orthographic one with a lens radius (a pinhole's is never read).
    pub fn reads_lens_sample(&self) -> bool {
        self.lens.is_some()
            || (self.lens_radius > 0.0 && matches!(self.kind, CameraKind::Perspective | CameraKind::Orthographic))
    }

    /// The ray through `p_raster` and lens sample `u_lens` at `time` with its weight:
    /// 1 but for a realistic camera, whose lens may stop it (`None`) or weight it.
    pub fn generate_ray_weighted(&self, p_raster: [f32; 2], u_lens: [f32; 2], time: f32) -> Option<(Ray, f32)> {
        let Some(lens) = &self.lens else { return Some((self.generate_ray_at(p_raster, u_lens, time), 1.0)) };
        let uv = [(p_raster[0] / self.resolution[0]) as f64, (p_raster[1] / self.resolution[1]) as f64];
        let (o, d, weight) = lens.ray(uv, u_lens)?;
        let world_from_camera = self.world_from_camera_at(time);
        let ow = world_from_camera.transform_point3(o);
        let dw = world_from_camera.transform_vector3(d).normalize();
        Some((Ray::new(Point3(ow.as_vec3()), Vector3(dw.as_vec3())).at_time(time), weight))
    }

    /// A world-space ray through raster position `p_raster` at time 0; `u_lens` picks
    /// the lens point (ignored for a pinhole). Directions are unit length.
    pub fn generate_ray(&self, p_raster: [f32; 2], u_lens: [f32; 2]) -> Ray {
        self.generate_ray_at(p_raster, u_lens, 0.0)
    }

    /// As [`Camera::generate_ray`], at `time` (where a moving camera then is).
    pub fn generate_ray_at(&self, p_raster: [f32; 2], u_lens: [f32; 2], time: f32) -> Ray {
        if let Some(p) = &self.pinhole {
            return p.ray(p_raster, time);
        }
        let [sx, sy] = self.screen(p_raster);
        let (mut o, mut d) = match self.kind {
            // A realistic camera's rays come from its lens (`generate_ray_weighted`);
            // here, for tools that want a ray per film point, a pinhole's.
            // Left at z = 1: the lens's focus and the world direction below come out
            // the same at any length, and the direction is normalised once, at the end.
            CameraKind::Perspective | CameraKind::Realistic => {
                (DVec3::ZERO, DVec3::new((sx * self.tan_half_fov) as f64, (sy * self.tan_half_fov) as f64, 1.0))
            }
            CameraKind::Orthographic => (DVec3::new(sx as f64, sy as f64, 0.0), DVec3::Z),
            CameraKind::Environment => (DVec3::ZERO, self.spherical(p_raster, SphericalMapping::Equirectangular)),
            CameraKind::Spherical(m) => (DVec3::ZERO, self.spherical(p_raster, m)),
        };
        let has_lens = matches!(self.kind, CameraKind::Perspective | CameraKind::Orthographic);
        if self.lens_radius > 0.0 && has_lens {
            let lens = (self.lens_radius * crate::sampling::concentric_disk(u_lens)).as_dvec2();
            let ft = self.focal_distance as f64 / d.z;
            let focus = o + d * ft;
            o = DVec3::new(o.x + lens.x, o.y + lens.y, 0.0);
            d = (focus - o).normalize();
        }
        let world_from_camera = self.world_from_camera_at(time);
        let ow = world_from_camera.transform_point3(o);
        let dw = world_from_camera.transform_vector3(d).normalize();
        Ray::new(Point3(ow.as_vec3()), Vector3(dw.as_vec3())).at_time(time)
    }

    /// The camera-space direction of a raster point on a spherical camera: the film's
    /// (u, v) in [0, 1]² laid on the sphere by `mapping`, with y up (pbrt's swap of y
    /// and z); v = 0 looks straight up.
    fn spherical(&self, p_raster: [f32; 2], mapping: SphericalMapping) -> DVec3 {
        let (u, v) = ((p_raster[0] / self.resolution[0]) as f64, (p_raster[1] / self.resolution[1]) as f64);
        let d = match mapping {
            SphericalMapping::Equirectangular => {
                let (theta, phi) = (std::f64::consts::PI * v, 2.0 * std::f64::consts::PI * u);
                DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
            }
            SphericalMapping::EqualArea => equal_area::square_to_sphere(equal_area::wrap([u, v])),
        };
        DVec3::new(d.x, d.z, d.y)
    }

    /// The film's area at distance 1 in camera space (pbrt's `A`).
    fn film_area(&self) -> f32 {
        let [x0, x1, y0, y1] = self.window;
        (x1 - x0) * (y1 - y0) * self.tan_half_fov * self.tan_half_fov
    }

    /// The lens area (1 for a pinhole, whose position is a delta).
    fn lens_area(&self) -> f32 {
        if self.lens_radius > 0.0 { std::f32::consts::PI * self.lens_radius * self.lens_radius } else { 1.0 }
    }

    /// Where a ray leaving the lens meets the film (raster position) and the cosine of
    /// its direction with the view axis; `None` off the film, behind the camera, or for
    /// an orthographic camera (its rays are parallel: no ray reaches it by chance).
    fn on_film(&self, ray: &Ray) -> Option<([f32; 2], f64)> {
        if self.kind != CameraKind::Perspective {
            return None;
        }
        let camera_from_world = self.camera_from_world_at(ray.time);
        let d = camera_from_world.transform_vector3(ray.d.0.as_dvec3()).normalize();
        if d.z <= 0.0 {
            return None;
        }
        let o = camera_from_world.transform_point3(ray.o.0.as_dvec3());
        let focus = if self.lens_radius > 0.0 { self.focal_distance as f64 } else { 1.0 };
        Some((self.raster(o + d * (focus / d.z))?, d.z))
    }

    /// The importance of a ray leaving the lens at `ray.o` along `ray.d` (unit length),
    /// and the raster point it reaches: pbrt-v3's `We`. `None` off the film, behind the
    /// camera, or for an orthographic camera.
    pub fn we(&self, ray: &Ray) -> Option<(f32, [f32; 2])> {
        let (raster, cos) = self.on_film(ray)?;
        let cos2 = (cos * cos) as f32;
        Some((1.0 / (self.film_area() * self.lens_area() * cos2 * cos2), raster))
    }

    /// The (lens position, direction) densities of a ray as `generate_ray` makes it
    /// from a uniform raster point and lens point (pbrt-v3's `Pdf_We`); 0 off the film.
    pub fn pdf_we(&self, ray: &Ray) -> (f32, f32) {
        let Some((_, cos)) = self.on_film(ray) else { return (0.0, 0.0) };
        let cos = cos as f32;
        (1.0 / self.lens_area(), 1.0 / (self.film_area() * cos * cos * cos))
    }

    /// A point on the lens seen from the scene point `p`: the unit direction from `p`
    /// to it, the importance arriving there, the solid-angle density at `p`, the lens
    /// point and the raster point (pbrt-v3's `Sample_Wi`), with the camera where it is
    /// at `time`.
    pub fn sample_wi(&self, p: Vec3, u: [f32; 2], time: f32) -> Option<CameraSample> {
        let lens = self.lens_radius * crate::sampling::concentric_disk(u);
        let on_lens = DVec3::new(lens.x as f64, lens.y as f64, 0.0);
        let world_from_camera = self.world_from_camera_at(time);
        let p_lens = world_from_camera.transform_point3(on_lens).as_vec3();
        let to_lens = p_lens - p;
        let dist2 = to_lens.length_squared();
        if dist2 == 0.0 {
            return None;
        }
        let wi = to_lens / dist2.sqrt();
        let (we, raster) = self.we(&Ray::new(Point3(p_lens), Vector3(-wi)).at_time(time))?;
        let axis = world_from_camera.transform_vector3(DVec3::Z).normalize().as_vec3();
        let pdf = dist2 / (axis.dot(wi).abs() * self.lens_area());
        Some(CameraSample { wi, we, pdf, p_lens, raster })
    }

    /// The raster position of a camera-space point in front of the lens, if on the film
    /// or within the filter's margin of it (pbrt-v4's `SampleBounds`).
    fn raster(&self, p: DVec3) -> Option<[f32; 2]> {
        let [x0, x1, y0, y1] = self.window.map(f64::from);
        let t = self.tan_half_fov as f64;
        let (sx, sy) = (p.x / p.z / t, p.y / p.z / t);
        let r = [(sx - x0) / (x1 - x0) * self.resolution[0] as f64, (y1 - sy) / (y1 - y0) * self.resolution[1] as f64];
        let within = |k: usize| (-self.margin[k]..=self.resolution[k] as f64 + self.margin[k]).contains(&r[k]);
        (within(0) && within(1)).then(|| r.map(|x| x as f32))
    }
}

/// Importance arriving at a scene point from a lens point (see [`Camera::sample_wi`]).
#[derive(Clone, Copy, Debug)]
pub struct CameraSample {
    /// Unit direction from the scene point to the lens point.
    pub wi: Vec3,
    pub we: f32,
    /// Solid-angle density at the scene point.
    pub pdf: f32,
    pub p_lens: Vec3,
    pub raster: [f32; 2],
}
