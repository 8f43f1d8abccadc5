//! Integrators: stochastic progressive photon mapping ([`sppm`] holds its passes) and
//! vertex connection and merging ([`vcm`]; bdpt is vcm without merging), both driven
//! through [`engine`]. [`grid`] is the photon (and light vertex) lookup grid,
//! [`adaptive`] adaptive photon chains, [`plan`] what a run is asked and runs with, [`run`] the render loop, [`error`] what stops
//! it, [`checkpoint`] saved and resumed state, [`completed`] the last completed image for an abort, [`passes`] independent passes, [`part`]
//! shard files and their merge, [`report`] `ERRORS.csv` and progress, [`preview`] images inside a long iteration. Data flows one
//! way: the render-ready scene (`render`) in, an image out.

pub mod adaptive;
pub mod beams;
pub mod buckets;
pub mod checkpoint;
pub mod completed;
pub mod engine;
pub mod error;
pub mod grid;
pub mod part;
pub mod passes;
pub mod plan;
pub mod preview;
pub mod report;
pub mod run;
pub mod sppm;
pub mod subsurface;
pub mod vcm;
pub mod volume;

pub use error::RenderError;

/// The most pixels one parallel task renders. Rayon splits a pixel range only a few
/// times before a thread runs a piece on its own, so when the costly pixels (the glass
/// of a caustic scene) sit in one quarter of the image, the other thread finishes its
/// half early and finds nothing left to steal: f16-9a's camera pass ran 1.56× faster on
/// two threads instead of 1.9×. Small tasks keep both threads busy to the end.
pub(crate) const PIXELS_PER_TASK: usize = 1024;
pub use plan::Algorithm;
pub use report::{ERRORS_HEADER, ErrorRow, errors_csv};
pub use run::{CheckpointTarget, Monitor, Plan, RenderOutput, RenderSettings, render};
