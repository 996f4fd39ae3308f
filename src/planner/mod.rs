//! Planning in the road frame: motion primitives on the kinematic bicycle model, the safety rule,
//! the single-CAV multi-phase A* (M-A*) and the priority-based search (PBS) that plans all CAVs
//! jointly. It knows nothing of SUMO or of the episode; it predicts HDVs through
//! [`crate::predict::Predictor`].

pub mod guard;
pub mod lane_changes;
pub mod lane_end;
pub mod mastar;
pub mod memo;
pub mod pbs;
pub mod primitives;
pub mod priority;
pub mod safety;
pub mod search;
