//! The multiple-importance weights of vertex connection and merging, computed as the
//! subpaths grow (Georgiev, Křivánek, Davidovič and Slusallek 2012, and the technical
//! report's §§4–5 recurrences).
//!
//! Every subpath carries three partial sums, [`Partial`]: `vcm`, `vc` and `vm` (the
//! report's dVCM, dVC, dVM). They are updated in constant time at each vertex, so a
//! technique's weight costs the same at any path length: no loop over the path.
//! Densities here follow the report's conventions:
//! - solid-angle densities at a vertex ("W"), area densities at the next one ("A");
//! - cosines are geometric (they convert densities between measures); at a vertex in a
//!   medium the density σt stands in their place (free flight stops there with density
//!   σt·Tr per unit length), and transmittance is left out of every density, as pbrt's
//!   bdpt leaves it out: it is common to both directions of an edge, so it only
//!   matters for the edge a technique connects, and there a grid's transmittance is a
//!   random estimate that would leave the weights summing to 1 only on average;
//! - merging in a medium gathers over a ball: its η is (4/3)πr³·N where a surface's is
//!   πr²·N ([`PassFactors`]);
//! - a delta distribution's density is dropped (it cancels in every ratio), and a
//!   specular bounce keeps `vc` and `vm` but clears `vcm`;
//! - light choice probabilities are folded into the light's densities.
//!
//! The heuristic is the power heuristic with β = 2 ([`mis`]); sums are `f64` (a squared
//! area density over a squared distance leaves `f32`'s range in large scenes).
//!
//! Direct light is never merged: a light subpath's first vertex (one edge from its
//! light) takes no part in merging, and every weight leaves that technique out. The
//! heuristic rates merging as η·p connections, as good as several light samples, while
//! next-event estimation of direct light has no bias and, for a point light or with
//! low-discrepancy samples, little or no variance: merging it left 1.3 times the
//! error on a diffuse scene's direct light (`docs/vcm.md`). (SmallVCM merges it.)
//!
//! Nor is a camera subpath's vertex merged past a specular bounce that followed a
//! diffuse one (a camera subpath E S* D*, read from the camera, merges; E … D S … does
//! not). Such a vertex is where a diffuse surface sees, through glass or a mirror,
//! what is usually a caustic: on a glass sphere's caustic (`verify/v3-caustic`),
//! camera paths from the floor in the sphere's shadow that bounced into the sphere
//! and out onto the focused spot merged its photons there, and those rare, bright
//! merges held three quarters of the image's error in a hundredth of its pixels. The
//! heuristic sees densities, not the light they carry, and gave them about half the
//! weight; without them the photons that made the same trip the other way (merged at
//! the shadowed floor, as SPPM gathers them) carry it. Merges past diffuse bounces
//! alone are kept: on a room lit through a gap (`keyhole`) they are what finds the lit
//! patch. For the weights, a light subpath keeps apart the part of its sums that
//! stands for merging at its own vertices and drops it at a specular bounce
//! ([`Partial::forget_merges`]); a connection from a camera vertex that may not merge
//! leaves it out too. `docs/vcm.md`, "Merging past a specular bounce", has the
//! measurements.
//!
//! Nor is direct light traced from the light to the camera: a path of two edges (light,
//! one vertex, camera) is found by next-event estimation and by the camera path hitting
//! the light, as a path tracer finds it. The heuristic gives light tracing the share
//! its density earns, but next-event estimation from the camera's low-discrepancy
//! samples is far better than its density says: with light tracing in, the direct
//! light of a diffuse scene had 14 times the error of next-event estimation alone
//! (`docs/vcm.md`). Light tracing keeps every longer path (caustics seen directly).

use std::f64::consts::PI;

/// The heuristic's power: x ↦ x².
#[inline]
pub fn mis(x: f64) -> f64 {
    x * x
}

