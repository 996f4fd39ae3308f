//! The road frame of the merge section: where each of SUMO's edges lies in it (the mapping of
//! readings and commands between the two is `crate::sumo::frame`).
//!
//! Frame: `s` is the distance along the main road (m), equal to SUMO's x on the straight part;
//! lane 0 is the ramp / acceleration lane, lanes 1 and 2 the main road's right and left lanes.
//! On the ramp edge, `s` is measured backwards from the merge-zone start along the ramp, so route
//! distances stay exact even though the ramp is curved.

/// Edge names the merge network must provide, in the order of their codes.
pub const EDGES: [&str; 4] = ["main_in", "ramp", "acc", "main_out"];
/// Codes (indices in [`EDGES`]) of the four edges.
pub const MAIN_IN: usize = 0;
pub const RAMP: usize = 1;
pub const ACC: usize = 2;
pub const MAIN_OUT: usize = 3;

/// Road-frame lane of the ramp and of the acceleration lane.
pub const MERGE_LANE: i32 = 0;
/// Road-frame lanes of the main road, right then left.
pub const MAIN_LANES: [i32; 2] = [1, 2];
/// Within this distance (m) of the acceleration lane's end a ramp HDV that has come to a stop
/// forces its way into the main road (the episode's merge rule), so a CAV must expect it there.
pub const FORCED_MERGE_ZONE: f64 = 10.0;
/// Slower than this (m/s) a ramp HDV counts as standing, for the forced merge.
pub const STANDING_SPEED: f64 = 0.5;

/// Every road-frame lane, lowest (the merge lane) to highest (the main road's left lane).
pub const LANES: std::ops::RangeInclusive<i32> = MERGE_LANE..=MAIN_LANES[1];

/// The nearest road-frame lane to `lane` (e.g. a lane computed from a predicted position that
/// strayed off the road).
pub fn clamp_lane(lane: i32) -> i32 {
    lane.clamp(*LANES.start(), *LANES.end())
}

/// The road-frame lane whose centre line is nearest to lateral position `y` (lane `k`'s centre
/// lies at `k · lane_width`).
pub fn lane_at(y: f64, lane_width: f64) -> i32 {
    clamp_lane((y / lane_width).round() as i32)
}

/// The merge network as embedded in the binary (`sumo_net/merge.net.xml`).
pub const EMBEDDED_NET: &str = include_str!("../../sumo_net/merge.net.xml");

/// Why the network cannot serve as the merge scenario.
#[derive(Debug, thiserror::Error)]
pub enum RoadError {
    #[error("network lacks what the merge scenario needs: {0}")]
    Shape(String),
}

/// One SUMO edge placed in the road frame.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeFrame {
    pub name: &'static str,
    /// Frame `s` of the edge's start.
    pub s_start: f64,
    pub length: f64,
    /// Frame lane of the edge's lane 0.
    pub lane_offset: i32,
    pub lanes: i32,
}

/// The merge section in the road frame, read from the running network.
#[derive(Debug, Clone, PartialEq)]
pub struct Road {
    pub edges: [EdgeFrame; 4],
    pub lane_width: f64,
    /// Where the acceleration lane begins and ends (`s`).
    pub merge_start: f64,
    pub merge_end: f64,
    /// End of the section: vehicles arrive here.
    pub section_end: f64,
    /// Frame `s` where ramp vehicles enter.
    pub ramp_start: f64,
}

impl Road {
    /// The merge section from its four edges' (name, length, lane count) in [`EDGES`] order,
    /// checked against the merge layout.
    ///
    /// # Errors
    /// An edge with another lane count than the layout needs.
    pub fn from_edges(
        lane_width: f64,
        frames: [(&'static str, f64, i32); 4],
    ) -> Result<Road, RoadError> {
        for (code, &(name, _, lanes)) in frames.iter().enumerate() {
            let expected = match code {
                MAIN_IN | MAIN_OUT => 2,
                RAMP => 1,
                _ => 3,
            };
            if lanes != expected {
                return Err(RoadError::Shape(format!(
                    "edge '{name}' has {lanes} lanes, the merge layout needs {expected}"
                )));
            }
        }
        let len = |c: usize| frames[c].1;
        let merge_start = len(MAIN_IN);
        let merge_end = merge_start + len(ACC);
        let section_end = merge_end + len(MAIN_OUT);
        let ramp_start = merge_start - len(RAMP);
        let s_start = [0.0, ramp_start, merge_start, merge_end];
        let lane_offset = [1, 0, 0, 1];
        let edges = std::array::from_fn(|c| EdgeFrame {
            name: frames[c].0,
            s_start: s_start[c],
            length: frames[c].1,
            lane_offset: lane_offset[c],
            lanes: frames[c].2,
        });
        Ok(Road {
            edges,
            lane_width,
            merge_start,
            merge_end,
            section_end,
            ramp_start,
        })
    }

    /// Whether a vehicle on the merge lane with its front at `front` and going `speed` stands in
    /// the zone where the merge rule forces it in: the one definition the rule and the planner
    /// (which may not predict such a merge away) share.
    pub fn forces_merge(&self, front: f64, speed: f64) -> bool {
        speed < STANDING_SPEED && front > self.merge_end - FORCED_MERGE_ZONE
    }

    /// The lanes a vehicle at `s` may occupy: the merge lane exists only up to the merge end.
    pub fn lanes_at(&self, s: f64) -> std::ops::RangeInclusive<i32> {
        if s < self.merge_end {
            MERGE_LANE..=MAIN_LANES[1]
        } else {
            MAIN_LANES[0]..=MAIN_LANES[1]
        }
    }

    /// The default road (lengths of the shipped network), for unit tests and planning without SUMO.
    pub fn paper_default() -> Road {
        let mk = |name, s_start, length, lane_offset, lanes| EdgeFrame {
            name,
            s_start,
            length,
            lane_offset,
            lanes,
        };
        Road {
            edges: [
                mk("main_in", 0.0, 150.0, 1, 2),
                mk("ramp", 150.0 - 166.79, 166.79, 0, 1),
                mk("acc", 150.0, 180.0, 0, 3),
                mk("main_out", 330.0, 130.0, 1, 2),
            ],
            lane_width: 4.5,
            merge_start: 150.0,
            merge_end: 330.0,
            section_end: 460.0,
            ramp_start: 150.0 - 166.79,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_lane_ends_at_merge_end() {
        let r = Road::paper_default();
        assert!(r.lanes_at(200.0).contains(&0));
        assert!(!r.lanes_at(340.0).contains(&0));
    }
}
