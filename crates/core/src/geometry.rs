//! Positions and displacements: x east, y north, z depth (positive down), metres.

/// A position or displacement in the local frame (x east, y north, z depth down), metres.
pub type Vec3 = nalgebra::Vector3<f64>;

/// Horizontal (x, y) distance between two points, ignoring depth.
pub fn horizontal_distance(a: &Vec3, b: &Vec3) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

/// Bearing (math convention, radians) of `to` as seen from `from`, in the horizontal plane.
pub fn horizontal_bearing(from: &Vec3, to: &Vec3) -> f64 {
    (to.y - from.y).atan2(to.x - from.x)
}
