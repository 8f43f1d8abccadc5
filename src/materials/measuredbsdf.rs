//! pbrt-v4's `MeasuredBxDF`: an isotropic or anisotropic BRDF measured by the RGL
//! gonio-photometer (Dupuy and Jakob 2018) and stored in a "tensor_file" (`.bsdf`),
//! read, evaluated and sampled as pbrt-v4 does. The `measured` material
//! ([`super::measured`]) reads the file.
//!
//! The BRDF is f = S(u) D(ωm) / (4 σ(ωo) cos θi). `ndf` tabulates D and `sigma` the
//! projected area σ over (√(2θ/π), φ/2π + ½); `vndf` is the density of visible normals
//! per incident (φo, θo), a warp from the unit square to normals; `spectra` holds S per
//! wavelength on that square, at the point the warp maps to the half vector ωm, and
//! `luminance` the density pbrt samples that square by first. Tables are interpolated
//! linearly in every coordinate ([`PiecewiseLinear2D`]). The file's `jacobian` flag is
//! read and ignored, as pbrt-v4 ignores it.

use super::shared::Sampled;
use crate::math::catmull_rom::find_interval;
use crate::sampling::{PiecewiseLinear2D, PlSample};
use crate::spectrum::Rgb;
use glam::Vec3;
use std::f32::consts::PI;
use std::sync::OnceLock;

/// What a lookup's three lanes stand for: three wavelengths (nm) of a spectral path,
/// or red, green and blue.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lanes {
    Wavelengths([f32; 3]),
    Rgb,
}

/// A measured BRDF's tables (pbrt-v4's `MeasuredBxDFData`).
#[derive(Debug)]
pub struct MeasuredTable {
    /// At most two incident azimuths: the tables depend on φm − φo only.
    isotropic: bool,
    ndf: PiecewiseLinear2D<0>,
    sigma: PiecewiseLinear2D<0>,
    vndf: PiecewiseLinear2D<2>,
    luminance: PiecewiseLinear2D<2>,
    /// S over (φi, θi, λ).
    spectra: PiecewiseLinear2D<3>,
    /// S as RGB over (φi, θi, channel 0–2), made on first use by an RGB render.
    rgb: OnceLock<PiecewiseLinear2D<3>>,
}

/// Why a file cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeasuredError {
    #[error("not a tensor file (no \"tensor_file\" version 1.0 header)")]
    Magic,
    #[error("the file ends inside {0}")]
    Truncated(String),
    #[error("field \"{0}\" has an unknown type {1}")]
    Type(String, u8),
    #[error(
        "no field \"{0}\" (pbrt-v4's measured BSDFs need ndf, sigma, vndf, luminance, spectra, wavelengths, theta_i, phi_i, description, jacobian)"
    )]
    Missing(&'static str),
    #[error("invalid BRDF file structure: {0}")]
    Structure(String),
}

/// One field of a tensor file.
struct Field<'a> {
    dtype: u8,
    shape: Vec<usize>,
    bytes: &'a [u8],
}

const FLOAT32: u8 = 10;
const UINT8: u8 = 1;

fn type_size(dtype: u8) -> Option<usize> {
    match dtype {
        1 | 2 => Some(1),
        3 | 4 | 9 => Some(2),
        5 | 6 | 10 => Some(4),
        7 | 8 | 11 => Some(8),
        _ => None,
    }
}

/// Little-endian reads that name what was cut short.
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], MeasuredError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.b.len());
        let end = end.ok_or_else(|| MeasuredError::Truncated(what.to_string()))?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u16(&mut self, what: &str) -> Result<u16, MeasuredError> {
        self.take(2, what).map(|s| u16::from_le_bytes([s[0], s[1]]))
    }

    fn u64(&mut self, what: &str) -> Result<u64, MeasuredError> {
        self.take(8, what).map(|s| u64::from_le_bytes(s.try_into().unwrap_or([0; 8])))
    }
}

