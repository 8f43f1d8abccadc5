//! Light through a `subsurface` material's BSSRDF, as pbrt's path tracers take it
//! (pbrt-v3's `SeparableBSSRDF::Sample_S`, pbrt-v4's `VolPathIntegrator`): where a
//! camera path refracts into the material at po, a probe segment through the object
//! finds the point pi where the light it sees entered, drawn by the profile's radius
//! on a disc about po perpendicular to one of three axes (the shading normal half the
//! time). pi's directional term is a Fresnel-weighted diffuse lobe, from which the path
//! goes on. vcm and bdpt share it ([`RenderScene::subsurface`] says when they use it).

use crate::accel::Hit;
use crate::interaction::SurfaceInteraction;
use crate::materials::bssrdf::Profile;
use crate::materials::lobes::Lobe;
use crate::materials::{Bsdf, Convention};
use crate::math::frame::coordinate_system;
use crate::math::{Point3, Ray, Vector3};
use crate::parser::Syntax;
use crate::render::RenderScene;
use crate::sampling::Sampler;
use crate::spectrum::Rgb;
use glam::Vec3;

/// Where a camera path crossed into a subsurface material.
pub struct Entry {
    pub profile: Profile,
    /// The boundary's index of refraction.
    pub eta: f32,
    /// The material (an index into the scene's): probes stop only on its surfaces.
    pub material: u32,
    pub po: Vec3,
    /// The shading frame at po: (s, t, n).
    pub frame: [Vec3; 3],
    pub time: f32,
}

/// Where the light leaves toward the camera path: the hit, its BSDF (the BSSRDF's
/// directional term) and the throughput's factor, Sp over the probe's density.
pub struct Exit {
    pub hit: Hit,
    pub si: SurfaceInteraction,
    pub bsdf: Bsdf,
    pub weight: Rgb,
}

/// The most surfaces one probe segment crosses.
// DEVIATION(pbrt): robustness. pbrt follows a probe until it finds no more surfaces;
// a ray that keeps finding the surface it left (a degenerate mesh) would never end.
const MAX_PROBE_HITS: u32 = 64;

/// The probe axes (disc x, disc y, probe direction) for `u` and what is left of `u`:
/// pbrt-v3 takes the shading frame (n half the time, s and t a quarter each), pbrt-v4
/// n and the two tangents of `CoordinateSystem(n)`, in the same proportions.
fn axes(v4: bool, [s, t, n]: [Vec3; 3], u: f32) -> ([Vec3; 3], f32) {
    if v4 {
        let (c1, c2) = coordinate_system(n);
        return match u {
            u if u < 0.25 => ([n, c1, c2], u * 4.0),
            u if u < 0.5 => ([c2, n, c1], (u - 0.25) * 4.0),
            u => ([c1, c2, n], (u - 0.5) * 2.0),
        };
    }
    match u {
        u if u < 0.5 => ([s, t, n], u * 2.0),
        u if u < 0.75 => ([t, n, s], (u - 0.5) * 4.0),
        u => ([n, s, t], (u - 0.75) * 4.0),
    }
}

/// The frame the probe density is measured in: (s, t, n), with pbrt-v4's tangents.
fn pdf_frame(v4: bool, [s, t, n]: [Vec3; 3]) -> [Vec3; 3] {
    if v4 {
        let (c1, c2) = coordinate_system(n);
        [c1, c2, n]
    } else {
        [s, t, n]
    }
}

