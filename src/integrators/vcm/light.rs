//! Light subpaths: emitted from a light chosen by power, scattered by the BSDFs'
//! adjoints and, in media, by phase functions; each vertex that is not purely
//! specular is kept (for connections and merging) and seen through the lens (light
//! tracing).

use super::emission_map;
use super::mis::{self, Factors, Partial};
use super::vertex::{self, Place, Scatterer};
use super::{Pass, Technique, Techniques};
use crate::guiding::{Guided, Toward};
use crate::integrators::sppm::{Surface, surface};
use crate::interaction::Footprint;
use crate::lights::Light;
use crate::materials::TransportMode;
use crate::math::{Ray, Vector3};
use crate::sampling::{Rng, Sampler, SamplerKind, SobolSample, hash};
use crate::spectrum::{Rgb, luminance};
use glam::Vec3;
use rayon::prelude::*;

/// Light subpaths per parallel work item.
const CHUNK: u64 = 1024;

/// Which half of a pass's light subpaths subpath `k` is in: even and odd (the pilot
/// compares the halves, [`super::balance`]).
pub fn half(k: u64) -> bool {
    k % 2 == 1
}

/// Where the pilot files a light-side contribution ([`super::balance`]): by the half of
/// the pass's subpaths it came from, and whether it is a caustic (see [`ByKind`]).
pub fn kind(half: bool, caustic: bool) -> usize {
    half as usize + 2 * caustic as usize
}

/// The pilot's classes of light-side contributions, indexed by [`kind`]: even, odd,
/// even caustic, odd caustic. A caustic is light a light subpath brought through a
/// specular bounce to a surface the camera sees directly or through specular bounces
/// only: no camera technique finds it, so its noise grows as the subpaths fall.
pub type ByKind = [Rgb; 4];

/// How many of a pass's `n` light subpaths are in each half.
pub fn halves(n: u64) -> [u64; 2] {
    [n.div_ceil(2), n / 2]
}

/// A light subpath's vertex on a surface that is not purely specular, or in a medium.
#[derive(Clone, Debug)]
pub struct LightVertex {
    pub place: Place,
    /// Unit direction toward the vertex before (where the light came from).
    pub wo: Vec3,
    /// Throughput up to here, divided by the scene's photon scale.
    pub beta: Rgb,
    pub at: Scatterer,
    pub partial: Partial,
    /// Edges from the light.
    pub len: u32,
    /// The half of the pass's subpaths its subpath is in ([`half`]).
    pub half: bool,
    /// The light subpath's bounce before it was specular (a caustic where the camera
    /// sees it directly, [`ByKind`]).
    pub after_specular: bool,
    /// The subpath kept only its first wavelength (dispersion).
    pub terminated: bool,
    /// The guided mixture a camera subpath reaching here would draw `wo` from, if the
    /// vertex is guided ([`Pass::guide_at`]).
    pub guide: Option<Toward>,
    /// Where the light subpath draws its next direction from a guide of importance,
    /// if it does ([`Pass::light_guided`]).
    pub light_guide: Option<Guided>,
}

impl LightVertex {
    /// f and both densities toward `wi`, carrying importance; the forward density is
    /// the light walk's, the reverse one a camera walk's (each its guided mixture's,
    /// where it has one).
    pub fn eval(&self, wi: Vec3, pass: &Pass) -> crate::materials::BsdfEval {
        if self.place.crosses_into_bssrdf(self.wo, wi) {
            return crate::materials::BsdfEval::NONE;
        }
        let mut e = self.at.eval(self.wo, wi, TransportMode::Importance);
        if let Some(g) = &self.guide {
            e.pdf_rev = g.pdf(e.pdf_rev);
        }
        if let Some(m) = self.light_guide.and_then(|g| pass.light_mix(g)) {
            e.pdf = m.pdf(e.pdf, wi);
        }
        e
    }

    /// The cosine factor of leaving along `wi` for the adjoint BSDF: |ωi·ns| with
    /// pbrt's correction for shading normals, |ωo·ns| |ωi·ng| / |ωo·ng| (Veach §5.3),
    /// so light subpaths carry what camera subpaths would; none in a medium.
    pub fn adjoint_cos(&self, wi: Vec3) -> f32 {
        let ng = self.place.ng;
        match &self.at {
            Scatterer::Surface(b) => self.wo.dot(b.shading_normal()).abs() * wi.dot(ng).abs() / self.wo.dot(ng).abs(),
            Scatterer::Medium(_) => 1.0,
        }
    }

