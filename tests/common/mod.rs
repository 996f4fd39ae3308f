//! Helpers shared by the integration tests. Each test binary includes this module and uses only
//! part of it, hence the `dead_code` allowance.
#![allow(dead_code)]

pub mod flows;
pub mod netconvert;

use std::collections::BTreeMap;
use std::process::{Command, Output};

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use bkpbs::config::Config;
use bkpbs::episode::{self, EpisodeResult};
use bkpbs::predict::features::{Observation, CAV_NODES};

/// A default-length episode of `planner` on real SUMO at (α, λ, seed), the paper's other settings.
pub fn episode_of(planner: &str, alpha: f64, lambda: f64, seed: u64) -> EpisodeResult {
    let mut c = Config::default();
    c.scenario.alpha = alpha;
    c.scenario.lambda = lambda;
    c.scenario.seed = seed;
    episode::run(&c, planner).unwrap()
}

/// Random observations with a mix of present and absent nodes.
pub fn random_obs(rng: &mut ChaCha8Rng) -> Observation {
    let mut o = Observation::default();
    o.ego.lane = rng.gen_range(0..3);
    o.ego.speed = rng.gen_range(5.0..35.0);
    o.ego.accel = rng.gen_range(-3.0..3.0);
    o.ego.to_merge_end = rng.gen_range(-50.0..300.0);
    o.ego.from_ramp = rng.gen_bool(0.3);
    for n in &mut o.neighbours {
        if rng.gen_bool(0.7) {
            n.present = true;
            n.ds = rng.gen_range(-90.0..90.0);
            n.dy = rng.gen_range(-5.0..5.0);
            n.speed = rng.gen_range(0.0..35.0);
            n.is_cav = rng.gen_bool(0.5);
        }
    }
    let cavs = rng.gen_range(1..=CAV_NODES);
    for step in o.cavs.iter_mut() {
        for c in step.iter_mut().take(cavs) {
            c.present = true;
            c.ds = rng.gen_range(-60.0..60.0);
            c.dy = rng.gen_range(-5.0..5.0);
            c.speed = rng.gen_range(0.0..35.0);
        }
    }
    o
}

/// Writes `routes` as `NAME.rou.xml` and `NAME.sumocfg` into `dir`: the network `net` (in
/// `dir`) and those routes from 0 to `end` s at 0.2 s steps. Returns the configuration's path.
pub fn write_scenario(
    dir: &std::path::Path,
    name: &str,
    net: &std::path::Path,
    routes: &str,
    end: u32,
) -> std::path::PathBuf {
    std::fs::write(dir.join(format!("{name}.rou.xml")), routes).unwrap();
    let cfg = format!(
        r#"<configuration>
    <input><net-file value="{}"/><route-files value="{name}.rou.xml"/></input>
    <time><begin value="0"/><end value="{end}"/><step-length value="0.2"/></time>
</configuration>
"#,
        net.file_name().unwrap().to_str().unwrap()
    );
    let path = dir.join(format!("{name}.sumocfg"));
    std::fs::write(&path, cfg).unwrap();
    path
}

/// The `bkpbs` binary run with `args`.
pub fn bkpbs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bkpbs"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// `bkpbs episode --sumocfg cfg --planner planner --alpha alpha --seed seed --out out`: an
/// episode on a scenario of the user's own, over the scenario's interval.
pub fn scenario_episode(
    cfg: &std::path::Path,
    planner: &str,
    alpha: &str,
    seed: &str,
    out: &std::path::Path,
) -> Output {
    bkpbs(&[
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--planner",
        planner,
        "--alpha",
        alpha,
        "--seed",
        seed,
        "--out",
        out.to_str().unwrap(),
    ])
}

/// `bkpbs episode --sumocfg cfg --planner planner FLAGS… --out out`.
pub fn scenario_run(
    cfg: &std::path::Path,
    planner: &str,
    flags: &[&str],
    out: &std::path::Path,
) -> Output {
    let mut args = vec![
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--planner",
        planner,
    ];
    args.extend_from_slice(flags);
    args.extend(["--out", out.to_str().unwrap()]);
    bkpbs(&args)
}

/// [`scenario_run`], asserting that the episode succeeded with no vehicle in a controllable
/// collision; returns its `episode.csv` row. `name` labels the run in a failure.
pub fn scenario_run_safely(
    cfg: &std::path::Path,
    planner: &str,
    flags: &[&str],
    out: &std::path::Path,
    name: &str,
) -> BTreeMap<String, String> {
    let o = scenario_run(cfg, planner, flags, out);
    assert!(o.status.success(), "{name}: {}", stderr(&o));
    let rows = csv_rows(&std::fs::read(out.join("episode.csv")).unwrap());
    let ep = rows.into_iter().next().expect("one episode row");
    assert_eq!(ep["controllable_crashed"], "0", "{name}: {ep:?}");
    ep
}