/// The fields of a tensor file by name (a later field of one name replaces an earlier
/// one, as in pbrt), every size and offset checked against the file.
fn fields(b: &[u8]) -> Result<Vec<(String, Field<'_>)>, MeasuredError> {
    if b.len() < 18 || &b[..12] != b"tensor_file\0" || b[12..14] != [1, 0] {
        return Err(if b.len() < 18 && b"tensor_file\0".starts_with(&b[..b.len().min(12)]) {
            MeasuredError::Truncated("the header".into())
        } else {
            MeasuredError::Magic
        });
    }
    let n = u32::from_le_bytes([b[14], b[15], b[16], b[17]]);
    let mut r = Reader { b, at: 18 };
    let mut out: Vec<(String, Field)> = Vec::new();
    for k in 0..n {
        let what = format!("field {k}'s description");
        let len = r.u16(&what)? as usize;
        let name = String::from_utf8_lossy(r.take(len, &what)?).into_owned();
        let ndim = r.u16(&what)? as usize;
        let dtype = r.take(1, &what)?[0];
        let offset = r.u64(&what)?;
        let size = type_size(dtype).ok_or_else(|| MeasuredError::Type(name.clone(), dtype))?;
        let mut shape = Vec::with_capacity(ndim.min(16));
        let mut bytes = Some(size);
        for _ in 0..ndim {
            let s = usize::try_from(r.u64(&what)?).ok();
            shape.push(s.unwrap_or(usize::MAX));
            bytes = bytes.zip(s).and_then(|(t, s)| t.checked_mul(s));
        }
        let bytes =
            bytes.ok_or_else(|| MeasuredError::Structure(format!("field \"{name}\"'s shape {shape:?} overflows")))?;
        let data = usize::try_from(offset)
            .ok()
            .and_then(|o| b.get(o..o.checked_add(bytes)?))
            .ok_or_else(|| MeasuredError::Truncated(format!("field \"{name}\"'s data")))?;
        out.retain(|(n, _)| *n != name);
        out.push((name, Field { dtype, shape, bytes: data }));
    }
    Ok(out)
}

fn floats(f: &Field) -> Vec<f32> {
    f.bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
}

/// An axis's nodes: finite and not decreasing, or the file is malformed.
fn axis(name: &str, f: &Field) -> Result<Vec<f32>, MeasuredError> {
    let v = floats(f);
    if v.iter().any(|x| !x.is_finite()) || v.windows(2).any(|w| w[1] < w[0]) {
        return Err(MeasuredError::Structure(format!("{name} is not a finite, increasing list")));
    }
    Ok(v)
}

