//! The render-ready scene: geometry and BVHs, camera, materials per shape, lights (area
//! lights one per quadric, triangle or patch), the photon-source distribution, and the world's
//! bounding sphere. Built once from a [`SceneDescription`]; `integrators` renders it.

use crate::accel::{Geometry, Hit};
use crate::camera::Camera;
use crate::camera::clamp::Clamp;
use crate::fixes::{Fix, Fixes};
use crate::interaction::{Footprint, SurfaceInteraction};
use crate::lights::choice::LightChoice;
use crate::lights::{AreaLight, Light, WorldSphere};
use crate::materials::{Bsdf, LobeList, Material, Shading, TexCtx, Textures};
use crate::math::Ray;
use crate::math::frame::coordinate_system;
use crate::media::MediumInterface;
use crate::parser::Syntax;
use crate::sampling::{Distribution1D, Pick};
use crate::scene::{
    AlphaRule, AreaLightDesc, Film, Integrator, MaterialKind, MixRule, SceneDescription, ShapeAlpha, TexValue,
};
use crate::shapes::{ShapeSample, TriangleMesh};
use crate::spectrum::sampled::Draw;
use crate::spectrum::transport::{PassCell, PassSpectrum};
use crate::spectrum::{EmissionSpectrum, Rgb};
use glam::{DVec3, Vec3};
use std::sync::Arc;

/// An emitting world shape: which side emits and where its lights start (each
/// primitive's light holds its radiance).
#[derive(Clone, Copy, Debug)]
pub struct EmitterInfo {
    pub two_sided: bool,
    /// Index of its (first) light; meshes have one light per stored triangle after it.
    pub first_light: u32,
}

/// The scene's BVHs over its shapes and `meshes` ([`Geometry::with_meshes`]). A
/// spectral scene's colours need its colour space's RGB-to-spectrum table, 40 ms to
/// unpack on first use: it is unpacked meanwhile, on another thread.
fn build_geometry(scene: &SceneDescription, meshes: Vec<Arc<TriangleMesh>>) -> Geometry {
    let geometry = || Geometry::with_meshes(scene, meshes);
    match scene.spectral {
        true => rayon::join(geometry, || crate::spectrum::sigmoid::RgbToSpectrumTable::of(scene.color_space)).0,
        false => geometry(),
    }
}

/// The description a render scene is made from: lent, or given up so that its meshes
/// move into the BVHs, which free each one as soon as its reordered copy is made
/// (the load benchmark's peak: 1,004 MiB, was 1,105).
enum Description<'a> {
    Lent(&'a SceneDescription),
    Given(Box<SceneDescription>),
}

impl Description<'_> {
    fn get(&self) -> &SceneDescription {
        match self {
            Description::Lent(s) => s,
            Description::Given(s) => s,
        }
    }

    /// The meshes for the BVHs: shares of a lent description's, or a given one's own,
    /// which it holds no longer.
    fn meshes(&mut self) -> Vec<Arc<TriangleMesh>> {
        match self {
            Description::Lent(s) => s.meshes.clone(),
            Description::Given(s) => std::mem::take(&mut s.meshes),
        }
    }
}

/// The sphere around the scene's shapes (distant and infinite lights emit across it).
pub fn world_sphere(scene: &SceneDescription) -> WorldSphere {
    match scene.world_bounds() {
        Some([lo, hi]) => {
            let c = (lo + hi) * 0.5;
            WorldSphere { center: c.as_vec3(), radius: ((hi - c).length() as f32).max(1e-6) }
        }
        None => WorldSphere { center: Vec3::ZERO, radius: 1.0 },
    }
}

/// Where alpha masks an area light's emission.
#[derive(Clone, Copy, Debug)]
struct AlphaEmission {
    /// Light samples and photons drawn on a cut-away point (pbrt-v4, and the fix).
    samples: bool,
    /// A hit again by the position's hash, after the ray's own alpha test let it
    /// through (pbrt-v4 only).
    hits: bool,
}

impl AlphaEmission {
    // DEVIATION(pbrt): appearance, `--fix area-alpha`. pbrt-v4 masks the emission of a
    // hit by alpha after the hit itself passed the ray's alpha test, counting a
    // fractional alpha twice there and once on light samples; the fix masks each
    // emitted point once.
    fn new(syntax: Syntax, fixes: Fixes) -> AlphaEmission {
        let fixed = fixes.has(Fix::AreaAlpha);
        AlphaEmission { samples: fixed || syntax == Syntax::V4, hits: !fixed && syntax == Syntax::V4 }
    }
}

