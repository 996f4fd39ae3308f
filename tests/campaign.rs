//! Campaigns: statistics and grid logic, then whole campaigns of short episodes on real SUMO
//! through the binary (parallel = serial, resume after SIGKILL, shards merged, failures).

use std::collections::{BTreeMap, HashSet};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant, SystemTime};

use bkpbs::campaign::grid::{Cell, Grid, Shard};
use bkpbs::episode::metrics::mean;
use bkpbs::report::stats::{sample_std, t_975, Estimate};

mod common;

use bkpbs::sumo::version::BUILT;

use common::{assert_ok, bkpbs, one_error_line};

// ---------------------------------------------------------------- statistics, grid, shards

#[test]
fn mean_and_student_ci_match_hand_computed_values() {
    assert_eq!(mean([]), None);
    assert_eq!(mean([4.0]), Some(4.0));
    // 1..5: mean 3, s² = (4+1+0+1+4)/4 = 2.5, s/√n = √0.5 = 0.707107,
    // half-width = t(0.975, 4) · 0.707107 = 2.776445 · 0.707107 = 1.963243.
    let e = Estimate::of(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
    assert_eq!((e.n, e.mean), (5, 3.0));
    assert!((sample_std(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap() - 2.5f64.sqrt()).abs() < 1e-12);
    assert!((e.ci95.unwrap() - 1.963_243).abs() < 1e-6, "{e:?}");
    // Two values 2 and 4: s = √2, s/√2 = 1, half-width = t(0.975, 1) = 12.706205.
    let e = Estimate::of(&[2.0, 4.0]).unwrap();
    assert!((e.ci95.unwrap() - 12.706_205).abs() < 1e-6, "{e:?}");
    // One value: a mean without interval; none: nothing.
    assert_eq!(Estimate::of(&[7.5]).unwrap().ci95, None);
    assert_eq!(Estimate::of(&[]), None);
    // Identical values: zero width.
    assert_eq!(Estimate::of(&[0.0, 0.0, 0.0]).unwrap().ci95, Some(0.0));
}

#[test]
fn student_t_quantiles_small_and_large_samples() {
    for (df, t) in [
        (1, 12.706_205),
        (2, 4.302_653),
        (4, 2.776_445),
        (9, 2.262_157),
        (30, 2.042_272),
        // Beyond the table (reference values of t(0.975, df)).
        (31, 2.039_513),
        (40, 2.021_075),
        (60, 2.000_298),
        (120, 1.979_930),
    ] {
        assert!(
            (t_975(df) - t).abs() < 2e-6,
            "df {df}: {} vs {t}",
            t_975(df)
        );
    }
    assert!((t_975(100_000) - 1.959_964).abs() < 1e-4);
}

fn names(ps: &[&str]) -> Vec<String> {
    ps.iter().map(|p| p.to_string()).collect()
}

#[test]
fn grid_order_is_planner_alpha_lambda_seed_with_sorted_unique_values() {
    let g = Grid::new(
        &names(&["idm-mobil", "sumo", "idm-mobil"]),
        &[0.8, 0.4, 0.8],
        &[3000.0, 2500.0],
        10,
        2,
    );
    assert_eq!(g.planners, names(&["idm-mobil", "sumo"]));
    assert_eq!(
        (g.alphas.clone(), g.lambdas.clone()),
        (vec![0.4, 0.8], vec![2500.0, 3000.0])
    );
    assert_eq!(g.seeds, vec![10, 11]);
    let cells = g.cells();
    assert_eq!(cells.len(), g.len());
    assert_eq!(g.len(), 2 * 2 * 2 * 2);
    let c = |p: &str, alpha, lambda, seed| Cell {
        planner: p.into(),
        alpha,
        lambda,
        seed,
        hdv_profile: "sumo-safe".into(),
        predictor: None,
        scenario: None,
    };
    assert_eq!(cells[0], c("idm-mobil", 0.4, 2500.0, 10));
    assert_eq!(cells[1], c("idm-mobil", 0.4, 2500.0, 11));
    assert_eq!(cells[2], c("idm-mobil", 0.4, 3000.0, 10));
    assert_eq!(cells[4], c("idm-mobil", 0.8, 2500.0, 10));
    assert_eq!(cells[8], c("sumo", 0.4, 2500.0, 10));
    assert_eq!(cells[15], c("sumo", 0.8, 3000.0, 11));
    assert_eq!(
        cells[0].dir_name(),
        PathBuf::from("idm-mobil").join("a0.4_l2500_s10")
    );
    // HDV profiles are an axis after the planner; other drivers get a folder of their own.
    let g = g.with_profiles(&names(&["sumo-safe", "paper", "sumo-safe"]));
    let cells = g.cells();
    assert_eq!(g.len(), 2 * 2 * 2 * 2 * 2);
    assert_eq!(cells[7].hdv_profile, "sumo-safe");
    assert_eq!(cells[8].hdv_profile, "paper");
    assert_eq!(cells[8].planner, "idm-mobil");
    assert_eq!(
        cells[8].dir_name(),
        PathBuf::from("idm-mobil")
            .join("hdv-paper")
            .join("a0.4_l2500_s10")
    );
    assert_eq!(
        cells[8].to_string(),
        "idm-mobil α=0.4 λ=2500 seed=10 hdv=paper"
    );
}

#[test]
fn shards_split_the_grid_into_disjoint_interleaved_slices() {
    let n = 3;
    let shards: Vec<Shard> = (1..=n)
        .map(|k| format!("{k}/{n}").parse().unwrap())
        .collect();
    for position in 0..10 {
        let owners: Vec<usize> = shards
            .iter()
            .filter(|s| s.contains(position))
            .map(|s| s.index)
            .collect();
        assert_eq!(owners, vec![position % n + 1], "cell {position}");
    }
    assert!(Shard::ALL.contains(0) && Shard::ALL.contains(7));
    let s: Shard = " 2 / 4 ".parse().unwrap();
    assert_eq!((s.index, s.count), (2, 4));
    for bad in ["0/2", "3/2", "1/0", "2", "a/b", "1/2/3", ""] {
        let e = bad.parse::<Shard>().unwrap_err().to_string();
        assert!(e.contains(&format!("'{bad}'")), "{bad}: {e}");
    }
}

// ---------------------------------------------------------------- campaigns on real SUMO

const BIN: &str = env!("CARGO_BIN_EXE_bkpbs");

/// A grid of the tests: sumo and idm-mobil × α 0.4, 0.8 × λ 3000 × `seeds` seeds, `steps` steps.
fn grid<'a>(seeds: &'a str, steps: &'a str) -> [&'a str; 10] {
    [
        "--planners",
        "sumo,idm-mobil",
        "--alphas",
        "0.4,0.8",
        "--lambdas",
        "3000",
        "--seeds",
        seeds,
        "--steps",
        steps,
    ]
}

/// `bkpbs campaign --out out`, for the caller to add the grid, environment and pipes.
fn campaign_into(out: &Path) -> Command {
    let mut command = Command::new(BIN);
    command.arg("campaign").arg("--out").arg(out);
    command
}

fn campaign(out: &Path, extra: &[&str]) -> Output {
    campaign_into(out)
        .args(extra)
        .env_remove(bkpbs::campaign::worker::FAULT_ENV)
        .output()
        .expect("the binary runs")
}

/// `bkpbs report` of the campaign directories `dirs`, then `extra` (`--out` and the like).
fn report(dirs: &[&Path], extra: &[&str]) -> Output {
    let mut args = vec!["report"];
    args.extend(dirs.iter().map(|d| d.to_str().unwrap()));
    args.extend(extra);
    bkpbs(&args)
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The "already done: N" count of a campaign's first status line.
fn already_done(o: &Output) -> usize {
    let out = text(&o.stdout);
    let at = out.find("already done: ").expect("status line") + "already done: ".len();
    out[at..].split(';').next().unwrap().trim().parse().unwrap()
}

/// The unsharded tiny campaign with 2 workers, shared by the tests that compare against it.
fn reference() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        let o = campaign(
            d.path(),
            &[&grid("2", "60")[..], &["--workers", "2"]].concat(),
        );
        assert_ok(&o);
        d
    })
    .path()
}

