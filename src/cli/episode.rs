//! `bkpbs episode`: one episode, its CSV files and a one-line summary.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use bkpbs::config::{Config, PredictorKind, Scenario};
use bkpbs::controller::PlannerKind;
use bkpbs::episode;
use bkpbs::sumo::files as sumo_files;

use super::scenario::{ScenarioArgs, TrajectoryArgs};

#[derive(Args)]
pub struct EpisodeArgs {
    /// Controller of the CAVs.
    #[arg(long, value_enum, default_value_t = PlannerKind::BkPbs)]
    planner: PlannerKind,
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Directory for the CSV files [default: out/<planner>_a<α>_l<λ>_s<seed>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// HDV predictor of the planners (overrides predictor.kind of the config).
    #[arg(long, value_enum)]
    predictor: Option<PredictorKind>,
    /// Also write trace.jsonl: per step and CAV, SUMO's state, the maneuver sent and its source,
    /// the planned trajectory and the predictions it was checked against (see `bkpbs explain`;
    /// empty with `--planner sumo`, which leaves the CAVs to SUMO).
    #[arg(long)]
    trace: bool,
    #[command(flatten)]
    trajectories: TrajectoryArgs,
    /// Show the episode live in SUMO's own sumo-gui (same results; needs a display): CAVs
    /// green on their plan, orange changing lanes, red when the shield took over.
    #[arg(long)]
    gui: bool,
    /// sumo-gui's pause per step in ms [default: real time]; implies --gui.
    #[arg(long, value_name = "MS", allow_negative_numbers = true)]
    gui_delay: Option<f64>,
}

/// A checked episode: the planner exists for this configuration and the output place is known.
pub struct Episode {
    config: Config,
    planner: PlannerKind,
    out: PathBuf,
    trace: bool,
}

impl EpisodeArgs {
    /// Checks the configuration and the planner before SUMO starts.
    pub fn resolve(self) -> Result<Episode> {
        let predictor = self.predictor;
        let trajectories = self.trajectories.format();
        let (gui, gui_delay) = (self.gui, self.gui_delay);
        let config = self.scenario.resolve_with(|c| {
            if let Some(kind) = predictor {
                c.predictor.kind = kind;
            }
            if let Some(format) = trajectories {
                c.output.trajectories = format;
            }
            c.sumo.gui |= gui || gui_delay.is_some();
            c.sumo.gui_delay_ms = gui_delay.or(c.sumo.gui_delay_ms);
            c.output.progress = true;
        })?;
        if let Some(why) = config.sumo.gui.then(sumo_files::gui_unavailable).flatten() {
            anyhow::bail!("cannot show the episode: {why}");
        }
        self.planner.check(&config)?;
        let out = self
            .out
            .unwrap_or_else(|| default_out(self.planner, &config.scenario));
        bkpbs::io::ensure_writable_dir(&out)?;
        Ok(Episode {
            config,
            planner: self.planner,
            out,
            trace: self.trace,
        })
    }
}

/// `out/<planner>_a<α>_l<λ>_s<seed>`: runs of different settings never overwrite each other.
fn default_out(planner: PlannerKind, s: &Scenario) -> PathBuf {
    PathBuf::from(format!(
        "out/{}_a{}_l{}_s{}",
        planner, s.alpha, s.lambda, s.seed
    ))
}

/// The error of a failed episode; when SUMO said why, all it printed is kept as `sumo.log` in
/// `out` (the error names the file).
fn keep_sumo_log(err: episode::EpisodeError, out: &std::path::Path) -> anyhow::Error {
    let path = out.join("sumo.log");
    match err.sumo_log() {
        Some(log) if bkpbs::io::write_atomic(&path, log.as_bytes()).is_ok() => {
            anyhow::anyhow!("{err} (SUMO's output: {})", path.display())
        }
        _ => err.into(),
    }
}

/// Writes `models.toml`: the learned files the episode used and what they were trained on;
/// warns of those trained on another scenario.
fn write_models_record(e: &Episode) -> Result<()> {
    let used = episode::models_used::models_used(&e.config, e.planner.name())?;
    let path = e.out.join(episode::models_used::MODELS_RECORD);
    bkpbs::io::write_atomic(&path, episode::models_used::models_toml(&used).as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    for line in episode::models_used::other_scenario_warnings(&e.config, &used) {
        eprintln!("{line}");
    }
    Ok(())
}

/// What an episode on the user's scenario prints: its summary, the options bkpbs set, its
/// regions' warnings, trajectories and traces.
fn print_scenario(e: &Episode, r: &episode::sumocfg::ScenarioResult) {
    print_scenario_summary(e, &r.summary);
    println!("SUMO options bkpbs set: {}", r.sumo_options.join(" "));
    for note in &r.sumo_notes {
        println!("{note}");
    }
    for line in r.no_ramp_traffic_warnings() {
        eprintln!("{line}");
    }
    for (region, _) in &r.trajectories {
        let d = episode::sumocfg::region_dir(&e.out, region);
        println!(
            "trajectories of region {region}: {} (`bkpbs plot {}` draws them)",
            d.display(),
            d.display()
        );
    }
    for (region, _) in &r.traces {
        let d = episode::sumocfg::region_dir(&e.out, region);
        println!(
            "trace of region {region}: {} (`bkpbs explain {}` tells the story of each collision)",
            d.join(episode::trace::TRACE_FILE).display(),
            e.out.display()
        );
    }
}

/// The one-line summary of an episode on the user's scenario.
fn print_scenario_summary(e: &Episode, s: &episode::summary::Summary) {
    let secs = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.2} s"));
    let cfg = e.config.scenario.sumocfg.as_ref().expect("a scenario");
    let cav_types = s.cav_types.as_deref().unwrap_or_default();
    let cavs = if cav_types.is_empty() {
        format!("α={}", s.alpha)
    } else {
        format!("CAVs of type {cav_types}")
    };
    let share = s.share.clone().unwrap_or_default();
    let time_loss = s.time_loss();
    println!(
        "{} {cavs} seed={} on {} (regions {}): inserted {} ({} CAVs, share {:.3}), never \
         inserted {}, in a region {}, arrived {}, crashed {} (controllable {}), mean timeLoss {}, mean delay in \
         its region {}",
        s.planner,
        s.seed,
        cfg.display(),
        s.regions.as_deref().unwrap_or_default(),
        s.inserted,
        s.inserted_cav,
        share.cav_share,
        s.never_inserted,
        share.in_region,
        s.arrived,
        s.crashed,
        s.controllable_crashed,
        secs(time_loss.mean_time_loss_s),
        secs(time_loss.mean_region_delay_s)
    );
}

/// Runs the episode, writes its files and prints its summary and where the files are.
pub fn run(e: Episode) -> Result<()> {
    let mut config = e.config.clone();
    config.output.trace = e.trace;
    for line in bkpbs::sumo::frame::scenario_left_to_sumo(&config.scenario)? {
        println!("{line}");
    }
    let ran =
        episode::ran::run(&config, e.planner.name()).map_err(|err| keep_sumo_log(err, &e.out))?;
    ran.write(&e.out).with_context(|| {
        format!(
            "episode finished but its results could not be saved in {}",
            e.out.display()
        )
    })?;
    write_models_record(&e)?;
    match &ran {
        episode::Ran::Demand(r) => print_demand(&e, r),
        episode::Ran::Scenario(r) => print_scenario(&e, r),
    }
    println!("results: {}", e.out.join("episode.csv").display());
    Ok(())
}

/// What an episode on the paper's demand prints: its summary, where its trajectories and
/// trace are.
fn print_demand(e: &Episode, result: &episode::EpisodeResult) {
    let m = &result.summary;
    let system_delay = m.system.as_ref().and_then(|s| s.system_delay_s);
    println!(
        "{} α={} λ={} seed={}: inserted {}, arrived {}, crashed {} (controllable rate {:.4}), system delay {} s, mean delay (arrived) {} s",
        m.planner,
        m.alpha,
        m.lambda.unwrap_or_default(),
        m.seed,
        m.inserted,
        m.arrived,
        m.crashed,
        m.controllable_collision_rate.unwrap_or_default(),
        system_delay.map_or("n/a".into(), |d| format!("{d:.2}")),
        m.travel().mean_delay_s.map_or("n/a".into(), |d| format!("{d:.2}"))
    );
    if let Some(t) = &result.trajectories {
        println!(
            "trajectories: {} (`bkpbs plot {}` draws them)",
            e.out.join(t.name).display(),
            e.out.display()
        );
    }
    if e.trace {
        println!(
            "trace: {} (`bkpbs explain {}` tells the story of each collision)",
            e.out.join(episode::trace::TRACE_FILE).display(),
            e.out.display()
        );
    }
}
