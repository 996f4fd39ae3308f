//! Colours of the CAVs in sumo-gui (`sumo.gui`): what each CAV is doing, at a glance.

use std::collections::HashMap;
use std::sync::Arc;

use crate::controller::{Command, Source};
use crate::model::scene::Scene;
use crate::sumo::{SumoClient, SumoError};

/// Keeping its lane on its plan: the CAV type's own green.
pub const CRUISING: [u8; 3] = [0, 200, 0];
/// Changing lanes (starting or under way).
pub const CHANGING_LANES: [u8; 3] = [255, 150, 0];
/// The safety shield replaced the plan, or there was none (braking).
pub const SHIELDED: [u8; 3] = [230, 0, 0];

/// The colour a command shows.
pub fn colour_of(c: &Command) -> [u8; 3] {
    match (c.source, c.maneuver.lane_change) {
        (Source::Shield | Source::Brake, _) => SHIELDED,
        (Source::Continuation, _) | (_, Some(_)) => CHANGING_LANES,
        _ => CRUISING,
    }
}

/// The colour last sent per CAV, so that only changes cross to sumo-gui.
#[derive(Default)]
pub struct GuiColours {
    shown: HashMap<Arc<str>, [u8; 3]>,
}

impl GuiColours {
    /// Colours the commanded CAVs whose state changed.
    pub fn update(
        &mut self,
        sim: &mut impl SumoClient,
        scene: &Scene,
        commands: &[Command],
    ) -> Result<(), SumoError> {
        for c in commands {
            let id = &scene.vehicles[c.vehicle].id;
            let colour = colour_of(c);
            if self.shown.get(id) != Some(&colour) {
                sim.set_color(id, colour)?;
                self.shown.insert(id.clone(), colour);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::{LaneChange, Maneuver};

    #[test]
    fn the_shield_shows_red_and_lane_changes_orange() {
        let cmd = |source, lane_change| Command {
            vehicle: 0,
            maneuver: Maneuver {
                speed: 20.0,
                lane_change,
            },
            source,
        };
        assert_eq!(colour_of(&cmd(Source::PbsSolution, None)), CRUISING);
        assert_eq!(
            colour_of(&cmd(Source::PbsSolution, Some(LaneChange::Left))),
            CHANGING_LANES
        );
        assert_eq!(colour_of(&cmd(Source::Continuation, None)), CHANGING_LANES);
        assert_eq!(
            colour_of(&cmd(Source::Shield, Some(LaneChange::Left))),
            SHIELDED
        );
    }
}
