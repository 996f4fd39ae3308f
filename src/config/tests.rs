//! Tests of the settings: defaults, TOML reading and writing, and every validation rule with
//! its exact error text.

use std::path::Path;

use crate::config::rules::{
    Rule, FREE_FLOW_ACCEL_RANGE, HORIZON_RANGE, MAX_RATE, PBS_BUDGET_RANGE, SEARCH_BUDGET_RANGE,
    STEPS_RANGE, V_MAX_RANGE,
};
use crate::config::*;

#[test]
fn defaults_are_the_papers() {
    let c = Config::default();
    assert_eq!(c.scenario.steps, 400);
    assert_eq!(c.scenario.dt, 0.2);
    assert_eq!(c.scenario.v_max, 35.0);
    assert_eq!(c.scenario.vehicle_length, 5.0);
    assert_eq!(c.demand.insertion_speed, [25.0, 35.0]);
    c.validate().unwrap();
}

#[test]
fn toml_round_trips() {
    let c = Config::default();
    let back: Config = toml::from_str(&c.to_toml()).unwrap();
    assert_eq!(back, c);
}

#[test]
fn partial_file_keeps_defaults() {
    let c: Config = toml::from_str("[scenario]\nalpha = 0.8\n").unwrap();
    assert_eq!(c.scenario.alpha, 0.8);
    assert_eq!(c.scenario.lambda, 3000.0);
}

/// `[planner] accel` unset means each CAV's own acceleration (the paper's 2 m/s² where it has
/// none of its own); written, it is kept and round-trips.
#[test]
fn planner_accel_is_unset_unless_written() {
    assert_eq!(Config::default().planner.accel, None);
    assert_eq!(Config::default().planner.accel_or_paper(), PAPER_ACCEL);
    let c: Config = toml::from_str("[planner]\naccel = 2.6\n").unwrap();
    assert_eq!(c.planner.accel, Some(2.6));
    assert_eq!(c.planner.accel_or_paper(), 2.6);
    let back: Config = toml::from_str(&c.to_toml()).unwrap();
    assert_eq!(back, c);
}

/// `[planner] gap_seeking` and `courtesy` and `[mobil] type_following` and `cooperative` are
/// unset by default and then not written, so the settings of campaigns from before them still
/// match: on a scenario of the user's own ramp CAVs seek gaps, main-road CAVs are courteous and
/// IDM+MOBIL's CAVs follow with their type's parameters and cooperate, on the paper's demand
/// none. Set either way, each holds everywhere, is written and round-trips.
#[test]
fn merge_behaviours_unset_are_on_for_a_scenario_only() {
    let unset = Config::default();
    assert!(unset.planner.gap_seeking.is_none() && unset.planner.courtesy.is_none());
    assert!(unset.mobil.type_following.is_none() && unset.mobil.cooperative.is_none());
    for key in ["gap_seeking", "courtesy", "type_following", "cooperative"] {
        assert!(!unset.to_toml().contains(key), "{key}");
    }
    assert!(unset.planner.seeks_gaps(true) && !unset.planner.seeks_gaps(false));
    assert!(unset.planner.is_courteous(true) && !unset.planner.is_courteous(false));
    assert!(unset.mobil.follows_type(true) && !unset.mobil.follows_type(false));
    for (text, on) in [("true", true), ("false", false)] {
        for key in ["gap_seeking", "courtesy", "type_following"] {
            let section = if key == "type_following" {
                "mobil"
            } else {
                "planner"
            };
            let c: Config = toml::from_str(&format!("[{section}]\n{key} = {text}\n")).unwrap();
            let p = &c.planner;
            let (own, paper) = match key {
                "courtesy" => (p.is_courteous(true), p.is_courteous(false)),
                "type_following" => (c.mobil.follows_type(true), c.mobil.follows_type(false)),
                "cooperative" => (c.mobil.cooperates(true), c.mobil.cooperates(false)),
                _ => (p.seeks_gaps(true), p.seeks_gaps(false)),
            };
            assert!(own == on && paper == on, "{key} = {text}");
            assert!(c.to_toml().contains(&format!("{key} = {text}")));
            let back: Config = toml::from_str(&c.to_toml()).unwrap();
            assert_eq!(back, c);
        }
    }
}

#[test]
fn the_shield_is_on_by_default_and_can_be_switched_off() {
    assert!(Config::default().safety.shield);
    let c: Config = toml::from_str("[safety]\nshield = false\n").unwrap();
    assert!(!c.safety.shield);
    assert!(toml::from_str::<Config>("[safety]\nsheild = false\n").is_err());
}

