//! pbrt-sppm: reads pbrt-v3 and pbrt-v4 scene files and renders them with stochastic
//! progressive photon mapping.
//!
//! Data flows one way: bytes → tokens → statements ([`parser`]) → scene description
//! ([`scene`]) → render-ready scene → image.

pub mod accel;
pub mod approx;
pub mod camera;
pub mod cli;
pub mod filters;
pub mod fixes;
pub mod guiding;
pub mod heap;
pub mod hugepages;
pub mod imageio;
pub mod integrators;
pub mod interaction;
pub mod job;
pub mod lights;
pub mod limits;
pub mod materials;
pub mod math;
pub mod media;
pub mod memory;
pub mod mitsuba;
pub mod parser;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shapes;
pub mod spectrum;
pub mod textures;
pub mod values;