/// The partial sums a subpath carries (the report's dVCM, dVC, dVM; dVM with merges
/// counted in units of a surface merge, see [`Factors::rel`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Partial {
    pub vcm: f64,
    pub vc: f64,
    pub vm: f64,
    /// The part of `vc` that stands for merging at the vertex last left (a camera
    /// subpath's: were the next vertex on a light, that merge would be of direct light,
    /// which is left out).
    pub vc_merge_last: f64,
    /// The parts of `vc` and `vm` that stand for merging at this subpath's own
    /// vertices: a light subpath drops them at a specular bounce
    /// ([`Partial::forget_merges`]).
    pub vc_merges: f64,
    pub vm_merges: f64,
}

/// The constants of merging at one kind of vertex: the heuristic applied to η (vertex
/// merging against one connection) and to 1/η; zero for a technique left out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Factors {
    /// The report's "MisVmWeightFactor", mis(η): 0 without merging.
    pub vm: f64,
    /// The report's "MisVcWeightFactor", mis(1/η): 0 without connections.
    pub vc: f64,
    /// mis(η / η_surface): 1 on a surface. `Partial::vm` counts merges in units of a
    /// surface merge, since merges at different kinds of vertex weigh differently.
    pub rel: f64,
    /// mis(1/η_surface): the unit `Partial::vm` counts connections in.
    pub unit_vc: f64,
}

/// An iteration's constants for each kind of vertex. Merging on a surface gathers over
/// a disc, η = π r² · N_light; in a medium over a ball, η = (4/3) π r³ · N_light, with
/// densities there per unit volume (Křivánek et al. 2014, "Unifying points, beams, and
/// paths", §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassFactors {
    pub surface: Factors,
    pub medium: Factors,
    radius: f64,
}

/// The most mean free paths a merging ball's radius may span (σt·r): where a medium is
/// denser, merging there is no technique. Light in a medium varies over a mean free
/// path, so a ball spanning many averages it away: on a fog of σt = 10⁴ (mean free path
/// 10⁻⁴) at radius 0.05 the image came out 37% dark, and the weights, which rate
/// merging by σt, gave it nearly all the weight.
pub const MAX_OPTICAL_RADIUS: f64 = 1.0;

impl PassFactors {
    /// For merging radius `radius` and `light_paths` light subpaths per iteration.
    pub fn new(radius: f64, light_paths: f64, connect: bool, merge: bool) -> PassFactors {
        let disc = PI * radius * radius * light_paths;
        let ball = disc * radius * (4.0 / 3.0);
        let unit_vc = if connect { mis(1.0 / disc) } else { 0.0 };
        let of = |eta: f64| Factors {
            vm: if merge { mis(eta) } else { 0.0 },
            vc: if connect { mis(1.0 / eta) } else { 0.0 },
            rel: mis(eta / disc),
            unit_vc,
        };
        PassFactors { surface: Factors { rel: 1.0, ..of(disc) }, medium: of(ball), radius }
    }

    /// The constants at a vertex on a surface (`None`), or in a medium of density σt:
    /// no merging where the ball spans more than [`MAX_OPTICAL_RADIUS`] mean free paths.
    #[inline]
    pub fn at(&self, medium_density: Option<f64>) -> Factors {
        match medium_density {
            None => self.surface,
            Some(st) if st * self.radius > MAX_OPTICAL_RADIUS => Factors { vm: 0.0, rel: 0.0, ..self.medium },
            Some(_) => self.medium,
        }
    }
}

impl Partial {
    /// A light subpath as it leaves its light. `emission`: the density of the emitted
    /// ray (position × direction × the light's choice); `direct`: the density next-event
    /// estimation gives the same emission point (area measure; solid angle for lights
    /// at infinity); `cos`: the cosine at the light (1 for lights at infinity);
    /// `delta`: no connection can reach the light's position or direction.
    pub fn light(emission: f64, direct: f64, cos: f64, delta: bool, f: Factors) -> Partial {
        let vc = if delta { 0.0 } else { mis(cos / emission) };
        Partial { vcm: mis(direct / emission), vc, vm: vc * f.unit_vc, ..Partial::default() }
    }

    /// A camera subpath as it leaves the lens: `camera_pdf` is the solid-angle density
    /// of its direction per unit of raster area (one pixel), 0 where no light path can
    /// reach the camera (an orthographic one).
    pub fn camera(camera_pdf: f64, light_paths: f64) -> Partial {
        let vcm = if camera_pdf > 0.0 { mis(light_paths / camera_pdf) } else { 0.0 };
        Partial { vcm, ..Partial::default() }
    }