#[test]
fn independent_groups_is_a_flag_or_auto() {
    let read = |v: &str| {
        toml::from_str::<Config>(&format!("[pbs]\nindependent_groups = {v}\n"))
            .map(|c| c.pbs.independent_groups)
    };
    assert_eq!(Config::default().pbs.independent_groups, Grouping::Auto);
    assert_eq!(read("true").unwrap(), Grouping::Always);
    assert_eq!(read("false").unwrap(), Grouping::Never);
    assert_eq!(read("\"auto\"").unwrap(), Grouping::Auto);
    let err = read("\"sometimes\"").unwrap_err().to_string();
    assert!(err.contains("expected true, false or \"auto\""), "{err}");
    // Written only when not the default, as `true` / `false`.
    assert!(!Config::default().to_toml().contains("independent_groups"));
    let mut c = Config::default();
    c.pbs.independent_groups = Grouping::Always;
    assert!(c.to_toml().contains("independent_groups = true"));
    // Auto decomposes large rounds only.
    assert!(!Grouping::Auto.applies(AUTO_GROUPING_ABOVE));
    assert!(Grouping::Auto.applies(AUTO_GROUPING_ABOVE + 1));
    assert!(Grouping::Always.applies(1) && !Grouping::Never.applies(1000));
}

#[test]
fn unknown_field_is_rejected() {
    assert!(toml::from_str::<Config>("[scenario]\nalhpa = 0.8\n").is_err());
}

#[test]
fn alpha_outside_unit_interval_is_invalid() {
    let mut c = Config::default();
    c.scenario.alpha = 1.5;
    let e = c.validate().unwrap_err().to_string();
    assert!(e.contains("scenario.alpha"), "{e}");
}

#[test]
fn cav_types_without_a_configuration_of_your_own_are_invalid() {
    let mut c = Config::default();
    c.scenario.cav_types = vec!["truck".into()];
    let e = c.validate().unwrap_err().to_string();
    assert!(
        e.contains("scenario.cav_types") && e.contains("sumocfg"),
        "{e}"
    );
    c.scenario.sumocfg = Some("ramp.sumocfg".into());
    assert!(c.validate().is_ok());
}