    /// The cosine the throughput takes leaving along `wi` sampled here: the adjoint one,
    /// but on a specular bounce of a file that asks for SPPM |ωi·ns| alone, as pbrt's
    /// photons cross glass and mirrors. The correction's 1/|ωo·ng| is unbounded where
    /// light grazes a smooth-shaded mesh's facets: on `caustic-ring`'s glass icosphere
    /// it made about one light subpath in 250 passes 80 times brighter than its kind
    /// (`docs/vcm.md`, "Specular bounces of light subpaths"). From a delta light only
    /// light subpaths sample such a chain (`L S… D`); from an area light, camera
    /// subpaths that find it through the same glass carry the corrected value and the
    /// weights mix the two, as pbrt's SPPM adds its camera paths through glass to its
    /// photons. Files asking for `bdpt` or `path` keep pbrt's bdpt's correction.
    pub fn leaving_cos(&self, wi: Vec3, specular: bool, pass: &Pass) -> f32 {
        match specular && !pass.correct_specular {
            true => self.at.cos(wi),
            false => self.adjoint_cos(wi),
        }
    }

    /// The pass's merging constants at this vertex.
    pub fn factors(&self, pass: &Pass) -> Factors {
        self.at.factors(&pass.factors)
    }
}

/// Paths traced, surfaces hit and vertices scattered at.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counts {
    pub paths: u64,
    pub hits: u64,
    pub vertices: u64,
}

impl std::ops::Add for Counts {
    type Output = Counts;
    fn add(self, o: Counts) -> Counts {
        Counts { paths: self.paths + o.paths, hits: self.hits + o.hits, vertices: self.vertices + o.vertices }
    }
}

/// A pass's light subpaths: their vertices in subpath order, where each begins, and
/// the lists of light-tracing splats (pixel, radiance), four per work item (list j
/// holds kind j mod 4's, [`kind`]). The vertices stay in the lists their work items
/// wrote (subpaths `CHUNK`·c onwards in list c): joined into one list they took their
/// room twice at the join (`doorway`'s vcm render peaked at 126 MB against 95).
#[derive(Default)]
pub struct LightPass {
    chunks: Vec<Vec<LightVertex>>,
    /// The number of list c's first vertex, counting through the lists in order.
    chunk_first: Vec<u32>,
    /// Vertex i's [`Spot`].
    pub spots: Vec<Spot>,
    /// Subpath k holds vertices `starts[k]..starts[k + 1]`.
    pub starts: Vec<u32>,
    pub splats: Vec<Vec<(u32, Rgb)>>,
    pub counts: Counts,
}

impl LightPass {
    /// The vertices of light subpath `k`, shortest first.
    pub fn path(&self, k: usize) -> &[LightVertex] {
        match (self.starts.get(k), self.starts.get(k + 1)) {
            (Some(&a), Some(&b)) => {
                let c = k / CHUNK as usize;
                let first = self.chunk_first[c];
                &self.chunks[c][(a - first) as usize..(b - first) as usize]
            }
            _ => &[],
        }
    }

    /// Vertex `i` (of all the pass's, in order).
    pub fn vertex(&self, i: u32) -> &LightVertex {
        let c = list_holding(&self.chunk_first, i);
        &self.chunks[c][(i - self.chunk_first[c]) as usize]
    }

    /// The number of vertices kept.
    pub fn stored(&self) -> usize {
        self.spots.len()
    }
}

/// The list holding vertex `i`, given each list's first vertex number: the last list
/// starting at or before i (a list left empty shares its start with the next one,
/// which holds i).
fn list_holding(first: &[u32], i: u32) -> usize {
    first.partition_point(|&f| f <= i) - 1
}

/// What merging checks of a light vertex before it reads the vertex: 16 bytes, so a
/// candidate outside the radius costs one cache line rather than the vertex's four.
#[derive(Clone, Copy, Debug)]
pub struct Spot {
    pub p: Vec3,
    /// Edges from the light (saturating at 2³¹ − 1, far past any subpath that fits in
    /// memory), with the top bit set in a medium.
    tag: u32,
}

impl Spot {
    const MEDIUM: u32 = 1 << 31;

    fn of(v: &LightVertex) -> Spot {
        Spot::new(v.place.p, v.len, v.at.in_medium())
    }

