//! Points, vectors and normals as newtypes over `glam::Vec3`, with only the operations
//! that make sense for each (point − point = vector; normals transform by the inverse
//! transpose, see [`super::Transform::normal`]).

use glam::Vec3;
use std::ops::{Add, Mul, Neg, Sub};

macro_rules! newtype {
    ($name:ident) => {
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        pub struct $name(pub Vec3);

        impl $name {
            pub const fn new(x: f32, y: f32, z: f32) -> $name {
                $name(Vec3::new(x, y, z))
            }
            pub fn to_array(self) -> [f32; 3] {
                self.0.to_array()
            }
        }
    };
}

newtype!(Point3);
newtype!(Vector3);
newtype!(Normal3);

impl Sub for Point3 {
    type Output = Vector3;
    fn sub(self, o: Point3) -> Vector3 {
        Vector3(self.0 - o.0)
    }
}

impl Add<Vector3> for Point3 {
    type Output = Point3;
    fn add(self, v: Vector3) -> Point3 {
        Point3(self.0 + v.0)
    }
}

impl Sub<Vector3> for Point3 {
    type Output = Point3;
    fn sub(self, v: Vector3) -> Point3 {
        Point3(self.0 - v.0)
    }
}

impl Point3 {
    pub fn distance(self, o: Point3) -> f32 {
        self.0.distance(o.0)
    }
}

impl Add for Vector3 {
    type Output = Vector3;
    fn add(self, o: Vector3) -> Vector3 {
        Vector3(self.0 + o.0)
    }
}

impl Sub for Vector3 {
    type Output = Vector3;
    fn sub(self, o: Vector3) -> Vector3 {
        Vector3(self.0 - o.0)
    }
}

impl Mul<f32> for Vector3 {
    type Output = Vector3;
    fn mul(self, s: f32) -> Vector3 {
        Vector3(self.0 * s)
    }
}

impl Neg for Vector3 {
    type Output = Vector3;
    fn neg(self) -> Vector3 {
        Vector3(-self.0)
    }
}

impl Vector3 {
    pub fn dot(self, o: Vector3) -> f32 {
        self.0.dot(o.0)
    }
    pub fn cross(self, o: Vector3) -> Vector3 {
        Vector3(self.0.cross(o.0))
    }
    pub fn length(self) -> f32 {
        self.0.length()
    }
    pub fn normalize(self) -> Vector3 {
        Vector3(self.0.normalize())
    }
}

impl Neg for Normal3 {
    type Output = Normal3;
    fn neg(self) -> Normal3 {
        Normal3(-self.0)
    }
}

impl Normal3 {
    pub fn dot(self, v: Vector3) -> f32 {
        self.0.dot(v.0)
    }
    pub fn normalize(self) -> Normal3 {
        Normal3(self.0.normalize())
    }
    /// The normal flipped, if needed, into the hemisphere of `v`.
    pub fn face_forward(self, v: Vector3) -> Normal3 {
        if self.dot(v) < 0.0 { -self } else { self }
    }
}

impl From<Normal3> for Vector3 {
    fn from(n: Normal3) -> Vector3 {
        Vector3(n.0)
    }
}

impl From<Vector3> for Normal3 {
    fn from(v: Vector3) -> Normal3 {
        Normal3(v.0)
    }
}
