//! Integrators. pbrt-sppm renders with stochastic progressive photon mapping only.

pub mod sppm;
