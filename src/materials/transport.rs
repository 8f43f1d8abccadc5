//! Which quantity a path carries, which decides how refraction scales it.

/// Which quantity a path carries: radiance (camera paths) or importance (photons).
/// Refraction differs: radiance is scaled by (η_i/η_t)².
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

impl TransportMode {
    /// The other quantity: paths traced backwards (pbrt-v4's `!mode`).
    pub fn adjoint(self) -> TransportMode {
        match self {
            TransportMode::Radiance => TransportMode::Importance,
            TransportMode::Importance => TransportMode::Radiance,
        }
    }
}