/// What a run printed to stderr.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts that the run `o` failed with exactly one line on stderr, an `error: ` line, and no
/// panic; returns that line for the caller to check what it names. Every refusal of the binary
/// promises this shape, so each test states only what its own line must say.
pub fn one_error_line(o: &Output) -> String {
    let err = stderr(o);
    assert!(!o.status.success(), "should fail: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line expected, got: {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    lines[0].to_string()
}

/// Asserts [`one_error_line`] with exit code 1 (a refusal, not a signal), the line naming every
/// one of `words`.
pub fn refused_naming(o: &Output, words: &[&str]) {
    assert_eq!(o.status.code(), Some(1), "{}", stderr(o));
    let line = one_error_line(o);
    for w in words {
        assert!(line.contains(w), "'{w}' not in: {line}");
    }
}

/// The episode input directories (`bkpbs-episode-…`) in the temporary directory `tmp`.
pub fn input_dirs(tmp: &std::path::Path) -> Vec<std::path::PathBuf> {
    std::fs::read_dir(tmp)
        .unwrap()
        .flatten()
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with("bkpbs-episode-")
        })
        .map(|e| e.path())
        .collect()
}

/// Waits until `done` holds, polling; panics naming `what` after `seconds`.
pub fn wait_for(what: &str, seconds: u64, mut done: impl FnMut() -> bool) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(seconds);
    while !done() {
        assert!(
            std::time::Instant::now() < deadline,
            "timed out waiting for {what}"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// SUMO's shipped game scenarios (`$SUMO_HOME/tools/game`, Debian's sumo-tools), asserted
/// present: real scenarios nobody here wrote.
pub fn sumo_game_dir() -> std::path::PathBuf {
    let home = std::env::var("SUMO_HOME").unwrap_or_else(|_| "/usr/share/sumo".into());
    let game = std::path::Path::new(&home).join("tools/game");
    assert!(
        game.exists(),
        "SUMO's game scenarios (sumo-tools) are installed"
    );
    game
}

/// SUMO's `game` directory copied into `dir` as a user would (its configurations name files
/// beside them, and write outputs there); the copy's path.
pub fn game_copy(dir: &std::path::Path) -> std::path::PathBuf {
    let out = dir.join("game");
    let status = Command::new("cp")
        .args([
            "-r",
            sumo_game_dir().to_str().unwrap(),
            out.to_str().unwrap(),
        ])
        .status()
        .unwrap();
    assert!(status.success());
    out
}

/// Runs `cmd` (its output piped), killed with SIGKILL if it outlives `bound`; its output and
/// how long it took.
pub fn output_within(
    cmd: &mut Command,
    bound: std::time::Duration,
) -> (Output, std::time::Duration) {
    let start = std::time::Instant::now();
    let child = cmd
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let pid = child.id() as i32;
    let killer = std::thread::spawn(move || {
        while start.elapsed() < bound {
            std::thread::sleep(std::time::Duration::from_millis(50));
            // SAFETY: signal 0 only probes whether the process still exists.
            if unsafe { libc::kill(pid, 0) } != 0 {
                return;
            }
        }
        send_signal(pid, libc::SIGKILL);
    });
    let out = child.wait_with_output().unwrap();
    let took = start.elapsed();
    killer.join().unwrap();
    (out, took)
}

/// The files `names` of directories `a` and `b` are byte for byte the same (`what`: why they
/// should be, for the message).
pub fn assert_same_files(a: &std::path::Path, b: &std::path::Path, names: &[&str], what: &str) {
    for f in names {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f} differs {what}"
        );
    }
}

/// The episode files of a scenario episode (`bkpbs episode --sumocfg`) compared between runs.
pub const SCENARIO_FILES: [&str; 5] = [
    "episode.csv",
    "vehicles.csv",
    "regions.csv",
    "entries.csv",
    "collisions.csv",
];