    /// Arriving at a vertex over a segment of squared length `dist2` (`None`: the first
    /// segment from a light at infinity, whose densities are in solid angle), at
    /// geometric cosine `cos` with the surface.
    pub fn arrive(&mut self, dist2: Option<f64>, cos: f64) {
        if let Some(d2) = dist2 {
            self.vcm *= mis(d2);
        }
        let c = mis(cos.abs());
        self.vcm /= c;
        self.vc /= c;
        self.vm /= c;
        self.vc_merge_last /= c;
        self.vc_merges /= c;
        self.vm_merges /= c;
    }

    /// The edge just arrived over, were a connection to make it, counts as `count`
    /// samples where a pair counts 1 (connections drawn from the whole pass,
    /// `links`). Not for an edge from a light's own point (next-event estimation
    /// makes that one, once) nor one from the lens (light tracing).
    pub fn count_edge(&mut self, count: f64) {
        self.vcm *= mis(count);
    }

    /// Leaving a vertex along a sampled direction: `cos_out` the geometric cosine there,
    /// `pdf` the solid-angle density of the sample, `pdf_rev` the density of the
    /// reverse walk choosing the direction the path came from. `merges`: whether
    /// merging at this vertex is a technique (not at a light subpath's first vertex;
    /// on a camera subpath, not past a specular bounce that followed a diffuse one).
    pub fn scatter(&mut self, cos_out: f64, pdf: f64, pdf_rev: f64, specular: bool, merges: bool, f: Factors) {
        if specular {
            let c = mis(cos_out);
            self.vcm = 0.0;
            (self.vc, self.vm, self.vc_merges, self.vm_merges) =
                (self.vc * c, self.vm * c, self.vc_merges * c, self.vm_merges * c);
            self.vc_merge_last = 0.0;
            return;
        }
        let (g, rev) = (mis(cos_out / pdf), mis(pdf_rev));
        let (vm_here, one) = if merges { (f.vm, f.rel) } else { (0.0, 0.0) };
        *self = Partial {
            vcm: mis(1.0 / pdf),
            vc: g * (self.vc * rev + self.vcm + vm_here),
            vm: g * (self.vm * rev + self.vcm * f.unit_vc + one),
            vc_merge_last: g * vm_here,
            vc_merges: g * (self.vc_merges * rev + vm_here),
            vm_merges: g * (self.vm_merges * rev + one),
        };
    }

    /// After a light subpath's specular bounce: merging at its vertices before it is no
    /// longer a technique for any path it goes on to make (a camera subpath would meet
    /// them past that bounce, where merging is left out; see the module's docs).
    pub fn forget_merges(&mut self) {
        self.vc = (self.vc - self.vc_merges).max(0.0);
        self.vm = (self.vm - self.vm_merges).max(0.0);
        (self.vc_merges, self.vm_merges) = (0.0, 0.0);
    }
}

/// The weight of a camera subpath that finds an emitter by itself (after at least one
/// bounce): `direct` is the area density next-event estimation gives the point found
/// (solid angle for a light at infinity), `emission` the density of the light emitting
/// back along the path.
/// `direct_light`: the emitter is the camera path's second vertex (the path is direct
/// light, which neither merging nor light tracing takes).
pub fn emitter_hit(camera: Partial, direct: f64, emission: f64, direct_light: bool) -> f64 {
    // Merging at the vertex before would merge direct light: not a technique.
    let vc = if direct_light { 0.0 } else { (camera.vc - camera.vc_merge_last).max(0.0) };
    1.0 / (1.0 + mis(direct) * camera.vcm + mis(emission) * vc)
}

/// The densities of one next-event estimate.
#[derive(Clone, Copy, Debug)]
pub struct DirectPdfs {
    /// The BSDF's density of sampling the light direction (0 for a delta light).
    pub bsdf: f64,
    /// The BSDF's density of the reverse direction.
    pub bsdf_rev: f64,
    /// The light sample's solid-angle density, times the light's choice (a point
    /// light's: the squared distance).
    pub direct: f64,
    /// The density of the light emitting toward the vertex (position × direction ×
    /// choice).
    pub emission: f64,
    /// Geometric cosines at the vertex and at the light (1 for delta and infinite lights).
    pub cos_here: f64,
    pub cos_light: f64,
}