#[test]
fn one_and_two_workers_give_byte_identical_results() {
    let two = reference();
    let d = tempfile::tempdir().unwrap();
    let o = campaign(
        d.path(),
        &[&grid("2", "60")[..], &["--workers", "1"]].concat(),
    );
    assert_ok(&o);
    for f in ["episodes.csv", "vehicles.csv"] {
        assert_eq!(read(&two.join(f)), read(&d.path().join(f)), "{f}");
    }
    let episodes = read(&two.join("episodes.csv"));
    let lines: Vec<&str> = episodes.lines().collect();
    assert_eq!(lines.len(), 1 + 8);
    assert!(
        lines[1].starts_with(&format!("sumo,0.4,3000,0,sumo-safe,{BUILT},60,")),
        "{}",
        lines[1]
    );
    assert!(
        lines[8].starts_with(&format!("idm-mobil,0.8,3000,1,sumo-safe,{BUILT},60,")),
        "{}",
        lines[8]
    );
    assert!(
        read(&two.join("vehicles.csv")).starts_with("planner,alpha,lambda,seed,hdv_profile,id,")
    );
    assert_eq!(read(&two.join("timings.csv")).lines().count(), 1 + 8);
    assert_eq!(read(&two.join("failures.csv")).lines().count(), 1);
    // The report ran at the end and printed its tables.
    let stdout = text(&o.stdout);
    assert!(
        stdout.contains("## Mean travel delay (s), λ = 3000 veh/h"),
        "{stdout}"
    );
    assert!(
        stdout.contains("## Controllable collision rate (%), idm-mobil"),
        "{stdout}"
    );
    assert!(
        stdout.contains("## Mean travel delay by entry (s)"),
        "{stdout}"
    );
    let by_entry = read(&d.path().join("report/delay_by_entry.csv"));
    assert!(by_entry.starts_with("planner,entry,inserted,arrived,crashed,mean_delay_s\nsumo,main,"));
    assert!(by_entry.contains("\nidm-mobil,ramp,"), "{by_entry}");
    for f in [
        "tables.md",
        "delay_l3000.csv",
        "collision_rate_sumo.csv",
        "collision_rate_idm-mobil.csv",
        "summary.csv",
        "collision_heatmap.png",
        "collision_heatmap.svg",
        "delay_vs_collision.png",
        "delay_vs_collision.svg",
    ] {
        assert!(d.path().join("report").join(f).is_file(), "{f}");
    }
    let png = std::fs::read(d.path().join("report/collision_heatmap.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
    // Quiet without a terminal: no progress bar on stderr.
    assert!(text(&o.stderr).is_empty(), "{}", text(&o.stderr));
}

#[test]
fn shards_merged_by_report_equal_the_unsharded_run() {
    let whole = reference();
    let d = tempfile::tempdir().unwrap();
    let (a, b, merged) = (d.path().join("a"), d.path().join("b"), d.path().join("m"));
    for (dir, k) in [(&a, "1/2"), (&b, "2/2")] {
        let o = campaign(
            dir,
            &[&grid("2", "60")[..], &["--workers", "1", "--shard", k]].concat(),
        );
        assert_ok(&o);
        assert!(
            text(&o.stdout).contains(&format!("shard {k}: 4;")),
            "{}",
            text(&o.stdout)
        );
    }
    let shard_rows = |p: &Path| read(&p.join("episodes.csv")).lines().count() - 1;
    assert_eq!((shard_rows(&a), shard_rows(&b)), (4, 4));
    let o = report(&[&a, &b], &["--out", merged.to_str().unwrap()]);
    assert_ok(&o);
    for f in ["episodes.csv", "vehicles.csv"] {
        assert_eq!(read(&whole.join(f)), read(&merged.join(f)), "{f}");
    }
    assert_eq!(
        read(&whole.join("report/tables.md")),
        read(&merged.join("report/tables.md"))
    );
    // The same shard twice is deduplicated; the merge still equals the whole.
    let o = report(&[&a, &a, &b], &["--out", merged.to_str().unwrap()]);
    assert_ok(&o);
    assert_eq!(
        read(&whole.join("episodes.csv")),
        read(&merged.join("episodes.csv"))
    );
    // A copy whose episode rows agree but one vehicle row differs is refused, naming the
    // file; one of the two was once kept without a word.
    let copy = d.path().join("a-copy");
    copy_tree(&a, &copy);
    let vehicles = read(&copy.join("vehicles.csv"));
    let mut lines: Vec<String> = vehicles.lines().map(String::from).collect();
    let last = lines.last_mut().unwrap();
    *last = format!("{},9", last.rsplit_once(',').unwrap().0);
    std::fs::write(copy.join("vehicles.csv"), lines.join("\n") + "\n").unwrap();
    let o = report(
        &[&a, &copy],
        &["--out", d.path().join("m2").to_str().unwrap()],
    );
    let line = one_error_line(&o);
    assert!(
        line.contains("different results") && line.contains("a-copy/vehicles.csv"),
        "{line}"
    );
}

/// Copies a directory tree (files and directories only).
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_tree(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}

#[test]
fn two_shards_running_at_once_into_one_directory_finish_every_cell() {
    // Each start once removed every temporary file in the directory, the other shard's
    // in-flight ones too, and about half the trials lost cells ("cannot write …/campaign.toml").
    for trial in 0..10 {
        let d = tempfile::tempdir().unwrap();
        let spawn = |k: &str| {
            campaign_into(d.path())
                .args(grid("2", "30"))
                .args(["--workers", "1", "--shard", k])
                .env_remove(bkpbs::campaign::worker::FAULT_ENV)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (spawn("1/2"), spawn("2/2"));
        for child in [a, b] {
            assert_ok(&child.wait_with_output().unwrap());
        }
        // The unsharded command finds every cell done.
        let o = campaign(d.path(), &grid("2", "30"));
        assert_ok(&o);
        assert_eq!(already_done(&o), 8, "trial {trial}: {}", text(&o.stdout));
    }
}

#[test]
fn a_corrupt_episode_file_does_not_count_as_finished() {
    let whole = reference();
    let d = tempfile::tempdir().unwrap();
    let args = [&grid("2", "60")[..], &["--workers", "1"]].concat();
    assert_ok(&campaign(d.path(), &args));
    // One cell's episode.csv garbled, another's holding a different cell's row.
    let cells = d.path().join("episodes/sumo");
    let (a, b) = (cells.join("a0.4_l3000_s0"), cells.join("a0.4_l3000_s1"));
    std::fs::write(a.join("episode.csv"), "garbage\n").unwrap();
    std::fs::copy(
        a.with_file_name("a0.8_l3000_s0").join("episode.csv"),
        b.join("episode.csv"),
    )
    .unwrap();
    let o = campaign(d.path(), &args);
    assert_ok(&o);
    assert_eq!(already_done(&o), 6, "{}", text(&o.stdout));
    for f in ["episodes.csv", "vehicles.csv"] {
        assert_eq!(read(&whole.join(f)), read(&d.path().join(f)), "{f}");
    }
}

#[test]
fn a_smaller_grid_is_refused_where_a_larger_one_was_recorded() {
    // It once rewrote episodes.csv, the report and campaign.toml for the small grid only: the
    // earlier episodes stayed on disk but were recorded nowhere.
    let d = tempfile::tempdir().unwrap();
    let big = [&grid("2", "30")[..], &["--workers", "1"]].concat();
    assert_ok(&campaign(d.path(), &big));
    let before = read(&d.path().join("episodes.csv"));
    let small = [
        &grid("1", "30")[..],
        &["--seed-base", "100", "--workers", "1"],
    ]
    .concat();
    let o = campaign(d.path(), &small);
    let line = one_error_line(&o);
    assert!(line.contains("8 episodes outside this grid"), "{line}");
    assert_eq!(read(&d.path().join("episodes.csv")), before);
    // The grid may grow.
    let more = [&grid("3", "30")[..], &["--workers", "1"]].concat();
    let o = campaign(d.path(), &more);
    assert_ok(&o);
    assert_eq!(already_done(&o), 8);
    // Results merged in by `report` (into the first directory) are recorded too: re-running
    // the directory's own campaign once dropped them without a word.
    let other = tempfile::tempdir().unwrap();
    assert_ok(&campaign(other.path(), &small));
    let o = report(&[d.path(), other.path()], &[]);
    assert_ok(&o);
    assert_eq!(
        read(&d.path().join("episodes.csv")).lines().count(),
        1 + 12 + 4
    );
    let o = campaign(d.path(), &more);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(err.contains("4 episodes outside this grid"), "{err}");
}

#[test]
fn report_refuses_damaged_episode_rows_naming_file_and_line() {
    let whole = reference();
    let original = read(&whole.join("episodes.csv"));
    let lines: Vec<&str> = original.lines().collect();
    let column = |name: &str| lines[0].split(',').position(|c| c == name).unwrap();
    let (rate, mean_delay) = (
        column("controllable_collision_rate"),
        column("mean_delay_s"),
    );
    let with_field = |line: usize, col: usize, value: &str| {
        let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        let mut f: Vec<&str> = lines[line].split(',').collect();
        f[col] = value;
        out[line] = f.join(",");
        out.join("\n") + "\n"
    };
    let duplicated = format!("{original}{}\n", lines[3]);
    for (damaged, expected) in [
        (duplicated, "line 10: cell"),
        (
            with_field(2, mean_delay, "NaN"),
            "line 3: mean_delay_s = 'NaN'",
        ),
        (
            with_field(2, mean_delay, "-999"),
            "line 3: mean_delay_s = '-999'",
        ),
        // Hardening II, finding 8: this was reported as "± inf".
        (
            with_field(2, mean_delay, "1e308"),
            "line 3: mean_delay_s = '1e308' is above 1e15",
        ),
        (
            with_field(4, rate, "7.5"),
            "line 5: controllable_collision_rate = '7.5'",
        ),
    ] {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("episodes.csv"), &damaged).unwrap();
        std::fs::copy(whole.join("vehicles.csv"), d.path().join("vehicles.csv")).unwrap();
        let line = one_error_line(&report(&[d.path()], &[]));
        assert!(
            line.contains("episodes.csv") && line.contains(expected),
            "{line}"
        );
    }
}

#[test]
fn report_refuses_to_merge_campaigns_of_other_settings_unless_told() {
    let d = tempfile::tempdir().unwrap();
    let (a, b, m) = (d.path().join("a"), d.path().join("b"), d.path().join("m"));
    // One sumo cell per λ, from `seed_base`, of `steps` steps.
    let tiny = |seed_base: &'static str, steps: &'static str| {
        [
            "--planners",
            "sumo",
            "--alphas",
            "0.4",
            "--seeds",
            "1",
            "--seed-base",
            seed_base,
            "--steps",
            steps,
        ]
    };
    assert_ok(&campaign(&a, &tiny("0", "30")));
    assert_ok(&campaign(&b, &tiny("5", "40")));
    let into_m = |extra: &[&str]| {
        report(
            &[&a, &b],
            &[&["--out", m.to_str().unwrap()][..], extra].concat(),
        )
    };
    let line = one_error_line(&into_m(&[]));
    assert!(
        line.contains("campaign.steps") && line.contains("--allow-mixed"),
        "{line}"
    );
    assert!(!m.join("episodes.csv").exists());
    assert_ok(&into_m(&["--allow-mixed"]));
    // Two λ per campaign by default: four episodes and the header.
    assert_eq!(read(&m.join("episodes.csv")).lines().count(), 5);
}

/// Processes whose environment holds `marker` (the campaign's workers inherit it).
fn processes_marked(marker: &str) -> Vec<u32> {
    let needle = format!("BKPBS_TEST_MARK={marker}");
    std::fs::read_dir("/proc")
        .unwrap()
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            std::fs::read(format!("/proc/{pid}/environ"))
                .map(|env| env.split(|&b| b == 0).any(|v| v == needle.as_bytes()))
                .unwrap_or(false)
        })
        .collect()
}

