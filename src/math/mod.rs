//! Geometry math: error-bounded floats, points/vectors/normals, transforms with error
//! propagation, bounds with pbrt's conservative slab test, rays and frames.

pub mod animated;
pub mod bounded;
pub mod bounds;
pub mod catmull_rom;
pub mod equal_area;
pub mod float;
pub mod frame;
pub mod ray;
pub mod transform;
pub mod vector;

pub use bounds::Bounds3;
pub use float::{EFloat, EFloat64, gamma};
pub use ray::Ray;
pub use transform::Transform;
pub use vector::{Normal3, Point3, Vector3};