pub struct RenderScene {
    pub geometry: Geometry,
    pub camera: Camera,
    pub film: Film,
    pub integrator: Integrator,
    pub materials: Vec<Material>,
    pub textures: Textures,
    world_shape_material: Vec<u32>,
    object_shape_material: Vec<Vec<u32>>,
    world_shape_alpha: Vec<Option<ShapeAlpha>>,
    object_shape_alpha: Vec<Vec<Option<ShapeAlpha>>>,
    /// Whether any shape has an alpha mask (rays then check the shapes they hit).
    has_alpha: bool,
    alpha_rules: AlphaEmission,
    /// The pbrt bugs fixed (`--fix`).
    pub fixes: Fixes,
    /// The file's pbrt version, whose integrator's rules the render follows.
    pub syntax: Syntax,
    /// Whether shading uses a pixel's footprint (bump maps, noise textures, `ptex`):
    /// camera rays then carry differentials.
    pub needs_differentials: bool,
    /// Whether a texture reads the footprint in (u, v) (`ptex`).
    pub needs_duv: bool,
    /// Whether anything moves while the shutter is open (a shape, an instance or the
    /// camera): camera rays, photons and light subpaths then draw a time.
    pub motion: bool,
    /// Per world shape (by `check --shapes` index): its emission, if it emits.
    pub emitters: Vec<Option<EmitterInfo>>,
    pub lights: Vec<Light>,
    /// The emission spectra of `lights` that are not area lights (those hold their
    /// own), where the file gives them as spectra.
    light_spectra: Vec<Option<std::sync::Arc<EmissionSpectrum>>>,
    pub light_power: Distribution1D,
    /// Per light, an area light's emitter's box (`None` for other lights): a ray that
    /// misses it cannot find that light.
    light_boxes: Vec<Option<crate::math::Bounds3>>,
    /// pbrt-v4's choice of light for a point's direct light, by each light's bounds
    /// (v4 scenes without media and with few lights).
    light_choice: Option<LightChoice>,
    /// Where SPPM's photons start: the lights (by `light_power`'s weights), then the
    /// emitting media of `medium_emitters`.
    pub photon_sources: Distribution1D,
    /// The emitting media (index into `media`) and how their photons start.
    pub medium_emitters: Vec<(u32, crate::media::emitters::EmissionPoints)>,
    /// Photons carry their power divided by this (a power of two near the lights'
    /// total power), so that lights far outside f32's range near 1 (an emitter of
    /// 1e38) neither overflow nor lose precision; the deposits are multiplied back in
    /// f64.
    pub photon_scale: f64,
    pub world: WorldSphere,
    /// Row-major world-to-camera, for image metadata.
    pub world_to_camera: [f32; 16],
    /// The rendered media (`SceneDescription::media`); empty for a scene in vacuum,
    /// whose rays then never ask which medium they are in.
    pub media: Vec<crate::media::Medium>,
    pub camera_medium: Option<u32>,
    world_shape_media: Vec<MediumInterface>,
    object_shape_media: Vec<Vec<MediumInterface>>,
    /// Per light of the scene's `LightSource`s (the first of `lights`): its medium.
    light_media: Vec<Option<u32>>,
    /// The film's bound on each camera sample and light-tracing splat
    /// ([`crate::camera::clamp`]), where it has one. SPPM does not apply it, as in pbrt.
    pub clamp: Option<Clamp>,
    /// The pass's wavelengths when paths carry them (`spectrum::transport`); `None`
    /// renders in RGB.
    spectral: Option<PassCell>,
    /// Spectral, with a material that disperses.
    dispersive: bool,
    /// Light crosses `subsurface` boundaries (and those of `disney` materials with a
    /// `scatterdistance`) through their BSSRDF (vcm and bdpt, for
    /// files whose pbrt integrator takes it: [`crate::materials::subsurface::follows_bssrdf`]);
    /// otherwise they are the glass pbrt's other integrators see.
    pub subsurface: bool,
    /// Per material: whether light crossing it goes into its BSSRDF.
    bssrdf_materials: Vec<bool>,
}

/// The rendered media, each shape's media on either side, and per material whether its
/// BSSRDF is followed ([`RenderScene::subsurface`]).
struct Interiors {
    media: Vec<crate::media::Medium>,
    world_shape_media: Vec<MediumInterface>,
    object_shape_media: Vec<Vec<MediumInterface>>,
    bssrdf: Vec<bool>,
}

/// The scene's media, and what becomes of `subsurface` materials: for vcm and bdpt, in
/// files whose pbrt integrator takes the BSSRDF, it is followed, or with `--fix
/// subsurface-walk` the interior is a homogeneous medium inside every shape of the
/// material (where its coefficients are constants); otherwise the boundary is all.
fn interiors(scene: &SceneDescription, bidirectional: bool) -> Interiors {
    let mut media: Vec<crate::media::Medium> = scene.media.iter().map(|m| m.kind.clone()).collect();
    let mut world_shape_media: Vec<MediumInterface> = scene.shapes.iter().map(|s| s.media).collect();
    let mut object_shape_media: Vec<Vec<MediumInterface>> =
        scene.objects.iter().map(|o| o.shapes.iter().map(|s| s.media).collect()).collect();
    let follows =
        bidirectional && crate::materials::subsurface::follows_bssrdf(scene.syntax, &scene.integrator.requested);
    let walk = follows && scene.fixes.has(Fix::SubsurfaceWalk);
    let space = scene.spectral.then_some(scene.color_space);
    let mut bssrdf = vec![false; scene.materials.len()];
    for (k, m) in scene.materials.iter().enumerate() {
        let MaterialKind::Subsurface(s) = &m.kind else {
            bssrdf[k] = follows && m.kind.may_have_bssrdf();
            continue;
        };
        let Some(medium) = walk.then(|| crate::materials::subsurface::walk_medium(s, space)).flatten() else {
            bssrdf[k] = follows;
            continue;
        };
        media.push(medium);
        let inside = Some(media.len() as u32 - 1);
        let shapes = scene.shapes.iter().zip(world_shape_media.iter_mut());
        let objects = scene
            .objects
            .iter()
            .zip(object_shape_media.iter_mut())
            .flat_map(|(o, mi)| o.shapes.iter().zip(mi.iter_mut()));
        for (_, mi) in shapes.chain(objects).filter(|(shape, _)| shape.material as usize == k) {
            mi.inside = inside;
        }
    }
    Interiors { media, world_shape_media, object_shape_media, bssrdf }
}

impl RenderScene {
    /// The time every ray of pass `iteration` takes, or `None` when each camera path
    /// and photon draws its own within the shutter (pbrt-v3's SPPM). A scene without
    /// motion draws none (its rays keep time 0 and its sample sequences). pbrt-v4's SPPM
    /// renders a pass at one time, `RadicalInverse(2, iteration)` across the shutter, so
    /// that photons light the moving surfaces where the camera sees them; vcm and bdpt
    /// do the same whatever the version, for the same reason between their subpaths.
    pub fn pass_time(&self, iteration: u32, bidirectional: bool) -> Option<f32> {
        // DEVIATION(pbrt): appearance, `--fix motion-time` (pbrt-v3's independent times).
        let one_time = bidirectional || self.syntax == Syntax::V4 || self.fixes.has(crate::fixes::Fix::MotionTime);
        if !self.motion {
            Some(0.0)
        } else if one_time {
            Some(self.camera.time(crate::sampling::radical_inverse_5(iteration as u64)))
        } else {
            None
        }
    }

