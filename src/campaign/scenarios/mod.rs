//! Campaigns over scenarios of the user's own (`bkpbs campaign --sumocfg A.sumocfg,B.sumocfg`):
//! every episode of a planners × scenarios × α × seeds grid, run in the same worker processes
//! as the paper's campaigns, resumable and shardable the same way, collected into one set of
//! CSV files.
//!
//! Layout of a campaign directory `<out>`:
//!
//! ```text
//! campaign.toml                                  the settings; a re-run must agree
//! episodes/<planner>/<scenario>/a<α>_s<seed>/     the files of `bkpbs episode --sumocfg`
//!     (+ settings.toml, provenance.toml), or error.txt
//! episodes.csv regions.csv entries.csv vehicles.csv timings.csv failures.csv
//!                                                collected, grid order
//! report/                                        per-region paired comparisons
//! ```
//!
//! The grid is the one of every campaign ([`super::grid`], with its scenario axis), and so are
//! the settings ([`super::Settings`], resolved over scenarios in [`super::settings::scenarios`]);
//! here are [`collect`] (resume state, gathering) and [`merge`] (shards gathered). `--trajectories` writes each cell's region trajectories
//! (`trajectories/<region>/`, as `bkpbs episode --sumocfg`), which `--plots` draws. The claim,
//! the preparation, the run and the collection are the paper campaign's own
//! ([`super::tasks`], [`super::run`]) over [`super::CampaignSpec`].

pub mod collect;
pub mod merge;

pub use collect::ScenarioResults;
