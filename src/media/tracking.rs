//! Media whose coefficients vary over a box: the grids ([`super::grid`],
//! [`super::rgbgrid`]) and the procedural cloud ([`super::cloud`]), tracked against a
//! majorant grid as pbrt-v4 does.
//!
//! ```text
//! MakeNamedMedium "smoke" "string type" "uniformgrid" "point3 p0" [-1 0 -1] "point3 p1" [1 2 1] ...
//! ```
//!
//! The box `p0`–`p1` (in the medium's space, the CTM at its statement) is split into
//! 16³ voxels (a NanoVDB medium's into 64³, as pbrt-v4's), each holding an upper bound
//! of σt inside it. A ray walks the voxels it crosses (a 3D DDA) and samples tentative
//! collisions at each voxel's bound, so a grid costs what its density warrants where it
//! is dense and little where it is empty.
//!
//! Colored media are tracked with one majorant for all channels (the largest) and
//! *spectral tracking* (Kutz et al. 2017): at a tentative collision the path scatters
//! with the probability its throughput-weighted σt gives, and the weights correct for
//! each channel. With equal channels this is plain delta tracking. Transmittance is
//! ratio tracking per channel; emission (σa·Le, pbrt-v4's grids) is summed over the
//! tentative collisions of a ratio-tracking walk.

use super::Flight;
use super::lanes::Lanes;
use super::phase::HenyeyGreenstein;
use crate::sampling::Sampler;
use glam::{DMat4, Vec3};
use std::sync::Arc;

/// Tracking steps one ray segment may take before it stops (Tr = 0, no scattering).
const MAX_STEPS: u32 = 1 << 20;

/// Tentative collisions a voxel's piece of a walk may expect at its majorant before
/// it is walked in shorter pieces, each at the bound of its own box.
const SPLIT_ABOVE: f32 = 256.0;

/// How far (in the unit cube) a piece's box reaches past its ends, so that rounding in
/// the points a walk looks up never leaves the box its bound was taken over.
const BOX_MARGIN: f32 = 1e-6;

/// Majorant voxels along each axis (pbrt-v4's 16).
const RES: usize = 16;

/// The coefficients at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Props {
    /// σt as tracked (pbrt-v3's grid tracks its first channel only).
    pub sigma_t: Vec3,
    pub sigma_s: Vec3,
    /// σa·Le, where asked for.
    pub emitted: Vec3,
}

/// What varies over the box: coefficients at a point of the unit cube.
pub trait Field: std::fmt::Debug + Send + Sync {
    /// The coefficients at `u` (the unit cube spans the box) at the lanes'
    /// wavelengths; `emitted` only where `emission` is asked.
    fn at(&self, u: Vec3, emission: bool, lanes: Lanes) -> Props;
    /// An upper bound of every channel of σt over the box `lo`–`hi` of the unit cube
    /// (of every wavelength, where the medium was read for a spectral scene).
    fn majorant(&self, lo: Vec3, hi: Vec3) -> f32;
    /// A bound of σt over a small box that a walk's piece crosses; a field that can
    /// bound its values more tightly there than over its samples gives that.
    fn fine_majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
        self.majorant(lo, hi)
    }
    fn emissive(&self) -> bool;
    /// An upper bound of every channel of σa·Le anywhere (0 for media that do not emit).
    fn emission_bound(&self) -> f32 {
        0.0
    }
    /// Majorant voxels per axis: 1 where σt has one bound over the whole box.
    fn majorant_res(&self) -> usize {
        RES
    }
}

/// A medium tracked through its box.
#[derive(Clone, Debug)]
pub struct Tracked {
    pub phase: HenyeyGreenstein,
    /// World to the unit cube of the box, and back.
    world_to_unit: DMat4,
    box_to_world: DMat4,
    res: usize,
    majorants: Vec<f32>,
    field: Arc<dyn Field>,
}