    pub fn new(scene: &SceneDescription) -> RenderScene {
        RenderScene::for_integrator(scene, false)
    }

    /// The scene for an integrator; `bidirectional` (vcm, bdpt) samples area lights
    /// exactly whatever `--fix` says.
    // DEVIATION(pbrt): appearance, for vcm and bdpt only. Their weights need each light
    // density to be the one its sampling has; pbrt's object-space sphere and disk
    // sampling (`--fix shape-sampling`) is not, and mixed with emitters found by rays
    // it gives neither pbrt's image nor the right one. SPPM keeps pbrt's by default.
    pub fn for_integrator(scene: &SceneDescription, bidirectional: bool) -> RenderScene {
        RenderScene::assemble(Description::Lent(scene), bidirectional)
    }

    /// As [`Self::for_integrator`], from a description no longer needed: its meshes
    /// move into the BVHs.
    pub fn from_description(scene: SceneDescription, bidirectional: bool) -> RenderScene {
        RenderScene::assemble(Description::Given(Box::new(scene)), bidirectional)
    }

    fn assemble(mut source: Description, bidirectional: bool) -> RenderScene {
        // What reads the scene's meshes comes first: they may move into the BVHs.
        let world = world_sphere(source.get());
        let Interiors { media, world_shape_media, object_shape_media, bssrdf } = interiors(source.get(), bidirectional);
        let medium_emitters = medium_emitters(&media, source.get());
        let meshes = source.meshes();
        let scene = source.get();
        let camera = Camera::new(&scene.camera, &scene.film);
        let textures = Textures::new(&scene.textures, scene.fixes);
        let needs_differentials = textures.use_footprint() || scene.materials.iter().any(|m| m.bump.is_some());
        let materials: Vec<Material> = (scene.materials.iter().map(|m| Material::from_desc(m, scene.fixes)))
            .map(|m| if bidirectional { m.bidirectional() } else { m })
            .collect();
        let world_shape_material = scene.shapes.iter().map(|s| s.material).collect();
        let object_shape_material =
            scene.objects.iter().map(|o| o.shapes.iter().map(|s| s.material).collect()).collect();
        let world_shape_alpha: Vec<_> = scene.shapes.iter().map(|s| s.alpha).collect();
        let object_shape_alpha: Vec<Vec<_>> =
            scene.objects.iter().map(|o| o.shapes.iter().map(|s| s.alpha).collect()).collect();
        let has_alpha = world_shape_alpha.iter().chain(object_shape_alpha.iter().flatten()).any(|a| a.is_some());
        let mut lights: Vec<Light> = scene.lights.iter().map(|l| Light::from_desc(l, scene.fixes)).collect();
        let shape_area_lights: Vec<Option<u32>> = scene.shapes.iter().map(|s| s.area_light).collect();
        let area_params = scene.area_lights.clone();
        let geometry = build_geometry(scene, meshes);
        let alpha_rules = AlphaEmission::new(scene.syntax, scene.fixes);
        let rules = EmitterRules::new(scene, bidirectional, alpha_rules);
        let emitters = area_lights(&geometry, &shape_area_lights, &world_shape_alpha, &area_params, rules, &mut lights);
        let light_media = scene.lights.iter().map(|l| l.medium).collect();
        let powers: Vec<f64> = lights.iter().map(|l| l.power(world)).collect();
        let sources: Vec<f64> = powers.iter().copied().chain(medium_emitters.iter().map(|e| e.1.power)).collect();
        let photon_scale = photon_scale(sources.iter().sum());
        let light_power = Distribution1D::new(&powers);
        let light_boxes = light_boxes(&lights, &geometry);
        let light_choice = (scene.syntax == Syntax::V4 && media.is_empty())
            .then(|| LightChoice::new(&lights, &geometry.shapes))
            .flatten();
        RenderScene {
            geometry,
            camera,
            film: scene.film.clone(),
            integrator: scene.integrator.clone(),
            materials,
            needs_duv: textures.use_duv(),
            textures,
            world_shape_material,
            object_shape_material,
            world_shape_alpha,
            object_shape_alpha,
            has_alpha,
            alpha_rules,
            fixes: if bidirectional { scene.fixes.with(Fix::ShapeSampling) } else { scene.fixes },
            syntax: scene.syntax,
            needs_differentials,
            motion: scene.camera.camera_from_world_end.is_some()
                || scene.instances.iter().any(|i| i.motion().is_some()),
            emitters,
            lights,
            light_spectra: scene.lights.iter().map(|l| l.spectrum.clone()).collect(),
            light_power,
            light_boxes,
            light_choice,
            photon_sources: Distribution1D::new(&sources),
            medium_emitters,
            photon_scale,
            world,
            world_to_camera: crate::math::transform::row_major(&scene.camera.camera_from_world).map(|x| x as f32),
            media,
            camera_medium: scene.camera_medium,
            world_shape_media,
            object_shape_media,
            light_media,
            clamp: film_clamp(scene),
            spectral: pass_cell(scene),
            dispersive: scene.spectral && scene.materials.iter().any(|m| m.kind.disperses()),
            subsurface: bssrdf.contains(&true),
            bssrdf_materials: bssrdf,
        }
    }

    /// The light direct lighting samples at `at` (point and normal, when on a
    /// surface), from a uniform number (the first coordinate of the light's own 2D
    /// sample, whose place the pick's `rest` takes): uniform, as
    /// pbrt-v3's SPPM, in a scene without media; in v4 scenes, by each light's bounds,
    /// as pbrt-v4's SPPM ([`LightChoice`], up to 64 lights); by power with media.
    // Not a deviation: any choice gives the same expected image, only the noise
    // differs. pbrt's SPPM ignores media; its volpath, the reference for them, picks
    // lights by a spatial distribution. Uniform choice there doubled the smoke scene's error at
    // equal iterations (relMSE 8.4e-3 against 3.6e-3 by power).
    pub fn direct_light_choice(&self, u: f32, at: Option<(Vec3, Vec3)>) -> Option<Pick> {
        let n = self.lights.len();
        if n == 0 {
            return None;
        }
        if let (Some(choice), Some((p, normal))) = (&self.light_choice, at) {
            return choice.choose(u, p, normal);
        }
        if self.media.is_empty() {
            return Some(Pick::uniform(u as f64, n));
        }
        self.light_power.pick(u)
    }

