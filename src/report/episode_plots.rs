//! `bkpbs plot DIR`: the figures of one episode directory (or one cell of a campaign): the
//! time–space diagram, the speed field and, when the episode was traced, a close-up of each
//! collision (`bkpbs explain --plot`).

use std::path::{Path, PathBuf};

use super::explain::{self, ExplainError};
use super::lane_tracks::{self, TracksError};
use super::plot::PlotError;
use super::timespace::{LaneFigure, View};
use crate::campaign::cell::cell_dir;
use crate::campaign::{CampaignSpec, Readiness};
use crate::episode::trace::TRACE_FILE;
use crate::io::{write_atomic, WriteError};

/// File stem of the time–space diagram (`.png` and `.svg` each) in the episode directory.
pub const TIME_SPACE: &str = "time_space";
/// File stem of the speed field (`.png` and `.svg` each) in the episode directory.
pub const SPEED_FIELD: &str = "speed_field";

/// Why an episode's figures could not be made.
#[derive(Debug, thiserror::Error)]
pub enum EpisodePlotError {
    /// The path given is not a directory.
    #[error("{dir} is not a directory")]
    NotADirectory {
        /// The path given.
        dir: PathBuf,
    },
    /// The trajectories (or collisions) could not be read, e.g. none were recorded.
    #[error(transparent)]
    Tracks(#[from] TracksError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A figure file could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// The collision close-ups could not be made from `trace.jsonl`.
    #[error(transparent)]
    Explain(#[from] ExplainError),
}

/// What `plot` made.
#[derive(Debug, Default)]
pub struct EpisodePlots {
    /// Every file written (PNG and SVG of each figure), in order.
    pub files: Vec<PathBuf>,
    /// Collisions seen in the trajectories.
    pub collisions: usize,
    /// Whether close-ups were drawn (they need `trace.jsonl`).
    pub close_ups: bool,
}

/// Draws the figures of episode directory `dir` into it: of an episode on a scenario of the
/// user's own, each merge region's into its trajectory directory (`trajectories/<region>/`).
pub fn plot_dir(dir: &Path) -> Result<EpisodePlots, EpisodePlotError> {
    if !dir.is_dir() {
        return Err(EpisodePlotError::NotADirectory {
            dir: dir.to_path_buf(),
        });
    }
    let regions = crate::episode::sumocfg::region_dirs(dir);
    if regions.is_empty() {
        return plot_tracks(dir);
    }
    let mut out = EpisodePlots::default();
    for region in &regions {
        let drawn = plot_tracks(region)?;
        out.files.extend(drawn.files);
        out.collisions += drawn.collisions;
        out.close_ups |= drawn.close_ups;
    }
    Ok(out)
}

/// Draws the figures of the trajectories in `dir` into it.
fn plot_tracks(dir: &Path) -> Result<EpisodePlots, EpisodePlotError> {
    let tracks = lane_tracks::read(dir)?;
    let title = episode_title(dir);
    let mut out = EpisodePlots {
        collisions: tracks.collisions.len(),
        ..EpisodePlots::default()
    };
    for (view, stem, what) in [
        (View::TimeSpace, TIME_SPACE, "time–space diagram"),
        (View::SpeedField, SPEED_FIELD, "speed field"),
    ] {
        let fig = LaneFigure {
            tracks: &tracks,
            view,
            title: format!("{what}: {title}"),
        }
        .render()?;
        let (png, svg) = (
            dir.join(format!("{stem}.png")),
            dir.join(format!("{stem}.svg")),
        );
        write_atomic(&png, &fig.png)?;
        write_atomic(&svg, fig.svg.as_bytes())?;
        out.files.extend([png, svg]);
    }
    if out.collisions > 0 && dir.join(TRACE_FILE).is_file() {
        let explanations = explain::explain_dir(dir)?;
        out.files.extend(explain::write_plots(dir, &explanations)?);
        out.close_ups = true;
    }
    Ok(out)
}

/// "bk-pbs, α = 0.5, λ = 3000 veh/h, seed 0" from the directory's `episode.csv`; for a region's
/// trajectories of an episode on a scenario of the user's own (`<episode>/trajectories/<region>`)
/// "bk-pbs on ramp.sumocfg, region gneE7, α = 0.5, seed 1" from the episode's; the directory's
/// name without either.
fn episode_title(dir: &Path) -> String {
    let demand = || -> Option<String> {
        let get = episode_row(dir)?;
        Some(format!(
            "{}, α = {}, λ = {} veh/h, seed {}",
            get("planner")?,
            get("alpha")?,
            get("lambda")?,
            get("seed")?
        ))
    };
    let region = || -> Option<String> {
        let get = episode_row(dir.parent()?.parent()?)?;
        Some(format!(
            "{} on {}, region {}, α = {}, seed {}",
            get("planner")?,
            get("scenario")?,
            dir.file_name()?.to_string_lossy().replace('+', " "),
            get("alpha")?,
            get("seed")?
        ))
    };
    demand()
        .or_else(region)
        .unwrap_or_else(|| dir.display().to_string())
}

/// The columns of `dir`'s one-row `episode.csv`, by name.
fn episode_row(dir: &Path) -> Option<impl Fn(&str) -> Option<String>> {
    let mut r = csv::Reader::from_reader(
        crate::io::bounded::open(&dir.join("episode.csv"), crate::io::bounded::FileKind::Data)
            .ok()?,
    );
    let header = r.headers().ok()?.clone();
    let row = r.records().next()?.ok()?;
    Some(move |name: &str| {
        let i = header.iter().position(|h| h == name)?;
        row.get(i).map(String::from)
    })
}

/// What `campaign --plots` drew.
#[derive(Debug, Default, PartialEq)]
pub struct CellPlots {
    /// Cells drawn.
    pub plotted: usize,
    /// Finished cells without trajectories (run before `--trajectories` was given).
    pub without_trajectories: usize,
}

/// The directories of the finished cells of this run's shard of either kind of campaign, in
/// grid order.
fn finished_dirs<S: CampaignSpec>(out: &Path, settings: &S) -> Vec<PathBuf> {
    let shard = settings.shard();
    let cells = settings.cells();
    let finished = cells
        .iter()
        .enumerate()
        .filter(|(i, c)| shard.contains(*i) && settings.readiness(out, c) == Readiness::Done(()));
    finished.map(|(_, c)| cell_dir(out, c)).collect()
}

/// Draws the figures of every finished cell of a campaign run (its shard), in parallel: a
/// scenario cell's of each of its regions (`trajectories/<region>/`), as [`plot_dir`] does.
pub fn plot_cells(
    out: &Path,
    settings: &crate::campaign::Settings,
) -> Result<CellPlots, EpisodePlotError> {
    use rayon::prelude::*;
    let dirs = finished_dirs(out, settings);
    let results: Vec<Result<bool, EpisodePlotError>> = dirs
        .par_iter()
        .map(|d| match plot_dir(d) {
            Ok(_) => Ok(true),
            Err(EpisodePlotError::Tracks(TracksError::Missing { .. })) => Ok(false),
            Err(e) => Err(e),
        })
        .collect();
    let mut summary = CellPlots::default();
    for r in results {
        if r? {
            summary.plotted += 1;
        } else {
            summary.without_trajectories += 1;
        }
    }
    Ok(summary)
}
