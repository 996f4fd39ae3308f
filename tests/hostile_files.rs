//! Files and counts that used to exhaust memory, block or spawn without limit (the second
//! hardening's finding 1, and the FIFO of finding 2): each is now one `error:` line and exit
//! 1, fast, under a memory bound the test sets. On the code before the bounded reader,
//! `/dev/zero` grew 1–2 GB/s until the bound killed the process (no `error:` line), and a
//! FIFO blocked until the time bound.

mod common;

use std::os::unix::process::CommandExt;
use std::process::{Command, Output};
use std::time::Duration;

use common::refused_naming;

/// Address space a run may take (bytes): far above what a refused run needs (libsumo loaded,
/// a few threads), far below what reading `/dev/zero` for seconds takes.
const MEMORY_BOUND: u64 = 4 << 30;
/// Wall time a refusal may take.
const TIME_BOUND: Duration = Duration::from_secs(10);

/// `bkpbs args`, its address space bounded, killed if it outlives the time bound.
fn bounded(args: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_bkpbs"));
    cmd.args(args);
    // SAFETY: setrlimit is async-signal-safe and touches only the child.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: MEMORY_BOUND,
                rlim_max: MEMORY_BOUND,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let (out, took) = common::output_within(&mut cmd, TIME_BOUND);
    assert!(took < TIME_BOUND, "{args:?} took {took:?}");
    out
}

#[test]
fn devices_and_fifos_are_refused_at_once_wherever_a_file_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("net.fifo");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo only creates the node.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let fifo = fifo.to_str().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let policy = dir.path().join("rl.toml");
    std::fs::write(&policy, "[rl]\npolicy = \"/dev/zero\"\n").unwrap();
    let policy = policy.to_str().unwrap();
    for (args, named) in [
        (vec!["network", "/dev/zero"], "a device"),
        (vec!["network", fifo], "a FIFO"),
        (
            vec!["episode", "--net", "/dev/zero", "--out", out],
            "a device",
        ),
        (
            vec!["episode", "--config", "/dev/zero", "--out", out],
            "a device",
        ),
        (vec!["episode", "--config", fifo, "--out", out], "a FIFO"),
        (
            vec![
                "episode",
                "--config",
                policy,
                "--planner",
                "rl-ppo",
                "--out",
                out,
            ],
            "a device",
        ),
        (
            vec!["campaign", "--config", "/dev/zero", "--out", out],
            "a device",
        ),
    ] {
        let o = bounded(&args);
        refused_naming(&o, &[named]);
    }
}

#[test]
fn oversized_counts_are_refused_before_anything_starts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rl");
    let out = out.to_str().unwrap();
    for (extra, named) in [
        (
            ["--episodes-per-update", "1000000000"],
            "--episodes-per-update",
        ),
        (["--eval-episodes", "100000000"], "--eval-episodes"),
        (["--threads", "100000"], "--threads: 100000"),
        (["--workers", "100000"], "--workers: 100000"),
    ] {
        let mut args = vec!["train-rl", "--out", out, "--steps", "100"];
        args.extend(extra);
        let o = bounded(&args);
        refused_naming(&o, &[named]);
    }
    let o = bounded(&["campaign", "--workers", "100000", "--out", out]);
    refused_naming(&o, &["--workers", "100000"]);
    let o = bounded(&["bench", "--threads", "1,100000"]);
    refused_naming(&o, &["--threads", "100000"]);
}

/// Networks SUMO would assert on or mis-measure (finding 6): NaN or infinite lane sizes, a NaN
/// shape point, an acceleration lane shorter than a car. Each is one `error:` line from
/// `network`, `episode`, `bench` and `collect`, before SUMO starts; the old code ran them
/// (exit 0).
#[test]
fn networks_of_impossible_lanes_are_refused() {
    let net = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/sumo_net/merge.net.xml"
    ))
    .unwrap();
    let acc = r#"id="acc_0" index="0" speed="40.00" length="180.00""#;
    assert!(net.contains(acc));
    let dir = tempfile::tempdir().unwrap();
    for (name, broken, named) in [
        (
            "nan-width",
            net.replacen(r#"width="4.50""#, r#"width="nan""#, 1),
            "width NaN",
        ),
        (
            "inf-length",
            net.replace(acc, &acc.replace("180.00", "inf")),
            "length inf",
        ),
        (
            "nan-shape",
            net.replacen("shape=\"150.00,", "shape=\"nan,", 1),
            "finite",
        ),
        (
            "short",
            net.replace(acc, &acc.replace("180.00", "0.10")),
            "shorter than one vehicle",
        ),
    ] {
        let path = dir.path().join(format!("{name}.net.xml"));
        std::fs::write(&path, broken).unwrap();
        let p = path.to_str().unwrap();
        refused_naming(&bounded(&["network", p]), &[named]);
        let out = dir.path().join(name);
        let o = bounded(&[
            "episode",
            "--net",
            p,
            "--steps",
            "5",
            "--out",
            out.to_str().unwrap(),
        ]);
        refused_naming(&o, &[named]);
        // Finding 4: `bench` printed no error line on such nets, `collect` aborted.
        refused_naming(&bounded(&["bench", "--net", p, "--steps", "5"]), &[named]);
        let data = dir.path().join(format!("{name}.bin"));
        let o = bounded(&[
            "collect",
            "--episodes",
            "1",
            "--steps",
            "5",
            "--net",
            p,
            "--out",
            data.to_str().unwrap(),
        ]);
        refused_naming(&o, &[named]);
    }
}