    /// Whether a ray may find light `idx`: false only where it misses an area light's
    /// box, so that tracing it could not reach that light.
    pub fn may_reach_light(&self, idx: usize, ray: &Ray) -> bool {
        self.light_boxes.get(idx).copied().flatten().is_none_or(|b| b.may_meet_ray(ray.o.0, ray.d.0))
    }

    /// The media on either side of a hit shape.
    pub fn media_of(&self, hit: &Hit) -> MediumInterface {
        match self.geometry.shape_of(hit) {
            (None, s) => self.world_shape_media[s as usize],
            (Some(o), s) => self.object_shape_media[o as usize][s as usize],
        }
    }

    /// The medium at point `p`, as a ray from it finds: the side of the first medium
    /// transition it crosses, or the camera's medium where it crosses none.
    pub fn medium_at(&self, p: Vec3) -> Option<u32> {
        let d = Vec3::new(0.267_261, 0.801_784, 0.534_522);
        let mut ray = crate::math::Ray::new(crate::math::Point3(p), crate::math::Vector3(d));
        for _ in 0..1024 {
            let Some(hit) = self.intersect(&ray) else { return self.camera_medium };
            let si = self.geometry.interaction(&hit);
            let mi = self.media_of(&hit);
            if mi.is_transition() {
                return mi.toward(-d, si.n.0);
            }
            ray = si.spawn_ray(crate::math::Vector3(d));
        }
        self.camera_medium
    }

    /// The medium a ray in `current` is in after crossing the hit surface in
    /// direction `d` (geometric normal `n`): a transition's side, else unchanged.
    #[inline]
    pub fn medium_after(&self, hit: &Hit, n: Vec3, d: Vec3, current: Option<u32>) -> Option<u32> {
        if self.media.is_empty() {
            return None;
        }
        let mi = self.media_of(hit);
        if mi.is_transition() { mi.toward(d, n) } else { current }
    }

    /// The medium light `idx` emits into along `d` from a point with normal `n`: an
    /// area light's shape's side, another light's own medium.
    pub fn light_medium(&self, idx: usize, d: Vec3, n: Vec3) -> Option<u32> {
        match &self.lights[idx] {
            _ if self.media.is_empty() => None,
            Light::Area(a) => self.world_shape_media[a.shape as usize].toward(d, n),
            _ => self.light_media.get(idx).copied().flatten(),
        }
    }

    /// The material of a hit shape.
    pub fn material(&self, hit: &Hit) -> &Material {
        &self.materials[self.material_index(hit) as usize]
    }

    /// The index of the material at a hit (in `materials`).
    pub fn material_index(&self, hit: &Hit) -> u32 {
        match self.geometry.shape_of(hit) {
            (None, s) => self.world_shape_material[s as usize],
            (Some(o), s) => self.object_shape_material[o as usize][s as usize],
        }
    }

    /// Whether light crossing the surface at a hit goes into a BSSRDF
    /// ([`RenderScene::subsurface`]).
    #[inline]
    pub fn has_bssrdf(&self, hit: &Hit) -> bool {
        self.subsurface && self.bssrdf_materials[self.material_index(hit) as usize]
    }

    /// Where light crosses a `subsurface` boundary at a hit into its BSSRDF: the profile
    /// there, the boundary's index and the material (probe rays look for it); `None`
    /// unless the render follows BSSRDFs ([`RenderScene::subsurface`]).
    pub fn bssrdf(&self, hit: &Hit, si: &SurfaceInteraction) -> Option<(crate::materials::bssrdf::Profile, f32, u32)> {
        if !self.has_bssrdf(hit) {
            return None;
        }
        let idx = self.material_index(hit);
        let ctx = || TexCtx { p: si.p.0, n: si.n.0, uv: si.uv, face: si.face, ..TexCtx::default() };
        let shading = Shading { textures: &self.textures, ctx, spectral: self.pass_spectrum() };
        let (profile, eta) = self.materials[idx as usize].bssrdf(shading)?;
        Some((profile, eta, idx))
    }

