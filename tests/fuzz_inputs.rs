//! A seeded fuzz over what a user writes into SUMO's inputs through bkpbs: HDV profile
//! attributes and network XML, with values from NaN, infinities, negatives, huge numbers and
//! markup (the second hardening's fuzz). Every run must end within a bound, without a panic,
//! either with exit 0 or with exactly one `error:` line and exit 1.
//!
//! Seeded (ChaCha8), so a failure names the case and reproduces; change `SEED` to explore.

mod common;

use std::process::{Command, Output};
use std::time::Duration;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const BIN: &str = env!("CARGO_BIN_EXE_bkpbs");
const SEED: u64 = 29;
/// Wall time one run may take: a stuck SUMO call is ended by the watchdog after the stall
/// bound the cases set (`sumo.stall_timeout_s = 5`).
const BOUND: Duration = Duration::from_secs(30);

/// Hostile values, and a few ordinary ones so that some cases run through.
const VALUES: [&str; 22] = [
    "nan",
    "NaN",
    "inf",
    "-inf",
    "-1",
    "0",
    "-0",
    "1e308",
    "-1e308",
    "1e-320",
    "1e4",
    "10001",
    "<",
    "&amp",
    "1\"/><vType id=\"x",
    "'",
    "",
    " ",
    "1,0,0",
    "0.5",
    "2.5",
    "33.3",
];
/// SUMO vType attributes, and names SUMO has not.
const ATTRIBUTES: [&str; 14] = [
    "minGap",
    "accel",
    "decel",
    "tau",
    "sigma",
    "length",
    "maxSpeed",
    "speedFactor",
    "speedDev",
    "color",
    "lcAssertive",
    "emergencyDecel",
    "id",
    "no such",
];
/// Lane attributes of a network.
const LANE_ATTRIBUTES: [&str; 4] = ["width", "length", "speed", "shape"];

fn pick<'a>(rng: &mut ChaCha8Rng, from: &[&'a str]) -> &'a str {
    from[rng.gen_range(0..from.len())]
}

/// Runs `bkpbs args`, killed past [`BOUND`], and checks how it ended.
fn run_bounded(case: &str, args: &[&str]) -> Output {
    let (out, took) = common::output_within(Command::new(BIN).args(args), BOUND);
    assert!(took < BOUND, "{case}: ran past {BOUND:?}");
    let err = common::stderr(&out);
    assert!(!err.contains("panicked"), "{case}: {err}");
    if !out.status.success() {
        assert_eq!(out.status.code(), Some(1), "{case}: {err}");
        common::one_error_line(&out);
    }
    out
}

/// A TOML string literal of `s` (basic string, escaped).
fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

#[test]
fn hostile_profile_attributes_end_in_exit_0_or_one_error_line() {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let d = tempfile::tempdir().unwrap();
    let (mut ran, mut refused) = (0, 0);
    for k in 0..40 {
        let mut text = String::from("[sumo]\nstall_timeout_s = 5\n[hdv]\nprofile = \"fuzz\"\n");
        text += "[hdv.profiles.fuzz.attributes]\n";
        let mut used = std::collections::BTreeSet::new();
        for _ in 0..rng.gen_range(1..=3) {
            let key = pick(&mut rng, &ATTRIBUTES);
            if used.insert(key) {
                let value = pick(&mut rng, &VALUES);
                text += &format!("{} = {}\n", toml_string(key), toml_string(value));
            }
        }
        let cfg = d.path().join(format!("profile-{k}.toml"));
        std::fs::write(&cfg, &text).unwrap();
        let out = d.path().join(format!("profile-{k}"));
        let o = run_bounded(
            &format!("profile case {k}:\n{text}"),
            &[
                "episode",
                "--steps",
                "25",
                "--config",
                cfg.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        );
        if o.status.success() {
            ran += 1;
        } else {
            refused += 1;
        }
    }
    // Both outcomes occur: the fuzz reaches SUMO, and refuses what it must.
    assert!(ran > 0 && refused > 0, "ran {ran}, refused {refused}");
}

/// The embedded merge network with one lane attribute of one lane set to a hostile value.
fn broken_net(rng: &mut ChaCha8Rng, net: &str) -> (String, String) {
    let lanes: Vec<usize> = net.match_indices("<lane ").map(|(i, _)| i).collect();
    let at = lanes[rng.gen_range(0..lanes.len())];
    let attribute = pick(rng, &LANE_ATTRIBUTES);
    let value = match attribute {
        "shape" => format!("{} 0,0", pick(rng, &VALUES)),
        _ => pick(rng, &VALUES).to_string(),
    };
    let tag_end = at + net[at..].find('>').unwrap();
    let needle = format!("{attribute}=\"");
    let Some(start) = net[at..tag_end]
        .find(&needle)
        .map(|i| at + i + needle.len())
    else {
        return (net.to_string(), "unchanged".into());
    };
    let end = start + net[start..].find('"').unwrap();
    let broken = format!("{}{}{}", &net[..start], value, &net[end..]);
    (broken, format!("{attribute}={value:?} at byte {at}"))
}

#[test]
fn hostile_network_xml_ends_in_exit_0_or_one_error_line() {
    let net = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/sumo_net/merge.net.xml"
    ))
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let d = tempfile::tempdir().unwrap();
    let cfg = d.path().join("watch.toml");
    std::fs::write(&cfg, "[sumo]\nstall_timeout_s = 5\n").unwrap();
    for k in 0..40 {
        let (broken, what) = broken_net(&mut rng, &net);
        let path = d.path().join(format!("net-{k}.net.xml"));
        std::fs::write(&path, broken).unwrap();
        let p = path.to_str().unwrap();
        let case = format!("network case {k}: {what}");
        run_bounded(&case, &["network", p]);
        // Every fourth case also as an episode (SUMO loads it).
        if k % 4 == 0 {
            let out = d.path().join(format!("net-{k}"));
            let args = ["episode", "--steps", "25", "--net", p, "--config"];
            let mut args: Vec<&str> = args.to_vec();
            args.extend([cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
            run_bounded(&case, &args);
        }
    }
}
