//! Path guiding (issue 59): a distribution of incident light over space and direction,
//! learnt from the light paths already traced, that camera paths can draw directions
//! from beside their BSDF. It is the spatial-directional tree of Müller et al. (2017),
//! "Practical Path Guiding": a binary tree over the scene ([`STree`]) whose leaves hold
//! quadtrees over the sphere of directions ([`DTree`]), trained in rounds of doubling
//! size.
//!
//! State that several integrators will share (vcm's and bdpt's camera subpaths,
//! SPPM's camera paths), so it lives here, apart from any of them. No integrator draws
//! from it yet: the data structure and its density come first, tested on their own
//! (the density integrates to 1 and its samples follow it).

pub mod dtree;
pub mod stree;

pub use dtree::DTree;
pub use stree::STree;

/// The density of a one-sample mixture that draws from the BSDF with probability
/// `bsdf_share` and from the guide otherwise: what every MIS weight of a guided
/// direction must use.
pub fn mixture_pdf(bsdf_share: f32, bsdf_pdf: f32, guide_pdf: f32) -> f32 {
    bsdf_share * bsdf_pdf + (1.0 - bsdf_share) * guide_pdf
}