    /// The closest hit along the ray that no alpha mask cuts away.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let hit = self.geometry.intersect(ray)?;
        if self.has_alpha { self.unmasked(ray, hit, false) } else { Some(hit) }
    }

    /// Whether anything that no alpha mask cuts away lies along the ray (shadow rays,
    /// which v3's `shadowalpha` masks too).
    #[inline]
    pub fn intersect_p(&self, ray: &Ray) -> bool {
        if !self.has_alpha {
            return self.geometry.intersect_p(ray);
        }
        self.geometry.intersect(ray).is_some_and(|hit| self.unmasked(ray, hit, true).is_some())
    }

    /// Whether the ray finds anything: `intersect(ray).is_some()`, by the cheaper
    /// any-hit query where no alpha mask is about (shadow rays read masks their own
    /// way, so with masks this asks for the first hit).
    pub fn hits_anything(&self, ray: &Ray) -> bool {
        if self.has_alpha { self.intersect(ray).is_some() } else { self.geometry.intersect_p(ray) }
    }

    /// `hit`, or if a mask cuts it away, the first hit beyond it that none cuts, found
    /// by continuing the ray from each cut-away surface (as pbrt-v4 does). A ray through
    /// more than [`MAX_ALPHA_SKIPS`] cut-away surfaces is taken to miss.
    #[cold]
    #[inline(never)]
    fn unmasked(&self, ray: &Ray, mut hit: Hit, shadow: bool) -> Option<Hit> {
        let (mut r, mut t0) = (*ray, 0.0);
        for _ in 0..MAX_ALPHA_SKIPS {
            let Some(alpha) = self.alpha(&hit) else { return Some(Hit { t: t0 + hit.t, ..hit }) };
            let si = self.geometry.interaction(&hit);
            if !self.cuts(alpha, &si, &r, shadow) {
                return Some(Hit { t: t0 + hit.t, ..hit });
            }
            t0 += hit.t;
            r = Ray { t_max: r.t_max - hit.t, ..si.spawn_ray(r.d) };
            hit = self.geometry.intersect(&r)?;
        }
        None
    }

    fn alpha(&self, hit: &Hit) -> Option<&ShapeAlpha> {
        match self.geometry.shape_of(hit) {
            (None, s) => self.world_shape_alpha[s as usize].as_ref(),
            (Some(o), s) => self.object_shape_alpha[o as usize][s as usize].as_ref(),
        }
    }

    /// Whether the alpha mask of `light`'s shape cuts away the point drawn on it, for
    /// light samples and photons (pbrt-v4 masks them by a hash of the position).
    // DEVIATION(pbrt): appearance, `--fix area-alpha`. pbrt-v3 ignores alpha on area
    // lights, which then emit from their cut-away parts along light samples and
    // photons (but not where rays hit them); the fix masks them as pbrt-v4 does.
    #[inline]
    pub fn emission_masked(&self, light: &Light, surface: Option<&ShapeSample>) -> bool {
        let (Light::Area(a), Some(s)) = (light, surface) else { return false };
        self.has_alpha && self.alpha_rules.samples && self.emission_masked_at(a.shape, s.p.0, s.n.0, s.uv)
    }

    /// Whether shape `shape`'s alpha cuts its emission away at a point (by a hash of
    /// the position, as pbrt-v4's `AlphaMasked`).
    #[inline(never)]
    fn emission_masked_at(&self, shape: u32, p: Vec3, n: Vec3, uv: [f32; 2]) -> bool {
        let Some(alpha) = &self.world_shape_alpha[shape as usize] else { return false };
        let ctx = TexCtx { p, n, uv, ..TexCtx::default() };
        self.alpha_cuts(&alpha.alpha, alpha.rule, &ctx, || hash_unit(&bits(p)))
    }

    /// Whether alpha `v` cuts the surface at `ctx` under `rule`; `hash` in [0, 1) makes
    /// the stochastic rule's choice.
    fn alpha_cuts(&self, v: &TexValue, rule: AlphaRule, ctx: &TexCtx, hash: impl Fn() -> f32) -> bool {
        let a = self.textures.float(*v, ctx);
        match rule {
            AlphaRule::ZeroCuts => a == 0.0,
            AlphaRule::Stochastic => a < 1.0 && (a <= 0.0 || hash() > a),
        }
    }

    /// Whether `alpha` cuts the surface away where ray `r` meets it.
    fn cuts(&self, alpha: &ShapeAlpha, si: &SurfaceInteraction, r: &Ray, shadow: bool) -> bool {
        let ctx = TexCtx { p: si.p.0, n: si.n.0, uv: si.uv, face: si.face, ..TexCtx::default() };
        let test = |v: &TexValue| self.alpha_cuts(v, alpha.rule, &ctx, || ray_hash(r));
        test(&alpha.alpha) || (shadow && alpha.shadow.as_ref().is_some_and(test))
    }

    /// The BSDF at a hit (`None` for interfaces), in the shading frame.
    /// `fp`: how the point moves across a pixel, where the camera ray's differentials
    /// say (bump maps, noise textures and `ptex` use it).
    pub fn bsdf(&self, hit: &Hit, si: &SurfaceInteraction, fp: &Footprint) -> Option<Bsdf> {
        let duv = if self.needs_duv && *fp != Footprint::default() { fp.duv_dxy(si) } else { [0.0; 4] };
        let ctx = || TexCtx { p: si.p.0, n: si.n.0, uv: si.uv, dpdx: fp.dpdx, dpdy: fp.dpdy, duv, face: si.face };
        let material = match self.material(hit) {
            m if matches!(m.kind(), MaterialKind::Mix { rule: MixRule::Choose, .. }) => self.chosen(m, &ctx),
            m => m,
        };
        // A boundary that does not scatter: nothing to build (rays through media cross
        // many of these).
        if matches!(material.kind(), MaterialKind::Interface) {
            return None;
        }
        let (ns, dpdu) = match (&material.normal_map, material.bump) {
            (Some(img), _) => normal_map(img, si),
            (None, Some(d)) => bump(&self.textures, d, si, fp, duv),
            (None, None) => (si.shading.n.0, si.shading.dpdu.0),
        };
        let mut ss = (dpdu - ns * ns.dot(dpdu)).normalize_or_zero();
        if ss == Vec3::ZERO {
            ss = coordinate_system(ns).0;
        }
        let ts = ns.cross(ss);
        if let MaterialKind::Mix { .. } = material.kind() {
            let mut lobes = LobeList::default();
            self.add_mixed(material, Vec3::ONE, &ctx, &mut lobes, 0);
            return Some(lobes.bsdf([ss, ts, ns], si.n.0));
        }
        material.bsdf(Shading { textures: &self.textures, ctx, spectral: self.pass_spectrum() }, [ss, ts, ns], si.n.0)
    }

    /// `m`, or for a pbrt-v4 `mix`, the material it picks here (repeatedly, for mixes
    /// of mixes): the second with probability `amount`, decided by a hash of the point
    /// and the two materials so the same point always picks the same one.
    #[inline(never)]
    fn chosen<'a>(&'a self, mut m: &'a Material, ctx: &impl Fn() -> TexCtx) -> &'a Material {
        for _ in 0..MAX_MIX_DEPTH {
            let MaterialKind::Mix { materials, amount, rule: MixRule::Choose } = m.kind() else { break };
            let a = self.textures.float(*amount, &ctx());
            let [x, y, z] = bits(ctx().p);
            let pick = a >= 1.0 || (a > 0.0 && hash_unit(&[x, y, z, materials[0] as u64, materials[1] as u64]) < a);
            m = &self.materials[materials[pick as usize] as usize];
        }
        m
    }

    /// Appends the lobes of pbrt-v3 mix `m`'s parts, each scaled by its share of `w`.
    fn add_mixed(&self, m: &Material, w: Rgb, ctx: &impl Fn() -> TexCtx, out: &mut LobeList, depth: u32) {
        let m = self.chosen(m, ctx);
        match m.kind() {
            MaterialKind::Mix { materials, amount, .. } if depth < MAX_MIX_DEPTH => {
                let s1 = self.textures.eval(*amount, &ctx()).max(Vec3::ZERO);
                // A v3 file rendered spectrally (`--colour spectral`): the weight too.
                let s1 = self.pass_spectrum().map_or(s1, |p| p.albedo(s1));
                let s2 = (Vec3::ONE - s1).max(Vec3::ZERO);
                for (k, s) in [(0, s1), (1, s2)] {
                    self.add_mixed(&self.materials[materials[k] as usize], w * s, ctx, out, depth + 1);
                }
            }
            _ => m.add_lobes(Shading { textures: &self.textures, ctx, spectral: self.pass_spectrum() }, w, out),
        }
    }

    /// The emitting world shape hit, and which of its lights (for MIS).
    pub fn emitter(&self, hit: &Hit) -> Option<(EmitterInfo, u32)> {
        if hit.instance.is_some() {
            return None; // area lights inside object definitions are ignored, as in pbrt
        }
        let info = (*self.emitters.get(hit.shape_index as usize)?)?;
        Some((info, info.first_light + hit.local.prim()))
    }

    /// What light `idx` sends back along `ray` that found `hit` (or escaped): its
    /// emission where the ray hit that very light, the sky's where it escaped; 0 where
    /// it found anything else. For MIS with the light's density.
    pub fn chosen_light_along(&self, hit: Option<&Hit>, idx: usize, ray: &Ray) -> Rgb {
        let wi = ray.d.0;
        match hit {
            Some(hit) => match self.emitter(hit) {
                Some((_, l)) if l as usize == idx => self.emitted(hit, &self.geometry.interaction(hit), -wi),
                _ => Vec3::ZERO,
            },
            None => self.emission_of(idx, self.lights[idx].le_escaped(ray.o.0, wi)),
        }
    }

    /// Radiance leaving a hit surface toward `w` (area lights).
    pub fn emitted(&self, hit: &Hit, si: &SurfaceInteraction, w: Vec3) -> Rgb {
        let Some((e, light)) = self.emitter(hit) else { return Vec3::ZERO };
        if !(e.two_sided || si.n.0.dot(w) > 0.0) {
            return Vec3::ZERO;
        }
        if self.has_alpha && self.alpha_rules.hits && self.emission_masked_at(hit.shape_index, si.p.0, si.n.0, si.uv) {
            return Vec3::ZERO;
        }
        match &self.lights[light as usize] {
            Light::Area(a) => self.emission_of(light as usize, a.radiance(si.uv)),
            _ => Vec3::ZERO,
        }
    }

    /// Sets the wavelengths of pass `pass` (SPPM's iteration, vcm's pass) before its
    /// work starts; nothing for a scene rendered in RGB.
    pub fn begin_pass(&self, pass: u32) {
        if let Some(cell) = &self.spectral {
            cell.begin(pass);
        }
    }

    /// Whether paths carry wavelengths (cheaper than reading the pass's, per bounce).
    #[inline]
    pub fn spectral(&self) -> bool {
        self.spectral.is_some()
    }

    /// The wavelengths of the pass under way, when the scene renders spectrally.
    #[inline]
    pub fn pass_spectrum(&self) -> Option<PassSpectrum> {
        self.spectral.as_ref().map(PassCell::get)
    }

    /// A light's RGB emission as the path carries it: itself in RGB, its illuminant
    /// spectrum at the pass's wavelengths when spectral.
    #[inline]
    pub fn emission(&self, rgb: Rgb) -> Rgb {
        match &self.spectral {
            Some(cell) if rgb != Vec3::ZERO => cell.get().illuminant(rgb),
            _ => rgb,
        }
    }

    /// Light `light`'s RGB emission `rgb` as the path carries it: [`Self::emission`],
    /// but exact where the light's emission is given as a spectrum (a blackbody, a
    /// named illuminant, samples), as pbrt-v4 reads it.
    #[inline]
    pub fn emission_of(&self, light: usize, rgb: Rgb) -> Rgb {
        let Some(cell) = &self.spectral else { return rgb };
        let spectrum = match self.lights.get(light) {
            Some(Light::Area(a)) => a.spectrum.as_deref(),
            _ => self.light_spectra.get(light).and_then(Option::as_deref),
        };
        match spectrum {
            Some(s) if rgb != Vec3::ZERO => s.lanes(rgb, &cell.get()),
            _ => self.emission(rgb),
        }
    }

    /// What a path's value adds to a pixel, in output RGB.
    #[inline]
    pub fn film_rgb(&self, v: Rgb) -> DVec3 {
        match &self.spectral {
            Some(cell) => cell.get().to_rgb(v.as_dvec3()),
            None => v.as_dvec3(),
        }
    }

    /// What a camera sample or splat whose film RGB ([`Self::film_rgb`]) is `rgb` is
    /// multiplied by: the film's bound over it where it is over, otherwise 1.
    #[inline]
    pub fn clamp_factor(&self, rgb: DVec3) -> f64 {
        self.clamp.map_or(1.0, |c| c.factor(rgb))
    }

    /// A camera sample or splat `v` as the film records it: scaled down to the film's
    /// bound where it is over.
    #[inline]
    pub fn clamped(&self, v: Rgb) -> Rgb {
        match self.clamp {
            Some(c) => v * c.factor(self.film_rgb(v)) as f32,
            None => v,
        }
    }

    /// [`Self::film_rgb`] of a value summed in f64.
    #[inline]
    pub fn film_rgb_f64(&self, v: DVec3) -> DVec3 {
        match &self.spectral {
            Some(cell) => cell.get().to_rgb(v),
            None => v,
        }
    }

    /// Whether a spectral path that meets `hit` keeps only its first wavelength (the
    /// material there disperses).
    #[inline]
    pub fn disperses(&self, hit: &Hit) -> bool {
        self.dispersive && self.material(hit).disperses(&self.materials)
    }

    /// A spectral path that builds a dispersing BSDF keeps only its first wavelength
    /// (pbrt-v4's `TerminateSecondary`): the others end and the first's weight grows
    /// by the lanes' count, once per path (`terminated` says whether it has).
    #[inline]
    pub fn terminate_if_dispersed(&self, hit: &Hit, beta: &mut Rgb, terminated: &mut bool) {
        if !*terminated && self.disperses(hit) {
            *beta *= crate::spectrum::transport::TERMINATE;
            *terminated = true;
        }
    }
}

