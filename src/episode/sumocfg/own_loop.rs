//! An episode on a user's scenario stepped by a loop of the caller's own (the Python
//! `Controller(sumocfg=…)` in a user's TraCI loop): the caller starts SUMO with
//! [`OwnLoop::sumo_command`], steps it, and calls [`OwnLoop::step`] after each step. The
//! regions, their planners and the books are those of `bkpbs episode --sumocfg`, and so are
//! the files of [`OwnLoop::finish`] for the same seed: the same SUMO, stepped the same way,
//! gives the same rows.

use std::path::PathBuf;

use crate::config::Config;
use crate::episode::error::EpisodeError;
use crate::episode::lockstep::step_error;
use crate::sumo::{frame, SumoClient};

use super::run::ScenarioRun;
use super::ScenarioResult;
use super::{check_cav_types, checked, command_line, regions, scratch_dir};
use super::{sumo_options, SumoOptions};

/// The episode's state between the caller's steps.
pub struct OwnLoop {
    run: ScenarioRun<'static>,
    planner: String,
    config: Config,
    /// The user's SUMO configuration.
    sumocfg: PathBuf,
    /// The options bkpbs needs beside it, its tripinfo output into `dir` among them when
    /// the configuration names none.
    options: SumoOptions,
    /// Holds bkpbs's tripinfo output until the episode ends.
    _scratch: tempfile::TempDir,
    /// SUMO's time when the step to book next began: read at the start and after each step.
    clock: Option<f64>,
    /// Steps booked so far.
    steps: u32,
    started: std::time::Instant,
}

impl OwnLoop {
    /// The episode of `config.scenario.sumocfg` with `planner` in each merge region.
    ///
    /// # Errors
    /// As `sumocfg::run`'s before SUMO starts.
    pub fn new(config: &Config, planner: &str) -> Result<OwnLoop, EpisodeError> {
        config.validate()?;
        let (sumocfg, cfg) = checked(config)?;
        let roads = frame::scenario_roads(&config.scenario)?;
        let dir = scratch_dir()?;
        let options = sumo_options(config, &cfg, dir.path());
        Ok(OwnLoop {
            run: ScenarioRun::of_regions(config, regions(config, roads, planner)?),
            planner: planner.to_string(),
            config: config.clone(),
            sumocfg,
            options,
            _scratch: dir,
            clock: None,
            steps: 0,
            started: std::time::Instant::now(),
        })
    }

    /// The command line to start SUMO with: the user's configuration, then bkpbs's options.
    pub fn sumo_command(&self) -> Vec<String> {
        command_line(&self.config, &self.sumocfg, &self.options.args)
    }

    /// The episode's length in steps: the scenario's interval, or `scenario.steps`.
    pub fn steps(&self) -> u32 {
        self.config.scenario.steps
    }

    /// Steps booked so far.
    pub fn steps_done(&self) -> u32 {
        self.steps
    }

    /// Once SUMO has started, before its first step: the CAV types checked, the regions'
    /// edges registered, the clock read.
    pub fn start(&mut self, sim: &mut impl SumoClient) -> Result<(), EpisodeError> {
        if self.clock.is_some() {
            return Err(EpisodeError::OutOfOrder(
                "the episode has started already: start it once, before the first step".into(),
            ));
        }
        check_cav_types(sim, &self.config, &self.sumocfg)?;
        let names = self.run.planning.edge_names();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let at = step_error(self.config.scenario.dt, 0);
        sim.set_edge_codes(&names).map_err(&at)?;
        self.clock = Some(sim.time().map_err(at)?);
        self.started = std::time::Instant::now();
        Ok(())
    }

    /// After each SUMO step: the step booked and, unless it was the episode's last, one
    /// planning round per region with its commands sent (as the CLI's loop, which plans
    /// nothing after the last step).
    pub fn step(&mut self, sim: &mut impl SumoClient) -> Result<(), EpisodeError> {
        let Some(now) = self.clock else {
            return Err(EpisodeError::OutOfOrder(
                "start the episode (once SUMO has started) before its first step".into(),
            ));
        };
        let total = self.steps();
        if self.steps >= total {
            return Err(EpisodeError::OutOfOrder(format!(
                "the episode has {total} steps, all booked: finish it (after closing SUMO)"
            )));
        }
        let at = step_error(self.config.scenario.dt, self.steps);
        let plan = self.steps + 1 < total;
        self.run.after_step(sim, now, plan).map_err(&at)?;
        self.steps += 1;
        self.clock = Some(sim.time().map_err(at)?);
        Ok(())
    }

    /// The names of every region's edges, in the order of their codes in the readings.
    pub fn edge_names(&self) -> Vec<String> {
        self.run.planning.edge_names()
    }

    /// Whether SUMO has been closed, so that its tripinfo output is complete.
    pub fn sumo_closed(&self) -> Result<(), EpisodeError> {
        // SUMO writes the document's end when it closes.
        let complete = std::fs::read_to_string(&self.options.tripinfo)
            .is_ok_and(|t| t.trim_end().ends_with("</tripinfos>"));
        if complete {
            return Ok(());
        }
        Err(EpisodeError::OutOfOrder(
            "SUMO has not completed its tripinfo output: close SUMO (traci.close()) before \
             finishing the episode"
                .into(),
        ))
    }

    /// The episode's result, once the caller has closed SUMO (which writes the tripinfo
    /// output): its rows cover the steps booked.
    pub fn finish(mut self) -> Result<ScenarioResult, EpisodeError> {
        self.sumo_closed()?;
        let loop_s = self.started.elapsed().as_secs_f64();
        self.run.ran_steps(self.steps);
        self.run.close_timing(loop_s);
        self.run
            .finish(&self.planner, &self.options)
            .map_err(EpisodeError::Output)
    }
}
