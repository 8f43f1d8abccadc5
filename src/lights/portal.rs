//! pbrt-v4's portal for an infinite light: the sky reaches the scene only through a
//! rectangle, such as a window, and is sampled only where it can be seen through it.
//!
//! ```text
//! LightSource "infinite" "string filename" "sky.exr"
//!     "point3 portal" [0 0 0  0 1 0  1 1 0  1 0 0]    # world space, not the CTM's
//! LightSource "infinite" "rgb L" [1 1 1] "point3 portal" [...]   # a 1×1 map of L
//! ```
//!
//! As pbrt-v4's `PortalImageInfiniteLight`:
//! - The portal's frame has x along corner 0 → 3, y along 0 → 1, and z = x × y; the
//!   sky is the half of the sphere on the +z side. A direction (x, y, z) there maps to
//!   (u, v) = ((atan2(x, z) + π/2)/π, (atan2(y, z) + π/2)/π), whose solid angle per unit
//!   area is π²(1 − x²)(1 − y²)/z.
//! - The equal-area map is resampled once, bilinearly, into a square image in (u, v)
//!   of its own resolution; a direction reads that image's nearest texel.
//! - A ray leaving `o` sees the sky only if its (u, v) lies between those of corners
//!   0 and 2 seen from `o` (the window): elsewhere, and behind the portal, it is black.
//! - Light samples are drawn in the window seen from the point lit, from a
//!   piecewise-constant density of each texel's channel mean times its solid angle;
//!   photons from the whole half-sphere, with that density.

use crate::math::equal_area;
use crate::spectrum::{Rgb, luminance};
use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// The whole (u, v) square, as a window: every direction on the sky's side.
const WHOLE: [f64; 4] = [0.0, 0.0, 1.0, 1.0];

/// The four corners of a portal (world space), and its frame.
#[derive(Clone, Copy, Debug)]
pub struct Portal {
    pub corners: [DVec3; 4],
    /// Rows: the frame's x, y and z axes.
    local_from_world: DMat3,
}

impl Portal {
    /// `None` when two edges have no length (no frame can be made).
    pub fn new(corners: [DVec3; 4]) -> Option<Portal> {
        let x = (corners[3] - corners[0]).try_normalize()?;
        let y = (corners[1] - corners[0]).try_normalize()?;
        let z = x.cross(y).try_normalize()?;
        Some(Portal { corners, local_from_world: DMat3::from_cols(x, y, z).transpose() })
    }

    /// Whether the corners make a rectangle, as pbrt-v4 checks (it warns otherwise and
    /// renders all the same).
    pub fn is_rectangle(&self) -> bool {
        let c = &self.corners;
        let unit = |a: DVec3, b: DVec3| (b - a).normalize_or_zero();
        let (p01, p12, p32, p03) = (unit(c[0], c[1]), unit(c[1], c[2]), unit(c[3], c[2]), unit(c[0], c[3]));
        let parallel = (p01.dot(p32) - 1.0).abs() <= 1e-3 && (p12.dot(p03) - 1.0).abs() <= 1e-3;
        let square = [p01.dot(p12), p12.dot(p32), p32.dot(p03), p03.dot(p01)].iter().all(|d| d.abs() <= 1e-3);
        parallel && square
    }

    /// The (u, v) of a world direction and the solid angle per unit (u, v) area there;
    /// `None` behind the portal.
    pub fn uv_of(&self, w: DVec3) -> Option<([f64; 2], f64)> {
        let l = self.local_from_world * w.normalize();
        if l.z <= 0.0 {
            return None;
        }
        let jacobian = PI * PI * (1.0 - l.x * l.x) * (1.0 - l.y * l.y) / l.z;
        let u = ((l.x.atan2(l.z) + FRAC_PI_2) / PI).clamp(0.0, 1.0);
        let v = ((l.y.atan2(l.z) + FRAC_PI_2) / PI).clamp(0.0, 1.0);
        Some(([u, v], jacobian))
    }

    /// The unit world direction of a (u, v) and the solid angle per unit area there.
    pub fn direction_of(&self, [u, v]: [f64; 2]) -> (DVec3, f64) {
        let (x, y) = ((-FRAC_PI_2 + u * PI).tan(), (-FRAC_PI_2 + v * PI).tan());
        let l = DVec3::new(x, y, 1.0).normalize();
        let jacobian = PI * PI * (1.0 - l.x * l.x) * (1.0 - l.y * l.y) / l.z;
        (self.local_from_world.transpose() * l, jacobian)
    }

