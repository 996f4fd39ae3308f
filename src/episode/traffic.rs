//! Where an episode's traffic comes from: the paper's generated demand or a user's SUMO
//! scenario. It decides the parts of the episode's summary and of its per-vehicle rows, and so
//! their columns.

/// Where an episode's traffic comes from, which decides the parts of its summary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Traffic {
    /// The paper's generated demand (λ, α, the HDV profile) on the embedded merge or a
    /// `--net`: bkpbs inserts every vehicle and keeps the books of its schedule.
    Demand,
    /// A user's SUMO scenario (`--sumocfg`): SUMO inserts its routes' vehicles and measures
    /// their trips.
    Scenario,
}