#[test]
fn workers_die_with_a_campaign_killed_at_any_moment() {
    // Killed in its first milliseconds, the campaign once left its workers running their
    // episodes to the end; they must die with it, however early the kill.
    for delay_ms in [0u64, 5, 10, 20, 50, 100] {
        let d = tempfile::tempdir().unwrap();
        let marker = format!("{}-{delay_ms}", std::process::id());
        let mut child = campaign_into(d.path())
            // Episodes long enough that an orphan would still run at the deadline.
            .args(grid("2", "100000"))
            .args(["--workers", "2"])
            .env("BKPBS_TEST_MARK", &marker)
            .env_remove(bkpbs::campaign::worker::FAULT_ENV)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        child.kill().unwrap();
        child.wait().unwrap();
        // The kernel kills the workers at once; give it a moment.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
        while !processes_marked(&marker).is_empty() && std::time::Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        assert_eq!(
            processes_marked(&marker),
            Vec::<u32>::new(),
            "killed after {delay_ms} ms"
        );
    }
}

#[test]
fn a_campaign_stopped_by_ctrl_c_keeps_what_finished_and_resumes() {
    // Ctrl-C reaches the campaign and its workers (one process group): the finished cells are
    // collected, the running one stays unfinished (not failed), no worker is left.
    let (d, tmpdir) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let out = d.path();
    let marker = format!("{}-ctrl-c", std::process::id());
    let args = idm_mobil_cells("3", "1");
    let child = campaign_into(out)
        .args(&args)
        .env(bkpbs::campaign::worker::FAULT_ENV, "hang:2")
        .env("BKPBS_TEST_MARK", &marker)
        .env("TMPDIR", tmpdir.path())
        .process_group(0)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_for("two finished cells", 60, || finished(out).len() == 2);
    std::thread::sleep(Duration::from_millis(300));
    common::send_signal(-(child.id() as i32), libc::SIGINT);
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(
        err.lines()
            .last()
            .unwrap()
            .starts_with("error: interrupted by SIGINT: 2 of 3"),
        "{err}"
    );
    assert_eq!(read(&out.join("episodes.csv")).lines().count(), 1 + 2);
    assert!(!out
        .join("episodes/idm-mobil/a0.5_l3000_s2/error.txt")
        .exists());
    assert_eq!(processes_marked(&marker), Vec::<u32>::new());
    assert_eq!(common::input_dirs(tmpdir.path()), Vec::<PathBuf>::new());
    let o = campaign(out, &args);
    assert_ok(&o);
    assert_eq!(already_done(&o), 2);
}