/// The shading normal and ∂p/∂u after displacing the surface by the float texture `d`
/// along its shading normal (pbrt's `Bump`). d is differenced over half the pixel
/// footprint in u and in v where the camera ray's differentials give one, else over
/// .0005 (pbrt's steps). The normal stays on the side of the geometric one.
fn bump(textures: &Textures, d: TexValue, si: &SurfaceInteraction, fp: &Footprint, duv: [f32; 4]) -> (Vec3, Vec3) {
    let [dudx, dvdx, dudy, dvdy] = fp.duv_dxy(si);
    let step = |a: f32, b: f32| match 0.5 * (a.abs() + b.abs()) {
        0.0 => 0.0005,
        s => s,
    };
    let (du, dv) = (step(dudx, dudy), step(dvdx, dvdy));
    let sh = &si.shading;
    let (p, [u, v]) = (si.p.0, si.uv);
    let n = sh.dpdu.0.cross(sh.dpdv.0);
    let at = |p: Vec3, uv: [f32; 2], n: Vec3| {
        textures.float(d, &TexCtx { p, n: n.normalize_or_zero(), uv, dpdx: fp.dpdx, dpdy: fp.dpdy, duv, face: si.face })
    };
    let d_u = at(p + du * sh.dpdu.0, [u + du, v], n + du * si.dndu.0);
    let d_v = at(p + dv * sh.dpdv.0, [u, v + dv], n + dv * si.dndv.0);
    let d0 = at(p, [u, v], si.n.0);
    let dpdu = sh.dpdu.0 + (d_u - d0) / du * sh.n.0 + d0 * sh.dndu.0;
    let dpdv = sh.dpdv.0 + (d_v - d0) / dv * sh.n.0 + d0 * sh.dndv.0;
    let ns = dpdu.cross(dpdv).normalize_or_zero();
    match ns {
        Vec3::ZERO => (sh.n.0, sh.dpdu.0),
        ns if ns.dot(si.n.0) < 0.0 => (-ns, dpdu),
        ns => (ns, dpdu),
    }
}

