//! Rays: origin, direction (not necessarily normalised) and the parametric limit.

use super::vector::{Point3, Vector3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Point3,
    pub d: Vector3,
    pub t_max: f32,
}

impl Ray {
    pub fn new(o: Point3, d: Vector3) -> Ray {
        Ray { o, d, t_max: f32::INFINITY }
    }
    pub fn at(&self, t: f32) -> Point3 {
        self.o + self.d * t
    }
}