impl PartialEq for Tracked {
    fn eq(&self, other: &Tracked) -> bool {
        Arc::ptr_eq(&self.field, &other.field) && self.world_to_unit == other.world_to_unit
    }
}

/// Where a ray runs through the box: its origin and direction in the unit cube
/// (per unit of world length) and the world distances [t0, t1] inside.
struct Segment {
    o: Vec3,
    d: Vec3,
    t0: f32,
    t1: f32,
}

/// How a walk crosses one piece of a span.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Piece {
    /// Tentative collisions at the piece's bound from its start to its end.
    Tracked,
    /// A piece too thin to resolve steps at its bound (beside a density spike): taken
    /// as uniform, with one chance of a collision, 1 − exp(−μ·length), at its middle.
    Sliver,
    /// The rest of a span that took [`MAX_STEPS`] pieces: the walk stops there.
    Exhausted,
}

/// How a walk over tentative collisions ended.
enum Walk {
    End,
    Stopped,
    Exhausted,
}

impl Tracked {
    /// `box_to_world` maps the unit cube onto the box in the world.
    pub fn new(box_to_world: DMat4, phase: HenyeyGreenstein, field: Arc<dyn Field>) -> Tracked {
        use rayon::prelude::*;
        let res = field.majorant_res().max(1);
        // In parallel: a NanoVDB medium's 64³ voxels each scan the grid's voxels.
        let majorants = (0..res * res * res)
            .into_par_iter()
            .map(|i| {
                let lo = Vec3::new((i % res) as f32, (i / res % res) as f32, (i / (res * res)) as f32) / res as f32;
                field.majorant(lo, lo + 1.0 / res as f32)
            })
            .collect();
        Tracked { phase, world_to_unit: box_to_world.inverse(), box_to_world, res, majorants, field }
    }

    /// Majorant voxels per axis.
    pub fn res(&self) -> usize {
        self.res
    }

    pub fn box_to_world(&self) -> DMat4 {
        self.box_to_world
    }

    /// The majorant of voxel `i` (x fastest).
    pub fn majorant_at(&self, i: usize) -> f32 {
        self.majorants[i]
    }

    /// σa·Le at a point of the unit cube of the box.
    pub fn emitted_at_unit(&self, u: Vec3, lanes: Lanes) -> Vec3 {
        self.field.at(u, true, lanes).emitted
    }

    /// σa·Le at a world point (0 outside the box).
    pub fn emitted_at(&self, p: Vec3, lanes: Lanes) -> Vec3 {
        let u = self.world_to_unit.transform_point3(p.as_dvec3()).as_vec3();
        if u.min_element() < 0.0 || u.max_element() > 1.0 {
            return Vec3::ZERO;
        }
        self.emitted_at_unit(u, lanes)
    }

    pub fn emissive(&self) -> bool {
        self.field.emissive()
    }

    /// The largest majorant (for the overflow check at reading; NaN where one is).
    pub fn max_majorant(&self) -> f32 {
        self.majorants.iter().fold(0f32, |m, &v| if m.is_nan() || v.is_nan() { f32::NAN } else { m.max(v) })
    }

    /// A bound of σa·Le (for the overflow check at reading).
    pub fn emission_bound(&self) -> f32 {
        self.field.emission_bound()
    }

    /// The part of the world ray (origin, unit direction, length) inside the box.
    fn clip(&self, o: Vec3, d: Vec3, len: f32) -> Option<Segment> {
        let og = self.world_to_unit.transform_point3(o.as_dvec3()).as_vec3();
        let dg = self.world_to_unit.transform_vector3(d.as_dvec3()).as_vec3();
        let (mut t0, mut t1) = (0f32, len);
        for a in 0..3 {
            let inv = 1.0 / dg[a];
            let (mut near, mut far) = ((0.0 - og[a]) * inv, (1.0 - og[a]) * inv);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            // NaN (a zero direction component on a slab's plane) keeps the old bound.
            t0 = if near > t0 { near } else { t0 };
            t1 = if far < t1 { far } else { t1 };
            if t0 > t1 {
                return None;
            }
        }
        Some(Segment { o: og, d: dg, t0, t1 })
    }