    fn new(p: Vec3, edges: u32, in_medium: bool) -> Spot {
        Spot { p, tag: edges.min(Self::MEDIUM - 1) | if in_medium { Self::MEDIUM } else { 0 } }
    }

    /// Edges from the light.
    pub fn edges(&self) -> u32 {
        self.tag & !Self::MEDIUM
    }

    pub fn in_medium(&self) -> bool {
        self.tag & Self::MEDIUM != 0
    }
}

#[derive(Default)]
struct Chunk {
    vertices: Vec<LightVertex>,
    lens: Vec<u32>,
    splats: [Vec<(u32, Rgb)>; 4],
    counts: Counts,
}

/// Traces the pass's light subpaths in parallel. Under `--sampler sobol` subpath k is
/// point k of a scrambled Sobol' sequence of the pass (seeded by (seed, pass)), so the
/// pass's subpaths stratify the lights' positions and directions; under `random` it
/// draws from a generator seeded by (seed, pass, k).
pub fn trace_all(pass: &Pass, seed: u64, iteration: u32, live: &crate::integrators::report::Live) -> LightPass {
    let n = pass.light_paths;
    let stream = hash(&[seed, iteration as u64, 3]);
    // Camera subpath i connects to light subpath i mod n: past the pixel count, no
    // subpath's first vertex (used only by connections) is ever read, unless camera
    // vertices draw from all of the pass's (`links`).
    let pixels = match pass.links {
        Some(_) => u64::MAX,
        None => (pass.size.0 * pass.size.1) as u64,
    };
    let mut chunks: Vec<Chunk> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = Chunk::default();
            for k in c * CHUNK..((c + 1) * CHUNK).min(n) {
                let before = out.vertices.len();
                let to = Keep { half: half(k), first: k < pixels, vertices: &mut out.vertices };
                out.counts = out.counts
                    + match pass.sampler {
                        SamplerKind::Sobol => trace(pass, &mut SobolSample::new(stream, k as u32), to, &mut out.splats),
                        SamplerKind::Random => {
                            let mut rng = Rng::new(hash(&[seed, iteration as u64, k, 3]));
                            trace(pass, &mut rng, to, &mut out.splats)
                        }
                    };
                out.lens.push((out.vertices.len() - before) as u32);
            }
            live.add_photons(out.counts.paths);
            out
        })
        .collect();
    let mut starts = Vec::with_capacity(n as usize + 1);
    starts.push(0u32);
    let mut at = 0u32;
    for len in chunks.iter().flat_map(|c| &c.lens) {
        at += len;
        starts.push(at);
    }
    let counts = chunks.iter().fold(Counts::default(), |a, c| a + c.counts);
    let splats = chunks.iter_mut().flat_map(|c| std::mem::take(&mut c.splats)).collect();
    // Chunk c's subpaths start at c·CHUNK.
    let chunk_first = (0..chunks.len()).map(|c| starts[c * CHUNK as usize]).collect();
    let chunks: Vec<Vec<LightVertex>> = chunks.into_iter().map(|c| c.vertices).collect();
    let spots = chunks.par_iter().flat_map_iter(|c| c.iter().map(Spot::of)).collect();
    LightPass { chunks, chunk_first, spots, starts, splats, counts }
}

/// `v`, moved to the end of `list` if it is kept there, else into `here`: a kept
/// vertex is read from the list, not copied into it (280 bytes).
fn hold<'a>(
    v: LightVertex,
    list: Option<&'a mut Vec<LightVertex>>,
    here: &'a mut Option<LightVertex>,
) -> &'a LightVertex {
    match list {
        Some(list) => {
            list.push(v);
            list.last().expect("the vertex just pushed")
        }
        None => here.insert(v),
    }
}

/// A light subpath as it leaves the light.
struct Start<'a> {
    ray: Ray,
    beta: Rgb,
    partial: Partial,
    light: &'a Light,
    /// Next-event estimation's probability of choosing the light, and the cosine at
    /// its surface.
    pick: f64,
    cos: f64,
    /// The medium it emits into.
    medium: Option<u32>,
}