/// Asserts that the run `o` succeeded, showing both its streams otherwise.
pub fn assert_ok(o: &Output) {
    assert!(
        o.status.success(),
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Sends `signal` to process `pid` (a negative `pid`: to its process group).
pub fn send_signal(pid: i32, signal: i32) {
    // SAFETY: plain kill(2) on a process the test started.
    assert_eq!(
        unsafe { libc::kill(pid, signal) },
        0,
        "kill({pid}, {signal})"
    );
}
/// A merge network with `main_lanes` lanes, one on-ramp per entry of `ramps_at` (x of the
/// merge), edge ids of its own, straight or bending (a gentle arc through the middle), built
/// by netconvert with its defaults (internal lanes) in `dir`.
/// A two-way road: two carriageways of equal width, neither of which joins the other (no merge).
pub const TWO_WAY_NET: &str = r#"<net><edge id="east"><lane id="east_0" index="0" length="100" shape="0,0 100,0"/></edge>
           <edge id="west"><lane id="west_0" index="0" length="100" shape="100,5 0,5"/></edge></net>"#;

pub fn netconvert_net(
    dir: &std::path::Path,
    main_lanes: u32,
    ramps_at: &[f64],
    curved: bool,
) -> std::path::PathBuf {
    let y = |x: f64| {
        if curved {
            0.0004 * (x - 300.0).powi(2)
        } else {
            0.0
        }
    };
    let mut nodes = String::from("<nodes>\n<node id=\"start\" x=\"0\" y=\"0\"/>\n");
    let mut edges = String::from("<edges>\n");
    let mut cons = String::from("<connections>\n");
    let mut from = "start".to_string();
    let mut prev: Option<String> = None;
    let shape = |x0: f64, x1: f64| {
        (0..=10)
            .map(|k| {
                let x = x0 + (x1 - x0) * k as f64 / 10.0;
                format!("{x:.2},{:.2}", y(x))
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut x = 0.0;
    for (k, &xm) in ramps_at.iter().enumerate() {
        let (a, m) = (format!("j{k}a"), format!("j{k}b"));
        nodes += &format!(
            "<node id=\"{a}\" x=\"{xm}\" y=\"{:.2}\"/>\n<node id=\"{m}\" x=\"{}\" y=\"{:.2}\"/>\n",
            y(xm),
            xm + 200.0,
            y(xm + 200.0)
        );
        nodes += &format!(
            "<node id=\"r{k}\" x=\"{}\" y=\"{:.2}\"/>\n",
            xm - 150.0,
            y(xm) - 60.0
        );
        let before = format!("road{k}");
        edges += &format!("<edge id=\"{before}\" from=\"{from}\" to=\"{a}\" numLanes=\"{main_lanes}\" speed=\"35\" width=\"3.6\" shape=\"{}\"/>\n", shape(x, xm));
        edges += &format!("<edge id=\"merge{k}\" from=\"{a}\" to=\"{m}\" numLanes=\"{}\" speed=\"35\" width=\"3.6\" shape=\"{}\"/>\n", main_lanes + 1, shape(xm, xm + 200.0));
        edges += &format!("<edge id=\"entry{k}\" from=\"r{k}\" to=\"{a}\" numLanes=\"1\" speed=\"30\" width=\"3.6\"/>\n");
        if let Some(p) = &prev {
            for i in 0..main_lanes {
                cons += &format!(
                    "<connection from=\"{p}\" to=\"{before}\" fromLane=\"{}\" toLane=\"{i}\"/>\n",
                    i + 1
                );
            }
        }
        for i in 0..main_lanes {
            cons += &format!(
                "<connection from=\"{before}\" to=\"merge{k}\" fromLane=\"{i}\" toLane=\"{}\"/>\n",
                i + 1
            );
        }
        cons += &format!(
            "<connection from=\"entry{k}\" to=\"merge{k}\" fromLane=\"0\" toLane=\"0\"/>\n"
        );
        prev = Some(format!("merge{k}"));
        from = m;
        x = xm + 200.0;
    }
    nodes += &format!(
        "<node id=\"end\" x=\"{}\" y=\"{:.2}\"/>\n</nodes>\n",
        x + 200.0,
        y(x + 200.0)
    );
    edges += &format!("<edge id=\"tail\" from=\"{from}\" to=\"end\" numLanes=\"{main_lanes}\" speed=\"35\" width=\"3.6\" shape=\"{}\"/>\n</edges>\n", shape(x, x + 200.0));
    for i in 0..main_lanes {
        cons += &format!(
            "<connection from=\"{}\" to=\"tail\" fromLane=\"{}\" toLane=\"{i}\"/>\n",
            prev.as_ref().unwrap(),
            i + 1
        );
    }
    cons += "</connections>\n";
    for (name, text) in [
        ("n.nod.xml", &nodes),
        ("n.edg.xml", &edges),
        ("n.con.xml", &cons),
    ] {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let out = dir.join("n.net.xml");
    let status = std::process::Command::new("netconvert")
        .current_dir(dir)
        .args([
            "--node-files",
            "n.nod.xml",
            "--edge-files",
            "n.edg.xml",
            "--connection-files",
            "n.con.xml",
            "--output-file",
            "n.net.xml",
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "netconvert failed on {}", dir.display());
    out
}

/// The rows of a CSV text as maps from column to field.
pub fn csv_rows(bytes: &[u8]) -> Vec<BTreeMap<String, String>> {
    let mut r = csv::Reader::from_reader(bytes);
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            header
                .iter()
                .cloned()
                .zip(rec.iter().map(String::from))
                .collect()
        })
        .collect()
}

/// Asserts `out` holds a line containing every one of `words`.
pub fn has_line(out: &str, words: &[&str]) {
    assert!(
        out.lines().any(|l| words.iter().all(|w| l.contains(w))),
        "no line with {words:?} in:\n{out}"
    );
}
