//! Positions and displacements: x east, y north, z depth (positive down), metres.

/// A position or displacement in the local frame (x east, y north, z depth down), metres.
pub type Vec3 = nalgebra::Vector3<f64>;

/// Horizontal (x, y) distance between two points, ignoring depth.
pub fn horizontal_distance(a: &Vec3, b: &Vec3) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

/// `dx.hypot(dy)`, or None when one component alone is farther than `bound` (the hypotenuse
/// then is too: it is at least the larger component, which the rounded hypot keeps). Vehicles
/// ask "within this distance?" every step and are mostly far, so most asks skip the hypot.
pub fn hypot_within(dx: f64, dy: f64, bound: f64) -> Option<f64> {
    (dx.abs() <= bound && dy.abs() <= bound).then(|| dx.hypot(dy))
}

/// Bearing (math convention, radians) of `to` as seen from `from`, in the horizontal plane.
pub fn horizontal_bearing(from: &Vec3, to: &Vec3) -> f64 {
    (to.y - from.y).atan2(to.x - from.x)
}

/// An axis-aligned rectangle (x east, y north), metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub min: (f64, f64),
    pub max: (f64, f64),
}

impl Rect {
    /// The smallest rectangle holding every point (an empty one, min +∞ and max −∞, for none).
    pub fn around(points: impl IntoIterator<Item = (f64, f64)>) -> Rect {
        let empty = Rect { min: (f64::INFINITY, f64::INFINITY), max: (f64::NEG_INFINITY, f64::NEG_INFINITY) };
        points.into_iter().fold(empty, |r, (x, y)| Rect {
            min: (r.min.0.min(x), r.min.1.min(y)),
            max: (r.max.0.max(x), r.max.1.max(y)),
        })
    }

    /// The rectangle shrunk by `inset` on every side (never past its centre line).
    pub fn inset(self, inset: f64) -> Rect {
        let half_w = (self.max.0 - self.min.0) / 2.0;
        let half_h = (self.max.1 - self.min.1) / 2.0;
        let (dx, dy) = (inset.min(half_w), inset.min(half_h));
        Rect { min: (self.min.0 + dx, self.min.1 + dy), max: (self.max.0 - dx, self.max.1 - dy) }
    }

    /// The diagonal's length, m.
    pub fn diagonal(&self) -> f64 {
        (self.max.0 - self.min.0).hypot(self.max.1 - self.min.1)
    }
}

#[cfg(test)]
mod tests {
    use super::hypot_within;

    /// Whatever the bound, "within" answers as the hypot itself would, with `<` and with `<=`,
    /// including components exactly at the bound and hypotenuses a rounding away from it.
    #[test]
    fn hypot_within_answers_as_the_hypot_does() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for bound in [0.15_f64, 1.0, 5.0, 1e-3] {
            let edge = [(bound, 0.0), (0.0, -bound), (bound.next_up(), 0.0), (0.6 * bound, 0.8 * bound)];
            let random: Vec<(f64, f64)> =
                (0..100_000).map(|_| ((next() - 0.5) * 3.0 * bound, (next() - 0.5) * 3.0 * bound)).collect();
            for (dx, dy) in edge.into_iter().chain(random) {
                let d = dx.hypot(dy);
                assert_eq!(hypot_within(dx, dy, bound).is_some_and(|h| h < bound), d < bound, "{dx}, {dy}");
                assert_eq!(hypot_within(dx, dy, bound).is_some_and(|h| h <= bound), d <= bound, "{dx}, {dy}");
            }
        }
    }
}
