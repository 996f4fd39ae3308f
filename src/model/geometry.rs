//! Oriented bounding boxes and their overlap test (separating axes), with a bounding-circle
//! pre-check that rejects most far-apart pairs with one distance comparison.

use crate::model::math::{Point, Vector};

/// A rectangle of half-extents `half` (along, across its heading) centred at `centre`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrientedBox {
    /// Centre of the rectangle (road frame, m).
    pub centre: Point,
    /// Direction of the rectangle's long axis (rad, 0 = along the road, positive to the left).
    pub heading: f64,
    /// Half-length along the heading and half-width across it (m).
    pub half: Vector,
}

impl OrientedBox {
    /// A vehicle's box: `length` × `width`, centred on its position.
    pub fn vehicle(centre: Point, heading: f64, length: f64, width: f64) -> Self {
        OrientedBox {
            centre,
            heading,
            half: Vector::new(0.5 * length, 0.5 * width),
        }
    }

    /// Radius of the circle around the centre that contains the box.
    pub fn bounding_radius(&self) -> f64 {
        self.half.norm()
    }

    fn axes(&self) -> [Vector; 2] {
        let (s, c) = self.heading.sin_cos();
        [Vector::new(c, s), Vector::new(-s, c)]
    }
}

/// Whether the bounding circles of `a` and `b` intersect (necessary for the boxes to).
pub fn intersection_test_circle_circle(a: &OrientedBox, b: &OrientedBox) -> bool {
    let r = a.bounding_radius() + b.bounding_radius();
    (a.centre - b.centre).norm_squared() <= r * r
}

/// Exact overlap test of two oriented boxes (touching counts as overlap).
///
/// Planning asks this for every pair of nearby vehicles at every step, so the usual answers
/// come cheaply and exactly: far apart along either axis (farther than the half-extents summed,
/// which bound the bounding circles) is no overlap without a square root, and two boxes both
/// heading along the road (heading exactly 0, most of them) are compared as axis-aligned
/// rectangles, which is what the separating-axis test computes for them, bit for bit. Inlined:
/// called with boxes just built on the stack, the call cost more than the usual answer.
#[inline(always)]
pub fn intersection_test_obb_obb(a: &OrientedBox, b: &OrientedBox) -> bool {
    let d = b.centre - a.centre;
    let reach = a.half.x + a.half.y + b.half.x + b.half.y;
    if d.x.abs() > reach || d.y.abs() > reach {
        return false;
    }
    if !intersection_test_circle_circle(a, b) {
        return false;
    }
    if a.heading == 0.0 && b.heading == 0.0 {
        return d.x.abs() <= a.half.x + b.half.x && d.y.abs() <= a.half.y + b.half.y;
    }
    let (aa, ba) = (a.axes(), b.axes());
    for axis in aa.iter().chain(ba.iter()) {
        let ra = a.half.x * aa[0].dot(axis).abs() + a.half.y * aa[1].dot(axis).abs();
        let rb = b.half.x * ba[0].dot(axis).abs() + b.half.y * ba[1].dot(axis).abs();
        if d.dot(axis).abs() > ra + rb {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_4;

    fn car(x: f64, y: f64, heading: f64) -> OrientedBox {
        OrientedBox::vehicle(Point::new(x, y), heading, 5.0, 2.0)
    }

    #[test]
    fn axis_aligned_overlap_and_near_miss() {
        assert!(intersection_test_obb_obb(
            &car(0.0, 0.0, 0.0),
            &car(4.9, 0.0, 0.0)
        ));
        assert!(!intersection_test_obb_obb(
            &car(0.0, 0.0, 0.0),
            &car(5.01, 0.0, 0.0)
        ));
        // Side by side in adjacent lanes 4.5 m apart: no overlap; 1.99 m apart: overlap.
        assert!(!intersection_test_obb_obb(
            &car(0.0, 0.0, 0.0),
            &car(0.0, 4.5, 0.0)
        ));
        assert!(intersection_test_obb_obb(
            &car(0.0, 0.0, 0.0),
            &car(1.0, 1.99, 0.0)
        ));
        assert!(!intersection_test_obb_obb(
            &car(0.0, 0.0, 0.0),
            &car(1.0, 2.01, 0.0)
        ));
    }

    #[test]
    fn rotated_boxes() {
        // A box turned 45°: its rearmost corner lies (2.5 + 1)/√2 = 2.4749 behind its centre
        // and (2.5 − 1)/√2 = 1.0607 below it; lifted by that much, the corner points at `a`'s
        // front edge.
        let reach = (2.5 + 1.0) / 2f64.sqrt();
        let lift = (2.5 - 1.0) / 2f64.sqrt();
        let a = car(0.0, 0.0, 0.0);
        assert!(intersection_test_obb_obb(
            &a,
            &car(2.5 + reach - 0.01, lift, FRAC_PI_4)
        ));
        assert!(!intersection_test_obb_obb(
            &a,
            &car(2.5 + reach + 0.01, lift, FRAC_PI_4)
        ));
        // Bounding circles overlap but the boxes do not: the separating axis is a rotated one.
        let b = car(4.0, 3.2, FRAC_PI_4);
        assert!(intersection_test_circle_circle(&a, &b));
        assert!(!intersection_test_obb_obb(&a, &b));
        // Crossing at right angles through each other's middle.
        assert!(intersection_test_obb_obb(
            &a,
            &car(0.0, 0.0, std::f64::consts::FRAC_PI_2)
        ));
    }

    #[test]
    fn symmetric() {
        let (a, b) = (car(0.0, 0.0, 0.3), car(3.0, 1.5, -0.7));
        assert_eq!(
            intersection_test_obb_obb(&a, &b),
            intersection_test_obb_obb(&b, &a)
        );
    }
}