    /// The majorant voxels the span crosses, in order: `visit(ta, tb, majorant)` for
    /// each piece until it returns false; returns whether it never did.
    fn voxels(&self, s: &Segment, mut visit: impl FnMut(f32, f32, f32) -> bool) -> bool {
        let n = self.res as i32;
        let p = (s.o + s.d * s.t0) * n as f32;
        let d = s.d * n as f32;
        let (mut voxel, mut next, mut delta, mut step) = ([0i32; 3], [f32::INFINITY; 3], [0f32; 3], [0i32; 3]);
        for a in 0..3 {
            voxel[a] = (p[a].floor() as i32).clamp(0, n - 1);
            if d[a] > 0.0 {
                (step[a], delta[a]) = (1, 1.0 / d[a]);
                next[a] = s.t0 + (voxel[a] as f32 + 1.0 - p[a]) / d[a];
            } else if d[a] < 0.0 {
                (step[a], delta[a]) = (-1, -1.0 / d[a]);
                next[a] = s.t0 + (voxel[a] as f32 - p[a]) / d[a];
            }
        }
        let mut t = s.t0;
        loop {
            let a = if next[0] < next[1] {
                if next[0] < next[2] { 0 } else { 2 }
            } else if next[1] < next[2] {
                1
            } else {
                2
            };
            let end = next[a].min(s.t1);
            let i = (voxel[2] as usize * self.res + voxel[1] as usize) * self.res + voxel[0] as usize;
            if end > t && !visit(t, end, self.majorants[i]) {
                return false;
            }
            if end >= s.t1 {
                return true;
            }
            t = end;
            voxel[a] += step[a];
            if !(0..n).contains(&voxel[a]) {
                return true;
            }
            next[a] += delta[a];
        }
    }

    /// Tentative collisions along the span, at each voxel's majorant (or its pieces',
    /// [`Self::refined`]): `hit(t, μ, sampler)` for each until it returns false.
    fn walk<S: Sampler>(
        &self,
        s: &Segment,
        lanes: Lanes,
        sampler: &mut S,
        mut hit: impl FnMut(f32, f32, &mut S) -> bool,
    ) -> Walk {
        let mut steps = 0u32;
        let mut ended = Walk::End;
        let mut track = |ta: f32, tb: f32, mu: f32, piece: Piece| {
            if piece == Piece::Exhausted {
                ended = Walk::Exhausted;
                return false;
            }
            if mu <= 0.0 {
                return true;
            }
            let (mut t, mut fine) = (ta, None::<f64>);
            loop {
                let step = -((1.0 - sampler.get1d()).max(f32::MIN_POSITIVE).ln() / mu);
                let next = t + step;
                if next == t && step > 0.0 || fine.is_some() || piece == Piece::Sliver {
                    if piece == Piece::Sliver {
                        // Its one chance of a collision, at its middle.
                        if f64::from(step) >= f64::from(tb) - f64::from(ta) {
                            return true;
                        }
                        t = 0.5 * (ta + tb);
                    } else {
                        // DEVIATION(pbrt): robustness. Where a step is below the
                        // precision of t (μ near a density spike), f32 t stops moving
                        // and every tentative collision falls on one point; t then runs
                        // in f64.
                        let f = fine.get_or_insert(f64::from(t));
                        *f += f64::from(step);
                        if *f >= f64::from(tb) {
                            return true;
                        }
                        t = *f as f32;
                    }
                } else {
                    t = next;
                    if t >= tb {
                        return true;
                    }
                }
                steps += 1;
                if steps > MAX_STEPS {
                    ended = Walk::Exhausted;
                    return false;
                }
                if !hit(t, mu, sampler) {
                    ended = Walk::Stopped;
                    return false;
                }
                if piece == Piece::Sliver {
                    return true;
                }
            }
        };
        self.voxels(s, |ta, tb, mu| self.refined((s, lanes), (ta, tb, mu), &mut track));
        ended
    }