#[test]
fn sigterm_to_the_campaign_alone_stops_its_workers_and_removes_their_input() {
    // Only the campaign gets the signal (`kill PID`); it passes it on to its workers, which
    // end their episodes and remove their input directories.
    let (d, tmpdir) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let marker = format!("{}-sigterm", std::process::id());
    let child = campaign_into(d.path())
        .args(["--planners", "sumo", "--alphas", "0.5", "--lambdas", "3000"])
        .args(["--seeds", "2", "--steps", "100000", "--workers", "2"])
        .env_remove(bkpbs::campaign::worker::FAULT_ENV)
        .env("BKPBS_TEST_MARK", &marker)
        .env("TMPDIR", tmpdir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_for("both workers' input", 60, || {
        common::input_dirs(tmpdir.path()).len() == 2
    });
    common::send_signal(child.id() as i32, libc::SIGTERM);
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(143), "{}", text(&o.stderr));
    assert_eq!(processes_marked(&marker), Vec::<u32>::new());
    assert_eq!(common::input_dirs(tmpdir.path()), Vec::<PathBuf>::new());
    assert_eq!(read(&d.path().join("failures.csv")).lines().count(), 1 + 2);
}

/// Finished cells (their episode.csv) and modification times.
fn finished(out: &Path) -> BTreeMap<PathBuf, SystemTime> {
    let mut m = BTreeMap::new();
    let Ok(planners) = std::fs::read_dir(out.join("episodes")) else {
        return m;
    };
    for p in planners.flatten() {
        for c in std::fs::read_dir(p.path()).unwrap().flatten() {
            let f = c.path().join("episode.csv");
            if let Ok(meta) = std::fs::metadata(&f) {
                m.insert(f, meta.modified().unwrap());
            }
        }
    }
    m
}

