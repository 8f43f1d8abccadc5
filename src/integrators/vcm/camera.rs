//! Camera subpaths: one per pixel and pass. At each vertex, on a surface or in a
//! medium, they count what every technique gives there: emitters found (and media's
//! emission along the way), next-event estimation, connections to the vertices of one
//! light subpath, and light vertices merged within the radius.
//! Files asking for pbrt-v3's `whitted` or `directlighting` take their own path ([`direct`]).

mod direct;
mod prefix;

pub use prefix::RAYS as PREFIX_RAYS;

use super::light::{ByKind, LightPass, LightVertex};
use super::links::{Links, MAX_DRAWS, Pool, Sample};
use super::mis::{self, ConnectPdfs, DirectPdfs, Partial};
use super::vertex::{self, Place, Scatterer};
use super::{Pass, Technique, Techniques};
use crate::accel::Hit;
use crate::guiding::{Mix, Record, Toward};
use crate::integrators::grid::{Grid, Site};
use crate::integrators::sppm::{Surface, camera_ray, surface};
use crate::integrators::subsurface;
use crate::interaction::{Footprint, SurfaceInteraction, light_sample_point};
use crate::lights::Light;
use crate::materials::TransportMode;
use crate::math::ray::RayDifferential;
use crate::math::{Normal3, Point3, Ray, Vector3};
use crate::memory::prefetch;
use crate::sampling::{Rng, Sampler, SamplerKind, SobolSample, hash};
use crate::spectrum::Rgb;
use glam::{DVec3, Vec3};

/// A BSSRDF under a boundary: its profile, the boundary's index and the material.
type Bssrdf = (crate::materials::bssrdf::Profile, f32, u32);

/// What the camera subpaths of a pass share.
pub struct Cameras<'a> {
    pub pass: &'a Pass<'a>,
    pub lights: &'a LightPass,
    pub grid: Option<&'a Grid>,
    pub seed: u64,
    pub iteration: u32,
    pub sampler: SamplerKind,
    pub differential_scale: f32,
    /// The pixels that trace more rays for the light they see through perfect
    /// specular chains ([`prefix`]; `Cameras::prefix_marks`), if any.
    pub prefix: Option<&'a [bool]>,
    /// The pass's light vertices by cell, where camera vertices draw their connections
    /// from them all ([`super::links`]).
    pub pool: Option<&'a Pool>,
}

/// What one camera subpath gives its pixel: the light of the techniques that trace
/// from the camera (emitters found, next-event estimation, connections), apart from
/// that of merging light vertices, by the pilot's kinds ([`super::light::ByKind`]); and
/// the work it took ([`super::balance`] weighs both).
#[derive(Clone, Debug, Default)]
pub struct PixelSample {
    pub traced: Rgb,
    pub merged: ByKind,
    pub work: Work,
    /// What the subpath found past its guidable vertices, for the guide's training
    /// (only when the pass trains, [`Pass::training`]).
    pub records: crate::guiding::Records,
    /// The connections it made, for the table of cached connections (only when the
    /// pass learns it, [`Pass::link_cells`]).
    pub links: Vec<Sample>,
}

impl PixelSample {
    pub fn total(&self) -> Rgb {
        self.traced + self.merged.iter().sum::<Rgb>()
    }

    /// Scales each part lane by lane so that the total is `total` (a lane whose total
    /// is 0 stays as it is).
    fn rescale(&mut self, total: Rgb) {
        let now = self.total();
        let f = Rgb::select(now.cmpne(Rgb::ZERO), total / now, Rgb::ONE);
        self.traced *= f;
        self.merged.iter_mut().for_each(|m| *m *= f);
    }
}

/// Work done, counted in whole units so that sums are the same in any order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Work {
    /// Rays traced: closest hits and shadow rays.
    pub rays: u64,
    /// Vertices scattered at (a BSDF built and sampled).
    pub vertices: u64,
    /// Light vertices a merge lookup looked at.
    pub candidates: u64,
    /// Connections that traced their shadow ray, and those of them it found clear.
    pub connections: u64,
    pub connections_clear: u64,
}

impl std::ops::Add for Work {
    type Output = Work;
    fn add(self, o: Work) -> Work {
        Work {
            rays: self.rays + o.rays,
            vertices: self.vertices + o.vertices,
            candidates: self.candidates + o.candidates,
            connections: self.connections + o.connections,
            connections_clear: self.connections_clear + o.connections_clear,
        }
    }
}

/// A camera subpath's vertex on a surface or in a medium.
struct Vertex<'a> {
    place: Place,
    at: &'a Scatterer,
    /// Unit direction toward the vertex before.
    wo: Vec3,
    partial: Partial,
    /// Edges from the camera.
    len: u32,
    /// Merging here is a technique: the camera subpath has not bounced specularly
    /// after a diffuse bounce (`mis`).
    merges: bool,
    /// The camera subpath has bounced only specularly before: light subpaths' caustics
    /// merged here are seen as they are ([`ByKind`]).
    first_diffuse: bool,
    /// The subpath kept only its first wavelength (dispersion).
    terminated: bool,
    /// Where light left a BSSRDF's interior toward the subpath (`subsurface`): no light
    /// subpath reaches the vertices before it, so no technique that ends there is one,
    /// and merging here is none.
    exit: bool,
    /// The guided mixture the subpath samples from here, if any ([`Pass::guide_at`]).
    guide: Option<Mix<'a>>,
    /// The guided mixture a light subpath reaching here would draw `wo` from, if light
    /// subpaths are guided here ([`Pass::light_guided`]).
    light_toward: Option<Toward>,
}