    /// The (u, v) rectangle of the sky seen through the portal from `p`: [u0, v0, u1,
    /// v1]; `None` from behind it.
    pub fn window(&self, p: DVec3) -> Option<[f64; 4]> {
        let (a, _) = self.uv_of(self.corners[0] - p)?;
        let (b, _) = self.uv_of(self.corners[2] - p)?;
        Some([a[0].min(b[0]), a[1].min(b[1]), a[0].max(b[0]), a[1].max(b[1])])
    }

    /// The cosine between a world direction and the portal's normal (toward the sky).
    pub fn cos_to_normal(&self, w: DVec3) -> f64 {
        (self.local_from_world * w.normalize()).z
    }

    /// The portal's area (pbrt-v4's, from two edges).
    pub fn area(&self) -> f64 {
        (self.corners[1] - self.corners[0]).length() * (self.corners[3] - self.corners[0]).length()
    }
}

/// A piecewise-constant density on an n × n grid over [0,1]², sampled within any
/// rectangle of it (pbrt-v4's `WindowedPiecewiseConstant2D`): a summed-area table
/// interpolated bilinearly gives the exact integral over any rectangle.
#[derive(Clone, Debug)]
pub struct WindowedDistribution {
    n: usize,
    f: Vec<f64>,
    /// (n + 1)², row-major in v: `sat[j * (n + 1) + i]` sums the cells left of i and
    /// above j.
    sat: Vec<f64>,
}

impl WindowedDistribution {
    /// `f` row by row (v), each row n values (u); negative values count as 0.
    pub fn new(f: Vec<f64>, n: usize) -> WindowedDistribution {
        let f: Vec<f64> = f.into_iter().map(|x| if x > 0.0 { x } else { 0.0 }).collect();
        let m = n + 1;
        let mut sat = vec![0.0; m * m];
        for j in 0..n {
            let mut row = 0.0;
            for i in 0..n {
                row += f[j * n + i];
                sat[(j + 1) * m + i + 1] = sat[j * m + i + 1] + row;
            }
        }
        WindowedDistribution { n, f, sat }
    }

    /// ∫ of the density over [0, x] × [0, y], in cells (x, y ∈ [0, n]).
    fn integral_to(&self, x: f64, y: f64) -> f64 {
        let (n, m) = (self.n, self.n + 1);
        let (x, y) = (x.clamp(0.0, n as f64), y.clamp(0.0, n as f64));
        let (i, j) = ((x as usize).min(n - 1), (y as usize).min(n - 1));
        let (a, b) = (x - i as f64, y - j as f64);
        let s = |i: usize, j: usize| self.sat[j * m + i];
        (1.0 - a) * (1.0 - b) * s(i, j)
            + a * (1.0 - b) * s(i + 1, j)
            + (1.0 - a) * b * s(i, j + 1)
            + a * b * s(i + 1, j + 1)
    }

    /// ∫ over [x0, x1] × [y0, y1], in cells.
    fn integral(&self, [x0, y0, x1, y1]: [f64; 4]) -> f64 {
        self.integral_to(x1, y1) - self.integral_to(x0, y1) - self.integral_to(x1, y0) + self.integral_to(x0, y0)
    }

    fn cells(&self, [u0, v0, u1, v1]: [f64; 4]) -> [f64; 4] {
        let n = self.n as f64;
        [u0 * n, v0 * n, u1 * n, v1 * n]
    }

    /// A point of `window` ([u0, v0, u1, v1] in [0,1]²) and its density there (with
    /// respect to area in [0,1]²); `None` where the window holds no weight.
    pub fn sample(&self, u: [f64; 2], window: [f64; 4]) -> Option<([f64; 2], f64)> {
        let w @ [x0, y0, x1, y1] = self.cells(window);
        let total = self.integral(w);
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        // u: the marginal G(x) = ∫ over [x0, x] × [y0, y1], linear between cell edges.
        let g = |x: f64| self.integral([x0, y0, x, y1]);
        let x = invert_piecewise_linear(g, x0, x1, u[0] * total);
        let column = (x as usize).min(self.n - 1);
        // v: within that column, the cumulative of its cells.
        let m = self.n + 1;
        let c = |y: f64| {
            let y = y.clamp(0.0, self.n as f64);
            let j = (y as usize).min(self.n - 1);
            let below = self.sat[j * m + column + 1] - self.sat[j * m + column];
            below + (y - j as f64) * self.f[j * self.n + column]
        };
        let (c0, c1) = (c(y0), c(y1));
        if c1 <= c0 {
            return None;
        }
        let y = invert_piecewise_linear(|y| c(y) - c0, y0, y1, u[1] * (c1 - c0));
        let n = self.n as f64;
        let uv = [x / n, y / n];
        let pdf = self.pdf(uv, window);
        (pdf > 0.0).then_some((uv, pdf))
    }

