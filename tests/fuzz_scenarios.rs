//! A seeded fuzz over a scenario of the user's own, as `bkpbs episode --sumocfg` takes it: the
//! configuration's options (times, seeds, server and output options, file names and paths,
//! options SUMO has not) and the route file's flows and vehicle types (counts, times,
//! probabilities, vType values), each from hostile values — NaN, infinities, negatives, huge
//! numbers, markup, paths out of the scenario's folder — and a few ordinary ones so that some
//! cases run through. On a copy of SUMO's `ramp` game, with real SUMO.
//!
//! Every run must end within a bound, without a panic, either with exit 0 or with exactly one
//! `error:` line and exit 1, and write nothing outside its output directory and the scenario's
//! folder. Seeded (ChaCha8), so a failure names the case and reproduces; set
//! `BKPBS_FUZZ_SEED` to explore other seeds.

mod common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const BIN: &str = env!("CARGO_BIN_EXE_bkpbs");
const SEED: u64 = 42;

/// The seed: [`SEED`], or `BKPBS_FUZZ_SEED` when set.
fn seed() -> u64 {
    std::env::var("BKPBS_FUZZ_SEED").map_or(SEED, |s| s.parse().expect("a number"))
}
/// Cases per test.
const CASES: usize = 24;
/// Wall time one run may take: a stuck SUMO call is ended by the watchdog after the stall
/// bound the cases set (`sumo.stall_timeout_s = 5`).
const BOUND: Duration = Duration::from_secs(40);

/// Hostile values, and a few ordinary ones so that some cases run through.
const VALUES: [&str; 24] = [
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "1e308",
    "-1e308",
    "1e-320",
    "1e9",
    "10001",
    "<",
    "&amp",
    "1\"/><x y=\"",
    "'",
    "",
    " ",
    "true",
    "1,0",
    "0.2",
    "0.5",
    "1",
    "30",
    "200",
    "2500",
];

/// Options of a configuration: SUMO's (times, seeds, server and output options, behaviour) and
/// a name SUMO has not.
const OPTIONS: [&str; 18] = [
    "begin",
    "end",
    "step-length",
    "seed",
    "random",
    "time-to-teleport",
    "remote-port",
    "num-clients",
    "output-prefix",
    "tripinfo-output",
    "summary-output",
    "fcd-output",
    "max-depart-delay",
    "scale",
    "lanechange.duration",
    "collision.action",
    "threads",
    "no-such-option",
];

/// File names an input option may be given: missing, out of the folder, a directory, the
/// configuration itself, absolute system paths.
const PATHS: [&str; 8] = [
    "ramp/ramp.rou.xml",
    "missing.rou.xml",
    "../ramp/ramp.rou.xml",
    "ramp",
    "ramp.sumocfg",
    "/dev/null",
    "/etc/hostname",
    "ramp/ramp.net.xml",
];

/// Attributes of a flow, and of a vType.
const FLOW_ATTRIBUTES: [&str; 8] = [
    "begin",
    "end",
    "number",
    "vehsPerHour",
    "probability",
    "period",
    "departSpeed",
    "departLane",
];
const VTYPE_ATTRIBUTES: [&str; 10] = [
    "accel",
    "decel",
    "length",
    "minGap",
    "speedFactor",
    "sigma",
    "tau",
    "maxSpeed",
    "lcStrategic",
    "emergencyDecel",
];

fn pick<'a>(rng: &mut ChaCha8Rng, from: &[&'a str]) -> &'a str {
    from[rng.gen_range(0..from.len())]
}

/// Every file below `dir` (relative paths), to see what a run wrote.
fn files_below(dir: &Path) -> BTreeSet<PathBuf> {
    let mut out = BTreeSet::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p.clone());
            }
            out.insert(p.strip_prefix(dir).unwrap().to_path_buf());
        }
    }
    out
}

/// An output file a configuration may name out of its own folder: SUMO alone writes it there
/// too, and so does an episode (the guide's "Your configuration's own outputs").
const ESCAPING_OUTPUT: &str = "../escaped.xml";

/// Runs the episode of case `case` on `cfg` into `out`, killed past [`BOUND`], and checks how
/// it ended and that it wrote only into `out`, the scenario's folder `game` and, where the
/// configuration names it, [`ESCAPING_OUTPUT`].
fn run_case(case: &str, root: &Path, cfg: &Path, out: &Path) -> Output {
    let settings = root.join("settings.toml");
    std::fs::write(&settings, "[sumo]\nstall_timeout_s = 5\n").unwrap();
    let before = files_below(root);
    let args = [
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--config",
        settings.to_str().unwrap(),
        "--planner",
        "bk-pbs",
        "--alpha",
        "0.5",
        "--seed",
        "1",
        "--steps",
        "25",
        "--out",
        out.to_str().unwrap(),
    ];
    let (o, took) = common::output_within(Command::new(BIN).args(args), BOUND);
    assert!(took < BOUND, "{case}: ran past {BOUND:?}");
    let err = common::stderr(&o);
    assert!(!err.contains("panicked"), "{case}: {err}");
    if !o.status.success() {
        assert_eq!(o.status.code(), Some(1), "{case}: {err}");
        let lines: Vec<&str> = err.lines().collect();
        assert!(
            lines.len() == 1 && lines[0].starts_with("error: "),
            "{case}: one error line expected, got: {err}"
        );
    }
    let named = std::fs::read_to_string(cfg)
        .unwrap()
        .contains(ESCAPING_OUTPUT);
    let outside: Vec<PathBuf> = files_below(root)
        .difference(&before)
        .filter(|p| !p.starts_with("out") && !p.starts_with("game"))
        .filter(|p| !(named && *p == Path::new("escaped.xml")))
        .cloned()
        .collect();
    assert!(outside.is_empty(), "{case}: wrote {outside:?}");
    o
}