impl<'a> Vertex<'a> {
    /// A vertex that merges nothing, past a diffuse bounce, unguided: those of paths
    /// that count only some techniques (`direct`, `prefix`), which set the rest.
    fn plain(place: Place, at: &'a Scatterer, wo: Vec3, partial: Partial, len: u32) -> Vertex<'a> {
        let (merges, first_diffuse, terminated, exit) = (false, false, false, false);
        let (guide, light_toward) = (None, None);
        Vertex { place, at, wo, partial, len, merges, first_diffuse, terminated, exit, guide, light_toward }
    }

    /// The vertex a camera subpath arrived at, `len` edges from the camera (`history`:
    /// how it scattered before), with the guided mixtures of both subpaths there. Not
    /// yet ended by dispersion (the caller sets that).
    fn arrived(
        pass: &'a Pass,
        place: Place,
        at: &'a Scatterer,
        wo: Vec3,
        partial: Partial,
        len: u32,
        history: &History,
    ) -> Vertex<'a> {
        let merges = !history.past_diffuse_specular && !at.is_delta();
        let (guide, light_toward) = (pass.guide_at(place.p, wo, at), light_toward(pass, &place, at, wo));
        let (first_diffuse, terminated, exit) = (!history.diffuse, false, false);
        Vertex { place, at, wo, partial, len, merges, first_diffuse, terminated, exit, guide, light_toward }
    }

    /// f and both densities toward `wi`, the forward one the camera walk's and the
    /// reverse one a light walk's (each its guided mixture's, where it has one).
    fn eval(&self, wi: Vec3) -> crate::materials::BsdfEval {
        if self.place.crosses_into_bssrdf(self.wo, wi) {
            return crate::materials::BsdfEval::NONE;
        }
        let mut e = self.at.eval(self.wo, wi, TransportMode::Radiance);
        if let Some(m) = &self.guide {
            e.pdf = m.pdf(e.pdf, wi);
        }
        if let Some(t) = &self.light_toward {
            e.pdf_rev = t.pdf(e.pdf_rev);
        }
        e
    }
}

/// A connection's factor for the first lane's growth on both subpaths: it counts once
/// (a subpath that ended its other wavelengths stands for all of them).
fn once(v: &Vertex, lv: &LightVertex) -> f32 {
    if v.terminated && lv.terminated { crate::spectrum::transport::ONCE } else { 1.0 }
}

/// A direction a camera subpath left a guidable vertex along, waiting for the light
/// found past it: `before`, what the subpath had found when it left, and `beta`, its
/// throughput after, turn what it found in the end into the light arriving along `d`.
struct Pending {
    p: Vec3,
    d: Vec3,
    pdf: f32,
    beta: Rgb,
    before: Rgb,
}

impl Pending {
    /// The record, once the subpath has found `total` in all: the light past the vertex
    /// over the throughput that carried it (channel by channel), its mean over the
    /// sampling density.
    fn record(&self, total: Rgb) -> Record {
        let found = total - self.before;
        let li = Vec3::select(self.beta.cmpgt(Vec3::ZERO), found / self.beta, Vec3::ZERO);
        let energy = (li.element_sum() / 3.0 / self.pdf).max(0.0);
        Record { p: self.p, d: self.d, energy: if energy.is_finite() { energy } else { 0.0 } }
    }
}

/// Whether a camera subpath has scattered diffusely, and specularly after that (then
/// merging is no technique at its vertices beyond, see `mis`).
#[derive(Clone, Copy, Debug, Default)]
struct History {
    diffuse: bool,
    past_diffuse_specular: bool,
}

impl History {
    /// The subpath left a vertex as `l` says (a BSSRDF's exit ends its prefix and
    /// starts afresh, as a diffuse bounce).
    fn left(&mut self, l: &Leave, in_prefix: &mut bool) {
        if l.through_bssrdf {
            (self.diffuse, self.past_diffuse_specular, *in_prefix) = (true, false, false);
        } else {
            self.past_diffuse_specular |= l.specular && self.diffuse;
            self.diffuse |= !l.specular;
        }
    }
}

/// How a camera subpath leaves a vertex ([`Cameras::leave`]): its throughput,
/// direction and partial sums after it, and the vertex it leaves from (a BSSRDF's exit,
/// when it went through one).
struct Leave {
    beta: Rgb,
    wi: Vec3,
    /// The density `wi` was drawn with (the guided mixture's, where there is one).
    pdf: f32,
    partial: Partial,
    from: Place,
    specular: bool,
    through_bssrdf: bool,
}

/// Where a camera ray goes next ([`Cameras::next`]). Made and taken apart once per
/// vertex: boxing the vertex would allocate there.
#[allow(clippy::large_enum_variant)]
enum Next {
    /// A vertex in a medium, or on a surface with its hit.
    Vertex(Place, Scatterer, Vec3, Option<(Hit, SurfaceInteraction)>),
    /// It crossed a surface without a material: trace on.
    Through,
    /// It left the scene.
    Escaped,
    /// It crossed too many surfaces without a material.
    Abandon,
}

