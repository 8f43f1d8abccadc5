//! SPPM's beam radiance estimate in media (Jarosz, Zwicker and Jensen 2008, "The beam
//! radiance estimate for volumetric photon mapping"), progressive as in Knaus and
//! Zwicker 2011: `--volume-gather beams`.
//!
//! ```text
//! Integrator "sppm" "integer numiterations" 64 "float radius" 0.05
//! MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_s" [0.1 0.1 0.1]
//! ```
//!
//! A camera path does not stop in a medium: every medium segment it crosses is a beam,
//! and it goes on to the surface behind (or through glass to the next segment) with the
//! segment's transmittance. Photons that scatter in a medium are kept as points; after
//! the photon pass each beam gathers those within `r` of its line, whose foot lies on
//! the segment:
//!
//! L = Σ β·Tr(t_i)·p(ω, ω_i)·σs(x_i)·Φ_i / (π r²)
//!
//! a 2D kernel across the ray, where the point estimate divides by a ball's volume. The
//! estimate of an iteration is added to the pixel's direct light (which is averaged over
//! iterations), and the radius shrinks from one iteration to the next as
//! r_{i+1}² = r_i²·(i + α)/(i + 1), α = 2/3 (or the independent passes' `--alpha`): the
//! per-iteration estimates are independent, so their mean converges (Knaus and Zwicker).

use super::grid::{Binning, Grid, Site};
use crate::math::Ray;
use crate::media::{HenyeyGreenstein, Profile};
use crate::render::RenderScene;
use crate::sampling::Sampler;
use crate::spectrum::Rgb;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// How SPPM's camera paths gather photons in media (`--volume-gather`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VolumeGather {
    /// A camera path scatters at a point drawn by free flight and gathers the photons
    /// in a ball there (Jensen and Christensen 1998).
    Points,
    /// Every medium segment of a camera path gathers the photons near it: the default,
    /// less error at equal time on the media scenes (docs/media-benchmark.md).
    #[default]
    Beams,
}

impl VolumeGather {
    pub fn name(self) -> &'static str {
        match self {
            VolumeGather::Points => "points",
            VolumeGather::Beams => "beams",
        }
    }
}

impl std::str::FromStr for VolumeGather {
    type Err = String;

    /// `--volume-gather`'s names: `points` or `beams`.
    fn from_str(s: &str) -> Result<VolumeGather, String> {
        match s {
            "points" => Ok(VolumeGather::Points),
            "beams" => Ok(VolumeGather::Beams),
            _ => Err(format!("expected points or beams, not \"{s}\"")),
        }
    }
}

/// A photon that scattered in a medium: where, back along its arrival, and its flux
/// times σs there.
#[derive(Clone, Copy, Debug)]
pub struct VolumePhoton {
    pub p: Vec3,
    pub wo: Vec3,
    pub flux: Rgb,
}

/// One medium segment of a camera path.
#[derive(Clone, Debug)]
pub struct Beam {
    o: Vec3,
    /// Unit direction.
    d: Vec3,
    /// World length (infinite where the ray leaves the scene).
    len: f32,
    /// The camera path's weight where the segment starts.
    beta: Rgb,
    phase: HenyeyGreenstein,
    tr: Profile,
}

impl Beam {
    /// The beam along `ray` in medium `m` up to `t_max` (ray parameter), starting with
    /// weight `beta`, and the transmittance over it all.
    pub fn along(
        scene: &RenderScene,
        ray: &Ray,
        (m, t_max): (u32, f32),
        beta: Rgb,
        sampler: &mut impl Sampler,
    ) -> (Beam, Rgb) {
        let dlen = ray.d.0.length();
        let (d, len) = (ray.d.0 / dlen, t_max * dlen);
        let medium = &scene.media[m as usize];
        let tr = medium.profile(ray.o.0, d, len, sampler, scene.pass_spectrum().as_ref());
        let through = tr.at(len);
        (Beam { o: ray.o.0, d, len, beta, phase: medium.phase(), tr }, through)
    }

