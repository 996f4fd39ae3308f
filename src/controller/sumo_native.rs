//! The `sumo` reference: CAVs driven by SUMO's own IDM and LC2013 with desired speed v_max.

use super::{CavHandling, Command, Controller};
use crate::model::scene::Scene;

/// Leaves CAVs to SUMO; issues no commands.
#[derive(Debug, Default, Clone, Copy)]
pub struct SumoNative;

impl Controller for SumoNative {
    fn name(&self) -> &'static str {
        "sumo"
    }

    fn handling(&self) -> CavHandling {
        CavHandling::Sumo
    }

    fn plan(&mut self, _scene: &Scene, _out: &mut Vec<Command>) {}
}