impl Cameras<'_> {
    /// The radiance pixel `i` of the rendered window (`width` wide) gets from its
    /// camera subpath this pass.
    pub fn pixel(&self, i: usize, width: usize) -> PixelSample {
        let (x, y) =
            ((self.pass.origin.0 as usize + i % width) as u64, (self.pass.origin.1 as usize + i / width) as u64);
        let pixel = [x as f32, y as f32];
        let (mut out, prefix) = match self.sampler {
            SamplerKind::Sobol => {
                let mut s = SobolSample::new(hash(&[self.seed, x, y, 2]), self.iteration);
                self.path(i, pixel, &mut s)
            }
            SamplerKind::Random => {
                let mut rng = Rng::new(hash(&[self.seed, x, y, self.iteration as u64, 2]));
                self.path(i, pixel, &mut rng)
            }
        };
        let rays = self.prefix_rays(i);
        let scene = self.pass.scene;
        // Each ray with the rest of the path is one of pbrt's camera samples, which
        // its film clamps one by one (`camera::clamp`).
        // DEVIATION(pbrt): appearance, with vcm's estimator. A clamp takes off what
        // the estimator's samples have over the bound; ours spread a highlight over
        // more, smaller samples than pbrt's path tracer (README, "Other differences").
        // A spectral film's buckets take the RGB's factor (pbrt-v4 clamps them apart,
        // by the largest wavelength's radiance), and the clamp sees the pixel filter's
        // sample weight, which pbrt applies after it (about ±1 for pbrt-v4's filters).
        let rest = out.total();
        let (mut sum, mut clamped) = (prefix, scene.clamped(prefix + rest));
        for stream in 1..rays {
            let extra = self.extra_prefix(pixel, stream as u64, &mut out.work);
            sum += extra;
            if scene.clamp.is_some() {
                clamped += scene.clamped(extra + rest);
            }
        }
        out.traced += sum / rays as f32;
        if scene.clamp.is_some() {
            out.rescale(clamped / rays as f32);
        }
        out
    }

    /// A camera subpath: what it gives its pixel, and apart from that its prefix light
    /// ([`prefix`]: found before its first vertex that is not perfectly specular, in
    /// vacuum), which the pixel may average with more rays'.
    fn path(&self, i: usize, pixel: [f32; 2], s: &mut impl Sampler) -> (PixelSample, Rgb) {
        let (pass, scene) = (self.pass, self.pass.scene);
        let (mut ray, mut diff, weight) = camera_ray(scene, pixel, s, self.differential_scale, self.pass.time);
        let mut out = PixelSample::default();
        if weight == 0.0 {
            return (out, Vec3::ZERO);
        }
        let camera_pdf = scene.camera.pdf_we(&ray).1 as f64 * pass.film_pixels;
        let mut partial = Partial::camera(camera_pdf, pass.lt_count());
        if pass.techniques == Techniques::Direct {
            return (self.direct_path(ray, diff, Vec3::splat(weight), partial, s), Vec3::ZERO);
        }
        let light_path = self.lights.path(i % pass.light_paths.max(1) as usize);
        // The last vertex, and where rays left it (past any interfaces since, light
        // densities are measured from there).
        let (mut beta, mut prev, mut origin) = (Vec3::splat(weight), ray.o.0, ray.o.0);
        // What refraction has divided `beta` by so far (pbrt's etaScale), for roulette.
        let mut eta_scale = 1.0f32;
        let (mut len, mut passes, mut medium) = (0u32, 0u32, scene.camera_medium);
        let mut history = History::default();
        // The prefix light, and whether the subpath is still in its prefix.
        let (mut prefix, mut in_prefix, mut terminated) = (Vec3::ZERO, true, false);
        // Directions left along, whose light is known when the subpath ends (training).
        let mut pending = Vec::new();
        loop {
            in_prefix &= medium.is_none();
            let (place, at, wo, surf) =
                match self.next(&mut ray, &mut diff, (&mut passes, &mut medium), &mut beta, &mut out, s) {
                    Next::Vertex(place, at, wo, surf) => (place, at, wo, surf),
                    Next::Through => continue,
                    Next::Escaped => {
                        if pass.techniques.uses(Technique::EmitterHit) && len < pass.max_len {
                            let found = beta * self.escaped(ray.d.0.normalize(), origin, len, partial);
                            *if in_prefix { &mut prefix } else { &mut out.traced } += found;
                        }
                        break;
                    }
                    Next::Abandon => break,
                };
            len += 1;
            let dist2 = (place.p - prev).length_squared() as f64;
            partial.arrive(Some(dist2), at.measure(wo, place.ng));
            let v = Vertex::arrived(pass, place, &at, wo, partial, len, &history);
            if pass.records_importance_at(&at, len) {
                out.records.importance.push(Record { p: place.p, d: wo, energy: beta.element_sum() / 3.0 });
            }
            if let Some((hit, si)) = &surf {
                if pass.techniques.uses(Technique::EmitterHit) {
                    let found = beta * self.emitted(hit, si, &v, origin, dist2);
                    *if in_prefix { &mut prefix } else { &mut out.traced } += found;
                }
                scene.terminate_if_dispersed(hit, &mut beta, &mut terminated);
            }
            let mut v = Vertex { terminated, ..v };
            if let Some(links) = pass.links.as_deref().filter(|_| len > 1) {
                v.partial.count_edge(links.count(place.p, prev));
            }
            in_prefix &= at.is_delta();
            if len >= pass.max_len || (surf.is_some() && wo.dot(place.ng) == 0.0) {
                break;
            }
            out.work.vertices += 1;
            if !at.is_delta() {
                self.add_at_vertex(&v, beta, light_path, s, &mut out);
            }
            let Some(l) = self.leave(&v, surf.as_ref(), (beta, &mut eta_scale), (light_path, &mut out), s) else {
                break;
            };
            if pass.records_at(&at) && !l.through_bssrdf {
                pending.push(Pending { p: place.p, d: l.wi, pdf: l.pdf, beta: l.beta, before: out.total() });
            }
            history.left(&l, &mut in_prefix);
            (beta, partial, prev) = (l.beta, l.partial, l.from.p);
            ray = l.from.spawn(l.wi);
            (medium, origin) = (l.from.toward(l.wi), ray.o.0);
        }
        let total = out.total();
        out.records.radiance = pending.iter().map(|q: &Pending| q.record(total)).collect();
        (out, prefix)
    }

    /// Samples how the subpath leaves `v` (`beta`: its throughput there), through a
    /// BSSRDF where the sampled direction crosses into one (adding what the exit
    /// vertex gives to `out`); `None` where the subpath ends.
    fn leave(
        &self,
        v: &Vertex,
        surf: Option<&(Hit, SurfaceInteraction)>,
        (beta, eta_scale): (Rgb, &mut f32),
        (light_path, out): (&[LightVertex], &mut PixelSample),
        s: &mut impl Sampler,
    ) -> Option<Leave> {
        let eta_before = *eta_scale;
        let sc = scatter(self.pass, v, (beta, eta_scale), s)?;
        let (wi, pdf, partial, specular) = (sc.wi, sc.pdf, sc.partial, sc.specular);
        let below = self.bssrdf_below(v, surf, wi);
        let Some(bssrdf) = below else {
            return Some(Leave { beta: sc.beta, wi, pdf, partial, from: v.place, specular, through_bssrdf: false });
        };
        // Refraction's η⁻² is paid back where the light leaves (`Lobe::NormalizedFresnel`).
        *eta_scale = eta_before;
        let (sc, from) = self.through_bssrdf(v, bssrdf, (sc.beta, eta_scale), light_path, out, s)?;
        let (beta, wi, pdf, partial) = (sc.beta, sc.wi, sc.pdf, sc.partial);
        Some(Leave { beta, wi, pdf, partial, from, specular: false, through_bssrdf: true })
    }

    /// The BSSRDF the direction `wi` sampled at `v` crosses into, if any
    /// ([`crate::render::RenderScene::subsurface`]): its profile, the boundary's index
    /// and the material.
    fn bssrdf_below(&self, v: &Vertex, surf: Option<&(Hit, SurfaceInteraction)>, wi: Vec3) -> Option<Bssrdf> {
        if !v.place.crosses_into_bssrdf(v.wo, wi) {
            return None;
        }
        let (hit, si) = surf?;
        self.pass.scene.bssrdf(hit, si)
    }

    /// A camera subpath that refracted into a subsurface material at `v` (throughput
    /// `beta` after it): the point where the light it sees left the interior, what
    /// next-event estimation and connections give there, and the subpath sampled on
    /// from it (throughput and direction, partial sums, the vertex); `None` where it
    /// ends. Its partial sums start afresh there: no technique's light subpath crosses
    /// a BSSRDF (they end where they would), so none reaches the vertices before.
    fn through_bssrdf(
        &self,
        v: &Vertex,
        (profile, eta, material): Bssrdf,
        (beta, eta_scale): (Rgb, &mut f32),
        light_path: &[LightVertex],
        out: &mut PixelSample,
        s: &mut impl Sampler,
    ) -> Option<(Scattered, Place)> {
        let scene = self.pass.scene;
        let Scatterer::Surface(bsdf) = v.at else { return None };
        let (po, time) = (v.place.p, v.place.time);
        let entry = subsurface::Entry { profile, eta, material, po, frame: bsdf.frame(), time };
        let exit = subsurface::exit(scene, &entry, s)?;
        let beta = beta * exit.weight;
        out.work.rays += 1;
        let place = Place::on_surface(scene, &exit.hit, &exit.si, v.place.toward(v.wo));
        let at = Scatterer::Surface(exit.bsdf);
        let wo = exit.si.shading.n.0;
        // Merging is a technique at the vertices beyond (not at this one: `exit`), whatever
        // the subpath did before.
        let ve = Vertex {
            place,
            at: &at,
            wo,
            partial: Partial::default(),
            merges: true,
            exit: true,
            first_diffuse: false,
            guide: None,
            light_toward: light_toward(self.pass, &place, &at, wo),
            ..*v
        };
        out.work.vertices += 1;
        self.add_at_vertex(&ve, beta, light_path, s, out);
        Some((scatter(self.pass, &ve, (beta, eta_scale), s)?, place))
    }

    /// Where the ray finds its next vertex, in a medium or on a surface; adds the light
    /// media emit along the way (found by camera paths alone, weight 1, as pbrt's
    /// volpath finds it).
    fn next(
        &self,
        ray: &mut Ray,
        diff: &mut Option<RayDifferential>,
        (passes, medium): (&mut u32, &mut Option<u32>),
        beta: &mut Rgb,
        out: &mut PixelSample,
        s: &mut impl Sampler,
    ) -> Next {
        let (pass, scene) = (self.pass, self.pass.scene);
        let hit = scene.intersect(ray);
        out.work.rays += 1;
        if let Some(m) = *medium
            && pass.techniques.uses(Technique::EmitterHit)
        {
            let t = hit.map_or(f32::INFINITY, |h| h.t);
            let lanes = scene.pass_spectrum();
            out.traced += *beta * scene.media[m as usize].emission(ray.o.0, ray.d.0, t, s, lanes.as_ref());
        }
        if let Some((place, at, wo)) = vertex::flight(scene, ray, (hit.as_ref(), *medium), beta, s) {
            return Next::Vertex(place, at, wo, None);
        }
        let Some(hit) = hit else { return Next::Escaped };
        let si = scene.geometry.interaction(&hit);
        let fp = diff.take().map(|d| Footprint::new(&si, &d)).unwrap_or_default();
        match surface(scene, (&hit, &si), &fp, ray, passes, medium) {
            Surface::Bsdf(bsdf) => {
                let place = Place::on_surface(scene, &hit, &si, *medium);
                Next::Vertex(place, Scatterer::Surface(bsdf), -ray.d.0.normalize(), Some((hit, si)))
            }
            Surface::PassedThrough => Next::Through,
            Surface::Abandon => Next::Abandon,
        }
    }

    /// Adds to `out` what the techniques give at vertex `v` (throughput `beta`).
    fn add_at_vertex(
        &self,
        v: &Vertex,
        beta: Rgb,
        light_path: &[LightVertex],
        s: &mut impl Sampler,
        out: &mut PixelSample,
    ) {
        let (traced, merged) = self.at_vertex(v, light_path, s, (&mut out.work, &mut out.links));
        out.traced += beta * traced;
        for (m, add) in out.merged.iter_mut().zip(merged) {
            *m += beta * add;
        }
    }

    /// What next-event estimation and connections give at a vertex, and what merging
    /// gives, by the pilot's kinds ([`ByKind`]); `work` counts the shadow rays and merge
    /// candidates.
    fn at_vertex(
        &self,
        v: &Vertex,
        light_path: &[LightVertex],
        s: &mut impl Sampler,
        (work, learnt): (&mut Work, &mut Vec<Sample>),
    ) -> (Rgb, ByKind) {
        let t = self.pass.techniques;
        let mut c = Vec3::ZERO;
        if t.uses(Technique::Direct) {
            c += self.direct(v, s);
            work.rays += if self.pass.nee_all { self.pass.scene.lights.len() as u64 } else { 1 };
        }
        // Alone, each counts one strategy, so that every path is counted once: the
        // light subpath's first vertex for connections, the camera subpath's first for
        // merging (as photon mapping does).
        if t.uses(Technique::Connect) {
            let first_only = t == Techniques::Only(Technique::Connect);
            if let (Some(pool), Some(links)) = (self.pool, self.pass.links.as_deref()) {
                c += self.connect_drawn(v, (pool, links), s, work, first_only);
            } else {
                for lv in light_path.iter().take_while(|lv| lv.len + v.len < self.pass.max_len) {
                    if !first_only || lv.len == 1 {
                        c += self.connect(v, lv, s, None, (work, learnt));
                        work.rays += 1;
                    }
                }
            }
        }
        if t.uses(Technique::Merge)
            && v.merges
            && !v.exit
            && (t != Techniques::Only(Technique::Merge) || v.len == 1)
            && let Some(grid) = self.grid
        {
            return (c, self.merge(v, grid, &mut work.candidates));
        }
        (c, [Vec3::ZERO; 4])
    }

    /// Light from an area light the path has found, weighted against the techniques
    /// that could have found the same point on it. `prev`: where the ray left the
    /// vertex before (offset off its surface, as light samples are taken from there).
    fn emitted(&self, hit: &Hit, si: &SurfaceInteraction, v: &Vertex, prev: Vec3, dist2: f64) -> Rgb {
        let scene = self.pass.scene;
        let le = scene.emitted(hit, si, v.wo);
        if le == Vec3::ZERO || v.len == 1 {
            return le;
        }
        let Some((_, idx)) = scene.emitter(hit) else { return Vec3::ZERO };
        let light = &scene.lights[idx as usize];
        let pick = scene.light_power.pmf(idx as usize) as f64;
        let cos = v.wo.dot(si.n.0).abs() as f64;
        let direct =
            self.pass.nee_pick(idx as usize) * light.pdf_li(&scene.geometry.shapes, prev, -v.wo) as f64 * cos / dist2;
        let out = Ray::new(si.p, Vector3(v.wo));
        let (pos, dir) = light.pdf_le(&scene.geometry.shapes, scene.world, &out, si.n.0);
        let dir = self.pass.maps[idx as usize]
            .as_ref()
            .map_or(dir, |m| dir * m.factor(light, scene.world, prev, (si.n.0, v.wo)));
        let direct_light = v.len == 2 || self.pass.techniques == Techniques::Direct;
        le * self.pass.techniques.weight(mis::emitter_hit(v.partial, direct, pick * (pos * dir) as f64, direct_light))
    }

    /// Light from lights at infinity along a ray that left the scene after `len` edges.
    fn escaped(&self, d: Vec3, prev: Vec3, len: u32, partial: Partial) -> Rgb {
        let scene = self.pass.scene;
        let mut sum = Vec3::ZERO;
        for (k, light) in scene.lights.iter().enumerate() {
            let le = scene.emission_of(k, light.le_escaped(prev, d));
            if le == Vec3::ZERO {
                continue;
            }
            if len == 0 {
                sum += le;
                continue;
            }
            let pick = scene.light_power.pmf(k) as f64;
            let direct = self.pass.nee_pick(k) * light.pdf_li(&scene.geometry.shapes, prev, d) as f64;
            let (pos, dir) =
                light.pdf_le(&scene.geometry.shapes, scene.world, &Ray::new(Point3(prev), Vector3(-d)), -d);
            let direct_light = len == 1 || self.pass.techniques == Techniques::Direct;
            let w = mis::emitter_hit(partial, direct, pick * (pos * dir) as f64, direct_light);
            sum += le * self.pass.techniques.weight(w);
        }
        sum
    }

    /// Next-event estimation: one point drawn on a light chosen by power, or on every
    /// light when the pass samples them all ([`Pass::nee_all`]).
    fn direct(&self, v: &Vertex, s: &mut impl Sampler) -> Rgb {
        let scene = self.pass.scene;
        if self.pass.nee_all {
            return (0..scene.lights.len()).map(|k| self.direct_from(v, k, 1.0, s.get2d(), s)).sum();
        }
        // The light is picked from its sample's first number (`Pick`'s rest).
        let u = s.get2d();
        let Some(pick) = scene.light_power.pick(u[0]) else { return Vec3::ZERO };
        self.direct_from(v, pick.index, pick.pmf, [pick.rest, u[1]], s)
    }

    /// One next-event estimate from light `k`, chosen with probability `pick`.
    fn direct_from(&self, v: &Vertex, k: usize, pick: f32, u: [f32; 2], s: &mut impl Sampler) -> Rgb {
        let scene = self.pass.scene;
        let light = &scene.lights[k];
        let from = match v.at {
            Scatterer::Surface(b) => {
                let (place, v4) = (&v.place, scene.syntax == crate::parser::Syntax::V4);
                light_sample_point(v4, Point3(place.p), place.p_error, Normal3(place.ng), b.sides(), v.wo).0
            }
            Scatterer::Medium(_) => v.place.p,
        };
        let Some(ls) = light.sample_li(&scene.geometry.shapes, from, u) else { return Vec3::ZERO };
        if ls.pdf <= 0.0 || ls.li == Vec3::ZERO || scene.emission_masked(light, ls.surface.as_ref()) {
            return Vec3::ZERO;
        }
        // Light that reaches the far side of a BSSRDF's boundary straight through its
        // transmission lobes: this estimate is the only technique that finds it.
        let crossing = v.place.crosses_into_bssrdf(v.wo, ls.wi);
        let e = match crossing {
            true => v.at.eval(v.wo, ls.wi, TransportMode::Radiance),
            false => v.eval(ls.wi),
        };
        if e.f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let (direct, cos_light, emission) = light_densities(self.pass, k, &ls, from);
        let pdfs = DirectPdfs {
            bsdf: if ls.delta { 0.0 } else { e.pdf as f64 },
            bsdf_rev: e.pdf_rev as f64,
            direct: pick as f64 * direct,
            emission: scene.light_power.pmf(k) as f64 * emission,
            cos_here: v.at.measure(ls.wi, v.place.ng),
            cos_light,
        };
        let only_direct = self.pass.techniques == Techniques::Direct;
        let w = match crossing {
            true => crossing_weight(scene.syntax, ls.delta, pdfs),
            false => self.pass.techniques.weight(mis::direct(v.partial, pdfs, v.len == 1 || only_direct)),
        };
        let c = e.f * v.at.cos(ls.wi) * scene.emission_of(k, ls.li) * (w / (pick * ls.pdf));
        if !c.is_finite() || c == Vec3::ZERO {
            return Vec3::ZERO;
        }
        c * match (ls.p_light, only_direct) {
            (Some(p), false) => vertex::visible(scene, &v.place, p, s),
            (None, false) => vertex::visible_along(scene, &v.place, ls.wi, s),
            // pbrt-v3's whitted and directlighting leave media out.
            (Some(p), true) => vertex::unoccluded(scene, &vertex::toward_point(&v.place, p)),
            (None, true) => vertex::unoccluded(scene, &v.place.spawn(ls.wi)),
        }
    }

    /// Connections to [`Links::draws`] light vertices drawn from the whole pass
    /// (`first_only`: of those one edge from their light).
    fn connect_drawn(
        &self,
        v: &Vertex,
        (pool, links): (&Pool, &Links),
        s: &mut impl Sampler,
        work: &mut Work,
        first_only: bool,
    ) -> Rgb {
        let per = self.pass.light_paths as f64 * links.draws as f64;
        // Drawn all first, so that the vertices' memory loads while the first is used.
        let mut drawn = [(0u32, 0f64); MAX_DRAWS];
        let mut n = 0;
        for _ in 0..links.draws.min(MAX_DRAWS as u32) {
            if let Some((i, q)) = pool.draw(links, v.place.p, s.get2d()) {
                prefetch(self.lights.vertex(i));
                drawn[n] = (i, q);
                n += 1;
            }
        }
        let mut c = Vec3::ZERO;
        for &(i, q) in &drawn[..n] {
            let lv = self.lights.vertex(i);
            if lv.len + v.len < self.pass.max_len && (!first_only || lv.len == 1) {
                c += self.connect(v, lv, s, Some(per * q), (work, &mut Vec::new()));
                work.rays += 1;
            }
        }
        c
    }

    /// A camera vertex connected to a light vertex: its pair's, or one drawn from the
    /// whole pass with density `drawn` (per light subpath and draw). A pass that
    /// learns the table of cached connections notes the connection in `learnt`; `work`
    /// counts it and whether its shadow ray was clear.
    fn connect(
        &self,
        v: &Vertex,
        lv: &LightVertex,
        s: &mut impl Sampler,
        drawn: Option<f64>,
        (work, learnt): (&mut Work, &mut Vec<Sample>),
    ) -> Rgb {
        let pass = self.pass;
        let d = lv.place.p - v.place.p;
        let dist2 = d.length_squared();
        if dist2 == 0.0 {
            return Vec3::ZERO;
        }
        let dir = d / dist2.sqrt();
        let (ec, el) = (v.eval(dir), lv.eval(-dir, pass));
        if ec.f == Vec3::ZERO || el.f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let (cos_c, cos_l, d2) = (v.at.measure(dir, v.place.ng), lv.at.measure(dir, lv.place.ng), dist2 as f64);
        let pdfs = ConnectPdfs {
            camera_a: ec.pdf as f64 * cos_l / d2,
            light_a: el.pdf as f64 * cos_c / d2,
            camera_rev: ec.pdf_rev as f64,
            light_rev: el.pdf_rev as f64,
        };
        let mut f = (lv.factors(pass), v.at.factors(&pass.factors));
        if v.exit {
            f.1.vm = 0.0; // no merging at the exit of a BSSRDF
        }
        let count = pass.links.as_ref().map_or(1.0, |l| l.count(lv.place.p, v.place.p));
        let w = mis::connect(lv.partial, v.partial, pdfs, lv.len, f, v.merges, count);
        let g = v.at.cos(dir) * lv.adjoint_cos(-dir) / dist2;
        // A pair's connection (`drawn` None) keeps the arithmetic it always had.
        let w = match drawn {
            None => pass.techniques.weight(w),
            Some(density) => (pass.techniques.weight(w) as f64 / density) as f32,
        };
        let carried = lv.beta * el.f * ec.f;
        let c = (carried * (g * w * once(v, lv))).as_dvec3() * pass.scene.photon_scale;
        let c = c.as_vec3();
        if c == Vec3::ZERO || !c.is_finite() {
            return Vec3::ZERO;
        }
        let seen = vertex::visible_between(pass.scene, &v.place, &lv.place, s);
        work.connections += 1;
        work.connections_clear += u64::from(seen != Vec3::ZERO);
        if let Some(cells) = &pass.link_cells {
            let unweighted = (carried * (g * once(v, lv))).as_dvec3() * pass.scene.photon_scale;
            let value = crate::spectrum::luminance((unweighted.as_vec3() * seen).max(Vec3::ZERO));
            learnt.push(Sample { camera: cells.of(v.place.p), light: cells.of(lv.place.p), value });
        }
        c * seen
    }

    /// Light vertices within the pass's radius merged at a camera vertex: their
    /// density estimate, over a disc on a surface and a ball in a medium (where only
    /// light vertices in media count, and on a surface only those on surfaces).
    fn merge(&self, v: &Vertex, grid: &Grid, candidates: &mut u64) -> ByKind {
        let pass = self.pass;
        let (p, r2, in_medium) = (v.place.p, pass.radius * pass.radius, v.at.in_medium());
        let f = v.at.factors(&pass.factors);
        if f.vm == 0.0 {
            return [Vec3::ZERO; 4];
        }
        let mut sum = [DVec3::ZERO; 4];
        // The site is the spot's point: light vertices out of reach are passed over
        // without reading their spot. Those in reach are listed first, with their
        // spots and vertices asked of the cache, so that the misses overlap (they were
        // half the lookup's time on `doorway`).
        let near = |k: u32, site: &Site| {
            *candidates += 1;
            let d2 = (site.p - p).length_squared();
            let near = d2 <= r2 || d2.is_nan(); // (as the test was: not beyond r)
            if near {
                prefetch(&self.lights.spots[k as usize]);
                prefetch(self.lights.vertex(k));
            }
            near
        };
        grid.gather_picked(p, near, |k| {
            let spot = &self.lights.spots[k as usize];
            // Direct light (one edge from the light) is never merged (see `mis`): first
            // light vertices are not in the grid.
            if spot.edges() + v.len > pass.max_len || spot.in_medium() != in_medium {
                return;
            }
            let lv = self.lights.vertex(k);
            let e = v.eval(lv.wo);
            if e.f == Vec3::ZERO {
                return;
            }
            let w = pass.techniques.weight(mis::merge(lv.partial, v.partial, e.pdf as f64, e.pdf_rev as f64, f));
            let c = e.f * lv.beta * (w * once(v, lv));
            sum[super::light::kind(lv.half, lv.after_specular && v.first_diffuse)] += c.as_dvec3();
        });
        let disc = std::f64::consts::PI * (r2 as f64);
        let kernel = if in_medium { disc * pass.radius as f64 * (4.0 / 3.0) } else { disc };
        let norm = pass.scene.photon_scale / (kernel * pass.light_paths as f64);
        sum.map(|s| (s * norm).as_vec3())
    }
}

