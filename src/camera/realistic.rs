//! pbrt's `realistic` camera: rays traced from the film through a system of spherical
//! lens elements and an aperture stop, as pbrt-v3 and pbrt-v4 trace them.
//!
//! ```text
//! Camera "realistic" "string lensfile" "dgauss.50mm.dat" "float aperturediameter" 6
//!        "float focusdistance" 1.5 "bool simpleweighting" true     # v3 only
//! Film "image" "float diagonal" 35                                  # mm
//! ```
//! The lens file lists each interface from the scene side to the film as four numbers,
//! in millimetres: curvature radius (0 for the aperture stop), thickness to the next,
//! index of refraction (0 for air) and aperture diameter; `#` starts a comment. The
//! stop's diameter becomes `aperturediameter` (never larger than the file's). The film
//! is placed by pbrt's thick-lens approximation to focus at `focusdistance`; a ray
//! leaves the film towards the rear element within the exit pupil's bounds (64 bands of
//! distance from the film centre, each found by tracing a million film-to-rear rays)
//! and carries pbrt's weight: cos⁴θ times the bound's area, over the centre bound's
//! area (pbrt-v3's `simpleweighting`, its default) or over the rear element's distance
//! squared (pbrt-v4, and pbrt-v3 without it, times the shutter's length).

use crate::sampling::radical_inverse;
use glam::DVec3;
use rayon::prelude::*;

/// One interface, in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Element {
    curvature_radius: f64,
    thickness: f64,
    eta: f64,
    aperture_radius: f64,
}

/// A lens system focused for a film, with its exit pupil bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct Lens {
    elements: Vec<Element>,
    /// Per band of film radius: [x0, y0, x1, y1] on the rear element's plane.
    pupils: Vec<[f64; 4]>,
    /// The film's physical width and height (metres) and its diagonal.
    extent: [f64; 2],
    diagonal: f64,
    weighting: Weighting,
    aperture: Option<Aperture>,
}

/// How a ray's weight is normalised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Weighting {
    /// pbrt-v3's `simpleweighting` (its default): over the centre band's pupil area.
    Simple,
    /// Over the rear element's distance squared, times this (pbrt-v3: the shutter's
    /// length without `simpleweighting`; pbrt-v4: 1, its film takes the exposure).
    Physical(f64),
}

/// What a lens file and the camera's parameters give.
#[derive(Clone, Debug, PartialEq)]
pub struct LensDesc {
    /// Four numbers per interface, as the file has them (millimetres).
    pub data: Vec<f64>,
    pub aperture_diameter: f64,
    pub focus_distance: f64,
    pub weighting: Weighting,
    /// pbrt-v4's `aperture`: the stop's shape or image (round without).
    pub aperture: Option<Aperture>,
}

/// pbrt-v4's aperture image: the stop's transmission over [−r, r]², one channel, its
/// rows flipped and scaled so that its mean is π/4 (a round stop's), as pbrt-v4 keeps
/// it.
#[derive(Clone, Debug, PartialEq)]
pub struct Aperture {
    width: usize,
    height: usize,
    values: Vec<f32>,
}

impl Aperture {
    /// From `width` × `height` values, top row first (an image as read).
    pub fn from_rows(width: usize, height: usize, mut values: Vec<f32>) -> Option<Aperture> {
        if width == 0 || height == 0 || values.len() != width * height {
            return None;
        }
        let flipped: Vec<f32> = (0..height).rev().flat_map(|y| values[y * width..(y + 1) * width].to_vec()).collect();
        values = flipped;
        let mean = values.iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64;
        if !(mean > 0.0 && mean.is_finite()) {
            return None;
        }
        let scale = (std::f64::consts::FRAC_PI_4 / mean) as f32;
        values.iter_mut().for_each(|v| *v *= scale);
        Some(Aperture { width, height, values })
    }

