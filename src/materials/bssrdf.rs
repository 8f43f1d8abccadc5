//! pbrt's tabulated BSSRDF (`TabulatedBSSRDF`): the radial profile Sr of light that
//! enters a translucent material at one point and leaves it at another, by photon beam
//! diffusion (d'Eon and Irving 2011, as pbrt computes it: single scattering plus a
//! dipole sum over depths), tabulated once per (g, η) over 100 albedos and 64 optical
//! radii and looked up with Catmull-Rom splines. Both pbrt versions share the method
//! and its constants; the `subsurface` materials ([`super::subsurface`]) make the
//! coefficients, and the integrators' probe rays ([`crate::integrators::subsurface`])
//! find where the light leaves. [`Profile`] is either this table's or the `disney`
//! material's closed form ([`super::disneybssrdf`]); the probes take both alike.

use super::disneybssrdf::Burley;
use crate::math::catmull_rom;
use crate::media::phase::hg;
use crate::spectrum::Rgb;
use glam::Vec3;
use std::collections::HashMap;
use std::f32::consts::PI;
use std::sync::{Arc, Mutex, OnceLock};

/// The profile table of one (g, η): `profile[i][j]` = 2π r Sr(ρ_i, r_j) at unit σt.
#[derive(PartialEq)]
pub struct BssrdfTable {
    pub rho_samples: Vec<f32>,
    pub radius_samples: Vec<f32>,
    profile: Vec<f32>,
    /// The effective albedo (the profile's integral) at each ρ.
    pub rho_eff: Vec<f32>,
    profile_cdf: Vec<f32>,
}

/// Tables made so far, by the bits of (g, η).
type Tables = Mutex<HashMap<(u32, u32), Arc<BssrdfTable>>>;

/// The table for (g, η), made once per process and shared.
pub fn table(g: f32, eta: f32) -> Arc<BssrdfTable> {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    let tables = TABLES.get_or_init(Default::default);
    let key = (g.to_bits(), eta.to_bits());
    if let Some(t) = tables.lock().ok().and_then(|m| m.get(&key).cloned()) {
        return t;
    }
    let t = Arc::new(BssrdfTable::beam_diffusion(g, eta));
    if let Ok(mut m) = tables.lock() {
        m.insert(key, t.clone());
    }
    t
}

impl std::fmt::Debug for BssrdfTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "BssrdfTable({} albedos × {} radii)", self.rho_samples.len(), self.radius_samples.len())
    }
}

impl BssrdfTable {
    /// pbrt's `ComputeBeamDiffusionBSSRDF` on pbrt's `BSSRDFTable(100, 64)`.
    pub fn beam_diffusion(g: f32, eta: f32) -> BssrdfTable {
        let (n_rho, n_radius) = (100usize, 64usize);
        let mut radius_samples = vec![0.0f32; n_radius];
        radius_samples[1] = 2.5e-3;
        for i in 2..n_radius {
            radius_samples[i] = radius_samples[i - 1] * 1.2;
        }
        let rho_samples: Vec<f32> = (0..n_rho)
            .map(|i| (1.0 - (-8.0 * i as f32 / (n_rho - 1) as f32).exp()) / (1.0 - (-8.0f32).exp()))
            .collect();
        let mut profile = vec![0.0f32; n_rho * n_radius];
        let mut profile_cdf = vec![0.0f32; n_rho * n_radius];
        let mut rho_eff = vec![0.0f32; n_rho];
        for (i, &rho) in rho_samples.iter().enumerate() {
            let row = &mut profile[i * n_radius..(i + 1) * n_radius];
            for (p, &r) in row.iter_mut().zip(&radius_samples) {
                *p = 2.0
                    * PI
                    * r
                    * (beam_diffusion_ss(rho, 1.0 - rho, g, eta, r) + beam_diffusion_ms(rho, 1.0 - rho, g, eta, r));
            }
            let cdf = &mut profile_cdf[i * n_radius..(i + 1) * n_radius];
            rho_eff[i] = catmull_rom::integrate(&radius_samples, row, cdf);
        }
        BssrdfTable { rho_samples, radius_samples, profile, rho_eff, profile_cdf }
    }

    fn eval_profile(&self, rho_index: usize, radius_index: usize) -> f32 {
        self.profile[rho_index * self.radius_samples.len() + radius_index]
    }

    /// pbrt's `SubsurfaceFromDiffuse`: (σa, σs) per channel from the effective albedo
    /// (a diffuse reflectance) and the mean free path.
    pub fn from_diffuse(&self, rho_eff: Rgb, mfp: Rgb) -> (Rgb, Rgb) {
        let rho =
            Vec3::from_array(rho_eff.to_array().map(|r| catmull_rom::invert(&self.rho_samples, &self.rho_eff, r)));
        ((Vec3::ONE - rho) / mfp, rho / mfp)
    }
}