    /// The density [`Self::sample`] gives `uv` within `window`.
    pub fn pdf(&self, [u, v]: [f64; 2], window: [f64; 4]) -> f64 {
        let [u0, v0, u1, v1] = window;
        if !(u0..=u1).contains(&u) || !(v0..=v1).contains(&v) {
            return 0.0;
        }
        let total = self.integral(self.cells(window));
        if total.is_nan() || total <= 0.0 {
            return 0.0;
        }
        let n = self.n as f64;
        let (i, j) = (((u * n) as usize).min(self.n - 1), ((v * n) as usize).min(self.n - 1));
        self.f[j * self.n + i] * n * n / total
    }
}

/// The x in [lo, hi] where the non-decreasing `g`, linear between integers, reaches
/// `target`: a search over the integers, then the line between two of them.
fn invert_piecewise_linear(g: impl Fn(f64) -> f64, lo: f64, hi: f64, target: f64) -> f64 {
    let (first, last) = (lo.floor() as i64 + 1, hi.ceil() as i64 - 1);
    // The edges strictly inside (lo, hi); find the first whose value passes target.
    let (mut a, mut b) = (first, last + 1);
    while a < b {
        let mid = a + (b - a) / 2;
        if g(mid as f64) <= target { a = mid + 1 } else { b = mid }
    }
    let left = if a == first { lo } else { (a - 1) as f64 };
    let right = if a > last { hi } else { a as f64 };
    let (gl, gr) = (g(left), g(right));
    let t = if gr > gl { ((target - gl) / (gr - gl)).clamp(0.0, 1.0) } else { 0.5 };
    (left + t * (right - left)).clamp(lo, hi)
}

/// An infinite light seen through a portal, ready to sample.
#[derive(Clone, Debug)]
pub struct PortalMap {
    portal: Portal,
    /// The sky resampled into the portal's (u, v), n × n, unscaled.
    texels: Vec<[f32; 3]>,
    n: usize,
    scale: Rgb,
    distribution: WindowedDistribution,
    /// pbrt-v4's `Phi` (in luminance), for choosing photon sources.
    pub power: f64,
}

impl PortalMap {
    /// `map`: the equal-area sky (square, `n` texels a side), light-space +z at its
    /// centre, oriented by `world_from_light`.
    pub fn new(map: &[[f32; 3]], n: usize, scale: Rgb, world_from_light: DMat3, portal: Portal) -> PortalMap {
        let light_from_world = world_from_light.inverse();
        // Each texel: its resampled value and the solid angle per unit area at its centre.
        let resampled: Vec<([f32; 3], f64)> = (0..n * n)
            .into_par_iter()
            .map(|i| {
                let uv = [((i % n) as f64 + 0.5) / n as f64, ((i / n) as f64 + 0.5) / n as f64];
                let (w, jacobian) = portal.direction_of(uv);
                let st = equal_area::sphere_to_square((light_from_world * w).normalize());
                (bilerp_octahedral(map, n, st), jacobian)
            })
            .collect();
        let weights = resampled.iter().map(|(t, j)| (t[0] + t[1] + t[2]) as f64 / 3.0 * j).collect();
        let sum: f64 = resampled.iter().map(|(t, j)| luminance(Vec3::from(*t).max(Vec3::ZERO)) as f64 / j).sum();
        let texels = resampled.into_iter().map(|(t, _)| t).collect();
        let power = luminance(scale) as f64 * portal.area() * sum / (n * n) as f64;
        PortalMap { portal, texels, n, scale, distribution: WindowedDistribution::new(weights, n), power }
    }

    /// The texel a (u, v) falls in, scaled; negative channels emit nothing.
    fn lookup(&self, [u, v]: [f64; 2]) -> Rgb {
        let n = self.n;
        let (x, y) = (((u * n as f64) as usize).min(n - 1), ((v * n as f64) as usize).min(n - 1));
        Vec3::from(self.texels[y * n + x]).max(Vec3::ZERO) * self.scale
    }

