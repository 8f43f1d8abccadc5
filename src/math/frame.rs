//! Orthonormal frames.

use glam::Vec3;

/// Two unit vectors completing `v` (unit) to an orthonormal basis (Duff et al. 2017).
pub fn coordinate_system(v: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(v.z);
    let a = -1.0 / (sign + v.z);
    let b = v.x * v.y * a;
    (Vec3::new(1.0 + sign * v.x * v.x * a, sign * b, -sign * v.x), Vec3::new(b, sign + v.y * v.y * a, -v.y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal() {
        for v in [Vec3::X, Vec3::NEG_Z, Vec3::new(0.3, -0.5, 0.8).normalize()] {
            let (a, b) = coordinate_system(v);
            assert!(a.dot(v).abs() < 1e-6 && b.dot(v).abs() < 1e-6 && a.dot(b).abs() < 1e-6);
            assert!((a.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
        }
    }
}
