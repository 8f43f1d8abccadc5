//! Camera subpaths: one per pixel and pass. At each vertex they count what every
//! technique gives there: emitters found, next-event estimation, connections to the
//! vertices of one light subpath, and light vertices merged within the radius.

use super::light::{LightPass, LightVertex, is_delta, occluded, occluded_between};
use super::mis::{self, ConnectPdfs, DirectPdfs, Partial};
use super::{Pass, Technique, Techniques};
use crate::accel::Hit;
use crate::integrators::grid::Grid;
use crate::integrators::sppm::{Surface, camera_ray, surface};
use crate::interaction::{Footprint, SurfaceInteraction};
use crate::lights::Light;
use crate::materials::{Bsdf, TransportMode};
use crate::math::{Point3, Ray, Vector3};
use crate::sampling::{Rng, Sampler, SamplerKind, SobolSample, hash};
use crate::spectrum::Rgb;
use glam::{DVec3, Vec3};

/// What the camera subpaths of a pass share.
pub struct Cameras<'a> {
    pub pass: &'a Pass<'a>,
    pub lights: &'a LightPass,
    pub grid: Option<&'a Grid>,
    pub seed: u64,
    pub iteration: u32,
    pub sampler: SamplerKind,
    pub differential_scale: f32,
}

/// A camera subpath's vertex on a surface.
struct Vertex<'a> {
    si: &'a SurfaceInteraction,
    bsdf: &'a Bsdf,
    /// Unit direction toward the vertex before.
    wo: Vec3,
    partial: Partial,
    /// Edges from the camera.
    len: u32,
}

impl Vertex<'_> {
    fn point(&self) -> (Vec3, Vec3, Vec3) {
        (self.si.p.0, self.si.p_error, self.si.n.0)
    }
}