    /// Σ β·Tr·p·Φ over the photons within `r` of the segment whose foot is on it, each
    /// counted in the grid cell that holds its foot (so once).
    fn gather(&self, grid: &Grid, photons: &[VolumePhoton], r: f32) -> Vec3 {
        let mut sum = Vec3::ZERO;
        grid.along(self.o, self.d, (0.0, self.len), |key, i| {
            let ph = &photons[i as usize];
            let t = (ph.p - self.o).dot(self.d);
            // Photons count whatever medium they scattered in, as at points: where two
            // media meet, which one a ray is in can be rounding's choice (coincident
            // boundaries), and beams that refused the other's photons there were 10%
            // darker than bdpt.
            if !(0.0..=self.len).contains(&t) {
                return;
            }
            let foot = self.o + self.d * t;
            if (ph.p - foot).length_squared() > r * r || grid.key_of(foot) != key {
                return;
            }
            sum += self.tr.at(t) * ph.flux * self.phase.p(-self.d, ph.wo);
        });
        self.beta * sum
    }
}

/// Photons in media gathered at most this many at a time, so that their memory stays
/// bounded in scenes where photons scatter a hundred times (albedo 1, `maxdepth` 100):
/// 4M photons of 36 bytes and their grid (up to 8 entries of 16 bytes each) come to
/// about 700 MB at most. Scenes with fewer (all the bundled ones) gather once.
const BLOCK: usize = 1 << 22;

/// An iteration's beam estimates, from photons in media handed over chunk by chunk in
/// the order they were traced: gathered in blocks that fill at the same chunks whatever
/// the photon pass's bands, so each pixel sums the same numbers in the same order.
pub struct Gather<'a> {
    beams: Vec<&'a [Beam]>,
    /// Photons held before they are gathered ([`BLOCK`]).
    block: usize,
    pending: Vec<VolumePhoton>,
    sums: Vec<DVec3>,
    r: f32,
    scale: f64,
    /// Time spent gathering.
    seconds: f64,
}

