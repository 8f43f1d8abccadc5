//! Where pbrt's image is wrong, and the switches that correct it.
//!
//! By default a file renders as its own pbrt renders it, bugs included: the people who
//! made a pbrt-v3 scene tuned it in pbrt-v3. Each bug that changes the converged image
//! of a valid scene has a name here; `--fix NAME,...` (or `--fix all`) renders the
//! physically right image instead, and `check` lists, at the statement that triggers
//! it, each bug a scene would show. Robustness fixes (hangs, crashes, NaN, missed hits,
//! overflow) are not listed: they are always on.
//!
//! ```text
//! pbrt-sppm scene.pbrt --fix plastic-fresnel,sky-after-glossy
//! pbrt-sppm scene.pbrt --fix all
//! pbrt-sppm --fix help
//! ```

/// One pbrt bug that changes how a valid scene looks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Fix {
    PlasticFresnel,
    LayeredWeights,
    SkyAfterGlossy,
    MarblePalette,
    MeshPower,
    AreaAlpha,
    PhotonsBehind,
    ShapeSampling,
    NormalDerivatives,
    HyperboloidSurface,
    CameraMedium,
    MediumEmission,
    MotionTime,
    MapIlluminance,
    SubsurfaceWalk,
    RoughTransmission,
    PortalPhotons,
}

/// Name, the pbrt versions that have the bug, and what fixing it changes.
pub struct FixInfo {
    pub fix: Fix,
    pub name: &'static str,
    pub versions: &'static str,
    pub effect: &'static str,
}

/// Every fix, in the order `--fix help` lists them.
pub const FIXES: [FixInfo; 17] = [
    FixInfo {
        fix: Fix::PlasticFresnel,
        name: "plastic-fresnel",
        versions: "v3",
        effect: "plastic's coat is air over index 1.5; pbrt-v3 swaps the indices, so its highlights turn \
                 totally reflecting past a 41.8° half-angle (much brighter highlights and rims)",
    },
    FixInfo {
        fix: Fix::LayeredWeights,
        name: "layered-weights",
        versions: "v4",
        effect: "coateddiffuse/coatedconductor with a rough coat: pbrt-v4 weighs two ways out of the coat \
                 with densities of different directions, so the material reflects too much (up to 7%)",
    },
    FixInfo {
        fix: Fix::SkyAfterGlossy,
        name: "sky-after-glossy",
        versions: "v3",
        effect: "an infinite light seen after a glossy bounce is counted once; pbrt-v3 adds it twice \
                 (direct lighting and the escaped ray), so glossy surfaces under a sky are too bright",
    },
    FixInfo {
        fix: Fix::MarblePalette,
        name: "marble-palette",
        versions: "v3",
        effect: "marble's colour spline stays within its palette; pbrt-v3 picks the wrong segment and \
                 evaluates colours far outside [0, 1] (values of 10 and more)",
    },
    FixInfo {
        fix: Fix::MeshPower,
        name: "mesh-power",
        versions: "v4",
        effect: "an area light's `power` on a mesh is spread over the whole mesh; pbrt-v4 gives each \
                 triangle or patch the whole power, so a mesh of n of them emits n times too much",
    },
    FixInfo {
        fix: Fix::AreaAlpha,
        name: "area-alpha",
        versions: "v3, v4",
        effect: "alpha masks an area light's emission once; pbrt-v3 ignores it (cut-away parts still \
                 emit photons and light samples), pbrt-v4 applies it twice where a ray sees the light",
    },
    FixInfo {
        fix: Fix::PhotonsBehind,
        name: "photons-behind",
        versions: "v3, v4",
        effect: "photons arriving from behind an opaque visible point are not counted; pbrt counts them \
                 with no flux, which shrinks the photon radius faster near edges and thin objects",
    },
    FixInfo {
        fix: Fix::ShapeSampling,
        name: "shape-sampling",
        versions: "v3, v4",
        effect: "sphere, disk and cylinder area lights are sampled over their own surface with its world-space \
                 area; pbrt samples the whole sphere or disk however it is cut, uses the object-space area and \
                 radius under a transform (a scaled sphere light is too dark or too bright), and flips sampled \
                 normals by ReverseOrientation only (a mirrored one-sided light emits from its back)",
    },
    FixInfo {
        fix: Fix::NormalDerivatives,
        name: "normal-derivatives",
        versions: "v3, v4",
        effect: "bump maps on scaled or reversed quadrics use the true derivatives of the normal; pbrt \
                 transforms them as normals (off by the scale) and ignores ReverseOrientation, which tilts \
                 the bumps' shading there",
    },
    FixInfo {
        fix: Fix::HyperboloidSurface,
        name: "hyperboloid-surface",
        versions: "v3",
        effect: "a hyperboloid is the surface its segment p1→p2 sweeps, which its (u,v), normals and \
                 area describe; pbrt-v3 intersects an implicit fit that is that surface only when the \
                 segment's closest approach to the axis is at z = 0 (pbrt-v3 #168)",
    },
    FixInfo {
        fix: Fix::CameraMedium,
        name: "camera-medium",
        versions: "v3",
        effect: "the camera sits in the outside medium current at its Camera statement, as in pbrt-v4; \
                 pbrt-v3 makes the camera at WorldEnd and gives it the medium current there, so a \
                 MediumInterface at the world's top level moves the camera into (or out of) that medium",
    },
    FixInfo {
        fix: Fix::MediumEmission,
        name: "medium-emission",
        versions: "v4",
        effect: "a temperature grid's blackbody and an rgbgrid's Le are recorded as the same spectrum on a \
                 light would be; pbrt-v4 normalises neither and its film records them 106.86 (∫ȳ dλ) times \
                 brighter than the same values on a homogeneous medium or a light",
    },
    FixInfo {
        fix: Fix::MotionTime,
        name: "motion-time",
        versions: "v3",
        effect: "each SPPM pass renders at one time within the shutter, as pbrt-v4's does; pbrt-v3 draws \
                 every photon's time apart from the camera paths', so a moving surface gathers the photons \
                 that landed where it is at other times and is lit too little by indirect light",
    },
    FixInfo {
        fix: Fix::MapIlluminance,
        name: "map-illuminance",
        versions: "v4",
        effect: "an environment map's `illuminance` gives an upward-facing surface that many lux; pbrt-v4 \
                 counts each texel's solid angle as half what it is, so the sky comes out twice as bright",
    },
    FixInfo {
        fix: Fix::SubsurfaceWalk,
        name: "subsurface-walk",
        versions: "v3, v4",
        effect: "light under a subsurface material's boundary walks through a homogeneous medium of its \
                 coefficients (vcm and bdpt, for the files whose pbrt takes the BSSRDF): the exact answer \
                 where pbrt's photon beam diffusion approximates it, which assumes a flat, semi-infinite \
                 slab and so brightens thin parts and blurs edges",
    },
    FixInfo {
        fix: Fix::RoughTransmission,
        name: "rough-transmission",
        versions: "v3",
        effect: "rough glass, translucent and disney transmission pass light only through microfacets \
                 that face both ways, as in pbrt-v4; pbrt-v3 also transmits through those facing away, which \
                 only next-event estimation finds and its MIS weights count in part, so each integrator keeps \
                 a different share of that light (a frosted glass ball about 2% brighter than fixed)",
    },
    FixInfo {
        fix: Fix::PortalPhotons,
        name: "portal-photons",
        versions: "v4",
        effect: "SPPM's photons from an infinite light with a portal enter through the portal; pbrt-v4 \
                 sends them from the portal's half of the sky across the whole scene, so its sky also \
                 lights what is outside and comes in through other openings, where the light itself \
                 shows black and gives no direct light",
    },
];