#[test]
fn killed_campaign_resumes_without_losing_or_duplicating_episodes() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("c");
    let args = grid("6", "150");
    let total = 2 * 2 * 6;
    // The campaign and its workers in a process group of their own, killed together.
    let mut child = campaign_into(&out)
        .args(args)
        .args(["--workers", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .process_group(0)
        .spawn()
        .unwrap();
    let start = Instant::now();
    while finished(&out).len() < 3 {
        assert!(start.elapsed() < Duration::from_secs(60), "no progress");
        std::thread::sleep(Duration::from_millis(5));
    }
    // SAFETY: signalling the process group we created.
    unsafe {
        libc::kill(-(child.id() as i32), libc::SIGKILL);
    }
    child.wait().unwrap();
    let before = finished(&out);
    assert!(
        before.len() >= 3 && before.len() < total,
        "killed after {} of {total}",
        before.len()
    );
    assert!(
        !out.join("episodes.csv").exists(),
        "killed before collecting"
    );

    let o = campaign(&out, &[&args[..], &["--workers", "2"]].concat());
    assert_ok(&o);
    assert_eq!(already_done(&o), before.len(), "{}", text(&o.stdout));
    let after = finished(&out);
    assert_eq!(after.len(), total);
    for (f, t) in &before {
        assert_eq!(after[f], *t, "{} was run again", f.display());
    }
    // Exactly one row per episode, in grid order, and every vehicle row once.
    let episodes = read(&out.join("episodes.csv"));
    let rows: Vec<&str> = episodes.lines().skip(1).collect();
    assert_eq!(rows.len(), total);
    let keys: Vec<String> = rows
        .iter()
        .map(|r| r.split(',').take(4).collect::<Vec<_>>().join(","))
        .collect();
    assert_eq!(keys.iter().collect::<HashSet<_>>().len(), total);
    assert_eq!(keys[0], "sumo,0.4,3000,0");
    assert_eq!(keys[total - 1], "idm-mobil,0.8,3000,5");
    // vehicles.csv has a row per scheduled vehicle, inserted or not.
    let header: Vec<&str> = episodes.lines().next().unwrap().split(',').collect();
    let scheduled_at = header.iter().position(|h| *h == "scheduled").unwrap();
    let scheduled: usize = rows
        .iter()
        .map(|r| {
            r.split(',')
                .nth(scheduled_at)
                .unwrap()
                .parse::<usize>()
                .unwrap()
        })
        .sum();
    assert_eq!(
        read(&out.join("vehicles.csv")).lines().count() - 1,
        scheduled
    );
    // A third run finds everything done and runs nothing.
    let o = campaign(&out, &[&args[..], &["--workers", "2"]].concat());
    assert_ok(&o);
    assert_eq!(already_done(&o), total);
    assert_eq!(read(&out.join("episodes.csv")), episodes);
}

#[test]
fn failed_episodes_are_recorded_others_go_on_and_a_rerun_repairs_them() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path();
    let args = idm_mobil_cells("4", "1");
    let with_fault = |fault: &str| {
        campaign_into(out)
            .args(&args)
            .env(bkpbs::campaign::worker::FAULT_ENV, fault)
            .output()
            .unwrap()
    };
    let cell = out.join("episodes/idm-mobil/a0.5_l3000_s1");
    // The worker process dies on seed 1: that episode fails, a new worker runs seeds 2 and 3.
    let o = with_fault("exit:1");
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert_eq!(
        err.lines().last().unwrap(),
        format!(
            "error: 1 of 4 episodes failed (see {})",
            out.join("failures.csv").display()
        ),
        "{err}"
    );
    assert_eq!(finished(out).len(), 3);
    assert!(read(&cell.join("error.txt")).contains("worker process died"));
    let failures = read(&out.join("failures.csv"));
    assert_eq!(failures.lines().count(), 2, "{failures}");
    assert!(failures
        .lines()
        .nth(1)
        .unwrap()
        .starts_with("idm-mobil,0.5,3000,1,"));
    assert_eq!(read(&out.join("episodes.csv")).lines().count(), 1 + 3);

    // A planner panic is caught in the worker and recorded; only the failed cell is retried.
    let o = with_fault("panic:1");
    assert!(!o.status.success());
    assert_eq!(already_done(&o), 3);
    let note = read(&cell.join("error.txt"));
    assert!(
        note.contains("panicked") && note.contains("injected planner fault"),
        "{note}"
    );

    // Without the fault the rerun completes the grid.
    let o = campaign(out, &args);
    assert_ok(&o);
    assert_eq!(already_done(&o), 3);
    assert!(!cell.join("error.txt").exists());
    assert_eq!(read(&out.join("failures.csv")).lines().count(), 1);
    assert_eq!(read(&out.join("episodes.csv")).lines().count(), 1 + 4);
}

