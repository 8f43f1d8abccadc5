//! pbrt-v4's named glasses and standard illuminants.
//!
//! ```text
//! Material "dielectric" "spectrum eta" "glass-BK7"
//! LightSource "point" "spectrum I" "stdillum-F2"      # also A, D50, D65, F1–F12, illum-acesD60
//! ```
//! Illuminants are the CIE tables (`data.rs`), scaled to luminance 1 as pbrt-v4 scales
//! them, and zero outside their tables.
//!
//! Glasses:
//! n²(λ) = 1 + Σ Bᵢ λ² / (λ² − Cᵢ), λ in µm, with SCHOTT's coefficients (BK7, N-BAF10,
//! N-FK51A, N-LASF9, SF5, N-SF10, N-SF11; as published by refractiveindex.info, CC0).
//! pbrt-v4 tabulates the same formulas at about 22 nm steps: its values are these at
//! 370–910 nm within 4.3e-4 (its printed wavelengths are rounded to whole nm).

/// A glass's dispersion: three Sellmeier terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sellmeier {
    pub b: [f64; 3],
    /// µm².
    pub c: [f64; 3],
}

impl Sellmeier {
    /// The refractive index at `lambda` nm.
    pub fn eta(&self, lambda: f64) -> f64 {
        let x = (lambda / 1000.0).powi(2);
        (1.0 + (0..3).map(|i| self.b[i] * x / (x - self.c[i])).sum::<f64>()).sqrt()
    }
}

/// The glasses pbrt-v4 names, and their formulas.
pub const GLASSES: [(&str, Sellmeier); 7] = [
    ("glass-BK7", glass([1.03961212, 0.231792344, 1.01046945], [0.00600069867, 0.0200179144, 103.560653])),
    ("glass-BAF10", glass([1.5851495, 0.143559385, 1.08521269], [0.00926681282, 0.0424489805, 105.613573])),
    ("glass-FK51A", glass([0.971247817, 0.216901417, 0.904651666], [0.00472301995, 0.0153575612, 168.68133])),
    ("glass-LASF9", glass([2.00029547, 0.298926886, 1.80691843], [0.0121426017, 0.0538736236, 156.530829])),
    ("glass-F5", glass([1.52481889, 0.187085527, 1.42729015], [0.011254756, 0.0588995392, 129.141675])),
    ("glass-F10", glass([1.62153902, 0.256287842, 1.64447552], [0.0122241457, 0.0595736775, 147.468793])),
    ("glass-F11", glass([1.73759695, 0.313747346, 1.89878101], [0.013188707, 0.0623068142, 155.23629])),
];

const fn glass(b: [f64; 3], c: [f64; 3]) -> Sellmeier {
    Sellmeier { b, c }
}

/// The glass pbrt-v4 calls `name`.
pub fn glass_named(name: &str) -> Option<Sellmeier> {
    GLASSES.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

/// One index for a renderer of RGB: the mean over the visible spectrum weighted by
/// luminance (ȳ), which is what the RGB of the index spectrum has as its luminance.
pub fn luminance_mean(s: &Sellmeier) -> f64 {
    super::cie::luminance_of(|l| s.eta(l))
}

/// The standard illuminant pbrt-v4 calls `name`: (its table, the table's first
/// wavelength in nm; 5 nm steps).
fn illuminant_table(name: &str) -> Option<(&'static [f64], f64)> {
    use super::data::*;
    let fluorescent: [&'static [f64]; 12] = [
        &ILLUM_F1, &ILLUM_F2, &ILLUM_F3, &ILLUM_F4, &ILLUM_F5, &ILLUM_F6, &ILLUM_F7, &ILLUM_F8, &ILLUM_F9, &ILLUM_F10,
        &ILLUM_F11, &ILLUM_F12,
    ];
    Some(match name {
        "stdillum-A" => (&ILLUM_A, 300.0),
        "stdillum-D50" => (&ILLUM_D50, 300.0),
        "stdillum-D65" => (&ILLUM_D65, 300.0),
        "illum-acesD60" => (&ILLUM_ACES_D60, 300.0),
        _ => {
            let i = (1..=12).find(|i| name == format!("stdillum-F{i}"))?;
            (fluorescent[i - 1], 380.0)
        }
    })
}

/// The standard illuminant pbrt-v4 calls `name`, as a function of λ (nm), at
/// luminance 1.
pub fn illuminant_named(name: &str) -> Option<impl Fn(f64) -> f64 + Copy> {
    let (table, start) = illuminant_table(name)?;
    let at = move |lambda: f64| super::cie::five_nm(table, start, lambda);
    let scale = 1.0 / super::cie::luminance_of(at);
    Some(move |lambda: f64| scale * at(lambda))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_indices_at_the_d_line() {
        // The catalogues' n_d (587.56 nm): BK7 1.5168, N-BAF10 1.6700, N-FK51A 1.4866,
        // N-LASF9 1.8503, SF5 1.6727, N-SF10 1.7283, N-SF11 1.7847.
        let nd = [1.5168, 1.6700, 1.4866, 1.8503, 1.6727, 1.7283, 1.7847];
        for ((name, s), want) in GLASSES.iter().zip(nd) {
            assert!((s.eta(587.56) - want).abs() < 1e-4, "{name}: {}", s.eta(587.56));
        }
    }

    #[test]
    fn standard_illuminants_have_their_published_whites() {
        // CIE chromaticities (x, y) of A, D50, D65, F2 and F11, and luminance 1.
        let whites = [
            ("stdillum-A", [0.44757, 0.40745]),
            ("stdillum-D50", [0.34567, 0.35850]),
            ("stdillum-D65", [0.31271, 0.32902]),
            ("stdillum-F2", [0.37208, 0.37529]),
            ("stdillum-F11", [0.38052, 0.37713]),
        ];
        for (name, [x, y]) in whites {
            let s = illuminant_named(name).unwrap();
            let xyz = crate::spectrum::cie::spectrum_to_xyz(s);
            let [gx, gy] = crate::spectrum::colorspace::chromaticity(xyz);
            assert!((gx - x).abs() < 1e-3 && (gy - y).abs() < 1e-3, "{name}: {gx} {gy}");
            assert!((xyz[1] - 1.0).abs() < 1e-9);
        }
        for other in ["stdillum-F13", "stdillum-F0", "stdillum-F01", "stdillum-F+1", "stdillum-F"] {
            assert!(illuminant_named(other).is_none(), "{other}");
        }
    }

    #[test]
    fn blue_bends_more_than_red() {
        for (name, s) in &GLASSES {
            assert!(s.eta(450.0) > s.eta(550.0) && s.eta(550.0) > s.eta(650.0), "{name}");
        }
        let bk7 = glass_named("glass-BK7").unwrap();
        assert!((luminance_mean(&bk7) - bk7.eta(560.0)).abs() < 1e-3);
    }
}