/// pbrt's `Pdf_Sp`: the density of finding pi (geometric normal `ni`) by a probe, over
/// the three axes and the channels.
fn pdf_sp(e: &Entry, v4: bool, pi: Vec3, ni: Vec3) -> f32 {
    let f = pdf_frame(v4, e.frame);
    let d = e.po - pi;
    let (dl, nl) = (Vec3::new(f[0].dot(d), f[1].dot(d), f[2].dot(d)), [f[0].dot(ni), f[1].dot(ni), f[2].dot(ni)]);
    let r_proj =
        [(dl.y * dl.y + dl.z * dl.z).sqrt(), (dl.z * dl.z + dl.x * dl.x).sqrt(), (dl.x * dl.x + dl.y * dl.y).sqrt()];
    let axis_prob = [0.25, 0.25, 0.5];
    let mut pdf = 0.0;
    for axis in 0..3 {
        for ch in 0..3 {
            pdf += e.profile.pdf_sr(ch, r_proj[axis]) * nl[axis].abs() * axis_prob[axis] / 3.0;
        }
    }
    pdf
}

/// Draws where the light seen at the entry left the material's interior: `None` when
/// the probe finds none of its surfaces.
// DEVIATION(pbrt): noise only. pbrt-v4 draws the radius from the first wavelength and
// weighs the lanes by its spectral MIS; drawing the channel uniformly, as pbrt-v3 does,
// gives the same average with the same density.
pub fn exit(scene: &RenderScene, e: &Entry, s: &mut impl Sampler) -> Option<Exit> {
    let v4 = scene.syntax == Syntax::V4;
    let (u1, u2, mut u_pick) = (s.get1d(), s.get2d(), s.get1d());
    let ([vx, vy, vz], u1) = axes(v4, e.frame, u1);
    let ch = ((u1 * 3.0) as usize).min(2);
    let r = e.profile.sample_sr(ch, u2[0])?;
    let r_max = e.profile.sample_sr(ch, 0.999)?;
    if r < 0.0 || r >= r_max {
        return None;
    }
    let phi = 2.0 * std::f32::consts::PI * u2[1];
    let l = 2.0 * (r_max * r_max - r * r).sqrt();
    let start = e.po + r * (vx * phi.cos() + vy * phi.sin()) - l * vz * 0.5;
    let target = Point3(start + l * vz);
    // Every surface of the material along the segment, one kept uniformly (a
    // reservoir of one, `u_pick` rescaled at each choice).
    let mut ray = Ray { o: Point3(start), d: Vector3(target.0 - start), t_max: 1.0, time: e.time };
    let (mut found, mut kept) = (0u32, None);
    for _ in 0..MAX_PROBE_HITS {
        if ray.d.0 == Vec3::ZERO {
            break;
        }
        let Some(hit) = scene.intersect(&ray) else { break };
        let si = scene.geometry.interaction(&hit);
        ray = si.spawn_ray_to(target);
        if scene.material_index(&hit) != e.material {
            continue;
        }
        found += 1;
        let p = 1.0 / found as f32;
        if u_pick < p {
            u_pick /= p;
            kept = Some((hit, si));
        } else {
            u_pick = (u_pick - p) / (1.0 - p);
        }
    }
    let (hit, si) = kept?;
    let pdf = pdf_sp(e, v4, si.p.0, si.n.0) / found as f32;
    let sp = e.profile.sr(e.po.distance(si.p.0));
    if pdf.is_nan() || pdf <= 0.0 || sp == Vec3::ZERO {
        return None;
    }
    let bsdf = exit_bsdf(&si, e.eta, v4);
    Some(Exit { hit, si, bsdf, weight: sp / pdf })
}

/// The BSDF where light enters: the BSSRDF's directional term in the hit's shading
/// frame (no bump map: the material is not evaluated there, as in pbrt).
fn exit_bsdf(si: &SurfaceInteraction, eta: f32, v4: bool) -> Bsdf {
    let ns = si.shading.n.0;
    let dpdu = si.shading.dpdu.0;
    let mut ss = (dpdu - ns * ns.dot(dpdu)).normalize_or_zero();
    if ss == Vec3::ZERO {
        ss = coordinate_system(ns).0;
    }
    let lobe = Lobe::NormalizedFresnel { eta, scale: Vec3::ONE };
    let convention = if v4 { Convention::PbrtV4 } else { Convention::PbrtV3 };
    Bsdf::new([ss, ns.cross(ss), ns], si.n.0, &[lobe], convention)
}