/// The shading normal and ∂p/∂u that normal map `img` gives (pbrt-v4's `NormalMap`):
/// its RGB at (u, 1 − v), repeating, read as a normal in the frame of the shading ∂p/∂u
/// and normal. The normal stays on the side of the geometric one.
fn normal_map(img: &crate::imageio::Texels, si: &SurfaceInteraction) -> (Vec3, Vec3) {
    let sh = &si.shading;
    let rgb = crate::imageio::lookup(img, si.uv[0], 1.0 - si.uv[1], crate::imageio::Wrap::Repeat, true);
    let local = (2.0 * rgb - Vec3::ONE).normalize_or_zero();
    let (n, dpdu) = (sh.n.0, sh.dpdu.0);
    let s = (dpdu - n * n.dot(dpdu)).normalize_or_zero();
    if local == Vec3::ZERO || s == Vec3::ZERO {
        return (n, dpdu);
    }
    let t = n.cross(s);
    let ns = (s * local.x + t * local.y + n * local.z).normalize();
    let dpdu = (dpdu - ns * ns.dot(dpdu)).normalize_or_zero() * dpdu.length();
    if ns.dot(si.n.0) < 0.0 { (-ns, dpdu) } else { (ns, dpdu) }
}

/// Mixes of mixes are followed this deep (the scene has no cycles; this bounds the work).
const MAX_MIX_DEPTH: u32 = 16;

/// A number in [0, 1) fixed by the given words (floats by their bits).
fn hash_unit(words: &[u64]) -> f32 {
    (crate::sampling::hash(words) >> 40) as f32 / (1u64 << 24) as f32
}

/// The bits of a vector's coordinates, for [`hash_unit`].
fn bits(v: Vec3) -> [u64; 3] {
    v.to_array().map(|x| x.to_bits() as u64)
}

/// Cut-away surfaces one ray may pass through before it is taken to miss.
pub const MAX_ALPHA_SKIPS: u32 = 1024;

/// A number in [0, 1) fixed by the ray's origin and direction (pbrt-v4's `HashFloat(o, d)`
/// plays this part): a ray meets the same stochastic alpha decision every time.
fn ray_hash(r: &Ray) -> f32 {
    let ([ox, oy, oz], [dx, dy, dz]) = (bits(r.o.0), bits(r.d.0));
    hash_unit(&[ox, oy, oz, dx, dy, dz])
}