    /// One of pbrt-v4's built-in shapes (`gaussian`, `square`, `pentagon`, `star`) at
    /// 256², as it draws them.
    pub fn builtin(name: &str) -> Option<Aperture> {
        const RES: usize = 256;
        let at = |x: usize, y: usize| {
            [-1.0 + 2.0 * (x as f32 + 0.5) / RES as f32, -1.0 + 2.0 * (y as f32 + 0.5) / RES as f32]
        };
        let image = |f: &dyn Fn([f32; 2], usize, usize) -> f32| {
            (0..RES).flat_map(|y| (0..RES).map(move |x| (x, y))).map(|(x, y)| f(at(x, y), x, y)).collect::<Vec<f32>>()
        };
        let values = match name {
            "gaussian" => image(&|p, _, _| ((-(p[0] * p[0] + p[1] * p[1])).exp() - (-1.0f32).exp()).max(0.0)),
            "square" => image(&|_, x, y| {
                let inside = |v: usize| (RES / 4..3 * RES / 4).contains(&v);
                if inside(x) && inside(y) { 4.0 } else { 0.0 }
            }),
            "pentagon" => {
                let (c1, c2) = ((5f32.sqrt() - 1.0) / 4.0, (5f32.sqrt() + 1.0) / 4.0);
                let s1 = (10.0 + 2.0 * 5f32.sqrt()).sqrt() / 4.0;
                let s2 = (10.0 - 2.0 * 5f32.sqrt()).sqrt() / 4.0;
                let vert = [[0.0, 1.0], [s1, c1], [s2, -c2], [-s2, -c2], [-s1, c1]].map(|v| [v[0] * 0.8, v[1] * 0.8]);
                image(&|p, _, _| winding(&vert, p))
            }
            "star" => {
                let inner = 72f32.to_radians().cos() / 36f32.to_radians().cos();
                let mut vert: Vec<[f32; 2]> = (0..10)
                    .map(|i| {
                        let r = if i & 1 == 1 { 1.0 } else { inner };
                        let a = std::f32::consts::PI * i as f32 / 5.0;
                        [r * a.cos(), r * a.sin()]
                    })
                    .collect();
                vert.reverse();
                image(&|p, _, _| winding(&vert, p))
            }
            _ => return None,
        };
        Aperture::from_rows(RES, RES, values)
    }

    /// The transmission at a stop point (x, y) over its radius: bilinear, 0 outside.
    fn at(&self, x: f64, y: f64) -> f32 {
        let (u, v) = ((x + 1.0) / 2.0 * self.width as f64 - 0.5, (y + 1.0) / 2.0 * self.height as f64 - 0.5);
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = ((u - x0) as f32, (v - y0) as f32);
        let texel = |x: f64, y: f64| {
            let inside = x >= 0.0 && y >= 0.0 && (x as usize) < self.width && (y as usize) < self.height;
            if inside { self.values[y as usize * self.width + x as usize] } else { 0.0 }
        };
        (1.0 - fx) * (1.0 - fy) * texel(x0, y0)
            + fx * (1.0 - fy) * texel(x0 + 1.0, y0)
            + (1.0 - fx) * fy * texel(x0, y0 + 1.0)
            + fx * fy * texel(x0 + 1.0, y0 + 1.0)
    }
}

/// 1 inside the polygon `vert` (non-zero winding, pbrt-v4's edge test), 0 outside.
fn winding(vert: &[[f32; 2]], p: [f32; 2]) -> f32 {
    let mut w = 0;
    for i in 0..vert.len() {
        let (a, b) = (vert[i], vert[(i + 1) % vert.len()]);
        let e = (p[0] - a[0]) * (b[1] - a[1]) - (p[1] - a[1]) * (b[0] - a[0]);
        if a[1] <= p[1] {
            if b[1] > p[1] && e > 0.0 {
                w += 1;
            }
        } else if b[1] <= p[1] && e < 0.0 {
            w -= 1;
        }
    }
    if w == 0 { 0.0 } else { 1.0 }
}

/// pbrt's `Refract`: the direction transmitted for incident `wi` (pointing away) about
/// normal `n` (on its side) with relative index `eta` = ηi/ηt; `None` past the critical
/// angle.
fn refract(wi: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let cos_i = n.dot(wi);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * -wi + (eta * cos_i - cos_t) * n)
}

/// The hit of a ray (lens space) with a spherical interface centred on the axis at
/// `z_center`: its t (`None` for a miss or behind the origin).
fn intersect_spherical(radius: f64, z_center: f64, o: DVec3, d: DVec3) -> Option<f64> {
    let oc = o - DVec3::new(0.0, 0.0, z_center);
    let (a, b, c) = (d.dot(d), 2.0 * d.dot(oc), oc.dot(oc) - radius * radius);
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = if b < 0.0 { -0.5 * (b - disc.sqrt()) } else { -0.5 * (b + disc.sqrt()) };
    let (mut t0, mut t1) = (q / a, c / q);
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let closer = (d.z > 0.0) ^ (radius < 0.0);
    let t = if closer { t0 } else { t1 };
    (!t.is_nan() && t >= 0.0).then_some(t)
}

