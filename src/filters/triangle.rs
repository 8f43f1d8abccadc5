//! `PixelFilter "triangle"` (radius 2): a tent, r − |x|, drawn exactly (pbrt-v4's
//! `TriangleFilter` and `SampleTent`).

/// An offset in [−r, r] with density ∝ r − |x|, for a uniform `u`.
pub fn sample_tent(u: f32, r: f32) -> f32 {
    // Which half by u, then that half's linear density by inversion.
    if u < 0.5 {
        let u = u / 0.5;
        -r + r * u.sqrt()
    } else {
        let u = (u - 0.5) / 0.5;
        r - r * (1.0 - u).sqrt()
    }
}