    /// Tracks the piece `ta`–`tb` of a span at the bound `mu` (`track`), or, where
    /// that bound would take more than [`SPLIT_ABOVE`] tentative collisions, marches
    /// over it in pieces that each expect at most that many at the bound of their own
    /// box (each as long as the last one's bound allows, shortened where the density
    /// ahead is higher); returns false once `track` does. A piece too short to shorten
    /// whose bound is still that large is a [`Piece::Sliver`], taken as uniform at σt
    /// in its middle.
    // DEVIATION(pbrt): robustness. pbrt-v4 tracks each voxel of its 16³ majorant grid
    // at that voxel's bound; a density spike (one sample of 2e9 in a smoke grid) then
    // makes every ray through the voxels about it take hundreds of millions of null
    // collisions, where most of them see little of the spike: a render that never
    // ends. Any piecewise bound keeps the estimates unbiased; pieces of fewer expected
    // collisions track exactly as before, so ordinary media render bit for bit alike.
    fn refined(
        &self,
        (s, lanes): (&Segment, Lanes),
        (ta, tb, mu): (f32, f32, f32),
        track: &mut impl FnMut(f32, f32, f32, Piece) -> bool,
    ) -> bool {
        if mu * (tb - ta) <= SPLIT_ABOVE {
            return track(ta, tb, mu, Piece::Tracked);
        }
        // Pieces no shorter than the points along the ray can resolve: shorter ones
        // would all look up the same point.
        let d_max = s.d.abs().max_element();
        let shortest = 4.0 * f32::EPSILON * (s.o.abs().max_element() + d_max * tb.abs() + BOX_MARGIN) / d_max;
        let (mut a, mut len, mut pieces) = (ta, SPLIT_ABOVE / mu, 0u32);
        while a < tb {
            pieces += 1;
            if pieces > MAX_STEPS {
                return track(a, tb, mu, Piece::Exhausted);
            }
            let (b, bound) = self.piece((s, a), (a + len.max(shortest)).min(tb), mu, shortest);
            let going = match bound {
                Some(m) => track(a, b, m, Piece::Tracked),
                None => {
                    let local = self.field.at(s.o + s.d * (0.5 * (a + b)), false, lanes).sigma_t.max_element();
                    track(a, b, local.min(mu), Piece::Sliver)
                }
            };
            if !going {
                return false;
            }
            len = match bound {
                Some(m) if m > 0.0 => SPLIT_ABOVE / m,
                Some(_) => tb - b,
                None => 2.0 * (b - a),
            };
            a = b;
        }
        true
    }

    /// The piece of a walk from `a`: up to `b`, or shorter where its box's bound
    /// would expect more than [`SPLIT_ABOVE`] tentative collisions, with that bound
    /// (at most `mu`); `None` for a piece that reached `shortest` with its bound still
    /// that large.
    fn piece(&self, (s, a): (&Segment, f32), mut b: f32, mu: f32, shortest: f32) -> (f32, Option<f32>) {
        loop {
            let (pa, pb) = (s.o + s.d * a, s.o + s.d * b);
            let m = self.field.fine_majorant(pa.min(pb) - BOX_MARGIN, pa.max(pb) + BOX_MARGIN).min(mu);
            if m * (b - a) <= SPLIT_ABOVE {
                return (b, Some(m));
            }
            let shorter = a + (0.5 * (b - a)).min(SPLIT_ABOVE / m);
            if shorter - a < shortest || shorter >= b {
                return (b, None);
            }
            b = shorter;
        }
    }