/// The normal of that interface at the hit `t`, facing back along the ray.
fn spherical_normal(z_center: f64, o: DVec3, d: DVec3, t: f64) -> DVec3 {
    let n = (o - DVec3::new(0.0, 0.0, z_center) + t * d).normalize();
    if n.dot(-d) < 0.0 { -n } else { n }
}

impl Element {
    fn is_stop(&self) -> bool {
        self.curvature_radius == 0.0
    }

    /// Moves a lens-space ray to this interface (at `z`) and through it into `eta_t`
    /// from `eta_i`; `None` when it misses, is stopped or reflects totally.
    fn pass(&self, z: f64, (o, d): (DVec3, DVec3), eta_i: f64, eta_t: f64) -> Option<(DVec3, DVec3)> {
        let z_center = z + self.curvature_radius;
        let t = if self.is_stop() {
            (d.z != 0.0).then_some((z - o.z) / d.z)?
        } else {
            intersect_spherical(self.curvature_radius, z_center, o, d)?
        };
        if t.is_nan() || t < 0.0 {
            return None;
        }
        let p = o + t * d;
        if p.x * p.x + p.y * p.y > self.aperture_radius * self.aperture_radius {
            return None;
        }
        if self.is_stop() {
            return Some((p, d));
        }
        // The normal only for rays the aperture lets by: most rays the exit pupils'
        // search traces stop at the rear element's rim.
        let n = spherical_normal(z_center, o, d, t);
        Some((p, refract((-d).normalize(), n, eta_i / eta_t)?))
    }
}

// DEVIATION(pbrt): input leniency. A curved interface whose index is 0 is air both
// ways; pbrt-v3's trace from the film divides by it (rays then leave along the normal).
fn air(eta: f64) -> f64 {
    if eta == 0.0 { 1.0 } else { eta }
}

/// Traces a camera-space ray from the film (z = 0, looking down +z) out through the
/// elements; the ray leaving the front element, in camera space, and the aperture
/// image's transmission where it crossed the stop (1 for a round stop).
fn trace_from_film(
    elements: &[Element],
    aperture: Option<&Aperture>,
    o: DVec3,
    d: DVec3,
) -> Option<(DVec3, DVec3, f32)> {
    let flip = DVec3::new(1.0, 1.0, -1.0);
    let (mut ray, mut z, mut weight) = ((o * flip, d * flip), 0.0, 1.0);
    for i in (0..elements.len()).rev() {
        let e = &elements[i];
        z -= e.thickness;
        if e.is_stop() && ray.1.z >= 0.0 {
            return None;
        }
        if let (true, Some(a)) = (e.is_stop(), aperture) {
            let p = ray.0 + (z - ray.0.z) / ray.1.z * ray.1;
            weight = a.at(p.x / e.aperture_radius, p.y / e.aperture_radius);
            if weight == 0.0 {
                return None;
            }
            ray.0 = p;
            continue;
        }
        let eta_t = if i > 0 { air(elements[i - 1].eta) } else { 1.0 };
        ray = e.pass(z, ray, air(e.eta), eta_t)?;
    }
    Some((ray.0 * flip, ray.1 * flip, weight))
}

/// Traces a camera-space ray from the scene in through the elements to the film side.
fn trace_from_scene(elements: &[Element], o: DVec3, d: DVec3) -> Option<(DVec3, DVec3)> {
    let flip = DVec3::new(1.0, 1.0, -1.0);
    let (mut ray, mut z) = ((o * flip, d * flip), -front_z(elements));
    for (i, e) in elements.iter().enumerate() {
        let eta_i = if i == 0 { 1.0 } else { air(elements[i - 1].eta) };
        ray = e.pass(z, ray, eta_i, air(e.eta))?;
        z += e.thickness;
    }
    Some((ray.0 * flip, ray.1 * flip))
}

fn front_z(elements: &[Element]) -> f64 {
    elements.iter().map(|e| e.thickness).sum()
}

fn rear_z(elements: &[Element]) -> f64 {
    elements.last().map_or(0.0, |e| e.thickness)
}

fn rear_radius(elements: &[Element]) -> f64 {
    elements.last().map_or(0.0, |e| e.aperture_radius)
}