/// With the committed seed, the cases reach both ends (some run, some are refused), so the fuzz
/// exercises both; another seed may draw only refusals.
fn assert_both_ends(ran: usize, refused: usize) {
    if seed() == SEED {
        assert!(ran > 0 && refused > 0, "{ran} ran, {refused} refused");
    }
}

/// The configuration with `options` (name, value) set in its own section, each value escaped
/// only as the case says (markup values stay raw: a broken file is a case too).
fn configuration(options: &[(String, String)]) -> String {
    let mut body = String::from(
        "<configuration>\n  <input>\n    <net-file value=\"ramp/ramp.net.xml\"/>\n    \
         <route-files value=\"ramp/ramp.rou.xml\"/>\n  </input>\n  <time>\n    \
         <begin value=\"0\"/>\n    <end value=\"400\"/>\n    <step-length value=\".2\"/>\n  \
         </time>\n  <fuzz>\n",
    );
    for (name, value) in options {
        body += &format!("    <{name} value=\"{value}\"/>\n");
    }
    body + "  </fuzz>\n</configuration>\n"
}

#[test]
fn hostile_configurations_end_in_exit_0_or_one_error_line() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let game = common::game_copy(root);
    let mut rng = ChaCha8Rng::seed_from_u64(seed());
    let (mut ran, mut refused) = (0, 0);
    for case in 0..CASES {
        let mut options = Vec::new();
        for _ in 0..rng.gen_range(1..4) {
            let name = pick(&mut rng, &OPTIONS).to_string();
            let value = if name.ends_with("-output") || name == "output-prefix" {
                pick(
                    &mut rng,
                    &["out.xml", ESCAPING_OUTPUT, "/nonexistent/y.xml", "sub/"],
                )
            } else {
                pick(&mut rng, &VALUES)
            };
            options.push((name, value.to_string()));
        }
        if rng.gen_bool(0.3) {
            let option = pick(&mut rng, &["route-files", "net-file", "additional-files"]);
            options.push((option.to_string(), pick(&mut rng, &PATHS).to_string()));
        }
        let cfg = game.join(format!("fuzz{case}.sumocfg"));
        std::fs::write(&cfg, configuration(&options)).unwrap();
        let label = format!("case {case} {options:?}");
        let out = root.join("out").join(case.to_string());
        match run_case(&label, root, &cfg, &out).status.success() {
            true => ran += 1,
            false => refused += 1,
        }
    }
    eprintln!("hostile configurations: {ran} ran, {refused} refused");
    assert_both_ends(ran, refused);
}

/// The game's route file with hostile values in flows and vehicle types.
fn hostile_routes(rng: &mut ChaCha8Rng, routes: &str) -> (String, String) {
    let mut text = routes.to_string();
    let mut said = Vec::new();
    for _ in 0..rng.gen_range(1..4) {
        let (tag, attrs) = match rng.gen_bool(0.5) {
            true => ("flow", &FLOW_ATTRIBUTES[..]),
            false => ("vType", &VTYPE_ATTRIBUTES[..]),
        };
        let (attr, value) = (pick(rng, attrs), pick(rng, &VALUES));
        // Set it on the first element of that kind (replacing the attribute if it is there).
        let open = format!("<{tag} ");
        let Some(at) = text.find(&open) else { continue };
        let insert = at + open.len();
        text.insert_str(insert, &format!("{attr}=\"{value}\" "));
        said.push(format!("{tag} {attr}={value:?}"));
    }
    (text, said.join(", "))
}

#[test]
fn hostile_route_files_end_in_exit_0_or_one_error_line() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let game = common::game_copy(root);
    let routes = game.join("ramp/ramp.rou.xml");
    let original = std::fs::read_to_string(&routes).unwrap();
    let cfg = game.join("ramp.sumocfg");
    let mut rng = ChaCha8Rng::seed_from_u64(seed() + 1);
    let (mut ran, mut refused) = (0, 0);
    for case in 0..CASES {
        let (text, said) = hostile_routes(&mut rng, &original);
        std::fs::write(&routes, text).unwrap();
        let out = root.join("out").join(case.to_string());
        let label = format!("case {case}: {said}");
        match run_case(&label, root, &cfg, &out).status.success() {
            true => ran += 1,
            false => refused += 1,
        }
    }
    eprintln!("hostile route files: {ran} ran, {refused} refused");
    assert_both_ends(ran, refused);
}