/// pbrt's `FresnelMoment1`: ∫ Fr(η, cos θ) cos θ sin θ dθ, fitted.
pub fn fresnel_moment1(eta: f32) -> f32 {
    let (e2, e3, e4, e5) = (eta * eta, eta * eta * eta, eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.45966 - 1.73965 * eta + 3.37668 * e2 - 3.904945 * e3 + 2.49277 * e4 - 0.68441 * e5
    } else {
        -4.61686 + 11.1136 * eta - 10.4646 * e2 + 5.11455 * e3 - 1.27198 * e4 + 0.12746 * e5
    }
}

/// pbrt's `FresnelMoment2`, fitted.
pub fn fresnel_moment2(eta: f32) -> f32 {
    let (e2, e3, e4, e5) = (eta * eta, eta * eta * eta, eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.27614 - 0.87350 * eta + 1.12077 * e2 - 0.65095 * e3 + 0.07883 * e4 + 0.04860 * e5
    } else {
        let (r1, r2, r3) = (1.0 / eta, 1.0 / e2, 1.0 / e3);
        -547.033 + 45.3087 * r3 - 218.725 * r2 + 458.843 * r1 + 404.557 * eta - 189.519 * e2 + 54.9327 * e3
            - 9.00603 * e4
            + 0.63942 * e5
    }
}

/// pbrt's `BeamDiffusionMS`: multiple scattering, a dipole per depth along the beam.
fn beam_diffusion_ms(sigma_s: f32, sigma_a: f32, g: f32, eta: f32, r: f32) -> f32 {
    const N: usize = 100;
    let sigmap_s = sigma_s * (1.0 - g);
    let sigmap_t = sigma_a + sigmap_s;
    let rhop = sigmap_s / sigmap_t;
    // The non-classical diffusion coefficient and the effective transport coefficient.
    let d_g = (2.0 * sigma_a + sigmap_s) / (3.0 * sigmap_t * sigmap_t);
    let sigma_tr = (sigma_a / d_g).max(0.0).sqrt();
    let (fm1, fm2) = (fresnel_moment1(eta), fresnel_moment2(eta));
    let ze = -2.0 * d_g * (1.0 + 3.0 * fm2) / (1.0 - 2.0 * fm1);
    let (c_phi, c_e) = (0.25 * (1.0 - 2.0 * fm1), 0.5 * (1.0 - 3.0 * fm2));
    let inv_4pi = 1.0 / (4.0 * PI);
    let mut ed = 0.0;
    for i in 0..N {
        let zr = -(1.0 - (i as f32 + 0.5) / N as f32).ln() / sigmap_t;
        let zv = -zr + 2.0 * ze;
        let (dr, dv) = ((r * r + zr * zr).sqrt(), (r * r + zv * zv).sqrt());
        let (er, ev) = ((-sigma_tr * dr).exp(), (-sigma_tr * dv).exp());
        let phi_d = inv_4pi / d_g * (er / dr - ev / dv);
        let ed_n = inv_4pi
            * (zr * (1.0 + sigma_tr * dr) * er / (dr * dr * dr) - zv * (1.0 + sigma_tr * dv) * ev / (dv * dv * dv));
        let e = phi_d * c_phi + ed_n * c_e;
        let kappa = 1.0 - (-2.0 * sigmap_t * (dr + zr)).exp();
        ed += kappa * rhop * rhop * e;
    }
    ed / N as f32
}

/// pbrt's `BeamDiffusionSS`: single scattering along the refracted beam.
fn beam_diffusion_ss(sigma_s: f32, sigma_a: f32, g: f32, eta: f32, r: f32) -> f32 {
    const N: usize = 100;
    let sigma_t = sigma_a + sigma_s;
    let rho = sigma_s / sigma_t;
    // DEVIATION(pbrt): robustness. pbrt-v3 takes √(η² − 1) unguarded, NaN for η < 1
    // (the whole table then NaN); pbrt-v4's SafeSqrt gives 0, as here.
    let t_crit = r * (eta * eta - 1.0).max(0.0).sqrt();
    let mut ess = 0.0;
    for i in 0..N {
        let ti = t_crit - (1.0 - (i as f32 + 0.5) / N as f32).ln() / sigma_t;
        let d = (r * r + ti * ti).sqrt();
        let cos_o = ti / d;
        let fr = crate::materials::microfacet::fr_dielectric(-cos_o, 1.0, eta);
        ess += rho * (-sigma_t * (d + t_crit)).exp() / (d * d) * hg(cos_o, g) * (1.0 - fr) * cos_o.abs();
    }
    ess / N as f32
}

