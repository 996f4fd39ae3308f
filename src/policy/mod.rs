//! The RL-PPO baseline's policy (paper, "Planning Algorithms"): what a CAV observes, which
//! motion primitives it may pick, the actor–critic networks and their file. Training is in
//! `crate::train::ppo`; the controller that applies the policy to every CAV is
//! `crate::controller::rl_ppo`.

pub mod actions;
pub mod mlp;
pub mod model_file;
pub mod network;
pub mod observation;
