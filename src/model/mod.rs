//! The plain road frame and what lives in it: vectors and boxes, kinematics, the road, a scene of
//! vehicles, trajectories. No SUMO, no planning: every layer above speaks these types.

pub mod braking;
pub mod geometry;
pub mod kinematics;
pub mod math;
pub mod reference_line;
pub mod road;
pub mod scene;
pub mod trajectory;