impl MeasuredTable {
    /// Reads a file as pbrt-v4 does, with pbrt's checks of its structure.
    pub fn read(b: &[u8]) -> Result<MeasuredTable, MeasuredError> {
        let all = fields(b)?;
        let get = |name: &'static str| {
            all.iter().find(|(n, _)| n == name).map(|(_, f)| f).ok_or(MeasuredError::Missing(name))
        };
        let [theta_i, phi_i, ndf, sigma, vndf, spectra, luminance, wavelengths, description, jacobian] = [
            "theta_i",
            "phi_i",
            "ndf",
            "sigma",
            "vndf",
            "spectra",
            "luminance",
            "wavelengths",
            "description",
            "jacobian",
        ]
        .map(get);
        let (theta_i, phi_i, ndf, sigma, vndf, spectra, luminance, wavelengths) =
            (theta_i?, phi_i?, ndf?, sigma?, vndf?, spectra?, luminance?, wavelengths?);
        let (description, jacobian) = (description?, jacobian?);
        let shape = |f: &Field, dims: usize, dtype: u8| f.shape.len() == dims && f.dtype == dtype;
        let (v, l, s) = (&vndf.shape, &luminance.shape, &spectra.shape);
        let ok = shape(description, 1, UINT8)
            && [theta_i, phi_i, wavelengths].iter().all(|f| shape(f, 1, FLOAT32))
            && shape(ndf, 2, FLOAT32)
            && shape(sigma, 2, FLOAT32)
            && shape(vndf, 4, FLOAT32)
            && shape(luminance, 4, FLOAT32)
            && shape(spectra, 5, FLOAT32)
            && shape(jacobian, 1, UINT8)
            && jacobian.shape[0] == 1
            && v[..2] == [phi_i.shape[0], theta_i.shape[0]]
            && l[..2] == v[..2]
            && l[2] == l[3]
            && s[..3] == [phi_i.shape[0], theta_i.shape[0], wavelengths.shape[0]]
            && s[3] == s[4]
            && l[2..] == s[3..];
        if !ok {
            return Err(MeasuredError::Structure(format!(
                "shapes ndf {:?}, sigma {:?}, vndf {v:?}, luminance {l:?}, spectra {s:?}, theta_i {:?}, phi_i {:?}, wavelengths {:?}",
                ndf.shape, sigma.shape, theta_i.shape, phi_i.shape, wavelengths.shape
            )));
        }
        let (theta, phi, lambda) =
            (axis("theta_i", theta_i)?, axis("phi_i", phi_i)?, axis("wavelengths", wavelengths)?);
        let isotropic = phi.len() <= 2;
        if !isotropic {
            let reduction = (2.0 * PI / (phi[phi.len() - 1] - phi[0])).round();
            if reduction != 1.0 {
                return Err(MeasuredError::Structure(format!(
                    "phi_i covers 2π/{reduction}: only files over the whole circle (reduction 1) are supported, as in pbrt-v4"
                )));
            }
        }
        let structure = MeasuredError::Structure;
        let plain = |f: &Field| PiecewiseLinear2D::new(&floats(f), [f.shape[1], f.shape[0]], [], false);
        let warp = |f: &Field| {
            PiecewiseLinear2D::new(&floats(f), [f.shape[3], f.shape[2]], [phi.as_slice(), theta.as_slice()], true)
        };
        let square = [s[4], s[3]];
        Ok(MeasuredTable {
            isotropic,
            ndf: plain(ndf).map_err(|e| structure(format!("ndf: {e}")))?,
            sigma: plain(sigma).map_err(|e| structure(format!("sigma: {e}")))?,
            vndf: warp(vndf).map_err(|e| structure(format!("vndf: {e}")))?,
            luminance: warp(luminance).map_err(|e| structure(format!("luminance: {e}")))?,
            spectra: PiecewiseLinear2D::new(&floats(spectra), square, [&phi, &theta, &lambda], false)
                .map_err(|e| structure(format!("spectra: {e}")))?,
            rgb: OnceLock::new(),
        })
    }

    /// S in RGB, for paths that carry RGB: each wavelength node's hat function
    /// (extended flat past the ends, as lookups clamp) as a reflectance under D65 in
    /// linear sRGB (so that S = 1 is white, as a spectral render under white light
    /// sees it), summed per point.
    fn rgb_table(&self) -> &PiecewiseLinear2D<3> {
        self.rgb.get_or_init(|| {
            let [phi, theta, lambda] = self.spectra.params();
            let hats: Vec<Rgb> = (0..lambda.len()).map(|k| reflectance_rgb(|l| hat(lambda, k, l))).collect();
            let [nx, ny] = self.spectra.size();
            let (n, values) = (nx * ny, self.spectra.values());
            let mut rgb = vec![0.0f32; phi.len() * theta.len() * 3 * n];
            for (slice, out) in rgb.chunks_exact_mut(3 * n).enumerate() {
                let s = &values[slice * lambda.len() * n..(slice + 1) * lambda.len() * n];
                for (k, hat) in hats.iter().enumerate() {
                    for (c, channel) in out.chunks_exact_mut(n).enumerate() {
                        channel.iter_mut().zip(&s[k * n..(k + 1) * n]).for_each(|(o, v)| *o += v * hat[c]);
                    }
                }
            }
            PiecewiseLinear2D::new(&rgb, [nx, ny], [phi, theta, &[0.0, 1.0, 2.0]], false)
                .expect("the RGB table has the spectra's shape")
        })
    }

    /// S at `u` for the incident (φo, θo), in the three lanes, never negative.
    fn s(&self, u: [f32; 2], phi_o: f32, theta_o: f32, lanes: Lanes) -> Rgb {
        let (table, at) = match lanes {
            Lanes::Wavelengths(l) => (&self.spectra, l),
            Lanes::Rgb => (self.rgb_table(), [0.0, 1.0, 2.0]),
        };
        Vec3::from_array(at.map(|x| table.evaluate(u, [phi_o, theta_o, x]).max(0.0)))
    }

    /// The square's coordinates of a half vector (φm relative to φo when isotropic).
    fn u_m(&self, theta_m: f32, phi_m: f32, phi_o: f32) -> [f32; 2] {
        let y = phi2u(if self.isotropic { phi_m - phi_o } else { phi_m });
        [theta2u(theta_m), y - y.floor()]
    }

    /// f(o, i): zero unless both are on one side (either side: the table is two-sided).
    pub fn f(&self, o: Vec3, i: Vec3, lanes: Lanes) -> Rgb {
        let Some((o, i, wm)) = reflection(o, i) else { return Vec3::ZERO };
        let ((theta_o, phi_o), (theta_m, phi_m)) = (spherical(o), spherical(wm));
        let u_wm = self.u_m(theta_m, phi_m, phi_o);
        let ui = self.vndf.invert(u_wm, [phi_o, theta_o]);
        let fr = self.s(ui.p, phi_o, theta_o, lanes);
        let sigma = self.sigma.evaluate([theta2u(theta_o), phi2u(phi_o)], []);
        let v = fr * self.ndf.evaluate(u_wm, []) / (4.0 * sigma * i.z);
        if v.is_finite() { v.max(Vec3::ZERO) } else { Vec3::ZERO }
    }

    /// The density `sample` draws i with.
    pub fn pdf(&self, o: Vec3, i: Vec3) -> f32 {
        let Some((o, _, wm)) = reflection(o, i) else { return 0.0 };
        let ((theta_o, phi_o), (theta_m, phi_m)) = (spherical(o), spherical(wm));
        let u_wm = self.u_m(theta_m, phi_m, phi_o);
        let ui = self.vndf.invert(u_wm, [phi_o, theta_o]);
        let lum = self.luminance.evaluate(ui.p, [phi_o, theta_o]);
        let sin_m = (wm.x * wm.x + wm.y * wm.y).sqrt();
        let pdf = ui.pdf * lum / jacobian(o, wm, u_wm[0], sin_m);
        if pdf.is_finite() { pdf.max(0.0) } else { 0.0 }
    }

    /// Draws i for `o`: a point of the square by the luminance, then a half vector by
    /// the visible normals.
    pub fn sample(&self, o: Vec3, u: [f32; 2], lanes: Lanes) -> Option<Sampled> {
        let flip = o.z <= 0.0;
        let o = if flip { -o } else { o };
        let (theta_o, phi_o) = spherical(o);
        let PlSample { p: u, pdf: lum_pdf } = self.luminance.sample(u, [phi_o, theta_o]);
        let PlSample { p: u_wm, pdf } = self.vndf.sample(u, [phi_o, theta_o]);
        let phi_m = u2phi(u_wm[1]) + if self.isotropic { phi_o } else { 0.0 };
        let theta_m = u2theta(u_wm[0]);
        let (sin_m, cos_m) = theta_m.sin_cos();
        let wm = Vec3::new(sin_m * phi_m.cos(), sin_m * phi_m.sin(), cos_m);
        let wi = 2.0 * o.dot(wm) * wm - o;
        if wi.z <= 0.0 {
            return None;
        }
        let sigma = self.sigma.evaluate([theta2u(theta_o), phi2u(phi_o)], []);
        let f = self.s(u, phi_o, theta_o, lanes) * self.ndf.evaluate(u_wm, []) / (4.0 * sigma * wi.z);
        let pdf = pdf * lum_pdf / jacobian(o, wm, u_wm[0], sin_m);
        let ok = pdf > 0.0 && pdf.is_finite() && f.is_finite();
        ok.then(|| Sampled { wi: if flip { -wi } else { wi }, f: f.max(Vec3::ZERO), pdf })
    }
}