/// One light per primitive of each emitting world shape: a quadric, each triangle of
/// a mesh, each patch of a bilinear mesh.
/// How area lights are made from their shapes.
#[derive(Clone, Copy, Debug)]
struct EmitterRules {
    /// v4's `power` is the whole shape's, not each primitive's.
    // DEVIATION(pbrt): appearance, `--fix mesh-power`. pbrt-v4 applies `power` to each
    // triangle or patch of a mesh on its own, so a mesh of n of them emits n times the
    // power asked for, the smaller ones brighter; the fix spreads it over the shape.
    spread_power: bool,
    /// Spheres, disks and cylinders are sampled as pbrt samples them (`--fix
    /// shape-sampling` turns it off; see `shapes::pbrt_sampling`).
    pbrt_sampling: bool,
    /// An alpha mask cuts light samples away ([`AlphaEmission::samples`]), so they
    /// need their (u, v).
    masks_samples: bool,
}

impl EmitterRules {
    fn new(scene: &SceneDescription, bidirectional: bool, alpha: AlphaEmission) -> EmitterRules {
        EmitterRules {
            spread_power: scene.syntax == Syntax::V3 || scene.fixes.has(Fix::MeshPower),
            pbrt_sampling: !scene.fixes.has(Fix::ShapeSampling) && !bidirectional,
            masks_samples: alpha.samples,
        }
    }
}

/// Each light's box for [`RenderScene::may_reach_light`]: its emitter's, for an area
/// light (one per triangle of an emitting mesh, so made on all threads).
fn light_boxes(lights: &[Light], geometry: &Geometry) -> Vec<Option<crate::math::Bounds3>> {
    use rayon::prelude::*;
    lights
        .par_iter()
        .map(|l| match l {
            Light::Area(a) => Some(geometry.shapes.piece_bounds(&a.emitter)),
            _ => None,
        })
        .collect()
}

/// The area lights of the world shapes (`area_lights[i]`: shape i's, whose alpha is
/// `alpha[i]`), appended to `lights`; each emitting shape's first light.
fn area_lights(
    g: &Geometry,
    area_lights: &[Option<u32>],
    alpha: &[Option<ShapeAlpha>],
    params: &[AreaLightDesc],
    rules: EmitterRules,
    lights: &mut Vec<Light>,
) -> Vec<Option<EmitterInfo>> {
    let mut emitters = vec![None; area_lights.len()];
    for (i, area) in area_lights.iter().enumerate() {
        let Some(a) = area else { continue };
        let desc = &params[*a as usize];
        let first_light = lights.len() as u32;
        // Only an emission image and an alpha mask read a sample's (u, v).
        let reads_uv = desc.image.is_some() || (rules.masks_samples && alpha[i].is_some());
        let pieces = g.shapes.pieces(g.world_shape(i), rules.pbrt_sampling);
        let per_piece = !rules.spread_power && desc.power.is_some() && pieces.len() > 1;
        let l = desc.emission(pieces.iter().map(|(_, a)| *a).sum());
        for (emitter, area) in pieces {
            let emitter = emitter.reading_uv(reads_uv);
            let l = if per_piece { desc.emission(area) } else { l };
            // The BVH dropped zero-area primitives; one whose area underflows in f32
            // still keeps its slot (lights are found by primitive) but emits nothing.
            let area = area as f32;
            let l = if area > 0.0 { l } else { Vec3::ZERO };
            let (two_sided, image, spectrum) = (desc.two_sided, desc.image.clone(), desc.spectrum.clone());
            lights.push(Light::Area(AreaLight { emitter, shape: i as u32, l, two_sided, area, image, spectrum }));
        }
        emitters[i] = Some(EmitterInfo { two_sided: desc.two_sided, first_light });
    }
    emitters
}

/// The emitting media and where their photons start.
fn medium_emitters(
    media: &[crate::media::Medium],
    scene: &SceneDescription,
) -> Vec<(u32, crate::media::emitters::EmissionPoints)> {
    let points = |(i, m)| {
        let region = medium_region(scene, i as u32)?;
        crate::media::emitters::EmissionPoints::new(m, region).map(|e| (i as u32, e))
    };
    media.iter().enumerate().filter_map(points).collect()
}

/// A box holding every point of medium `m`: the bounds of the world shapes it is the
/// inside of, where it is nowhere else (not outside a shape, not the camera's or a
/// light's, not in an object); the scene's bounds otherwise.
fn medium_region(scene: &SceneDescription, m: u32) -> Option<[glam::DVec3; 2]> {
    let open = scene.camera_medium == Some(m)
        || scene.lights.iter().any(|l| l.medium == Some(m))
        || scene
            .objects
            .iter()
            .flat_map(|o| &o.shapes)
            .any(|s| s.media.inside == Some(m) || s.media.outside == Some(m))
        || scene.shapes.iter().any(|s| s.media.outside == Some(m) && s.media.is_transition());
    let inside = scene.shapes.iter().filter(|s| s.media.inside == Some(m) && s.media.is_transition());
    match inside.filter_map(|s| scene.local_bounds(s)).reduce(crate::scene::union) {
        Some(b) if !open => Some(b),
        _ => scene.world_bounds(),
    }
}

/// Where the passes' wavelengths are kept, when paths carry them.
fn pass_cell(scene: &SceneDescription) -> Option<PassCell> {
    let draw = scene.film.buckets.map_or(Draw::Visible, |b| b.draw());
    scene.spectral.then(|| PassCell::new(scene.color_space, scene.film.sensor.clone(), draw))
}

/// The film's sample clamp as it applies to the film RGB of the render's paths: through
/// a named camera's curves where paths carry wavelengths (with RGB paths a camera is
/// seen as the CIE observer).
fn film_clamp(scene: &SceneDescription) -> Option<Clamp> {
    let film = &scene.film;
    let sensor = film.sensor.as_ref().filter(|_| scene.spectral).map(|s| &s.xyz_from_sensor);
    film.clamp.map(|rule| Clamp::new(rule, film.scale as f64, scene.color_space, sensor))
}

/// The power of two nearest `total` (1 for no light).
fn photon_scale(total: f64) -> f64 {
    if total > 0.0 && total.is_finite() { total.log2().round().clamp(-1000.0, 1000.0).exp2() } else { 1.0 }
}
