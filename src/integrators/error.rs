//! What can stop a render before or while it runs.

use std::ops::Range;

/// Why a render cannot start or cannot finish; every message names what to change.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("the radius must be at least {min:e} and finite, not {radius}")]
    Radius { radius: f32, min: f32 },
    #[error(
        "the pass range {}..{} does not fit in the render's {iterations} passes (0..{iterations}; set the total with --spp)",
        range.start, range.end
    )]
    PassRange { range: Range<u32>, iterations: u32 },
    #[error("a pass range needs independent passes (--passes independent)")]
    RangeNeedsIndependentPasses,
    #[error(
        "adaptive photon sampling carries its Markov chains from pass to pass, so it cannot render independent \
         passes; use --photon-sampling uniform"
    )]
    AdaptiveIndependent,
    #[error("adaptive photon sampling is for SPPM; vcm and bdpt trace uniform light paths (--photon-sampling uniform)")]
    AdaptiveVcm,
    #[error(
        "path guiding is for vcm and bdpt; SPPM's camera paths stop at their first diffuse surface, and its \
         photons find what the camera sees with --photon-sampling adaptive (--guiding off)"
    )]
    GuidingSppm,
    #[error("--emission is vcm's and bdpt's: SPPM's photons leave their lights as pbrt's do")]
    EmissionSppm,
    #[error("--connections is vcm's and bdpt's: SPPM makes no connections")]
    ConnectionsSppm,
    #[error("--volume-gather is SPPM's; vcm and bdpt connect and merge in media as they do on surfaces")]
    VolumeGatherVcm,
    #[error("--volume-gather beams needs uniform photons (--photon-sampling uniform)")]
    AdaptiveBeams,
    #[error("not enough memory for the state of {width}x{height} pixels ({bytes} bytes)")]
    OutOfMemory { width: usize, height: usize, bytes: usize },
    #[error("the reference image is {}x{}, the render {}x{}", reference.0, reference.1, render.0, render.1)]
    ReferenceSize { reference: (usize, usize), render: (usize, usize) },
    #[error("the checkpoint is at pass {at}, outside this run's passes {}..{}", range.start, range.end)]
    CheckpointOutside { at: u32, range: Range<u32> },
    #[error("the checkpoint holds {saved} pixels, the film {film}")]
    CheckpointPixels { saved: usize, film: usize },
    #[error("the checkpoint's photon sampling differs from this run's")]
    CheckpointSampling,
    #[error("the checkpoint holds {saved} spectral bucket sums, the film {film}")]
    CheckpointBuckets { saved: usize, film: usize },
    // DEVIATION(pbrt): robustness. pbrt writes such a light's pixels as Inf; vcm
    // dropped its infinite samples and rendered the scene as if it were not there.
    #[error(
        "the area light on world shape {shape} (counted from 0 in the file's order): its \"power\" over a piece of \
         area {area:.2e} is a radiance beyond the range of 32-bit floats"
    )]
    LightOverflow { shape: u32, area: f32 },
    // DEVIATION(pbrt): robustness. pbrt writes such pixels as Inf.
    #[error(
        "pixel ({}, {}) is {value:?}, beyond the range of 32-bit floats: lower the lights or the Film's \"scale\"",
        pixel.0, pixel.1
    )]
    NotFinite { pixel: (i32, i32), value: [f32; 3] },
    /// A second interrupt took over: the image of the completed iterations is written
    /// by whoever aborted, and the render writes nothing.
    #[error("stopped by a second interrupt")]
    Aborted,
}