/// The linear sRGB of a reflectance spectrum seen under D65, white for 1.
fn reflectance_rgb(s: impl Fn(f32) -> f32) -> Rgb {
    use crate::spectrum::colorspace::ColorSpaceName;
    // sRGB's illuminant is D65, scaled to luminance 1.
    let d65 = |l: f64| ColorSpaceName::Srgb.illuminant_at(l);
    crate::spectrum::xyz_to_rgb(crate::spectrum::cie::spectrum_to_xyz(|l| s(l as f32) as f64 * d65(l)))
}

/// Node `k`'s hat function over `nodes` at `l`, flat past the first and last node.
fn hat(nodes: &[f32], k: usize, l: f32) -> f32 {
    if nodes.len() == 1 {
        return 1.0;
    }
    let l = l.clamp(nodes[0], nodes[nodes.len() - 1]);
    let i = find_interval(nodes.len(), |j| nodes[j] <= l);
    let t = if nodes[i + 1] > nodes[i] { (l - nodes[i]) / (nodes[i + 1] - nodes[i]) } else { 0.0 };
    if k == i {
        1.0 - t
    } else if k == i + 1 {
        t
    } else {
        0.0
    }
}

/// (o, i, ωm) with o and i on the upper side, for a pair on one side.
fn reflection(o: Vec3, i: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
    if o.z * i.z <= 0.0 {
        return None;
    }
    let (o, i) = if o.z < 0.0 { (-o, -i) } else { (o, i) };
    let wm = o + i;
    (wm.length_squared() > 0.0).then(|| (o, i, wm.normalize()))
}

