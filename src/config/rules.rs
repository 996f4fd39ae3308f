//! The rules a configuration must satisfy: a small engine (a [`Rule`] per number, a table of
//! rows per section) and the table of every section's checks.
//!
//! Apart from the settings types so that every bound and its error text is found in one place,
//! and settings alike are rejected alike; `Config::validate` runs the sections in order.

use crate::config::{
    ConfigError, Demand, Idm, Mobil, PbsSettings, PlannerSettings, PredictorSettings, RampMerge,
    Scenario, SumoSettings,
};

/// Highest arrival rate accepted (veh/h): the demand of an episode is drawn in full before it
/// starts, so the rate bounds its memory.
pub const MAX_RATE: f64 = 20_000.0;

/// Why counts and sizes are bounded: each bound keeps an episode's memory and time finite.
pub(super) const STEPS_RANGE: &str = "must be 1 to 100000 steps (longer episodes only fill memory)";
pub(super) const V_MAX_RANGE: &str =
    "must lie in [1, 100] m/s (the lane-change table grows with it)";
pub(super) const FREE_FLOW_ACCEL_RANGE: &str =
    "must lie in [0.1, 20] m/s² (the free-flow time t* grows without bound near 0)";
pub(super) const HORIZON_RANGE: &str =
    "must be 1 to 100 steps (the search grows exponentially with it)";
pub(super) const SEARCH_BUDGET_RANGE: &str = "must be 1 to 1000000 node expansions";
pub(super) const PBS_BUDGET_RANGE: &str = "must be 1 to 100000 priority-tree nodes";

/// What a number in the settings must satisfy. Each rule owns its error text, so settings alike
/// are rejected alike.
#[derive(Debug, Clone, Copy)]
pub(super) enum Rule {
    /// Within [low, high], both included: a bound that keeps memory and run time finite, or a
    /// value physics allows, which the reason names.
    Between(f64, f64, &'static str),
    /// Above zero; unlike [`Rule::Rate`], infinity passes.
    Positive,
    NonNegative,
    /// A share: [0, 1].
    UnitInterval,
    /// A probability strictly between 0 and 1.
    OpenUnitInterval,
    /// The step length: (0, 1] s.
    StepLength,
    /// An arrival rate: positive and at most [`MAX_RATE`].
    Rate,
    /// A time budget: 0 (off) or positive and finite.
    TimeBudget,
    /// At least another setting's value, which the reason names.
    AtLeast(f64, &'static str),
}

impl Rule {
    pub(super) fn holds(self, v: f64) -> bool {
        match self {
            Rule::Between(low, high, _) => (low..=high).contains(&v),
            Rule::Positive => v > 0.0,
            Rule::NonNegative => v >= 0.0,
            Rule::UnitInterval => (0.0..=1.0).contains(&v),
            Rule::OpenUnitInterval => v > 0.0 && v < 1.0,
            Rule::StepLength => v > 0.0 && v <= 1.0,
            Rule::Rate => v > 0.0 && v <= MAX_RATE,
            Rule::TimeBudget => v >= 0.0 && v.is_finite(),
            Rule::AtLeast(bound, _) => v >= bound,
        }
    }

    pub(super) fn reason(self) -> &'static str {
        match self {
            Rule::Between(_, _, reason) => reason,
            Rule::Positive => "must be positive",
            Rule::NonNegative => "must not be negative",
            Rule::UnitInterval => "must lie in [0, 1]",
            Rule::OpenUnitInterval => "must lie in (0, 1)",
            Rule::StepLength => "must lie in (0, 1] s",
            Rule::Rate => {
                "must be a positive rate of at most 20000 veh/h (two lanes carry about 4000; \
                 more only queues vehicles at the entry and fills memory)"
            }
            Rule::TimeBudget => "must be 0 (off) or a positive time in ms",
            Rule::AtLeast(_, reason) => reason,
        }
    }
}

/// A setting's value as a [`Rule`] reads it; a count stays an integer so that an error prints it
/// as it was written.
#[derive(Debug, Clone, Copy)]
enum Value {
    Real(f64),
    Count(u64),
}

impl Value {
    fn number(self) -> f64 {
        match self {
            Value::Real(v) => v,
            Value::Count(n) => n as f64,
        }
    }
}

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Real(v) => write!(f, "{v}"),
            Value::Count(n) => write!(f, "{n}"),
        }
    }
}