/// The weight of a next-event estimate whose direction crosses into a BSSRDF
/// (`Place::crosses_into_bssrdf`). A BSDF sample that way enters the BSSRDF in pbrt's
/// path tracers, so no other technique finds this light. pbrt-v3's direct-light
/// estimate still counts it in full (its own BSDF-sampled half traces toward the light).
/// pbrt-v4's weighs it by the balance heuristic against its BSDF density and drops
/// the rest, which its BSDF sample never finds.
fn crossing_weight(syntax: crate::parser::Syntax, delta: bool, p: DirectPdfs) -> f32 {
    match syntax == crate::parser::Syntax::V4 && !delta {
        true => (p.direct / (p.direct + p.bsdf)) as f32,
        false => 1.0,
    }
}

/// A light sample's densities as the weights take them: (solid-angle density of the
/// sample, a point light's being the squared distance; the cosine at the light; the
/// density of the light emitting toward `p`, aimed or not), each without the light's
/// choice.
fn light_densities(pass: &Pass, k: usize, ls: &crate::lights::LightSample, p: Vec3) -> (f64, f64, f64) {
    let (scene, light) = (pass.scene, &pass.scene.lights[k]);
    let from = ls.p_light.unwrap_or(p + ls.wi);
    let n = ls.surface.map_or(-ls.wi, |s| s.n.0);
    let (pos, dir) = light.pdf_le(&scene.geometry.shapes, scene.world, &Ray::new(Point3(from), Vector3(-ls.wi)), n);
    // Where a light's own emission is mapped, the mixture's density over it.
    let q = pass.maps[k].as_ref().map_or(1.0, |m| m.factor(light, scene.world, p, (n, -ls.wi)) as f64);
    let (pos, dir) = (pos as f64, dir as f64);
    match light {
        Light::Area(_) => (ls.pdf as f64, n.dot(ls.wi).abs() as f64, pos * (dir * q)),
        Light::Infinite(_) => (ls.pdf as f64, 1.0, pos * dir),
        // Delta positions and directions: their densities cancel (taken as 1).
        Light::Point(_) | Light::Spot(_) | Light::Goniometric(_) | Light::Projection(_) => {
            let dir = pass.cones[k].map_or(dir, |c| c.density(-ls.wi));
            ((from - p).length_squared() as f64, 1.0, dir)
        }
        Light::Distant(_) => (1.0, 1.0, pos * q),
    }
}

