//! Rays: origin, direction (not necessarily normalised), the parametric limit and the
//! time (within the camera's shutter; it places moving shapes).

use super::vector::{Point3, Vector3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Point3,
    pub d: Vector3,
    pub t_max: f32,
    pub time: f32,
}

impl Ray {
    /// A ray at time 0 (see [`Ray::at_time`]).
    pub fn new(o: Point3, d: Vector3) -> Ray {
        Ray { o, d, t_max: f32::INFINITY, time: 0.0 }
    }

    /// The same ray at `time`.
    pub fn at_time(self, time: f32) -> Ray {
        Ray { time, ..self }
    }

    pub fn at(&self, t: f32) -> Point3 {
        self.o + self.d * t
    }
}

/// The rays through the next pixel over in x and in y, for a camera ray: how its
/// footprint grows (pbrt's `RayDifferential`, scaled as pbrt's SPPM scales it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayDifferential {
    pub rx: Ray,
    pub ry: Ray,
}

impl RayDifferential {
    /// Offsets scaled by `s` about the main ray (pbrt's `ScaleDifferentials`).
    pub fn scaled(&self, main: &Ray, s: f32) -> RayDifferential {
        let scale = |r: &Ray| Ray {
            o: Point3(main.o.0 + (r.o.0 - main.o.0) * s),
            d: Vector3(main.d.0 + (r.d.0 - main.d.0) * s),
            t_max: r.t_max,
            time: r.time,
        };
        RayDifferential { rx: scale(&self.rx), ry: scale(&self.ry) }
    }
}