#[test]
fn an_episode_over_the_timeout_is_stopped_and_recorded_as_failed() {
    // Without a limit, one hanging episode held its worker, and so the campaign, forever.
    let d = tempfile::tempdir().unwrap();
    let out = d.path();
    let args = [&idm_mobil_cells("3", "2")[..], &["--episode-timeout", "4"]].concat();
    let started = std::time::Instant::now();
    let o = campaign_into(out)
        .args(&args)
        .env(bkpbs::campaign::worker::FAULT_ENV, "hang:1")
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        started.elapsed().as_secs() < 120,
        "the hanging episode was not stopped"
    );
    assert_eq!(finished(out).len(), 2);
    let failures = read(&out.join("failures.csv"));
    let rows: Vec<&str> = failures.lines().skip(1).collect();
    assert_eq!(rows.len(), 1, "{failures}");
    assert!(rows[0].starts_with("idm-mobil,0.5,3000,1,"), "{failures}");
    assert!(rows[0].contains("episode timeout of 4 s"), "{failures}");
    // The limit is not a result setting: campaign.toml does not record it, and a rerun
    // without the fault finishes the cell.
    assert!(!read(&out.join("campaign.toml")).contains("timeout"));
    let o = campaign(out, &args);
    assert_ok(&o);
    assert_eq!(already_done(&o), 2);
}