    /// Radiance along a ray from `o` that escapes in direction `d`.
    pub fn le(&self, o: Vec3, d: Vec3) -> Rgb {
        let (Some((uv, _)), Some([u0, v0, u1, v1])) =
            (self.portal.uv_of(d.as_dvec3()), self.portal.window(o.as_dvec3()))
        else {
            return Vec3::ZERO;
        };
        if (u0..=u1).contains(&uv[0]) && (v0..=v1).contains(&uv[1]) { self.lookup(uv) } else { Vec3::ZERO }
    }

    /// A direction from `p` through the portal: (direction, radiance, solid-angle pdf).
    pub fn sample_li(&self, p: Vec3, u: [f32; 2]) -> Option<(Vec3, Rgb, f32)> {
        self.sample_within(u, self.portal.window(p.as_dvec3())?)
    }

    /// The solid-angle density [`Self::sample_li`] gives `wi` from `p`.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        self.portal.window(p.as_dvec3()).map_or(0.0, |window| self.pdf_within(wi, window))
    }

    /// A direction toward the sky for a photon, from the whole half-sphere:
    /// (direction, radiance, solid-angle pdf).
    pub fn sample_direction(&self, u: [f32; 2]) -> Option<(Vec3, Rgb, f32)> {
        self.sample_within(u, WHOLE)
    }

    /// A direction whose (u, v) lies in `window`: (direction, radiance, solid-angle pdf).
    fn sample_within(&self, u: [f32; 2], window: [f64; 4]) -> Option<(Vec3, Rgb, f32)> {
        let (uv, pdf_uv) = self.distribution.sample([u[0] as f64, u[1] as f64], window)?;
        let (w, jacobian) = self.portal.direction_of(uv);
        let pdf = pdf_uv / jacobian;
        (jacobian > 0.0 && pdf.is_finite()).then(|| (w.as_vec3(), self.lookup(uv), pdf as f32))
    }

    /// The solid-angle density [`Self::sample_within`] gives the direction `w`.
    fn pdf_within(&self, w: Vec3, window: [f64; 4]) -> f32 {
        match self.portal.uv_of(w.as_dvec3()) {
            Some((uv, jacobian)) if jacobian > 0.0 => (self.distribution.pdf(uv, window) / jacobian) as f32,
            _ => 0.0,
        }
    }

    /// A light subpath's start through the portal: a direction toward the sky drawn
    /// as [`Self::sample_direction`], a point uniform on the portal, and the ray
    /// arriving there from `reach` beyond it. Returns (origin, direction of travel,
    /// radiance, position density across the direction, direction density).
    // DEVIATION(pbrt): appearance, always on for vcm and bdpt. pbrt-v4 starts every
    // portal light's emission on a disk across the scene (its SPPM's photons, which
    // we keep), so light also enters through openings that are not the portal, where
    // the light's radiance is 0: its bdpt disagrees with its path tracer there
    // (pbrt's own comment says so). A bidirectional estimate needs emission and
    // radiance to agree, so our light subpaths enter through the portal, and vcm and
    // bdpt render pbrt-v4's `path` image.
    pub fn sample_through(&self, u1: [f32; 2], u2: [f32; 2], reach: f64) -> Option<(Vec3, Vec3, Rgb, f32, f32)> {
        let (w, le, pdf_dir) = self.sample_direction(u1)?;
        let c = &self.portal.corners;
        let q = c[0] + u2[0] as f64 * (c[3] - c[0]) + u2[1] as f64 * (c[1] - c[0]);
        let cos = self.portal.cos_to_normal(w.as_dvec3());
        let pdf_pos = 1.0 / (self.portal.area() * cos);
        let origin = q + w.as_dvec3() * (reach + q.length());
        (cos > 0.0 && pdf_pos.is_finite()).then(|| (origin.as_vec3(), -w, le, pdf_pos as f32, pdf_dir))
    }

    /// The position density [`Self::sample_through`] gives a ray arriving along `d`
    /// (across the direction; the ray is taken to pass through the portal).
    pub fn pdf_position(&self, d: Vec3) -> f32 {
        let cos = self.portal.cos_to_normal(-d.as_dvec3());
        if cos > 0.0 { (1.0 / (self.portal.area() * cos)) as f32 } else { 0.0 }
    }

    /// The density [`Self::sample_direction`] gives the direction `w` toward the sky.
    pub fn pdf_direction(&self, w: Vec3) -> f32 {
        self.pdf_within(w, WHOLE)
    }
}

