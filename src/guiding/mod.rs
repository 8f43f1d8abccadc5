//! Path guiding (issue 59): a distribution of incident light over space and direction,
//! learnt from the light paths already traced, that camera paths draw directions from
//! beside their BSDF, and a distribution of incident importance (where the camera's
//! paths arrive from), that light paths draw from. Each is the spatial-directional tree
//! of Müller et al. (2017), "Practical Path Guiding": a binary tree over the scene
//! ([`STree`]) whose leaves hold quadtrees over the sphere of directions ([`DTree`]),
//! trained in rounds of doubling size ([`Guide`]).
//!
//! ```text
//! pbrt-sppm render room.pbrt --integrator vcm --guiding on      # camera subpaths
//! pbrt-sppm render room.pbrt --integrator vcm --guiding light   # light subpaths
//! pbrt-sppm render room.pbrt --integrator vcm --guiding both
//! ```
//!
//! State that several integrators may share (vcm's and bdpt's subpaths today), so it
//! lives here, apart from any of them.

pub mod dtree;
pub mod stree;
pub mod training;

pub use dtree::DTree;
pub use stree::STree;
pub use training::{Guide, Record, Records};

use glam::Vec3;

/// Which subpaths draw directions from a guide (`--guiding`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Guiding {
    #[default]
    Off,
    /// Camera subpaths, from the incident light (`on`).
    Camera,
    /// Light subpaths, from the incident importance.
    Light,
    /// Both.
    Both,
}

impl Guiding {
    /// Camera subpaths are guided.
    pub fn camera(self) -> bool {
        matches!(self, Guiding::Camera | Guiding::Both)
    }

    /// Light subpaths are guided.
    pub fn light(self) -> bool {
        matches!(self, Guiding::Light | Guiding::Both)
    }

    /// The option's value that asks for it.
    pub fn name(self) -> &'static str {
        match self {
            Guiding::Off => "off",
            Guiding::Camera => "on",
            Guiding::Light => "light",
            Guiding::Both => "both",
        }
    }
}

impl std::str::FromStr for Guiding {
    type Err = String;
    fn from_str(s: &str) -> Result<Guiding, String> {
        [Guiding::Off, Guiding::Camera, Guiding::Light, Guiding::Both]
            .into_iter()
            .find(|g| g.name() == s)
            .ok_or_else(|| format!("expected off, on, light or both, not \"{s}\""))
    }
}

/// The share of directions a guided vertex draws from its BSDF (Müller et al.'s fixed
/// one half): the BSDF keeps what the guide has not learnt reachable.
pub const BSDF_SHARE: f32 = 0.5;

/// The density of a one-sample mixture that draws from the BSDF with probability
/// `bsdf_share` and from the guide otherwise: what every MIS weight of a guided
/// direction must use.
pub fn mixture_pdf(bsdf_share: f32, bsdf_pdf: f32, guide_pdf: f32) -> f32 {
    bsdf_share * bsdf_pdf + (1.0 - bsdf_share) * guide_pdf
}

/// A guided vertex's mixture: its directional tree and the BSDF's share, and, where
/// the BSDF only reflects, the normal (toward the side it reflects to) the guide's
/// directions are folded about: a direction drawn behind the surface is mirrored to
/// the front, so none is lost to a zero BSDF (the tree covers the whole sphere, and a
/// leaf spans surfaces facing many ways).
#[derive(Clone, Copy, Debug)]
pub struct Mix<'a> {
    pub tree: &'a DTree,
    pub bsdf_share: f32,
    pub fold: Option<Vec3>,
}

impl Mix<'_> {
    /// The mixture's density of direction `d`, given the BSDF's.
    #[inline]
    pub fn pdf(&self, bsdf_pdf: f32, d: Vec3) -> f32 {
        mixture_pdf(self.bsdf_share, bsdf_pdf, self.guide_pdf(d))
    }

    /// The guide's density of `d` (folded: that of `d` and of its mirror image, none
    /// behind the surface).
    pub fn guide_pdf(&self, d: Vec3) -> f32 {
        match self.fold {
            None => self.tree.pdf(d),
            Some(n) => match d.dot(n) {
                c if c < 0.0 => 0.0,
                c => self.tree.pdf(d) + self.tree.pdf(d - 2.0 * c * n),
            },
        }
    }

    /// The mixture toward direction `d`, fixed once (see [`Toward`]).
    pub fn toward(&self, d: Vec3) -> Toward {
        Toward { bsdf_share: self.bsdf_share, guide_pdf: self.guide_pdf(d) }
    }

    /// A direction from the guide (folded to the front where it folds).
    pub fn sample_guide(&self, u: [f32; 2]) -> Vec3 {
        let d = self.tree.sample(u);
        match self.fold {
            Some(n) if d.dot(n) < 0.0 => d - 2.0 * d.dot(n) * n,
            _ => d,
        }
    }
}

/// Where a vertex kept for later stands in a guide: its leaf ([`STree::leaf`]) and the
/// normal its mixture folds about (see [`Mix`]), so that the mixture is made again
/// without descending the tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Guided {
    pub leaf: u32,
    pub fold: Option<Vec3>,
}

/// A guided vertex's mixture density for one direction known in advance (a light
/// vertex's way back toward the light: what a camera subpath reaching it would have to
/// draw).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Toward {
    pub bsdf_share: f32,
    /// The guide's density of the direction.
    pub guide_pdf: f32,
}

impl Toward {
    /// The mixture's density of the direction, given the BSDF's.
    #[inline]
    pub fn pdf(&self, bsdf_pdf: f32) -> f32 {
        mixture_pdf(self.bsdf_share, bsdf_pdf, self.guide_pdf)
    }
}