/// pbrt's cardinal points from a ray in and the ray out: (principal plane z, focal z).
fn cardinal_points(r_in: (DVec3, DVec3), r_out: (DVec3, DVec3)) -> (f64, f64) {
    let tf = -r_out.0.x / r_out.1.x;
    let tp = (r_in.0.x - r_out.0.x) / r_out.1.x;
    (-(r_out.0.z + tp * r_out.1.z), -(r_out.0.z + tf * r_out.1.z))
}

/// The film distance that focuses at `focus_distance` by pbrt's thick-lens
/// approximation (the rear element's thickness to the film); an error when the lens
/// cannot focus that close or no paraxial ray gets through.
fn focus_thick_lens(elements: &[Element], diagonal: f64, focus_distance: f64) -> Result<f64, String> {
    let x = 0.001 * diagonal;
    let r_scene = (DVec3::new(x, 0.0, front_z(elements) + 1.0), DVec3::new(0.0, 0.0, -1.0));
    let no_ray = "no ray parallel to the axis gets through the lens system (is the aperture stop tiny?)";
    let r_film = trace_from_scene(elements, r_scene.0, r_scene.1).ok_or(no_ray)?;
    let (pz0, fz0) = cardinal_points(r_scene, r_film);
    let r_film2 = (DVec3::new(x, 0.0, rear_z(elements) - 1.0), DVec3::new(0.0, 0.0, 1.0));
    let r_scene2 = trace_from_film(elements, None, r_film2.0, r_film2.1).ok_or(no_ray)?;
    let (pz1, _) = cardinal_points(r_film2, (r_scene2.0, r_scene2.1));
    let f = fz0 - pz0;
    let z = -focus_distance;
    let c = (pz1 - z - pz0) * (pz1 - z - 4.0 * f - pz0);
    if c.is_nan() || c <= 0.0 {
        return Err(format!(
            "the lens cannot focus at {} m (too close for its focal length {f:.4} m)",
            focus_distance as f32
        ));
    }
    Ok(rear_z(elements) + 0.5 * (pz1 - z + pz0 - c.sqrt()))
}

/// Samples per exit pupil band, as pbrt takes them.
const PUPIL_SAMPLES: usize = 1024 * 1024;

/// The points on the rear element's plane that every band's pupil is sampled at, as
/// pbrt places them: (2, 3) radical inverses over a square 1.5 times the rear element.
/// Made once for all 64 bands: drawn per band, they took a quarter of the bands' time.
fn pupil_samples(elements: &[Element]) -> Vec<[f64; 2]> {
    let r = 1.5 * rear_radius(elements);
    let at = |i: usize| {
        let (u, v) = (radical_inverse(2, i as u64), radical_inverse(3, i as u64));
        [-r + 2.0 * r * u, -r + 2.0 * r * v]
    };
    (0..PUPIL_SAMPLES).into_par_iter().map(at).collect()
}

/// The bounds on the rear element's plane of the rays from film points between x0 and
/// x1 (on the x axis) that get through, as pbrt finds them: at the `samples` (film
/// points spread from x0 to x1 in their order), widened by two sample spacings.
fn bound_exit_pupil(
    elements: &[Element],
    aperture: Option<&Aperture>,
    samples: &[[f64; 2]],
    (x0, x1): (f64, f64),
) -> [f64; 4] {
    let n = samples.len() as f64;
    let r = 1.5 * rear_radius(elements);
    let z = rear_z(elements);
    let inside = |b: &[f64; 4], x: f64, y: f64| x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3];
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    let mut any = false;
    for (i, &[x, y]) in samples.iter().enumerate() {
        let film = DVec3::new(x0 + (x1 - x0) * (i as f64 + 0.5) / n, 0.0, 0.0);
        let rear = DVec3::new(x, y, z);
        if inside(&b, x, y) || trace_from_film(elements, aperture, film, rear - film).is_some() {
            b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
            any = true;
        }
    }
    if !any {
        return [-r, -r, r, r];
    }
    let grow = 2.0 * (2.0 * r * std::f64::consts::SQRT_2) / n.sqrt();
    [b[0] - grow, b[1] - grow, b[2] + grow, b[3] + grow]
}

fn area(b: &[f64; 4]) -> f64 {
    (b[2] - b[0]) * (b[3] - b[1])
}