/// The weight of next-event estimation (a camera vertex connected to a point drawn on
/// a light). `first`: the vertex is the camera path's first, so the path is direct
/// light, which light tracing (the only technique with more light vertices) leaves out.
pub fn direct(camera: Partial, p: DirectPdfs, first: bool) -> f64 {
    let w_light = mis(p.bsdf / p.direct);
    let w_camera = match first {
        true => 0.0,
        false => mis(p.emission * p.cos_here / (p.direct * p.cos_light)) * (camera.vcm + camera.vc * mis(p.bsdf_rev)),
    };
    1.0 / (w_light + 1.0 + w_camera)
}

/// The densities of a connection between a light vertex and a camera vertex.
#[derive(Clone, Copy, Debug)]
pub struct ConnectPdfs {
    /// The camera vertex's BSDF choosing the light vertex, in area measure there.
    pub camera_a: f64,
    /// The light vertex's BSDF choosing the camera vertex, in area measure there.
    pub light_a: f64,
    /// Each BSDF's density of the direction its own subpath arrived from.
    pub camera_rev: f64,
    pub light_rev: f64,
}

/// The weight of connecting a light vertex to a camera vertex; `light_len`: the light
/// vertex's edges from its light (at 1, merging there would merge direct light);
/// `fl`, `fc`: the constants at the light and the camera vertex; `merges`: whether
/// merging is a technique at the camera vertex, and so at the light subpath's vertices
/// beyond it (not when the camera subpath has bounced specularly after a diffuse
/// bounce); `count`: the samples this connection counts as ([`Partial::count_edge`]).
pub fn connect(
    light: Partial,
    camera: Partial,
    p: ConnectPdfs,
    light_len: u32,
    (fl, fc): (Factors, Factors),
    merges: bool,
    count: f64,
) -> f64 {
    let (vm_l, vm_c, light_vc) = match merges {
        true => (if light_len > 1 { fl.vm } else { 0.0 }, fc.vm, light.vc),
        false => (0.0, 0.0, (light.vc - light.vc_merges).max(0.0)),
    };
    let w_light = mis(p.camera_a) * (vm_l + light.vcm + light_vc * mis(p.light_rev));
    let w_camera = mis(p.light_a) * (vm_c + camera.vcm + camera.vc * mis(p.camera_rev));
    // A pair's connection (count 1) keeps the sum in the order it always had.
    let k = mis(count);
    k / (w_light + k + w_camera)
}

/// The weight of light tracing: a light vertex connected to the lens. `camera_a`: the
/// camera's density of the vertex (per raster area, in area measure there);
/// `bsdf_rev`: the vertex BSDF's density of the direction its subpath arrived from;
/// `light_len`: the vertex's edges from its light (at 1, the path is direct light:
/// not a technique).
pub fn to_camera(light: Partial, camera_a: f64, bsdf_rev: f64, light_len: u32, light_paths: f64, f: Factors) -> f64 {
    if light_len <= 1 {
        return 0.0;
    }
    let vm = f.vm;
    let w_light = mis(camera_a / light_paths) * (vm + light.vcm + light.vc * mis(bsdf_rev));
    1.0 / (w_light + 1.0)
}

/// The weight of merging a light vertex (at least two edges from its light) at a
/// camera vertex: `pdf` and `pdf_rev` are the camera vertex BSDF's densities of the
/// light vertex's arrival direction and of the camera subpath's own; `f` the constants
/// where they merge.
pub fn merge(light: Partial, camera: Partial, pdf: f64, pdf_rev: f64, f: Factors) -> f64 {
    if f.vm == 0.0 {
        return 0.0;
    }
    // The partial sums count merges in units of a surface merge: here, one of weight
    // `f.rel` of those.
    let w_light = (light.vcm * f.unit_vc + light.vm * mis(pdf)) / f.rel;
    let w_camera = (camera.vcm * f.unit_vc + camera.vm * mis(pdf_rev)) / f.rel;
    1.0 / (w_light + 1.0 + w_camera)
}