/// Emits from a light chosen by power (`None`: nothing emitted).
fn emit<'a>(pass: &Pass<'a>, s: &mut impl Sampler) -> Option<Start<'a>> {
    let scene = pass.scene;
    // The light is picked with a number of its own. Picked from the emission's first
    // number instead (as camera vertices pick theirs), this pass's Sobol' points
    // gave a caustic under a small light more outliers (docs/sampling.md).
    let (li, pick) = scene.light_power.sample(s.get1d())?;
    let light = &scene.lights[li];
    let (u1, u2) = (s.get2d(), s.get2d());
    let e = match (&pass.cones[li], &pass.maps[li]) {
        (Some(cone), _) => super::aim::emit(light, cone, u1),
        (None, Some(map)) => mapped_emission(pass, light, map, (u1, u2))?,
        (None, None) => match light {
            Light::Infinite(sky) => sky.sample_le_through_portal(scene.world, u1, u2)?,
            _ => light.sample_le(&scene.geometry.shapes, scene.world, u1, u2)?,
        },
    };
    if scene.emission_masked(light, e.surface.as_ref()) || e.pdf_pos <= 0.0 || e.pdf_dir <= 0.0 || e.le == Vec3::ZERO {
        return None;
    }
    let d = e.ray.d.0.normalize();
    let (pick, cos) = (pick as f64, e.n.dot(d).abs() as f64);
    let emission = pick * e.pdf_pos as f64 * e.pdf_dir as f64;
    // Next-event estimation's density of the same emission point: an area light's
    // and a portal's are found at the first hit (they depend on the point lit).
    let nee = pass.nee_pick(li);
    let direct = match light {
        _ if density_at_first_hit(light) => 1.0,
        Light::Infinite(_) => nee * e.pdf_dir as f64,
        _ => nee,
    };
    let cos_used = if is_finite(light) { cos } else { 1.0 };
    let partial = Partial::light(emission, direct, cos_used, light.is_delta(), pass.factors.surface);
    // DEVIATION(pbrt): robustness. Formed in f64 and carried divided by the scene's
    // photon scale, as SPPM's photons, so emitters past f32's range keep their paths.
    let beta = (scene.emission_of(li, e.le).as_dvec3() * (cos / emission / scene.photon_scale)).as_vec3();
    let medium = scene.light_medium(li, d, e.n);
    let time = pass.time.unwrap_or_else(|| scene.camera.time(s.get1d()));
    let ray = Ray::new(e.ray.o, Vector3(d)).at_time(time);
    Some(Start { ray, beta, partial, light, pick: nee, cos, medium })
}

/// An emission with one of its points drawn from the light's map ([`emission_map`]).
// DEVIATION(pbrt): always on where `--emission auto` maps a light, sampling only. pbrt's
// bdpt draws over the light's own density; the image's mean is the same (README,
// "Other differences").
fn mapped_emission(
    pass: &Pass,
    light: &Light,
    map: &emission_map::EmissionMap,
    (u1, u2): ([f32; 2], [f32; 2]),
) -> Option<crate::lights::Emission> {
    let shapes = &pass.scene.geometry.shapes;
    match emission_map::mapped(light)? {
        emission_map::Mapped::Direction => {
            let (u2, q) = map.draw(u2);
            let e = light.sample_le(shapes, pass.scene.world, u1, u2)?;
            Some(crate::lights::Emission { pdf_dir: e.pdf_dir * q, ..e })
        }
        emission_map::Mapped::Start => {
            let (u1, q) = map.draw(u1);
            let e = light.sample_le(shapes, pass.scene.world, u1, u2)?;
            Some(crate::lights::Emission { pdf_pos: e.pdf_pos * q, ..e })
        }
    }
}

/// Whether next-event estimation's density of a light subpath's first direction
/// depends on the point it reaches: an area light's, a portal's.
fn density_at_first_hit(light: &Light) -> bool {
    match light {
        Light::Area(_) => true,
        Light::Infinite(sky) => matches!(sky.sky, crate::lights::infinite::Sky::Portal(_)),
        _ => false,
    }
}

/// Whether a light has a position (distances to it count).
pub fn is_finite(light: &Light) -> bool {
    !matches!(light, Light::Distant(_) | Light::Infinite(_))
}

/// Where a light subpath keeps its vertices: the half of the pass it is in, whether a
/// camera subpath connects to it (else its first vertex is not kept), the list.
struct Keep<'a> {
    half: bool,
    first: bool,
    vertices: &'a mut Vec<LightVertex>,
}

