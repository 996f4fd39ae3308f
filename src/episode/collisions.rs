//! The one collision book of both loops: the collisions SUMO reports after a step become events
//! (each vehicle's kind told, so that one with a CAV in it is controllable), and their vehicles
//! are taken out of SUMO at once, each once, when the episode removes crashed vehicles. Each loop
//! then marks its own records crashed ([`CollisionEvent::pairs`]).

use crate::episode::metrics::CollisionEvent;
use crate::model::scene::Kind;
use crate::sumo::{SumoClient, SumoError};

/// How a loop tells its vehicles apart and what it does with a crashed one.
pub trait Crashes {
    /// The kind of vehicle `id` (of SUMO type `type_id`), if it can be told.
    fn kind_of(&self, id: &str, type_id: &str) -> Option<Kind>;
    /// Whether vehicle `id` is to be taken out of SUMO now (a vehicle removed already is not
    /// asked again in the same step).
    fn removes(&self, id: &str) -> bool;
    /// Vehicle `id` was taken out of SUMO.
    fn removed(&mut self, id: &str);
}

/// The collisions SUMO reported after the step that began at `now`, as events; every vehicle
/// in one that `crashes` removes is taken out of SUMO, collider before victim, each once.
///
/// # Errors
/// SUMO failing to report or to remove.
pub fn take_collisions(
    sim: &mut impl SumoClient,
    now: f64,
    crashes: &mut impl Crashes,
) -> Result<Vec<CollisionEvent>, SumoError> {
    let collisions = sim.collisions()?;
    let mut removed: Vec<String> = Vec::new();
    let mut events = Vec::with_capacity(collisions.len());
    for c in collisions {
        for id in [&c.collider, &c.victim] {
            if !removed.contains(id) && crashes.removes(id) {
                sim.remove_vehicle(id)?;
                crashes.removed(id);
                removed.push(id.clone());
            }
        }
        events.push(CollisionEvent {
            time: now,
            collider_kind: crashes.kind_of(&c.collider, &c.collider_type),
            victim_kind: crashes.kind_of(&c.victim, &c.victim_type),
            collider: c.collider,
            victim: c.victim,
            lane: c.lane,
            position: c.position,
        });
    }
    Ok(events)
}

impl CollisionEvent {
    /// Each vehicle of the collision with the other one: (collider, victim), (victim,
    /// collider).
    pub fn pairs(&self) -> [(&str, &str); 2] {
        [
            (&self.collider, &self.victim),
            (&self.victim, &self.collider),
        ]
    }
}