/// dω/du of the square's map to half vectors, times the half vector's 4 (o·ωm) to
/// reflected directions (pbrt's floor of 10⁻⁶ kept).
fn jacobian(o: Vec3, wm: Vec3, u_theta: f32, sin_m: f32) -> f32 {
    4.0 * o.dot(wm) * (2.0 * PI * PI * u_theta * sin_m).max(1e-6)
}

/// (θ, φ) of a unit vector, φ in [−π, π].
// DEVIATION(pbrt): robustness. θ as 2·asin(|w − z|/2) (Mitsuba's `elevation`), where
// pbrt-v4 takes acos(w.z): in f32 that is 0 below θ ≈ 3·10⁻⁴, where the tables' map
// has density 0, so a sampled half vector that near the normal got density 0 from
// `pdf` (pbrt's `PDF`) while `sample` gave it a large one. Elsewhere the two agree to
// rounding.
fn spherical(w: Vec3) -> (f32, f32) {
    let d = Vec3::new(w.x, w.y, w.z - 1.0).length();
    (2.0 * (0.5 * d).min(1.0).asin(), w.y.atan2(w.x))
}

fn theta2u(theta: f32) -> f32 {
    (theta * (2.0 / PI)).sqrt()
}

fn phi2u(phi: f32) -> f32 {
    phi * (0.5 / PI) + 0.5
}

fn u2theta(u: f32) -> f32 {
    u * u * (PI / 2.0)
}

fn u2phi(u: f32) -> f32 {
    (2.0 * u - 1.0) * PI
}

/// A table shared by every material that read the same file, compared by address.
pub type Table = super::shared::Shared<MeasuredTable>;

#[cfg(test)]
mod tests {
    use super::*;