impl Lens {
    /// The lens of `desc`, focused, for a film of `resolution` pixels and a diagonal of
    /// `diagonal_mm`.
    pub fn new(desc: &LensDesc, resolution: [u32; 2], diagonal_mm: f64) -> Result<Lens, String> {
        let mut elements = elements_of(desc);
        let diagonal = diagonal_mm * 0.001;
        let film = focus_thick_lens(&elements, diagonal, desc.focus_distance)?;
        if let Some(last) = elements.last_mut() {
            last.thickness = film;
        }
        let aspect = resolution[1] as f64 / resolution[0] as f64;
        let x = (diagonal * diagonal / (1.0 + aspect * aspect)).sqrt();
        let samples = pupil_samples(&elements);
        let pupils = (0..64)
            .into_par_iter()
            .map(|i| {
                let band = (i as f64 / 64.0 * diagonal / 2.0, (i + 1) as f64 / 64.0 * diagonal / 2.0);
                bound_exit_pupil(&elements, desc.aperture.as_ref(), &samples, band)
            })
            .collect();
        let aperture = desc.aperture.clone();
        Ok(Lens { elements, pupils, extent: [x, aspect * x], diagonal, weighting: desc.weighting, aperture })
    }

    /// The camera-space ray for a raster position (as a fraction of the full film,
    /// [0, 1]²) and a lens sample, with its weight; `None` when the lens stops it.
    pub fn ray(&self, film_uv: [f64; 2], u: [f32; 2]) -> Option<(DVec3, DVec3, f32)> {
        let p2 =
            [-self.extent[0] / 2.0 + film_uv[0] * self.extent[0], -self.extent[1] / 2.0 + film_uv[1] * self.extent[1]];
        let film = DVec3::new(-p2[0], p2[1], 0.0);
        let r = (film.x * film.x + film.y * film.y).sqrt();
        let band = ((r / (self.diagonal / 2.0) * self.pupils.len() as f64) as usize).min(self.pupils.len() - 1);
        let b = &self.pupils[band];
        let (lx, ly) = (b[0] + (b[2] - b[0]) * u[0] as f64, b[1] + (b[3] - b[1]) * u[1] as f64);
        let (sin, cos) = if r != 0.0 { (film.y / r, film.x / r) } else { (0.0, 1.0) };
        let rear = DVec3::new(cos * lx - sin * ly, sin * lx + cos * ly, rear_z(&self.elements));
        let d = rear - film;
        let (o, dir, transmission) = trace_from_film(&self.elements, self.aperture.as_ref(), film, d)?;
        let cos_theta = d.normalize().z;
        let cos4 = cos_theta.powi(4);
        let weight = match self.weighting {
            Weighting::Simple => cos4 * area(b) / area(&self.pupils[0]),
            Weighting::Physical(k) => k * cos4 * area(b) / (rear_z(&self.elements) * rear_z(&self.elements)),
        };
        Some((o, dir.normalize(), weight as f32 * transmission))
    }
}

/// Whether the lens of `desc` can focus at its distance on a film of `diagonal_mm`
/// (the reason when it cannot).
pub fn check_focus(desc: &LensDesc, diagonal_mm: f64) -> Result<(), String> {
    let elements: Vec<Element> = elements_of(desc);
    focus_thick_lens(&elements, diagonal_mm * 0.001, desc.focus_distance).map(|_| ())
}

/// The interfaces of a lens file in metres, the stop narrowed to the asked diameter
/// (a larger one is clamped to the file's, as pbrt does with a warning).
fn elements_of(desc: &LensDesc) -> Vec<Element> {
    desc.data
        .chunks_exact(4)
        .map(|c| Element {
            curvature_radius: c[0] * 0.001,
            thickness: c[1] * 0.001,
            eta: c[2],
            aperture_radius: if c[0] == 0.0 { desc.aperture_diameter.min(c[3]) } else { c[3] } * 0.001 / 2.0,
        })
        .collect()
}

