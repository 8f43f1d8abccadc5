//! Integrators. pbrt-sppm renders with stochastic progressive photon mapping only:
//! [`sppm`] holds its passes, [`grid`] the photon lookup grid, [`run`] the render loop, [`report`] `ERRORS.csv` and
//! progress. Data flows one way: the render-ready scene (`render`) in, an image out.

pub mod adaptive;
pub mod grid;
pub mod report;
pub mod run;
pub mod sppm;

pub use report::{ERRORS_HEADER, ErrorRow, errors_csv};
pub use run::{RenderOutput, RenderSettings};
