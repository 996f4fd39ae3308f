//! The options bkpbs gives SUMO beside a user's configuration, and a line for each of the
//! configuration's settings it changes.
//!
//! With no CAV (α = 0 and no `cav_types`) an episode is `sumo -c` with the episode's seed:
//! bkpbs adds only what changes no vehicle's motion (its own tripinfo output when the
//! configuration names none, SUMO's console output off). With CAVs it adds what its planners
//! need, which SUMO can set only for every vehicle at once: lane changes of
//! `scenario.lane_change_duration` (SUMO's `lanechange.duration` is global; a vehicle type's
//! `maxSpeedLat` sets the lateral speed only once some duration makes changes continuous) and
//! collisions of physical overlap reported, not acted on (`collision.*` are global too).
//! Teleports stay as the configuration says.

use std::path::{Path, PathBuf};

use crate::config::Config;
use crate::sumo::sumocfg::SumoConfig;

/// SUMO's options for an episode on a user's configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct SumoOptions {
    /// The command-line options, given after the configuration (`-c FILE`).
    pub args: Vec<String>,
    /// One line per setting of the configuration bkpbs changes (or SUMO default it changes
    /// for a CAV's sake): what the configuration says, what bkpbs uses, and why.
    pub notes: Vec<String>,
    /// The tripinfo output bkpbs reads after SUMO closes: the configuration's own, or bkpbs's.
    pub tripinfo: PathBuf,
}

/// An option bkpbs sets: its names in a configuration (the first is the command line's), the
/// value, SUMO's default when a change from it is worth a line, and why.
struct Setting<'a> {
    names: &'a [&'a str],
    value: String,
    default: Option<&'a str>,
    why: &'a str,
}

/// The options of an episode of `config` on the configuration `cfg`; bkpbs's own tripinfo
/// output, when the configuration names none, goes into the directory `scratch`.
pub fn sumo_options(config: &Config, cfg: &SumoConfig, scratch: &Path) -> SumoOptions {
    let has_cavs = has_cavs(&config.scenario);
    let mut settings = Vec::new();
    if has_cavs {
        settings.extend(cav_settings(config));
    }
    settings.extend(run_settings(config, cfg));
    let (tripinfo, trip_settings) = tripinfo(cfg, scratch);
    settings.extend(trip_settings);
    let mut out = SumoOptions {
        args: Vec::new(),
        notes: Vec::new(),
        tripinfo,
    };
    for setting in &settings {
        out.args.push(format!("--{}", setting.names[0]));
        out.args.push(setting.value.clone());
        out.notes.extend(note(cfg, setting));
    }
    out
}

/// Whether an episode of scenario `s` may have CAVs: α above 0, or CAV types named. Only
/// then does bkpbs change how SUMO moves vehicles, and handle collisions itself (SUMO reports
/// each, the episode removes both vehicles); else SUMO's own `collision.action` applies.
pub fn has_cavs(s: &crate::config::Scenario) -> bool {
    s.alpha > 0.0 || !s.cav_types.is_empty()
}

/// What the planners need of SUMO for their CAVs.
fn cav_settings(config: &Config) -> Vec<Setting<'static>> {
    let duration = config.scenario.lane_change_duration;
    vec![
        Setting {
            names: &["collision.action"],
            value: "warn".into(),
            default: Some("teleport"),
            why: "SUMO reports each collision and the episode removes both vehicles",
        },
        Setting {
            names: &["collision.check-junctions"],
            value: "true".into(),
            default: Some("false"),
            why: "collisions on junctions count too",
        },
        Setting {
            names: &["collision.mingap-factor"],
            value: "0".into(),
            default: Some("-1"),
            why: "only a physical overlap is a collision",
        },
        Setting {
            names: &["lanechange.duration"],
            value: format!("{duration}"),
            default: Some("0"),
            why: "the planners' lane changes take scenario.lane_change_duration, and SUMO sets \
                  it for every vehicle (set scenario.lane_change_duration to keep yours)",
        },
    ]
}

/// The episode's seed, and SUMO's console output off (it goes to `sumo.log`).
fn run_settings<'a>(config: &Config, cfg: &SumoConfig) -> Vec<Setting<'a>> {
    let seed = config.scenario.seed % (i32::MAX as u64);
    let mut out = vec![Setting {
        names: &["seed", "srand"],
        value: format!("{seed}"),
        default: None,
        why: "an episode runs on its --seed",
    }];
    if cfg.option(&["random", "abs-rand"]).is_some_and(is_true) {
        out.push(Setting {
            names: &["random", "abs-rand"],
            value: "false".into(),
            default: None,
            why: "random would seed SUMO from the clock, and an episode runs on its --seed",
        });
    }
    let quiet = |names, value: &str| Setting {
        names,
        value: value.into(),
        default: None,
        why: "SUMO's console output goes to sumo.log (--verbose shows its warnings)",
    };
    out.extend([
        quiet(&["verbose", "v"], "false"),
        quiet(&["no-step-log"], "true"),
        quiet(&["duration-log.disable"], "true"),
        quiet(&["no-warnings", "W"], &(!config.sumo.verbose).to_string()),
    ]);
    out
}