/// A BSSRDF's radial profile at one point: the `subsurface` materials' table, or the
/// `disney` material's two exponentials.
#[derive(Clone, Debug)]
pub enum Profile {
    Tabulated(Tabulated),
    Burley(Burley),
}

impl Profile {
    /// The tabulated profile of σa and σs.
    pub fn new(table: Arc<BssrdfTable>, sigma_a: Rgb, sigma_s: Rgb) -> Profile {
        let sigma_t = sigma_a + sigma_s;
        let rho = Vec3::select(sigma_t.cmpne(Vec3::ZERO), sigma_s / sigma_t, Vec3::ZERO);
        Profile::Tabulated(Tabulated { table, sigma_t, rho })
    }

    /// pbrt's `Sr`: the profile at distance `r`, per channel.
    pub fn sr(&self, r: f32) -> Rgb {
        match self {
            Profile::Tabulated(t) => t.sr(r),
            Profile::Burley(b) => b.sr(r),
        }
    }

    /// pbrt's `Sample_Sr`: a radius drawn from channel `ch`'s profile (`None` where the
    /// channel has none).
    pub fn sample_sr(&self, ch: usize, u: f32) -> Option<f32> {
        match self {
            Profile::Tabulated(t) => t.sample_sr(ch, u),
            Profile::Burley(b) => b.sample_sr(ch, u),
        }
    }

    /// pbrt's `Pdf_Sr`: the density of `sample_sr` on channel `ch` at radius `r`, per
    /// unit area of the plane it is drawn in.
    pub fn pdf_sr(&self, ch: usize, r: f32) -> f32 {
        match self {
            Profile::Tabulated(t) => t.pdf_sr(ch, r),
            Profile::Burley(b) => b.pdf_sr(ch, r),
        }
    }
}

/// The tabulated profile at one point: the table and the coefficients per channel (RGB
/// for pbrt-v3's files, the pass's wavelengths for pbrt-v4's).
#[derive(Clone, Debug)]
pub struct Tabulated {
    pub table: Arc<BssrdfTable>,
    pub sigma_t: Rgb,
    pub rho: Rgb,
}

impl Tabulated {
    /// The spline weights of channel `ch` at distance `r`: (ρ offset, ρ weights,
    /// radius offset, radius weights).
    fn weights(&self, ch: usize, r: f32) -> Option<(usize, [f32; 4], usize, [f32; 4])> {
        let t = &self.table;
        let (ro, rw) = catmull_rom::weights(&t.rho_samples, self.rho[ch])?;
        let (do_, dw) = catmull_rom::weights(&t.radius_samples, r * self.sigma_t[ch])?;
        Some((ro as usize, rw, do_ as usize, dw))
    }

    /// The profile at optical radius, per unit area: Σ w_ij profile_ij / (2π r σt).
    fn spline(&self, ch: usize, r: f32, (ro, rw, d0, dw): (usize, [f32; 4], usize, [f32; 4])) -> f32 {
        let mut sr = 0.0;
        for (i, wi) in rw.iter().enumerate().filter(|w| *w.1 != 0.0) {
            for (j, wj) in dw.iter().enumerate().filter(|w| *w.1 != 0.0) {
                sr += wi * wj * self.table.eval_profile(ro + i, d0 + j);
            }
        }
        let r_optical = r * self.sigma_t[ch];
        if r_optical != 0.0 { sr / (2.0 * PI * r_optical) } else { sr }
    }

    /// The profile at distance `r`, per channel, clamped at 0.
    fn sr(&self, r: f32) -> Rgb {
        let mut out = Vec3::ZERO;
        for ch in 0..3 {
            if let Some(w) = self.weights(ch, r) {
                out[ch] = self.spline(ch, r, w);
            }
        }
        (out * self.sigma_t * self.sigma_t).max(Vec3::ZERO)
    }

    /// A radius drawn from channel `ch`'s profile (`None` where the channel has no
    /// extinction).
    fn sample_sr(&self, ch: usize, u: f32) -> Option<f32> {
        if self.sigma_t[ch] == 0.0 {
            return None;
        }
        let t = &self.table;
        let (r, _) =
            catmull_rom::sample_2d(&t.rho_samples, &t.radius_samples, &t.profile, &t.profile_cdf, self.rho[ch], u)?;
        Some(r / self.sigma_t[ch])
    }