    fn file(name: &str) -> Vec<u8> {
        std::fs::read(format!("{}/pbrt-scenes/verify/bsdfs/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
    }

    fn dir(theta_deg: f32, phi_deg: f32) -> Vec3 {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    }

    /// The model `tools/make_measured_bsdf.py` tabulated in `rosegold.bsdf`: GGX α 0.3
    /// with Schlick's Fresnel on a rising reflectance, at 550 nm.
    fn rosegold(o: Vec3, i: Vec3) -> f32 {
        let alpha = 0.3f32;
        let m = (o + i).normalize();
        let e = (m.x * m.x + m.y * m.y) / (alpha * alpha) + m.z * m.z;
        let d = 1.0 / (PI * alpha * alpha * e * e);
        let lambda = |w: Vec3| (-1.0 + (1.0 + alpha * alpha * (1.0 - w.z * w.z) / (w.z * w.z)).sqrt()) / 2.0;
        let f0 = 0.25 + 0.65 / (1.0 + (-(550.0f32 - 580.0) / 25.0).exp());
        let fresnel = f0 + (1.0 - f0) * (1.0 - o.dot(m)).powi(5);
        fresnel * d / (4.0 * o.z * i.z * (1.0 + lambda(o) + lambda(i)))
    }

    #[test]
    fn the_isotropic_file_reproduces_its_model() {
        let t = MeasuredTable::read(&file("rosegold.bsdf")).unwrap();
        assert!(t.isotropic);
        let lanes = Lanes::Wavelengths([550.0; 3]);
        // Half vectors up to 35° from the normal (where the lobe has its mass), over
        // incident angles between the table's nodes and azimuths either side.
        for (to, ti, dphi) in
            [(0.0, 20.0, 0.0), (25.0, 40.0, 180.0), (37.0, 10.0, 90.0), (52.0, 52.0, 180.0), (65.0, 30.0, 150.0)]
        {
            let (o, i) = (dir(to, 30.0), dir(ti, 30.0 + dphi));
            let (got, want) = (t.f(o, i, lanes).x, rosegold(o, i));
            assert!((got - want).abs() < 0.06 * want, "θo {to} θi {ti} Δφ {dphi}: {got} vs {want}");
            // Reciprocal in its model, two-sided in pbrt's.
            assert_eq!(t.f(-o, -i, lanes), t.f(o, i, lanes));
        }
        assert_eq!(t.f(dir(30.0, 0.0), -dir(30.0, 180.0), lanes), Vec3::ZERO);
    }

    /// ∫ pdf dω and ∫ f cos dω by the midpoint rule over the hemisphere in (cos θ, φ).
    fn integrals(t: &MeasuredTable, o: Vec3) -> (f32, f32) {
        let (n, lanes) = (400, Lanes::Wavelengths([600.0; 3]));
        let (mut pdf, mut albedo) = (0.0, 0.0);
        for k in 0..n * n {
            let c = ((k % n) as f32 + 0.5) / n as f32;
            let phi = 2.0 * PI * ((k / n) as f32 + 0.5) / n as f32;
            let s = (1.0 - c * c).sqrt();
            let i = Vec3::new(s * phi.cos(), s * phi.sin(), c);
            pdf += t.pdf(o, i);
            albedo += t.f(o, i, lanes).x * c;
        }
        let dw = 2.0 * PI / (n * n) as f32;
        (pdf * dw, albedo * dw)
    }

    #[test]
    fn sampling_matches_the_density_and_the_value() {
        for name in ["rosegold.bsdf", "anodized.bsdf"] {
            let t = MeasuredTable::read(&file(name)).unwrap();
            let lanes = Lanes::Wavelengths([600.0; 3]);
            for o in [dir(10.0, 20.0), dir(50.0, -100.0), dir(75.0, 160.0)] {
                let (pdf_total, albedo) = integrals(&t, o);
                // Mass lost only where reflected directions fall below the horizon.
                assert!(pdf_total > 0.85 && pdf_total < 1.01, "{name} {o}: ∫pdf {pdf_total}");
                let (mut sum, n, mut s) = (0.0, 40_000, 5u64);
                let mut u = || crate::sampling::testing::lcg(&mut s);
                for _ in 0..n {
                    let Some(x) = t.sample(o, [u(), u()], lanes) else { continue };
                    let (pdf, f) = (t.pdf(o, x.wi), t.f(o, x.wi, lanes));
                    // f32 round trips through the warps: 0.2% at densities in the
                    // thousands (the anisotropic lobe's narrow axis).
                    assert!((pdf - x.pdf).abs() < 1e-2 * pdf.max(1.0), "{name}: pdf {pdf} vs {}", x.pdf);
                    assert!((f - x.f).abs().max_element() < 1e-2 * f.max_element().max(1.0), "{f} vs {}", x.f);
                    sum += x.f.x * x.wi.z / x.pdf;
                }
                let estimate = sum / n as f32;
                assert!((estimate - albedo).abs() < 0.02 * albedo + 0.005, "{name} {o}: {estimate} vs {albedo}");
                // Below the surface the lobe mirrors itself.
                let flipped = t.sample(-o, [0.3, 0.6], lanes).map(|x| x.wi.z);
                assert!(flipped.is_none_or(|z| z < 0.0));
            }
        }
    }

    #[test]
    fn a_flat_reflectance_is_white_in_rgb() {
        let white = reflectance_rgb(|_| 1.0);
        assert!((white - Vec3::ONE).abs().max_element() < 2e-3, "{white}");
        let nodes = [400.0, 500.0, 700.0];
        let sum: f32 = (0..3).map(|k| hat(&nodes, k, 550.0)).sum();
        assert_eq!((hat(&nodes, 1, 550.0), hat(&nodes, 2, 550.0), sum), (0.75, 0.25, 1.0));
        assert_eq!((hat(&nodes, 0, 300.0), hat(&nodes, 2, 900.0)), (1.0, 1.0));
    }

    #[test]
    fn malformed_files_are_errors_never_panics() {
        let good = file("rosegold.bsdf");
        // Every truncation, and every single-byte change of the header and field table.
        for n in 0..good.len().min(400) {
            assert!(MeasuredTable::read(&good[..n]).is_err(), "{n} bytes read");
            for v in [0u8, 0x7f, 0xff] {
                let mut b = good.clone();
                b[n] = v;
                let _ = MeasuredTable::read(&b);
            }
        }
        for n in (400..good.len()).step_by(997) {
            assert!(MeasuredTable::read(&good[..n]).is_err());
        }
        let mut b = good.clone();
        b[0] = b'T';
        assert_eq!(MeasuredTable::read(&b).unwrap_err(), MeasuredError::Magic);
        let e = MeasuredTable::read(&good[..10]).unwrap_err();
        assert!(matches!(e, MeasuredError::Truncated(_)), "{e}");
    }
}