impl Cameras<'_> {
    /// The radiance pixel `i` of the rendered window (`width` wide) gets from its
    /// camera subpath this pass.
    pub fn pixel(&self, i: usize, width: usize) -> Rgb {
        let (x, y) =
            ((self.pass.origin.0 as usize + i % width) as u64, (self.pass.origin.1 as usize + i / width) as u64);
        let pixel = [x as f32, y as f32];
        match self.sampler {
            SamplerKind::Sobol => {
                let mut s = SobolSample::new(hash(&[self.seed, x, y, 2]), self.iteration);
                self.path(i, pixel, &mut s)
            }
            SamplerKind::Random => {
                let mut rng = Rng::new(hash(&[self.seed, x, y, self.iteration as u64, 2]));
                self.path(i, pixel, &mut rng)
            }
        }
    }

    fn path(&self, i: usize, pixel: [f32; 2], s: &mut impl Sampler) -> Rgb {
        let (pass, scene) = (self.pass, self.pass.scene);
        let (mut ray, mut diff) = camera_ray(scene, pixel, s, self.differential_scale);
        let camera_pdf = scene.camera.pdf_we(&ray).1 as f64 * pass.film_pixels;
        let mut partial = Partial::camera(camera_pdf, pass.lt_count());
        let light_path = self.lights.path(i % pass.light_paths as usize);
        // The last vertex, and where rays left it (past any interfaces since, light
        // densities are measured from there).
        let (mut beta, mut color, mut prev, mut origin) = (Vec3::ONE, Vec3::ZERO, ray.o.0, ray.o.0);
        let (mut len, mut passes) = (0u32, 0u32);
        loop {
            let Some(hit) = scene.intersect(&ray) else {
                if pass.techniques.uses(Technique::EmitterHit) && len < pass.max_len {
                    color += beta * self.escaped(ray.d.0.normalize(), origin, len, partial);
                }
                break;
            };
            let si = scene.geometry.interaction(&hit);
            let fp = diff.take().map(|d| Footprint::new(&si, &d)).unwrap_or_default();
            let bsdf = match surface(scene, &hit, &si, &fp, &mut ray, &mut passes) {
                Surface::Bsdf(b) => b,
                Surface::PassedThrough => continue,
                Surface::Abandon => break,
            };
            len += 1;
            let wo = -ray.d.0.normalize();
            let dist2 = (si.p.0 - prev).length_squared() as f64;
            partial.arrive(Some(dist2), wo.dot(si.n.0) as f64);
            let v = Vertex { si: &si, bsdf: &bsdf, wo, partial, len };
            if pass.techniques.uses(Technique::EmitterHit) {
                color += beta * self.emitted(&hit, &v, origin, dist2);
            }
            if len >= pass.max_len || wo.dot(si.n.0) == 0.0 {
                break;
            }
            if !is_delta(&bsdf) {
                color += beta * self.at_vertex(&v, light_path, s);
            }
            let Some((b, p)) = scatter(pass, &v, beta, s) else { break };
            (beta, partial, prev) = (b.0, p, si.p.0);
            ray = si.spawn_ray(Vector3(b.1));
            origin = ray.o.0;
        }
        color
    }

    /// What next-event estimation, connections and merging give at a vertex.
    fn at_vertex(&self, v: &Vertex, light_path: &[LightVertex], s: &mut impl Sampler) -> Rgb {
        let t = self.pass.techniques;
        let mut c = Vec3::ZERO;
        if t.uses(Technique::Direct) {
            c += self.direct(v, s);
        }
        // Alone, each counts one strategy, so that every path is counted once: the
        // light subpath's first vertex for connections, the camera subpath's first for
        // merging (as photon mapping does).
        if t.uses(Technique::Connect) {
            let first_only = t == Techniques::Only(Technique::Connect);
            for lv in light_path.iter().take_while(|lv| lv.len + v.len < self.pass.max_len) {
                if !first_only || lv.len == 1 {
                    c += self.connect(v, lv);
                }
            }
        }
        if t.uses(Technique::Merge)
            && (t != Techniques::Only(Technique::Merge) || v.len == 1)
            && let Some(grid) = self.grid
        {
            c += self.merge(v, grid);
        }
        c
    }

    /// Light from an area light the path has found, weighted against the techniques
    /// that could have found the same point on it. `prev`: where the ray left the
    /// vertex before (offset off its surface, as light samples are taken from there).
    fn emitted(&self, hit: &Hit, v: &Vertex, prev: Vec3, dist2: f64) -> Rgb {
        let scene = self.pass.scene;
        let le = scene.emitted(hit, v.si, v.wo);
        if le == Vec3::ZERO || v.len == 1 {
            return le;
        }
        let Some((_, idx)) = scene.emitter(hit) else { return Vec3::ZERO };
        let light = &scene.lights[idx as usize];
        let pick = scene.light_power.pmf(idx as usize) as f64;
        let cos = v.wo.dot(v.si.n.0).abs() as f64;
        let direct = pick * light.pdf_li(&scene.geometry.shapes, prev, -v.wo) as f64 * cos / dist2;
        let out = Ray::new(v.si.p, Vector3(v.wo));
        let (pos, dir) = light.pdf_le(&scene.geometry.shapes, scene.world, &out, v.si.n.0);
        le * self.pass.techniques.weight(mis::emitter_hit(v.partial, direct, pick * (pos * dir) as f64))
    }

    /// Light from lights at infinity along a ray that left the scene after `len` edges.
    fn escaped(&self, d: Vec3, prev: Vec3, len: u32, partial: Partial) -> Rgb {
        let scene = self.pass.scene;
        let mut sum = Vec3::ZERO;
        for (k, light) in scene.lights.iter().enumerate() {
            let le = light.le_escaped(d);
            if le == Vec3::ZERO {
                continue;
            }
            if len == 0 {
                sum += le;
                continue;
            }
            let pick = scene.light_power.pmf(k) as f64;
            let direct = pick * light.pdf_li(&scene.geometry.shapes, prev, d) as f64;
            let (pos, dir) =
                light.pdf_le(&scene.geometry.shapes, scene.world, &Ray::new(Point3(prev), Vector3(-d)), -d);
            let w = mis::emitter_hit(partial, direct, pick * (pos * dir) as f64);
            sum += le * self.pass.techniques.weight(w);
        }
        sum
    }

    /// Next-event estimation: one point drawn on a light chosen by power.
    fn direct(&self, v: &Vertex, s: &mut impl Sampler) -> Rgb {
        let scene = self.pass.scene;
        let (pick_u, u) = (s.get1d(), s.get2d());
        let Some((k, pick)) = scene.light_power.sample(pick_u) else { return Vec3::ZERO };
        let light = &scene.lights[k];
        let Some(ls) = light.sample_li(&scene.geometry.shapes, v.si.p.0, u) else { return Vec3::ZERO };
        if ls.pdf <= 0.0 || ls.li == Vec3::ZERO || scene.emission_masked(light, ls.surface.as_ref()) {
            return Vec3::ZERO;
        }
        let e = v.bsdf.eval(v.wo, ls.wi, TransportMode::Radiance);
        if e.f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let (direct, cos_light, emission) = light_densities(self.pass, light, &ls, v.si.p.0);
        let pick = pick as f64;
        let pdfs = DirectPdfs {
            bsdf: if ls.delta { 0.0 } else { e.pdf as f64 },
            bsdf_rev: e.pdf_rev as f64,
            direct: pick * direct,
            emission: pick * emission,
            cos_here: ls.wi.dot(v.si.n.0).abs() as f64,
            cos_light,
        };
        let w = self.pass.techniques.weight(mis::direct(v.partial, pdfs));
        let c = e.f * ls.wi.dot(v.bsdf.shading_normal()).abs() * ls.li * (w / (pick as f32 * ls.pdf));
        let blocked = match ls.p_light {
            Some(p) => occluded(scene, v.point(), p),
            None => scene.intersect_p(&v.si.spawn_ray(Vector3(ls.wi))),
        };
        if blocked || !c.is_finite() { Vec3::ZERO } else { c }
    }

    /// A camera vertex connected to a light vertex.
    fn connect(&self, v: &Vertex, lv: &LightVertex) -> Rgb {
        let d = lv.p - v.si.p.0;
        let dist2 = d.length_squared();
        if dist2 == 0.0 {
            return Vec3::ZERO;
        }
        let dir = d / dist2.sqrt();
        let ec = v.bsdf.eval(v.wo, dir, TransportMode::Radiance);
        let el = lv.bsdf.eval(lv.wo, -dir, TransportMode::Importance);
        if ec.f == Vec3::ZERO || el.f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let (cos_c, cos_l, d2) = (dir.dot(v.si.n.0).abs() as f64, dir.dot(lv.ng).abs() as f64, dist2 as f64);
        let pdfs = ConnectPdfs {
            camera_a: ec.pdf as f64 * cos_l / d2,
            light_a: el.pdf as f64 * cos_c / d2,
            camera_rev: ec.pdf_rev as f64,
            light_rev: el.pdf_rev as f64,
        };
        let w = self.pass.techniques.weight(mis::connect(lv.partial, v.partial, pdfs, lv.len, self.pass.factors));
        let g = dir.dot(v.bsdf.shading_normal()).abs() * lv.adjoint_cos(-dir) / dist2;
        let c = (lv.beta * el.f * ec.f * (g * w)).as_dvec3() * self.pass.scene.photon_scale;
        let c = c.as_vec3();
        if c == Vec3::ZERO || !c.is_finite() || occluded_between(self.pass.scene, v.point(), (lv.p, lv.p_error, lv.ng))
        {
            return Vec3::ZERO;
        }
        c
    }

    /// Light vertices within the pass's radius merged at a camera vertex: their
    /// density estimate.
    fn merge(&self, v: &Vertex, grid: &Grid) -> Rgb {
        let pass = self.pass;
        let (p, r2) = (v.si.p.0, pass.radius * pass.radius);
        let mut sum = DVec3::ZERO;
        grid.gather(p, |k| {
            let lv = &self.lights.vertices[k as usize];
            // Direct light (one edge from the light) is never merged (see `mis`).
            if lv.len < 2 || lv.len + v.len > pass.max_len || (lv.p - p).length_squared() > r2 {
                return;
            }
            let e = v.bsdf.eval(v.wo, lv.wo, TransportMode::Radiance);
            if e.f == Vec3::ZERO {
                return;
            }
            let w =
                pass.techniques.weight(mis::merge(lv.partial, v.partial, e.pdf as f64, e.pdf_rev as f64, pass.factors));
            sum += (e.f * lv.beta * w).as_dvec3();
        });
        let norm = pass.scene.photon_scale / (std::f64::consts::PI * (r2 as f64) * pass.light_paths as f64);
        (sum * norm).as_vec3()
    }
}