    fn pdf_sr(&self, ch: usize, r: f32) -> f32 {
        let Some(w) = self.weights(ch, r) else { return 0.0 };
        let rho_eff: f32 = (0..4).filter(|&i| w.1[i] != 0.0).map(|i| self.table.rho_eff[w.0 + i] * w.1[i]).sum();
        let sr = self.spline(ch, r, w);
        (sr * self.sigma_t[ch] * self.sigma_t[ch] / rho_eff).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_effective_albedo_rises_with_albedo_and_stays_below_it() {
        let t = BssrdfTable::beam_diffusion(0.0, 1.33);
        assert_eq!((t.rho_samples.len(), t.radius_samples.len()), (100, 64));
        assert_eq!(t.rho_eff[0], 0.0);
        for i in 1..100 {
            assert!(t.rho_eff[i] > t.rho_eff[i - 1], "{i}");
            // Below ρ = 0.99; above it the model (fitted moments, a dipole) overshoots
            // slightly, as pbrt's table does: 1.006 at ρ = 0.99997.
            assert!(t.rho_eff[i] < t.rho_samples[i] || t.rho_samples[i] > 0.99, "{i}: {}", t.rho_eff[i]);
        }
        // A white, non-absorbing medium sends back (nearly) all that enters.
        assert!(t.rho_eff[99] > 0.95 && t.rho_eff[99] < 1.02, "{}", t.rho_eff[99]);
    }

    #[test]
    fn from_diffuse_inverts_the_effective_albedo() {
        let t = table(0.0, 1.33);
        let (a, s) = t.from_diffuse(Vec3::new(0.2, 0.5, 0.8), Vec3::splat(2.0));
        let rho = s / (a + s);
        assert!(((a + s) - Vec3::splat(0.5)).abs().max_element() < 1e-6, "σt is 1/mfp");
        for (ch, want) in [0.2f32, 0.5, 0.8].into_iter().enumerate() {
            let (o, w) = catmull_rom::weights(&t.rho_samples, rho[ch]).unwrap();
            let got: f32 = (0..4).filter(|&i| w[i] != 0.0).map(|i| t.rho_eff[o as usize + i] * w[i]).sum();
            assert!((got - want).abs() < 1e-3, "{ch}: {got}");
        }
    }

    #[test]
    fn extreme_parameters_keep_the_table_finite() {
        for (g, eta) in [(0.99, 1.33), (-0.99, 1.33), (0.0, 0.7), (0.5, 3.0), (0.0, 1.0)] {
            let t = BssrdfTable::beam_diffusion(g, eta);
            assert!(t.profile.iter().chain(&t.rho_eff).chain(&t.profile_cdf).all(|v| v.is_finite()), "g {g}, η {eta}");
            let p = Profile::new(Arc::new(t), Vec3::new(0.0, 1e-6, 10.0), Vec3::new(0.0, 5.0, 1e-8));
            assert_eq!(p.sample_sr(0, 0.5), None, "a channel without extinction draws nothing");
            for r in [0.0, 1e-4, 0.1, 1.0, 1e6] {
                assert!(p.sr(r).is_finite() && (0..3).all(|c| p.pdf_sr(c, r).is_finite()), "g {g}, η {eta}, r {r}");
            }
        }
    }

    /// The sampled radii have the density `pdf_sr`, which integrates to 1 over the plane.
    #[test]
    fn radii_are_drawn_with_the_density_pdf_sr_gives() {
        let p = Profile::new(table(0.0, 1.33), Vec3::new(0.05, 0.2, 1.0), Vec3::new(2.0, 1.0, 1.0));
        for ch in 0..3 {
            let r_max = p.sample_sr(ch, 0.999).unwrap();
            let n = 4000;
            // ∫ pdf(r) 2π r dr over [0, r_max] ≈ 0.999.
            let (mut integral, dr) = (0.0f64, r_max / n as f32);
            for k in 0..n {
                let r = (k as f32 + 0.5) * dr;
                integral += (p.pdf_sr(ch, r) * 2.0 * PI * r * dr) as f64;
            }
            assert!((integral - 0.999).abs() < 0.01, "{ch}: {integral}");
            // The median of the samples is where the integral reaches one half.
            let median = p.sample_sr(ch, 0.5).unwrap();
            let mut half = 0.0f64;
            for k in 0..n {
                let r = (k as f32 + 0.5) * median / n as f32;
                half += (p.pdf_sr(ch, r) * 2.0 * PI * r * median / n as f32) as f64;
            }
            assert!((half - 0.5).abs() < 0.01, "{ch}: {half}");
        }
    }
}
