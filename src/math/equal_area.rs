//! Clarberg's equal-area map between the unit square and the sphere of directions,
//! as pbrt-v4 uses it for its spherical camera and goniometric lights.

use glam::DVec3;

/// Clarberg's equal-area map of the unit square onto the sphere (pbrt-v4's
/// `EqualAreaSquareToSphere`), +z at the square's centre.
pub fn square_to_sphere([px, py]: [f64; 2]) -> DVec3 {
    let (u, v) = (2.0 * px - 1.0, 2.0 * py - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let signed_distance = 1.0 - (up + vp);
    let r = 1.0 - signed_distance.abs();
    let phi = (if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 }) * std::f64::consts::FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed_distance);
    let (cos_phi, sin_phi) = (phi.cos().copysign(u), phi.sin().copysign(v));
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    DVec3::new(cos_phi * s, sin_phi * s, z)
}

/// Folds a point outside the unit square back onto it as the equal-area map's
/// symmetries do (pbrt-v4's `WrapEqualAreaSquare`).
pub fn wrap([mut u, mut v]: [f64; 2]) -> [f64; 2] {
    if u < 0.0 {
        (u, v) = (-u, 1.0 - v);
    } else if u > 1.0 {
        (u, v) = (2.0 - u, 1.0 - v);
    }
    if v < 0.0 {
        (u, v) = (1.0 - u, -v);
    } else if v > 1.0 {
        (u, v) = (1.0 - u, 2.0 - v);
    }
    [u, v]
}

/// The inverse of [`square_to_sphere`] for a unit direction (pbrt-v4's
/// `EqualAreaSphereToSquare`, with its polynomial arctangent).
pub fn sphere_to_square(d: DVec3) -> [f64; 2] {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let a = x.max(y);
    let b = if a == 0.0 { 0.0 } else { x.min(y) / a };
    const T: [f64; 7] = [
        0.406_758_566_246_788_5e-5,
        0.636_226_545_274_016_1,
        0.615_720_178_982_802_1e-2,
        -0.247_333_733_281_268_94,
        0.881_770_664_775_316_3e-1,
        0.419_038_818_029_165_7e-1,
        -0.251_390_972_343_483_5e-1,
    ];
    let mut phi = T.iter().rev().fold(0.0, |acc, &c| acc * b + c);
    if x < y {
        phi = 1.0 - phi;
    }
    let (mut v, mut u) = (phi * r, r - phi * r);
    if d.z < 0.0 {
        (u, v) = (1.0 - v, 1.0 - u);
    }
    [0.5 * (u.copysign(d.x) + 1.0), 0.5 * (v.copysign(d.y) + 1.0)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_equal_area_square_covers_the_sphere_evenly() {
        assert!((square_to_sphere([0.5, 0.5]) - DVec3::Z).length() < 1e-12);
        assert!((square_to_sphere([0.0, 0.0]) + DVec3::Z).length() < 1e-12);
        // Unit directions, and equal areas: a grid's cells split the upper hemisphere
        // (the square's inner diamond) from the lower one half and half.
        let n = 200;
        let mut upper = 0;
        for j in 0..n {
            for i in 0..n {
                let d = square_to_sphere([(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64]);
                assert!((d.length() - 1.0).abs() < 1e-9);
                upper += usize::from(d.z > 0.0);
            }
        }
        assert!((upper as f64 / (n * n) as f64 - 0.5).abs() < 0.01, "{upper}");
        assert_eq!(wrap([-0.25, 0.25]), [0.25, 0.75]);
        // The inverse map takes each direction back to its point of the square.
        for p in [[0.3, 0.7], [0.9, 0.2], [0.05, 0.5], [0.6, 0.95]] {
            let q = sphere_to_square(square_to_sphere(p));
            assert!((q[0] - p[0]).abs() < 1e-5 && (q[1] - p[1]).abs() < 1e-5, "{p:?} -> {q:?}");
        }
    }
}
