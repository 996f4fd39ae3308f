//! A curvilinear frame: `s`, the arc length along a reference line (a polyline, e.g. the centre
//! line of the main carriageway's leftmost lane read from SUMO's lane shapes), and `d`, the
//! signed lateral offset from it (positive to the left). Both directions of the mapping live
//! here, so that a pose read from SUMO and a pose sent back agree.
//!
//! The heading of a polyline jumps at its vertices; SUMO's lane shapes place vertices densely
//! on curves, so the jump is small, and [`ReferenceLine::curvature_at`] smooths it over the
//! neighbouring segments for a bicycle that must follow the lane.

use super::math::{wrap_angle, Point};

/// A polyline with its cumulative arc length.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceLine {
    points: Vec<Point>,
    /// Arc length at each point.
    s: Vec<f64>,
}

/// Points closer than this are merged (m).
const MERGE_TOLERANCE: f64 = 1e-3;

impl ReferenceLine {
    /// The line through `points` in order; `None` with fewer than two distinct points.
    pub fn new(points: impl IntoIterator<Item = Point>) -> Option<ReferenceLine> {
        let mut pts: Vec<Point> = Vec::new();
        for p in points {
            if pts.last().is_none_or(|q| (p - q).norm() > MERGE_TOLERANCE) {
                pts.push(p);
            }
        }
        if pts.len() < 2 {
            return None;
        }
        let mut s = vec![0.0];
        for w in pts.windows(2) {
            s.push(s.last().expect("non-empty") + (w[1] - w[0]).norm());
        }
        Some(ReferenceLine { points: pts, s })
    }

    /// Total arc length (m).
    pub fn length(&self) -> f64 {
        *self.s.last().expect("two points at least")
    }

    /// The segment holding arc length `s` (the first or last beyond the ends).
    fn segment_at(&self, s: f64) -> usize {
        match self.s.binary_search_by(|x| x.total_cmp(&s)) {
            Ok(k) | Err(k) => k.saturating_sub(1).min(self.points.len() - 2),
        }
    }

    /// Unit direction of segment `k`.
    fn direction(&self, k: usize) -> nalgebra::Vector2<f64> {
        (self.points[k + 1] - self.points[k]).normalize()
    }

    /// Whether the line runs due east (SUMO's x) throughout: then `s` is x shifted and every
    /// heading 0.
    pub fn is_straight_east(&self) -> bool {
        self.points
            .windows(2)
            .all(|w| w[1].y == w[0].y && w[1].x > w[0].x)
    }

    /// The point at arc length `s` and the line's heading there (rad); beyond the ends the
    /// first and last segments are extended.
    pub fn pose_at(&self, s: f64) -> (Point, f64) {
        let k = self.segment_at(s);
        let u = self.direction(k);
        (self.points[k] + u * (s - self.s[k]), u.y.atan2(u.x))
    }

    /// The point at arc length `s` and lateral offset `d` (positive to the left).
    pub fn to_xy(&self, s: f64, d: f64) -> Point {
        let k = self.segment_at(s);
        let u = self.direction(k);
        let left = nalgebra::Vector2::new(-u.y, u.x);
        self.points[k] + u * (s - self.s[k]) + left * d
    }

    /// (s, d) of `p`: its projection on the nearest segment (the ends extended).
    pub fn to_frame(&self, p: Point) -> (f64, f64) {
        let last = self.points.len() - 2;
        let mut best = (f64::INFINITY, 0.0, 0.0);
        for k in 0..=last {
            let a = self.points[k];
            let seg = self.points[k + 1] - a;
            let len = seg.norm();
            let u = seg / len;
            let mut t = (p - a).dot(&u);
            if k > 0 {
                t = t.max(0.0);
            }
            if k < last {
                t = t.min(len);
            }
            let foot = a + u * t;
            let dist = (p - foot).norm();
            if dist < best.0 - 1e-9 {
                let d = u.x * (p.y - a.y) - u.y * (p.x - a.x);
                best = (dist, self.s[k] + t, d);
            }
        }
        (best.1, best.2)
    }

    /// Curvature at arc length `s` (1/m, positive turning left): the heading change between the
    /// segments before and after the nearest vertex, over the distance between their middles.
    pub fn curvature_at(&self, s: f64) -> f64 {
        let k = self.segment_at(s);
        let (before, after) = if k == 0 { (0, 1) } else { (k - 1, k) };
        if after > self.points.len() - 2 {
            return 0.0;
        }
        let h = |j: usize| {
            let u = self.direction(j);
            u.y.atan2(u.x)
        };
        let mid = |j: usize| 0.5 * (self.s[j] + self.s[j + 1]);
        let ds = mid(after) - mid(before);
        if ds <= 0.0 {
            return 0.0;
        }
        wrap_angle(h(after) - h(before)) / ds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_line_is_the_identity_shifted() {
        let l = ReferenceLine::new([
            Point::new(0.0, -2.25),
            Point::new(150.0, -2.25),
            Point::new(460.0, -2.25),
        ])
        .unwrap();
        assert_eq!(l.length(), 460.0);
        let (s, d) = l.to_frame(Point::new(123.4, -6.75));
        assert!(
            (s - 123.4).abs() < 1e-9 && (d + 4.5).abs() < 1e-9,
            "{s} {d}"
        );
        let p = l.to_xy(200.0, 4.5);
        assert!((p - Point::new(200.0, 2.25)).norm() < 1e-9);
        // Beyond the ends: extended.
        assert!((l.to_frame(Point::new(-10.0, -2.25)).0 + 10.0).abs() < 1e-9);
        assert_eq!(l.curvature_at(100.0), 0.0);
    }

    /// A quarter circle of radius 500 m drawn with 1 m chords: frame and back agree within
    /// 1 cm, and the curvature is 1/500.
    #[test]
    fn round_trip_on_a_curve() {
        let r = 500.0;
        let n = (r * std::f64::consts::FRAC_PI_2).ceil() as usize;
        let pts = (0..=n).map(|k| {
            let a = k as f64 / n as f64 * std::f64::consts::FRAC_PI_2;
            Point::new(r * a.sin(), r - r * a.cos())
        });
        let l = ReferenceLine::new(pts).unwrap();
        assert!((l.length() - r * std::f64::consts::FRAC_PI_2).abs() < 0.01);
        for &(s, d) in &[(10.0, 0.0), (300.0, -7.2), (700.0, 3.6)] {
            let (s2, d2) = l.to_frame(l.to_xy(s, d));
            assert!(
                (s2 - s).abs() < 0.01 && (d2 - d).abs() < 0.01,
                "{s},{d} → {s2},{d2}"
            );
        }
        assert!(
            (l.curvature_at(400.0) - 1.0 / r).abs() < 1e-4,
            "{}",
            l.curvature_at(400.0)
        );
        let (_, heading) = l.pose_at(l.length() - 0.5);
        assert!(
            (heading - std::f64::consts::FRAC_PI_2).abs() < 0.01,
            "{heading}"
        );
    }

    #[test]
    fn degenerate_lines_are_refused() {
        assert!(ReferenceLine::new([Point::new(1.0, 1.0), Point::new(1.0, 1.0)]).is_none());
        assert!(ReferenceLine::new([]).is_none());
    }
}