impl<'a> Gather<'a> {
    /// `beams[i]`: pixel i's beams; `r` the radius, `scale` the photons' flux scale.
    pub fn new(beams: Vec<&'a [Beam]>, r: f32, scale: f64) -> Gather<'a> {
        let sums = vec![DVec3::ZERO; beams.len()];
        Gather { beams, block: BLOCK, pending: Vec::new(), sums, r, scale, seconds: 0.0 }
    }

    /// The next chunk's photons.
    pub fn add(&mut self, photons: Vec<VolumePhoton>) {
        self.pending.extend(photons);
        if self.pending.len() >= self.block {
            self.flush();
        }
    }

    fn flush(&mut self) {
        if self.pending.is_empty() {
            return;
        }
        let t = std::time::Instant::now();
        let e = estimate(&self.beams, &self.pending, self.r, self.scale);
        self.sums.par_iter_mut().zip(e).for_each(|(s, e)| *s += e);
        self.pending.clear();
        self.seconds += t.elapsed().as_secs_f64();
    }

    /// Each pixel's estimate, and the seconds spent gathering.
    pub fn finish(mut self) -> (Vec<DVec3>, f64) {
        self.flush();
        (self.sums, self.seconds)
    }
}

/// The most grid cells of 2r a beam walks across the photons' box, per axis: a radius
/// far below the box's size bins photons in cells of 1/`MAX_CELLS` of it instead
/// (still counting only those within r), so that no beam walks a million cells.
const MAX_CELLS: usize = 2048;

/// The largest side of the photons' bounding box.
fn extent(photons: &[VolumePhoton]) -> f32 {
    let empty = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let (lo, hi) = photons
        .par_iter()
        .fold(|| empty, |(lo, hi), p| (lo.min(p.p), hi.max(p.p)))
        .reduce(|| empty, |a, b| (a.0.min(b.0), a.1.max(b.1)));
    (hi - lo).max_element().max(0.0)
}

/// Each pixel's beam estimate Σ β·Tr·p·Φ/(π r²), the photons' flux times `scale`.
/// Pixels sum their beams in order, each beam its cells in order along it and each
/// cell's photons in the order they were traced: the same for any thread count.
pub fn estimate(beams: &[&[Beam]], photons: &[VolumePhoton], r: f32, scale: f64) -> Vec<DVec3> {
    let bin = r.max(extent(photons) / MAX_CELLS as f32);
    let sites: Vec<Option<Site>> = photons.par_iter().map(|p| Some(Site { p: p.p, radius: bin })).collect();
    let Some(grid) = Grid::build(&sites, Binning::Overlap) else { return vec![DVec3::ZERO; beams.len()] };
    let norm = scale / (std::f64::consts::PI * r as f64 * r as f64);
    beams
        .par_iter()
        .with_max_len(super::PIXELS_PER_TASK)
        .map(|bs| bs.iter().map(|b| b.gather(&grid, photons, r).as_dvec3()).sum::<DVec3>() * norm)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// The profile of a homogeneous medium that absorbs with σt = `sigma`.
    fn exact(sigma: Vec3) -> Profile {
        Profile::Exact(crate::media::Coefficients { sigma_a: sigma, sigma_s: Vec3::ZERO, le: Vec3::ZERO })
    }

    fn beam(o: Vec3, d: Vec3, len: f32, tr: Profile) -> Beam {
        Beam { o, d, len, beta: Vec3::ONE, phase: HenyeyGreenstein::new(0.0), tr }
    }

    /// Against brute force over every photon: the grid walk finds each photon within r
    /// of the segment (foot on it) exactly once, in any direction, and none other.
    #[test]
    fn a_beam_gathers_every_photon_near_it_once() {
        let mut rng = Rng::new(7);
        let mut u3 = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
        let photons: Vec<VolumePhoton> = (0..20_000)
            .map(|k| VolumePhoton { p: u3() * 4.0 - 2.0, wo: Vec3::Z, flux: Vec3::splat(1.0 + k as f32) })
            .collect();
        let r = 0.07;
        let sites: Vec<Option<Site>> = photons.iter().map(|p| Some(Site { p: p.p, radius: r })).collect();
        let Some(grid) = Grid::build(&sites, Binning::Overlap) else { panic!("no grid") };
        let uniform = HenyeyGreenstein::new(0.0).p(Vec3::Z, Vec3::Z);
        for k in 0..200 {
            let o = u3() * 5.0 - 2.5;
            let mut d = u3() * 2.0 - 1.0;
            // Rays along axes and planes too: the DDA's special cases.
            if k % 5 == 0 {
                d = Vec3::new(d.x, 0.0, 0.0);
            } else if k % 5 == 1 {
                d = Vec3::new(0.0, d.y, d.z);
            }
            let d = d.normalize();
            let len = if k % 7 == 0 { f32::INFINITY } else { 6.0 * u3().x };
            let b = beam(o, d, len, exact(Vec3::ZERO));
            let got = b.gather(&grid, &photons, r);
            let want: Vec3 = photons
                .iter()
                .filter(|p| {
                    let t = (p.p - o).dot(d);
                    (0.0..=len).contains(&t) && (p.p - (o + d * t)).length_squared() <= r * r
                })
                .map(|p| p.flux * uniform)
                .sum();
            assert!(
                (got - want).abs().max_element() <= 1e-3 * want.max_element().max(1.0),
                "beam {k}: {got} vs {want}"
            );
        }
    }

    /// A radius far below the photons' box (here 1 in 10,000) bins them in coarser
    /// cells, so no beam walks millions of them; it still gathers exactly the photons
    /// within r.
    #[test]
    fn a_tiny_radius_in_a_huge_box_gathers_what_brute_force_does() {
        let mut rng = Rng::new(11);
        let mut u3 = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
        let mut photons: Vec<VolumePhoton> =
            (0..5000).map(|_| VolumePhoton { p: u3() * 1e4 - 5e3, wo: Vec3::Z, flux: Vec3::ONE }).collect();
        photons.extend((0..20_000).map(|_| {
            let u = u3();
            VolumePhoton { p: Vec3::new(200.0 * u.x - 100.0, 4.0 * u.y - 2.0, 4.0 * u.z - 2.0), wo: Vec3::Z, flux: u }
        }));
        assert!(extent(&photons) / MAX_CELLS as f32 > 4.0);
        let r = 1.0;
        let pixels: Vec<Vec<Beam>> = (0..50)
            .map(|k| {
                let o = Vec3::new(-150.0, (k % 7) as f32 * 0.3 - 1.0, (k % 5) as f32 * 0.4 - 0.8);
                let d = Vec3::new(1.0, 0.01 * (k % 3) as f32, -0.004 * (k % 4) as f32).normalize();
                vec![beam(o, d, 60.0 + 4.0 * k as f32, exact(Vec3::ZERO))]
            })
            .collect();
        let lists: Vec<&[Beam]> = pixels.iter().map(|b| b.as_slice()).collect();
        let got = estimate(&lists, &photons, r, 1.0);
        let uniform = HenyeyGreenstein::new(0.0).p(Vec3::Z, Vec3::Z) as f64;
        for (k, b) in pixels.iter().enumerate() {
            let b = &b[0];
            let near = photons.iter().filter(|p| {
                let t = (p.p - b.o).dot(b.d);
                (0.0..=b.len).contains(&t) && (p.p - (b.o + b.d * t)).length_squared() <= r * r
            });
            let want = near.map(|p| p.flux.as_dvec3()).sum::<DVec3>() * uniform / std::f64::consts::PI;
            assert!(want.x > 0.0, "beam {k} passes no photon");
            assert!((got[k] - want).abs().max_element() <= 1e-4 * want.max_element(), "beam {k}: {} vs {want}", got[k]);
        }
    }

    /// Gathering in blocks (as a pass with many photons in media does) sums what one
    /// gather of them all does, pixel by pixel, and holds no more than a block.
    #[test]
    fn blocks_of_photons_add_up_to_one_gather() {
        let mut rng = Rng::new(3);
        let mut u3 = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
        let photons: Vec<VolumePhoton> =
            (0..5000).map(|_| VolumePhoton { p: u3() * 2.0 - 1.0, wo: u3().normalize(), flux: u3() }).collect();
        let pixels: Vec<Vec<Beam>> = (0..300)
            .map(|k| {
                let (o, d) = (u3() * 4.0 - 2.0, (u3() - 0.5).normalize());
                (0..k % 3).map(|_| beam(o, d, 3.0, exact(Vec3::splat(0.3)))).collect()
            })
            .collect();
        let lists = || pixels.iter().map(|b| b.as_slice()).collect::<Vec<_>>();
        let whole = estimate(&lists(), &photons, 0.1, 2.0);
        let mut g = Gather::new(lists(), 0.1, 2.0);
        g.block = 700;
        for chunk in photons.chunks(256) {
            g.add(chunk.to_vec());
            assert!(g.pending.len() < 700);
        }
        let (blocks, _) = g.finish();
        assert!(whole.iter().filter(|s| s.max_element() > 0.0).count() > 50, "too few pixels gather anything");
        for (a, b) in blocks.iter().zip(&whole) {
            assert!((*a - *b).abs().max_element() <= 1e-5 * b.max_element().max(1e-30), "{a} vs {b}");
        }
    }

    /// The transmittance weights each photon at its foot; photons beyond either end or
    /// farther than r from the line do not count; the phase function favours, for g > 0,
    /// photons travelling on toward the camera.
    #[test]
    fn photons_are_weighted_by_the_transmittance_to_their_foot_and_the_phase() {
        let ph = |x: f32, y: f32, wo: Vec3| VolumePhoton { p: Vec3::new(x, y, 0.0), wo, flux: Vec3::ONE };
        // The beam runs along +x from the camera: a photon travelling toward the camera
        // (along -x) arrived from +x.
        let (toward, away) = (Vec3::X, -Vec3::X);
        let photons = [ph(1.0, 0.01, toward), ph(3.0, -0.05, away), ph(-0.05, 0.0, toward), ph(10.05, 0.0, toward)];
        let photons = [&photons[..], &[ph(5.0, 0.11, toward)]].concat();
        let sites: Vec<Option<Site>> = photons.iter().map(|p| Some(Site { p: p.p, radius: 0.1 })).collect();
        let Some(grid) = Grid::build(&sites, Binning::Overlap) else { panic!("no grid") };
        let mut b = beam(Vec3::ZERO, Vec3::X, 10.0, exact(Vec3::new(0.5, 1.0, 0.0)));
        b.phase = HenyeyGreenstein::new(0.5);
        let got = b.gather(&grid, &photons, 0.1);
        let (fwd, back) = (b.phase.p(-Vec3::X, toward), b.phase.p(-Vec3::X, away));
        assert!(fwd > 3.0 * back, "forward {fwd}, backward {back}");
        let want = b.tr.at(1.0) * fwd + b.tr.at(3.0) * back;
        assert!((got - want).abs().max_element() < 1e-6, "{got} vs {want}");
        let steps = Profile::Steps(vec![(0.5, Vec3::splat(0.5)), (2.0, Vec3::splat(0.25))]);
        assert_eq!(steps.at(0.1), Vec3::ONE);
        assert_eq!(steps.at(1.0), Vec3::splat(0.5));
        assert_eq!(steps.at(7.0), Vec3::splat(0.25));
    }
}