/// The tripinfo output bkpbs reads, and what it sets for it: the configuration's own file, its
/// unfinished and undeparted trips added; else one of bkpbs's own in `scratch`.
fn tripinfo<'a>(cfg: &SumoConfig, scratch: &Path) -> (PathBuf, Vec<Setting<'a>>) {
    let unfinished = |default| {
        [
            Setting {
                names: &["tripinfo-output.write-unfinished"],
                value: "true".into(),
                default,
                why: "bkpbs counts the time lost by vehicles still driving at the end",
            },
            Setting {
                names: &["tripinfo-output.write-undeparted"],
                value: "true".into(),
                default,
                why: "bkpbs lists the vehicles never inserted, each with its wait to the end",
            },
        ]
    };
    match cfg.option(&["tripinfo-output", "tripinfo"]) {
        Some(own) if !own.trim().is_empty() => {
            let dir = cfg.path.parent().unwrap_or(Path::new("."));
            (dir.join(own.trim()), unfinished(Some("false")).into())
        }
        _ => {
            let path = scratch.join("tripinfo.xml");
            let ours = Setting {
                names: &["tripinfo-output"],
                value: path.display().to_string(),
                default: None,
                why: "bkpbs reads SUMO's trips",
            };
            let [a, b] = unfinished(None);
            (path, vec![ours, a, b])
        }
    }
}

/// The line saying what `setting` changes of `cfg`, if it changes anything: a value the
/// configuration sets otherwise, or a default of SUMO's worth naming.
fn note(cfg: &SumoConfig, setting: &Setting) -> Option<String> {
    let name = setting.names[0];
    let (said, theirs) = match cfg.option(setting.names) {
        Some(v) => (format!("sets {name} = {v}"), v.to_string()),
        None => {
            let d = setting.default?;
            (
                format!("leaves {name} at SUMO's default {d}"),
                d.to_string(),
            )
        }
    };
    (!same(&theirs, &setting.value)).then(|| {
        format!(
            "your configuration {said}; bkpbs uses {} because {}",
            setting.value, setting.why
        )
    })
}

/// Whether two option values mean the same: as numbers, as booleans, or as text.
fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.trim(), b.trim());
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => x == y,
        _ if is_bool(a) && is_bool(b) => is_true(a) == is_true(b),
        _ => a == b,
    }
}

/// SUMO's true (`StringUtils::toBool`).
fn is_true(v: &str) -> bool {
    ["1", "yes", "true", "on", "x", "t"].contains(&v.trim().to_lowercase().as_str())
}

/// Whether SUMO reads `v` as a boolean.
fn is_bool(v: &str) -> bool {
    is_true(v) || ["0", "no", "false", "off", "-", "f"].contains(&v.trim().to_lowercase().as_str())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(body: &str) -> (tempfile::TempDir, SumoConfig) {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("s.sumocfg");
        let text = format!(r#"<configuration><net-file value="a"/>{body}</configuration>"#);
        std::fs::write(&p, text).unwrap();
        let c = SumoConfig::read(&p).unwrap();
        (d, c)
    }

    fn has(args: &[String], k: &str) -> bool {
        args.iter().any(|a| a == k)
    }

    #[test]
    fn with_no_cav_nothing_that_moves_a_vehicle() {
        let mut config = Config::default();
        config.scenario.alpha = 0.0;
        config.scenario.seed = 7;
        let (d, c) = cfg(r#"<seed value="42"/>"#);
        let o = sumo_options(&config, &c, Path::new("/scratch"));
        for k in [
            "--lanechange.duration",
            "--collision.action",
            "--time-to-teleport",
        ] {
            assert!(!has(&o.args, k), "{k}: {:?}", o.args);
        }
        assert_eq!(o.tripinfo, Path::new("/scratch/tripinfo.xml"));
        assert_eq!(
            o.notes,
            ["your configuration sets seed = 42; bkpbs uses 7 because an episode runs on its --seed"]
        );
        drop(d);
    }

    #[test]
    fn with_cavs_each_change_is_named_and_the_own_tripinfo_read() {
        let mut config = Config::default();
        config.scenario.alpha = 0.5;
        let body = r#"<lanechange.duration value="2"/><collision.action value="warn"/>
                      <random value="true"/><tripinfo-output value="out/t.xml"/>
                      <verbose value="true"/>"#;
        let (d, c) = cfg(body);
        let o = sumo_options(&config, &c, Path::new("/scratch"));
        assert_eq!(o.tripinfo, d.path().join("out/t.xml"));
        assert!(!has(&o.args, "--tripinfo-output"), "{:?}", o.args);
        let named = |w: &str| o.notes.iter().filter(|n| n.contains(w)).count();
        assert_eq!(
            named("lanechange.duration = 2; bkpbs uses 1"),
            1,
            "{:?}",
            o.notes
        );
        assert_eq!(
            named("collision.action"),
            0,
            "the same value: {:?}",
            o.notes
        );
        assert_eq!(
            named("leaves collision.mingap-factor at SUMO's default -1"),
            1
        );
        assert_eq!(named("random = true; bkpbs uses false"), 1);
        assert_eq!(
            named("leaves tripinfo-output.write-unfinished at SUMO's default false"),
            1
        );
        assert_eq!(
            named("leaves tripinfo-output.write-undeparted at SUMO's default false"),
            1
        );
        assert_eq!(named("verbose = true; bkpbs uses false"), 1);
    }
}