/// One light subpath: appends its usable vertices and its splats; returns its counts
/// (one path, the surfaces hit, the vertices).
fn trace(pass: &Pass, s: &mut impl Sampler, to: Keep, splats: &mut [Vec<(u32, Rgb)>; 4]) -> Counts {
    let scene = pass.scene;
    let mut n = Counts { paths: 1, ..Default::default() };
    let Some(Start { mut ray, mut beta, mut partial, light, pick, cos, mut medium }) = emit(pass, s) else { return n };
    let (mut prev, mut len, mut passes, mut after_specular) = (ray.o.0, 0u32, 0u32, false);
    let mut terminated = false;
    // The throughput as it left the last vertex, which Russian roulette compares with.
    let mut before = beta;
    let keep = pass.techniques.uses(Technique::Connect) || pass.techniques.uses(Technique::Merge);
    loop {
        let hit = scene.intersect(&ray);
        let (place, at, wo) = match vertex::flight(scene, &ray, (hit.as_ref(), medium), &mut beta, s) {
            Some(found) => found,
            None => {
                let Some(hit) = hit else { break };
                n.hits += 1;
                let si = scene.geometry.interaction(&hit);
                let fp = Footprint::default();
                let bsdf = match surface(scene, (&hit, &si), &fp, &mut ray, &mut passes, &mut medium) {
                    Surface::Bsdf(b) => b,
                    Surface::PassedThrough => continue,
                    Surface::Abandon => break,
                };
                scene.terminate_if_dispersed(&hit, &mut beta, &mut terminated);
                (Place::on_surface(scene, &hit, &si, medium), Scatterer::Surface(bsdf), -ray.d.0.normalize())
            }
        };
        len += 1;
        n.vertices += 1;
        let dist2 = (place.p - prev).length_squared() as f64;
        if len == 1 && density_at_first_hit(light) {
            // Measured from the point offset off the surface, as light samples are.
            let from = place.origin_toward(wo);
            let pdf = light.pdf_li(&scene.geometry.shapes, from.0, wo) as f64;
            let per_area = if is_finite(light) { cos / dist2 } else { 1.0 };
            partial.vcm *= mis::mis(pick * pdf * per_area);
        }
        partial.arrive((len > 1 || is_finite(light)).then_some(dist2), at.measure(wo, place.ng));
        if let Some(links) = pass.links.as_deref().filter(|_| len > 1) {
            partial.count_edge(links.count(prev, place.p));
        }
        if !at.in_medium() && wo.dot(place.ng) == 0.0 {
            break;
        }
        // A camera subpath reaching here on a reflecting BSDF arrives on `wo`'s side
        // (else f is 0 and the density does not count).
        let guide = pass.guide_at(place.p, wo, &at).map(|m| m.toward(wo));
        let light_guide = pass.light_guided(place.p, wo, &at);
        let half = to.half;
        let v = LightVertex { place, wo, beta, at, partial, len, half, after_specular, terminated, guide, light_guide };
        let stays = !v.at.is_delta() && keep && len < pass.max_len && (len > 1 || to.first);
        if !v.at.is_delta() {
            // Direct light is not light-traced (`mis`), unless light tracing is alone.
            let traced = len > 1 || pass.techniques == Techniques::Only(Technique::LightTrace);
            if pass.techniques.uses(Technique::LightTrace) && len < pass.max_len && traced {
                to_camera(pass, &v, s, &mut splats[kind(v.half, v.after_specular)]);
            }
        }
        let mut here = None;
        let v = hold(v, stays.then_some(&mut *to.vertices), &mut here);
        if len + 2 > pass.max_len {
            break;
        }
        let Some((next, b, p, specular)) = scatter(pass, v, before, s) else { break };
        // What crosses into a BSSRDF is found by camera subpaths alone (`subsurface`).
        if v.place.crosses_into_bssrdf(v.wo, next.d.0) {
            break;
        }
        medium = v.place.toward(next.d.0);
        (ray, beta, before, partial, prev, after_specular) = (next, b, b, p, v.place.p, specular);
    }
    n
}