    /// Spectral tracking along a segment of parameter length `t_max` of a ray
    /// `o + t·d`: where it scatters, the weight before σs and σs there.
    pub fn sample_flight(&self, o: Vec3, d: Vec3, t_max: f32, sampler: &mut impl Sampler, lanes: Lanes) -> Flight {
        let dlen = d.length();
        let Some(span) = self.clip(o, d / dlen, t_max * dlen) else { return Flight::Through { weight: Vec3::ONE } };
        let (mut w, mut scatter) = (Vec3::ONE, None);
        let walk = self.walk(&span, lanes, sampler, |t, mu, sampler| {
            let props = self.field.at(span.o + span.d * t, false, lanes);
            let p_real = ((w * props.sigma_t).element_sum() / (mu * w.element_sum())).min(1.0);
            if sampler.get1d() < p_real {
                let weight = w / (mu * p_real);
                scatter = Some(Flight::Scatter { t: t / dlen, weight, sigma_s: props.sigma_s, sigma_t: props.sigma_t });
                return false;
            }
            w *= (Vec3::splat(mu) - props.sigma_t).max(Vec3::ZERO) / (mu * (1.0 - p_real));
            w != Vec3::ZERO
        });
        match (scatter, walk) {
            (Some(f), _) => f,
            (None, Walk::End) => Flight::Through { weight: w },
            (None, _) => Flight::Through { weight: Vec3::ZERO },
        }
    }

    /// Ratio tracking: an unbiased estimate of the transmittance over `dist` world
    /// units from `o` along unit direction `d`, with pbrt-v3's Russian roulette below 0.1.
    pub fn transmittance(&self, o: Vec3, d: Vec3, dist: f32, sampler: &mut impl Sampler, lanes: Lanes) -> Vec3 {
        let Some(span) = self.clip(o, d, dist) else { return Vec3::ONE };
        let mut tr = Vec3::ONE;
        match self.walk(&span, lanes, sampler, |t, mu, sampler| {
            ratio_step(&mut tr, self.field.at(span.o + span.d * t, false, lanes), mu, sampler)
        }) {
            Walk::Exhausted => Vec3::ZERO,
            _ => tr,
        }
    }

    /// Ratio tracking over `dist` world units from `o` along unit direction `d`,
    /// recording (distance, transmittance so far) at each tentative collision: the
    /// transmittance to any distance t is the last record at or before t (1 before the
    /// first), an unbiased estimate for every t at once (the beam radiance estimate
    /// reads it at each photon it gathers).
    pub fn transmittance_steps(
        &self,
        o: Vec3,
        d: Vec3,
        dist: f32,
        sampler: &mut impl Sampler,
        lanes: Lanes,
    ) -> Vec<(f32, Vec3)> {
        let mut steps = Vec::new();
        let Some(span) = self.clip(o, d, dist) else { return steps };
        let mut tr = Vec3::ONE;
        let walk = self.walk(&span, lanes, sampler, |t, mu, sampler| {
            let more = ratio_step(&mut tr, self.field.at(span.o + span.d * t, false, lanes), mu, sampler);
            steps.push((t, tr));
            more
        });
        if let (Walk::Exhausted, Some(last)) = (walk, steps.last_mut()) {
            last.1 = Vec3::ZERO;
        }
        steps
    }

    /// An unbiased estimate of the emission ∫ Tr·σa·Le dt over `dist` world units from
    /// `o` along unit direction `d`: σa·Le/μ at each tentative collision, weighted by
    /// the ratio-tracking transmittance up to it.
    pub fn emission(&self, o: Vec3, d: Vec3, dist: f32, sampler: &mut impl Sampler, lanes: Lanes) -> Vec3 {
        if !self.emissive() {
            return Vec3::ZERO;
        }
        let Some(span) = self.clip(o, d, dist) else { return Vec3::ZERO };
        let (mut tr, mut sum) = (Vec3::ONE, Vec3::ZERO);
        self.walk(&span, lanes, sampler, |t, mu, sampler| {
            let props = self.field.at(span.o + span.d * t, true, lanes);
            sum += tr * props.emitted / mu;
            ratio_step(&mut tr, props, mu, sampler)
        });
        sum
    }
}