/// One idm-mobil cell (α 0.5, λ 3000) × `seeds` seeds of 40 steps, on `workers` workers.
fn idm_mobil_cells(seeds: &'static str, workers: &'static str) -> Vec<&'static str> {
    vec![
        "--planners",
        "idm-mobil",
        "--alphas",
        "0.5",
        "--lambdas",
        "3000",
        "--seeds",
        seeds,
        "--steps",
        "40",
        "--workers",
        workers,
    ]
}

/// Runs the binary and checks for one `error:` line naming `culprit` and a non-zero exit.
fn assert_clear_failure(args: &[&str], culprit: &str) {
    let line = one_error_line(&bkpbs(args));
    assert!(
        line.contains(culprit),
        "{args:?}: '{culprit}' not in: {line}"
    );
}

#[test]
fn bad_input_ends_with_one_error_line_and_nothing_written() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("c");
    let o = out.to_str().unwrap();
    let run = |extra: &[&str], culprit: &str| {
        assert_clear_failure(&[&["campaign", "--out", o][..], extra].concat(), culprit);
        assert!(!out.exists(), "{extra:?} wrote {}", out.display());
    };
    run(&["--planners", "sumo,bk-pbz"], "bk-pbz");
    run(&["--planners", "sumo,bk-pbz"], "--planners");
    run(&["--alphas", "0.4,1.5"], "1.5");
    run(&["--alphas", "0.4,1.5"], "[0, 1]");
    run(&["--alphas", "0.4,abc"], "abc");
    run(&["--lambdas=-5"], "-5");
    run(&["--lambdas", "2500,-5"], "λ -5");
    run(&["--shard", "3/2"], "3/2");
    run(&["--shard", "1-2"], "1-2");
    run(&["--episode-timeout", "0"], "--episode-timeout");
    run(&["--episode-timeout", "-3"], "(0, 604800]");
    run(&["--episode-timeout", "1e9"], "1000000000");
    run(&["--episode-timeout", "nan"], "--episode-timeout");
    run(&["--seeds", "0"], "--seeds");
    run(&["--workers", "0"], "--workers");
    let cfg = d.path().join("c.toml");
    std::fs::write(&cfg, "[campaign]\nalphas = [0.2, 2.0]\n").unwrap();
    run(&["--config", cfg.to_str().unwrap()], "campaign.alphas in");
    std::fs::write(&cfg, "[campaign]\nalhpas = [0.2]\n").unwrap();
    run(&["--config", cfg.to_str().unwrap()], "alhpas");
    std::fs::write(&cfg, "[scenario]\nalpha = 0.3\n").unwrap();
    run(&["--config", cfg.to_str().unwrap()], "campaign.alphas");
    std::fs::write(&cfg, "[idm]\naccel = -1.0\n").unwrap();
    run(&["--config", cfg.to_str().unwrap()], "idm.accel");
    assert_clear_failure(&["report", d.path().join("none").to_str().unwrap()], "none");
}