/// Samples the adjoint BSDF (or the phase function) at a light vertex: the ray on, the
/// throughput and the partial sums after it (`None`: absorbed or ended by Russian
/// roulette against `before`, the throughput as the subpath left the vertex before),
/// and whether the bounce was specular.
fn scatter(pass: &Pass, v: &LightVertex, before: Rgb, s: &mut impl Sampler) -> Option<(Ray, Rgb, Partial, bool)> {
    let cos = |wi, specular| v.leaving_cos(wi, specular, pass);
    let smp = match v.light_guide.and_then(|g| pass.light_mix(g)) {
        Some(mix) => v.at.sample_guided(v.wo, s, (&mix, TransportMode::Importance), |wi| cos(wi, false))?,
        None => v.at.sample(v.wo, s, TransportMode::Importance, cos)?,
    };
    let bnew = v.beta * smp.f * smp.scale;
    // As SPPM's photons: continue with the probability the throughput kept.
    let q = (1.0 - luminance(bnew) / luminance(before).max(1e-30)).max(0.0);
    if s.get1d() < q {
        return None;
    }
    let beta = bnew / (1.0 - q);
    if !beta.is_finite() || beta == Vec3::ZERO {
        return None;
    }
    let mut partial = v.partial;
    let m = v.at.measure(smp.wi, v.place.ng);
    // A camera subpath would draw the way back from the guided mixture, if any.
    let pdf_rev = v.guide.map_or(smp.pdf_rev, |g| g.pdf(smp.pdf_rev));
    partial.scatter(m, smp.pdf as f64, pdf_rev as f64, smp.specular, v.len > 1, v.factors(pass));
    if smp.specular {
        partial.forget_merges();
    }
    Some((v.place.spawn(smp.wi), beta, partial, smp.specular))
}

/// Light tracing: connects a light vertex to a point on the lens and splats what it
/// sends there onto the pixel it reaches.
fn to_camera(pass: &Pass, v: &LightVertex, s: &mut impl Sampler, splats: &mut Vec<(u32, Rgb)>) {
    let scene = pass.scene;
    let Some(cs) = scene.camera.sample_wi(v.place.p, s.get2d(), v.place.time) else { return };
    let pixel = pass.pixel_index(cs.raster);
    if pixel.is_none() && scene.film.filter.is_none() {
        return;
    }
    let e = v.eval(cs.wi, pass);
    if e.f == Vec3::ZERO || cs.pdf <= 0.0 {
        return;
    }
    let dist2 = (cs.p_lens - v.place.p).length_squared() as f64;
    let (_, pdf_dir) =
        scene.camera.pdf_we(&Ray::new(crate::math::Point3(cs.p_lens), Vector3(-cs.wi)).at_time(v.place.time));
    let camera_a = pdf_dir as f64 * pass.film_pixels * v.at.measure(cs.wi, v.place.ng) / dist2;
    let light_paths = pass.light_paths as f64;
    let w = mis::to_camera(v.partial, camera_a, e.pdf_rev as f64, v.len, pass.lt_count(), v.factors(pass));
    let c = v.beta * e.f * v.adjoint_cos(cs.wi) * (cs.we / cs.pdf) * (pass.film_pixels / light_paths) as f32;
    let c = c * pass.techniques.weight(w);
    if c == Vec3::ZERO || !c.is_finite() {
        return;
    }
    // pbrt's film clamps each splat: what one light subpath brings, pbrt's light
    // tracing sending one a pixel sample.
    let c = match scene.clamp {
        Some(_) => {
            c * scene.clamp_factor(scene.film_rgb(c) * (scene.photon_scale * light_paths / pass.film_pixels)) as f32
        }
        None => c,
    };
    let c = c * vertex::visible(scene, &v.place, cs.p_lens, s);
    if c == Vec3::ZERO {
        return;
    }
    match (&scene.film.filter, pixel) {
        (Some(f), _) => splats.extend(pass.footprint(cs.raster, f).map(|(pixel, w)| (pixel, c * w))),
        (None, Some(pixel)) => splats.push((pixel, c)),
        (None, None) => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_vertex_is_found_in_its_list_past_empty_ones() {
        // Lists of 0, 3, 0, 0, 2 and 0 vertices.
        let first = [0, 0, 3, 3, 3, 5];
        let lists: Vec<usize> = (0..5).map(|i| list_holding(&first, i)).collect();
        assert_eq!(lists, [1, 1, 1, 4, 4]);
    }

    #[test]
    fn a_spot_keeps_the_edges_and_the_medium_apart() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        for (edges, in_medium) in [(2, false), (2, true), (7, true), (0, false)] {
            let s = Spot::new(p, edges, in_medium);
            assert_eq!((s.p, s.edges(), s.in_medium()), (p, edges, in_medium));
        }
        // A length past the top bit saturates rather than reading as a medium.
        let s = Spot::new(p, u32::MAX, false);
        assert_eq!((s.edges(), s.in_medium()), (Spot::MEDIUM - 1, false));
        assert_eq!(std::mem::size_of::<Spot>(), 16);
    }
}