/// One way to break the default config: the field, its bad value as the error prints it,
/// the reason given, and the change.
type Case = (&'static str, &'static str, &'static str, fn(&mut Config));

const UNIT: &str = "must lie in [0, 1]";
const RATE: &str = "must be a positive rate of at most 20000 veh/h (two lanes carry about \
                    4000; more only queues vehicles at the entry and fills memory)";
const STEP: &str = "must lie in (0, 1] s";
const POSITIVE: &str = "must be positive";
const ONE_STEP: &str = "must be at least one step";
const SPEED_RANGE: &str = "must be [low, high] with 0 < low <= high <= v_max";
const NON_NEGATIVE: &str = "must not be negative";
const IDM_DECEL: &str = "must be at least idm.decel";
const TIME_BUDGET: &str = "must be 0 (off) or a positive time in ms";
const OPEN_UNIT: &str = "must lie in (0, 1)";
const MODEL_FILE: &str = "no such model file";

/// Every rule, in the order `validate` checks them.
const CASES: [Case; 47] = [
    ("scenario.alpha", "1.5", UNIT, |c| c.scenario.alpha = 1.5),
    ("scenario.lambda", "0", RATE, |c| c.scenario.lambda = 0.0),
    ("scenario.steps", "0", STEPS_RANGE, |c| c.scenario.steps = 0),
    ("scenario.dt", "0", STEP, |c| c.scenario.dt = 0.0),
    ("scenario.v_max", "0", V_MAX_RANGE, |c| {
        c.scenario.v_max = 0.0
    }),
    (
        "scenario.free_flow_accel",
        "0",
        FREE_FLOW_ACCEL_RANGE,
        |c| c.scenario.free_flow_accel = 0.0,
    ),
    ("scenario.vehicle_length", "0", POSITIVE, |c| {
        c.scenario.vehicle_length = 0.0
    }),
    ("scenario.vehicle_width", "0", POSITIVE, |c| {
        c.scenario.vehicle_width = 0.0
    }),
    ("scenario.lane_change_duration", "0.1", ONE_STEP, |c| {
        c.scenario.lane_change_duration = 0.1
    }),
    ("demand.ramp_share", "-0.1", UNIT, |c| {
        c.demand.ramp_share = -0.1
    }),
    ("demand.insertion_speed", "[30.0, 20.0]", SPEED_RANGE, |c| {
        c.demand.insertion_speed = [30.0, 20.0]
    }),
    (
        "demand.hdv_desired_speed",
        "[20.0, 40.0]",
        SPEED_RANGE,
        |c| c.demand.hdv_desired_speed = [20.0, 40.0],
    ),
    ("idm.accel", "0", POSITIVE, |c| c.idm.accel = 0.0),
    ("idm.decel", "0", POSITIVE, |c| c.idm.decel = 0.0),
    ("idm.min_gap", "-1", NON_NEGATIVE, |c| c.idm.min_gap = -1.0),
    ("idm.time_headway", "-1", POSITIVE, |c| {
        c.idm.time_headway = -1.0
    }),
    ("idm.delta", "0", POSITIVE, |c| c.idm.delta = 0.0),
    ("idm.max_decel", "4", IDM_DECEL, |c| c.idm.max_decel = 4.0),
    ("mobil.politeness", "-1", NON_NEGATIVE, |c| {
        c.mobil.politeness = -1.0
    }),
    ("mobil.safe_braking", "0", POSITIVE, |c| {
        c.mobil.safe_braking = 0.0
    }),
    ("mobil.merge_safe_braking", "0", POSITIVE, |c| {
        c.mobil.merge_safe_braking = 0.0
    }),
    ("mobil.merge_min_gap", "-1", NON_NEGATIVE, |c| {
        c.mobil.merge_min_gap = -1.0
    }),
    ("mobil.decision_interval", "-1", NON_NEGATIVE, |c| {
        c.mobil.decision_interval = -1.0
    }),
    ("pbs.node_budget", "0", PBS_BUDGET_RANGE, |c| {
        c.pbs.node_budget = 0
    }),
    ("pbs.time_budget_ms", "-1", TIME_BUDGET, |c| {
        c.pbs.time_budget_ms = -1.0
    }),
    ("planner.horizon", "0", HORIZON_RANGE, |c| {
        c.planner.horizon = 0
    }),
    ("planner.phase1_budget", "0", SEARCH_BUDGET_RANGE, |c| {
        c.planner.phase1_budget = 0
    }),
    ("planner.phase2_budget", "0", SEARCH_BUDGET_RANGE, |c| {
        c.planner.phase2_budget = 0
    }),
    ("planner.goal_distance", "0", POSITIVE, |c| {
        c.planner.goal_distance = 0.0
    }),
    ("planner.fallback_goal_distance", "0", POSITIVE, |c| {
        c.planner.fallback_goal_distance = 0.0
    }),
    ("planner.accel", "0", POSITIVE, |c| {
        c.planner.accel = Some(0.0)
    }),
    ("planner.decel", "0", POSITIVE, |c| c.planner.decel = 0.0),
    ("planner.emergency_decel", "0", POSITIVE, |c| {
        c.planner.emergency_decel = 0.0
    }),
    ("planner.s_bin", "0", POSITIVE, |c| c.planner.s_bin = 0.0),
    ("planner.v_bin", "0", POSITIVE, |c| c.planner.v_bin = 0.0),
    (
        "planner.phase1_lane_change_penalty",
        "-1",
        NON_NEGATIVE,
        |c| c.planner.phase1_lane_change_penalty = -1.0,
    ),
    (
        "planner.phase2_lane_change_penalty",
        "-1",
        NON_NEGATIVE,
        |c| c.planner.phase2_lane_change_penalty = -1.0,
    ),
    (
        "planner.lane_change_deferral_penalty",
        "-1",
        NON_NEGATIVE,
        |c| c.planner.lane_change_deferral_penalty = -1.0,
    ),
    ("planner.min_lane_change_speed", "-1", NON_NEGATIVE, |c| {
        c.planner.min_lane_change_speed = -1.0
    }),
    ("planner.margin_long", "-1", NON_NEGATIVE, |c| {
        c.planner.margin_long = -1.0
    }),
    ("planner.margin_lat", "-1", NON_NEGATIVE, |c| {
        c.planner.margin_lat = -1.0
    }),
    ("planner.safe_gap", "-1", NON_NEGATIVE, |c| {
        c.planner.safe_gap = -1.0
    }),
    ("planner.reaction_time", "-1", NON_NEGATIVE, |c| {
        c.planner.reaction_time = -1.0
    }),
    ("ramp_merge.exponent", "0", POSITIVE, |c| {
        c.ramp_merge.exponent = 0.0
    }),
    ("predictor.decision_probability", "1", OPEN_UNIT, |c| {
        c.predictor.decision_probability = 1.0
    }),
    (
        "predictor.conditioned_model",
        "no/such/model.json",
        MODEL_FILE,
        |c| c.predictor.conditioned_model = Some("no/such/model.json".into()),
    ),
    (
        "predictor.unconditioned_model",
        "no/such/model.json",
        MODEL_FILE,
        |c| c.predictor.unconditioned_model = Some("no/such/model.json".into()),
    ),
];

/// Checks that every field under `reason` rejects its bad value with exactly today's text;
/// returns how many fields that was.
fn assert_rule_rejects(reason: &str) -> usize {
    let cases: Vec<&Case> = CASES.iter().filter(|c| c.2 == reason).collect();
    for (field, value, reason, break_it) in &cases {
        let mut c = Config::default();
        break_it(&mut c);
        let e = c.validate().unwrap_err().to_string();
        assert_eq!(e, format!("invalid setting {field} = {value}: {reason}"));
    }
    cases.len()
}

/// Checks which numbers a rule lets through, at its edges.
fn assert_bounds(rule: Rule, good: &[f64], bad: &[f64]) {
    for &v in good {
        assert!(rule.holds(v), "{rule:?} should accept {v}");
    }
    for &v in bad {
        assert!(!rule.holds(v), "{rule:?} should reject {v}");
    }
    assert!(CASES.iter().any(|c| c.2 == rule.reason()));
}

#[test]
fn default_config_passes_every_rule() {
    Config::default().validate().unwrap();
}

#[test]
fn rules_are_checked_in_order_and_the_first_failure_is_reported() {
    // Break every field from the last rule to the first: each time, the newly broken field
    // is the earliest failing one and must be the one reported.
    let mut c = Config::default();
    for (field, _, _, break_it) in CASES.iter().rev() {
        break_it(&mut c);
        let e = c.validate().unwrap_err().to_string();
        assert!(e.starts_with(&format!("invalid setting {field} = ")), "{e}");
    }
}

#[test]
fn unit_interval_rule() {
    assert_eq!(assert_rule_rejects(UNIT), 2);
    assert_bounds(Rule::UnitInterval, &[0.0, 1.0], &[-0.1, 1.5, f64::NAN]);
}

#[test]
fn rate_rule() {
    assert_eq!(assert_rule_rejects(RATE), 1);
    assert_bounds(
        Rule::Rate,
        &[1e-9, MAX_RATE],
        &[0.0, 20_000.5, 1e12, f64::INFINITY, f64::NAN],
    );
}

#[test]
fn bounded_counts_and_sizes() {
    for (reason, n, low, high) in [
        (STEPS_RANGE, 1, 1.0, 100_000.0),
        (V_MAX_RANGE, 1, 1.0, 100.0),
        (FREE_FLOW_ACCEL_RANGE, 1, 0.1, 20.0),
        (HORIZON_RANGE, 1, 1.0, 100.0),
        (SEARCH_BUDGET_RANGE, 2, 1.0, 1e6),
        (PBS_BUDGET_RANGE, 1, 1.0, 100_000.0),
    ] {
        assert_eq!(assert_rule_rejects(reason), n, "{reason}");
        let rule = Rule::Between(low, high, reason);
        let above = high * (1.0 + 1e-9);
        assert_bounds(rule, &[low, high], &[low * 0.99, above, 1e300, f64::NAN]);
    }
}

#[test]
fn absurd_sizes_are_refused_before_anything_runs() {
    // The values that once exhausted memory or hung a worker: each is one error naming its
    // key, at once.
    type Breaker = fn(&mut Config);
    let cases: [(&str, Breaker); 4] = [
        ("scenario.lambda", |c| c.scenario.lambda = 1e12),
        ("scenario.steps", |c| c.scenario.steps = u32::MAX),
        ("scenario.v_max", |c| c.scenario.v_max = 1e300),
        ("planner.horizon", |c| c.planner.horizon = 100_000),
    ];
    for (field, break_it) in cases {
        let mut c = Config::default();
        break_it(&mut c);
        let e = c.validate().unwrap_err().to_string();
        assert!(e.starts_with(&format!("invalid setting {field} = ")), "{e}");
    }
}

#[test]
fn step_length_rule() {
    assert_eq!(assert_rule_rejects(STEP), 1);
    assert_bounds(Rule::StepLength, &[1e-9, 1.0], &[0.0, 1.01, f64::NAN]);
}

#[test]
fn positive_rule() {
    assert_eq!(assert_rule_rejects(POSITIVE), 16);
    assert_bounds(Rule::Positive, &[1e-9, f64::INFINITY], &[0.0, f64::NAN]);
}

#[test]
fn lane_change_duration_rule() {
    assert_eq!(assert_rule_rejects(ONE_STEP), 1);
    assert_bounds(Rule::AtLeast(0.2, ONE_STEP), &[0.2, 1.0], &[0.19, f64::NAN]);
}

#[test]
fn speed_range_rule() {
    assert_eq!(assert_rule_rejects(SPEED_RANGE), 2);
    for bad in [[0.0, 30.0], [30.0, 20.0], [25.0, 36.0], [f64::NAN, 30.0]] {
        let mut c = Config::default();
        c.demand.insertion_speed = bad;
        let e = c.validate().unwrap_err().to_string();
        assert_eq!(
            e,
            format!("invalid setting demand.insertion_speed = {bad:?}: {SPEED_RANGE}")
        );
    }
    let mut c = Config::default();
    c.demand.insertion_speed = [35.0, 35.0];
    c.validate().unwrap();
}

#[test]
fn non_negative_rule() {
    assert_eq!(assert_rule_rejects(NON_NEGATIVE), 12);
    assert_bounds(Rule::NonNegative, &[0.0, f64::INFINITY], &[-1e-9, f64::NAN]);
}

#[test]
fn max_decel_rule() {
    assert_eq!(assert_rule_rejects(IDM_DECEL), 1);
    assert_bounds(
        Rule::AtLeast(5.0, IDM_DECEL),
        &[5.0, 9.0],
        &[4.99, f64::NAN],
    );
}

#[test]
fn time_budget_rule() {
    assert_eq!(assert_rule_rejects(TIME_BUDGET), 1);
    assert_bounds(
        Rule::TimeBudget,
        &[0.0, 1e6],
        &[-1.0, f64::INFINITY, f64::NAN],
    );
}

#[test]
fn open_unit_interval_rule() {
    assert_eq!(assert_rule_rejects(OPEN_UNIT), 1);
    assert_bounds(Rule::OpenUnitInterval, &[1e-9, 0.5], &[0.0, 1.0, f64::NAN]);
}

#[test]
fn model_file_rule() {
    assert_eq!(assert_rule_rejects(MODEL_FILE), 2);
}

#[test]
fn missing_and_malformed_files_name_the_file() {
    let e = Config::from_file(Path::new("no/such/file.toml")).unwrap_err();
    assert!(e.to_string().contains("no/such/file.toml"));
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.toml");
    std::fs::write(&p, "[scenario\nalpha = ").unwrap();
    let e = Config::from_file(&p).unwrap_err().to_string();
    assert!(e.contains("bad.toml") && e.starts_with("malformed"), "{e}");
}

/// Profile attributes SUMO cannot be given (hardening II, findings 2, 4 and 5): each refused in
/// one line naming the setting, before anything is written into SUMO's XML; the values that
/// used to inject a second vType, spin SUMO for ever or make it assert.
#[test]
fn hostile_profile_attributes_are_refused_naming_the_setting() {
    for (key, value, rule) in [
        ("tau", "1\"/><vType id=\"evil", "markup"),
        ("color", "1&2<3", "markup"),
        ("minGap", "nan", "finite"),
        ("accel", "1e308", "finite"),
        ("tau", "inf", "finite"),
        ("tau", "-inf", "finite"),
        ("bad name", "1", "attribute name"),
        ("id", "x", "attribute name"),
        ("length", "0", "positive"),
        ("decel", "-3", "positive"),
        ("minGap", "-1", "not be negative"),
        ("sigma", "1.5", "[0, 1]"),
    ] {
        let text =
            format!("[hdv]\nprofile = \"x\"\n[hdv.profiles.x.attributes]\n\"{key}\" = '{value}'\n");
        let c: Config = toml::from_str(&text).unwrap();
        let e = c.validate().unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "invalid setting hdv.profiles.x.attributes.{key} = "
            )) && e.contains(rule),
            "{key} = {value}: {e}"
        );
    }
    // What SUMO's own attributes look like passes: numbers, colours, names.
    let ok = "[hdv]\nprofile = \"x\"\n[hdv.profiles.x.attributes]\nsigma = \"0.5\"\ncolor = \"1,0,0\"\nlcAssertive = \"2\"\nlatAlignment = \"center\"\n";
    toml::from_str::<Config>(ok).unwrap().validate().unwrap();
}