/// One step of ratio tracking: the transmittance takes the null-collision fraction,
/// with Russian roulette once every channel is below 0.1; false where it ends at 0.
fn ratio_step(tr: &mut Vec3, props: Props, mu: f32, sampler: &mut impl Sampler) -> bool {
    *tr *= (Vec3::ONE - props.sigma_t / mu).max(Vec3::ZERO);
    let m = tr.max_element();
    if m < 0.1 {
        let q = (1.0 - m).max(0.05);
        if sampler.get1d() < q {
            *tr = Vec3::ZERO;
            return false;
        }
        *tr /= 1.0 - q;
    }
    *tr != Vec3::ZERO
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// σt = (1, 2, 4)·ramp(x), σs half of it, σa·Le = (0.5, 0, 1)·ramp(x), where the
    /// ramp rises from 0 at x = 0 to 2 at x = 1 (majorants are exact per voxel).
    #[derive(Debug)]
    struct Ramp;

    impl Field for Ramp {
        fn at(&self, u: Vec3, emission: bool, _lanes: Lanes) -> Props {
            let r = 2.0 * u.x;
            let emitted = if emission { Vec3::new(0.5, 0.0, 1.0) * r } else { Vec3::ZERO };
            Props { sigma_t: Vec3::new(1.0, 2.0, 4.0) * r, sigma_s: Vec3::new(0.5, 1.0, 2.0) * r, emitted }
        }
        fn majorant(&self, _lo: Vec3, hi: Vec3) -> f32 {
            8.0 * hi.x
        }
        fn emissive(&self) -> bool {
            true
        }
    }

    /// The box [0, 2]³ in the world: world x = 2·u.x.
    fn ramp() -> Tracked {
        Tracked::new(DMat4::from_scale(glam::DVec3::splat(2.0)), HenyeyGreenstein::new(0.0), Arc::new(Ramp))
    }

    /// Along x from world x = −1 to x = 1.5 (into the box and three quarters through):
    /// the optical depth of channel c is σ_c·∫₀^1.5 x dx = σ_c·1.125.
    #[test]
    fn spectral_tracking_ratio_tracking_and_emission_are_unbiased_per_channel() {
        let t = ramp();
        let (o, d) = (Vec3::new(-1.0, 1.0, 1.0), Vec3::X);
        let tau = Vec3::new(1.0, 2.0, 4.0) * 1.125;
        let want_tr = Vec3::new((-tau.x).exp(), (-tau.y).exp(), (-tau.z).exp());
        // ∫₀^1.5 Tr(x)·σs(x) dx = (σs/σt)·(1 − Tr) per channel: half of 1 − Tr.
        let want_s = (Vec3::ONE - want_tr) * 0.5;
        // ∫₀^1.5 exp(−σ x²/2)·k·x dx = (k/σ)·(1 − Tr) per channel, k = (0.5, 0, 1).
        let want_e = Vec3::new(0.5, 0.0, 0.25) * (Vec3::ONE - want_tr);
        let mut rng = Rng::new(11);
        let n = 200_000;
        let (mut through, mut scattered, mut ratio, mut emitted) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        for _ in 0..n {
            match t.sample_flight(o, d * 2.0, 1.25, &mut rng, None) {
                Flight::Through { weight } => through += weight,
                Flight::Scatter { t: s, weight, sigma_s, .. } => {
                    assert!((0.5..1.25).contains(&s), "scattered outside the box or the segment at t = {s}");
                    scattered += weight * sigma_s;
                }
            }
            ratio += t.transmittance(o, d, 2.5, &mut rng, None);
            emitted += t.emission(o, d, 2.5, &mut rng, None);
        }
        let close = |got: Vec3, want: Vec3, what: &str| {
            let got = got / n as f32;
            assert!((got - want).abs().max_element() < 6e-3, "{what}: {got} against {want}");
        };
        close(through, want_tr, "tracking's passes");
        close(scattered, want_s, "tracking's scattering");
        close(ratio, want_tr, "ratio tracking");
        close(emitted, want_e, "emission");
    }

    /// σt = 1 in the unit cube but for a wall of 10⁹ at x ≈ ½ over y < ½; its coarse
    /// bound sees the wall's x only (as a grid's sample maximum reaches past where the
    /// samples weigh), its fine one the wall's y too. `at` counts its calls.
    #[derive(Debug, Default)]
    struct Spike(std::sync::atomic::AtomicUsize);

    impl Spike {
        fn wall(lo: Vec3, hi: Vec3, all_y: bool) -> bool {
            lo.x <= 0.5005 && hi.x >= 0.4995 && (all_y || lo.y < 0.5)
        }
    }

    impl Field for Spike {
        fn at(&self, u: Vec3, _emission: bool, _lanes: Lanes) -> Props {
            self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let sigma = if Spike::wall(u, u, false) { 1e9 } else { 1.0 };
            Props { sigma_t: Vec3::splat(sigma), sigma_s: Vec3::splat(sigma), emitted: Vec3::ZERO }
        }
        fn majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
            if Spike::wall(lo, hi, true) { 1e9 } else { 1.0 }
        }
        fn fine_majorant(&self, lo: Vec3, hi: Vec3) -> f32 {
            if Spike::wall(lo, hi, false) { 1e9 } else { 1.0 }
        }
        fn emissive(&self) -> bool {
            false
        }
    }

    /// A ray beside the wall (y = ¾) crosses voxels bounded at 10⁹: tracked at that
    /// bound it took a million null collisions a voxel and then gave up (Tr = 0); the
    /// finer pieces give e^−1 at a few lookups a ray. Through the wall (y = ¼) it is 0.
    #[test]
    fn a_density_spike_beside_the_ray_costs_little_and_biases_nothing() {
        let spike = Arc::new(Spike::default());
        let t = Tracked::new(DMat4::IDENTITY, HenyeyGreenstein::new(0.0), spike.clone());
        let mut rng = Rng::new(3);
        let n = 20_000;
        spike.0.store(0, std::sync::atomic::Ordering::Relaxed);
        let mut beside = 0f64;
        let mut scattered = 0;
        for _ in 0..n {
            beside += f64::from(t.transmittance(Vec3::new(-0.5, 0.75, 0.5), Vec3::X, 2.0, &mut rng, None).x);
            let flight = t.sample_flight(Vec3::new(-0.5, 0.75, 0.5), Vec3::X, 2.0, &mut rng, None);
            scattered += matches!(flight, Flight::Scatter { .. }) as u32;
        }
        let lookups = spike.0.load(std::sync::atomic::Ordering::Relaxed) as f64 / n as f64;
        let beside = beside / n as f64;
        let want = (-1f64).exp();
        assert!((beside - want).abs() < 0.02, "transmittance beside the wall {beside}, not {want}");
        let scattered = scattered as f64 / n as f64;
        assert!((scattered - (1.0 - want)).abs() < 0.02, "scattered {scattered}, not {}", 1.0 - want);
        assert!(lookups < 20.0, "{lookups} lookups a ray");
        let through = t.transmittance(Vec3::new(-0.5, 0.25, 0.5), Vec3::X, 2.0, &mut rng, None).x;
        assert_eq!(through, 0.0, "the wall lets light through");
    }

    /// The walk visits voxels in order and covers the clipped span exactly once.
    #[test]
    fn the_dda_covers_the_span_in_order() {
        let t = ramp();
        for d in [Vec3::new(1.0, 0.3, -0.2), Vec3::new(-0.4, -1.0, 0.7), Vec3::Z] {
            let d = d.normalize();
            let o = Vec3::splat(1.0) - d * 3.0;
            let span = t.clip(o, d, 10.0).expect("the ray crosses the box");
            let mut last = span.t0;
            t.voxels(&span, |ta, tb, _| {
                assert!((ta - last).abs() < 1e-5 && tb > ta, "gap or overlap at {ta} after {last}");
                last = tb;
                true
            });
            assert!((last - span.t1).abs() < 1e-4, "ended at {last}, the box at {}", span.t1);
        }
    }
}