/// Reads a lens file's numbers (pbrt's `ReadFloatFile`: numbers separated by white
/// space, `#` to the end of a line a comment); an error names what is not a number or
/// a count that is not a multiple of four.
pub fn read_lens_file(text: &str) -> Result<Vec<f64>, String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        for word in line.split_whitespace() {
            let v: f64 = word.parse().map_err(|_| format!("line {}: \"{word}\" is not a number", n + 1))?;
            if !v.is_finite() {
                return Err(format!("line {}: {word} is not finite", n + 1));
            }
            out.push(v);
        }
    }
    if out.is_empty() || !out.len().is_multiple_of(4) {
        return Err(format!("a lens file has four numbers per interface; this one has {}", out.len()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A single biconvex lens (radius 50 mm both sides, 5 mm thick, η 1.5) with a stop
    /// in front of it.
    fn simple() -> LensDesc {
        let data = vec![0.0, 2.0, 0.0, 20.0, 50.0, 5.0, 1.5, 20.0, -50.0, 40.0, 0.0, 20.0];
        LensDesc { data, aperture_diameter: 10.0, focus_distance: 1.0, weighting: Weighting::Simple, aperture: None }
    }

    /// `simple()` focused for a 64 × 64 film of 35 mm, made once for the tests that
    /// share it (its exit pupils take 2 s on 2 cores).
    fn simple_lens() -> &'static Lens {
        static LENS: std::sync::OnceLock<Lens> = std::sync::OnceLock::new();
        LENS.get_or_init(|| Lens::new(&simple(), [64, 64], 35.0).unwrap())
    }

    #[test]
    fn a_focused_lens_images_a_point_on_the_axis_to_the_film_centre() {
        let lens = simple_lens();
        // Rays from a point 1 m in front (the focus distance, measured from the film)
        // through several lens points all meet the film near its centre.
        let p = DVec3::new(0.0, 0.0, 1.0);
        let mut hits = 0;
        for (x, y) in [(0.002, 0.0), (0.0, 0.003), (-0.004, 0.001), (0.001, -0.002)] {
            let front = DVec3::new(x, y, front_z(&lens.elements));
            let Some((o, d)) = trace_from_scene(&lens.elements, p, front - p) else { continue };
            let t = -o.z / d.z;
            let on_film = o + t * d;
            assert!(on_film.truncate().length() < 2e-4, "{on_film}");
            hits += 1;
        }
        assert!(hits >= 3);
        // The stop was narrowed to the asked diameter.
        assert_eq!(lens.elements[0].aperture_radius, 0.005);
    }

    #[test]
    fn exit_pupils_hold_every_ray_that_gets_through() {
        let lens = simple_lens();
        let z = rear_z(&lens.elements);
        let r = rear_radius(&lens.elements);
        let mut through = 0;
        for i in 0..20_000u64 {
            let film = DVec3::new(radical_inverse(5, i) * 0.0175, 0.0, 0.0);
            let rear = DVec3::new((radical_inverse(2, i) * 2.0 - 1.0) * r, (radical_inverse(3, i) * 2.0 - 1.0) * r, z);
            if trace_from_film(&lens.elements, None, film, rear - film).is_some() {
                let band = ((film.x / 0.0175 * 64.0) as usize).min(63);
                let b = &lens.pupils[band];
                assert!(rear.x >= b[0] && rear.x <= b[2] && rear.y >= b[1] && rear.y <= b[3]);
                through += 1;
            }
        }
        assert!(through > 100);
    }

    #[test]
    fn builtin_apertures_have_a_round_stops_mean_and_their_shapes() {
        for name in ["gaussian", "square", "pentagon", "star"] {
            let a = Aperture::builtin(name).unwrap();
            let mean = a.values.iter().map(|&v| v as f64).sum::<f64>() / a.values.len() as f64;
            assert!((mean - std::f64::consts::FRAC_PI_4).abs() < 1e-4, "{name}: mean {mean}");
            assert!(a.at(0.0, 0.0) > 0.0, "{name}: closed at the centre");
            assert_eq!(a.at(0.99, 0.99), 0.0, "{name}: open in the corner");
        }
        // The square is open to half the radius; the pentagon's top vertex is 0.8 up
        // and its base 0.65 down (pbrt flips the rows: here the base is up).
        let square = Aperture::builtin("square").unwrap();
        assert!(square.at(0.4, -0.4) > 0.0 && square.at(0.6, 0.0) == 0.0);
        let pentagon = Aperture::builtin("pentagon").unwrap();
        assert!(pentagon.at(0.0, -0.75) > 0.0 && pentagon.at(0.0, 0.75) == 0.0);
        assert!(Aperture::builtin("hexagon").is_none());
    }

    #[test]
    fn lens_files_read_as_pbrt_reads_them() {
        assert_eq!(read_lens_file("# r t eta d\n0 1 0 2\n3 4 1.5 5 # last\n").unwrap().len(), 8);
        assert!(read_lens_file("1 2 3").unwrap_err().contains("four numbers"));
        assert!(read_lens_file("1 2 x 4").unwrap_err().contains("\"x\""));
    }
}
