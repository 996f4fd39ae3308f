//! Inputs of a scenario of the user's own that once got through without a word, each now one
//! `error:` line naming the culprit (or, for the scratch directories, cleaned up): a
//! `--cav-types` naming a vTypeDistribution (0 CAVs), `--lambda`/`--hdv-profile` beside
//! `--sumocfg` (ignored), an `<end>` before `<begin>` or absurdly far (0 or 4294967295 steps), and
//! the scratch directories of killed episodes (never swept), a flow of 1e9 vehicles (SUMO grew
//! to 3.85 GB before it aborted). On a copy of SUMO's `ramp` game, with real SUMO.

mod common;

use std::path::Path;
use std::process::Command;

use common::{assert_ok, game_copy, refused_naming};

/// `bkpbs episode --sumocfg cfg --planner sumo --out out` and `extra`, with `TMPDIR` at `tmp`.
fn episode(cfg: &Path, out: &Path, tmp: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_bkpbs"))
        .args(["episode", "--planner", "sumo", "--sumocfg"])
        .arg(cfg)
        .arg("--out")
        .arg(out)
        .args(extra)
        .env("TMPDIR", tmp)
        .output()
        .expect("the binary runs")
}

#[test]
fn what_a_scenario_would_ignore_or_misread_is_one_error_line() {
    let dir = tempfile::tempdir().unwrap();
    let game = game_copy(dir.path());
    let (ramp, out, tmp) = (
        game.join("ramp.sumocfg"),
        dir.path().join("out"),
        dir.path(),
    );
    // `ramp` draws every vehicle's type from the distribution DEFAULT_VEHTYPE.
    let o = episode(
        &ramp,
        &out,
        tmp,
        &["--cav-types", "DEFAULT_VEHTYPE", "--steps", "20"],
    );
    refused_naming(
        &o,
        &[
            "'DEFAULT_VEHTYPE', a vTypeDistribution of ramp/ramp.rou.xml",
            "(truck, passenger)",
        ],
    );
    assert_ok(&episode(
        &ramp,
        &out,
        tmp,
        &["--cav-types", "truck", "--steps", "20"],
    ));
    for (flag, value, what) in [
        ("--lambda", "2000", "its own demand"),
        ("--hdv-profile", "paper", "its own drivers"),
    ] {
        let o = episode(&ramp, &out, tmp, &[flag, value]);
        refused_naming(&o, &[flag, "ramp.sumocfg", what]);
    }
    let text = std::fs::read_to_string(&ramp).unwrap();
    let backwards = game.join("backwards.sumocfg");
    let begin = text.replace("<begin value=\"0\"/>", "<begin value=\"500\"/>");
    std::fs::write(&backwards, begin).unwrap();
    let o = episode(&backwards, &out, tmp, &[]);
    refused_naming(
        &o,
        &[
            "backwards.sumocfg",
            "<end> 400 s is not after its <begin> 500 s",
        ],
    );
    let far = game.join("far.sumocfg");
    std::fs::write(
        &far,
        text.replace("<end value=\"400\"/>", "<end value=\"1e12\"/>"),
    )
    .unwrap();
    let o = episode(&far, &out, tmp, &[]);
    refused_naming(
        &o,
        &[
            "far.sumocfg",
            "more than an episode runs (100000)",
            "--steps",
        ],
    );
}

#[test]
fn scratch_directories_of_dead_episodes_are_swept_and_live_ones_kept() {
    let dir = tempfile::tempdir().unwrap();
    let game = game_copy(dir.path());
    let tmp = dir.path().join("tmp");
    std::fs::create_dir(&tmp).unwrap();
    // A process that has ended: its id names a dead episode's directory.
    let mut child = Command::new("true").spawn().unwrap();
    let dead = child.id();
    child.wait().unwrap();
    let stale = tmp.join(format!("bkpbs-scenario-{dead}-abc123"));
    let live = tmp.join(format!("bkpbs-scenario-{}-def456", std::process::id()));
    for d in [&stale, &live] {
        std::fs::create_dir(d).unwrap();
        std::fs::write(d.join("tripinfo.xml"), "<tripinfos/>").unwrap();
    }
    let o = episode(
        &game.join("ramp.sumocfg"),
        &dir.path().join("out"),
        &tmp,
        &["--steps", "10"],
    );
    assert_ok(&o);
    assert!(
        !stale.exists(),
        "the dead episode's scratch directory is swept"
    );
    assert!(live.exists(), "a running process's is kept");
}

/// The peak resident memory of the waited-for children of this process so far (MiB).
fn children_peak_mib() -> f64 {
    // SAFETY: getrusage fills the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    assert_eq!(
        unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) },
        0
    );
    usage.ru_maxrss as f64 / 1024.0
}

#[test]
fn a_flow_of_a_billion_vehicles_is_one_error_line_in_bounded_memory() {
    let dir = tempfile::tempdir().unwrap();
    let game = game_copy(dir.path());
    let flows = game.join("ramp/huge.rou.xml");
    let flow = r#"<routes><flow id="huge" type="passenger" begin="0" end="400" number="1000000000" from="gneE2" to="gneE8"/></routes>"#;
    std::fs::write(&flows, flow).unwrap();
    let text = std::fs::read_to_string(game.join("ramp.sumocfg")).unwrap();
    let cfg = game.join("huge.sumocfg");
    let routes = "<route-files value=\"ramp/ramp.rou.xml,ramp/huge.rou.xml\"/>";
    std::fs::write(
        &cfg,
        text.replace("<route-files value=\"ramp/ramp.rou.xml\"/>", routes),
    )
    .unwrap();
    let start = std::time::Instant::now();
    let o = episode(&cfg, &dir.path().join("out"), dir.path(), &[]);
    refused_naming(
        &o,
        &[
            "huge.sumocfg",
            "flow 'huge' of ramp/huge.rou.xml",
            "1.000e9",
        ],
    );
    assert!(
        start.elapsed() < std::time::Duration::from_secs(5),
        "{:?}",
        start.elapsed()
    );
    let peak = children_peak_mib();
    assert!(peak < 1024.0, "peak memory {peak} MiB");
}
