//! `bkpbs calibrate`: the planner's HDV model against the HDVs SUMO drives under a profile,
//! or on a scenario of the user's own (`--sumocfg`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use bkpbs::config::hdv::BUILT_IN;
use bkpbs::config::Config;
use bkpbs::report::calibration;
use bkpbs::train::longitudinal::{self, CalibrateSpec};

use super::scenario::{check_own_scenario, load_config};

#[derive(Args)]
pub struct CalibrateArgs {
    /// HDV driver profile to calibrate against (see `bkpbs config --print --hdv-profile`)
    /// [default: sumo-safe].
    #[arg(long)]
    profile: Option<String>,
    /// Episodes the IDM is fitted on.
    #[arg(long, default_value_t = 20, allow_negative_numbers = true)]
    episodes: u64,
    /// Further episodes (the next seeds) the models are evaluated on.
    #[arg(long, default_value_t = 10, allow_negative_numbers = true)]
    held_out: u64,
    /// First seed.
    #[arg(long, default_value_t = 5000, allow_negative_numbers = true)]
    seed_base: u64,
    /// TOML file with settings (α, λ, steps, profiles of one's own, …).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Directory for calibration.json (with --matrix: for the matrix's tables and figure).
    #[arg(long)]
    out: PathBuf,
    /// The generalisation matrix instead: an IDM fitted on each of --profiles, evaluated on
    /// each of them.
    #[arg(long, conflicts_with = "profile")]
    matrix: bool,
    /// Profiles of the matrix, comma-separated [default: every built-in profile].
    #[arg(long, requires = "matrix", value_name = "NAMES")]
    profiles: Option<String>,
    /// A SUMO configuration of your own (.sumocfg): its routes are the episodes' demand and its
    /// vehicle types the drivers (no profile), each merge region's HDVs sampled apart.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["profile", "matrix"])]
    sumocfg: Option<PathBuf>,
}

/// The profile calibrate runs when none is given.
const DEFAULT_PROFILE: &str = "sumo-safe";

/// A checked calibration run.
pub struct Calibrate {
    config: Config,
    spec: CalibrateSpec,
    out: PathBuf,
    /// The matrix's profiles, when asked for the matrix.
    matrix: Option<Vec<String>>,
}

impl CalibrateArgs {
    pub fn resolve(self) -> Result<Calibrate> {
        let (profile, sumocfg) = (self.profile.clone(), self.sumocfg.clone());
        let config = load_config(self.config.as_deref(), |c| {
            c.hdv.profile = profile.unwrap_or_else(|| DEFAULT_PROFILE.into());
            if sumocfg.is_some() {
                c.scenario.sumocfg = sumocfg;
            }
        })?;
        self.check_scenario(&config)?;
        let matrix: Option<Vec<String>> = match (self.matrix, &self.profiles) {
            (false, _) => None,
            (true, None) => Some(BUILT_IN.iter().map(|p| p.to_string()).collect()),
            (true, Some(text)) => Some(text.split(',').map(|p| p.trim().to_string()).collect()),
        };
        for p in matrix.iter().flatten() {
            let mut c = config.clone();
            c.hdv.profile = p.clone();
            c.validate().context("--profiles")?;
        }
        for (flag, n) in [("--episodes", self.episodes), ("--held-out", self.held_out)] {
            if !(1..=10_000).contains(&n) {
                anyhow::bail!("{flag} {n} must be 1 to 10000 episodes");
            }
        }
        bkpbs::io::ensure_writable_dir(&self.out)?;
        Ok(Calibrate {
            config,
            spec: CalibrateSpec {
                episodes: self.episodes,
                held_out: self.held_out,
                seed_base: self.seed_base,
            },
            out: self.out,
            matrix,
        })
    }

    /// A scenario of the user's own (`--sumocfg` or the config's `[scenario] sumocfg`) that can
    /// be read and has a region to plan, without the flags of the paper's drivers.
    fn check_scenario(&self, config: &Config) -> Result<()> {
        let Some(cfg) = &config.scenario.sumocfg else {
            return Ok(());
        };
        for (flag, given) in [
            ("--profile", self.profile.is_some()),
            ("--matrix", self.matrix),
        ] {
            if given {
                anyhow::bail!(
                    "{flag}: a scenario of your own ({}) brings its own drivers; leave {flag} out",
                    cfg.display()
                );
            }
        }
        check_own_scenario(config)
    }
}

/// Runs the episodes, prints the report and writes `calibration.json` (or the matrix).
pub fn run(c: Calibrate) -> Result<()> {
    if let Some(profiles) = &c.matrix {
        return run_matrix(&c, profiles);
    }
    let total = c.spec.episodes + c.spec.held_out;
    let mut done = 0;
    let calibration = longitudinal::calibrate(&c.config, &c.spec, |line| {
        done += 1;
        eprintln!("calibrate: {done}/{total} {line}");
    })?;
    print!("{}", calibration.to_text());
    let path = c.out.join("calibration.json");
    let text = serde_json::to_string_pretty(&calibration).expect("calibration serialises") + "\n";
    bkpbs::io::write_atomic(&path, text.as_bytes())
        .with_context(|| format!("cannot save the calibration in {}", c.out.display()))?;
    println!("calibration: {}", path.display());
    Ok(())
}

/// The generalisation matrix: tables (CSV, Markdown) and the heat map into `--out`.
fn run_matrix(c: &Calibrate, profiles: &[String]) -> Result<()> {
    let total = (c.spec.episodes + c.spec.held_out) * profiles.len() as u64;
    let mut done = 0;
    let m = longitudinal::matrix(&c.config, profiles, &c.spec, |line| {
        done += 1;
        eprintln!("calibrate: {done}/{total} {line}");
    })?;
    let (table, markdown) = (calibration::csv(&m), calibration::markdown(&m));
    let figure = calibration::figure(&m)?;
    let files: [(&str, &[u8]); 4] = [
        ("longitudinal_matrix.csv", table.as_bytes()),
        ("longitudinal_matrix.md", markdown.as_bytes()),
        ("longitudinal_matrix.png", &figure.png),
        ("longitudinal_matrix.svg", figure.svg.as_bytes()),
    ];
    print!("{markdown}");
    for (name, bytes) in files {
        let path = c.out.join(name);
        bkpbs::io::write_atomic(&path, bytes)?;
        println!("written: {}", path.display());
    }
    Ok(())
}