impl Fix {
    pub fn info(self) -> &'static FixInfo {
        FIXES.iter().find(|i| i.fix == self).expect("every fix is listed")
    }

    pub fn name(self) -> &'static str {
        self.info().name
    }

    fn bit(self) -> u32 {
        1 << self as u32
    }
}

/// The fixes a render applies (none by default: pbrt's image).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Fixes(u32);

impl Fixes {
    pub const NONE: Fixes = Fixes(0);

    pub fn all() -> Fixes {
        Fixes(FIXES.iter().fold(0, |m, i| m | i.fix.bit()))
    }

    pub fn has(self, fix: Fix) -> bool {
        self.0 & fix.bit() != 0
    }

    pub fn with(self, fix: Fix) -> Fixes {
        Fixes(self.0 | fix.bit())
    }

    /// The names of the fixes applied, comma-separated (`none` when there are none).
    pub fn names(self) -> String {
        let names: Vec<&str> = FIXES.iter().filter(|i| self.has(i.fix)).map(|i| i.name).collect();
        if names.is_empty() { "none".into() } else { names.join(",") }
    }

    /// Parses `--fix`'s value: names separated by commas, `all` or `none`.
    pub fn parse(s: &str) -> Result<Fixes, String> {
        let mut fixes = Fixes::NONE;
        for word in s.split(',').map(str::trim).filter(|w| !w.is_empty()) {
            fixes = match word {
                "all" => Fixes::all(),
                "none" => fixes,
                _ => match FIXES.iter().find(|i| i.name == word) {
                    Some(i) => fixes.with(i.fix),
                    None => {
                        let known: Vec<&str> = FIXES.iter().map(|i| i.name).collect();
                        return Err(format!("unknown fix \"{word}\"; the fixes are all, {}", known.join(", ")));
                    }
                },
            };
        }
        Ok(fixes)
    }

    /// `--fix help`: one line per fix.
    pub fn help() -> String {
        let mut s =
            String::from("pbrt bugs pbrt-sppm reproduces by default and can fix (--fix NAME,... or --fix all):\n");
        for i in &FIXES {
            s += &format!("  {:<28} [{}] {}\n", i.name, i.versions, i.effect);
        }
        s
    }
}

/// A pbrt bug a scene triggers, where (for `check`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PbrtBug {
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub name: String,
    pub effect: String,
    /// Whether this run fixes it (`--fix`).
    pub fixed: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_to_their_fixes_and_back() {
        let f = Fixes::parse("plastic-fresnel, mesh-power").unwrap();
        assert!(f.has(Fix::PlasticFresnel) && f.has(Fix::MeshPower) && !f.has(Fix::AreaAlpha));
        assert_eq!(f.names(), "plastic-fresnel,mesh-power");
        assert_eq!(Fixes::parse("all").unwrap(), Fixes::all());
        assert_eq!(Fixes::parse("none").unwrap(), Fixes::NONE);
        assert!(FIXES.iter().all(|i| Fixes::all().has(i.fix) && i.fix.name() == i.name));
        let e = Fixes::parse("plastic").unwrap_err();
        assert!(e.contains("unknown fix \"plastic\"") && e.contains("plastic-fresnel"), "{e}");
    }

    #[test]
    fn help_lists_every_fix_on_one_line() {
        let h = Fixes::help();
        assert_eq!(h.lines().count(), FIXES.len() + 1);
        // The effects are written over several source lines; each reads as one line.
        assert!(FIXES.iter().all(|i| !i.effect.contains("  ") && !i.effect.contains('\n')));
        assert!(FIXES.iter().all(|i| h.contains(i.name)));
    }
}