/// The guided mixture a light subpath reaching a camera vertex would draw the
/// vertex's `wo` from, if light subpaths are guided there.
fn light_toward(pass: &Pass, place: &Place, at: &Scatterer, wo: Vec3) -> Option<Toward> {
    let g = pass.light_guided(place.p, wo, at)?;
    pass.light_mix(g).map(|m| m.toward(wo))
}

/// How a camera subpath left a vertex ([`scatter`]).
struct Scattered {
    beta: Rgb,
    wi: Vec3,
    /// The density `wi` was drawn with.
    pdf: f32,
    partial: Partial,
    specular: bool,
}

/// Samples the BSDF (or phase function, or the guided mixture where the vertex has
/// one) at a camera vertex: the throughput, direction and partial sums after it;
/// `None` when absorbed or ended by Russian roulette. `eta_scale`: what refraction has
/// divided the throughput by so far, updated here.
fn scatter(pass: &Pass, v: &Vertex, (beta, eta_scale): (Rgb, &mut f32), s: &mut impl Sampler) -> Option<Scattered> {
    let cos = |wi: Vec3| v.at.cos(wi);
    let mut smp = match &v.guide {
        Some(mix) => v.at.sample_guided(v.wo, s, (mix, TransportMode::Radiance), cos)?,
        None => v.at.sample(v.wo, s, TransportMode::Radiance, |wi, _| cos(wi))?,
    };
    if let Some(t) = &v.light_toward {
        smp.pdf_rev = t.pdf(smp.pdf_rev);
    }
    let mut beta = beta * smp.f * smp.scale;
    *eta_scale *= v.at.eta_scale(v.wo, smp.wi);
    // pbrt's path tracer's roulette, after three bounces and only below a throughput of
    // one, with refraction's radiance scaling undone: inside glass the throughput is
    // η² too small, and cutting paths for it made fireflies of those that got out (on
    // `cornell-glass`, a path reflected inside the sphere reached the light 2.5 times
    // as bright as it left the camera).
    let rr = (beta * *eta_scale).max_element();
    if v.len > 3 && rr < 1.0 {
        let q = (1.0 - rr).max(0.05);
        if s.get1d() < q {
            return None;
        }
        beta /= 1.0 - q;
    }
    if !beta.is_finite() || beta == Vec3::ZERO {
        return None;
    }
    let mut partial = v.partial;
    let m = v.at.measure(smp.wi, v.place.ng);
    let merges_here = v.merges && !v.exit;
    partial.scatter(m, smp.pdf as f64, smp.pdf_rev as f64, smp.specular, merges_here, v.at.factors(&pass.factors));
    Some(Scattered { beta, wi: smp.wi, pdf: smp.pdf, partial, specular: smp.specular })
}