#[test]
fn a_campaign_file_sets_the_grid_and_scenario_and_a_changed_scenario_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("c");
    let cfg = d.path().join("c.toml");
    std::fs::write(
        &cfg,
        "[campaign]\nplanners = [\"idm-mobil\"]\nalphas = [0.5]\nlambdas = [2500.0]\nseeds = 1\n\
         seed_base = 7\nsteps = 30\nworkers = 1\n\n[idm]\ntime_headway = 1.2\n",
    )
    .unwrap();
    let o = campaign(&out, &["--config", cfg.to_str().unwrap()]);
    assert_ok(&o);
    let episodes = read(&out.join("episodes.csv"));
    assert!(episodes
        .lines()
        .nth(1)
        .unwrap()
        .starts_with(&format!("idm-mobil,0.5,2500,7,sumo-safe,{BUILT},30,")));
    // The saved settings reproduce the campaign.
    let saved = read(&out.join("campaign.toml"));
    assert!(
        saved.contains("time_headway = 1.2") && !saved.contains("workers"),
        "{saved}"
    );
    // Same out, different scenario: refused, nothing touched.
    std::fs::write(&cfg, "[idm]\ntime_headway = 1.0\n").unwrap();
    let o = campaign(&out, &["--config", cfg.to_str().unwrap()]);
    let err = text(&o.stderr);
    assert!(
        !o.status.success() && err.contains("idm.time_headway"),
        "{err}"
    );
    assert_eq!(read(&out.join("campaign.toml")), saved);
}

#[test]
fn campaign_trajectories_are_written_per_cell_and_are_no_setting() {
    let d = tempfile::tempdir().unwrap();
    let args = idm_mobil_cells("2", "2");
    assert_ok(&campaign(
        d.path(),
        &[&args[..], &["--trajectories"]].concat(),
    ));
    for seed in 0..2 {
        let cell = d
            .path()
            .join(format!("episodes/idm-mobil/a0.5_l3000_s{seed}"));
        let text = read(&cell.join("trajectories.csv"));
        assert!(text.starts_with("time,id,type,origin"), "{text}");
    }
    let settings = read(&d.path().join("campaign.toml"));
    assert!(!settings.contains("trajectories"), "{settings}");
    // Outputs do not change results: the same grid without them finds every cell done.
    let o = campaign(d.path(), &args);
    assert_ok(&o);
    assert_eq!(already_done(&o), 2);
    // `--plots` draws every finished cell that has trajectories.
    let o = campaign(d.path(), &[&args[..], &["--plots"]].concat());
    assert_ok(&o);
    assert!(
        text(&o.stdout).contains("speed field of 2 cells"),
        "{}",
        text(&o.stdout)
    );
    let cell = d.path().join("episodes/idm-mobil/a0.5_l3000_s1");
    for f in [
        "time_space.png",
        "time_space.svg",
        "speed_field.png",
        "speed_field.svg",
    ] {
        assert!(cell.join(f).is_file(), "{f}");
    }
    let o = campaign(
        d.path(),
        &[&args[..], &["--plots", "--trajectories-format", "fcd"]].concat(),
    );
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("--plots"), "{}", text(&o.stderr));
}

#[test]
fn hdv_profiles_are_a_grid_axis_recorded_in_every_row() {
    let d = tempfile::tempdir().unwrap();
    let args = [
        &idm_mobil_cells("2", "2")[..],
        &["--hdv-profiles", "sumo-safe,paper"],
    ]
    .concat();
    let o = campaign(d.path(), &args);
    assert_ok(&o);
    assert!(
        text(&o.stdout).contains("1 planners × 2 HDV profiles × 1 α × 1 λ × 2 seeds = 4 episodes"),
        "{}",
        text(&o.stdout)
    );
    let episodes = read(&d.path().join("episodes.csv"));
    let profiles: Vec<&str> = episodes
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(4).unwrap())
        .collect();
    assert_eq!(profiles, ["sumo-safe", "sumo-safe", "paper", "paper"]);
    let vehicles = read(&d.path().join("vehicles.csv"));
    assert!(vehicles.lines().skip(1).any(|l| l.contains(",paper,")));
    assert!(d
        .path()
        .join("episodes/idm-mobil/hdv-paper/a0.5_l3000_s1/episode.csv")
        .is_file());
    let tables = read(&d.path().join("report/tables.md"));
    assert!(tables.contains("| idm-mobil (paper) |"), "{tables}");
    assert!(d
        .path()
        .join("report/collision_rate_idm-mobil_paper.csv")
        .is_file());
    // The grid grows by a profile (dropping one would be refused); an unknown one is refused
    // naming the flag.
    let grown = ["--hdv-profiles", "sumo-safe,paper,krauss"];
    let o = campaign(d.path(), &[&idm_mobil_cells("2", "2")[..], &grown].concat());
    assert_ok(&o);
    assert_eq!(already_done(&o), 4);
    let dropped = ["--hdv-profiles", "paper,krauss"];
    let o = campaign(
        d.path(),
        &[&idm_mobil_cells("2", "2")[..], &dropped].concat(),
    );
    assert!(
        text(&o.stderr).contains("outside this grid"),
        "{}",
        text(&o.stderr)
    );
    assert_clear_failure(
        &[
            &["campaign", "--out", d.path().to_str().unwrap()][..],
            &["--hdv-profiles", "paper,reckless"],
        ]
        .concat(),
        "reckless",
    );
}
