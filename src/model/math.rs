//! The crate's 2-D, f64 geometry types, so no other module spells out nalgebra's generics.

/// A free vector in the road frame (m): x along the road, y to the left.
pub type Vector = nalgebra::Vector2<f64>;
/// A point in the road frame (m).
pub type Point = nalgebra::Point2<f64>;
/// A rigid pose: translation plus rotation.
pub type Isometry = nalgebra::Isometry2<f64>;

/// Wraps an angle into (−π, π].
pub fn wrap_angle(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let r = a.rem_euclid(two_pi);
    if r > std::f64::consts::PI {
        r - two_pi
    } else {
        r
    }
}
