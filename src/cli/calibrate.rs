//! `bkpbs calibrate`: the planner's HDV model against the HDVs SUMO drives under a profile.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use bkpbs::config::Config;
use bkpbs::train::longitudinal::{self, CalibrateSpec};

use super::scenario::load_config;

#[derive(Args)]
pub struct CalibrateArgs {
    /// HDV driver profile to calibrate against (see `bkpbs config --print --hdv-profile`).
    #[arg(long, default_value = "sumo-safe")]
    profile: String,
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
    /// Directory for calibration.json.
    #[arg(long)]
    out: PathBuf,
}

/// A checked calibration run.
pub struct Calibrate {
    config: Config,
    spec: CalibrateSpec,
    out: PathBuf,
}

impl CalibrateArgs {
    pub fn resolve(self) -> Result<Calibrate> {
        let profile = self.profile;
        let config = load_config(self.config.as_deref(), |c| c.hdv.profile = profile)?;
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
        })
    }
}

/// Runs the episodes, prints the report and writes `calibration.json`.
pub fn run(c: Calibrate) -> Result<()> {
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
