//! Aimed emission: a light with a position and no extent that stands outside the
//! scene's shapes emits its light subpaths only toward them.
//!
//! ```text
//! LightSource "point" "color I" [300 290 270] "point from" [1.5 9 3]  # far above a pool
//! LightSource "point" "color I" [40 40 40] "point from" [3 2.2 0]     # outside a room
//! ```
//!
//! A point light emits uniformly over the sphere of directions (a spot, projection
//! or goniometric light over its own cone or the sphere), as pbrt's `Sample_Le` does.
//! Seen from outside the sphere around everything a ray can hit, most of those
//! directions meet nothing: their subpaths end at once, with no vertex, no light
//! tracing and nothing to merge. They cost a pass as much as the useful ones (on the
//! pool, 99% of the light subpaths were such). Drawing directions uniformly within the
//! cone the sphere subtends instead changes no path that can reach the camera, only
//! how densely it is drawn, so the estimate keeps its mean: a subpath carries the
//! light's intensity along its direction over the cone's density, and the weights
//! read the same density for next-event estimation's paths ([`Cone::density`]).
//!
//! Only lights in a vacuum are aimed: in a medium a subpath scatters anywhere along
//! its ray. SPPM's photons keep pbrt's sampling (its noise is pbrt's).

use crate::lights::{Emission, Light};
use crate::math::{Point3, Ray, Vector3};
use crate::render::RenderScene;
use glam::{DVec3, Vec3};
use std::f64::consts::TAU;

/// Directions from a light uniformly within a cone around `axis`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// The light's position, its apex.
    from: Vec3,
    axis: DVec3,
    /// A frame completing `axis`.
    across: [DVec3; 2],
    /// 1 − cos of the half angle, formed without cancellation for narrow cones.
    one_minus_cos: f64,
}

/// How much larger than the box's own the sphere around the shapes is taken to be,
/// relatively and absolutely, so that no direction that meets a shape falls outside
/// the cone: directions are rounded to f32 (an angle of up to ~2⁻²³), and traversal's
/// box test is widened by a few ulps.
const MARGIN: (f64, f64) = (1e-3, 1e-6);

/// The farthest a light is aimed from, in sphere radii: past it, rounding a direction
/// to f32 moves it across more than the margin. (Lights that far see the scene in
/// under 10⁻⁶ of their directions; they keep their own sampling.)
const MAX_DISTANCE: f64 = 1000.0;

impl Cone {
    /// The cone from `p` that holds the sphere (`center`, `radius`), if `p` is outside.
    pub fn toward(p: DVec3, center: DVec3, radius: f64) -> Option<Cone> {
        let to = center - p;
        let dist = to.length();
        if !(dist > radius && dist <= radius * MAX_DISTANCE) {
            return None;
        }
        let s2 = (radius / dist).powi(2);
        let axis = to / dist;
        let (a, b) = crate::math::frame::coordinate_system(axis.as_vec3());
        Some(Cone {
            from: p.as_vec3(),
            axis,
            across: [a.as_dvec3(), b.as_dvec3()],
            one_minus_cos: s2 / (1.0 + (1.0 - s2).sqrt()),
        })
    }

    /// Its solid angle.
    pub fn solid_angle(&self) -> f64 {
        TAU * self.one_minus_cos
    }

    /// A unit direction drawn uniformly within it.
    pub fn sample(&self, u: [f32; 2]) -> Vec3 {
        let x = u[0] as f64 * self.one_minus_cos;
        let (cos_t, sin_t) = (1.0 - x, (x * (2.0 - x)).max(0.0).sqrt());
        let (sin_p, cos_p) = (TAU * u[1] as f64).sin_cos();
        let d = self.axis * cos_t + (self.across[0] * cos_p + self.across[1] * sin_p) * sin_t;
        d.normalize().as_vec3()
    }

    /// The density [`Cone::sample`] has for the unit direction `d` (0 outside).
    pub fn density(&self, d: Vec3) -> f64 {
        match 1.0 - d.as_dvec3().normalize().dot(self.axis) <= self.one_minus_cos {
            true => 1.0 / self.solid_angle(),
            false => 0.0,
        }
    }
}

/// For each light of the scene, the cone its light subpaths are drawn in, where aiming
/// narrows its own sampling: a light with a position and no extent, in a vacuum,
/// outside the (slightly widened) sphere around the shapes.
pub fn cones(scene: &RenderScene) -> Vec<Option<Cone>> {
    let Some(b) = scene.geometry.bounds() else { return vec![None; scene.lights.len()] };
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let center = (lo + hi) * 0.5;
    let radius = (hi - center).length() * (1.0 + MARGIN.0) + MARGIN.1 * (1.0 + center.abs().max_element());
    (0..scene.lights.len())
        .map(|k| {
            let (p, own_density) = scene.lights[k].point_source()?;
            if scene.light_medium(k, Vec3::Z, Vec3::Z).is_some() {
                return None;
            }
            let cone = Cone::toward(p.as_dvec3(), center, radius)?;
            (1.0 / cone.solid_angle() > own_density as f64).then_some(cone)
        })
        .collect()
}

/// An aimed emission from `light`, as its `sample_le` reports one (its `le` zero where
/// the light sends nothing along the direction drawn).
pub fn emit(light: &Light, cone: &Cone, u: [f32; 2]) -> Emission {
    // DEVIATION(pbrt): always on, sampling only. pbrt's bdpt draws over the light's own
    // directions; the image's mean is the same (README, "Other differences").
    let d = cone.sample(u);
    let le = light.intensity(d);
    let ray = Ray::new(Point3(cone.from), Vector3(d));
    let pdf_dir = (1.0 / cone.solid_angle()) as f32;
    Emission { ray, n: d, pdf_pos: 1.0, pdf_dir, le, surface: None }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_stay_in_the_cone_and_fill_it_uniformly() {
        // A sphere of radius 1 seen from 3, 10 and 900 away.
        for dist in [3.0, 10.0, 900.0] {
            let p = DVec3::new(0.3, dist, -0.2);
            let c = Cone::toward(p, DVec3::ZERO, 1.0).unwrap();
            let exact = TAU * (1.0 - (1.0 - 1.0 / p.length_squared()).sqrt());
            assert!((c.solid_angle() / exact - 1.0).abs() < 1e-6, "{dist}: {} vs {exact}", c.solid_angle());
            let (mut near_axis, n) = (0, 4000);
            for k in 0..n {
                let u = [(k as f32 + 0.5) / n as f32, ((k * 7919) % n) as f32 / n as f32];
                let d = c.sample(u);
                assert!(c.density(d) > 0.0, "{dist}: {d:?} left the cone");
                // Every drawn ray passes the sphere: its closest approach to the centre
                // is within the radius (and f32's rounding of the direction).
                let miss = (-p).cross(d.as_dvec3()).length();
                assert!(miss <= 1.0 + dist * 1e-7, "{dist}: passes {miss} from the centre");
                // Uniform in solid angle: the inner half of the solid angle holds half.
                near_axis += (1.0 - d.as_dvec3().dot(c.axis) <= c.one_minus_cos / 2.0) as usize;
            }
            assert!((near_axis as f64 / n as f64 - 0.5).abs() < 0.02, "{dist}: {near_axis}");
            assert_eq!(c.density(-c.axis.as_vec3()), 0.0);
        }
        assert!(Cone::toward(DVec3::ZERO, DVec3::X * 0.5, 1.0).is_none(), "inside the sphere: no cone");
        assert!(Cone::toward(DVec3::Y * 2000.0, DVec3::ZERO, 1.0).is_none(), "too far: no cone");
    }
}
