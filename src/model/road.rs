//! The road frame of the merge section and its mapping to SUMO's edges and lanes.
//!
//! Frame: `s` is the distance along the main road (m), equal to SUMO's x on the straight part;
//! lane 0 is the ramp / acceleration lane, lanes 1 and 2 the main road's right and left lanes.
//! On the ramp edge, `s` is measured backwards from the merge-zone start along the ramp, so route
//! distances stay exact even though the ramp is curved.

use crate::sumo::{Simulation, SumoError};

/// Edge names the merge network must provide, in the order of their codes.
pub const EDGES: [&str; 4] = ["main_in", "ramp", "acc", "main_out"];
const MAIN_IN: usize = 0;
const RAMP: usize = 1;
const ACC: usize = 2;
const MAIN_OUT: usize = 3;

/// Road-frame lane of the ramp and of the acceleration lane.
pub const MERGE_LANE: i32 = 0;
/// Road-frame lanes of the main road, right then left.
pub const MAIN_LANES: [i32; 2] = [1, 2];

/// The merge network as embedded in the binary (`sumo_net/merge.net.xml`).
pub const EMBEDDED_NET: &str = include_str!("../../sumo_net/merge.net.xml");

/// Why the network cannot serve as the merge scenario.
#[derive(Debug, thiserror::Error)]
pub enum RoadError {
    #[error("network lacks what the merge scenario needs: {0}")]
    Shape(String),
    #[error(transparent)]
    Sumo(#[from] SumoError),
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
    /// Reads edge lengths and lane counts from SUMO and checks the merge layout.
    pub fn from_simulation(sim: &Simulation) -> Result<Road, RoadError> {
        let known = sim.edge_ids()?;
        for e in EDGES {
            if !known.iter().any(|k| k == e) {
                return Err(RoadError::Shape(format!("edge '{e}' is missing")));
            }
        }
        let mut frames = Vec::with_capacity(4);
        let mut width = None;
        for (code, name) in EDGES.iter().enumerate() {
            let lanes = sim.edge_lane_count(name)? as i32;
            let lane0 = format!("{name}_0");
            let length = sim.lane_length(&lane0)?;
            let w = sim.lane_width(&lane0)?;
            width.get_or_insert(w);
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
            frames.push((name, length, lanes));
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
            lane_width: width.unwrap_or(4.5),
            merge_start,
            merge_end,
            section_end,
            ramp_start,
        })
    }

    /// Frame `s` and lane of a SUMO (edge code, lane index, lane position); `None` off the section.
    pub fn to_frame(
        &self,
        edge_code: i32,
        lane_index: i32,
        lane_position: f64,
    ) -> Option<(f64, i32)> {
        let e = self.edges.get(usize::try_from(edge_code).ok()?)?;
        Some((e.s_start + lane_position, e.lane_offset + lane_index))
    }

    /// SUMO lane index on edge `edge_code` of frame lane `lane`, if that edge has it.
    pub fn sumo_lane_index(&self, edge_code: i32, lane: i32) -> Option<i32> {
        let e = self.edges.get(usize::try_from(edge_code).ok()?)?;
        let idx = lane - e.lane_offset;
        (0..e.lanes).contains(&idx).then_some(idx)
    }

    /// Whether an `s` lies on the ramp edge, before the merge zone.
    pub fn is_on_ramp(&self, edge_code: i32) -> bool {
        edge_code == RAMP as i32
    }

    /// Whether the vehicle is on the acceleration lane (frame lane 0 within the merge zone).
    pub fn is_on_acceleration_lane(&self, edge_code: i32, lane_index: i32) -> bool {
        edge_code == ACC as i32 && lane_index == 0
    }

    /// The edge codes SUMO is told to report (`Simulation::set_edge_codes`).
    pub fn edge_names() -> [&'static str; 4] {
        EDGES
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
    fn frame_mapping_round_trips() {
        let r = Road::paper_default();
        // main_in lane 1 (left) at 10 m -> frame lane 2, s = 10.
        assert_eq!(r.to_frame(0, 1, 10.0), Some((10.0, 2)));
        // acc lane 0 (acceleration lane) -> frame lane 0, s = 150 + pos.
        assert_eq!(r.to_frame(2, 0, 20.0), Some((170.0, 0)));
        assert_eq!(r.to_frame(3, 0, 5.0), Some((335.0, 1)));
        assert_eq!(r.to_frame(-1, 0, 5.0), None);
        assert_eq!(r.sumo_lane_index(2, 1), Some(1));
        assert_eq!(r.sumo_lane_index(0, 1), Some(0));
        assert_eq!(r.sumo_lane_index(0, 0), None);
        assert_eq!(r.sumo_lane_index(3, 3), None);
    }

    #[test]
    fn merge_lane_ends_at_merge_end() {
        let r = Road::paper_default();
        assert!(r.lanes_at(200.0).contains(&0));
        assert!(!r.lanes_at(340.0).contains(&0));
    }
}