/// pbrt-v4's bilinear lookup of an equal-area map at `st`, texel centres at half
/// integers, neighbours past an edge folded back as the sphere's map folds
/// (`WrapMode::OctahedralSphere`).
fn bilerp_octahedral(map: &[[f32; 3]], n: usize, st: [f64; 2]) -> [f32; 3] {
    let (x, y) = (st[0] * n as f64 - 0.5, st[1] * n as f64 - 0.5);
    let (xi, yi) = (x.floor() as i64, y.floor() as i64);
    let (dx, dy) = ((x - xi as f64) as f32, (y - yi as f64) as f32);
    let texel = |mut px: i64, mut py: i64| -> Vec3 {
        let n = n as i64;
        if px < 0 {
            (px, py) = (-px, n - 1 - py);
        } else if px >= n {
            (px, py) = (2 * n - 1 - px, n - 1 - py);
        }
        if py < 0 {
            (px, py) = (n - 1 - px, -py);
        } else if py >= n {
            (px, py) = (n - 1 - px, 2 * n - 1 - py);
        }
        let (px, py) = (px.clamp(0, n - 1) as usize, py.clamp(0, n - 1) as usize);
        Vec3::from(map[py * n as usize + px])
    };
    let v = (1.0 - dx) * (1.0 - dy) * texel(xi, yi)
        + dx * (1.0 - dy) * texel(xi + 1, yi)
        + (1.0 - dx) * dy * texel(xi, yi + 1)
        + dx * dy * texel(xi + 1, yi + 1);
    v.to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_portal() -> Portal {
        // A unit window in the plane z = 1 looking up +z... the frame's z is x × y.
        let c = [
            DVec3::new(-0.5, -0.5, 1.0),
            DVec3::new(-0.5, 0.5, 1.0),
            DVec3::new(0.5, 0.5, 1.0),
            DVec3::new(0.5, -0.5, 1.0),
        ];
        Portal::new(c).unwrap()
    }

    #[test]
    fn directions_and_uv_map_back_and_forth() {
        let p = square_portal();
        assert!(p.is_rectangle());
        for uv in [[0.5, 0.5], [0.1, 0.8], [0.93, 0.02], [0.3, 0.6]] {
            let (w, j) = p.direction_of(uv);
            let (back, j2) = p.uv_of(w).unwrap();
            assert!((back[0] - uv[0]).abs() < 1e-9 && (back[1] - uv[1]).abs() < 1e-9, "{uv:?} -> {back:?}");
            assert!((j - j2).abs() < 1e-9 * j);
        }
        // The Jacobian integrates to the half-sphere's solid angle.
        let n = 400;
        let mut sum = 0.0;
        for y in 0..n {
            for x in 0..n {
                let uv = [(x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64];
                sum += p.direction_of(uv).1 / (n * n) as f64;
            }
        }
        assert!((sum - 2.0 * PI).abs() < 0.01, "{sum}");
        // Directions behind the portal have no (u, v).
        let (w, _) = p.direction_of([0.5, 0.5]);
        assert!(p.uv_of(-w).is_none());
    }

    #[test]
    fn the_window_is_what_the_portal_shows() {
        let p = square_portal();
        let from = DVec3::new(0.2, -0.1, -1.0);
        let [u0, v0, u1, v1] = p.window(from).unwrap();
        // A direction through the portal's inside is in the window; one past its edge
        // is not; from the far side there is no window.
        let through = |x: f64, y: f64| p.uv_of(DVec3::new(x, y, 1.0) - from).unwrap().0;
        let inside = through(0.1, 0.3);
        assert!((u0..=u1).contains(&inside[0]) && (v0..=v1).contains(&inside[1]));
        let outside = through(0.7, 0.0);
        assert!(!((u0..=u1).contains(&outside[0]) && (v0..=v1).contains(&outside[1])));
        assert!(p.window(DVec3::new(0.0, 0.0, 2.0)).is_none());
    }

    /// Samples fall in the window with the density `pdf` reports, which integrates to
    /// one over it.
    #[test]
    fn windowed_samples_follow_their_density() {
        let n = 8;
        let f: Vec<f64> = (0..n * n).map(|i| ((i * 37) % 11) as f64 + if i % 5 == 0 { 0.0 } else { 0.5 }).collect();
        let d = WindowedDistribution::new(f, n);
        let window = [0.13, 0.27, 0.81, 0.66];
        // The density integrates to 1 over the window (cells cut at its edges).
        let m = 800;
        let mut integral = 0.0;
        for y in 0..m {
            for x in 0..m {
                integral += d.pdf([(x as f64 + 0.5) / m as f64, (y as f64 + 0.5) / m as f64], window) / (m * m) as f64;
            }
        }
        assert!((integral - 1.0).abs() < 0.01, "{integral}");
        // A histogram of samples over the cells matches the density's mass in each.
        let mut rng = crate::sampling::Rng::new(7);
        let samples = 200_000;
        let mut counts = vec![0usize; n * n];
        for _ in 0..samples {
            let (uv, pdf) = d.sample([rng.uniform() as f64, rng.uniform() as f64], window).unwrap();
            assert!(uv[0] >= window[0] && uv[0] <= window[2] && uv[1] >= window[1] && uv[1] <= window[3]);
            assert!((pdf - d.pdf(uv, window)).abs() < 1e-9 * pdf.max(1.0));
            counts[(uv[1] * n as f64).min(n as f64 - 1.0) as usize * n
                + (uv[0] * n as f64).min(n as f64 - 1.0) as usize] += 1;
        }
        let total = d.integral(d.cells(window));
        for j in 0..n {
            for i in 0..n {
                let cell = [i as f64, j as f64, i as f64 + 1.0, j as f64 + 1.0];
                let [x0, y0, x1, y1] = d.cells(window);
                let clipped = [cell[0].max(x0), cell[1].max(y0), cell[2].min(x1), cell[3].min(y1)];
                let mass =
                    if clipped[0] < clipped[2] && clipped[1] < clipped[3] { d.integral(clipped) / total } else { 0.0 };
                let expected = mass * samples as f64;
                let got = counts[j * n + i] as f64;
                assert!(
                    (got - expected).abs() <= 5.0 * expected.sqrt() + 1.0,
                    "cell ({i}, {j}): {got} against {expected}"
                );
            }
        }
    }

    /// A portal light's samples are its radiance's directions through the window, with
    /// the density `pdf_li` gives; light only arrives through the window.
    #[test]
    fn a_portal_light_shines_only_through_its_window() {
        let n = 16;
        let map: Vec<[f32; 3]> =
            (0..n * n).map(|i| if i % 7 == 0 { [4.0, 2.0, 1.0] } else { [0.5, 0.6, 0.7] }).collect();
        let light = PortalMap::new(&map, n, Vec3::ONE, DMat3::IDENTITY, square_portal());
        let p = Vec3::new(0.1, 0.2, -0.5);
        let mut rng = crate::sampling::Rng::new(3);
        for _ in 0..2000 {
            let (wi, li, pdf) = light.sample_li(p, [rng.uniform(), rng.uniform()]).unwrap();
            assert!((pdf - light.pdf_li(p, wi)).abs() <= 1e-3 * pdf, "{pdf} against {}", light.pdf_li(p, wi));
            assert_eq!(light.le(p, wi), li);
            // The sampled ray passes through the portal's rectangle (z = 1).
            let t = (1.0 - p.z) / wi.z;
            let q = p + t * wi;
            assert!(q.x.abs() <= 0.5 + 1e-4 && q.y.abs() <= 0.5 + 1e-4, "{q:?}");
        }
        // Past the window's edge, and from behind the portal, the sky is black.
        assert_eq!(light.le(p, (Vec3::new(2.0, 0.0, 1.0) - p).normalize()), Vec3::ZERO);
        assert_eq!(light.le(Vec3::new(0.0, 0.0, 3.0), Vec3::Z), Vec3::ZERO);
        assert!(light.le(p, (Vec3::new(0.0, 0.0, 1.0) - p).normalize()) != Vec3::ZERO);
        // Photon directions: any over the half-sphere, with their density.
        for _ in 0..500 {
            let (w, _, pdf) = light.sample_direction([rng.uniform(), rng.uniform()]).unwrap();
            assert!(w.z > 0.0 && (pdf - light.pdf_direction(w)).abs() <= 1e-3 * pdf);
        }
    }
}