impl From<f64> for Value {
    fn from(v: f64) -> Self {
        Value::Real(v)
    }
}

impl From<u32> for Value {
    fn from(n: u32) -> Self {
        Value::Count(n.into())
    }
}

impl From<usize> for Value {
    fn from(n: usize) -> Self {
        Value::Count(n as u64)
    }
}

/// One rule of a section's table: the dotted field name, its value and what it must satisfy.
type Row = (&'static str, Value, Rule);

/// The [`Row`]s of one section, `section: value; field => rule, …`: each field is named once,
/// so an error cannot name another field than the one checked.
macro_rules! rows {
    ($section:ident: $settings:expr; $($field:ident => $rule:expr),+ $(,)?) => {
        [$((
            concat!(stringify!($section), ".", stringify!($field)),
            Value::from($settings.$field),
            $rule,
        )),+]
    };
}

/// Checks the rows in order and reports the first that fails.
fn check_rows(rows: &[Row]) -> Result<(), ConfigError> {
    for &(field, value, rule) in rows {
        check(field, value, rule.holds(value.number()), rule.reason())?;
    }
    Ok(())
}

/// The error for `field` unless `ok`.
fn check(
    field: &'static str,
    value: impl std::fmt::Display,
    ok: bool,
    reason: &'static str,
) -> Result<(), ConfigError> {
    if ok {
        Ok(())
    } else {
        Err(ConfigError::Invalid {
            field,
            value: value.to_string(),
            reason,
        })
    }
}

pub(super) fn check_scenario(s: &Scenario) -> Result<(), ConfigError> {
    use Rule::*;
    check_rows(&rows!(scenario: s;
        alpha => UnitInterval,
        lambda => Rate,
        steps => Between(1.0, f64::from(super::scenario::MAX_STEPS), STEPS_RANGE),
        dt => StepLength,
        v_max => Between(1.0, 100.0, V_MAX_RANGE),
        free_flow_accel => Between(0.1, 20.0, FREE_FLOW_ACCEL_RANGE),
        vehicle_length => Positive,
        vehicle_width => Positive,
        lane_change_duration => AtLeast(s.dt, "must be at least one step"),
    ))?;
    if let (None, Some(t)) = (&s.sumocfg, s.cav_types.first()) {
        return Err(ConfigError::Invalid {
            field: "scenario.cav_types",
            value: t.clone(),
            reason: "names vehicle types of a configuration of your own: set scenario.sumocfg \
                     (--sumocfg) too (the paper's demand draws its CAVs by α)",
        });
    }
    if let (Some(cfg), Some(_)) = (&s.sumocfg, &s.net_file) {
        return Err(ConfigError::Invalid {
            field: "scenario.sumocfg",
            value: cfg.display().to_string(),
            reason: "comes with its own net-file: leave scenario.net_file (--net) unset",
        });
    }
    Ok(())
}

/// The speed ranges are pairs bounded by the speed limit, so they have a rule of their own.
pub(super) fn check_demand(d: &Demand, v_max: f64) -> Result<(), ConfigError> {
    check_rows(
        &rows!(demand: d; ramp_share => Rule::UnitInterval, exit_share => Rule::UnitInterval),
    )?;
    let weights = &d.ramp_weights;
    if weights.iter().any(|w| !w.is_finite() || *w < 0.0)
        || (!weights.is_empty() && weights.iter().sum::<f64>() <= 0.0)
    {
        return Err(ConfigError::Invalid {
            field: "demand.ramp_weights",
            value: format!("{weights:?}"),
            reason: "weights must be finite, at least 0, and not all 0",
        });
    }
    for (field, r) in [
        ("demand.insertion_speed", d.insertion_speed),
        ("demand.hdv_desired_speed", d.hdv_desired_speed),
    ] {
        check(
            field,
            format!("{r:?}"),
            r[0] > 0.0 && r[0] <= r[1] && r[1] <= v_max,
            "must be [low, high] with 0 < low <= high <= v_max",
        )?;
    }
    Ok(())
}

pub(super) fn check_idm(i: &Idm) -> Result<(), ConfigError> {
    use Rule::*;
    check_rows(&rows!(idm: i;
        accel => Positive,
        decel => Positive,
        min_gap => NonNegative,
        time_headway => Positive,
        delta => Positive,
        max_decel => AtLeast(i.decel, "must be at least idm.decel"),
    ))
}

pub(super) fn check_mobil(m: &Mobil) -> Result<(), ConfigError> {
    use Rule::*;
    check_rows(&rows!(mobil: m;
        politeness => NonNegative,
        safe_braking => Positive,
        merge_safe_braking => Positive,
        merge_min_gap => NonNegative,
        decision_interval => NonNegative,
    ))
}

pub(super) fn check_pbs(p: &PbsSettings) -> Result<(), ConfigError> {
    check_rows(&rows!(pbs: p;
        node_budget => Rule::Between(1.0, 100_000.0, PBS_BUDGET_RANGE),
        time_budget_ms => Rule::TimeBudget,
    ))
}

pub(super) fn check_planner(p: &PlannerSettings) -> Result<(), ConfigError> {
    use Rule::*;
    check_rows(&rows!(planner: p;
        horizon => Between(1.0, 100.0, HORIZON_RANGE),
        phase1_budget => Between(1.0, 1e6, SEARCH_BUDGET_RANGE),
        phase2_budget => Between(1.0, 1e6, SEARCH_BUDGET_RANGE),
        goal_distance => Positive,
        fallback_goal_distance => Positive,
    ))?;
    if let Some(accel) = p.accel {
        check(
            "planner.accel",
            accel,
            Positive.holds(accel),
            Positive.reason(),
        )?;
    }
    check_rows(&rows!(planner: p;
        decel => Positive,
        emergency_decel => Positive,
        s_bin => Positive,
        v_bin => Positive,
        phase1_lane_change_penalty => NonNegative,
        phase2_lane_change_penalty => NonNegative,
        lane_change_deferral_penalty => NonNegative,
        min_lane_change_speed => NonNegative,
        margin_long => NonNegative,
        margin_lat => NonNegative,
        safe_gap => NonNegative,
        reaction_time => NonNegative,
    ))
}

pub(super) fn check_ramp_merge(r: &RampMerge) -> Result<(), ConfigError> {
    check_rows(&rows!(ramp_merge: r; exponent => Rule::Positive))
}

/// Model files are checked with the other settings so that a missing one is reported before
/// any episode starts.
pub(super) fn check_predictor(p: &PredictorSettings) -> Result<(), ConfigError> {
    check_rows(&rows!(predictor: p; decision_probability => Rule::OpenUnitInterval))?;
    for (field, path) in [
        ("predictor.conditioned_model", &p.conditioned_model),
        ("predictor.unconditioned_model", &p.unconditioned_model),
    ] {
        if let Some(path) = path {
            check(field, path.display(), path.is_file(), "no such model file")?;
        }
    }
    Ok(())
}

/// sumo-gui's pause per step: from none to ten seconds; the stall bound: from a tenth of a
/// second to a day.
pub(super) fn check_sumo(s: &SumoSettings) -> Result<(), ConfigError> {
    match (s.gui_delay_ms, s.stall_timeout_s) {
        (Some(d), _) if !(0.0..=10_000.0).contains(&d) => Err(ConfigError::Invalid {
            field: "sumo.gui_delay_ms",
            value: d.to_string(),
            reason: "must lie in [0, 10000] ms",
        }),
        (_, Some(t)) if !(0.1..=86_400.0).contains(&t) => Err(ConfigError::Invalid {
            field: "sumo.stall_timeout_s",
            value: t.to_string(),
            reason: "must lie in [0.1, 86400] s",
        }),
        _ => Ok(()),
    }
}