/// A light sample's densities as the weights take them: (solid-angle density of the
/// sample, a point light's being the squared distance; the cosine at the light; the
/// density of the light emitting toward `p`), each without the light's choice.
fn light_densities(pass: &Pass, light: &Light, ls: &crate::lights::LightSample, p: Vec3) -> (f64, f64, f64) {
    let scene = pass.scene;
    let from = ls.p_light.unwrap_or(p + ls.wi);
    let n = ls.surface.map_or(-ls.wi, |s| s.n.0);
    let (pos, dir) = light.pdf_le(&scene.geometry.shapes, scene.world, &Ray::new(Point3(from), Vector3(-ls.wi)), n);
    let (pos, dir) = (pos as f64, dir as f64);
    match light {
        Light::Area(_) => (ls.pdf as f64, n.dot(ls.wi).abs() as f64, pos * dir),
        Light::Infinite(_) => (ls.pdf as f64, 1.0, pos * dir),
        // Delta positions and directions: their densities cancel (taken as 1).
        Light::Point(_) | Light::Spot(_) => ((from - p).length_squared() as f64, 1.0, dir),
        Light::Distant(_) => (1.0, 1.0, pos),
    }
}

/// Samples the BSDF at a camera vertex: ((throughput, direction), partial sums)
/// after it; `None` when absorbed or ended by Russian roulette.
fn scatter(pass: &Pass, v: &Vertex, beta: Rgb, s: &mut impl Sampler) -> Option<((Rgb, Vec3), Partial)> {
    let b = v.bsdf;
    let smp = b.sample_f(v.wo, s.get2d(), s.get1d(), TransportMode::Radiance)?;
    let pdf = if smp.proportional { b.pdf_mode(v.wo, smp.wi, TransportMode::Radiance) } else { smp.pdf };
    let pdf_rev = if smp.specular { pdf } else { b.pdf_mode(smp.wi, v.wo, TransportMode::Importance) };
    if !(pdf > 0.0 && smp.pdf > 0.0) {
        return None;
    }
    let mut beta = beta * smp.f * (smp.wi.dot(b.shading_normal()).abs() / smp.pdf);
    // pbrt's path tracer's roulette, after three bounces.
    if v.len > 3 {
        let q = (1.0 - beta.max_element()).max(0.05);
        if s.get1d() < q {
            return None;
        }
        beta /= 1.0 - q;
    }
    if !beta.is_finite() || beta == Vec3::ZERO {
        return None;
    }
    let mut partial = v.partial;
    let cos = smp.wi.dot(v.si.n.0).abs() as f64;
    partial.scatter(cos, pdf as f64, pdf_rev as f64, smp.specular, true, pass.factors);
    Some(((beta, smp.wi), partial))
}
